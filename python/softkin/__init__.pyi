# Type stubs of the package softkin (python/softkin/__init__.py and the compiled _softkin).
from os import PathLike
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from . import ik as ik

ArrayLike = npt.ArrayLike
Vec = npt.NDArray[np.float64]
Idx = npt.NDArray[np.int64]

class Scene:
    @property
    def name(self) -> str: ...
    @property
    def vertices(self) -> Vec: ...  # (#V, 3) mm
    @property
    def elements(self) -> Idx: ...  # (#E, 4) or (#E, 6)
    @property
    def tags(self) -> Idx: ...  # (#E,)
    @property
    def num_vertices(self) -> int: ...
    @property
    def num_elements(self) -> int: ...
    @property
    def num_actuators(self) -> int: ...
    @property
    def actuators(self) -> List[Dict[str, Any]]: ...
    @property
    def lower(self) -> Vec: ...  # (#A,)
    @property
    def upper(self) -> Vec: ...  # (#A,)
    @property
    def rest(self) -> Vec: ...  # (#A,)
    @property
    def markers(self) -> Dict[str, Idx]: ...
    @property
    def fixed(self) -> Idx: ...
    def marker_positions(self, positions: ArrayLike) -> Dict[str, Vec]: ...

class FkResult:
    @property
    def positions(self) -> Vec: ...  # (#V, 3) mm
    @property
    def markers(self) -> Dict[str, Vec]: ...  # name -> (3,)
    @property
    def status(self) -> str: ...
    @property
    def converged(self) -> bool: ...
    @property
    def message(self) -> str: ...
    @property
    def solver(self) -> str: ...
    @property
    def actuation(self) -> Vec: ...
    @property
    def iterations(self) -> int: ...
    @property
    def energy(self) -> float: ...
    @property
    def gradient_ratio(self) -> float: ...
    @property
    def time_s(self) -> float: ...
    @property
    def volume_ratios(self) -> Vec: ...  # (#A,)
    @property
    def inverted_elements(self) -> int: ...
    @property
    def min_volume_ratio(self) -> float: ...
    def write_vtu(self, path: Union[str, PathLike]) -> None: ...

def robots() -> List[Dict[str, Any]]: ...
def robot(name: str, res: Optional[int] = ..., **params: float) -> Scene: ...
def load_scene(path: Union[str, PathLike]) -> Scene: ...
def scene_from_arrays(
    vertices: ArrayLike,
    elements: ArrayLike,
    tags: ArrayLike,
    regions: Iterable[Mapping[str, Any]],
    fixed: Iterable[Mapping[str, Any]],
    markers: Iterable[Mapping[str, Any]] = ...,
    motions: Iterable[Mapping[str, Any]] = ...,
    obstacles: Iterable[Mapping[str, Any]] = ...,
    solver: Optional[Mapping[str, Any]] = ...,
    name: str = ...,
) -> Scene: ...

class FkSolver:
    def __init__(self, scene: Scene, solver: str = ..., **options: Any) -> None: ...
    @property
    def scene(self) -> Scene: ...
    @property
    def name(self) -> str: ...
    @property
    def options(self) -> Dict[str, Any]: ...
    def solve(self, c: ArrayLike, warm_start: Optional[ArrayLike] = ...) -> FkResult: ...
    def jacobian(
        self, c: ArrayLike, mode: str = ..., warm_start: Optional[ArrayLike] = ...
    ) -> Dict[str, Any]: ...  # dX (#V, 3, #A), markers name -> (3, #A), result, mode

def solve_fk(scene: Scene, c: ArrayLike, solver: str = ..., **options: Any) -> FkResult: ...

class Kinematics:
    """Subclass in Python: call Kinematics.__init__ and implement compute(c, with_jacobian)."""
    def __init__(
        self,
        points: Sequence[str],
        lower: ArrayLike,
        upper: ArrayLike,
        rest: Optional[ArrayLike] = ...,
        name: str = ...,
    ) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def point_names(self) -> List[str]: ...
    @property
    def num_actuators(self) -> int: ...
    @property
    def lower(self) -> Vec: ...
    @property
    def upper(self) -> Vec: ...
    @property
    def rest(self) -> Vec: ...
    @property
    def total_fk_solves(self) -> int: ...
    def evaluate(self, c: ArrayLike, with_jacobian: bool = ...) -> Dict[str, Any]: ...
    def p(self, c: ArrayLike) -> Vec: ...  # (#P, 3)
    def J(self, c: ArrayLike) -> Vec: ...  # (3 #P, #A)

class PccKinematics(Kinematics):
    def __init__(
        self,
        length: float = ...,
        cable_offset: float = ...,
        max_pull: float = ...,
        backbone_points: int = ...,
        axial: bool = ...,
    ) -> None: ...

def cli(args: Sequence[Union[str, PathLike]]) -> int: ...
def dataset(out: Union[str, PathLike], robot: str, **options: Any) -> int: ...
def train(dataset_path: Union[str, PathLike], out: Union[str, PathLike], **options: Any) -> Kinematics: ...
def load_nets(
    directory: Union[str, PathLike], jacobian: str = ..., use_s2r: bool = ...
) -> Kinematics: ...

class SimulatorKinematics(Kinematics):
    def __init__(
        self,
        scene: Scene,
        jacobian: str = ...,
        points: Sequence[str] = ...,
        fd_step: float = ...,
        solver: str = ...,
        **options: Any,
    ) -> None: ...
    def reset(self) -> None: ...

# Type stubs of softkin.ik (python/softkin/ik.py).
from typing import Any, Dict, List, Optional

import numpy.typing as npt

from . import Kinematics

def methods() -> List[str]: ...
def solve(
    kin: Kinematics,
    target: npt.ArrayLike,
    point: Optional[str] = ...,
    c0: Optional[npt.ArrayLike] = ...,
    bounds: Optional[npt.ArrayLike] = ...,
    method: str = ...,
    gradient: str = ...,
    lambda_mm: float = ...,
    max_iterations: int = ...,
    max_evaluations: int = ...,
    max_time_s: float = ...,
) -> Dict[str, Any]: ...
def follow(
    kin: Kinematics,
    waypoints: npt.ArrayLike,
    point: Optional[str] = ...,
    c0: Optional[npt.ArrayLike] = ...,
    bounds: Optional[npt.ArrayLike] = ...,
    samples_per_axis: int = ...,
    method: str = ...,
    gradient: str = ...,
    lambda_mm: float = ...,
    max_iterations: int = ...,
    max_evaluations: int = ...,
    max_time_s: float = ...,
) -> Dict[str, Any]: ...

"""SoftKin in Python: soft-robot scenes, forward kinematics and Jacobians with NumPy arrays.

Lengths are in mm. Arrays are float64 (positions, actuations) or int64 (indices) NumPy arrays,
always copies. Bad input raises ValueError with the same message as the ``softkin`` command
(file:line, or the key path); a solve that fails raises RuntimeError only where no result can be
returned (a Jacobian); ``FkSolver.solve`` returns its status instead.

    import softkin
    scene = softkin.robot("pneumatic_finger")
    solver = softkin.FkSolver(scene, solver="lg-aa")
    result = solver.solve([2.0])
    result.markers["tip"]          # (3,) mm
    result.write_vtu("bent.vtu")   # for ParaView
"""

import json as _json

import numpy as _np

from . import _softkin
from ._softkin import FkResult, Kinematics, PccKinematics, Scene
from . import ik

__all__ = [
    "FkResult",
    "FkSolver",
    "Kinematics",
    "PccKinematics",
    "Scene",
    "SimulatorKinematics",
    "cli",
    "dataset",
    "ik",
    "load_nets",
    "load_scene",
    "robot",
    "robots",
    "scene_from_arrays",
    "solve_fk",
    "train",
]


def _floats(x, what):
    """x as a float64 array, or ValueError naming ``what``."""
    try:
        a = _np.asarray(x, dtype=_np.float64)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{what}: expected numbers, got {type(x).__name__} ({e})") from None
    return a


def _indices(x, what):
    """x as an int64 array of whole numbers, or ValueError naming ``what``."""
    try:
        a = _np.asarray(x)
        if a.dtype.kind == "f":
            if not _np.all(_np.isfinite(a)) or not _np.all(a == _np.round(a)):
                raise ValueError("not whole numbers")
        elif a.dtype.kind not in "iub":
            raise ValueError(f"dtype {a.dtype}")
        return a.astype(_np.int64)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{what}: expected integer indices, got {e}") from None


def _actuation(c):
    c = _np.atleast_1d(_floats(c, "c (one value per actuator)"))
    if not _np.all(_np.isfinite(c)):
        raise ValueError(f"c (one value per actuator): expected finite numbers, got {c.tolist()}")
    return c


def robots():
    """The embedded robot generators: a list of dicts with name, description,
    default_resolution, resolution_doc and params (name, default, min, max, doc)."""
    return _softkin._robots()


def robot(name, res=None, **params):
    """Builds embedded robot ``name`` at resolution ``res`` (None: its default), with its design
    parameters as keyword arguments (``softkin.robots()`` lists them and their ranges)."""
    if res is None:
        res = 0
    elif isinstance(res, bool) or not isinstance(res, (int, _np.integer)) or res < 1:
        raise ValueError(f"res: expected an integer >= 1, or None for the robot's default; got {res!r}")
    return _softkin._robot(name, int(res), {k: float(v) for k, v in params.items()})


def load_scene(path):
    """Loads a scene JSON file (``softkin scene --schema`` documents its keys); relative paths in
    it are relative to its folder."""
    return _softkin._load_scene(str(path))


def scene_from_arrays(vertices, elements, tags, regions, fixed, markers=(), motions=(),
                      obstacles=(), solver=None, name="arrays"):
    """A scene from arrays, e.g. a mesh read with meshio or gmsh.

    vertices: #V x 3 rest positions, mm. elements: #E x 4 (tets) or #E x 6 (prisms), 0-based rows
    of vertices; orientation is fixed as for files. tags: #E region tags. The other arguments are
    the scene JSON's keys of the same names (lists of dicts; ``softkin scene --schema``), e.g.
    regions=[{"tag": 0, "role": "body"}, {"tag": 1, "role": "pneumatic", "name": "chamber"}],
    or regions as a dict tag -> role or tag -> entry, e.g. {0: "body", 1: {"role": "pneumatic",
    "name": "chamber"}},
    fixed=[{"plane": {"point": [0, 0, 0], "normal": [1, 0, 0]}}]. Vertex indices in them are
    rows of ``vertices``. The mesh gets the same checks as a mesh file (folds, duplicates,
    cracks; unused vertices are dropped with a note).
    """
    if isinstance(regions, dict):  # {tag: "role"} or {tag: {"role": ..., ...}}
        regions = [dict(v, tag=int(k)) if isinstance(v, dict) else {"tag": int(k), "role": v}
                   for k, v in regions.items()]
    spec = {"name": name, "regions": list(regions), "fixed": list(fixed),
            "markers": list(markers), "motions": list(motions), "obstacles": list(obstacles)}
    if solver is not None:
        spec["solver"] = dict(solver)
    return _softkin._scene_from_arrays(
        _floats(vertices, "vertices"), _indices(elements, "elements"), _indices(tags, "tags"),
        _json.dumps(spec), name)


class FkSolver:
    """A forward-kinematics solver on one scene, reused across solves (it keeps the model's
    factorisation). ``solver`` is one of lg, lg-aa, newton, auto, ceres, ipopt-lbfgs,
    ipopt-newton, ipopt-hard, calculix-linear, calculix-nonlinear (None: the scene's own, auto
    unless the scene says otherwise); the other keyword arguments are the scene JSON's
    ``solver`` options (e.g. max_iterations=20000, tolerance=1e-7, threads=2), over the scene's
    own.
    """

    def __init__(self, scene, solver=None, **options):
        options = dict(options)
        if solver is not None:
            options["solver"] = solver
        self._impl = _softkin._FkSolver(scene, _json.dumps(options))

    @property
    def scene(self):
        return self._impl.scene

    @property
    def name(self):
        return self._impl.name

    @property
    def options(self):
        """Every solver option in effect, as a dict in the scene JSON's layout."""
        return _json.loads(self._impl._options_json)

    def solve(self, c, warm_start=None):
        """Solves for actuation ``c`` (#A values, or a number for one actuator) from the rest
        shape, or from ``warm_start`` (#V x 3 positions, e.g. a previous result's). Returns an
        FkResult; check ``result.converged``. ValueError for a c of the wrong size, not finite
        or outside the actuators' ranges."""
        if warm_start is not None:
            warm_start = _floats(warm_start, "warm_start")
        return self._impl.solve(_actuation(c), warm_start)

    def jacobian(self, c, mode="implicit", warm_start=None):
        """dX/dc at the equilibrium for ``c``: a dict with ``dX`` (#V x 3 x #A, mm per unit of
        actuation), ``markers`` (name -> 3 x #A), ``result`` (the FkResult at c) and ``mode``.
        Modes: implicit (differentiating the equilibrium: no extra solves), fd (central
        differences, probes solved like c itself), fd-warm (probes start from the state at c);
        differences step 1/160 of each actuator's range, one-sided at a bound. Raises
        RuntimeError when the solve at c or a probe does not converge."""
        if warm_start is not None:
            warm_start = _floats(warm_start, "warm_start")
        return self._impl.jacobian(_actuation(c), mode, warm_start)

    def __repr__(self):
        return f"<softkin.FkSolver {self.name} on {self.scene!r}>"


def solve_fk(scene, c, solver=None, **options):
    """One shot: builds an FkSolver and solves for ``c``."""
    return FkSolver(scene, solver=solver, **options).solve(c)


class SimulatorKinematics(_softkin._SimulatorKinematics):
    """The simulator as IK sees it (a Kinematics): tracked points p(c) (#P x 3, mm) and the
    Jacobian J(c) (3 #P x #A; row 3 i + d is coordinate d of point i). ``jacobian``: implicit,
    fd or fd-warm. ``points``: marker names ("tip"), "name[*]" for every vertex of a marker,
    "name[i]" for one; empty: every marker. Solves warm-start from the previous one (``reset()``
    forgets it). ``solver`` and ``options`` as for FkSolver."""

    def __init__(self, scene, jacobian="implicit", points=(), fd_step=1.0 / 160.0,
                 solver=None, **options):
        options = dict(options)
        if solver is not None:
            options["solver"] = solver
        super().__init__(scene, jacobian, list(points), float(fd_step), _json.dumps(options))


def cli(args):
    """Runs a ``softkin`` command in this process, e.g. ``softkin.cli(["run",
    "experiments/configs/fig2_11.json", "--quick"])``; returns its exit code (0 ok, 1 a solve or
    job failed). Bad input raises ValueError with the command's message. Output and progress go
    to the process's stdout and stderr."""
    return _softkin._cli([str(a) for a in args])


def _flags(options):
    """Keyword arguments as command-line flags: a_b=v -> --a-b v; True -> --a-b; False/None: left
    out; lists and tuples -> comma lists."""
    out = []
    for key, value in options.items():
        if value is None or value is False:
            continue
        flag = "--" + key.replace("_", "-")
        if value is True:
            out.append(flag)
        elif isinstance(value, (list, tuple)):
            out += [flag, ",".join(str(v) for v in value)]
        elif isinstance(value, dict):
            for k, v in value.items():
                out += [flag, f"{k}={v}"]
        else:
            out += [flag, str(value)]
    return out


def dataset(out, robot, **options):
    """Generates (or resumes) a learning dataset CSV ``out`` of embedded robot ``robot``, as
    ``softkin dataset`` does (docs/datasets.md): options are its flags with underscores, e.g.
    res=6, grid=8 (or random=500, seed=1), jacobian="implicit", points="tip", shard="1/4",
    param={"gap": 2}, quiet=True. Rerunning with the same options continues where a killed run
    stopped. Returns the exit code (1: some samples failed and were recorded so)."""
    return cli(["dataset", "--robot", robot, "--out", str(out)] + _flags(options))


def train(dataset_path, out, **options):
    """Trains the networks of Sec. 5.3 on dataset CSV ``dataset_path`` into directory ``out``, as
    ``softkin train`` does: e.g. what="fk,jac", hidden=(35, 35), hidden_jac=(64, 64),
    epochs=200, seed=1, quiet=True. Returns the learned kinematics (``load_nets(out)``)."""
    cli(["train", "--dataset", str(dataset_path), "--out", str(out)] + _flags(options))
    return load_nets(out)


def load_nets(directory, jacobian="network", use_s2r=False):
    """The learned kinematics (N_fk, N_J and optionally N_s2r) in a directory written by
    ``softkin train``, as a Kinematics. ``jacobian``: network (N_J) or fk-derivative (the
    derivative of N_fk)."""
    return _softkin._load_nets(str(directory), jacobian, bool(use_s2r))

"""Inverse kinematics on any softkin.Kinematics (the simulator, PCC, learned networks, or one
written in Python): one target, or a path of waypoints (thesis Algorithm 4).

Methods: softls (the soft line search, Algorithm 3), nlopt-mma, nlopt-lbfgs, nlopt-slsqp,
nlopt-ccsaq, nlopt-bobyqa, gauss-newton, broyden. ``lambda_mm``: stop when the tracked point is
within this distance of its target (the thesis's 0.2 mm). ``converged`` means exactly that; a
state with inverted elements is flagged by ``inverted_elements`` (> 0), whatever the distance.
"""

import numpy as _np

from . import _softkin

__all__ = ["follow", "methods", "solve"]


def methods():
    """The IK method names, as a list."""
    return [m.strip() for m in _softkin._ik.methods().split(",")]


def _bounds(bounds):
    return None if bounds is None else _np.asarray(bounds, dtype=_np.float64)


def solve(kin, target, point=None, c0=None, bounds=None, method="softls", gradient="jacobian",
          lambda_mm=0.2, max_iterations=30, max_evaluations=300, max_time_s=60.0):
    """Moves tracked point ``point`` (None: "tip", or the first point) to ``target`` (3,) mm,
    starting from ``c0`` (None: the rest actuation, clamped into the box), within the kinematics'
    bounds or the narrower ``bounds`` (#A x 2: min, max per actuator). Returns a
    dict: c (#A), p (#P x 3), point, objective (mm^2), error_mm, converged, termination, message,
    iterations, evaluations, fk_solves, time_s, history (objective per iteration),
    inverted_elements."""
    return _softkin._ik.solve(kin, _np.asarray(target, dtype=_np.float64), point or "",
                              None if c0 is None else _np.asarray(c0, dtype=_np.float64),
                              _bounds(bounds), method, gradient, float(lambda_mm), int(max_iterations),
                              int(max_evaluations), float(max_time_s))


def follow(kin, waypoints, point=None, c0=None, bounds=None, samples_per_axis=5,
           method="softls", gradient="jacobian", lambda_mm=0.2, max_iterations=30,
           max_evaluations=300, max_time_s=600.0):
    """Follows ``waypoints`` (#W x 3, mm) with tracked point ``point``: each waypoint starts from
    the previous answer; the first from ``c0``, or else from the closest of a grid of
    ``samples_per_axis``^#A sampled configurations (within ``bounds``, as for solve). Returns a dict of arrays over the waypoints:
    c (#W x #A), reached (#W x 3), error_mm, converged, inverted_elements, iterations,
    termination; and num_converged, mean_error_mm, max_error_mm, max_jump_fraction, time_s."""
    return _softkin._ik.follow(kin, _np.asarray(waypoints, dtype=_np.float64), point or "",
                               None if c0 is None else _np.asarray(c0, dtype=_np.float64),
                               _bounds(bounds), int(samples_per_axis), method, gradient, float(lambda_mm),
                               int(max_iterations), int(max_evaluations), float(max_time_s))

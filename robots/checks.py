"""Conformance checks for robot error models, one small named check each (scikit-learn's
``sklearn/utils/estimator_checks.py`` style; contract in :mod:`evotol.robots.base`).

:func:`robot_checks` yields ``(name, check)`` pairs, each check a callable of no argument that
raises :class:`evotol.errors.CheckFailed` saying what failed (not an ``assert``: the
checks hold under ``python -O``) and returns measured numbers; a plugin author turns
each into its own pytest id::

    @pytest.mark.parametrize("check", list(robot_checks(MyRobot())), ids=lambda c: c[0])
    def test_my_robot(check):
        check[1]()

:func:`check_robot` runs them all and reports every failure, not only the first.

The parameters several definitions of this module share are described once, here.

Parameters
----------
s : _Settings
    The robot under check, its validated poses (SI units) and the finite-difference
    settings, shared by every check of one :func:`robot_checks` call.
robot : RobotErrorModel
    Any object following :class:`evotol.robots.base.RobotErrorModel`'s contract.
poses : (n, workspace.dim) array_like, optional
    Poses to check at, in SI units (m, rad); default (None): 8 Latin-hypercube poses of the
    workspace (seed 1).
step : float, optional
    Finite-difference step of each source component, in the source's SI unit (m or rad).
rtol : float, optional
    Tolerated finite-difference mismatch relative to the sensitivity's largest entry
    (dimensionless).
atol : float, optional
    Absolute tolerance added to it, and the largest pose error accepted at zero source
    errors (m or rad).
"""
from __future__ import annotations

import functools
import pickle
from typing import Any, Callable, Iterator

import numpy as np

from evotol._runtime.check_suite import require, run_checks
from evotol.errors import CheckFailed, KinematicsError
from evotol.units import UNITS

#: any object following :class:`evotol.robots.base.RobotErrorModel`'s contract (evotol.robots.base imports this
#: module -- ``check_robot`` is part of the protocol's API -- so the class is not imported here)
Robot = Any


class _Settings:
    """What every check of one robot shares: the poses and the finite-difference settings."""

    def __init__(self, robot: Robot, poses, step: float, rtol: float, atol: float):
        self.robot = robot
        self.poses = robot.check_poses(robot.workspace.latin_hypercube(8, seed=1) if poses is None else poses)
        self.step, self.rtol, self.atol = step, rtol, atol


def check_sources_declared(s: _Settings) -> dict:
    """At least one error source, unique names, dimensions 1-3.

    Returns
    -------
    dict
        ``{"n_columns": ...}``: the length of the stacked error vector.

    Raises
    ------
    evotol.errors.CheckFailed
        No source, duplicate source names, or a dimension outside 1-3.
    """
    r = s.robot
    require(r.sources, f"{r.name}: no error sources declared")
    names = [x.name for x in r.sources]
    require(len(set(names)) == len(names), f"{r.name}: duplicate source names {names}")
    require(all(x.dim in (1, 2, 3) for x in r.sources),
            f"{r.name}: source dimensions {[x.dim for x in r.sources]}")
    return {"n_columns": r.n_columns}


def check_units_declared(s: _Settings) -> dict:
    """Every source declares an SI unit (m or rad), every workspace coordinate one too (m, rad,
    or "1" when dimensionless), and the display scales (to mm, deg...) are positive numbers.

    Returns
    -------
    dict
        Empty: nothing measured.

    Raises
    ------
    evotol.errors.CheckFailed
        A source unit not in ``("m", "rad")``, a workspace unit not in ``("m", "rad", "1")``
        or not one per coordinate, or a display scale that is not finite and positive.
    """
    r, ws = s.robot, s.robot.workspace
    bad = [x.name for x in r.sources if x.unit not in UNITS]
    require(not bad, f"{r.name}: sources {bad} have no SI unit (one of {UNITS})")
    # a workspace coordinate may also be a dimensionless SI quantity ("1": an index, a ratio)
    allowed = UNITS + ("1",)
    require(len(ws.units) == ws.dim and all(u in allowed for u in ws.units),
            f"{r.name}: workspace units {ws.units}, expected one of {allowed} per coordinate {ws.names}")
    require(len(ws.display_scale) == ws.dim and all(np.isfinite(ws.display_scale)) and min(ws.display_scale) > 0,
            f"{r.name}: workspace display_scale {ws.display_scale}")
    return {}


def check_sensitivity_shape(s: _Settings) -> dict:
    """``sensitivity(poses)`` has shape (n_poses, 6, n_columns) and finite entries.

    Returns
    -------
    dict
        ``{"n_poses": ...}``: the number of poses checked.

    Raises
    ------
    evotol.errors.CheckFailed
        The wrong shape or a non-finite entry.
    """
    r = s.robot
    J = np.asarray(r.sensitivity(s.poses))
    expected = (len(s.poses), 6, r.n_columns)
    require(J.shape == expected, f"{r.name}: sensitivity shape {J.shape}, expected {expected}")
    require(np.all(np.isfinite(J)), f"{r.name}: sensitivity has non-finite entries")
    return {"n_poses": len(s.poses)}


def check_pose_subset_invariance(s: _Settings) -> dict:
    """The sensitivity (and the nonlinear error) of a subset of poses equals the same rows of the
    full call: no pose leaks into another one's result (batching, caches, reordering).

    The sensitivity must agree to ``1e-10`` of its largest entry; the nonlinear error (random
    source errors of about 1e-6 m or rad, 2 samples per pose) to ``1e-6`` of its largest entry.

    Returns
    -------
    dict
        Empty: nothing measured.

    Raises
    ------
    evotol.errors.CheckFailed
        A subset's result differs from the same rows of the full call.
    """
    r, P = s.robot, s.poses
    idx = np.arange(len(P))[::-2][: max(1, len(P) // 2)]
    J = np.asarray(r.sensitivity(P))
    Jsub = np.asarray(r.sensitivity(P[idx]))
    scale = max(float(np.abs(J).max()), 1e-300)
    gap = float(np.abs(Jsub - J[idx]).max())
    require(gap <= 1e-10 * scale,
            f"{r.name}: sensitivity of poses {idx.tolist()} differs from the full call by {gap:.3g}")
    if r.has_nonlinear_model:
        # errors of 1e-6 (m, rad): a pose error leaking between poses would be of that order;
        # iterative solvers may differ by round-off of the pose itself (~1e-15), < 1e-6 of it
        E = np.random.default_rng(0).normal(size=(len(P), 2, r.n_columns)) * 1e-6
        full = np.asarray(r.pose_error(P, E))
        sub = np.asarray(r.pose_error(P[idx], E[idx]))
        gap_e = float(np.abs(sub - full[idx]).max())
        require(gap_e <= 1e-6 * max(float(np.abs(full).max()), 1e-300),
                f"{r.name}: pose_error of poses {idx.tolist()} differs from the full call by {gap_e:.3g}")
    return {}


def check_pickle_round_trip(s: _Settings) -> dict:
    """The robot pickles (it travels to worker processes and Dask) and gives the same sensitivity.

    Returns
    -------
    dict
        Empty: nothing measured.

    Raises
    ------
    evotol.errors.CheckFailed
        The unpickled robot's sensitivity is not bit-for-bit equal to the original's.

    Notes
    -----
    A robot that does not pickle raises the pickling error itself (``pickle.PicklingError``,
    ``TypeError``, ``AttributeError``...), not ``CheckFailed``.
    """
    r = s.robot
    back = pickle.loads(pickle.dumps(r))
    require(np.array_equal(np.asarray(back.sensitivity(s.poses)), np.asarray(r.sensitivity(s.poses))),
            f"{r.name}: sensitivity differs after a pickle round trip")
    return {}


def check_out_of_reach_raises(s: _Settings) -> dict:
    """A pose far outside the workspace raises KinematicsError (naming the pose) from
    ``sensitivity`` and ``pose_error`` -- never a NaN that travels on.

    The pose is ``high + 10 (high - low) + 1`` per coordinate (SI units); ``pose_error`` is called
    only when the robot has a nonlinear model, with zero source errors.

    Returns
    -------
    dict
        Empty: nothing measured.

    Raises
    ------
    evotol.errors.CheckFailed
        A call returns (numbers or NaN) instead of raising
        :class:`evotol.errors.KinematicsError`.
    """
    r, ws = s.robot, s.robot.workspace
    hi, lo = np.asarray(ws.high, float), np.asarray(ws.low, float)
    far = hi + 10 * (hi - lo) + 1.0
    calls = [("sensitivity", lambda P: r.sensitivity(P))]
    if r.has_nonlinear_model:
        calls.append(("pose_error", lambda P: r.pose_error(P, np.zeros((len(P), 1, r.n_columns)))))
    for name, call in calls:
        try:
            out = np.asarray(call(far[None, :]))
        except KinematicsError:
            continue
        raise CheckFailed(f"{r.name}: {name} at the unreachable pose {far.tolist()} returned "
                          f"{'NaN' if np.isnan(out).any() else 'numbers'} instead of raising KinematicsError")
    return {}


def check_pose_error_consistency(s: _Settings) -> dict:
    """Where a nonlinear ``pose_error`` exists: shape (n_poses, n_samples, 6), zero source errors
    give zero pose error, and its central finite differences equal ``sensitivity`` to ``rtol``
    relative to the largest entry (+ ``atol``).

    The finite differences step each stacked source component by ``+-step`` (SI: m or rad).

    Returns
    -------
    dict
        ``{"nonlinear_model": False}`` when the robot has no nonlinear model (nothing checked);
        otherwise ``{"fd_mismatch": ..., "fd_relative_mismatch": ...}``: the largest absolute
        difference between finite differences and ``sensitivity`` (m or rad per source unit) and
        that difference over the sensitivity's largest entry (dimensionless).

    Raises
    ------
    evotol.errors.CheckFailed
        The wrong shape, a pose error above ``atol`` at zero source errors, or a mismatch
        above ``rtol * max|sensitivity| + atol``.
    """
    r, P = s.robot, s.poses
    if not r.has_nonlinear_model:
        return {"nonlinear_model": False}
    n = r.n_columns
    zero = np.asarray(r.pose_error(P, np.zeros((len(P), 1, n))))
    require(zero.shape == (len(P), 1, 6),
            f"{r.name}: pose_error shape {zero.shape}, expected {(len(P), 1, 6)}")
    require(np.max(np.abs(zero)) <= s.atol,
            f"{r.name}: zero source errors give pose error {np.max(np.abs(zero)):.3g}")
    J = np.asarray(r.sensitivity(P))
    E = np.concatenate([np.eye(n) * s.step, -np.eye(n) * s.step], axis=0)  # (2n, n)
    out = np.asarray(r.pose_error(P, np.ascontiguousarray(np.broadcast_to(E, (len(P), 2 * n, n)))))
    fd = (out[:, :n, :] - out[:, n:, :]).transpose(0, 2, 1) / (2 * s.step)
    scale = float(np.max(np.abs(J)))
    mismatch = float(np.max(np.abs(fd - J)))
    require(mismatch <= s.rtol * scale + s.atol,
            f"{r.name}: sensitivity differs from finite differences by {mismatch:.3g} (scale {scale:.3g})")
    return {"fd_mismatch": mismatch, "fd_relative_mismatch": mismatch / scale}


CHECKS = (check_sources_declared, check_units_declared, check_sensitivity_shape, check_pose_error_consistency,
          check_pose_subset_invariance, check_pickle_round_trip, check_out_of_reach_raises)


def robot_checks(robot: Robot, poses=None, *, step: float = 1e-7, rtol: float = 1e-4,
                 atol: float = 1e-9) -> Iterator[tuple[str, Callable[[], dict]]]:
    """The named checks of ``robot`` at ``poses`` (default: 8 Latin-hypercube poses of its
    workspace); ``step`` (SI) and ``rtol``/``atol`` set the finite-difference Jacobian check.

    Yields
    ------
    name : str
        The check's function name, e.g. ``"check_sensitivity_shape"``.
    check : callable
        The check bound to this robot's settings: no argument, returns a dict of measured numbers,
        raises :class:`evotol.errors.CheckFailed` on failure.

    Raises
    ------
    evotol.errors.ValidationError
        ``poses`` of the wrong shape or not finite (from ``robot.check_poses``, at the first
        ``next``).
    evotol.errors.KinematicsError
        A pose outside the workspace (same).
    """
    settings = _Settings(robot, poses, step, rtol, atol)
    for c in CHECKS:
        yield c.__name__, functools.partial(c, settings)


def check_robot(robot: Robot, poses=None, *, step: float = 1e-7, rtol: float = 1e-4,
                atol: float = 1e-9) -> dict:
    """Run every check of :func:`robot_checks` (like sklearn's ``check_estimator``); returns the
    merged measurements (e.g. ``fd_relative_mismatch``).

    Raises one :class:`evotol.errors.CheckFailed` listing every failed check (not only the first).

    Returns
    -------
    dict
        The measurements of every check merged into one dict (see each ``check_*`` function).

    Raises
    ------
    evotol.errors.CheckFailed
        One or more checks failed; the message lists them all.
    evotol.errors.ValidationError
        ``poses`` of the wrong shape or not finite (from ``robot.check_poses``).
    evotol.errors.KinematicsError
        A pose outside the workspace.
    """
    return run_checks(str(robot.name), robot_checks(robot, poses, step=step, rtol=rtol, atol=atol))

"""Conformance checks for accuracy measures (contract in :mod:`evotol.measures.protocol`), one small
named check each, like :mod:`evotol.robots.checks` and :mod:`evotol.cost_models.checks`. They build a
:class:`~evotol.core.problem.ToleranceProblem`, so they sit beside the problem, not in the measures' package
(which the problem imports).

:func:`measure_checks` yields ``(name, check)`` pairs; :func:`check_measure` runs them all and
raises :class:`evotol.errors.CheckFailed` listing every failure. By default they run on
:func:`small_problem`: a linear arm with four interval sources (normal distributions, t = 3σ) at
three poses, small enough for the measure's :meth:`~evotol.measures.protocol.Measure.brute_force`.
A plugin author runs them in their own tests::

    @pytest.mark.parametrize("check", list(measure_checks(MY_MEASURE)), ids=lambda c: c[0])
    def test_my_measure(check):
        check[1]()

The parameters several definitions of this module share are described once, here.

Parameters
----------
s : _Settings
    The measure, the problem (default :func:`small_problem`) and four designs ``T``
    (n_designs, n_sources; SI), as :func:`measure_checks` binds them.
measure : Measure
    The measure object (registered or not).
"""
from __future__ import annotations

import functools
from typing import Callable, Iterator

import numpy as np

from evotol.cost_models.reciprocal import ReciprocalCost
from evotol.measures.protocol import COMPONENTS, Evaluation, Measure
from evotol._runtime.check_suite import require, run_checks
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from evotol.robots.base import RobotErrorModel, SourceSpec, Workspace

#: Evaluation fields that hold (n_designs, n_poses[, ...]) arrays
ARRAY_FIELDS = ("position", "orientation", "position_bound", "orientation_bound", "position_contrib",
                "orientation_contrib", "position_direction", "orientation_direction", "probability")


class LinearArm(RobotErrorModel):
    """A linear error model J(x) = A + x·B (fixed random 6×4 matrices, seed 3) over x in [0, 1]
    with four interval sources in m: the small problem of the measure checks."""

    name = "linear-arm"

    def __init__(self):
        rng = np.random.default_rng(3)
        self.sources = tuple(SourceSpec(f"l{j}", 1, "m", "length") for j in range(4))
        self.workspace = Workspace(("x",), (0.0,), (1.0,), ("m",))
        self._A, self._B = rng.normal(size=(6, 4)), rng.normal(size=(6, 4))

    def sensitivity(self, poses):
        """J(x) = A + x·B at each pose x in [0, 1] (m), shape (n, 6, 4): the four length sources
        (rows 0–2 position in m/m, rows 3–5 orientation in rad/m).

        Raises
        ------
        evotol.errors.ValidationError
            A malformed pose array.
        evotol.errors.KinematicsError
            A pose outside [0, 1].
        """
        x = self.check_poses(poses)[:, 0]
        return self._A[None] + x[:, None, None] * self._B[None]


def small_problem() -> ToleranceProblem:
    """Four interval sources of tolerance 20–100 µm (normal, t = 3σ), three poses, position
    bound 0.2 mm (first-order yield between 0.5 and 1 at the designs of the checks).

    Returns
    -------
    ToleranceProblem
        :class:`LinearArm` with reciprocal costs, poses x = 0, 0.5, 1 m, ``Requirement(position=2e-4)``.
    """
    tol = {f"l{j}": Tolerance(ReciprocalCost(1.0, 1.0, scale=1e-5), 2e-5, 1e-4, distribution="normal")
           for j in range(4)}
    return ToleranceProblem(LinearArm(), tol, Requirement(position=2e-4), [[0.0], [0.5], [1.0]])


def _designs(problem: ToleranceProblem, n: int = 4) -> np.ndarray:
    rng = np.random.default_rng(11)
    return problem.lower + rng.random((n, problem.n_sources)) * (problem.upper - problem.lower)


def _fields(ev: Evaluation) -> dict[str, np.ndarray]:
    return {f: np.asarray(getattr(ev, f)) for f in ARRAY_FIELDS if getattr(ev, f) is not None}


class _Settings:
    def __init__(self, measure: Measure, problem: ToleranceProblem | None):
        self.measure = measure
        self.problem = small_problem() if problem is None else problem
        self.T = _designs(self.problem)


def check_returns_evaluation(s: _Settings) -> dict:
    """An :class:`Evaluation` with (n_designs, n_poses) errors of every constrained component, a
    finite (n_designs,) violation equal to max(error / bound) − 1 for the errors it reports.

    Returns
    -------
    dict
        ``n_fields``: the number of array fields the evaluation fills.

    Raises
    ------
    evotol.errors.CheckFailed
        Not an Evaluation, a missing or non-finite error array of the wrong shape, or a
        wrong violation.
    """
    ev = s.measure.evaluate(s.problem, s.T)
    n, P = s.T.shape[0], s.problem.n_poses
    require(isinstance(ev, Evaluation), f"{s.measure.name}: evaluate returned {type(ev).__name__}, not an Evaluation")
    for comp, lim in s.problem.components:
        val = getattr(ev, comp)
        require(val is not None and np.shape(val) == (n, P) and np.all(np.isfinite(val)),
                f"{s.measure.name}: {comp} is {None if val is None else np.shape(val)}, expected finite ({n}, {P})")
    v = np.asarray(ev.violation)
    require(v.shape == (n,) and np.all(np.isfinite(v)), f"{s.measure.name}: violation shape {v.shape}, expected ({n},)")
    if ev.probability is None:    # a yield measure's violation is in probability, not in error
        ratio = np.max([np.max(getattr(ev, c), axis=1) / lim for c, lim in s.problem.components], axis=0) - 1
        require(np.allclose(v, ratio, rtol=1e-12, atol=1e-12), f"{s.measure.name}: violation {v} != max(error/bound) − 1 = {ratio}")
    return {"n_fields": len(_fields(ev))}


def check_monotone_in_t(s: _Settings) -> dict:
    """Larger tolerances never give smaller errors: t → 1.5 t, and one source at a time × 1.5,
    at every pose and component (relative decrease at most the measure's ``monotone_rtol``), and
    the violation never decreases beyond the same.

    Returns
    -------
    dict
        ``largest_relative_decrease``: the largest relative decrease of an error seen.

    Raises
    ------
    evotol.errors.CheckFailed
        An error or the violation decreases by more than ``monotone_rtol``.
    """
    base = s.measure.evaluate(s.problem, s.T)
    grown = [1.5 * s.T] + [s.T * np.where(np.arange(s.problem.n_sources) == j, 1.5, 1.0)
                           for j in range(s.problem.n_sources)]
    worst = 0.0
    for T1 in grown:
        ev = s.measure.evaluate(s.problem, T1)
        for comp in COMPONENTS:
            a, b = getattr(base, comp), getattr(ev, comp)
            if a is None:
                continue
            drop = float(np.max((a - b) / np.maximum(np.abs(a), 1e-300)))
            worst = max(worst, drop)
            require(drop <= s.measure.monotone_rtol, f"{s.measure.name}: {comp} decreases by {drop:.3g} (relative; "
                    f"allowed {s.measure.monotone_rtol:g}) when tolerances grow")
        require(np.all(ev.violation >= base.violation - s.measure.monotone_rtol * (1 + np.abs(base.violation))),
                f"{s.measure.name}: violation decreases when tolerances grow")
    return {"largest_relative_decrease": worst}


def check_equals_brute_force(s: _Settings) -> dict:
    """Equal to the measure's own brute-force computation (:meth:`Measure.brute_force`) on the
    small problem, within its declared ``brute_force_rtol`` / ``brute_force_atol``.

    Returns
    -------
    dict
        ``largest_brute_force_difference``: the largest absolute difference (units of the field).

    Raises
    ------
    evotol.errors.CheckFailed
        No ``brute_force``, an empty result, or a field that differs beyond ``brute_force_rtol`` /
        ``brute_force_atol``.
    """
    m = s.measure
    worst = 0.0
    for t in s.T[:2]:
        try:
            ref = m.brute_force(s.problem, t)
        except NotImplementedError:
            require(False, f"{m.name}: no brute_force() to check evaluate() against")
        ev = m.evaluate(s.problem, t[None])
        require(ref, f"{m.name}: brute_force returned no field")
        for f, r in ref.items():
            got = np.asarray(getattr(ev, f))[0]
            err = float(np.max(np.abs(got - r)))
            worst = max(worst, err)
            require(np.allclose(got, r, rtol=m.brute_force_rtol, atol=m.brute_force_atol),
                    f"{m.name}: {f} = {got} but brute force gives {r} (rtol {m.brute_force_rtol}, atol {m.brute_force_atol})")
    return {"largest_brute_force_difference": worst}


def check_vectorised(s: _Settings) -> dict:
    """Evaluating four designs at once equals evaluating them one by one (every array field).

    Returns
    -------
    dict
        Empty: nothing measured.

    Raises
    ------
    evotol.errors.CheckFailed
        A field present only one way, or a design's values that differ.
    """
    ev = _fields(s.measure.evaluate(s.problem, s.T))
    for i in range(s.T.shape[0]):
        one = _fields(s.measure.evaluate(s.problem, s.T[i:i + 1]))
        require(set(one) == set(ev), f"{s.measure.name}: fields {sorted(one)} alone, {sorted(ev)} together")
        for f, a in one.items():
            require(np.allclose(ev[f][i], a[0], rtol=1e-10, atol=1e-15),
                    f"{s.measure.name}: {f} of design {i} differs between the vectorised call and the loop")
    return {}


CHECKS: tuple[Callable[[_Settings], dict], ...] = (
    check_returns_evaluation, check_monotone_in_t, check_equals_brute_force, check_vectorised)


def measure_checks(measure: Measure, problem: ToleranceProblem | None = None) -> Iterator[tuple[str, Callable[[], dict]]]:
    """Yield ``(name, check)`` for every conformance check of ``measure``.

    Parameters
    ----------
    problem : ToleranceProblem, optional
        A small problem (default :func:`small_problem`); the measure's ``brute_force`` must handle it.

    Yields
    ------
    name : str
        The check's function name (e.g. ``"check_monotone_in_t"``).
    check : callable
        Takes no argument, raises :class:`evotol.errors.CheckFailed` and returns measured numbers.
    """
    settings = _Settings(measure, problem)
    for check in CHECKS:
        yield check.__name__, functools.partial(check, settings)


def check_measure(measure: Measure, problem: ToleranceProblem | None = None) -> dict:
    """Run every check of :func:`measure_checks`.

    Parameters
    ----------
    problem : ToleranceProblem, optional
        A small problem (default :func:`small_problem`).

    Returns
    -------
    dict
        What the checks measured.

    Raises
    ------
    evotol.errors.CheckFailed
        Listing every failed check.
    """
    return run_checks(f"measure {getattr(measure, 'name', measure)!r}", measure_checks(measure, problem))

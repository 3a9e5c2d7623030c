"""What evotol calls *feasible*: one rule for every allocator, and the repair that makes a final
design meet it.

**The rule.** A design is feasible when every free tolerance lies within its bounds and, for every
constrained component (position, orientation),

    proven upper bound of the largest error over the poses  ≤  requirement × (1 + FEASIBILITY_RTOL)

with ``FEASIBILITY_RTOL = 1e-6`` (0.5 nm on a 0.5 mm requirement: far below anything a drawing
carries, far above round-off). The proven bound is the measure's own: for the worst case, the
certified bound of :mod:`evotol.measures.linear.proven_bound` (tightened to 1e-8 relative at the poses that can
hold the maximum, so a design allocated to hold the requirement with equality is not rejected for
the looseness of a direction grid); for RSS and a quantile, the value itself (exact); for joint
clearances, the certified engine's bound; for yield, the yield's lower bound against the required
probability (``Evaluation.violation``).

**The repair.** A GA or NSGA-II may end a hair outside (its penalty and its direction sample see the
attained value, not the proven bound). A miss of at most ``REPAIR_MAX`` = 0.1 % is repaired; a larger
one is a rule's own answer (e.g. a paper's sensitivity rule) and is reported infeasible, unchanged;
a search method (GA, cutting planes, the polyblock bracket) is repaired whatever its miss. :func:`repair_by_scaling` scales the free tolerances by one
factor s < 1 until the rule holds (every measure is non-decreasing in each tolerance) and reports
s. The allocators whose final design needs it call :func:`hold_to_rule` as an explicit last step
(``result.info["feasibility_repair"]``); :func:`evotol.core.result.make_result` then only builds the
result of the design it is given.

The parameters several definitions of this module share are described once, here.

Parameters
----------
t : array_like, shape (n_sources,)
    The design (SI: m or rad).
problem : evotol.core.problem.ToleranceProblem
    The problem.
"""
from __future__ import annotations

import numpy as np

from evotol.measures import linear as measures
from evotol.measures.linear.proven_bound import certified_max

#: relative tolerance of the feasibility rule (see module docstring)
FEASIBILITY_RTOL = 1e-6
#: relative tolerance to which the worst-case bound is tightened before the rule is read
BOUND_RTOL = 1e-8
#: a design further outside than this (relative) is not "a hair outside": it is reported as the
#: method gave it (infeasible), not rescaled -- a rule such as a paper's sensitivity method keeps its answer
REPAIR_MAX = 1e-3


def tighten_bounds(problem, ev, t: np.ndarray) -> None:
    """Tighten ``ev.<component>_bound`` of one design ``t`` in place (worst-case measure only).

    Only poses whose grid bound exceeds the requirement × (1 + FEASIBILITY_RTOL) are refined: the
    others already meet the rule, whatever their exact maximum.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem; nothing is done unless its measure is ``worst_case`` without clearances.
    ev : Evaluation
        The evaluation of the one design ``t`` (first row used); its ``*_bound`` (m, rad) are
        lowered to the certified bound of :func:`evotol.measures.linear.proven_bound.certified_max` and its
        attained values raised to what that search attains.
    t : ndarray, shape (n_sources,)
        The design (SI: m or rad).
    """
    _tighten(problem, ev, np.asarray(t, dtype=float))


def _tighten(problem, ev, t: np.ndarray) -> list:
    """:func:`tighten_bounds`' search, in place; returns ``(component, requirement, pose, attained, direction)`` of
    each pose it searched (the direction ``None`` when the value passed in was not beaten), for
    :func:`proven_cuts`."""
    if problem.requirement.measure != "worst_case" or problem.clearances is not None:
        return []
    shape = None if problem.shape.plain else problem.shape
    found = []
    for comp, lim in problem.components:
        bound = getattr(ev, f"{comp}_bound")
        value = getattr(ev, comp)
        if bound is None or value is None:
            continue
        D, delta = problem.directions(comp)
        blocks = problem.blocks[comp]
        for p in np.flatnonzero(bound[0] > lim * (1 + FEASIBILITY_RTOL)):
            b, attained, u = certified_max([B[p:p + 1] for B in blocks], t, D, delta, float(value[0, p]), shape,
                                           rtol=BOUND_RTOL, return_direction=True)
            bound[0, p] = min(float(bound[0, p]), b)
            value[0, p] = max(float(value[0, p]), attained)
            found.append((comp, lim, int(p), attained, u))
    return found


def proven_cuts(problem, rows, t: np.ndarray, return_evaluation: bool = False):
    """Add to a cutting-plane working set (:class:`evotol.measures.constraints.ConstraintRows`) the rows of
    the directions where the certified search of :mod:`evotol.measures.linear.proven_bound` finds design ``t``
    above the requirement (directions the ascent from the grid missed). Returns the rows added;
    0 means ``t`` meets the rule as far as the worst case goes.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem; nothing is added unless its measure is ``worst_case`` without clearances.
    rows : evotol.measures.constraints.ConstraintRows
        The working set, extended in place with rows ``row·t / requirement`` (+ constant).
    return_evaluation : bool
        Also return the evaluation of ``t`` with its bounds tightened: the search is the one
        :func:`tighten_bounds` makes (same poses, same calls), so this equals
        :func:`evaluate_proven` of ``t`` bit for bit and a caller need not search again.

    Returns
    -------
    int or (int, Evaluation)
        Number of rows added; with ``return_evaluation``, also the tightened evaluation (``None``
        when the measure is not ``worst_case`` or there are clearance sources).
    """
    if problem.requirement.measure != "worst_case" or problem.clearances is not None:
        return (0, None) if return_evaluation else 0
    t = np.asarray(t, dtype=float)
    ev = problem.evaluate(t[None])
    added = 0
    for comp, lim, p, attained, u in _tighten(problem, ev, t):      # the search tighten_bounds makes
        if u is not None and attained > lim * (1 + 0.1 * FEASIBILITY_RTOL):
            row, const = problem.support_row(comp, p, u)
            added += rows._add_linear(row[None] / lim, [(comp, p, tuple(np.round(u, 12)))], [const / lim])
    return (added, ev) if return_evaluation else added


def bound_ratio(problem, ev) -> float:
    """Largest proven error / requirement over components and poses (1 = exactly at it).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        Supplies the constrained components, their bounds and the measure.
    ev : Evaluation
        Evaluation of one design (first row used); ``*_bound`` where present, else the values.

    Returns
    -------
    float
        The ratio (dimensionless); for the ``yield`` measure ``violation + 1``. NaN when an error
        (or the violation) is NaN.
    """
    if problem.requirement.measure == "yield":
        return float(ev.violation[0] + 1)
    ratios = []
    for comp, lim in problem.components:
        b = getattr(ev, f"{comp}_bound")
        if b is None:
            b = getattr(ev, comp)
        ratios.append(float(np.max(b[0])) / lim)
    return float(np.max(ratios, initial=-np.inf))      # NaN anywhere stays NaN (never "met")


def meets_requirement(problem, ev) -> bool:
    """The rule (module docstring) for one evaluated design.

    Parameters
    ----------
    ev : Evaluation
        Evaluation of one design (ideally :func:`evaluate_proven`'s).

    Returns
    -------
    bool
        ``bound_ratio(problem, ev) <= 1 + FEASIBILITY_RTOL``.
    """
    return bound_ratio(problem, ev) <= 1 + FEASIBILITY_RTOL


def evaluate_proven(problem, t: np.ndarray):
    """Exact evaluation of one design with its worst-case bound tightened: ``Evaluation``.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem (its requirement's measure is used).

    Returns
    -------
    Evaluation
        One row (n_designs = 1), bounds tightened by :func:`tighten_bounds`.
    """
    ev = problem.evaluate(np.asarray(t, dtype=float)[None])
    tighten_bounds(problem, ev, np.asarray(t, dtype=float))
    return ev


def repair_by_scaling(problem, t: np.ndarray, ev=None, max_steps: int = 40, max_miss: float = REPAIR_MAX):
    """Scale the free tolerances of ``t`` until the rule holds.

    Parameters
    ----------
    problem : ToleranceProblem
        The problem (bounds, free variables, requirement).
    t : ndarray
        Full design (n_sources,), SI.
    ev : Evaluation, optional
        Its proven evaluation (:func:`evaluate_proven`), if already computed.
    max_steps : int
        Largest number of scaling steps (each evaluates the scaled design).
    max_miss : float
        Largest relative miss repaired (default ``REPAIR_MAX``, for rules whose answer is their own;
        a search method -- GA, NSGA-II, cutting planes -- passes ``inf``: its final design is only
        as good as its last generation).

    Returns
    -------
    (t, ev, info) : tuple
        The repaired design and its proven evaluation, and ``info`` = ``{"scale": s, "ratio_before":
        ..., "ratio_after": ...}`` or ``None`` when no repair was needed. When scaling down to the
        lower bounds cannot meet the rule, or the ratio is not finite (inf or NaN), ``t`` is
        returned unchanged with ``info["failed"] = True`` (the result is then reported infeasible).
    """
    t = np.asarray(t, dtype=float)
    ev = evaluate_proven(problem, t) if ev is None else ev
    ratio0 = bound_ratio(problem, ev)
    if ratio0 <= 1 + FEASIBILITY_RTOL:
        return t, ev, None
    if not np.isfinite(ratio0):     # inf or NaN: no scale can be aimed at, nothing is proven
        return t, ev, {"scale": 1.0, "ratio_before": ratio0, "ratio_after": ratio0, "failed": True,
                       "reason": f"the proven error / requirement is {ratio0} (not finite): reported infeasible, "
                                 f"not repaired"}
    if ratio0 > 1 + max_miss:
        return t, ev, {"scale": 1.0, "ratio_before": ratio0, "ratio_after": ratio0, "failed": True,
                       "reason": f"misses the requirement by {ratio0 - 1:.2e} (relative), more than the "
                                 f"{max_miss:g} a repair may take: reported as the method gave it"}
    f = problem.free
    s_total, tt, ratio = 1.0, t.copy(), ratio0
    for _ in range(max_steps):
        # aim a little inside: the error is at most linear in the scale for centred intervals
        s = (1 + 0.5 * FEASIBILITY_RTOL) / ratio if problem.requirement.measure != "yield" else 1 - 2e-3
        s_total *= s
        # through the problem's variables: shared members follow their variable, locked sources stay
        tt = problem.full(np.maximum(t[f] * s_total, problem.lower[f])[None])[0]
        ev = evaluate_proven(problem, tt)
        ratio = bound_ratio(problem, ev)
        if ratio <= 1 + FEASIBILITY_RTOL:
            return tt, ev, {"scale": s_total, "ratio_before": ratio0, "ratio_after": ratio}
        if np.all(tt[f] <= problem.lower[f]):
            break
    return t, evaluate_proven(problem, t), {"scale": 1.0, "ratio_before": ratio0, "ratio_after": ratio0, "failed": True}


def hold_to_rule(problem, t, max_miss: float = REPAIR_MAX, evaluation=None):
    """An allocator's final design held to the rule: its proven evaluation and, when it misses by at
    most ``max_miss``, the free tolerances scaled until it holds (:func:`repair_by_scaling`).

    Parameters
    ----------
    t : array_like or mapping
        The final design (SI: m or rad), anything ``problem.as_array`` takes.
    max_miss : float
        Largest relative miss repaired: ``REPAIR_MAX`` for a rule's answer (sensitivity, Lagrange,
        equal tolerance), ``inf`` for a search method (GA, cutting planes, the polyblock bracket).
    evaluation : Evaluation, optional
        The proven evaluation of ``t`` (:func:`evaluate_proven`, or :func:`proven_cuts` with
        ``return_evaluation``) when the caller has it; default: computed here.

    Returns
    -------
    t : numpy.ndarray, shape (n_sources,)
        The design to report (SI: m or rad): scaled, or as given.
    ev : Evaluation
        Its proven evaluation (:func:`evaluate_proven`), for :func:`evotol.core.result.make_result`.
    info : dict
        ``{"feasibility_repair": {...}}`` (:func:`repair_by_scaling`'s record) when the design missed
        the rule, else empty.

    Raises
    ------
    evotol.errors.ValidationError
        A design that is not one non-negative finite value per source.
    """
    t = np.asarray(problem.as_array(t), dtype=float)
    t, ev, fix = repair_by_scaling(problem, t, ev=evaluation, max_miss=max_miss)
    return t, ev, ({} if fix is None else {"feasibility_repair": fix})


__all__ = ["FEASIBILITY_RTOL", "REPAIR_MAX", "proven_cuts", "bound_ratio", "meets_requirement", "evaluate_proven",
           "repair_by_scaling", "hold_to_rule", "tighten_bounds"]

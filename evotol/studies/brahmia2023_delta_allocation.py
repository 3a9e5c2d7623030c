"""Part 2 of the ``brahmia2023-delta`` study (beyond the paper): the 47 Delta tolerances as an evotol
:class:`~evotol.core.problem.ToleranceProblem` -- a reciprocal cost model per family (linear /
angular), a worst-case position requirement over workspace poses, the paper's asymmetric
intervals stated through the core (Table 3 included) and the screening of critical poses.

Units: SI inside (m, rad); cost models read tolerances in µm or millidegrees (``UM``, ``MDEG``).
"""
from __future__ import annotations

import numpy as np

from evotol.studies.brahmia2023_delta_paper import table3_si
from evotol.robots.delta import DeltaRobot
from evotol.robots.delta_synthesis import REQUIRED_MM

UM, MDEG = 1e-6, np.radians(1e-3)      # cost-model units: micrometre, millidegree
COST_A0, COST_A1 = 1.0, 10.0
T_MIN, T_MAX = 0.5, 100.0              # tolerance range, in µm (linear) or mdeg (angular)


def family_cost_models():
    """Cost model per parameter family (an assumption: the paper has none).

    Reciprocal model c = a0 + a1/x (Chase & Greenwood 1988) with a0 = 1, a1 = 10 and x the
    tolerance in micrometres (linear family) or millidegrees (angular family): a +-10 µm length
    or +-10 mdeg angle costs 2 units, +-1 µm or +-1 mdeg costs 11.

    Returns
    -------
    dict of str to evotol.cost_models.ReciprocalCost
        ``"linear"`` (tolerance scaled by 1 µm) and ``"angular"`` (scaled by 1 mdeg); both take
        the tolerance in SI (m or rad) and return cost units.
    """
    from evotol.cost_models import ReciprocalCost

    return {"linear": ReciprocalCost(COST_A0, COST_A1, scale=UM), "angular": ReciprocalCost(COST_A0, COST_A1, scale=MDEG)}


def tolerance_problem(robot: DeltaRobot, poses, position_mm: float = REQUIRED_MM, n_directions: int = 400):
    """ToleranceProblem of the 47 Delta parameters: worst-case ``|δp| <= position_mm`` at ``poses``.

    Tolerances range over [0.5, 100] µm or mdeg. Sources with no first-order effect anywhere
    (Δd_i and Δq2_i, see docs/delta.md) are locked at the upper bound.

    Parameters
    ----------
    robot : evotol.robots.delta.DeltaRobot
        The Delta robot model (its 47 sources).
    poses : (n, 3) array_like
        Platform positions, m.
    position_mm : float, optional
        Required worst-case position error, mm (default 0.2 mm).
    n_directions : int, optional
        Number of directions of the worst-case measure (passed to the problem).

    Returns
    -------
    evotol.core.problem.ToleranceProblem
        Problem with the cost models of :func:`family_cost_models` and the requirement
        ``position = position_mm`` (converted to m), ``measure="worst_case"``.
    """
    from evotol.core.problem import Requirement, Tolerance, ToleranceProblem

    models = family_cost_models()
    S = robot.sensitivity(poses)[:, :3]
    no_effect = np.max(np.abs(S), axis=(0, 1)) < 1e-12
    tols = {}
    for k, s in enumerate(robot.sources):
        unit = UM if s.unit == "m" else MDEG
        tols[s.name] = Tolerance(models[s.group], T_MIN * unit, T_MAX * unit,
                                 locked=T_MAX * unit if no_effect[k] else None)
    return ToleranceProblem(robot, tols, Requirement(position=position_mm * 1e-3, measure="worst_case"), poses,
                            n_directions=n_directions)


def interval_problem(problem, lo, hi):
    """The problem with every source on its interval [lo_j, hi_j] (SI), stated through the core's
    asymmetric tolerances: ``Tolerance.offset`` = (lo + hi)/2 and the design t = (hi − lo)/2.
    Costs follow the core's ``cost_width="half"`` (the cost model sees the half-width), the
    worst case keeps the offset (full sphere of directions, :mod:`evotol.measures.linear`).
    Returns (problem, t).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The symmetric problem (e.g. from :func:`tolerance_problem`).
    lo, hi : (n_sources,) array_like
        Lower and upper interval limits per source, SI (m or rad).

    Returns
    -------
    problem : evotol.core.problem.ToleranceProblem
        Copy with ``offset = (lo + hi)/2`` and ``cost_width="half"`` for every source.
    t : (n_sources,) ndarray
        The design: half-widths ``(hi - lo)/2``, SI.

    Raises
    ------
    ValidationError
        If a changed tolerance does not validate (from ``ToleranceProblem.with_tolerances``).
    """
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return problem.with_tolerances(offset=(lo + hi) / 2, cost_width="half"), (hi - lo) / 2


def table3_problem(problem):
    """Table 3 of the paper with its printed asymmetric intervals, through the core (SI).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The symmetric 47-source problem (from :func:`tolerance_problem`).

    Returns
    -------
    problem : evotol.core.problem.ToleranceProblem
        Copy with the Table 3 interval centres as offsets (see :func:`interval_problem`).
    t : (47,) ndarray
        Table 3 half-widths, m or rad.
    """
    return interval_problem(problem, *table3_si())


def critical_poses(problem, designs, k: int = 8) -> np.ndarray:
    """Indices of the poses that hold the largest worst-case errors of some probe designs
    (top ``k`` per design) -- the screening set the allocators run on before dense verification.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        Problem over the dense pose set.
    designs : (n_designs, n_sources) or (n_sources,) array_like
        Probe tolerance designs, SI (m or rad).
    k : int, optional
        Number of worst poses kept per design.

    Returns
    -------
    1-D ndarray of int
        Sorted, unique pose indices into ``problem``'s poses.
    """
    ev = problem.evaluate(np.atleast_2d(designs), top_only=True)
    val = ev.position
    return np.unique(np.concatenate([np.argsort(-v)[:k] for v in val]))


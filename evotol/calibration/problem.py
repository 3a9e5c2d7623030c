"""A tolerance problem for a robot that will be calibrated: :func:`calibrated_problem`.

The problem keeps the user's tolerances, cost models and poses; it changes three things
(``docs/calibration.md``):

1. the robot is the :class:`~evotol.calibration.model.CalibratedRobot` of the plan (first-order
   map ``J M``), so every allocator and measure sees the error left after compensation;
2. the requirement gives the instrument noise its share (:func:`evotol.calibration.model.noise_allowance`:
   ``k`` sigma off worst-case bounds, in quadrature for ``rss``, in the covariance for ``yield``);
3. each identified source's upper bound is lowered to its linear range and the controller's
   compensation range (:mod:`evotol.calibration.linear_range`), so it never runs to infinity.

The result carries ``problem.calibration`` (:class:`CalibrationInfo`: the plan, the identification,
the noise allowance, the bounds) and ``problem.uncalibrated`` (the problem it was made from), for
the report's side-by-side comparison.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from evotol.calibration.configurations import is_described
from evotol.calibration.identification import Identification, identify
from evotol.calibration.linear_range import (calibrated_upper_bounds, checked_range, noise_second_order,
                                             remainder_allowance, second_order_norms)
from evotol.calibration.model import NOISE_RULE, CalibratedRobot, noise_allowance
from evotol.calibration.plan import CalibrationPlan
from evotol.calibration.noise_share import level_of
from evotol.calibration.random_allocation import least_cost
from evotol.calibration.random_budget import RandomBudget
from evotol.calibration.random_share import RandomPart, iso_terms, random_terms, unit_terms
from evotol.measures.iso9283.figures import ap_worst_case
from evotol.core.problem import ToleranceProblem
from evotol.errors import ValidationError


@dataclass
class CalibrationInfo:
    """What a calibrated problem was made with (SI).

    Parameters
    ----------
    identification : evotol.calibration.identification.Identification
        Its identification.
    noise : dict
        :func:`evotol.calibration.model.noise_allowance` of the user's requirement.
    bounds : dict
        :func:`evotol.calibration.linear_range.calibrated_upper_bounds`, plus each source's
        ``upper`` before and after.
    requirement : evotol.core.requirement.Requirement
        The user's requirement (the problem's is the geometric share).
    simulate : int
        Robots of the simulated calibration per design in a study (``[calibration] simulate``).
    random : evotol.calibration.random_share.RandomPart or None
        The robot's random sources (issue 44 item 4), in the budget beside the noise; None: none.
    random_allocation : dict or None
        :func:`evotol.calibration.random_allocation.allocate_random`'s result when they were allocated.
    random_budget : evotol.calibration.random_budget.RandomBudget or None
        The budget they were allocated in, which the study's other methods allocate them in too
        (:mod:`evotol.calibration.random_rules`); not in the JSON.
    """

    plan: CalibrationPlan
    identification: Identification
    noise: dict
    bounds: dict
    requirement: object
    simulate: int = 200
    random: RandomPart | None = None
    random_allocation: dict | None = None
    random_budget: RandomBudget | None = None

    def to_dict(self) -> dict:
        """Plain data for the JSON summary and the report (SI).

        Returns
        -------
        dict
            ``identification`` (:meth:`Identification.to_dict`), ``noise``, ``tolerance_bounds``
            (``linear_range``, ``compensation_range``, ``upper_before``, ``upper``: source -> m or
            rad), the plan's
            ``measure``, ``instrument``, ``k``, ``linear_fraction`` and noise sigmas.
        """
        p = self.plan
        fields = ("linear_range", "compensation_range", "checked_range", "upper_before", "upper")
        bounds = {f: {n: b[f] for n, b in self.bounds.items() if b.get(f) is not None} for f in fields}
        return {"identification": self.identification.to_dict(), "noise": self.noise, "tolerance_bounds": bounds,
                "measure": list(p.measure), "instrument": p.instrument, "k": float(p.k),
                "linear_fraction": float(p.linear_fraction),
                "noise_sigma": {c: v.tolist() for c, v in p.noise.items()},
                "identify": p.identify if isinstance(p.identify, str) else list(p.identify),
                **({} if self.random is None else {"random_sources": {
                    s.name: float(t) for s, t in zip(self.random.sources, self.random.tolerances)}}),
                **({} if self.random_allocation is None else {"random_allocation": self.random_allocation})}


def check_composable(problem) -> None:
    """Refuse, before any work, the parts a calibration cannot be composed with (docs/combinations.md).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The uncalibrated problem.

    Raises
    ------
    evotol.errors.ValidationError
        One line naming the calibration and the other part, and why: joint clearances (a clearance
        is not identified by a geometric calibration); drawing callouts (their zone members are 2-D
        discs and faces, the identification and the controller's compensation work on 1-D source
        errors); per-axis limits (the noise allowance and the linear-range bounds are derived for
        the error's norm); every tolerance given (nothing to allocate: the analysis of a given
        design does not model the calibration); a model without joint maps (no linear-range bound
        and no simulated calibration could be derived).
    """
    robot = problem.model
    if problem.clearances is not None:
        raise ValidationError("calibration", "clearances", "a problem without clearance sources (a clearance is not "
                              "identified by a geometric calibration)")
    if robot.part_of("callouts") is not None:
        raise ValidationError("calibration", "[[robot.callouts]]", "a robot without drawing callouts: calibration with "
                              "callouts is not supported (a callout's zone members are 2-D discs and faces; the "
                              "identification and the controller's compensation work on 1-D source errors)")
    if robot.part_of("axis_limits") is not None:
        raise ValidationError("calibration", "requirement per axis", "a requirement on the error's norm (position = "
                              "'0.5 mm'): calibration with per-axis limits is not supported (the noise allowance and "
                              "the linear-range bounds are derived for the norm)")
    if not problem.free.any():
        raise ValidationError("calibration", "every tolerance given", "at least one source free to allocate: the analysis "
                              "of given tolerances does not model a calibration (in Python, evotol.calibration."
                              "simulate_calibration(calibrated_problem(...), tolerances) checks a given design)")
    if not robot.joint_maps:
        raise ValidationError("calibration", robot.name, "a described mechanism (robot.mechanism or robot.urdf): its "
                              "joint maps give the linear-range bounds and the simulated calibration")


def _checked(robot, idn, plan, task_joints, req, norms, tolerances, bounds):
    """The upper bounds after the iterated fit's check (:func:`checked_range`), and the second-order allowance.

    Every free source's upper bound is scaled by the check's ``c`` when below 1 (``checked_range`` in
    ``bounds``); the allowance is the larger of the proven second-order term at the final bounds and
    the largest residual beyond first order the check saw (m, rad).
    """
    cols = [n.split("[")[0] for n in idn.source_names]
    b = np.array([tolerances[n].upper for n in cols], float)
    c, seen = checked_range(robot, idn, plan, task_joints, np.where(np.isfinite(b), b, 0.0), req)
    if c < 1:
        for n, tol in list(tolerances.items()):
            if tol.locked is None and n in bounds:
                tolerances[n] = dataclasses.replace(tol, upper=max(c * tol.upper, tol.lower))
                bounds[n]["checked_range"] = float(c * tol.upper)
        b = np.array([tolerances[n].upper for n in cols], float)
    proven = remainder_allowance(norms, np.where(np.isfinite(b), b, 0.0))
    return tolerances, {k: max(v, seen.get(k, 0.0)) for k, v in proven.items()}


#: share of the requirement kept for the systematic residual when the random sources are allocated after
#: calibration (a calibration that leaves no first-order error would otherwise leave the tolerances a bound of 0)
SYSTEMATIC_RESERVE = 0.01


def _allocate_random(robot, cal, idn, plan, problem, tolerances, second, remainder, random):
    """The random sources allocated within what calibration leaves (evotol.calibration.random_allocation)."""
    E = problem.requirement.position
    if E is None:
        raise ValidationError("iso9283.allocate", True, "a position requirement to allocate random sources for")
    up = np.array([tolerances[n].upper for n in robot.source_names], float)
    JM = np.asarray(cal.sensitivity(problem.poses), float)[:, :3]
    wc_sys = float(ap_worst_case(JM, np.zeros(len(up)), up)[1].max())
    d = float((second or {}).get("position", 0.0)) + float((remainder or {}).get("position", 0.0))
    budget = E - d - wc_sys - SYSTEMATIC_RESERVE * E      # the systematic share keeps a margin: a requirement row > 0
    u = unit_terms(robot, idn, plan, problem.poses, random)
    C0 = cal.noise_covariance(problem.poses)[:, :3, :3]
    iso = None
    if random.iso is not None:      # ISO 9283 AP/RP required after calibration too (issue 44, docs/iso9283.md)
        iso = iso_terms(cal, idn, plan, random, up)
        iso["AP_budget"] = None if random.iso.AP is None else random.iso.AP - d
    rb = RandomBudget(C0, u["covariance"], u["support"], u["cos_delta"], random.costs, random.lower, random.upper,
                      budget, level_of(plan.k), iso)
    al = least_cost(rb, start=np.array(random.tolerances))
    t = al.pop("tolerances")
    al.update(systematic_worst_case=wc_sys, second_order=d, joint_optimum=bool(wc_sys <= 1e-9 * E),
              tolerances={s.name: float(v) for s, v in zip(random.sources, t)},
              costs={s.name: float(c.cost(v)) for s, c, v in zip(random.sources, random.costs, t)},
              meaning="allocated with every systematic tolerance at its upper bound, "
                      + ("the joint optimum here: calibration leaves no systematic first-order error"
                         if wc_sys <= 1e-9 * E else "a sequential allocation: systematic first"))
    return dataclasses.replace(random, tolerances=tuple(float(v) for v in t)), al, rb


def calibrated_problem(problem, plan: CalibrationPlan, simulate: int = 200, random: RandomPart | None = None):
    """The problem of the same robot after the plan's calibration (module docstring).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The uncalibrated problem (a robot without clearance sources).
    plan : evotol.calibration.plan.CalibrationPlan
        The calibration plan.
    simulate : int
        Robots of the simulated calibration per design when a study is run (kept on ``calibration``).
    random : evotol.calibration.random_share.RandomPart, optional
        Random sources of the robot (lost motion, encoder resolution, bearing play) at their tolerances:
        they disturb the identification beside the noise and add their worst case at each pose
        (:mod:`evotol.calibration.random_share`); a worst-case requirement (``worst_case`` and the other
        bounds) and a described mechanism only.

    Returns
    -------
    evotol.core.problem.ToleranceProblem
        The calibrated problem, with ``calibration`` (:class:`CalibrationInfo`) and
        ``uncalibrated`` attributes.

    Raises
    ------
    evotol.errors.ValidationError
        A problem with clearance sources, a plan that is not a :class:`CalibrationPlan`, what
        :func:`evotol.calibration.identification.identify` refuses, a noise (with the random sources)
        that takes the whole requirement, random sources with an ``rss`` or ``yield`` requirement or a
        model without joint maps.
    """
    if not isinstance(plan, CalibrationPlan):
        raise ValidationError("calibration", plan, "an evotol.calibration.CalibrationPlan")
    check_composable(problem)
    robot = problem.model
    if random is not None and (problem.requirement.measure in NOISE_RULE or not is_described(robot)):
        raise ValidationError("calibration random sources", problem.requirement.measure if is_described(robot) else
                              robot.name, "a worst-case requirement on a described arm (random sources in a calibrated "
                              "budget are taken off the requirement by the triangle inequality)")
    idn = identify(robot, plan)
    cal = CalibratedRobot(robot, idn, plan)
    req = problem.requirement
    task_joints, second, norms = None, None, None
    if is_described(robot):
        q = robot.joint_values(problem.poses)
        task_joints = np.stack([np.asarray(q[v], float) for v in robot.kin.variables], axis=1)
        second = noise_second_order(robot, idn, plan, task_joints)
        norms = second_order_norms(robot, idn, plan, task_joints)
    cal.linear_range_checked = task_joints is not None
    bounds = calibrated_upper_bounds(robot, idn, plan, task_joints, req, norms)
    tolerances = dict(problem.tolerances)
    for n, b in bounds.items():
        tol = tolerances[n]
        b["upper_before"] = float(tol.upper)
        if b["bound"] is not None and b["bound"] < tol.upper and tol.locked is None:
            tolerances[n] = dataclasses.replace(tol, upper=max(b["bound"], tol.lower))
    remainder = None
    if task_joints is not None and plan.linear_fraction < 1:          # >= 1 (Python only): first order, no cap
        tolerances, remainder = _checked(robot, idn, plan, task_joints, req, norms, tolerances, bounds)
    for n, b in bounds.items():
        b["upper"] = float(tolerances[n].upper)
    allocation = random_budget = None
    if random is not None and random.allocated:     # the random sources are variables too (random_allocation.py)
        noise_allowance(cal, problem.poses, req, second, remainder)        # a noise alone too large: refused first
        random, allocation, random_budget = _allocate_random(robot, cal, idn, plan, problem, tolerances, second, remainder, random)
    extra = None if random is None else random_terms(robot, idn, plan, problem.poses, random)
    noise = noise_allowance(cal, problem.poses, req, second, remainder, extra)
    changes = {c: v["geometric_bound"] for c, v in noise.items() if isinstance(v, dict)}
    new_req = dataclasses.replace(req, **changes) if noise["rule"] != "covariance" else req
    shared = problem.shared or None
    out = ToleranceProblem(cal, tolerances, new_req, problem.poses, n_directions=problem.n_directions,
                           shared=shared, shared_cost=problem.shared_cost)
    out.calibration = CalibrationInfo(plan, idn, noise, bounds, req, int(simulate), random, allocation, random_budget)
    out.uncalibrated = problem
    return out

"""Analysis of given tolerances: what a set of tolerances gives, before (or instead of) allocating.

A tolerance engineer's first question is "what does this drawing give?". For a problem whose
every tolerance is fixed (``[sources.NAME] fixed = t`` for every source, or
``ToleranceProblem(..., all_given=True)``), :func:`analyse` computes, at every pose:

* the **worst case** of the norm of the position and orientation error (the ``worst_case``
  measure: attained value and proven bound, the worst direction, each source's share at the worst
  pose; :mod:`evotol.measures.linear`);
* the **per-axis range**: the lowest and highest error along x, y, z (position, m; orientation,
  rad), in the base frame (and the tool frame when the robot knows it), both signed limits:
  ``[Σ_j min(J_aj l_j, J_aj u_j), Σ_j max(J_aj l_j, J_aj u_j)]`` over the interval ends
  ``[l_j, u_j]`` of each source (exact for the linear model: the error is linear in each source,
  so each end is reached at a vertex of the box), and ``±t_j |J_a,j|`` for a disk or ball source;
* the **RSS** of the norm (the ``rss`` measure) and per axis (``sqrt(Σ_j (J_aj ρ_j t_j)²)`` around
  the mean shift);
* the **probability** that the requirement is met (the ``yield`` measure, under the stated
  distributions, first-order model; per axis with per-axis limits) and the **position error at a
  stated probability** (the
  bound at which that probability is reached, by bisection on the same model);
* the **Monte Carlo** check on the nonlinear model (:func:`evotol.verification.montecarlo.verify`), and the
  verdict of the requirement's own measure with the worst pose.

Everything is SI in :meth:`ToleranceAnalysis.to_dict`; reports convert.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evotol.core.axis_limits import configurations, tool_rotation
from evotol.core.problem import ToleranceProblem
from evotol.errors import ValidationError
from evotol.verification.montecarlo import verify
from evotol._runtime.random_state import seed_from
from evotol.robots.mechanism.posture.held import joints_at

AXES = ("x", "y", "z")
COMPONENT_ROWS = {"position": slice(0, 3), "orientation": slice(3, 6)}


def given_tolerances(problem) -> np.ndarray:
    """The design of a problem whose every source is fixed or locked (SI, source order).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem (``all_given=True`` or every source fixed/locked).

    Returns
    -------
    (n_sources,) ndarray
        The given tolerances (m or rad).

    Raises
    ------
    evotol.errors.ValidationError
        A source that is free (no value given).
    """
    t = np.asarray(problem.locked_values, float)
    free = [n for n, v in zip(problem.names, t) if not np.isfinite(v)]
    if free:
        raise ValidationError(f"sources.{free[0]}", None, "a given tolerance (fixed = t) for every source to analyse")
    return t


def axis_ranges(jacobian: np.ndarray, column_slices, ends: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest error along each row of the error twist over the tolerance box (linear model).

    Parameters
    ----------
    jacobian : (n_poses, 6, n_columns) ndarray
        First-order map of the stacked source errors (m or rad per unit).
    column_slices : sequence of slice
        Columns of each source.
    ends : (n_sources, 2) ndarray
        Interval ends [lower, upper] of each source (m or rad); for a disk or ball, [-t, t].
    t : (n_sources,) ndarray
        Tolerances (bound on the norm of a disk or ball source).

    Returns
    -------
    low, high : (n_poses, 6) ndarray
        Per pose and row (dx, dy, dz in m; rotation about x, y, z in rad) the signed extremes.
    """
    n = jacobian.shape[0]
    low, high = np.zeros((n, 6)), np.zeros((n, 6))
    for j, sl in enumerate(column_slices):
        B = jacobian[:, :, sl]
        if B.shape[2] == 1:
            a, b = B[..., 0] * ends[j, 0], B[..., 0] * ends[j, 1]
            low += np.minimum(a, b)
            high += np.maximum(a, b)
        else:                                   # a disk or ball: |e| <= t, each row ±t |B_row|
            r = np.linalg.norm(B, axis=2) * t[j]
            low -= r
            high += r
    return low, high


@dataclass
class ToleranceAnalysis:
    """What a set of given tolerances yields (module docstring); SI throughout.

    Parameters
    ----------
    names : tuple of str
        Source names.
    t : ndarray
        The given tolerances (m or rad).
    poses : ndarray
        The poses analysed (the robot's workspace coordinates, SI).
    requirement : dict
        Component -> bound (m or rad) and ``measure``.
    meets : bool
        The requirement's measure is within its bounds at every pose.
    violation : float
        Largest error / bound - 1 over the poses (requirement's measure).
    worst_case : dict
        Component -> {"value", "bound"} (n_poses,) norms, "worst_pose", "contributions" (%).
    axes : dict
        Frame -> component -> axis -> {"low", "high", "rss"} (n_poses,).
    rss : dict
        Component -> (n_poses,) RSS norm.
    probability : ndarray or None
        First-order probability of meeting the requirement per pose (yield measure).
    error_at_probability : dict
        ``{"probability": p, "position": (n_poses,)}``: the position bound met with probability p.
    probability_axes : dict
        With per-axis limits (:mod:`evotol.core.axis_limits`): axis label (``"x"``, ...) ->
        (n_poses,) first-order ``P(|δ_a| <= L_a)`` at each configuration -- per axis, not jointly
        (issue 41); empty otherwise.
    monte_carlo : dict
        :meth:`evotol.verification.montecarlo.MonteCarloResult.to_dict` on the nonlinear model.
    joints : dict
        Joint variable -> (n_poses,) values at the poses (rad or m), where known.
    """

    names: tuple
    t: np.ndarray
    poses: np.ndarray
    requirement: dict
    meets: bool
    violation: float
    worst_case: dict
    axes: dict
    rss: dict
    probability: np.ndarray | None = None
    error_at_probability: dict = field(default_factory=dict)
    probability_axes: dict = field(default_factory=dict)
    monte_carlo: dict = field(default_factory=dict)
    joints: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """JSON-ready, SI.

        Returns
        -------
        dict
            Every field, arrays as lists.
        """
        def plain(v):
            if isinstance(v, np.ndarray):
                return v.tolist()
            if isinstance(v, dict):
                return {k: plain(x) for k, x in v.items()}
            if isinstance(v, (list, tuple)):
                return [plain(x) for x in v]
            if isinstance(v, (np.floating, np.integer, np.bool_)):
                return v.item()
            return v
        return {k: plain(getattr(self, k)) for k in self.__dataclass_fields__}


def _base(problem):
    """The robot and configurations behind a per-axis problem (evotol.core.axis_limits), else the problem's."""
    return configurations(problem.model, problem.poses)


def error_at_probability(problem, t: np.ndarray, probability: float, component: str = "position",
                         rtol: float = 1e-6) -> np.ndarray:
    """The bound on ``component``'s error norm met with ``probability`` at each pose (first-order yield model).

    Bisection on the bound of the ``yield`` measure (:mod:`evotol.measures.statistical`): the smallest E with
    ``P(|δ| <= E) >= probability``, to ``rtol``.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        A problem on the robot's own poses (not per axis).
    t : (n_sources,) ndarray
        The tolerances (m or rad).
    probability : float
        In (0, 1).
    component : {"position", "orientation"}
        The error component.
    rtol : float
        Relative precision of the bisection.

    Returns
    -------
    (n_poses,) ndarray
        The error (m or rad) at that probability per pose.
    """
    other = "orientation" if component == "position" else "position"
    hi = np.max(problem.evaluate(t[None], measure="worst_case").__getattribute__(component)[0]) * 1.01 + 1e-300
    lo_b, hi_b = np.zeros(problem.n_poses), np.full(problem.n_poses, hi)
    base = problem.with_requirement(**{component: float(hi), other: None, "measure": "yield", "probability": probability,
                                       "ppm": None, "model": "linear"})
    for _ in range(60):
        mid = 0.5 * (lo_b + hi_b)
        ok = np.empty(problem.n_poses, bool)
        # one bound per pose: evaluate each distinct bound level on all poses, keep the pose's own
        for i in range(problem.n_poses):
            p = base.with_requirement(**{component: float(mid[i])}).with_poses([i])
            ok[i] = p.evaluate(t[None]).probability[0, 0] >= probability
        lo_b, hi_b = np.where(ok, lo_b, mid), np.where(ok, mid, hi_b)
        if np.all(hi_b - lo_b <= rtol * np.maximum(hi_b, 1e-300)):
            break
    return hi_b


def analyse(problem, t=None, *, probability: float = 0.9973, n_samples: int = 2000, seed: int = 0,
            nonlinear: bool = True, rng: int | np.random.Generator | None = None) -> ToleranceAnalysis:
    """Analyse given tolerances on a problem (see the module docstring).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem; its requirement gives the verdict and the probability's bounds.
    t : array_like or Mapping or None, optional
        The tolerances (SI); None: the problem's given (fixed/locked) ones.
    probability : float, optional
        The probability of the error quantile (default 0.9973, 3σ).
    n_samples : int, optional
        Monte Carlo samples per pose (0: none).
    seed : int, optional
        Seed of the Monte Carlo samples.
    nonlinear : bool, optional
        Also sample the nonlinear model where the robot has one.
    rng : int, numpy.random.Generator or None, optional
        As SciPy's ``rng``: an integer seed, or a Generator drawn from once for the seed of the run
        (recorded in the result); replaces ``seed`` (which keeps working, and also takes a Generator).

    Returns
    -------
    ToleranceAnalysis
        The analysis.

    Raises
    ------
    evotol.errors.ValidationError
        Tolerances missing or invalid, a probability outside (0, 1), or a problem with
        joint-clearance classes (not analysed here, issue 39).
    """
    if problem.clearances is not None:      # a pair refused before any work: its worst case is the certified engine's
        raise ValidationError("clearances", list(problem.clearances.names), "no joint-clearance classes in an analysis of "
                              "given tolerances: the analysis samples and splits the linear worst case, the clearance "
                              "classes have the certified engine's (check the design with problem.evaluate(t), or "
                              "leave a tolerance free to allocate)")
    seed = seed_from(rng, seed)
    if not (isinstance(probability, float) and 0 < probability < 1):
        raise ValidationError("probability", probability, "a probability in (0, 1)")
    t = given_tolerances(problem) if t is None else problem.as_array(t)
    ev = problem.evaluate(t[None])
    req = {c: lim for c, lim in problem.components}
    req["measure"] = problem.requirement.measure
    robot, configs = _base(problem)
    if robot is problem.model:
        bp = problem
    else:       # the norm quantities on the configurations themselves
        r = problem.requirement
        bp = ToleranceProblem(robot, problem.tolerances, r.__class__(position=r.position, orientation=r.orientation),
                              configs, all_given=True)
    wc = bp.evaluate(t[None], measure="worst_case")
    worst = {}
    for comp in ("position", "orientation"):
        val = getattr(wc, comp)[0]
        p = int(np.argmax(val))
        contrib = getattr(wc, f"{comp}_contrib")
        worst[comp] = {"value": val, "bound": getattr(wc, f"{comp}_bound")[0], "worst_pose": p,
                       "contributions": dict(zip(bp.names, (100 * contrib[0, p]).tolist())) if contrib is not None else {}}
    ends = bp.intervals(t)
    J = bp.jacobian
    frames = {"base": J}
    axis = problem.model.part_of("axis_limits")
    if axis is not None and axis.limits.frame == "tool":
        Rt = np.swapaxes(tool_rotation(robot, configs), 1, 2)
        frames["tool"] = np.concatenate([Rt @ J[:, 0:3], Rt @ J[:, 3:6]], axis=1)
    axes = {}
    rho_t = np.array([bp.shape.rho[j] * t[j] for j in range(len(t))])
    for frame, Jf in frames.items():
        low, high = axis_ranges(Jf, bp.model.column_slices, ends, t)
        rss_axis = np.sqrt(sum((np.linalg.norm(Jf[:, :, sl], axis=2) * rho_t[j]) ** 2
                               for j, sl in enumerate(bp.model.column_slices)))
        axes[frame] = {comp: {ax: {"low": low[:, rows.start + i], "high": high[:, rows.start + i],
                                   "rss": rss_axis[:, rows.start + i]} for i, ax in enumerate(AXES)}
                       for comp, rows in COMPONENT_ROWS.items()}
    rs = bp.evaluate(t[None], measure="rss")
    rss = {c: getattr(rs, c)[0] for c in ("position", "orientation")}
    prob, at_p = None, {}
    if problem.clearances is None:      # the yield model is the interval sources' (no clearance classes)
        yp = problem.with_requirement(measure="yield", probability=probability, ppm=None, model="linear")
        prob = yp.evaluate(t[None]).probability[0]
        at_p = {"probability": probability, "position": error_at_probability(bp, t, probability)}
    prob_axes = {}
    if prob is not None and axis is not None:   # one yield per (configuration, axis slot): P(meet) per axis
        P = np.asarray(prob).reshape(len(configs), axis.slots)
        prob_axes = {label: P[:, k] for k, label in enumerate(axis.coordinate_labels["axis"])}
    mc = {}
    if n_samples:
        mc = verify(problem, t, n_samples=int(n_samples), seed=seed, nonlinear=nonlinear).to_dict()
    joints = joints_at(robot, configs)
    return ToleranceAnalysis(names=tuple(problem.names), t=t, poses=configs, requirement=req,
                             meets=bool(ev.violation[0] <= 1e-9), violation=float(ev.violation[0]), worst_case=worst,
                             axes=axes, rss=rss, probability=prob, error_at_probability=at_p,
                             probability_axes=prob_axes, monte_carlo=mc,
                             joints=joints)

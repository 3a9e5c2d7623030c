"""Probabilistic tolerance allocation of the planar 5R mechanism (issue 5, item 4).

Design variables (SI): the radial clearance of the actuated joints ``clearance_A`` (m, both
A_1 and A_2), of the passive elbows ``clearance_B`` (m, both B_1 and B_2), and the actuator
angle error ``theta`` (rad, the standard deviation ``delta_theta`` of eq. 8, both motors). Link
lengths stay at Table 1 (``delta_r = 0.004 %``, independent per link).

Requirement: at every pose of the maximum inscribed workspace (the MIW poses of
:meth:`robots.planar5r.Planar5R.miw_poses`), the probability that the end-effector leaves the
circle of radius ``radius`` around its nominal position is at most ``p_max``; a sample that cannot
be assembled counts as leaving. The probability is estimated from the exact (nonlinear) loop
closure with a Latin hypercube of ``n_samples`` rows shared by every design (common random
numbers: the estimate is a deterministic function of the design, so the GA compares designs
without sampling noise); the final allocation is re-verified on a fresh, larger sample.

The core's :class:`evotol.problem.ToleranceProblem` measures are worst-case / RSS / a quantile of the
linear model with uniform or 3-sigma normal sources; this problem needs a per-pose exceedance
probability of the nonlinear model with contact-mode clearances (|c| = r_c exactly, Sec. 2.5),
so it is a small pymoo :class:`~pymoo.core.problem.Problem` here, built on ``cost_models`` and the
vectorised sampler of :mod:`robots.planar5r.uncertainty`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from cost_models import CostModel, ReciprocalCost, PowerCost
from evotol.errors import ValidationError
from robots.planar5r import Planar5R
from robots.planar5r import kinematics as K
from robots.planar5r import uncertainty as U

VARIABLES = ("clearance_A", "clearance_B", "theta")
UNITS = {"clearance_A": "m", "clearance_B": "m", "theta": "rad"}


def default_costs() -> dict[str, CostModel]:
    """Illustrative cost-tolerance models (the paper has none), per part:

    * journal-bearing fits, reciprocal ``c = a0 + a1 / (r_c / 1 um)`` (Chase & Greenwood):
      actuated joints ``1 + 20 / x`` (motor-side bearing), elbows ``0.5 + 10 / x``;
    * actuator accuracy (encoder + servo), power ``c = 4 (delta_theta / 0.01 deg)^-0.7``.
    """
    return {"clearance_A": ReciprocalCost(1.0, 20.0, scale=1e-6),
            "clearance_B": ReciprocalCost(0.5, 10.0, scale=1e-6),
            "theta": PowerCost(4.0, 0.7, scale=np.deg2rad(0.01))}


@dataclass
class AllocationSpec:
    """Settings of the allocation (SI units).

    case, D: design of Table 2 and its size (m). radius (m), p_max: the accuracy requirement.
    bounds: variable -> (lower, upper). multiplicity: parts per variable (two joints / motors).
    n_samples: LHS rows (common random numbers) inside the optimiser.
    """

    case: str = "b"
    D: float = 0.2
    radius: float = 0.1e-3
    p_max: float = 0.01
    bounds: dict = field(default_factory=lambda: {"clearance_A": (1e-6, 100e-6), "clearance_B": (1e-6, 100e-6),
                                                  "theta": (np.deg2rad(0.001), np.deg2rad(0.2))})
    costs: dict = field(default_factory=default_costs)
    multiplicity: dict = field(default_factory=lambda: {"clearance_A": 2, "clearance_B": 2, "theta": 2})
    n_samples: int = 1024
    seed: int = 0

    def __post_init__(self):
        for v in VARIABLES:
            lo, hi = self.bounds[v]
            if not (0 < lo < hi and np.isfinite(hi)):
                raise ValidationError(f"bounds[{v!r}]", (lo, hi), "0 < lower < upper (SI)")
            if not isinstance(self.costs[v], CostModel):
                raise ValidationError(f"costs[{v!r}]", self.costs[v], "a cost_models.CostModel")
            self.costs[v].validate_range(lo, hi)
        if not (self.radius > 0 and 0 < self.p_max < 1):
            raise ValidationError("requirement", (self.radius, self.p_max), "radius > 0 (m) and 0 < p_max < 1")


class ExceedanceModel:
    """Per-pose exceedance probability of many designs in one array pass.

    Unit errors are drawn once (lengths at Table 1, unit-std actuator errors, unit clearance
    direction vectors); a design ``(r_cA, r_cB, delta_theta)`` only rescales them.
    """

    def __init__(self, robot: Planar5R, poses: np.ndarray, radius: float, n_samples: int, seed=0,
                 method: str = "lhs"):
        self.robot, self.radius = robot, float(radius)
        self.poses = robot.check_poses(poses)
        self.theta = robot.nominal_angles(self.poses)
        model = U.UncertaintyModel(theta_std=1.0, clearance=1.0, shared_lengths=False, renormalise=False)
        unit = U.unit_samples(n_samples, model.n_dims, method, seed)
        self.err = model.errors_from_unit(unit, robot.r1, robot.r2, robot.r3)
        self.n_samples = int(n_samples)

    def exceed(self, T: np.ndarray, chunk: int = 250_000) -> np.ndarray:
        """P(|dP| > radius or no assembly), shape (n_designs, n_poses), for designs T (n, 3)."""
        T = np.atleast_2d(np.asarray(T, dtype=float))
        n_p, n_s = len(self.poses), self.n_samples
        step = max(1, chunk // (n_p * n_s))
        out = np.empty((len(T), n_p))
        th = self.theta[None, :, None, :]
        for a in range(0, len(T), step):
            t = T[a:a + step, :, None, None]                 # (m, 3, 1, 1): broadcast over poses, samples
            e = {k: v for k, v in self.err.items() if k.startswith("d") and not k.startswith("dth")}
            e["dth1"], e["dth2"] = t[:, 2] * self.err["dth1"], t[:, 2] * self.err["dth2"]
            for j, J in ((0, "A"), (1, "B")):
                for i in (1, 2):
                    e[f"c{J}{i}x"] = t[:, j] * self.err[f"c{J}{i}x"]
                    e[f"c{J}{i}y"] = t[:, j] * self.err[f"c{J}{i}y"]
            px, py, h2 = K.perturbed_position(th, self.robot.r1, self.robot.r2, self.robot.r3, e, self.robot.assembly)
            dev2 = (px - self.poses[None, :, 0, None]) ** 2 + (py - self.poses[None, :, 1, None]) ** 2
            out[a:a + step] = np.mean((dev2 > self.radius ** 2) | ~(h2 >= 0), axis=-1)
        return out


def _pymoo_problem(spec: AllocationSpec, em: ExceedanceModel, n_obj: int):
    from pymoo.core.problem import Problem

    lo = np.log10([spec.bounds[v][0] for v in VARIABLES])
    hi = np.log10([spec.bounds[v][1] for v in VARIABLES])

    class ClearanceAccuracyProblem(Problem):
        """x = log10 of (clearance_A, clearance_B, theta); f = cost [, max_pose P_exceed]."""

        def __init__(self):
            super().__init__(n_var=3, n_obj=n_obj, n_ieq_constr=1 if n_obj == 1 else 0, xl=lo, xu=hi)

        def _evaluate(self, X, out, *args, **kwargs):
            T = 10.0 ** X
            p = em.exceed(T).max(axis=1)
            c = total_cost(spec, T)
            if n_obj == 1:
                out["F"], out["G"] = c[:, None], (p - spec.p_max)[:, None]
            else:
                out["F"] = np.stack([c, p], -1)

    return ClearanceAccuracyProblem()


def total_cost(spec: AllocationSpec, T: np.ndarray) -> np.ndarray:
    """Cost of designs T (n, 3): sum over variables of multiplicity x cost(t)."""
    T = np.atleast_2d(T)
    return sum(spec.multiplicity[v] * spec.costs[v].cost(T[:, j]) for j, v in enumerate(VARIABLES))


def clopper_pearson_upper(k: int, n: int, conf: float = 0.95) -> float:
    """One-sided upper confidence bound of a binomial proportion."""
    return 1.0 if k >= n else float(stats.beta.ppf(conf, k + 1, n - k))


def allocate(spec: AllocationSpec, poses=None, pop_size: int = 40, n_gen: int = 40, n_verify: int = 20000,
             pareto: bool = True, grid: int = 0, n_calibrate: int | None = None) -> dict:
    """GA (cost subject to max_pose P_exceed <= p_max on the common sample), a calibration of
    the design's common scale on a larger independent sample (95 % upper confidence bound per
    pose <= p_max), a verification on a third sample, optionally NSGA-II (cost vs max_pose
    P_exceed) and a feasibility grid over (r_c, delta_theta) with r_cA = r_cB.
    Returns plain data (SI units)."""
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.algorithms.soo.nonconvex.ga import GA
    from pymoo.optimize import minimize

    robot = Planar5R(spec.case, D=spec.D)
    poses = robot.miw_poses() if poses is None else poses
    em = ExceedanceModel(robot, poses, spec.radius, spec.n_samples, seed=spec.seed)
    out = {"case": spec.case, "D": spec.D, "radius": spec.radius, "p_max": spec.p_max, "n_samples": spec.n_samples,
           "variables": list(VARIABLES), "units": UNITS, "bounds": {v: list(spec.bounds[v]) for v in VARIABLES},
           "costs": {v: repr(spec.costs[v]) for v in VARIABLES}, "n_poses": len(em.poses)}
    n_eval = 0

    res = minimize(_pymoo_problem(spec, em, 1), GA(pop_size=pop_size, eliminate_duplicates=True),
                   ("n_gen", n_gen), seed=spec.seed, verbose=False)
    n_eval += pop_size * n_gen
    if res.X is None:
        lo = np.array([[spec.bounds[v][0] for v in VARIABLES]])
        out.update(feasible=False, p_exceed_at_lower_bounds=float(em.exceed(lo).max()),
                   message="no design met the requirement within the bounds")
        return out
    T = 10.0 ** np.atleast_2d(np.asarray(res.X, dtype=float))
    ga_T, ga_cost = T.copy(), float(total_cost(spec, T)[0])
    # Calibration: the GA's estimate comes from n_samples rows and sits on the constraint, so it
    # is optimistic. On a larger, independent sample, find the largest common factor s applied to
    # the GA design whose per-pose 95 % Clopper-Pearson upper bound still meets p_max (bisection;
    # the exceedance grows with every tolerance, so the test is monotone in s).
    cal = ExceedanceModel(robot, em.poses, spec.radius, n_calibrate or 8 * spec.n_samples, seed=spec.seed + 104729)

    def certified(s):
        k = np.round(cal.exceed(T * s)[0] * cal.n_samples).astype(int)
        return max(clopper_pearson_upper(int(ki), cal.n_samples) for ki in k) <= spec.p_max

    lower = np.array([spec.bounds[v][0] for v in VARIABLES])
    upper = np.array([spec.bounds[v][1] for v in VARIABLES])
    s_lo, s_hi = float(np.max(lower / T)), float(np.min(upper / T))
    if not certified(s_lo):
        out.update(feasible=False, ga_tolerances={v: float(ga_T[0, j]) for j, v in enumerate(VARIABLES)},
                   message="the GA design scaled to the lower bounds does not meet the requirement with 95 % confidence")
        return out
    if certified(s_hi):
        s_lo = s_hi
    else:
        for _ in range(40):
            mid = np.sqrt(s_lo * s_hi)
            s_lo, s_hi = (mid, s_hi) if certified(mid) else (s_lo, mid)
    n_eval += 42
    T = T * s_lo
    cost = float(total_cost(spec, T)[0])
    p_opt = em.exceed(T)[0]
    ver = ExceedanceModel(robot, em.poses, spec.radius, n_verify, seed=spec.seed + 7919)
    p_ver = ver.exceed(T)[0]
    k = int(round(p_ver.max() * n_verify))
    out.update(feasible=True, tolerances={v: float(T[0, j]) for j, v in enumerate(VARIABLES)}, cost=cost,
               ga_tolerances={v: float(ga_T[0, j]) for j, v in enumerate(VARIABLES)}, ga_cost=ga_cost,
               calibration_factor=s_lo, n_calibrate=cal.n_samples, p_exceed_optimiser=p_opt.tolist(),
               p_exceed_verified=p_ver.tolist(), p_exceed_verified_max=float(p_ver.max()),
               p_exceed_verified_upper95=clopper_pearson_upper(k, n_verify), n_verify=n_verify,
               cost_parts={v: float(spec.multiplicity[v] * spec.costs[v].cost(T[0, j])) for j, v in enumerate(VARIABLES)})
    if pareto:
        r2 = minimize(_pymoo_problem(spec, em, 2), NSGA2(pop_size=pop_size), ("n_gen", n_gen), seed=spec.seed,
                      verbose=False)
        n_eval += pop_size * n_gen
        F, X = np.atleast_2d(r2.F), 10.0 ** np.atleast_2d(r2.X)
        order = np.argsort(F[:, 0])
        out["pareto"] = {"cost": F[order, 0].tolist(), "p_exceed": F[order, 1].tolist(),
                         **{v: X[order, j].tolist() for j, v in enumerate(VARIABLES)}}
    if grid:
        rc = np.geomspace(*spec.bounds["clearance_A"], grid)
        dth = np.geomspace(*spec.bounds["theta"], grid)
        RC, DT = np.meshgrid(rc, dth)
        G = np.stack([RC.ravel(), RC.ravel(), DT.ravel()], -1)
        P = em.exceed(G).max(axis=1).reshape(RC.shape)
        C = total_cost(spec, G).reshape(RC.shape)
        n_eval += len(G)
        feas = P <= spec.p_max
        best = np.unravel_index(np.argmin(np.where(feas, C, np.inf)), C.shape) if feas.any() else None
        out["grid"] = {"clearance": rc.tolist(), "theta": dth.tolist(), "p_exceed_max": P.tolist(), "cost": C.tolist(),
                       "best_equal_clearance": None if best is None else
                       {"clearance": float(RC[best]), "theta": float(DT[best]), "cost": float(C[best])}}
    out["n_design_evaluations"] = n_eval
    out["pose_samples_evaluated"] = int(n_eval * len(em.poses) * spec.n_samples)
    return out


def worst_case_allocation(spec: AllocationSpec, poses=None, sigma_multiple: float = 3.0) -> dict:
    """The deterministic counterpart through the evotol core: :class:`evotol.problem.ToleranceProblem`
    with the exact worst-case measure and :func:`evotol.allocators.allocate_optimum` (certified).

    Every source of :class:`Planar5R` gets its own tolerance: clearances are disks ``|c| <= r_c``
    with the costs of ``spec``; the actuator errors are intervals ``|dtheta| <= t`` with
    ``t = sigma_multiple x std``, costed as ``spec.costs["theta"](t / sigma_multiple)``; link
    lengths are locked at ``sigma_multiple x`` their Table 1 std. The requirement is
    ``|dP| <= radius`` for every admissible error. Returns the design (SI), its cost on the same
    cost models as :func:`allocate`, and its exceedance under the probabilistic model.
    """
    from evotol.allocators import allocate_optimum
    from evotol.problem import Requirement, Tolerance

    robot = Planar5R(spec.case, D=spec.D)
    poses = robot.miw_poses() if poses is None else poses
    k = float(sigma_multiple)
    th = spec.costs["theta"]
    theta_cost = type(th)(*th.p, scale=th.scale * k)
    tiny = ReciprocalCost(1e-12, 1e-12, scale=1e-6)          # locked sources: no cost to speak of
    tol = {}
    for name, length in (("A1B1", robot.r1), ("A2B2", robot.r1), ("B1P", robot.r2), ("B2P", robot.r2),
                         ("OA1", robot.r3), ("OA2", robot.r3)):
        t_len = k * U.DELTA_R * length
        tol[name] = Tolerance(cost=tiny, lower=0.5 * t_len, upper=2 * t_len, locked=t_len)  # lower == upper is refused
    lo_t, hi_t = spec.bounds["theta"]
    for name in ("theta1", "theta2"):
        tol[name] = Tolerance(cost=theta_cost, lower=k * lo_t, upper=k * hi_t)
    for J in ("A", "B"):
        for i in (1, 2):
            tol[f"clearance_{J}{i}"] = Tolerance(cost=spec.costs[f"clearance_{J}"], lower=spec.bounds[f"clearance_{J}"][0],
                                                 upper=spec.bounds[f"clearance_{J}"][1])
    from evotol.problem import ToleranceProblem

    problem = ToleranceProblem(robot, tol, Requirement(position=spec.radius, measure="worst_case"), poses=poses)
    res = allocate_optimum(problem)
    t = res.tolerances
    T = np.array([[max(t["clearance_A1"], t["clearance_A2"]), max(t["clearance_B1"], t["clearance_B2"]),
                   max(t["theta1"], t["theta2"]) / k]])
    em = ExceedanceModel(robot, problem.poses, spec.radius, 20000, seed=spec.seed + 31)
    free_cost = float(sum(tol[n].cost.cost(t[n]) for n in tol if tol[n].locked is None))
    return {"tolerances": {n: float(v) for n, v in t.items()}, "cost": free_cost, "feasible": bool(res.feasible),
            "max_position_error": res.max_error("position"), "certificate": res.certificate,
            "as_variables": {v: float(T[0, j]) for j, v in enumerate(VARIABLES)},
            "p_exceed_probabilistic_model": float(em.exceed(T).max()), "sigma_multiple": k}

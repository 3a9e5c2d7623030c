"""Tolerance allocation of the Lara-Molina et al. 2019 study (:mod:`evotol.studies.laramolina2019_5r`).

The joint clearances and the actuator accuracy of the planar 5R mechanism allocated through the
evotol core: shared tolerances (one per joint pair / motor pair), link lengths as fixed normal
sources (Table 1), contact-mode clearances (Sec. 2.5), a nonlinear ``yield`` requirement at the
MIW poses; ``allocate_ga`` / ``allocate_nsga2``, ``calibrate_scale``, ``verify``; and the exact
worst-case counterpart. The cost models are illustrative (the paper has none).

The parameters several definitions of this module share are described once, here.

Parameters
----------
case : {"a", "b", "c", "d"}
    Design case of Table 2.
radius : float, optional
    Allowed position deviation, m (default 0.2 mm).
"""
from __future__ import annotations

import numpy as np

from evotol.robots.planar5r import uncertainty as U
from evotol.robots.planar5r.model import Planar5R

#: the three design variables: shared tolerance groups of the core problem
SHARED = {"clearance_A": ("clearance_A1", "clearance_A2"), "clearance_B": ("clearance_B1", "clearance_B2"),
          "theta": ("theta1", "theta2")}
SIGMA_K = 3.0          # actuator error tolerance t = 3 std (normal); reported as the std t/3
BOUNDS = {"clearance_A": (1e-6, 100e-6), "clearance_B": (1e-6, 100e-6), "theta": (np.deg2rad(0.001), np.deg2rad(0.2))}


def default_costs() -> dict:
    """Illustrative cost-tolerance models (the paper has none), per part:

    * journal-bearing fits, reciprocal ``c = a0 + a1 / (r_c / 1 um)`` (Chase & Greenwood):
      actuated joints ``1 + 20 / x`` (motor-side bearing), elbows ``0.5 + 10 / x``;
    * actuator accuracy (encoder + servo), power ``c = 4 (std / 0.01 deg)^-0.7``, i.e. of the
      tolerance t = 3 std: ``4 (t / 0.03 deg)^-0.7``.

    Returns
    -------
    dict of str to cost model
        ``"clearance_A"`` and ``"clearance_B"`` (:class:`evotol.cost_models.ReciprocalCost`, clearance
        in m) and ``"theta"`` (:class:`evotol.cost_models.PowerCost`, tolerance t = 3 std in rad); costs
        in cost units per part.
    """
    from evotol.cost_models import PowerCost, ReciprocalCost

    return {"clearance_A": ReciprocalCost(1.0, 20.0, scale=1e-6), "clearance_B": ReciprocalCost(0.5, 10.0, scale=1e-6),
            "theta": PowerCost(4.0, 0.7, scale=SIGMA_K * np.deg2rad(0.01))}


def allocation_problem(case: str, n_samples: int, seed: int, D: float = 0.2, radius: float = 0.2e-3,
                       p_max: float = 0.01, measure: str = "yield"):
    """The core problem: link lengths fixed at 3 std of Table 1 (normal, no cost); actuator errors
    normal with t = 3 std; contact-mode clearances ``|c| = r_c`` (Sec. 2.5); one shared tolerance per
    joint pair / motor pair (cost counted per part); requirement ``P(|dp| <= radius) >= 1 − p_max`` at
    every MIW pose on the nonlinear loop closure (common LHS rows, unassembled = miss), or the
    exact worst case (``measure="worst_case"``).

    Parameters
    ----------
    n_samples : int
        Monte Carlo samples of the yield requirement (ignored for other measures).
    seed : int
        Random seed of those samples.
    D : float, optional
        Scale of the mechanism, m (physical length = non-dimensional length x D); default 0.2 m.
    p_max : float, optional
        Allowed probability of exceeding ``radius`` at each pose (default 0.01).
    measure : str, optional
        ``"yield"`` (default; nonlinear Monte Carlo) or another registered measure, e.g.
        ``"worst_case"``.

    Returns
    -------
    evotol.core.problem.ToleranceProblem
        Problem at the MIW poses with the shared variables of :data:`SHARED` (clearances in m,
        actuator tolerance t = 3 std in rad) and the link lengths fixed.
    """
    from evotol.core.problem import Requirement, Tolerance, ToleranceProblem

    robot = Planar5R(case, D=D)
    costs = default_costs()
    lengths = {"A1B1": robot.r1, "A2B2": robot.r1, "B1P": robot.r2, "B2P": robot.r2, "OA1": robot.r3, "OA2": robot.r3}
    tol = {n: Tolerance.fixed(SIGMA_K * U.DELTA_R * L, distribution="normal") for n, L in lengths.items()}
    for var, members in SHARED.items():
        lo, hi = BOUNDS[var]
        if var == "theta":
            lo, hi = SIGMA_K * lo, SIGMA_K * hi
        for m in members:
            tol[m] = Tolerance(costs[var], lo, hi, distribution="normal" if var == "theta" else "contact")
    if measure == "yield":
        req = Requirement(position=radius, measure="yield", probability=1 - p_max, model="nonlinear",
                          mc_samples=int(n_samples), seed=int(seed))
    else:
        req = Requirement(position=radius, measure=measure)
    return ToleranceProblem(robot, tol, req, robot.miw_poses(), shared=SHARED)


def _as_variables(problem, T: np.ndarray) -> dict:
    """Design (SI source tolerances) -> the three variables; theta as the actuator std t/3."""
    idx = {n: j for j, n in enumerate(problem.names)}
    return {v: float(T[idx[m[0]]] / (SIGMA_K if v == "theta" else 1.0)) for v, m in SHARED.items()}


def _from_variables(problem, V: np.ndarray) -> np.ndarray:
    """Designs (n, 3) of (clearance_A, clearance_B, theta std) -> source tolerances (n, n_sources)."""
    X = np.asarray(V, dtype=float) * np.array([1.0, 1.0, SIGMA_K])
    order = [list(SHARED).index(v) for v in problem.variables]
    return problem.full(X[:, order])


def allocate_case(case: str, cfg: dict, seed: int, pareto: bool, grid: int, p_max: float = 0.01,
                  radius: float = 0.2e-3, seed_designs=()) -> dict:
    """GA on the core yield problem, calibration on fresh samples, verification, NSGA-II, grid.

    The GA starts from the tightest design (every tolerance at its lower bound: feasible whenever
    anything is), the Lagrange baseline and ``seed_designs`` (e.g. the worst-case optimum, whose
    exceedance is 0); its search runs on the tolerances themselves (the feasible region of case a
    is a small corner of the box).

    Parameters
    ----------
    cfg : dict
        Settings: ``n_alloc_samples`` (samples of the yield problem), ``pop`` and ``n_gen`` (GA
        and NSGA-II), ``n_verify`` (verification samples).
    seed : int
        Random seed.
    pareto : bool
        Also run NSGA-II (cost vs exceedance).
    grid : int
        Points per axis of the equal-clearance x actuator-tolerance grid; 0 for none.
    p_max : float, optional
        Allowed exceedance probability per pose (default 0.01).
    seed_designs : sequence of array_like, optional
        Extra GA start designs, source tolerances in SI (m, rad).

    Returns
    -------
    dict
        Problem description and ``feasible``; when feasible the calibrated design
        ``tolerances`` (clearances in m, ``theta`` as actuator std in rad), ``cost`` (cost units),
        the optimiser's and verified exceedance probabilities with a 95 % upper bound, cost
        parts, and optionally ``pareto`` and ``grid``; otherwise a ``message``.
    """
    from scipy.stats import beta

    from evotol.allocators import allocate_ga, allocate_nsga2
    from evotol.verification.montecarlo import calibrate_scale, verify

    n = cfg["n_alloc_samples"]
    P = allocation_problem(case, n, seed, p_max=p_max, radius=radius)
    out = {"case": case, "D": 0.2, "radius": P.requirement.position, "p_max": p_max, "n_samples": n,
           "variables": list(SHARED), "units": {"clearance_A": "m", "clearance_B": "m", "theta": "rad (std)"},
           "bounds": {v: [float(x) for x in b] for v, b in BOUNDS.items()},
           "costs": {v: repr(c) for v, c in default_costs().items()}, "n_poses": P.n_poses,
           "problem": "evotol core: ToleranceProblem(shared, Tolerance.fixed, Requirement(measure='yield', "
                      "model='nonlinear')), allocate_ga, calibrate_scale, verify"}
    from evotol.errors import InfeasibleError

    T_lo = P.full(P.lower[P.free][None])
    from evotol.allocators import allocate_lagrange
    from evotol.errors import EvotolError

    seeds = [T_lo[0]] + [np.asarray(d, dtype=float) for d in seed_designs]
    try:
        seeds.append(allocate_lagrange(P).t)
    except EvotolError:                            # no Lagrange design meets the requirement
        pass
    try:
        ga = allocate_ga(P, pop_size=cfg["pop"], n_gen=cfg["n_gen"], seed=seed, progress=False, seeds=seeds)
        message = "no design met the requirement within the bounds"
    except InfeasibleError as exc:                 # even the tightest tolerances miss the requirement
        ga, message = None, str(exc)
    if ga is None or not ga.feasible:
        out.update(feasible=False, p_exceed_at_lower_bounds=float(1 - P.evaluate(T_lo).probability.min()),
                   message=message)
        return out
    cal = calibrate_scale(P, ga.t, 8 * n, seed=seed + 104729)
    out["ga_tolerances"], out["ga_cost"] = _as_variables(P, ga.t), float(ga.cost)
    if not cal["certified"]:
        out.update(feasible=False, message="the GA design scaled to the lower bounds does not meet the requirement "
                                           "with 95 % confidence")
        return out
    T = cal["tolerances"]
    p_opt = 1 - P.evaluate(T[None]).probability[0]
    mc = verify(P, T, cfg["n_verify"], method="lhs", seed=seed + 7919, chunk_poses=1, progress=False)
    p_ver = 1 - mc.yield_nonlinear
    k = int(round(p_ver.max() * cfg["n_verify"]))
    sc = P.source_costs(T)
    out.update(feasible=True, tolerances=_as_variables(P, T), cost=float(P.cost(T)), calibration_factor=float(cal["scale"]),
               n_calibrate=cal["n_samples"], p_exceed_optimiser=p_opt.tolist(), p_exceed_verified=p_ver.tolist(),
               p_exceed_verified_max=float(p_ver.max()), n_verify=cfg["n_verify"],
               p_exceed_verified_upper95=1.0 if k >= cfg["n_verify"] else float(beta.ppf(0.95, k + 1, cfg["n_verify"] - k)),
               yield_check=mc.yield_check,
               cost_parts={v: float(sum(sc[P.names.index(m)] for m in mem)) for v, mem in SHARED.items()})
    if pareto:
        front = allocate_nsga2(P, pop_size=cfg["pop"], n_gen=cfg["n_gen"], seed=seed, progress=False)
        TF = front.table[list(P.names)].to_numpy(dtype=float)
        order = np.argsort(P.cost(TF))
        TF = TF[order]
        var = [_as_variables(P, t) for t in TF]
        out["pareto"] = {"cost": P.cost(TF).tolist(), "p_exceed": (1 - P.evaluate(TF).probability.min(axis=1)).tolist(),
                         **{v: [d[v] for d in var] for v in SHARED}}
    if grid:
        rc = np.geomspace(*BOUNDS["clearance_A"], grid)
        dth = np.geomspace(*BOUNDS["theta"], grid)
        RC, DT = np.meshgrid(rc, dth)
        G = _from_variables(P, np.stack([RC.ravel(), RC.ravel(), DT.ravel()], -1))
        Pg = (1 - P.evaluate(G).probability.min(axis=1)).reshape(RC.shape)
        C = P.cost(G).reshape(RC.shape)
        feas = Pg <= p_max
        best = np.unravel_index(np.argmin(np.where(feas, C, np.inf)), C.shape) if feas.any() else None
        out["grid"] = {"clearance": rc.tolist(), "theta": dth.tolist(), "p_exceed_max": Pg.tolist(), "cost": C.tolist(),
                       "best_equal_clearance": None if best is None else
                       {"clearance": float(RC[best]), "theta": float(DT[best]), "cost": float(C[best])}}
    return out


def worst_case_case(case: str, seed: int) -> dict:
    """The deterministic counterpart: the same sources and shared tolerances under the exact
    worst-case measure, certified :func:`evotol.allocators.allocate_optimum`; its exceedance under
    the probabilistic model on 20 000 fresh samples.

    Parameters
    ----------
    seed : int
        Random seed of the probabilistic check (``seed + 31``).

    Returns
    -------
    dict
        ``tolerances`` (SI, m or rad), ``cost`` (cost units), ``feasible``,
        ``max_position_error`` (m), ``certificate``, ``as_variables`` (clearances in m, actuator
        std in rad), ``p_exceed_probabilistic_model``, ``sigma_multiple`` and ``_design`` (the
        source tolerances as an ndarray, not JSON-ready).

    Raises
    ------
    EvotolError
        If the allocation fails, e.g. ``InfeasibleError`` when the fixed link-length tolerances
        alone break the requirement (from :func:`evotol.allocators.allocate_optimum`).
    """
    from evotol.allocators import allocate_optimum

    Pw = allocation_problem(case, 0, seed, measure="worst_case")
    res = allocate_optimum(Pw)
    T = res.t
    Pp = allocation_problem(case, 20000, seed + 31)
    return {"tolerances": {n: float(v) for n, v in res.tolerances.items()}, "cost": float(res.cost),
            "feasible": bool(res.feasible), "max_position_error": res.max_error("position"),
            "certificate": res.certificate, "as_variables": _as_variables(Pw, T),
            "p_exceed_probabilistic_model": float(1 - Pp.evaluate(T[None]).probability.min()), "sigma_multiple": SIGMA_K,
            "_design": T}

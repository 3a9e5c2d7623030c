"""Brahmia et al. 2023: geometric-tolerance synthesis of a Delta robot, and its cost-optimal allocation.

Part 1 reproduces the paper's three-step method (Sec. 2.3, 3.1, 4.1):

1. joint variables Q_k at the postures (eq. 11) -- :meth:`evotol.robots.delta.DeltaRobot.inverse_kinematics`;
2. per posture P1, P3, P6, P9 and per imposed displacement of 0.2 mm along +-x, +-y, +-z
   (Tables A1-A2), problem (12)-(13): minimise F (eq. 10) over the 47 error parameters under
   ``|ΔL| <= 0.015 mm``, ``|Δφ| <= 0.015 deg``, with scipy's ``trust-constr`` (interior point, as the
   paper's fmincon "interior-point"), :func:`solve_displacement`;
3. tolerance interval per parameter by the rule of Fig. 4 (:func:`fig4_intervals`) and the
   verification of Sec. 4.1 (4 cases, 15 postures, :func:`verification_errors`).

Two objectives F are available: ``"closed"`` (ours: the platform position from the loop-closure
forward kinematics with errors must move by ΔP) and ``"open"`` (the paper's eq. 10 read
literally: every serial sub-chain, joints held at Q_k, must end at P + ΔP).

Part 2 (beyond the paper) allocates the same 47 tolerances with evotol's allocators under a cost
model per family (linear / angular) and a 0.2 mm worst-case requirement over >= 1000 workspace
poses, verifies them by Monte Carlo through the nonlinear model, and prices the paper's Table 3.

The method (step 2 included: :func:`evotol.robots.delta_synthesis.synthesis_runs`) lives in
:mod:`evotol.robots.delta_synthesis` (the next user of it needs it too); the paper's tables in SI in
:mod:`evotol.studies.brahmia2023_delta_paper`; the problem of part 2 in
:mod:`evotol.studies.brahmia2023_delta_allocation`; the report in
``evotol/studies/_brahmia2023_delta_report.py``. This module holds the runs (:func:`compute`) and
hands the report on (:func:`render`); the names that moved stay importable from here.
"""
from __future__ import annotations

import time

import numpy as np

from evotol.studies import Study, StudyResult
from evotol.studies._brahmia2023_delta_data import TABLE_3, TABLE_A, TABLE_A_TESTS  # noqa: F401
from evotol.studies._brahmia2023_delta_report import render_report
from evotol.studies.brahmia2023_delta_allocation import (COST_A0, COST_A1, MDEG, T_MAX, T_MIN, UM,  # noqa: F401
                                                         critical_poses, family_cost_models, interval_problem,
                                                         table3_problem, tolerance_problem)
from evotol.studies.brahmia2023_delta_paper import TO_PAPER, inferred_min_magnitude, table3_si, table_a_si  # noqa: F401
from evotol.robots.delta import ANGULAR, LINEAR, PARAMETER_NAMES, POSTURES_MM, DeltaRobot  # noqa: F401
from evotol.robots.delta_synthesis import (IS_LINEAR, REQUIRED_MM, SYNTHESIS_POSTURES, TEST_DIRECTIONS,  # noqa: F401
                                    fig4_intervals, paper_bounds, postures_m, solve_displacement, synthesis_runs,
                                    verification_errors)

NAME = "brahmia2023-delta"


def _kinematics_checks(robot: DeltaRobot, seed: int) -> dict:
    from evotol.robots.checks import check_robot
    from evotol.robots.delta import cylinder_poses

    P = np.vstack([postures_m(), cylinder_poses(200, seed=seed)])
    Q = robot.inverse_kinematics(P)
    b1, b2 = robot.branch_points(Q[..., 0], Q[..., 1], Q[..., 2], np.zeros((len(P), 47)))
    gap_ik = max(np.max(np.abs(np.stack(b, -1) - P[:, None])) for b in (b1, b2)) * 1e3
    rng = np.random.default_rng(seed)
    E = rng.uniform(-1, 1, (len(P), 20, 47)) * paper_bounds()
    gap_fk = float(robot.closure_residual(P, E).max() * 1e3)
    fd = check_robot(robot, P[:30], rtol=1e-6)
    return {"ik_closure_mm": float(gap_ik), "fk_with_errors_closure_mm": gap_fk,
            "jacobian_fd_relative_mismatch": fd["fd_relative_mismatch"], "n_poses": int(len(P))}


CONFIG = {"seed": 0}
QUICK: dict = {}   # the quick run's sizes are set by config["quick"] below


def compute(config: dict) -> StudyResult:
    """Reproduce Brahmia et al. 2023 and allocate its tolerances by cost (JSON-ready summary).

    Parameters
    ----------
    config : dict
        Study config: ``seed`` (int) and ``quick`` (bool: 2 postures x 2 tests, one variant,
        150 instead of 1000 dense poses, smaller GA/NSGA-II and Monte Carlo runs).

    Returns
    -------
    StudyResult
        ``summary`` only (no tables): the reproduced intervals (mm or deg) and verification
        errors (mm), the variants of problem (12), the allocations (costs in cost units, errors
        in mm, tolerances in SI), the Pareto front, model checks, timing (s) and ``figures``.
    """
    from evotol.allocators import allocate_ga, allocate_nsga2, allocate_optimum, allocate_sensitivity
    from evotol.verification.montecarlo import verify
    from evotol.verification.nonlinear import verify_nonlinear
    from evotol.allocators.workspace_refinement import refine_poses, scale_into_requirement
    from evotol.core.result import make_result
    from evotol.robots.delta import cylinder_poses

    t_start = time.perf_counter()
    quick, seed = config["quick"], config["seed"]
    robot = DeltaRobot()
    timing: dict[str, float] = {}

    def tick(key, t0):
        timing[key] = round(time.perf_counter() - t0, 2)

    # --- model checks ------------------------------------------------------------------------------
    t0 = time.perf_counter()
    checks = _kinematics_checks(robot, seed)
    tick("kinematics checks", t0)

    # --- the paper's three-step method --------------------------------------------------------------
    t0 = time.perf_counter()
    postures = ("P1", "P6") if quick else SYNTHESIS_POSTURES
    tests = ("+x", "+z") if quick else tuple(TEST_DIRECTIONS)
    mins = inferred_min_magnitude()
    variant_defs = {"closed loop, eq. (12) with lower limits": dict(objective="closed", min_magnitude=mins),
                    "open chains (eq. 10 literally), eq. (12) with lower limits": dict(objective="open", min_magnitude=mins),
                    "closed loop, |Δ| <= bound only (eq. 13)": dict(objective="closed", min_magnitude=None),
                    "open chains, |Δ| <= bound only (eq. 13)": dict(objective="open", min_magnitude=None)}
    if quick:
        variant_defs = dict(list(variant_defs.items())[:1])
    variants = {}
    for label, kw in variant_defs.items():
        runs = synthesis_runs(robot, postures, tests, maxiter=60 if quick else 80, **kw)
        lo, hi = fig4_intervals(np.array([r["errors"] for r in runs]))
        variants[label] = {"runs": runs, "lo": lo, "hi": hi, "verification": verification_errors(robot, lo, hi)}
    headline = next(iter(variants))
    lo, hi = variants[headline]["lo"], variants[headline]["hi"]
    tick("three-step method", t0)
    t3_lo, t3_hi = table3_si()
    ver_t3 = verification_errors(robot, t3_lo, t3_hi)
    ta_lo, ta_hi = fig4_intervals(table_a_si())

    # --- beyond the paper: cost-aware allocation over the workspace -------------------------------------
    t0 = time.perf_counter()
    n_dense = 150 if quick else 1000
    dense = np.vstack([postures_m(), cylinder_poses(n_dense, seed=seed)])
    full = tolerance_problem(robot, dense)
    req_mm = REQUIRED_MM
    bnd = paper_bounds()
    interval_designs = {"paper Table 3": (t3_lo, t3_hi), "ours: paper's method": (lo, hi),
                        "bounds of eq. (13)": (-bnd, bnd)}
    sens = allocate_sensitivity(full)
    crit = np.union1d(np.arange(15), critical_poses(full, np.stack([sens.t, (t3_hi - t3_lo) / 2, bnd]),
                                                    k=4 if quick else 8))
    tick("problem + screening", t0)
    t0 = time.perf_counter()
    # whole-workspace refinement by the core: allocate on the critical poses, add the dense poses
    # where the design misses 0.2 mm, repeat (evotol.allocators.workspace_refinement.refine_poses, index mode)
    pose_rounds = dict(start=crit, local=False, add=8, max_rounds=5, dense=full)
    opt_sub, ref = refine_poses(full, lambda p: allocate_optimum(p, max_rows=120), **pose_rounds)
    opt_idx, opt_rounds = ref["pose_indices"], ref["rounds"]
    opt = make_result(full, "optimum", opt_sub.t, certificate=opt_sub.certificate,
                      info={"pose_rounds": opt_rounds, "poses_in_last_round": int(len(opt_idx))})
    t3_problem, t3_half = table3_problem(full)
    wc_t3 = float(t3_problem.evaluate(t3_half[None], top_only=True).position.max())
    full_eq = full.with_requirement(position=wc_t3)
    eq_sub, _ = refine_poses(full_eq, lambda p: allocate_optimum(p, max_rows=120),
                             **{**pose_rounds, "start": opt_idx, "dense": full_eq})
    opt_eq = make_result(full_eq, "optimum at Table 3's accuracy", eq_sub.t, certificate=eq_sub.certificate)
    tick("certified optimum (x2)", t0)
    t0 = time.perf_counter()
    sub = opt_sub.problem
    ga_raw = allocate_ga(sub, pop_size=16 if quick else 40, n_gen=8 if quick else 60, seed=seed, progress=False)
    ga_t = scale_into_requirement(full, ga_raw.t)
    ga = make_result(full, "GA", ga_t, history=ga_raw.history,
                     info={"scaled_after_dense_check": bool(not np.allclose(ga_t, ga_raw.t)), **ga_raw.info})
    tick("GA", t0)
    t0 = time.perf_counter()
    front = allocate_nsga2(sub, pop_size=16 if quick else 40, n_gen=8 if quick else 60, seed=seed, progress=False,
                           seeds=[sens.t, opt.t, opt_eq.t])
    T_front = front.table[list(full.names)].to_numpy()
    front_err_mm = full.evaluate(T_front, top_only=True).position.max(axis=1) * 1e3
    tick("NSGA-II", t0)

    # --- verification through the nonlinear model ------------------------------------------------------
    t0 = time.perf_counter()
    sym = {"sensitivity": sens.t, "optimum": opt.t, "optimum at Table 3's accuracy": opt_eq.t, "GA": ga.t}
    designs = {**interval_designs, **{k: (-v, v) for k, v in sym.items()}}
    mc_problem = opt_sub.problem
    allocations = {}
    n_mc = 100 if quick else 1000
    # the worst case over the dense poses needs the support coefficients c[p, d, j] of a design's
    # problem (about 1 s per problem and component): Table 3's problem is the one built above, and a
    # centred design's problem is plain like `full`, whose coefficients are already computed -- the same
    # arithmetic on the same arrays, so the same numbers (the sub-problem at `opt_idx` inherits them)
    built = {(t3_lo.tobytes(), t3_hi.tobytes()): t3_problem}
    for name, (dlo, dhi) in designs.items():
        design_problem, half = interval_problem(full, dlo, dhi)
        computed = full if design_problem.shape.plain and full.shape.plain else built.get((dlo.tobytes(), dhi.tobytes()))
        wc_problem = design_problem if computed is None else computed
        wc = wc_problem.evaluate(half[None], top_only=True).position[0]
        chk = verify_nonlinear(wc_problem.with_poses(opt_idx), half, n_samples=n_mc, seed=seed)
        vertex = chk.worst_vertex["position"] * 1e3
        mc = {"max_mm": chk.mc_max["position"] * 1e3, "q999_mm": chk.mc_q999["position"] * 1e3,
              "n_samples": int(n_mc), "n_poses": int(len(opt_idx))}
        allocations[name] = {"cost": float(design_problem.cost(half)), "worst_case_error_mm": float(wc.max() * 1e3),
                             "meets_0.2mm": bool(wc.max() * 1e3 <= req_mm * (1 + 1e-9)),
                             "nonlinear_at_worst_vertex_mm": float(vertex.max()), "mc": mc,
                             "tolerances_si": {n: [float(a), float(b)] for n, a, b in zip(PARAMETER_NAMES, dlo, dhi)}}
        if name in sym:  # the core's verification (symmetric tolerances only), nonlinear model included
            allocations[name]["mc_core"] = verify(mc_problem, sym[name], n_samples=100 if quick else 1000,
                                                  seed=seed, progress=False).to_dict()
    tick("nonlinear verification", t0)

    summary = {
        "study": NAME, "quick": bool(quick), "seed": int(seed),
        "tolerance_interval_units": {"linear": "mm", "angular": "deg"},
        "tolerance_intervals": {n: [float(a * k), float(b * k)] for n, a, b, k in zip(PARAMETER_NAMES, lo, hi, TO_PAPER)},
        "tolerance_intervals_variant": headline,
        "verification_error_mm": {c: v["closed"].tolist() for c, v in variants[headline]["verification"].items()},
        "verification_error_mm_range": [float(min(v["closed"].min() for v in variants[headline]["verification"].values())),
                                        float(max(v["closed"].max() for v in variants[headline]["verification"].values()))],
        "paper_verification_error_mm_range": [0.0029, 0.135],
        "table3_verification_error_mm": {c: v["closed"].tolist() for c, v in ver_t3.items()},
        "variants": {label: {"intervals_paper_units": {n: [float(a * k), float(b * k)] for n, a, b, k in
                                                      zip(PARAMETER_NAMES, v["lo"], v["hi"], TO_PAPER)},
                             "verification_max_mm": {m: float(max(x[m].max() for x in v["verification"].values()))
                                                     for m in ("closed", "open", "linear")},
                             "runs_reaching_displacement": int(sum(r["residual_mm"] < 1e-4 for r in v["runs"])),
                             "n_runs": len(v["runs"])} for label, v in variants.items()},
        "table3_cost": allocations["paper Table 3"]["cost"],
        "table3_worst_case_error_mm": allocations["paper Table 3"]["worst_case_error_mm"],
        "optimum_cost": opt.cost, "optimum_cost_at_table3_accuracy": opt_eq.cost,
        "sensitivity_cost": sens.cost, "ga_cost": ga.cost,
        "saving_vs_table3_at_equal_accuracy": 1 - opt_eq.cost / allocations["paper Table 3"]["cost"],
        "saving_vs_table3_at_0.2mm": 1 - opt.cost / allocations["paper Table 3"]["cost"],
        "optimum_certificate": opt.certificate, "optimum_tolerances_si": opt.tolerances,
        "worst_case_error_mm": {k: v["worst_case_error_mm"] for k, v in allocations.items()},
        "allocations": allocations,
        "pareto_front": {"cost": front.table["cost"].tolist(), "worst_case_error_mm": front_err_mm.tolist()},
        "n_dense_poses": int(len(dense)), "n_critical_poses": int(len(opt_idx)),
        "kinematics_checks": checks,
        "cost_model": {fam: repr(m) for fam, m in family_cost_models().items()},
        "timing_s": timing,
    }
    summary["figures"] = {
        "step2_runs": [{"posture": r["posture"], "test": r["test"], "errors": np.asarray(r["errors"]).tolist(),
                        "residual_mm": r["residual_mm"], "nit": r["nit"]} for r in variants[headline]["runs"]],
        "rule_on_tables_a_si": [ta_lo.tolist(), ta_hi.tolist()],
    }
    summary["seconds"] = round(time.perf_counter() - t_start, 2)
    return StudyResult(summary)


def render(result: StudyResult):
    """Model checks, Tables A/3 and Fig. 7 reproduced, and the cost-optimal allocation.

    Parameters
    ----------
    result : StudyResult
        Output of :func:`compute` (its summary, possibly read back from JSON).

    Returns
    -------
    evotol.reporting.html.Report
        The HTML report.
    """
    return render_report(result, NAME)


STUDY = Study(name=NAME, title="Delta robot geometric-tolerance synthesis (KK error model) and cost-optimal allocation",
              compute=compute, render=render, config=CONFIG, quick=QUICK, seed_paper="Brahmia et al. 2023, Appl. Sci. 13:10703 (seed 000)")

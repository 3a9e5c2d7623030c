"""Planar 5R symmetrical mechanism under clearances and uncertainties (Lara-Molina et al. 2019).

For each design case of Table 2: the usable workspace with its singular loci and maximum
inscribed circle (eqs. 16-22), the sampled end-effector clouds at nine poses inside their 0.005
circles (Figs. 5/7/9/11; Monte Carlo with Latin hypercube, Table 1 + Sec. 2.5), the LCI map
(Figs. 6/8/10/12); then the measured LHS-vs-MC convergence, and a probabilistic tolerance
allocation of the joint clearances and actuator accuracy (GA and NSGA-II).

``compute(config)`` returns the JSON summary (figure data under ``figures``), ``render`` draws
the report from it; ``evotol reproduce laramolina2019-5r`` writes ``.html`` and ``.json``.
The allocation (``allocation_problem``, ``allocate_case``, ``worst_case_case``) lives in
:mod:`evotol.studies._laramolina2019_5r_allocation`, the figures in
:mod:`evotol.studies._laramolina2019_5r_figures`; this module imports them.
"""
from __future__ import annotations

import time

import numpy as np

from evotol.reporting.html import Report
from evotol.studies import Study, StudyResult
from evotol.studies import _laramolina2019_5r_figures as F
from evotol.studies._laramolina2019_5r_allocation import (BOUNDS, SHARED, SIGMA_K,  # noqa: F401
                                                          allocate_case, allocation_problem, default_costs,
                                                          worst_case_case)
from evotol.robots.planar5r import kinematics as K
from evotol.robots.planar5r import uncertainty as U
from evotol.robots.planar5r.design import CASES, TABLE2_PRINTED
from evotol.robots.planar5r.model import Planar5R

__all__ = ["analyse_case", "default_costs", "allocation_problem", "allocate_case", "worst_case_case",
           "compute", "render"]

NAME = "laramolina2019-5r"
POSE_LABELS = F.POSE_LABELS
PAPER_LCI = {"b": ("LCI = 0.9 (Sec. 3.2)", 0.9), "d": ("max(LCI) = 0.55 (Sec. 3.4)", 0.55)}


SETTINGS = dict(grid=201, n_samples=4000, cloud=250, conv_sizes=(16, 32, 64, 128, 256, 512, 1024), conv_rep=100,
                conv_ref=2 ** 16, alloc_cases=("a", "b", "c", "d"), pop=32, n_gen=30, n_alloc_samples=1024,
                n_verify=200_000, alloc_grid=20)
CONFIG = {"seed": 0, **SETTINGS}
QUICK = dict(grid=61, n_samples=300, cloud=60, conv_sizes=(16, 64), conv_rep=10, conv_ref=2 ** 11,
             alloc_cases=("b",), pop=10, n_gen=5, n_alloc_samples=256, n_verify=5000, alloc_grid=6)


# ----------------------------------------------------------------------------------------------
# physics (no plotting)
# ----------------------------------------------------------------------------------------------
def analyse_case(case: str, cfg: dict, seed: int, model: U.UncertaintyModel) -> dict:
    """Workspace, MIC, LCI and the sampled clouds of one design case (non-dimensional, D = 1).

    Parameters
    ----------
    case : {"a", "b", "c", "d"}
        Design case of Table 2.
    cfg : dict
        Settings: ``grid`` (workspace grid points per side), ``n_samples`` (LHS samples shared by
        the poses) and ``cloud`` (samples kept per pose for the figures).
    seed : int
        Random seed of the samples.
    model : evotol.robots.planar5r.uncertainty.UncertaintyModel
        Distributions of the uncertain parameters (Table 1, Sec. 2.5).

    Returns
    -------
    dict
        Link lengths, MIC (closed form and numeric), usable area, LCI statistics, forward/inverse
        kinematics round-trip errors, per-pose deviation statistics (with eq. 24 as printed and
        without clearance), all non-dimensional (lengths in units of D); ``_plot`` holds the
        figure arrays (ndarrays, not JSON-ready).
    """
    d = CASES[case]
    r1, r2, r3 = d.r1, d.r2, d.r3
    mic = K.mic_closed_form(r1, r2, r3)
    mic_num = K.mic_numeric(r1, r2, r3)
    uw = K.usable_workspace(r1, r2, r3, n=cfg["grid"], seed=(0.0, mic["center_y"]))
    P = uw.points()
    th = K.inverse_kinematics(P, r1, r2, r3)
    lci_pts = K.local_conditioning_index(P, r1, r2, r3)
    fk_err = np.max(np.abs(K.forward_kinematics(th, r1, r2, r3) - P), axis=1)
    PL = P.astype(np.longdouble)          # the same round trip in extended precision (docs/planar5r.md)
    fk_err_ld = np.max(np.abs(K.forward_kinematics(K.inverse_kinematics(PL, r1, r2, r3), r1, r2, r3) - PL), axis=1)
    X, Y = np.meshgrid(uw.x, uw.y)
    in_mic = (X ** 2 + (Y - mic["center_y"]) ** 2 <= mic["radius"] ** 2) & uw.mask
    robot = Planar5R(case, D=1.0)
    poses = robot.evaluation_poses()
    lci_poses = K.local_conditioning_index(poses, r1, r2, r3)
    unit = U.unit_samples(cfg["n_samples"], model.n_dims, "lhs", seed)
    dp, ok = U.position_deviations(poses, r1, r2, r3, model, unit, failures="mask")
    stats = U.pose_statistics(dp, U.PAPER_CIRCLE, assembled=ok)
    variant = U.UncertaintyModel(clearance=model.clearance, clearance_model="eq24_printed")
    dp24, ok24 = U.position_deviations(poses, r1, r2, r3, variant, unit, failures="mask")
    st24 = U.pose_statistics(dp24, U.PAPER_CIRCLE, assembled=ok24)
    no_clear = U.UncertaintyModel(clearance=0.0)
    dp0, ok0 = U.position_deviations(poses, r1, r2, r3, no_clear, unit, failures="mask")
    st0 = U.pose_statistics(dp0, U.PAPER_CIRCLE, assembled=ok0)
    rng = np.random.default_rng(seed + 1)
    keep = np.sort(rng.choice(dp.shape[1], size=min(cfg["cloud"], dp.shape[1]), replace=False))
    locus = K.type2_locus(r1, r2, r3, n=4000)
    return {
        "r1": r1, "r2": r2, "r3": r3, "s": d.s, "t": d.t, "table2_printed": TABLE2_PRINTED[case],
        "mic_equation": mic["equation"], "mic_radius": mic["radius"], "mic_center_y": mic["center_y"],
        "mic_numeric": mic_num, "usable_area": uw.area,
        "lci_max": uw.lci_max, "lci_at_mic_center": float(K.local_conditioning_index([0.0, mic["center_y"]], r1, r2, r3)),
        "lci_p90": float(np.nanpercentile(uw.lci, 90)), "lci_median": float(np.nanmedian(uw.lci)),
        "lci_mean_miw": float(np.nanmean(uw.lci[in_mic])), "lci_min_miw": float(np.nanmin(uw.lci[in_mic])),
        "fk_ik_max_error": float(fk_err.max()), "fk_ik_max_error_lci_ge_0.01": float(fk_err[lci_pts >= 0.01].max()),
        "fk_ik_max_error_longdouble": float(fk_err_ld.max()), "fk_ik_longdouble_eps": float(np.finfo(np.longdouble).eps),
        "lci_min_grid": float(lci_pts.min()),
        "n_grid_points_usable": int(len(P)),
        "poses": {"label": list(POSE_LABELS), "x": poses[:, 0], "y": poses[:, 1], "lci": lci_poses,
                  **{k: v for k, v in stats.items()}},
        "poses_eq24_printed": {k: st24[k] for k in ("rms_dev", "max_dev", "p_exceed")},
        "poses_without_clearance": {k: st0[k] for k in ("rms_dev", "max_dev", "p_exceed")},
        "_plot": {"x": uw.x, "y": uw.y, "usable": uw.mask, "lci": uw.lci, "type1_circles": K.type1_circles(r1, r2, r3),
                  "type2_locus": locus, "cloud": dp[:, keep], "cloud_ok": ok[:, keep], "poses": poses},
    }


# ----------------------------------------------------------------------------------------------
# study
# ----------------------------------------------------------------------------------------------
def compute(config: dict) -> StudyResult:
    """Workspace, MIC, LCI and clouds of the four cases, LHS-vs-MC convergence, allocation.

    Parameters
    ----------
    config : dict
        Study config: ``seed``, ``quick`` and the keys of ``SETTINGS`` (grid and sample sizes,
        convergence sizes, the allocation cases, GA sizes, ``n_verify``, ``alloc_grid``).

    Returns
    -------
    StudyResult
        ``summary`` only: settings, uncertainty model, per case the workspace and cloud
        statistics (non-dimensional), the convergence study, the allocation per case (SI
        tolerances, cost units), timing (s), ``figures`` and ``seconds``.
    """
    from evotol.errors import EvotolError

    t0 = time.perf_counter()
    quick, seed = config["quick"], config["seed"]
    cfg = {k: config[k] for k in SETTINGS}
    model = U.UncertaintyModel()
    cases = {c: analyse_case(c, cfg, seed + i, model) for i, c in enumerate(CASES)}
    t_cases = time.perf_counter() - t0

    b = cases["b"]
    conv = U.convergence_study(b["_plot"]["poses"], b["r1"], b["r2"], b["r3"], model, sizes=cfg["conv_sizes"],
                               n_rep=cfg["conv_rep"], n_reference=cfg["conv_ref"], seed=seed)
    t_conv = time.perf_counter() - t0 - t_cases

    alloc = {}
    for c in cfg["alloc_cases"]:
        try:
            wc = worst_case_case(c, seed)
        except EvotolError as exc:      # e.g. the fixed link-length tolerances alone break the requirement
            wc = {"feasible": False, "message": str(exc)[:300]}
        start = [wc.pop("_design")] if "_design" in wc else []
        alloc[c] = allocate_case(c, cfg, seed, pareto=c == "b", grid=cfg["alloc_grid"] if c == "b" else 0,
                                 seed_designs=start)
        alloc[c]["worst_case"] = wc
    t_alloc = time.perf_counter() - t0 - t_cases - t_conv

    summary = {
        "study": NAME, "seed_paper": STUDY.seed_paper, "quick": quick, "seed": seed,
        "settings": {k: list(v) if isinstance(v, tuple) else v for k, v in cfg.items()},
        "uncertainty": {"delta_r": model.length_rel_std, "delta_theta_deg": float(np.rad2deg(model.theta_std)),
                        "clearance_rc": model.clearance, "clearance_model": model.clearance_model,
                        "shared_lengths": model.shared_lengths, "renormalise": model.renormalise,
                        "circle": U.PAPER_CIRCLE, "sampling": "lhs"},
        "cases": {c: {k: v for k, v in r.items() if not k.startswith("_")} for c, r in cases.items()},
        "paper_lci": {"b": 0.9, "d_max": 0.55},
        "convergence": conv,
        "allocation": alloc,
    }
    summary["timing"] = {"cases": t_cases, "convergence": t_conv, "allocation": t_alloc}
    summary["figures"] = {c: r["_plot"] for c, r in cases.items()}
    summary["seconds"] = time.perf_counter() - t0
    return StudyResult(summary)


def render(result: StudyResult) -> Report:
    """Table 2 with the workspace indices, Figs. 5-12 per case, LHS vs MC, the allocation.

    Returns
    -------
    evotol.reporting.html.Report
        The HTML report.
    """
    summary = result.summary
    cases, conv, alloc = summary["cases"], summary["convergence"], summary["allocation"]
    rep = Report("Planar 5R symmetrical mechanism under clearances and uncertainties",
                 f"Reproduction of {STUDY.seed_paper}; evotol study {NAME}"
                 + (" (quick run: small samples and grids)" if summary["quick"] else ""))
    u = summary["uncertainty"]
    rep.text(f"Uncertainties (Table 1, Sec. 2.5): link lengths normal with std {u['delta_r'] * 100:.3g} % (one variable "
             f"per symmetric pair, renormalised by D(Omega) as the paper does), actuator errors normal with std "
             f"{u['delta_theta_deg']:g} deg, radial clearance r_c = {u['clearance_rc']:g} D at A1, A2, B1, B2 in the "
             f"contact mode (uniform contact direction). Latin hypercube with {summary['settings']['n_samples']} samples "
             f"shared by the nine poses. The paper prints no r_c and no pose coordinates: r_c is our choice and the poses "
             f"are the MIC centre (a) and eight points at 0.7 r_MIC (b-i, counter-clockwise from +x).", note=True)
    rep.heading("Design cases (Table 2) and workspace indices")
    rows = []
    for c, r in summary["cases"].items():
        pr = r["table2_printed"]
        rows.append([c, r["r1"], r["r2"], r["r3"], f"{r['s']:.3f} ({pr['s']})", f"{r['t']:.2f} ({pr['t']})",
                     r["mic_equation"], r["mic_radius"], r["mic_numeric"]["radius"], r["mic_center_y"], r["lci_max"],
                     r["lci_at_mic_center"], r["lci_p90"], r["lci_mean_miw"], r["fk_ik_max_error_lci_ge_0.01"],
                     r["fk_ik_max_error"], r["fk_ik_max_error_longdouble"], r["lci_min_grid"]])
    rep.table(rows, ["case", "r1", "r2", "r3", "s eq.5 (printed)", "t eq.6 (printed)", "MIC by", "r_MIC",
                     "r_MIC numeric", "y_MIC", "LCI max", "LCI at MIC centre", "LCI p90", "LCI mean in MIW",
                     "|FK(IK(p)) - p| max, float64, LCI >= 0.01", "same, float64, whole grid",
                     "same, long double, whole grid", "LCI min on the grid"])
    ld_max = max(r["fk_ik_max_error_longdouble"] for r in summary["cases"].values())
    f64_max = max(r["fk_ik_max_error"] for r in summary["cases"].values())
    rep.text("Round trip forward(inverse(p)) over every point of the usable-workspace grid: the forward problem "
             "amplifies the rounding of the crank angles by about 1/LCI, and LCI -> 0 at the usable workspace's "
             f"singular border. In float64 the largest error is {f64_max:.1e} (eps/LCI at the border); in long double "
             f"(eps {summary['cases']['a']['fk_ik_longdouble_eps']:.1e} on this machine) it is {ld_max:.1e} "
             f"({'within' if ld_max <= 1e-12 else 'ABOVE'} the 1e-12 target).", note=True)
    rep.text("Paper: case b LCI = 0.9 (Sec. 3.2), case d max(LCI) = 0.55 (Sec. 3.4). Measured: case b "
             f"LCI {summary['cases']['b']['lci_at_mic_center']:.3f} at the MIC centre, 90th percentile "
             f"{summary['cases']['b']['lci_p90']:.3f} over the usable workspace, max {summary['cases']['b']['lci_max']:.3f}; "
             f"case d max {summary['cases']['d']['lci_max']:.3f} (= 1/sqrt(3) on the symmetry axis), "
             f"{summary['cases']['d']['lci_at_mic_center']:.3f} at the MIC centre. Table 2's printed t for case a (0.08) "
             f"and s for case d (1.80) contradict eqs. 5-6; the link lengths are used.")
    for c, r in cases.items():
        p = F.plot_arrays(summary["figures"][c])
        rep.heading(f"Case {c}: r1 = {r['r1']:g}, r2 = {r['r2']:g}, r3 = {r['r3']:g}")
        rep.figure(F.workspace_figure(c, r, p))
        rep.figure(F.zoom_figure(c, r, p))
        rep.figure(F.lci_figure(c, r, p))
        st = r["poses"]
        rows = [[lab, st["x"][i], st["y"][i], st["lci"][i], st["mean_dx"][i], st["mean_dy"][i], st["std_dx"][i],
                 st["std_dy"][i], st["rms_dev"][i], st["max_dev"][i], st["p_exceed"][i], st["p_unassembled"][i],
                 r["poses_without_clearance"]["rms_dev"][i], r["poses_eq24_printed"]["rms_dev"][i]]
                for i, lab in enumerate(POSE_LABELS)]
        rep.table(rows, ["pose", "x", "y", "LCI", "mean dx", "mean dy", "std dx", "std dy", "rms |dp|", "max |dp|",
                         "P(|dp| > 0.005)", "P(no assembly)", "rms |dp| without clearance", "rms |dp| eq. 24 as printed"])
    rep.heading("Latin hypercube vs plain Monte Carlo")
    rep.figure(F.convergence_figure(conv))
    vr = conv["variance_ratio"]
    rep.table([[N] + [conv["mc"][k][i] for k in vr] + [conv["lhs"][k][i] for k in vr] + [vr[k][i] for k in vr]
               for i, N in enumerate(conv["sizes"])],
              ["N"] + [f"MC {k}" for k in vr] + [f"LHS {k}" for k in vr] + [f"MC/LHS variance {k}" for k in vr])
    rep.text("The paper states that LHS needs fewer samples than plain MC. Measured: for the mean deviation LHS is "
             "orders of magnitude more accurate (the response is nearly linear in the inputs); for the rms deviation "
             "and for an exceedance probability, which are what an accuracy requirement uses, the gain is a factor "
             "of about 1-2 in variance, i.e. LHS saves at most about half of the samples there.")
    rep.heading("Tolerance allocation: clearances and actuator accuracy (GA, NSGA-II)")
    rep.text("Requirement: at each of 17 MIW poses (centre + rings at 0.35 and 0.7 r_MIC), P(|dp| > 0.2 mm) <= 1 % for "
             "D = 0.2 m (0.001 D). Variables: r_c of the actuated joints, r_c of the elbows, actuator error std; link "
             "lengths at Table 1. Costs are illustrative (reciprocal for fits, power law for actuators; the paper has "
             "none). Everything runs through the evotol core: a ToleranceProblem with shared tolerances (one r_c per "
             "joint pair, one accuracy per motor pair, cost counted per part), link lengths as fixed normal sources "
             "(Tolerance.fixed, 3 std), contact-mode clearances, and Requirement(measure='yield', model='nonlinear'): "
             "exact loop closure on common Latin-hypercube rows (unassembled = miss). allocate_ga (seeded with the "
             "tightest design, the Lagrange baseline and the worst-case optimum), then calibrate_scale rescales the "
             "design on a larger independent sample so that every pose's 95 % upper confidence bound meets the "
             "requirement (calibration factor), then verify checks it on a third sample (docs/statistical.md).",
             note=True)
    rows = []
    for c, a in alloc.items():
        if not a.get("feasible"):
            rows.append([c, "infeasible: " + a.get("message", ""), "", "", "", "", "", "",
                         a.get("p_exceed_at_lower_bounds", "")])
            continue
        t = a["tolerances"]
        rows.append([c, t["clearance_A"] * 1e6, t["clearance_B"] * 1e6, np.rad2deg(t["theta"]), a["cost"], a["ga_cost"],
                     a["calibration_factor"], a["p_exceed_verified_max"], a["p_exceed_verified_upper95"]])
    rep.table(rows, ["case", "r_c active (um)", "r_c elbow (um)", "actuator std (deg)", "cost", "GA cost before calibration",
                     "calibration factor", "verified max P_exceed", "95 % upper bound"])
    rep.text("Deterministic counterpart through the evotol core (ToleranceProblem, exact worst-case measure, "
             "certified allocate_optimum): every admissible error must keep |dp| <= 0.2 mm; actuator errors bounded "
             "by 3 std, link lengths fixed at 3 std of Table 1, the same shared tolerances. Costs on the same models.")
    rows = []
    for c, a in alloc.items():
        w = a.get("worst_case", {})
        if "as_variables" not in w:
            rows.append([c, a.get("cost", "infeasible"), "infeasible: " + w.get("message", "")[:120], "", "", "", ""])
            continue
        v = w["as_variables"]
        rows.append([c, a.get("cost", "infeasible"), w["cost"], v["clearance_A"] * 1e6, v["clearance_B"] * 1e6,
                     np.rad2deg(v["theta"]), w["p_exceed_probabilistic_model"]])
    rep.table(rows, ["case", "probabilistic cost", "worst-case cost", "worst-case r_c active (um)",
                     "worst-case r_c elbow (um)", "worst-case actuator std = bound/3 (deg)",
                     "P_exceed of the worst-case design (probabilistic model)"])
    if "b" in alloc and alloc["b"].get("feasible"):
        if "pareto" in alloc["b"]:
            rep.figure(F.pareto_figure(alloc["b"]))
        if "grid" in alloc["b"]:
            rep.figure(F.grid_figure(alloc["b"]))
    rep.text(f"Run time: cases {summary['timing']['cases']:.1f} s, convergence {summary['timing']['convergence']:.1f} s, "
             f"allocation {summary['timing']['allocation']:.1f} s.")
    return rep


STUDY = Study(name=NAME, title="Planar 5R under clearances and uncertainties: workspace, MIC, LCI, MC/LHS, allocation",
              compute=compute, render=render, config=CONFIG, quick=QUICK, seed_paper="Lara-Molina, Koroishi, Policarpo, Steffen (COBEM 2019), 001_661fb1681958f265")

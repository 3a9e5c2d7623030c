"""Yao, Wang, Zhou & Zhou 2013: accuracy synthesis of a 3-UCR parallel robot by GA (seed 002).

Reproduces: the GA allocation under the exponential cost model (Table 1, cost 2.1837), the
sensitivity-based allocation (Table 2, cost 4.2391), the convergence curve (Fig. 4) and the Monte
Carlo exceed rate over (α, β) at Z_c = 0.305 m (Fig. 5); and judges them against the certified
optimum, under both error models (``paper`` = eqs. 10–11 as printed, ``verified`` = derived and
checked against finite differences) and two accuracy measures (RSS, exact worst case).
"""
from __future__ import annotations

import time

import numpy as np

from evotol.cost_models import ExponentialCost
from evotol.allocators import (allocate_ga, allocate_lagrange, allocate_nsga2, allocate_optimum,
                               allocate_sensitivity)
from evotol.units.display import LENGTHS
from evotol.verification.montecarlo import verify_designs
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from evotol.reporting import Report
from evotol.studies import Study, StudyResult
from evotol.robots.ucr3 import UCR3

UNIT = 1e-5  # the paper's tolerance unit (m)
E_POS = 5e-5  # allowed position error (m), Sec. 5
UM = LENGTHS["µm"]  # the report shows errors in µm (m per µm, the display units' table)
#: Paper Table 1 (GA) and Table 2 (sensitivity), units of 1e-5 m, in our source order
#: l1..l3, U1a..U3a, U1b..U3b, R1..R3. The paper's first "U joints" row is the pair whose
#: sensitivity-based tolerance is tighter (≈2.2); under the paper's model that is R_i2 (U_ib),
#: so row 1 -> U_ib and row 2 -> U_ia.
PAPER_TABLE1 = np.array([4.94, 4.81, 4.96, 2.95, 2.96, 2.94, 2.94, 2.93, 2.97, 2.98, 2.93, 2.89]) * UNIT
PAPER_TABLE2 = np.array([1.38, 1.38, 1.38, 4.29, 4.34, 4.31, 2.21, 2.19, 2.17, 4.30, 4.37, 4.32]) * UNIT
PAPER_COSTS = {"table1": 2.1837, "table2": 4.2391}
#: the allocations checked by Monte Carlo (keys of each variant's summary)
_DESIGNS = ("paper_table1", "paper_table2", "ga", "sensitivity", "optimum")


def yao2013_problem(variant: str, measure: str = "rss", grid=(11, 11, 6), lower=0.1 * UNIT, upper=20 * UNIT) -> ToleranceProblem:
    """The paper's problem: 12 sources, exponential costs (a0, a1) = (1.9, 0.5) for lengths and
    (1.1, 0.6) for joints with t in units of 1e-5 m, ``|δp| <= 5e-5 m`` over the workspace grid.

    Parameters
    ----------
    variant : {"paper", "verified"}
        Error model of :class:`evotol.robots.ucr3.UCR3`: eqs. 10-11 as printed or the derived one.
    measure : str, optional
        Accuracy measure of the requirement (default ``"rss"``; ``"worst_case"`` for the exact
        worst case).
    grid : sequence of 3 int, optional
        Points per workspace coordinate (α, β, Z_c) of the pose grid; default (11, 11, 6).
    lower, upper : float, optional
        Tolerance range of every source, m (default 1e-6 m and 2e-4 m).

    Returns
    -------
    evotol.core.problem.ToleranceProblem
        The 12-source problem with the requirement ``position = 5e-5 m``.

    Raises
    ------
    ValidationError
        If ``variant`` is unknown (from :class:`evotol.robots.ucr3.UCR3`).
    """
    robot = UCR3(variant=variant)
    tol = {}
    for s in robot.sources:
        cost = ExponentialCost(1.9, 0.5, scale=UNIT) if s.group == "length" else ExponentialCost(1.1, 0.6, scale=UNIT)
        tol[s.name] = Tolerance(cost, lower, upper)
    return ToleranceProblem(robot, tol, Requirement(position=E_POS, measure=measure), robot.workspace.grid(list(grid)))


def _plane(problem: ToleranceProblem, zc: float) -> ToleranceProblem:
    idx = np.flatnonzero(np.isclose(problem.poses[:, 2], zc))
    return ToleranceProblem(problem.model, problem.tolerances, problem.requirement, problem.poses[idx])


CONFIG = {"seed": 0, "grid": (11, 11, 6), "pop_size": 100, "n_gen": 200, "n_mc": 1000}
QUICK = {"grid": (5, 5, 3), "pop_size": 40, "n_gen": 40, "n_mc": 200}


def compute(config: dict) -> StudyResult:
    """Both error models: GA (pymoo and paper operators), sensitivity, Lagrange, certified optimum
    (RSS and worst case), NSGA-II front and Monte Carlo checks of every allocation (Sec. 5).

    Parameters
    ----------
    config : dict
        Study config: ``seed``, ``grid`` (points per workspace coordinate), ``pop_size`` and
        ``n_gen`` (GA and NSGA-II), ``n_mc`` (Monte Carlo samples).

    Returns
    -------
    StudyResult
        ``summary`` only: the costs of the paper's Tables 1-2 (cost units), per error model
        (``variants``) every allocator's cost, tolerances (m), certificates, the Monte Carlo
        checks (errors in m, exceed rates as fractions), the NSGA-II front; ``figures``, GA time
        and ``seconds`` (s).
    """
    t_start = time.perf_counter()
    seed, grid = config["seed"], tuple(config["grid"])
    pop, gens, n_mc = config["pop_size"], config["n_gen"], config["n_mc"]
    summary = {"paper_table1_cost": None, "paper_table2_cost": None, "variants": {}, "paper_reported_costs": PAPER_COSTS,
               "grid": list(grid), "requirement_position_m": E_POS, "seed": seed}
    figures, ga_seconds = {}, {}
    for variant in ("paper", "verified"):
        prob = yao2013_problem(variant, "rss", grid)
        prob_wc = prob.with_requirement(measure="worst_case")
        summary["paper_table1_cost"] = float(prob.cost(PAPER_TABLE1))
        summary["paper_table2_cost"] = float(prob.cost(PAPER_TABLE2))
        sens = allocate_sensitivity(prob)
        sens_c = allocate_sensitivity(prob, collective_groups=("length",))
        opt = allocate_optimum(prob)
        ga = allocate_ga(prob, pop_size=pop, n_gen=gens, seed=seed)
        ga_paper = allocate_ga(prob, pop_size=pop, n_gen=gens, seed=seed, operators="paper")
        # the same GA started from a Latin hypercube only (no baseline seeds): its convergence is Fig. 4's analogue
        ga_cold = allocate_ga(prob, pop_size=pop, n_gen=gens, seed=seed, seed_with_baselines=False)
        lag = allocate_lagrange(prob)
        opt_wc = allocate_optimum(prob_wc)
        sens_wc = allocate_sensitivity(prob_wc)
        front = allocate_nsga2(prob, pop_size=pop, n_gen=gens, seed=seed)
        ga_seconds[variant] = ga.seconds
        designs = dict(zip(_DESIGNS, (PAPER_TABLE1, PAPER_TABLE2, ga.t, sens.t, opt.t)))
        plane = _plane(prob, prob.poses[:, 2].max())
        checks = {}
        # the five designs on common samples (each result equals its own verify call, bit for bit)
        mcs = verify_designs(prob, list(designs.values()), n_mc, seed=seed, nonlinear=False)
        mcs_nl = verify_designs(plane, list(designs.values()), n_mc, seed=seed, nonlinear=True)
        for (name, t), mc, mc_nl in zip(designs.items(), mcs, mcs_nl):
            checks[name] = {"cost": float(prob.cost(t)),
                            "worst_case_error": float(prob_wc.max_errors(t[None])["position"][0]),
                            "rss_error": float(prob.max_errors(t[None])["position"][0]),
                            "mc_max_exceed_rate": mc.max_exceed_rate(),
                            "mc_max_exceed_rate_nonlinear_at_top_plane": mc_nl.max_exceed_rate(nonlinear=True),
                            "linearisation_error": mc_nl.linearisation_error,
                            "mc_max_over_worst_case": mc.max_error_over_worst_case["position"]}
            if name == "ga":
                fig5 = {"alpha_deg": np.unique(np.degrees(plane.poses[:, 0])).tolist(),
                        "beta_deg": np.unique(np.degrees(plane.poses[:, 1])).tolist(),
                        "z_c_m": float(plane.poses[0, 2]), "n_samples": mc_nl.n_samples,
                        "exceed_rate_linear": np.asarray(mc_nl.exceed_rate["position"]).tolist(),
                        "exceed_rate_nonlinear": np.asarray(mc_nl.nonlinear_exceed_rate["position"]).tolist()}
        summary["variants"][variant] = {
            "accuracy_measure": "rss",
            "ga_cost": ga.cost, "ga_paper_operators_cost": ga_paper.cost, "sensitivity_cost": sens.cost,
            "sensitivity_collective_lengths_cost": sens_c.cost, "lagrange_cost": lag.cost, "optimum_cost": opt.cost,
            "optimum_certificate": opt.certificate,
            "ga_over_optimum": ga.cost / opt.cost - 1, "ga_paper_operators_over_optimum": ga_paper.cost / opt.cost - 1,
            "ga_unseeded_cost": ga_cold.cost, "ga_unseeded_over_optimum": ga_cold.cost / opt.cost - 1,
            "ga_unseeded_initial_best": ga_cold.info["initial_best"],
            "sensitivity_over_ga": sens.cost / ga.cost, "sensitivity_collective_over_ga": sens_c.cost / ga.cost,
            "paper_table2_over_ga": summary["paper_table2_cost"] / ga.cost,
            "tolerances": {k: dict(zip(prob.names, np.asarray(v).tolist())) for k, v in
                           {"ga": ga.t, "sensitivity": sens.t, "sensitivity_collective": sens_c.t, "optimum": opt.t}.items()},
            "worst_case_measure": {"optimum_cost": opt_wc.cost, "sensitivity_cost": sens_wc.cost,
                                   "optimum_certificate": opt_wc.certificate,
                                   "optimum_tolerances": dict(zip(prob.names, opt_wc.t.tolist()))},
            **checks,
            "pareto_front": front.table[["cost", "normalised_error"]].to_dict(orient="list"),
            "contributions_ga_worst_pose": ga.contributions().to_dict(orient="list"),
        }
        figures[variant] = {
            "ga_max_rss_error": ga.max_error(),
            "convergence_lhs_start": ga_cold.history[["generation", "best_fitness", "mean_fitness"]].to_dict(orient="list"),
            "convergence_paper_operators": ga_paper.history[["generation", "best_feasible"]].to_dict(orient="list"),
            "fig5_ga": fig5,
        }
    summary["ga_seconds"] = ga_seconds["paper"]
    summary["ga_seconds_by_variant"] = ga_seconds
    summary["figures"] = figures
    summary["seconds"] = time.perf_counter() - t_start
    return StudyResult(summary)


def render(result: StudyResult) -> Report:
    """The report: what holds, costs, Tables 1-2 with ours, Figs. 4-5 and the NSGA-II front.

    Returns
    -------
    evotol.reporting.html.Report
        The HTML report.
    """
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    summary = result.summary

    rep = Report("Yao et al. 2013 — accuracy synthesis of a 3-UCR parallel robot",
                 "Seed 002: 3-UCR telescope secondary-mirror support; exponential cost model; |δp| ≤ 50 µm over "
                 "α, β ∈ [−5°, 5°], Z_c ∈ [0.255, 0.305] m. Reproduced by evotol.")
    v_p, v_v = summary["variants"]["paper"], summary["variants"]["verified"]
    rep.heading("What holds")
    holds = []
    for variant, v in summary["variants"].items():
        for key, label in (("paper_table1", "Table 1 (GA)"), ("paper_table2", "Table 2 (sensitivity)")):
            c = v[key]
            holds.append([variant, label, c["cost"], c["rss_error"] / UM, c["rss_error"] <= E_POS * (1 + 1e-9),
                          c["worst_case_error"] / UM, c["worst_case_error"] <= E_POS * (1 + 1e-9), c["mc_max_exceed_rate"],
                          c["mc_max_exceed_rate_nonlinear_at_top_plane"]])
    rep.table(holds, ["error model", "paper allocation", "cost", "max RSS error (µm)", "holds 50 µm (RSS)",
                      "max worst-case error (µm)", "holds 50 µm (worst case)", "MC max exceed rate (linear)",
                      "MC max exceed rate (nonlinear, Z_c = top)"], table_id="holds")
    rep.text(
        f"Under the paper's own model (eqs. 10–11 as printed) and the RSS measure, Table 1 has max RSS error "
        f"{v_p['paper_table1']['rss_error'] / UM:.2f} µm ({100 * (v_p['paper_table1']['rss_error'] / E_POS - 1):+.1f} % of the bound) "
        f"and a Monte Carlo exceed rate of at most {100 * v_p['paper_table1']['mc_max_exceed_rate']:.1f} % (the paper: under 10 %). "
        f"Under the verified model Table 1 has RSS error {v_v['paper_table1']['rss_error'] / UM:.2f} µm and exceed rate "
        f"{100 * v_v['paper_table1']['mc_max_exceed_rate']:.0f} %: the paper's allocation does not hold the requirement on the real kinematics. "
        "No paper allocation holds 50 µm in the worst case under either model.", note=True)
    rep.heading("Cost comparison (RSS measure, as the paper)")
    rows = []
    for variant, v in summary["variants"].items():
        rows.append([variant, v["ga_cost"], v["optimum_cost"], 100 * v["ga_over_optimum"], v["ga_paper_operators_cost"],
                     v["sensitivity_cost"], v["sensitivity_collective_lengths_cost"], v["lagrange_cost"],
                     v["sensitivity_over_ga"], v["sensitivity_collective_over_ga"], v["optimum_certificate"]["gap"]])
    rep.table(rows, ["error model", "GA cost", "certified optimum", "GA above optimum (%)", "GA, paper operators",
                     "sensitivity (equal effect)", "sensitivity (collective lengths)", "Lagrange closed form",
                     "sensitivity / GA", "collective sensitivity / GA", "optimum duality gap"], table_id="costs")
    rep.text(
        f"The paper reports 2.1837 (GA) and 4.2391 (sensitivity): ratio 1.94. The paper's tables cost "
        f"{summary['paper_table1_cost']:.4f} and {summary['paper_table2_cost']:.4f} under its cost model. Under the paper's "
        f"model our GA reaches {v_p['ga_cost']:.4f}, {100 * v_p['ga_over_optimum']:.3f} % above the certified optimum "
        f"{v_p['optimum_cost']:.4f} (the paper's own GA was {100 * (summary['paper_table1_cost'] / v_p['optimum_cost'] - 1):.1f} % above it, "
        f"and slightly outside the bound). Table 2 is reproduced by the equal-effect RSS rule only if the three leg lengths are "
        f"sized as one collective lift (sensitivity of all three moving together): that rule gives cost "
        f"{v_p['sensitivity_collective_lengths_cost']:.4f} (paper 4.2391) and the paper's comparison holds: "
        f"{v_p['sensitivity_collective_over_ga']:.2f}× the GA cost (paper 1.94×; Table 2 / our GA = {v_p['paper_table2_over_ga']:.2f}). "
        f"With each source's own sensitivity (our documented default rule) the joints keep Table 2's values within 2 % but the "
        f"lengths loosen to ≈43 µm, and the sensitivity allocation costs only {v_p['sensitivity_over_ga']:.2f}× the GA. "
        f"Under the verified model every tolerance must be far tighter (optimum {v_v['optimum_cost']:.3f}); there the "
        f"sensitivity rule costs {v_v['sensitivity_over_ga']:.2f}× the GA, because the verified model couples all sources "
        f"through the platform's parasitic motion and leaves little to trade between them.")
    rep.heading("Why the two error models differ")
    rep.text("The constraint rows of J_x in eq. 11 are printed as [u_iᵀ, (s_i × u_i)ᵀ]. Differentiating the constraint "
             "u_i · n_i = 0 with u_i = R u_iᵉ gives [u_iᵀ, (s_i × u_i + l_i u_i × n_i)ᵀ]: the printed row omits the "
             "rotation of the revolute axis with the platform. Our nonlinear forward kinematics (six loop equations, chord "
             "Newton) agrees with the verified first-order model to finite-difference accuracy (tests: relative mismatch "
             "< 1e-6) and disagrees with the printed one by O(1). J_p agrees with the paper's.")
    for variant in ("paper", "verified"):
        v, figs = summary["variants"][variant], summary["figures"][variant]
        tols, wc = v["tolerances"], v["worst_case_measure"]
        names = list(tols["ga"])
        rows = [[n, PAPER_TABLE1[j] / UNIT, tols["ga"][n] / UNIT, tols["optimum"][n] / UNIT, PAPER_TABLE2[j] / UNIT,
                 tols["sensitivity"][n] / UNIT, tols["sensitivity_collective"][n] / UNIT,
                 wc["optimum_tolerances"][n] / UNIT] for j, n in enumerate(names)]
        rows.append(["cost", summary["paper_table1_cost"], v["ga_cost"], v["optimum_cost"], summary["paper_table2_cost"],
                     v["sensitivity_cost"], v["sensitivity_collective_lengths_cost"], wc["optimum_cost"]])
        rep.heading(f"Tolerances (1e-5 m), {variant} model, RSS measure — Tables 1–2 with ours")
        rep.table(rows, ["source", "paper Table 1", "our GA", "certified optimum", "paper Table 2", "sensitivity",
                         "sensitivity (collective lengths)", "optimum, worst-case measure"], table_id=f"tol-{variant}")
        c = v["contributions_ga_worst_pose"]
        rep.text(f"Contributors at the GA's worst pose ({variant} model): " +
                 ", ".join(f"{src} {pc:.1f} %" for src, pc in zip(c["source"], c["percent"]) if pc >= 1) + ".")
        opt_cost = v["optimum_cost"]
        fig = go.Figure()
        h = figs["convergence_lhs_start"]
        fig.add_scatter(x=h["generation"], y=h["best_fitness"], name="best (pymoo GA + boundary repair, LHS start)")
        fig.add_scatter(x=h["generation"], y=h["mean_fitness"], name="population mean", line=dict(dash="dot"))
        hp = figs["convergence_paper_operators"]
        fig.add_scatter(x=hp["generation"], y=hp["best_feasible"], name="best feasible (paper operators, penalty eq. 15, baseline seeds)")
        fig.add_hline(y=opt_cost, line_dash="dash", annotation_text=f"certified optimum {opt_cost:.4f}")
        fig.update_layout(title=f"Convergence of the manufacturing cost (Fig. 4), {variant} model",
                          xaxis_title="generation", yaxis_title="cost", height=420,
                          yaxis_range=[opt_cost * 0.95, max(opt_cost * 1.6, float(h["best_fitness"][0]) * 1.05)])
        rep.figure(fig)
        f5 = figs["fig5_ga"]
        au, bu = np.asarray(f5["alpha_deg"]), np.asarray(f5["beta_deg"])
        fig = make_subplots(rows=1, cols=2, subplot_titles=(f"first-order {variant} model (the paper's check)",
                                                            "nonlinear kinematics (the real robot)"))
        for col, rate in ((1, f5["exceed_rate_linear"]), (2, f5["exceed_rate_nonlinear"])):
            z = 100 * np.asarray(rate, float).reshape(len(au), len(bu)).T
            fig.add_trace(go.Heatmap(x=au, y=bu, z=z, coloraxis="coloraxis"), 1, col)
        fig.update_layout(title=f"Monte Carlo exceed rate (%) of the GA allocation at Z_c = {f5['z_c_m']:.3f} m (Fig. 5), "
                                f"{f5['n_samples']} LHS samples per pose", coloraxis=dict(colorscale="Viridis", cmin=0),
                          height=430)
        fig.update_xaxes(title_text="α (deg)")
        fig.update_yaxes(title_text="β (deg)")
        rep.figure(fig)
        fig = go.Figure()
        front = v["pareto_front"]
        fig.add_scatter(x=np.asarray(front["normalised_error"], float) * E_POS / UM, y=front["cost"], mode="markers",
                        name="NSGA-II front")
        for key, label in (("paper_table1", "paper Table 1"), ("paper_table2", "paper Table 2")):
            fig.add_scatter(x=[v[key]["rss_error"] / UM], y=[v[key]["cost"]], mode="markers+text", text=[label],
                            textposition="top center", marker=dict(size=12, symbol="diamond"), name=label)
        fig.add_scatter(x=[figs["ga_max_rss_error"] / UM], y=[v["ga_cost"]], mode="markers", marker=dict(size=10, symbol="x"),
                        name="our GA")
        fig.add_vline(x=E_POS / UM, line_dash="dash", annotation_text="requirement 50 µm")
        fig.update_layout(title=f"Cost vs. max RSS position error (NSGA-II), {variant} model", xaxis_title="max RSS error (µm)",
                          yaxis_title="cost", xaxis_type="log", yaxis_type="log", height=450)
        rep.figure(fig)
    checks = {variant: {k: summary["variants"][variant][k] for k in _DESIGNS} for variant in ("paper", "verified")}
    rep.heading("Monte Carlo and the worst case")
    rep.text(f"Sampled errors (1000 LHS samples per pose) reach at most "
             f"{100 * max(c['mc_max_over_worst_case'] for c in checks['verified'].values()):.0f} % of the exact worst case: "
             "sampling alone cannot verify a worst-case requirement. The linearisation error of the verified model "
             f"(nonlinear vs first order) is {checks['verified']['ga']['linearisation_error']:.2e} relative; "
             f"of the paper's model, {checks['paper']['ga']['linearisation_error']:.2f}.")
    rep.heading("GA robustness")
    rep.text("Started from a Latin hypercube only (no baseline seeds), the GA reaches " + "; ".join(
        f"{v}: {d['ga_unseeded_cost']:.5f} ({100 * d['ga_unseeded_over_optimum']:+.4f} % vs the optimum, first generation's best "
        f"{d['ga_unseeded_initial_best']:.4f})" for v, d in summary["variants"].items()) + ".")
    return rep


STUDY = Study(name="yao2013", title="3-UCR accuracy synthesis by GA vs. sensitivity vs. certified optimum",
              compute=compute, render=render, config=CONFIG, quick=QUICK,
              seed_paper="Yao, Wang, Zhou & Zhou 2013 (JATIT 53(1))")

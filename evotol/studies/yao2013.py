"""Yao, Wang, Zhou & Zhou 2013: accuracy synthesis of a 3-UCR parallel robot by GA (seed 002).

Reproduces: the GA allocation under the exponential cost model (Table 1, cost 2.1837), the
sensitivity-based allocation (Table 2, cost 4.2391), the convergence curve (Fig. 4) and the Monte
Carlo exceed rate over (α, β) at Z_c = 0.305 m (Fig. 5); and judges them against the certified
optimum, under both error models (``paper`` = eqs. 10–11 as printed, ``verified`` = derived and
checked against finite differences) and two accuracy measures (RSS, exact worst case).
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from cost_models import ExponentialCost
from evotol.allocators import (allocate_ga, allocate_lagrange, allocate_nsga2, allocate_optimum,
                               allocate_sensitivity)
from evotol.montecarlo import verify
from evotol.problem import Requirement, Tolerance, ToleranceProblem
from evotol.reporting import Report, write_json
from evotol.studies import Study
from robots.ucr3 import UCR3

UNIT = 1e-5  # the paper's tolerance unit (m)
E_POS = 5e-5  # allowed position error (m), Sec. 5
#: Paper Table 1 (GA) and Table 2 (sensitivity), units of 1e-5 m, in our source order
#: l1..l3, U1a..U3a, U1b..U3b, R1..R3. The paper's first "U joints" row is the pair whose
#: sensitivity-based tolerance is tighter (≈2.2); under the paper's model that is R_i2 (U_ib),
#: so row 1 -> U_ib and row 2 -> U_ia.
PAPER_TABLE1 = np.array([4.94, 4.81, 4.96, 2.95, 2.96, 2.94, 2.94, 2.93, 2.97, 2.98, 2.93, 2.89]) * UNIT
PAPER_TABLE2 = np.array([1.38, 1.38, 1.38, 4.29, 4.34, 4.31, 2.21, 2.19, 2.17, 4.30, 4.37, 4.32]) * UNIT
PAPER_COSTS = {"table1": 2.1837, "table2": 4.2391}


def yao2013_problem(variant: str, measure: str = "rss", grid=(11, 11, 6), lower=0.1 * UNIT, upper=20 * UNIT) -> ToleranceProblem:
    """The paper's problem: 12 sources, exponential costs (a0, a1) = (1.9, 0.5) for lengths and
    (1.1, 0.6) for joints with t in units of 1e-5 m, |δp| <= 5e-5 m over the workspace grid."""
    robot = UCR3(variant=variant)
    tol = {}
    for s in robot.sources:
        cost = ExponentialCost(1.9, 0.5, scale=UNIT) if s.group == "length" else ExponentialCost(1.1, 0.6, scale=UNIT)
        tol[s.name] = Tolerance(cost, lower, upper)
    return ToleranceProblem(robot, tol, Requirement(position=E_POS, measure=measure), robot.workspace.grid(list(grid)))


def _plane(problem: ToleranceProblem, zc: float) -> ToleranceProblem:
    idx = np.flatnonzero(np.isclose(problem.poses[:, 2], zc))
    return ToleranceProblem(problem.robot, problem.tolerances, problem.requirement, problem.poses[idx])


def run(out_dir, quick: bool = False, seed: int = 0) -> dict:
    t_start = time.perf_counter()
    out_dir = Path(out_dir)
    grid = (5, 5, 3) if quick else (11, 11, 6)
    pop, gens = (40, 40) if quick else (100, 200)
    n_mc = 200 if quick else 1000
    summary = {"paper_table1_cost": None, "paper_table2_cost": None, "variants": {}, "paper_reported_costs": PAPER_COSTS,
               "grid": list(grid), "requirement_position_m": E_POS, "seed": seed}
    figs, tables, ga_seconds = {}, {}, {}
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
        designs = {"paper_table1": PAPER_TABLE1, "paper_table2": PAPER_TABLE2, "ga": ga.t, "sensitivity": sens.t,
                   "optimum": opt.t}
        plane = _plane(prob, prob.poses[:, 2].max())
        checks = {}
        for name, t in designs.items():
            mc = verify(prob, t, n_mc, seed=seed, nonlinear=False)
            mc_nl = verify(plane, t, n_mc, seed=seed, nonlinear=True)
            checks[name] = {"cost": float(prob.cost(t)),
                            "worst_case_error": float(prob_wc.max_errors(t[None])["position"][0]),
                            "rss_error": float(prob.max_errors(t[None])["position"][0]),
                            "mc_max_exceed_rate": mc.max_exceed_rate(),
                            "mc_max_exceed_rate_nonlinear_at_top_plane": mc_nl.max_exceed_rate(nonlinear=True),
                            "linearisation_error": mc_nl.linearisation_error,
                            "mc_max_over_worst_case": mc.max_error_over_worst_case["position"]}
            if name == "ga":
                figs[(variant, "fig5")] = (plane.poses, mc_nl)
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
        tables[variant] = (prob, ga, ga_paper, sens, sens_c, opt, opt_wc, front, checks, ga_cold)
    summary["ga_seconds"] = ga_seconds["paper"]
    summary["ga_seconds_by_variant"] = ga_seconds
    summary["seconds"] = time.perf_counter() - t_start
    _report(out_dir / "yao2013.html", summary, tables, figs)
    write_json(out_dir / "yao2013.json", summary)
    return summary


def _report(path: Path, summary: dict, tables: dict, figs: dict) -> None:
    import plotly.graph_objects as go

    rep = Report("Yao et al. 2013 — accuracy synthesis of a 3-UCR parallel robot",
                 "Seed 002: 3-UCR telescope secondary-mirror support; exponential cost model; |δp| ≤ 5e-5 m over "
                 "α, β ∈ [−5°, 5°], Z_c ∈ [0.255, 0.305] m. Reproduced by evotol.")
    v_p, v_v = summary["variants"]["paper"], summary["variants"]["verified"]
    rep.heading("What holds")
    holds = []
    for variant, v in summary["variants"].items():
        for key, label in (("paper_table1", "Table 1 (GA)"), ("paper_table2", "Table 2 (sensitivity)")):
            c = v[key]
            holds.append([variant, label, c["cost"], c["rss_error"], c["rss_error"] <= E_POS * (1 + 1e-9),
                          c["worst_case_error"], c["worst_case_error"] <= E_POS * (1 + 1e-9), c["mc_max_exceed_rate"],
                          c["mc_max_exceed_rate_nonlinear_at_top_plane"]])
    rep.table(holds, ["error model", "paper allocation", "cost", "max RSS error (m)", "holds 5e-5 m (RSS)",
                      "max worst-case error (m)", "holds 5e-5 m (worst case)", "MC max exceed rate (linear)",
                      "MC max exceed rate (nonlinear, Z_c = top)"], table_id="holds")
    rep.text(
        f"Under the paper's own model (eqs. 10–11 as printed) and the RSS measure, Table 1 has max RSS error "
        f"{v_p['paper_table1']['rss_error']:.4g} m ({100 * (v_p['paper_table1']['rss_error'] / E_POS - 1):+.1f} % of the bound) "
        f"and a Monte Carlo exceed rate of at most {100 * v_p['paper_table1']['mc_max_exceed_rate']:.1f} % (the paper: under 10 %). "
        f"Under the verified model Table 1 has RSS error {v_v['paper_table1']['rss_error']:.4g} m and exceed rate "
        f"{100 * v_v['paper_table1']['mc_max_exceed_rate']:.0f} %: the paper's allocation does not hold the requirement on the real kinematics. "
        f"No paper allocation holds 5e-5 m in the worst case under either model.", note=True)
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
        f"lengths loosen to ≈4.3e-5 m, and the sensitivity allocation costs only {v_p['sensitivity_over_ga']:.2f}× the GA. "
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
        prob, ga, ga_paper, sens, sens_c, opt, opt_wc, front, checks, ga_cold = tables[variant]
        rep.heading(f"Tolerances (1e-5 m), {variant} model, RSS measure — Tables 1–2 with ours")
        rows = [[n, PAPER_TABLE1[j] / UNIT, ga.t[j] / UNIT, opt.t[j] / UNIT, PAPER_TABLE2[j] / UNIT, sens.t[j] / UNIT,
                 sens_c.t[j] / UNIT, opt_wc.t[j] / UNIT] for j, n in enumerate(prob.names)]
        rows.append(["cost", summary["paper_table1_cost"], ga.cost, opt.cost, summary["paper_table2_cost"], sens.cost,
                     sens_c.cost, opt_wc.cost])
        rep.table(rows, ["source", "paper Table 1", "our GA", "certified optimum", "paper Table 2", "sensitivity",
                         "sensitivity (collective lengths)", "optimum, worst-case measure"], table_id=f"tol-{variant}")
        c = ga.contributions()
        rep.text(f"Contributors at the GA's worst pose ({variant} model): " +
                 ", ".join(f"{r.source} {r.percent:.1f} %" for r in c.itertuples() if r.percent >= 1) + ".")
        fig = go.Figure()
        h = ga_cold.history
        fig.add_scatter(x=h["generation"], y=h["best_fitness"], name="best (pymoo GA + boundary repair, LHS start)")
        fig.add_scatter(x=h["generation"], y=h["mean_fitness"], name="population mean", line=dict(dash="dot"))
        hp = ga_paper.history
        fig.add_scatter(x=hp["generation"], y=hp["best_feasible"], name="best feasible (paper operators, penalty eq. 15, baseline seeds)")
        fig.add_hline(y=opt.cost, line_dash="dash", annotation_text=f"certified optimum {opt.cost:.4f}")
        fig.update_layout(title=f"Convergence of the manufacturing cost (Fig. 4), {variant} model",
                          xaxis_title="generation", yaxis_title="cost", height=420,
                          yaxis_range=[opt.cost * 0.95, max(opt.cost * 1.6, float(h["best_fitness"].iloc[0]) * 1.05)])
        rep.figure(fig)
        poses, mc = figs[(variant, "fig5")]
        from plotly.subplots import make_subplots
        au, bu = np.unique(np.degrees(poses[:, 0])), np.unique(np.degrees(poses[:, 1]))
        fig = make_subplots(rows=1, cols=2, subplot_titles=(f"first-order {variant} model (the paper's check)",
                                                            "nonlinear kinematics (the real robot)"))
        for col, rate in ((1, mc.exceed_rate["position"]), (2, mc.nonlinear_exceed_rate["position"])):
            fig.add_trace(go.Heatmap(x=au, y=bu, z=100 * rate.reshape(len(au), len(bu)).T, coloraxis="coloraxis"), 1, col)
        fig.update_layout(title=f"Monte Carlo exceed rate (%) of the GA allocation at Z_c = {poses[0, 2]:.3f} m (Fig. 5), "
                                f"{mc.n_samples} LHS samples per pose", coloraxis=dict(colorscale="Viridis", cmin=0),
                          height=430)
        fig.update_xaxes(title_text="α (deg)")
        fig.update_yaxes(title_text="β (deg)")
        rep.figure(fig)
        fig = go.Figure()
        fig.add_scatter(x=front.table["normalised_error"] * E_POS, y=front.cost, mode="markers", name="NSGA-II front")
        for key, label in (("paper_table1", "paper Table 1"), ("paper_table2", "paper Table 2")):
            fig.add_scatter(x=[checks[key]["rss_error"]], y=[checks[key]["cost"]], mode="markers+text", text=[label],
                            textposition="top center", marker=dict(size=12, symbol="diamond"), name=label)
        fig.add_scatter(x=[ga.max_error()], y=[ga.cost], mode="markers", marker=dict(size=10, symbol="x"), name="our GA")
        fig.add_vline(x=E_POS, line_dash="dash", annotation_text="requirement")
        fig.update_layout(title=f"Cost vs. max RSS position error (NSGA-II), {variant} model", xaxis_title="max RSS error (m)",
                          yaxis_title="cost", xaxis_type="log", yaxis_type="log", height=450)
        rep.figure(fig)
    rep.heading("Monte Carlo and the worst case")
    rep.text(f"Sampled errors (1000 LHS samples per pose) reach at most "
             f"{100 * max(c['mc_max_over_worst_case'] for c in tables['verified'][8].values()):.0f} % of the exact worst case: "
             "sampling alone cannot verify a worst-case requirement. The linearisation error of the verified model "
             f"(nonlinear vs first order) is {tables['verified'][8]['ga']['linearisation_error']:.2e} relative; "
             f"of the paper's model, {tables['paper'][8]['ga']['linearisation_error']:.2f}.")
    rep.heading("GA robustness")
    rep.text("Started from a Latin hypercube only (no baseline seeds), the GA reaches " + "; ".join(
        f"{v}: {d['ga_unseeded_cost']:.5f} ({100 * d['ga_unseeded_over_optimum']:+.4f} % vs the optimum, first generation's best "
        f"{d['ga_unseeded_initial_best']:.4f})" for v, d in summary["variants"].items()) + ".")
    rep.write(path)


STUDY = Study(name="yao2013", title="3-UCR accuracy synthesis by GA vs. sensitivity vs. certified optimum",
              run=run, seed_paper="Yao, Wang, Zhou & Zhou 2013 (JATIT 53(1))")

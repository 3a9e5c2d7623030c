"""The report of the ``choi2000-clutch`` study, drawn from its JSON summary only."""
from __future__ import annotations


def _row(label: str, d: dict) -> list:
    return [label, ", ".join(map(str, d["processes"])), ", ".join(f"{t:.6f}" for t in d["tolerances_mm"]),
            d["machining_cost"], d["quality_loss"], d["total_cost"], d["rss_rad"], d["worst_case_rad"],
            "yes" if d["holds_limit"] else f"no ({d['measure_over_limit']:.5f} × limit)"]


HEAD = ["design", "processes (1-based ids)", "t (mm)", "machining cost", "quality loss", "total", "RSS angle (rad)",
        "worst-case angle (rad)", "holds the limit"]


def render_report(s: dict):
    from evotol.reporting import Report

    rep = Report("Overrunning clutch with quality loss: exact process selection vs. Choi 2000",
                 f"Data: {s['source']}. Y = {s['assembly_function'].split('(contact')[0].strip()}, limit ±{s['limit_rad']} rad "
                 f"(RSS, t = 3σ); cost a + b/t per process; loss K = A/T² times E[(Y − Y0)²] (first order, σ = t/3).")
    rep.heading("Which cage nominal the published numbers fit")
    rows = []
    for cage, e in s["cage_nominal_evidence"].items():
        rows.append([cage, e["nominal_angle_rad"], e["rss_over_T_A0"], e["rss_over_T_A20"], e["rss_over_T_A100"],
                     ", ".join(f"{r:.4f}" for r in e["loss_balance_ratio_A100"])])
    rep.table(rows, ["cage (mm)", "nominal angle (rad)", "published RSS / T, A = 0", "A = 20", "A = 100",
                     "A = 100 loss balance b/(S²t³) / (2K/9)"], table_id="cage_nominal")
    rep.text(f"Chosen: {s['cage_nominal_mm']} mm. {s['cage_nominal_rule']} The data file's nominal angle is 0.122 rad.",
             note=True)
    for c in s["cases"]:
        A = c["quality_loss_A"]
        rep.heading(f"A = {A:g} (K = {c['K_per_rad2']:.1f} per rad²)")
        rows = [_row("exact optimum (branch and bound)", c["optimum"])]
        if "published" in c:
            rows.append(_row("published (Choi's method), recomputed", c["published"]))
            rows.append(_row("certified optimum on the published processes", c["optimum_on_published_processes"]))
        rows.append(_row("GA (pymoo)", c["ga"]))
        rows.append(_row("exact optimum, worst-case limit (first order)", c["worst_case"]["optimum"]))
        rows.append(_row("worst-case limit held on the nonlinear angle", c["worst_case"]["nonlinear"]["holding_the_nonlinear_limit"]))
        rep.table(rows, HEAD, table_id=f"designs_A{A:g}")
        cert = c["optimum"]["certificate"]
        mc = c["mc_nonlinear_at_optimum"]
        txt = (f"Branch and bound: {cert['n_nodes']} nodes, {cert['n_convex_solves']} convex solves of "
               f"{cert['n_combinations']} combinations (enumeration: {c['enumeration']['n_convex_solves']} solves, same "
               f"optimum: {c['enumeration']['same_optimum']}); leaf duality gap {cert['leaf_gap']:.1e}, smallest pruned "
               f"bound {_pruned(cert)}. GA / optimum − 1 = {c['ga_over_optimum']:.2e}; NSGA-II cheapest "
               f"feasible front point / optimum − 1 = {c['nsga2']['cheapest_feasible_over_optimum']:.2e} "
               f"({c['nsga2']['front_size']} points). Nonlinear Monte Carlo at the optimum ({mc['n_samples']} assemblies, "
               f"{mc['sampling']}): {mc['fraction_outside']:.4%} outside ±T (linear model: 0.27 %), largest "
               f"|ΔY|/T = {mc['max_abs_normalised']:.3f}. Worst-case optimum costs "
               f"{c['worst_case']['over_rss_optimum']:+.2%} more than the RSS optimum.")
        nl = c["worst_case"]["nonlinear"]
        txt += (f" Nonlinear worst case over the tolerance box ({nl['method']}): the first-order worst-case optimum "
                f"reaches {nl['linear_optimum_nonlinear_worst_case_over_limit']:.4f} T; holding the real limit "
                f"({nl['iterations']} re-linearisations) costs {nl['cost_difference']:+.4f} "
                f"({100 * nl['cost_difference_over_linear']:+.2f} %), proven worst case "
                f"{nl['holding_the_nonlinear_limit']['nonlinear_worst_case_over_limit']:.6f} T, Monte Carlo largest "
                f"|ΔY|/T {nl['mc_nonlinear']['max_abs_normalised']:.4f}.")
        rep.text(txt, note=True)
        if "difference" in c:
            rep.text(c["difference"]["text"], note=True)
    return rep


def _pruned(cert: dict) -> str:
    """The smallest pruned lower bound against the incumbent (cost units), or that none was pruned."""
    b, inc = cert["smallest_pruned_bound"], cert["incumbent"]
    if b is None:
        return "none (no node was pruned)"
    return f"{b:.6g} (incumbent {inc:.6g}; bound / incumbent − 1 = {b / inc - 1:+.1e})"

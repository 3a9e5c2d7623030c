"""The "ISO 9283" section of a user study's report, from its JSON summary alone.

Reads ``summary["iso9283"]`` (:func:`evotol.studyfile.iso9283.iso9283_block`): per pose the predicted and
simulated AP and RP with their intervals, what each source takes of AP and of RP, the random sources and
the allocation (docs/iso9283.md).
"""
from __future__ import annotations

from html import escape

import plotly.graph_objects as go

from evotol.units.display import DisplayUnits

#: the ISO block's allocations by the study's rules (evotol/studyfile/iso9283_methods.py): key -> (name, method, how)
RULE_NAMES = {
    "allocation_sensitivity": ("the equal-effect rule", "sensitivity", "each source the same share of AP, each random "
                               "source the same share of RP, scaled onto the boundary"),
    "allocation_equal": ("equal tolerances", "equal", "every tolerance the same value, the largest that meets AP and RP"),
    "allocation_lagrange": ("the Lagrange closed form", "lagrange", "least cost on the AP worst-case and RP "
                            "root-sum-square stack-ups, scaled onto the boundary"),
    "allocation_monotone": ("the polyblock bracket's design", "monotone", "the cheapest design the polyblock search "
                            "found or started from, the upper end of a bracket of the least cost"),
}


def bracket_clause(g: dict, optimum_cost: float) -> str:
    """The bracket of the ``monotone`` rule beside the optimum's cost (page and terminal); empty for the other rules.

    Parameters
    ----------
    g : dict
        The rule's allocation in the ISO block (``lower_bound``, ``gap``, ``rounds``, ``vertices``, ``converged``).
    optimum_cost : float
        The certified optimum's cost (cost models' unit).

    Returns
    -------
    str
    """
    if "lower_bound" not in g:
        return ""
    return (f"; bracket [{g['lower_bound']:.6g}, {g['cost']:.6g}] of the least cost (gap {100 * g['gap']:.1f} %, "
            f"{g['rounds']} rounds, {g['vertices']} vertices, "
            f"{'converged' if g['converged'] else 'not converged: stopped by ' + str(g.get('stop'))}), "
            f"the certified optimum {optimum_cost:.6g}"
            + (" inside it" if g["lower_bound"] <= optimum_cost <= g["cost"] else
               " above it (the optimum aims its AP at AP cos δ, at most about 0.4 % dearer)" if optimum_cost > g["cost"]
               else " below it (RP on the fixed draws is not monotone: docs/iso9283.md)"))


def iso9283_section(rep, summary: dict) -> None:
    """Append the ISO 9283 section to a user study's report (module docstring).

    Parameters
    ----------
    rep : evotol.reporting.html.Report
        The page being built.
    summary : dict
        A user study's JSON summary with an ``iso9283`` block (SI values).
    """
    iso = summary["iso9283"]
    u = DisplayUnits(**summary["display_units"])

    def L(v):
        return "–" if v is None else u.format(v, "m")

    req = iso["requirement"]
    rep.heading("ISO 9283 pose accuracy and repeatability")
    rep.text(f"Test cube: centre ({', '.join(L(c) for c in iso['cube']['centre'])}), edge {L(iso['cube']['edge'])}; "
             f"requirement AP ≤ {L(req['AP'])}" + ("" if req["yield"] is None else f" at yield {req['yield']:g}")
             + f", RP ≤ {L(req['RP'])}; systematic tolerances from {iso['systematic_from']}; simulated: "
             f"{iso['simulation']['robots']} robots × {iso['simulation']['cycles']} cycles, approaches "
             f"{', '.join(iso['simulation']['approaches'])}, {iso['simulation']['model']}.")
    rows = []
    for p in iso["poses"]:
        ap, rp, aq = p["AP"], p["RP"], p["AP_quantile"]
        rows.append([p["name"], ", ".join(L(c) for c in p["position"]), L(ap["predicted"]), L(ap["bound"]),
                     L(ap["simulated"]), f"{L(aq['predicted'])} / {L(aq['simulated'])} "
                     f"({L(aq['interval'][0])} – {L(aq['interval'][1])})", L(rp["predicted"]), L(rp["gaussian_shortcut"]), L(rp["simulated"]),
                     f"{L(rp['interval'][0])} – {L(rp['interval'][1])}", L(p.get("vAP", {}).get("simulated"))])
    q = iso["poses"][0]["AP_quantile"]["yield"]
    rep.table(rows, ["pose", "position", "AP predicted", "AP proven bound", "AP simulated",
                     f"AP at yield {q:g}: predicted / simulated (95 %)", "RP predicted",
                     "RP Gaussian shortcut", "RP simulated", "RP of one test (95 %)", "vAP simulated"],
              table_id="iso9283")
    if "AP_orientation" in iso["poses"][0]:     # ISO 9283 §7.2, where the requirement has an orientation
        A = lambda v: u.format(v, "rad")        # noqa: E731
        rep.table([[p["name"]] + [f"{A(p['AP_orientation'][a]['predicted'])} / {A(p['AP_orientation'][a]['simulated'])}"
                                  for a in "abc"]
                   + [f"{A(p['RP_orientation'][a]['predicted'])} / {A(p['RP_orientation'][a]['simulated'])}" for a in "abc"]
                   for p in iso["poses"]],
                  ["pose"] + [f"AP{a} predicted / simulated" for a in "abc"] + [f"RP{a} predicted / simulated" for a in "abc"],
                  table_id="iso9283-orientation")
    for fig, v in iso.get("verdict", {}).items():     # a verdict names its model (STYLE.md)
        unit = "rad" if fig[2:] in ("a", "b", "c") else "m"             # APa, RPb, ...: an angle
        V = lambda x: escape(u.format(x, unit))                           # noqa: E731
        sim = (f"simulated on the nonlinear model ({escape(v['simulated_as'])}): {V(v['simulated'])}"
               + ("." if v["simulated_within"] else ", above the requirement.")) if v["simulated"] is not None else \
            escape(v["simulated_as"]) + "."
        rep.text(f"{fig} ≤ {V(v['requirement'])}: the design <b>{v['verdict']}</b> it: {V(v['predicted'])} on the "
                 f"{escape(v['model'])}; {sim}", raw=True)
    for line in iso["notes"]:
        rep.text(line, note=True)
    buys = iso["what_each_source_buys"]
    rep.text("What buys accuracy (share of the worst-case AP at " + buys["AP_pose"] + "): "
             + ", ".join(f"{k} {100 * v:.1f} %" for k, v in list(buys["AP"].items())[:8])
             + ". What buys repeatability (share of the RP variance at " + buys["RP_pose"] + "): "
             + ", ".join(f"{k} {100 * v:.1f} %" for k, v in list(buys["RP"].items())[:8]) + ".")
    rows = [[s["name"], s["kind"], u.format(s["tolerance"], s["unit"]), "–" if s["cost"] is None else f"{s['cost']:.4g}"]
            for s in iso["random_sources"]]
    rep.table(rows, ["random source", "kind", "tolerance", "cost"], table_id="iso9283-random")
    if "calibrated" in iso:
        c = iso["calibrated"]
        rep.text(f"The same design calibrated ({c['robots']} simulated robots; {c['configurations']} configurations, "
                 f"noise {L(c['noise'])} per axis; rank {c['identified_rank']} of {c['n_columns']} sources identified): "
                 "calibration lowers AP, not RP; the lost motion's offset, the random sources and the noise remain.")
        rep.table([[p["name"], L(p["AP_before_mean"]), L(p["AP_after_mean"]), L(p["AP_before_max"]), L(p["AP_after_max"]),
                    L(p["RP_before_mean"]), L(p["RP_after_mean"])] for p in c["poses"]],
                  ["pose", "AP before (mean)", "AP after (mean)", "AP before (max)", "AP after (max)", "RP before",
                   "RP after"], table_id="iso9283-calibrated")
    if "calibrated_budget" in iso:          # the study's [calibration] with random sources (issue 44 item 4)
        b = iso["calibrated_budget"]
        al = b.get("random_allocation")
        rep.text(f"After the study's calibration (first order, the noise's quantile at {100 * iso['poses'][0]['calibrated']['AP']['level']:.2f} %): "
                 "AP is the systematic residual and the lost motion's offset (proven bound) plus the fit's error from the "
                 "tracker's noise and the random sources; RP does not change."
                 + ("" if b.get("random_worst_case") is None else
                    f" The random sources take {L(b['random_worst_case'])} (worst case at a task pose) and "
                    f"{L(b['random_identification'])} of the fit's quantile (noise alone {L(b['noise_only'])}) of the "
                    f"requirement {L(b['requirement'])}")
                 + ("." if not al else f"; allocated, they cost {al['cost']:.4g} and the requirement "
                    + ("binds." if al["active"] else "does not bind."))
                 + ("" if not (al and al.get("iso")) else
                    " They are allocated to the ISO requirement after calibration too (binding: "
                    + (", ".join(k for k, v in al["iso"]["active"].items() if v) or "none") + "). " + al["iso"]["proven"] + "."))
        rep.table([[p["name"], L(p["AP"]["predicted"]), L(p["calibrated"]["AP"]["predicted"]),
                    L(p["calibrated"]["AP"]["systematic_bound"]), L(p["calibrated"]["AP"]["noise_quantile"]),
                    L(p["calibrated"]["RP"]["predicted"])] for p in iso["poses"]],
                  ["pose", "AP uncalibrated", "AP calibrated", "of which systematic and lost motion", "of which fit error",
                   "RP (unchanged)"], table_id="iso9283-calibrated-plan")
        for line in calibrated_method_lines(b):
            rep.text(line, note="NOT feasible" in line)
        if not_iso(iso):
            rep.text(not_iso(iso), note=True)
    if "allocation" in iso:
        a = iso["allocation"]
        rep.text(f"Allocated with the systematic sources: cost {a['cost']:.4g}, "
                 f"{'feasible' if a['feasible'] else 'NOT feasible'}, active: "
                 + (", ".join(k for k, v in a["active"].items() if v) or "none") + ". " + a["proven"], note=not a["feasible"])
        if "allocation_ga" in iso:      # the study's GA on the same problem (evotol/studyfile/iso9283_methods.py)
            g = iso["allocation_ga"]
            rep.text(f"The GA ({g['pop_size']} × {g['n_gen']}) allocated them together too: cost {g['cost']:.4g} "
                     f"({100 * g['gap_to_optimum']:+.2f} % against the allocation above), "
                     + ("feasible" if g["feasible"] else "NOT feasible") + " by the same check (proven AP bound, RP on the "
                     "same draws).", note=not g["feasible"])
        for key, (name, method, how) in RULE_NAMES.items():     # the study's rules on the same problem
            if key in iso:
                g = iso[key]
                rep.text(f"{name[0].upper() + name[1:]} (the study's {method} method: {how}) costs {g['cost']:.4g} "
                         f"({100 * g['gap_to_optimum']:+.2f} % against the allocation above), "
                         + ("feasible" if g["feasible"] else "NOT feasible") + " by the same check"
                         + bracket_clause(g, a["cost"]) + ".", note=not g["feasible"])
        if "front_nsga2" in iso:        # the study's nsga2 on the same problem: cost against AP, RP held
            f = iso["front_nsga2"]
            rep.text(front_sentence(f, L))
            rep.figure(_front_figure(f, u), div_id="iso9283-front")
        if not_iso(iso):
            rep.text(not_iso(iso), note=True)


def calibrated_method_lines(budget: dict) -> list[str]:
    """One sentence per study method that allocated the random sources in the calibrated budget too (page and
    terminal; evotol/studyfile/iso9283_calibrated.py).

    Parameters
    ----------
    budget : dict
        The ISO block's ``calibrated_budget`` (its ``methods`` and ``random_allocation``).

    Returns
    -------
    list of str
    """
    al = budget.get("random_allocation") or {}
    out = []
    for m, g in budget.get("methods", {}).items():
        size = f" ({g['pop_size']} x {g['n_gen']})" if m == "ga" else ""
        bracket = "" if "lower_bound" not in g else (
            f" Its bracket of the least cost: [{g['lower_bound']:.6g}, {g['upper_bound']:.6g}] (gap {100 * g['gap']:.1f} %, "
            f"stopped by {g['stop']}; the lower bound proven for {g['lower_bound_proven_for']}).")
        out.append(f"The study's {m}{size} allocated the random sources in the calibrated budget too: cost {g['cost']:.6g} "
                   f"({100 * g['gap_to_optimum']:+.2f} % against the least-cost design, {al.get('cost', float('nan')):.6g}), "
                   + ("feasible" if g["feasible"] else "NOT feasible") + " by the same check; " + g["meaning"] + "." + bracket)
    return out


def not_iso(iso: dict) -> str:
    """The sentence naming the study's methods that allocated the systematic sources alone (not to AP/RP, or inside
    ``[calibration]`` not the random sources); empty when every method that ran allocated them too.

    Parameters
    ----------
    iso : dict
        The study JSON's ``iso9283`` block.

    Returns
    -------
    str
    """
    names = [n for n, key in iso.get("methods", {}).items() if key is None]
    if names and "calibrated_budget" in iso:      # [calibration]: the random sources sit in the calibrated budget
        return (f"Random sources not allocated by {', '.join(names)}: it allocated the systematic sources alone, to the "
                "calibrated position requirement; the random sources' designs in the calibrated budget are the ones above.")
    return "" if not names else (
        f"Not allocated to AP/RP: {', '.join(names)} allocated the systematic sources alone, to the position "
        "requirement; the allocations above are the ones to AP and RP.")


def _gaps(f: dict) -> list[float]:
    return [p["gap"] for p in f["points"] if p["gap"] is not None]


def front_sentence(f: dict, L) -> str:
    """What the ISO front is and how far above the exact frontier it lies (page and terminal).

    Parameters
    ----------
    f : dict
        The block's ``front_nsga2`` (evotol/studyfile/iso9283_methods.py).
    L : callable
        A length (m) as text.

    Returns
    -------
    str
    """
    g = _gaps(f)
    ap = [p["AP_bound"] for p in f["points"]]
    return (f"NSGA-II front of cost against AP with RP <= {L(f['requirement']['RP'])} held ({f['pop_size']} x "
            f"{f['n_gen']}): {f['kept']} of {f['judged']} points kept after re-judging by the optimum's check"
            + ("" if not ap else f", AP {L(min(ap))} – {L(max(ap))}")
            + ("" if not g else f"; cost above the exact frontier (certified optima at {len(f['exact_frontier'])} AP "
               f"levels, interpolated in log AP) by {100 * min(g):+.2f} % to {100 * max(g):+.2f} % "
               f"(median {100 * sorted(g)[len(g) // 2]:+.2f} %)") + ".")


def _front_figure(f: dict, u: DisplayUnits):
    k = u.factor("m")
    pts, ex = f["points"], f["exact_frontier"]
    fig = go.Figure(go.Scatter(x=[p["AP_bound"] * k for p in pts], y=[p["cost"] for p in pts], mode="markers",
                               name="NSGA-II front (proven AP bound, RP held)",
                               text=[None if p["gap"] is None else f"{100 * p['gap']:+.2f} % above the frontier"
                                     for p in pts]))
    fig.add_scatter(x=[e["AP"] * k for e in ex], y=[e["cost"] for e in ex], mode="lines+markers",
                    name="exact frontier (certified optima)", line={"color": "black"})
    fig.add_scatter(x=[f["optimum"]["AP_bound"] * k], y=[f["optimum"]["cost"]], mode="markers",
                    name="certified optimum at the requirement", marker={"symbol": "star", "size": 14})
    if f["requirement"]["AP"] is not None:
        fig.add_vline(x=f["requirement"]["AP"] * k, line_dash="dash", line_color="grey", annotation_text="AP required")
    fig.update_layout(title="ISO 9283: cost against AP, RP held (log scales)", height=460, xaxis_type="log",
                      yaxis_type="log", xaxis_title=f"AP, proven bound ({u.length})",
                      yaxis_title="cost")
    return fig


def verdict_lines(summary: dict) -> list[str]:
    """One line per required ISO 9283 figure: the verdict, its value and the model it is on (the page's
    sentences; the nonlinear simulation beside it as evidence).

    Parameters
    ----------
    summary : dict
        A study's JSON summary (allocation or analysis); no lines without an ``iso9283`` verdict.

    Returns
    -------
    list of str
        ``"AP <= 0.5 mm: meets (0.4993 mm, <model>; simulated 0.2021 mm, <as>)"`` per figure.
    """
    u = DisplayUnits(**summary["display_units"])
    out = []
    for fig, v in summary.get("iso9283", {}).get("verdict", {}).items():
        unit = "rad" if fig[2:] in ("a", "b", "c") else "m"        # APa, RPb, ...: an angle
        f = lambda x: u.format(x, unit)                            # noqa: E731
        sim = f"simulated {f(v['simulated'])}, {v['simulated_as']}" if v["simulated"] is not None else v["simulated_as"]
        out.append(f"{fig} <= {f(v['requirement'])}: {v['verdict']} ({f(v['predicted'])}, {v['model']}; {sim})")
    return out


def terminal_lines(summary: dict) -> list[str]:
    """What the page's ISO 9283 section states, as terminal lines: the cube and requirement, the allocation
    of systematic and random sources, each figure's verdict, the predicted and simulated AP and RP per pose,
    and the calibrated AP (RP unchanged).

    Parameters
    ----------
    summary : dict
        A user study's JSON summary; no lines without an ``iso9283`` block.

    Returns
    -------
    list of str
        A title line, then lines indented by two spaces.
    """
    iso = summary.get("iso9283")
    if not iso:
        return []
    u = DisplayUnits(**summary["display_units"])

    def L(v):
        return "-" if v is None else u.format(v, "m")

    req = iso["requirement"]
    out = [f"[evotol] ISO 9283 (docs/iso9283.md): test cube centre ({', '.join(L(c) for c in iso['cube']['centre'])}), "
           f"edge {L(iso['cube']['edge'])}; AP <= {L(req['AP'])}, RP <= {L(req['RP'])}; systematic tolerances from "
           f"{iso['systematic_from']}"]
    if "allocation" in iso:
        a = iso["allocation"]
        out.append(f"  allocated with the random sources: cost {a['cost']:.6g}, {'feasible' if a['feasible'] else 'NOT feasible'}"
                   f", binding: {', '.join(k for k, v in a['active'].items() if v) or 'none'}")
    if "allocation_ga" in iso:
        g = iso["allocation_ga"]
        out.append(f"  the study's ga ({g['pop_size']} x {g['n_gen']}) allocated them too: cost {g['cost']:.6g} "
                   f"({100 * g['gap_to_optimum']:+.2f} % against the allocation above), "
                   + ("feasible" if g["feasible"] else "NOT feasible") + " by the same check")
    for key, (name, method, _) in RULE_NAMES.items():
        if key in iso:
            g = iso[key]
            out.append(f"  {name} ({method}) allocated them too: cost {g['cost']:.6g} "
                       f"({100 * g['gap_to_optimum']:+.2f} % against the allocation above), "
                       + ("feasible" if g["feasible"] else "NOT feasible") + " by the same check"
                       + bracket_clause(g, iso["allocation"]["cost"]))
    if "front_nsga2" in iso:
        out.append("  " + front_sentence(iso["front_nsga2"], L))
    out += ["  " + line for line in calibrated_method_lines(iso.get("calibrated_budget", {}))]
    if not_iso(iso):
        out.append("  " + not_iso(iso))
    out += ["  " + line for line in verdict_lines(summary)]
    for p in iso["poses"]:
        ap, rp = p["AP"], p["RP"]
        out.append(f"  {p['name']}: AP {L(ap['predicted'])} predicted, {L(ap['simulated'])} simulated; RP {L(rp['predicted'])} "
                   f"predicted, {L(rp['simulated'])} simulated ({L(rp['interval'][0])} - {L(rp['interval'][1])} for one test)")
    if "calibrated" in iso:
        c = iso["calibrated"]
        out.append(f"  calibrated ({c['robots']} simulated robots, {c['configurations']} configurations): largest AP "
                   + ", ".join(f"{p['name']} {L(p['AP_before_max'])} -> {L(p['AP_after_max'])}" for p in c["poses"])
                   + "; RP unchanged (" + ", ".join(f"{L(p['RP_before_mean'])} -> {L(p['RP_after_mean'])}" for p in c["poses"][:1])
                   + " at " + c["poses"][0]["name"] + ")")
    return out

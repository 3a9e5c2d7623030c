"""The HTML page of an analysis of given tolerances (``evotol run`` when every source is given).

Drawn from the JSON summary alone (:func:`evotol.studyfile.given_tolerances.analysis_summary`): the
verdict, the given tolerances, per pose the worst case of the norm and the per-axis range (both
signed limits), RSS, the probability of meeting the requirement, the error at the requirement's
probability, the joints used (wrapped to (-180°, 180°]), the contributions at the worst pose,
the Monte Carlo check and, where the study asks, the ISO 9283 section. Values are shown in the study's display units; the JSON stays SI.
"""
from __future__ import annotations

from evotol.reporting.html import Report
from evotol.reporting.iso9283 import iso9283_section
from evotol.reporting.joints_section import joints_section
from evotol.units.display import DisplayUnits

AXES = ("x", "y", "z")


def render_analysis(summary: dict) -> Report:
    """The page of an analysis study.

    Parameters
    ----------
    summary : dict
        The analysis summary (SI values, ``display_units``).

    Returns
    -------
    Report
        The page, not yet written.
    """
    u = DisplayUnits(**summary["display_units"])
    a = summary["analysis"]
    L = lambda v: u.format(v, "m")          # noqa: E731
    A = lambda v: u.format(v, "rad")        # noqa: E731
    al = summary.get("axis_limits") or {}
    req = (", ".join([f"|δ{k}| ≤ {L(v)}" for k, v in al["position"].items()] + [f"|δθ{k}| ≤ {A(v)}" for k, v in al["orientation"].items()])
           + f" ({al['frame']} frame)") if al else ", ".join(f"{c} ≤ {(L if c == 'position' else A)(v)}" for c, v in summary["requirement"].items())
    rep = Report(f"evotol analysis: {summary['name']}",
                 f"{summary['robot']}, {len(summary['poses'])} poses, requirement ({summary['measure']}) {req}; "
                 f"lengths in {u.length}, angles in {u.angle} (the JSON holds SI values)")
    for line in summary.get("warnings", []):
        rep.text(f"Warning: {line}", note=True)
    for line in summary.get("notes", []):
        rep.text(line, note=True)
    verdict = "meets" if a["meets"] else "misses"
    rep.heading("Verdict")
    rep.text(f"Every tolerance is given, so nothing is allocated: these are their consequences. Under the requirement's "
             f"measure ({summary['measure']}) the design <b>{verdict}</b> the requirement: largest error / limit = "
             f"{a['violation'] + 1:.4g}.", raw=True)
    rep.heading("Given tolerances")
    rep.table([[s["name"], s["group"], u.format(s["tolerance"], s["unit"], sign="±"),
                f"{a['worst_case']['position']['contributions'].get(s['name'], 0.0):.1f}"] for s in summary["sources"]],
              ["source", "group", "tolerance", "share of the worst |δp| at the worst pose (%)"])
    rep.heading("Position error per pose")
    rep.text("Worst case of |δp| (exact for the linear model, attained by a vertex of the tolerance box) and of each "
             "component along the base axes, with both signed limits; RSS of |δp| and per axis; the first-order "
             "probability of meeting the requirement under the stated distributions (with per-axis limits: per axis, "
             "P(|δa| ≤ La) for each axis a, not jointly).")
    wc, ax, rss = a["worst_case"]["position"], a["axes"]["base"]["position"], a["rss"]["position"]
    prob = a.get("probability")
    per_axis = a.get("probability_axes") or {}          # per-axis limits: P(meet) per axis (issue 41)
    header = ["pose", "worst |δp|"] + [f"δ{k} range" for k in AXES] + ["RSS |δp|"] + [f"RSS δ{k}" for k in AXES]
    if per_axis:
        header += [f"P(meet) {k}" for k in per_axis]
    elif prob is not None and len(prob) == len(wc["value"]):
        header.append("P(meet)")
    rows = []
    for i in range(len(wc["value"])):
        row = [str(i), L(wc["value"][i])] + [f"[{L(ax[k]['low'][i])}, {L(ax[k]['high'][i])}]" for k in AXES]
        row += [L(rss[i])] + [L(ax[k]["rss"][i]) for k in AXES]
        if per_axis:
            row += [f"{v[i]:.6f}" for v in per_axis.values()]
        elif len(header) > len(row):
            row.append(f"{prob[i]:.6f}")
        rows.append(row)
    rep.table(rows, header, table_id="per-pose")
    if "tool" in a["axes"]:
        tx = a["axes"]["tool"]["position"]
        rep.text("The same per-axis ranges in the nominal tool frame (the requirement's frame):")
        rep.table([[str(i)] + [f"[{L(tx[k]['low'][i])}, {L(tx[k]['high'][i])}]" for k in AXES] for i in range(len(wc["value"]))],
                  ["pose"] + [f"δ{k} range (tool)" for k in AXES])
    ori = a["worst_case"]["orientation"]
    rep.text("Orientation: worst |δθ| per pose " + ", ".join(A(v) for v in ori["value"]) + ".")
    ap = a.get("error_at_probability") or {}
    if ap:
        rep.text(f"|δp| met with probability {ap['probability']:.6g} (first-order model, stated distributions; bisection "
                 f"on the yield measure's bound), per pose: " + ", ".join(L(v) for v in ap["position"]) + ".")
    p = wc["worst_pose"]
    ws = summary["workspace"]
    pose = ", ".join(f"{n} = {_num(v * k)} {du}" for n, v, k, du in zip(ws["names"], summary["poses"][p], ws["display_scale"],
                                                                     ws["display_units"]))
    rep.heading("Worst pose")
    rep.text(f"Pose #{p} ({pose}): |δp| ≤ {L(wc['value'][p])} (proven bound {L(wc['bound'][p])}).")
    joints_section(rep, summary)
    mc = a.get("monte_carlo") or {}
    if mc:
        rep.heading("Monte Carlo")
        rep.text(f"{mc['n_samples']} samples per pose inside the tolerances (seed {mc['seed']}): largest exceed rate "
                 f"{100 * mc['max_exceed_rate']:.3g} % on the linear model"
                 + (f", {100 * mc['max_exceed_rate_nonlinear']:.3g} % on the nonlinear model" if mc.get("max_exceed_rate_nonlinear") is not None else "")
                 + (f". {mc['linearisation_verdict']}." if mc.get("linearisation_verdict") else "."))
    if "iso9283" in summary:        # ISO 9283 AP and RP of the given tolerances (docs/iso9283.md)
        iso9283_section(rep, summary)
    return rep


def _num(v: float) -> str:
    return f"{0.0 if abs(v) < 1e-9 else v:.5g}"

"""The report of a user study (``evotol run``), drawn from its JSON summary alone.

Per method: a top table (cost, the error at the worst pose in display units, the worst pose in
workspace coordinates, the verdict and the certificate, the Monte Carlo exceed rate, the yield
when the measure is yield), the tolerances in display units, an error map over slices of the
continuous workspace, the contributions at the worst pose, the linearisation check with a verdict;
the NSGA-II front with the certified optimum, the GA and the sensitivity design marked; the
what-if explorer (:mod:`evotol.reporting.explorer`). Lengths are shown in µm or mm and angles in
arcsec, mrad or deg (the study's ``display_units``, :mod:`evotol.units.display`); the JSON stays SI.

The parameters several definitions of this module share are described once, here.

Parameters
----------
summary : dict
    A user study's JSON summary (``evotol run``, :mod:`evotol.summaries.user_study`; SI values).
"""
from __future__ import annotations

import html

import numpy as np
import plotly.graph_objects as go
from plotly.subplots import make_subplots

from evotol.units.display import DisplayUnits, number
from evotol.core.pareto import ideal_point_knee
from evotol.reporting.callout_drawing import callout_sections
from evotol.reporting.calibration import calibration_section
from evotol.reporting.shop_floors import floor_lines
from evotol.reporting.iso9283 import iso9283_section
from evotol.reporting.joints_section import joints_section
from evotol.reporting.explorer import explorer_section
from evotol.reporting.html import Report
from evotol.reporting.drawing import drawing_check_text, nominal_line, tolerance_rows, verdict_text, zone_text
from evotol.summaries.drawing import tolerance_zone

#: marker of each method on the NSGA-II plot (symbol, colour)
MARKS = {"optimum": ("star", "#d62728"), "ga": ("diamond", "#2ca02c"), "sensitivity": ("square", "#ff7f0e"),
         "lagrange": ("triangle-up", "#9467bd"), "equal": ("cross", "#8c564b"), "monotone": ("star-diamond", "#e377c2")}


def _units(summary: dict) -> DisplayUnits:
    return DisplayUnits(**summary["display_units"])


def _error_text(summary: dict, comp: str, value) -> str:
    if summary.get("assembly") and summary["error_units"][comp] == "1" and value is not None:
        return f"{number(float(value))} × limit"        # an assembly's error: deviation / its limit
    return _units(summary).format(value, summary["error_units"][comp])


def pose_cells(summary: dict, pose) -> str:
    """A pose (SI) in the workspace's display units: ``x = 12.00 mm, y = -3.000 mm``.

    Parameters
    ----------
    pose : sequence of float
        Workspace coordinates in SI (m, rad), in the order of ``summary["workspace"]["names"]``.

    Returns
    -------
    str
        ``name = value unit`` per coordinate, comma-separated (no unit for dimensionless ones).
    """
    ws = summary["workspace"]
    if summary.get("assembly") and list(ws["names"]) == ["response"]:      # an assembly: name the response
        return summary["assembly"]["responses"][int(round(pose[0]))]
    labels = ws.get("labels") or {}         # a coordinate whose values are names (a per-axis requirement's axis)
    # round-off below 1e-9 of a display unit (mm, deg) shows as 0, not -1.115e-14 (issue 33)
    return ", ".join(f"{n} = {labels[n][int(round(v))]}" if n in labels else
                     f"{n} = {number(0.0 if abs(v * k) < 1e-9 else v * k)}" + (f" {u}" if u not in ("1", "") else "")
                     for n, v, k, u in zip(ws["names"], pose, ws["display_scale"], ws["display_units"]))


def yield_cell(y: dict) -> str:
    """Report cell of a yield check: worst-pose estimate with its interval at the stated
    confidence, then the verdict with the interval it is read from (Bonferroni level over the
    poses), so an interval above the requirement next to "undecided" is explained.

    Parameters
    ----------
    y : dict
        A Monte Carlo yield check: ``yield_estimate``, ``yield_lower``, ``yield_upper``,
        ``confidence``, ``model``, and when judged ``verdict``, ``verdict_interval``,
        ``yield_required``, ``verdict_level`` (yields and levels as fractions).

    Returns
    -------
    str
        The cell text (confidence levels in %).
    """
    pct = lambda c: f"{100 * c:.4g} %"
    cell = (f"{y['yield_estimate']:.5f} [{y['yield_lower']:.5f}, {y['yield_upper']:.5f}] at {pct(y['confidence'])} "
            f"({y['model']} model)")
    if "verdict" in y:
        lo, hi = y["verdict_interval"]
        cell += (f"; {y['verdict']} against {y['yield_required']:g}: worst pose [{lo:.5f}, {hi:.5f}] at "
                 f"{pct(y['verdict_level'])} per pose")
    return cell


def _certificate_cell(r: dict) -> str:
    c = r.get("certificate")
    if not c:
        return "none (no lower bound for this method)"
    if "gap" in c and "lower_bound" in c:
        return f"lower bound {float(c['lower_bound']):.6g}, gap {float(c['gap']):.1e}"
    return ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in c.items())


def top_table_rows(summary: dict) -> tuple[list[list], list[str]]:
    """Rows of the top table: one per method and, for NSGA-II, its cheapest feasible point and knee.

    Returns
    -------
    rows : list of list
        Method, cost, the largest error of each requirement component (display units), the
        yield (yield measure only), worst pose, status, verdict or certificate, and the Monte
        Carlo exceed rate.
    header : list of str
        The column titles.
    """
    comps = list(summary["requirement"])
    yield_measure = summary["measure"] == "yield"
    # the yield column is the error at the required yield (a quantile of the stated model, issue 33)
    kind = " at the required yield" if yield_measure else ""
    what = (lambda c: "response deviation") if summary.get("assembly") else (lambda c: f"{c} error")   # noqa: E731
    header = ["method", "cost"] + [f"max {what(c)}{kind} (requirement {_error_text(summary, c, summary['requirement'][c])})"
                                   for c in comps]
    header += ["worst pose (workspace coordinates)", "status", "verdict / certificate", "MC exceed rate"]
    if yield_measure:
        header.insert(2 + len(comps), "yield at the worst pose (first-order; required)")
    rows = []
    for m, r in summary["results"].items():
        comp0 = comps[0]
        row = [m, r["cost"]] + [_error_text(summary, c, _shown_error(r, c)) for c in comps]
        if yield_measure:
            mc = summary["monte_carlo"].get(m) or {}
            row.append((f"{r['yield_at_worst_pose']:.6f} (required {r['required_yield']:g})" if "yield_at_worst_pose" in r
                        else "–") + (f"; Monte Carlo: {yield_cell(mc['yield'])}" if "yield" in mc else ""))
        mc = summary["monte_carlo"].get(m)
        row += [f"#{r['worst_pose'][comp0]}: {pose_cells(summary, r['worst_pose_coordinates'][comp0])}",
                status_text(r), r.get("verdict") or _certificate_cell(r),
                f"{mc['max_exceed_rate']:.2%}" if mc else "not run"]
        rows.append(row)
    for key, label in (("cheapest_feasible", "NSGA-II cheapest feasible"), ("knee", "NSGA-II knee")):
        p = summary.get("nsga2", {}).get(key)
        if p is None:
            continue
        row = [label, p["cost"]] + [_error_text(summary, c, p.get(f"max_{c}_error")) for c in comps]
        if yield_measure:
            row.append("–")
        over = summary["nsga2"].get("cheapest_feasible_over_optimum") if key == "cheapest_feasible" else None
        where = (f"#{p['worst_pose'][comps[0]]}: {pose_cells(summary, p['worst_pose_coordinates'][comps[0]])}"
                 if "worst_pose" in p else "")
        row += [f"{where} (front row {p['row']})".strip(), "meets the requirement" if p["normalised_error"] <= 1 + 1e-9
                else f"misses the requirement (normalised error {p['normalised_error']:.4g})",
                "no certificate" + (f"; {100 * over:.3g} % above the certified optimum" if over is not None else ""), "not run"]
        rows.append(row)
    return rows, header


def _shown_error(r: dict, comp: str):
    """The error a method's row shows: the quantile at the required yield for a yield design, else the
    measure's largest error (SI)."""
    q = r.get("error_at_required_yield", {}).get(comp)
    return q["value"] if q else r.get(f"max_{comp}_error")


def terminal_rows(summary: dict) -> tuple[list[list[str]], list[str]]:
    """The terminal table of ``evotol run``: every method run, NSGA-II as its cheapest feasible
    point and its knee; errors in the study's display units.

    A process-selection study (a summary without ``display_units``) gets cost, normalised error
    and status instead, the NSGA-II points read from its ``pareto_front``.

    Returns
    -------
    rows : list of list of str
        One row per method and NSGA-II point, formatted.
    header : list of str
        The column titles (error columns name their display unit).
    """
    if "display_units" not in summary:    # a process-selection study (evotol/studyfile/processes.py): no lengths
        header = ["method", "cost", "max error / requirement", "status"]
        rows = [[m, f"{r['cost']:.6g}", number(r["normalised_error"]) if "normalised_error" in r else "",
                 "meets the requirement" if r.get("feasible") else "misses the requirement"]
                for m, r in (summary.get("results") or {}).items() if isinstance(r, dict) and "cost" in r]
        pf = summary.get("pareto_front") or {}
        if "cost" in pf and "normalised_error" in pf and len(pf["cost"]):
            cost, err = np.asarray(pf["cost"], dtype=float), np.asarray(pf["normalised_error"], dtype=float)
            ok = np.flatnonzero(err <= 1 + 1e-9)
            picks = ([("nsga2 cheapest feasible", int(ok[np.argmin(cost[ok])]))] if ok.size else []) + \
                [("nsga2 knee", ideal_point_knee(np.stack([cost, err], axis=1)))]
            rows += [[label, f"{cost[i]:.6g}", number(err[i]),
                      "meets the requirement" if err[i] <= 1 + 1e-9 else "misses the requirement"] for label, i in picks]
        return rows, header
    comps = list(summary.get("requirement", {}))
    u = _units(summary)
    header = ["method", "cost"] + [f"{c} ({u.unit_for(summary['error_units'][c])})" for c in comps] + ["MC exceed", "status"]
    rows = []
    for m, r in (summary.get("results") or {}).items():
        mc = (summary.get("monte_carlo") or {}).get(m)
        rows.append([m, f"{r['cost']:.6g}"] + [number(u.convert(_shown_error(r, c), summary["error_units"][c]))
                                               for c in comps]
                    + [f"{mc['max_exceed_rate']:.2%}" if mc else "", status_text(r)])
    for key, label in (("cheapest_feasible", "nsga2 cheapest feasible"), ("knee", "nsga2 knee")):
        p = summary.get("nsga2", {}).get(key)
        if p is not None:
            rows.append([label, f"{p['cost']:.6g}"] + [number(u.convert(p[f"max_{c}_error"], summary["error_units"][c]))
                                                       for c in comps]
                        + ["", "meets the requirement" if p["normalised_error"] <= 1 + 1e-9
                           else f"misses the requirement ({p['normalised_error']:.4g} × requirement)"])
    if "pareto_front" in summary and "cheapest_feasible" not in summary.get("nsga2", {}):
        rows.append(["nsga2", "", *[""] * len(comps), "", "no front member meets the requirement"])
    return rows, header


def status_text(r: dict) -> str:
    """A method's status, naming the model of each verdict when the first-order model and the
    nonlinear check (``r["nonlinear_check"]``, :func:`evotol.summaries.drawing.nonlinear_check`)
    disagree: ``"meets the requirement (first-order model); 0.070 µm over (position) on the
    nonlinear model"``.

    Parameters
    ----------
    r : dict
        One method's entry of a study summary's ``results``.

    Returns
    -------
    str
        The status (unchanged when the models agree or no nonlinear check was made).
    """
    status, check = r.get("status", ""), r.get("nonlinear_check")
    if not check or check["meets_nonlinear"] == bool(r.get("feasible")):
        return status
    return f"{status} (first-order model); " + verdict_text({"meets": bool(r.get("feasible")), **check}).split("; ", 1)[1]


def _dist_text(d: dict) -> str:
    """``normal (t = 3σ)``, ``uniform, mean shift 0.2·t``: a distribution as the page names it."""
    return (d["kind"] + (f" (t = {d['sigma_k']:g}σ)" if "normal" in d["kind"] else "")
            + (f", mean shift {d['mean_shift']:g}·t" if d["mean_shift"] else ""))


def model_line(summary: dict) -> str:
    """One line stating the model the Monte Carlo sampled (issue 34: every verdict on one stated
    model). The ``rss`` measure takes every tolerance as 3σ of a normal about its zone's centre;
    a study file whose sources' distributions are not stated samples that model
    (:func:`evotol.studyfile.run.verification_model`), else the sources' own distributions, and
    the line says when the two models differ.

    Parameters
    ----------
    summary : dict
        A user study's JSON summary (``sources`` with their ``distribution``; each Monte Carlo's
        ``sampled_distribution`` when it sampled one distribution for every source).

    Returns
    -------
    str
        The line, or ``""`` when no Monte Carlo ran.
    """
    checks = [c for c in (summary.get("monte_carlo") or {}).values() if c]
    if not checks:
        return ""
    rss = summary.get("measure") == "rss"
    one = next((c["sampled_distribution"] for c in checks if "sampled_distribution" in c), None)
    if one is not None:
        same = one["kind"] == "normal" and one["sigma_k"] == 3 and not one["mean_shift"]
        text = (f"The Monte Carlo sampled every source from one model: {_dist_text(one)} about its zone's centre"
                + (", σ = half-width / 3" if same else ""))
        if rss and same:
            return text + " -- the RSS verdict's own model (no source distribution was stated in the study file)."
        return text + (" -- the RSS verdict takes t = 3σ, so the two can differ." if rss else ".")
    own = sorted({_dist_text(d) for d in (s.get("distribution") for s in summary["sources"]) if d is not None})
    other = [t for t in own if t != "normal (t = 3σ)"]
    if rss and other:
        return ("Two models: the RSS verdict takes every tolerance as 3σ of a normal; the Monte Carlo exceed rate samples "
                f"the sources' own distributions ({', '.join(other)}), as the study file states them, so the two can differ. "
                "Leave the distributions unstated (or give distribution = \"normal\") to check the RSS verdict on its own model.")
    return ("The Monte Carlo sampled each source's own distribution (" + ", ".join(own) + ")"
            + (": the RSS verdict's own model." if rss else "."))


def _error_map_figure(summary: dict, method: str, comp: str):
    """Heatmaps of ``comp`` error over the workspace slices (display units), allocation poses
    projected as dots, the worst allocation pose as a star."""
    slices = summary["figures"]["error_maps"][method]
    ws = summary["workspace"]
    scale = dict(zip(ws["names"], ws["display_scale"]))
    dunit = dict(zip(ws["names"], ws["display_units"]))
    u = _units(summary)
    eu = summary["error_units"][comp]
    k = u.factor(eu)
    titles = [", ".join(f"{n} = {number(v * scale[n])} {dunit[n]}" for n, v in s["fixed"].items()) or "whole workspace"
              for s in slices]
    fig = make_subplots(rows=1, cols=len(slices), subplot_titles=titles, horizontal_spacing=0.08)
    zmax = np.nanmax([np.nanmax(np.asarray(s["values"][comp], dtype=float)) for s in slices]) * k
    zmin = np.nanmin([np.nanmin(np.asarray(s["values"][comp], dtype=float)) for s in slices]) * k
    lim = summary["requirement"][comp] * k
    poses = np.asarray(summary["poses"], dtype=float)
    r = summary["results"][method]
    wp = np.asarray(r["worst_pose_coordinates"][comp])
    for i, s in enumerate(slices, start=1):
        xn, yn = s["x_name"], s["y_name"]
        x = np.asarray(s["x"]) * scale[xn]
        z = np.asarray(s["values"][comp], dtype=float) * k
        if yn is None:
            fig.add_scatter(x=x, y=z, mode="lines", name=f"{comp} error", row=1, col=i, showlegend=i == 1)
            continue
        y = np.asarray(s["y"]) * scale[yn]
        fig.add_heatmap(x=x, y=y, z=z, zmin=zmin, zmax=max(zmax, lim), colorscale="Viridis", row=1, col=i,
                        colorbar={"title": u.unit_for(eu)}, showscale=i == len(slices),
                        hovertemplate=f"{xn} %{{x:.4g}}<br>{yn} %{{y:.4g}}<br>error %{{z:.4g}} {u.unit_for(eu)}<extra></extra>")
        fig.add_contour(x=x, y=y, z=z, contours={"start": lim, "end": lim, "coloring": "none", "showlabels": True},
                        line={"color": "white", "width": 2, "dash": "dash"}, showscale=False, hoverinfo="skip",
                        row=1, col=i, name="requirement", showlegend=False)
        ix, iy = ws["names"].index(xn), ws["names"].index(yn)
        fixed = [(ws["names"].index(n), v) for n, v in s["fixed"].items()]
        on = np.all([np.isclose(poses[:, k], v, rtol=1e-9, atol=1e-12) for k, v in fixed], axis=0) if fixed \
            else np.ones(len(poses), dtype=bool)
        # allocation poses on this slice as dots; none there (a Latin hypercube, a 6-D box): their projection
        pick, label, colour = (on, "allocation poses on this slice", "white") if on.any() else \
            (np.ones(len(poses), dtype=bool), "allocation poses (projected)", "#bbbbbb")
        fig.add_scatter(x=poses[pick, ix] * scale[xn], y=poses[pick, iy] * scale[yn], mode="markers", row=1, col=i,
                        marker={"color": colour, "size": 5, "line": {"color": "black", "width": 1}},
                        name=label, showlegend=bool(i == 1 or not on.any()))
        if all(np.isclose(wp[k], v, rtol=1e-9, atol=1e-12) for k, v in fixed):
            fig.add_scatter(x=[wp[ix] * scale[xn]], y=[wp[iy] * scale[yn]], mode="markers", row=1, col=i,
                            marker={"symbol": "star", "color": "red", "size": 14, "line": {"color": "black", "width": 1}},
                            name="worst allocation pose")
        fig.update_xaxes(title_text=f"{xn} ({dunit[xn]})", row=1, col=i)
        fig.update_yaxes(title_text=f"{yn} ({dunit[yn]})", row=1, col=i)
    fig.update_layout(title=f"{method}: {comp} error over the workspace ({u.unit_for(eu)}; dashed: the requirement)",
                      height=420, legend={"orientation": "h", "y": -0.25})
    return fig


def map_caption(summary: dict, method: str, comp: str) -> str:
    """The largest error on the map against the largest over the allocation poses.

    Says when the map finds a larger error between the allocation poses, and how many map poses
    are out of reach.

    Parameters
    ----------
    method : str
        A method with an error map (``summary["figures"]["error_maps"]``).
    comp : str
        The error component (a key of ``summary["requirement"]``).

    Returns
    -------
    str
        The caption (errors and pose in display units).
    """
    slices = summary["figures"]["error_maps"][method]
    best = (-np.inf, None, None)
    for s in slices:
        z = np.asarray(s["values"][comp], dtype=float)
        if np.all(np.isnan(z)):
            continue
        idx = np.unravel_index(np.nanargmax(z), z.shape)
        if z[idx] > best[0]:
            best = (float(z[idx]), s, idx)
    v, s, idx = best
    r = summary["results"][method]
    unreachable = sum(sl["unreachable"] for sl in slices)
    if s is None:
        return "No pose of the map is reachable."
    names = summary["workspace"]["names"]
    pose = [s["fixed"].get(n) for n in names]
    pose[names.index(s["x_name"])] = s["x"][idx[-1]]
    if s["y_name"] is not None:
        pose[names.index(s["y_name"])] = s["y"][idx[0]]
    text = (f"Largest {comp} error on the map {_error_text(summary, comp, v)} at {pose_cells(summary, pose)}; "
            f"over the allocation poses {_error_text(summary, comp, r[f'max_{comp}_error'])}.")
    if v > r[f"max_{comp}_error"] * (1 + 1e-6):
        text += (" The map finds a larger error between the allocation poses: the allocation holds the requirement "
                 "only at its poses; add poses there (or [poses] refine = true) to hold it over the whole workspace.")
    if unreachable:
        text += f" {unreachable} map poses are out of reach and left blank."
    return text


def _front_figure(summary: dict):
    pf = summary["pareto_front"]
    fig = go.Figure(go.Scatter(x=pf["normalised_error"], y=pf["cost"], mode="markers", name="NSGA-II front",
                               marker={"color": "#1f77b4", "size": 6}))
    for key, (label, sym) in {"cheapest_feasible": ("NSGA-II cheapest feasible", "circle-open"),
                              "knee": ("NSGA-II knee", "hexagon-open")}.items():
        p = summary.get("nsga2", {}).get(key)
        if p is not None:
            fig.add_scatter(x=[p["normalised_error"]], y=[p["cost"]], mode="markers", name=label,
                            marker={"symbol": sym, "size": 16, "color": "#1f77b4", "line": {"width": 2}})
    # the certified optimum drawn last, on top of a GA that lands next to it
    for m, r in sorted(summary["results"].items(), key=lambda kv: kv[0] == "optimum"):
        sym, col = MARKS.get(m, ("x", "#7f7f7f"))
        label = "certified optimum" if m == "optimum" and (r.get("verdict") or "").startswith("certified optimal") else m
        fig.add_scatter(x=[r["normalised_error"]], y=[r["cost"]], mode="markers", name=label,
                        marker={"symbol": sym, "color": col, "size": 18 if m == "optimum" else 14,
                                "line": {"color": "black", "width": 1}})
    fig.add_vline(x=1.0, line_dash="dash", line_color="grey", annotation_text="requirement")
    fig.update_layout(title="Cost vs. normalised error (max error / requirement): NSGA-II front and the methods "
                            "(log scales)", xaxis_title="max error / requirement", yaxis_title="cost", height=480,
                      xaxis_type="log", yaxis_type="log")
    return fig


def _convergence_figure(method: str, history: dict):
    fig = go.Figure()
    fig.add_scatter(x=history["generation"], y=history["best_fitness"], name="best")
    fig.add_scatter(x=history["generation"], y=history["mean_fitness"], name="mean")
    fig.update_layout(title=f"{method} convergence", xaxis_title="generation", yaxis_title="fitness", yaxis_type="log",
                      height=360)
    return fig


def _linearisation_rows(summary: dict) -> list[list]:
    rows = []
    for m, mc in summary["monte_carlo"].items():
        e = mc.get("linearisation_error")
        rows.append([m, mc["n_samples"], f"{mc['max_exceed_rate']:.2%}",
                     f"{mc['max_exceed_rate_nonlinear']:.2%}" if "max_exceed_rate_nonlinear" in mc else "–",
                     "–" if e is None else f"{100 * e:.3g} %",
                     mc.get("linearisation_verdict") or "no nonlinear model: first-order only"])
    return rows


def render_user_study(summary: dict) -> Report:
    """The HTML report of ``evotol run`` from its JSON summary (see the module docstring).

    Returns
    -------
    Report
        The page, not yet written (:meth:`evotol.reporting.html.Report.write`).
    """
    u = _units(summary)
    req = ", ".join(f"{c} ≤ {_error_text(summary, c, v)}" for c, v in summary["requirement"].items())
    if summary.get("assembly"):
        a = summary["assembly"]
        req = ("every response within its limit: " + ", ".join(f"{n} within ±{number(v)} of its nominal"
                                                               for n, v in zip(a["responses"], a["limits"]))
               + " (the response's unit); errors are shown as deviation / limit")
    rep = Report(f"evotol study: {summary['name']}",
                 f"{summary['robot']}, {summary['n_poses']} poses, measure {summary['measure']}, requirement {req}; "
                 f"lengths in {u.length}, angles in {u.angle} (the JSON holds SI values)")
    for line in summary.get("warnings", []):
        rep.text(f"Warning: {line}", note=True)
    for line in summary.get("notes", []):
        rep.text(line, note=True)
    rep.heading("Results")
    rows, header = top_table_rows(summary)
    rep.table(rows, header, table_id="top")
    line = model_line(summary)
    if line:
        rep.text(line, note=True)
    rep.heading("Allocated tolerances")
    rows, header = tolerance_rows(summary)
    rep.table(rows, header, table_id="tolerances")
    rep.text("Each cell is the zone as the drawing states it: deviations from the nominal, ±t when symmetric, "
             "+upper / −lower otherwise (the CSV's lower and upper deviation columns).")
    if nominal_line(summary):
        rep.text(nominal_line(summary))
    for m, d in (summary.get("drawing") or {}).items():
        rep.text(f"Drawing, {m}: {drawing_check_text(d)}.", note=not d["meets"])
    for line in floor_lines(summary):       # feasible at the shop's floors: which sources sit there (issue 41)
        rep.text(line + ".")
    if "calibration" in summary:    # a calibrated robot: uncalibrated vs calibrated (docs/calibration.md)
        calibration_section(rep, summary)
    if "iso9283" in summary:        # ISO 9283 AP and RP (docs/iso9283.md)
        iso9283_section(rep, summary)
    if summary.get("exports"):
        rep.text("The tolerance table as a drawing carries it: " + ", ".join(
            f'<a href="{html.escape(p)}">{html.escape(p)}</a>' for p in summary["exports"].values()) + ".", raw=True)
    if summary.get("callouts"):          # drawing callouts on joint seats (issue 35, docs/callouts.md)
        callout_sections(rep, summary)
    if "pareto_front" in summary:
        rep.heading("NSGA-II front")
        over = summary.get("nsga2", {}).get("cheapest_feasible_over_optimum")
        if over is not None:
            rep.text(f"The front's cheapest feasible point costs {100 * over:.3g} % more than the certified optimum: "
                     "NSGA-II approximates the front, the optimum is proven.", note=True)
        rep.figure(_front_figure(summary), div_id="front")
    for m, r in summary["results"].items():
        rep.heading(f"{m}")
        for comp in summary["requirement"]:
            if m in summary["figures"].get("error_maps", {}):
                rep.figure(_error_map_figure(summary, m, comp), div_id=f"map-{m}-{comp}")
                rep.text(map_caption(summary, m, comp))
            c = r["contributions"].get(comp)
            if c:
                src = {s["name"]: s for s in summary["sources"]}
                rows = [[s, src[s]["group"] + (" (no effect on the requirement)" if src[s].get("no_effect") else ""),
                         f"{zone_text(tolerance_zone(src[s], r['tolerances'][s]), u, src[s]['unit'], src[s]['dim'])} "
                         f"{u.unit_for(src[s]['unit'])}", number(pc)] for s, pc in zip(c["source"], c["percent"])]
                rep.text(f"Contributions to the {comp} error at the worst pose "
                         f"(#{r['worst_pose'][comp]}: {pose_cells(summary, r['worst_pose_coordinates'][comp])}):")
                rep.table(rows, ["source", "group", "tolerance", "share (%)"])
        if r.get("history"):
            rep.figure(_convergence_figure(m, r["history"]), div_id=f"conv-{m}")
        if r.get("diagnostics", {}).get("solver_message_meaning"):
            rep.text("Note: " + r["diagnostics"]["solver_message_meaning"] + ".")
    if summary["monte_carlo"]:
        rep.heading("Monte Carlo and the linearisation check")
        rep.table(_linearisation_rows(summary), ["method", "samples", "exceed rate (first-order)",
                                                 "exceed rate (nonlinear)", "linearisation error", "verdict"])
    joints_section(rep, summary)           # the posture used at every pose (issue 33)
    explorer_section(rep, summary)
    return rep

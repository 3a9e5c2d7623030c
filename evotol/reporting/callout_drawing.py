"""The drawing table of a study with callouts, and exact zones against independent boxes (issue 35).

Read from a user study's JSON summary alone (``summary["callouts"]``, written by
:func:`evotol.studyfile.callouts.callout_summary`): per part (the link that carries the
seat), each feature's callout as an engineer copies it onto the drawing -- symbol and value in
µm, feature length and where the zone sits on the axis, datums -- with its share of the cost and
of the worst error; and the side-by-side of the certified optimum under exact zones and under the
independent-box rule. The HTML page, the terminal and the CSV/XLSX export all show these tables.
"""
from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from evotol._runtime.atomic_files import atomic_path

from evotol.errors import ValidationError
from evotol.reporting.drawing import drawing_check_text
from evotol.reporting.export import chosen_method
from evotol.reporting.callout_frame import AXIAL_TILT, drawn_value, frame_text, micrometres, with_svg_symbols
from evotol.reporting.html import table_html


def _method(summary: dict, method: str | None) -> str:
    return method or chosen_method(summary)


def _blank_nan(rows: list) -> list:
    """Rows with NaN cells (a missing value in a numeric column) as empty cells."""
    return [["" if isinstance(v, float) and math.isnan(v) else v for v in r] for r in rows]


def drawing_table(summary: dict, method: str | None = None) -> pd.DataFrame:
    """Per part, each callout of one method's allocation (default: the one the drawing carries).

    Parameters
    ----------
    summary : dict
        A user study's JSON summary with ``callouts`` (SI values).
    method : str, optional
        A method of ``summary["results"]``.

    Returns
    -------
    pandas.DataFrame
        Columns: part, feature, callout (the feature control frame ``⌖ | ⌀3.0 µm | A | B``, the
        face as a profile of a surface ``⌓ | 62.3 µm | A | B``: the design rounded inward to the
        drawing precision and re-checked, :func:`drawn_value`), value (µm), length (mm), zone
        (placement along the axis), datums, datum features (what the letters name on the part),
        cost share (%), contribution (%) to the first
        constrained component's error at the worst pose (the members' shares summed).

    Raises
    ------
    ValidationError
        A summary without callouts, or an unknown method.
    """
    if not summary.get("callouts"):
        raise ValidationError("callouts", None, "a study summary with drawing callouts ([[robot.callouts]])")
    method = _method(summary, method)
    results = summary.get("results") or {}
    if method not in results:
        raise ValidationError("method", method, f"one of {sorted(results)}")
    r = results[method]
    comp = next(iter(summary["requirement"]))
    con = r["contributions"].get(comp, {})
    share = dict(zip(con.get("source", []), con.get("percent", [])))
    costs = r.get("source_costs", {})
    total = sum(costs.values())
    rows = []
    for f in summary["callouts"]["features"]:
        t, um = drawn_value(summary, method, f["members"][0])
        lo, hi = f["ends"]
        axis = "(" + ", ".join(f"{v:g}" for v in f["axis"]) + ")"
        if f["kind"] == "axial":
            feature = f"shoulder face of {f['joint']}"
            zone = (f"±{micrometres(t / 2, None if um is None else um + 1)} µm along the axis {axis}, at the joint origin "
                    f"(profile of the face's surface; {AXIAL_TILT})")
            frame = frame_text(summary, method, f)
        else:
            feature = f"{'guide' if f.get('joint_type') == 'prismatic' else 'bore'} axis of {f['joint']}"
            zone = f"from {lo * 1e3:g} to {hi * 1e3:g} mm along the axis {axis} from the joint origin"
            frame = frame_text(summary, method, f)
        contrib = [share[m] for m in f["members"] if share.get(m) is not None]
        rows.append({"part": f["part"], "feature": feature, "callout": frame,
                     "value (µm)": t * 1e6 if um is None else round(t * 1e6, um), "length (mm)": f["length"] * 1e3,
                     "zone": zone, "datums": f["datums"], "datum features": f.get("datum_features", ""),
                     "cost share (%)": 100 * sum(costs.get(m, 0.0) for m in f["members"]) / total if total else 0.0,
                     f"contribution to the {comp} error at the worst pose (%)": sum(contrib) if contrib else None})
    return pd.DataFrame(rows).sort_values("part", kind="stable").reset_index(drop=True)


def comparison_table(summary: dict) -> pd.DataFrame:
    """Exact zones against independent boxes, callout by callout and in total.

    Parameters
    ----------
    summary : dict
        A user study's JSON summary with ``callouts.comparison``.

    Returns
    -------
    pandas.DataFrame
        Columns: item, exact zones, independent boxes (callout values in µm, then the cost, the
        worst error each design holds under its own zones -- linear and nonlinear -- and the box
        design's under the exact zones, in µm), one row each.

    Raises
    ------
    ValidationError
        A summary without the comparison.
    """
    cmp_ = (summary.get("callouts") or {}).get("comparison")
    if not cmp_:
        raise ValidationError("callouts.comparison", None, "a study summary with the exact-zones comparison")
    ex, bx = cmp_["exact"], cmp_["boxes"]
    rows = [(f"{n} (µm)", ex["values"][n] * 1e6, bx["values"][n] * 1e6) for n in cmp_["callouts"]]
    rows.append(("cost", ex["cost"], bx["cost"]))
    for c, w in ex["worst"].items():
        k, u = (1e6, "µm") if c == "position" else (1e6, "µrad")
        rows.append((f"worst {c} error, own zones, linear ({u})", w["linear"] * k, bx["worst"][c]["linear"] * k))
        rows.append((f"worst {c} error, own zones, nonlinear ({u})", w["nonlinear"] * k, bx["worst"][c]["nonlinear"] * k))
        rows.append((f"worst {c} error under the exact zones, nonlinear ({u})", w["nonlinear"] * k,
                     bx["worst_in_exact_zones"][c]["nonlinear"] * k))
    rows.append(("saving of the exact zones (% of the box rule's cost)", 100 * cmp_["saving"], None))
    return pd.DataFrame(rows, columns=["item", "exact zones", "independent boxes"])


def terminal_lines(summary: dict) -> list[str]:
    """The drawing table and the saving as lines for the terminal.

    Parameters
    ----------
    summary : dict
        A user study's JSON summary (no lines without callouts).

    Returns
    -------
    list of str
        Text lines (no trailing newline).
    """
    if not summary.get("callouts") or not summary.get("results"):
        return []
    d = drawing_table(summary)
    out = [f"[evotol] drawing callouts ({_method(summary, None)}):"]
    for _, r in d.iterrows():
        out.append(f"  {r['part']:<22s} {r['feature']:<36s} {r['callout']:<24s} L {r['length (mm)']:g} mm  "
                   f"cost {r['cost share (%)']:.3g} %")
    for part, text in dict(zip(d["part"], d["datum features"])).items():
        if text:
            out.append(f"  datums on {part}: {text}")
    check = (summary.get("drawing") or {}).get(_method(summary, None))
    if check:
        out.append(f"  as drawn: {drawing_check_text(check)}")
    cmp_ = summary["callouts"].get("comparison")
    if cmp_:
        out.append(f"  exact zones cost {cmp_['exact']['cost']:.6g}, independent boxes {cmp_['boxes']['cost']:.6g}: "
                   f"{100 * cmp_['saving']:.3g} % saved")
    return out


def callout_sections(rep, summary: dict) -> None:
    """Add the drawing table and the exact-zones comparison to a study's page.

    Parameters
    ----------
    rep : evotol.reporting.html.Report
        The page being built.
    summary : dict
        A user study's JSON summary with callouts.
    """
    d = drawing_table(summary)
    rep.heading("Drawing callouts")
    rep.text(f"Per part, each seat's callouts of the {_method(summary, None)} allocation, as they go on the drawing: "
             "the zone's value in µm, the feature length and where the zone sits on the joint axis (from the joint's "
             "origin, the datum frame of docs/callouts.md), the datums, and each callout's share of the cost and of the "
             "error at the worst pose.")
    # a feature control frame reads as one row of compartments: never wrapped inside "⌖ | ⌀10.0 µm | A | B"
    # (issue 41, seen in headless Chromium: the narrow column broke it after the ⌀)
    col = list(d.columns).index("callout") + 1
    rep.html(f"<style>#callouts td:nth-child({col}) {{ white-space: nowrap; }}</style>"
             + with_svg_symbols(table_html(_blank_nan(d.values.tolist()), list(d.columns), table_id="callouts")))
    check = (summary.get("drawing") or {}).get(_method(summary, None))
    if check:
        rep.text(f"These values, as drawn: {drawing_check_text(check)}.", note=not (check["meets"] and
                                                                                    check.get("meets_nonlinear", True)))
    if summary["callouts"].get("comparison"):
        c = comparison_table(summary)
        cmp_ = summary["callouts"]["comparison"]
        rep.heading("Exact zones against independent boxes")
        rep.text(f"The certified optimum with each callout's exact zone costs {cmp_['exact']['cost']:.6g}; with the "
                 f"independent-box rule (translations ±t/2 and tilts ±t/L as independent intervals) "
                 f"{cmp_['boxes']['cost']:.6g}: the exact zones save {100 * cmp_['saving']:.3g} %. The boxes contain "
                 "the zone, so the box design also holds under the exact zones, with the margin shown in the last "
                 "error row; the nonlinear rows push each pose's worst-case vertex through the nonlinear model.")
        rep.table(_blank_nan(c.values.tolist()), list(c.columns), table_id="zones")



def write_callout_exports(summary: dict, csv_path, xlsx_path=None) -> list[Path]:
    """Write the drawing table to a CSV file and add it, with the exact-zones comparison, as the
    sheets ``drawing`` and ``exact zones vs boxes`` of the study's workbook.

    Parameters
    ----------
    summary : dict
        A user study's JSON summary with callouts.
    csv_path : str or Path
        The drawing CSV (the chosen method's callouts).
    xlsx_path : str or Path, optional
        An existing workbook (:func:`evotol.reporting.export.write_tolerance_table`) to add the
        sheets to; None: none.

    Returns
    -------
    list of Path
        The files written or extended.

    Raises
    ------
    ValidationError
        A summary without callouts.
    """
    csv_path = Path(csv_path)
    csv_path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(csv_path) as tmp:
        drawing_table(summary).to_csv(tmp, index=False, encoding="utf-8")
    out = [csv_path]
    if xlsx_path is not None:
        with atomic_path(xlsx_path, keep_existing=True) as tmp, \
                pd.ExcelWriter(tmp, engine="openpyxl", mode="a", if_sheet_exists="replace") as xl:
            drawing_table(summary).to_excel(xl, sheet_name="drawing", index=False)
            if summary["callouts"].get("comparison"):
                comparison_table(summary).to_excel(xl, sheet_name="exact zones vs boxes", index=False)
        out.append(Path(xlsx_path))
    return out

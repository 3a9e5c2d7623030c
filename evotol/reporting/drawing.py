"""A tolerance as a drawing states it: the zone's text in display units (``±t`` or
``+upper / −lower``), one function for the page and the terminal (issue 34: a one-sided zone
``+0 / −288.6 µm`` was shown as ``± 288.6``); the page's and the terminal's tolerance tables.

The parameters several definitions of this module share are described once, here.

Parameters
----------
summary : dict
    A user study's JSON summary (with ``display_units``).
"""
from __future__ import annotations

import math

from evotol.summaries.drawing import clean, tolerance_zone
from evotol.units.display import DisplayUnits, number


def zone_text(zone: dict, u: DisplayUnits, si_unit: str, dim: int = 1) -> str:
    """A tolerance zone as a drawing writes it, in display units: ``±144.3`` when it is symmetric
    about the nominal, else the two deviations ``+0 / −288.6`` (never a doubled or halved ±).

    Parameters
    ----------
    zone : dict
        ``lower`` and ``upper`` deviations from the nominal (SI, m or rad), as
        :func:`evotol.summaries.user_study.tolerance_zone` gives them.
    u : DisplayUnits
        The study's display units.
    si_unit : str
        The source's SI unit (``"m"`` or ``"rad"``).
    dim : {1, 2, 3}
        The source's dimension: a disc or ball zone (2, 3) is stated by its radius, ``r ≤ 1.554``.

    Returns
    -------
    str
        The zone's text (4 significant digits, no unit).
    """
    lo, hi = float(u.convert(zone["lower"], si_unit)), float(u.convert(zone["upper"], si_unit))
    if dim > 1:         # a disc or ball: the error vector's length within r (no sign, no axis)
        return f"r ≤ {number(hi)}"
    if abs(lo + hi) <= 1e-9 * max(abs(lo), abs(hi)):
        return f"±{number(hi)}"

    def signed(v):
        return "0" if v == 0 else f"+{number(v)}" if v > 0 else f"−{number(-v)}"
    return f"{signed(hi)} / {signed(lo)}"


def drawing_check_text(check: dict) -> str:
    """The re-check of a design rounded to the drawing precision, in one line (page and workbook).

    Parameters
    ----------
    check : dict
        One method's entry of a study summary's ``drawing`` block
        (:func:`evotol.summaries.drawing.rounded_design`).

    Returns
    -------
    str
        E.g. ``"rounded inward to 0.1 µm: normalised error 0.998, meets the requirement (cost 135.7)"``.
    """
    steps = ", ".join(f"{p:.{max(0, -math.floor(math.log10(p) + 1e-9))}f} {u}" for u, p in check["precision"].items()) \
        or "no rounding"
    if check["vanished"]:
        return f"rounded to {steps}: the zones of {', '.join(check['vanished'])} vanish; state a finer drawing precision"
    return (f"rounded inward to {steps} (fixed sources outward): the drawn zones give normalised error "
            f"{check['normalised_error']:.6g}, {verdict_text(check)} (cost {check['cost']:.6g})")


def _excess(v: float, comp: str) -> str:
    """An error beyond the requirement in µm or µrad (``0.07 µm``)."""
    return f"{number(v * 1e6, 2)} {'µm' if comp == 'position' else 'µrad'}"


def verdict_text(check: dict) -> str:
    """A design's verdict naming the model of each verdict when the first-order and the nonlinear
    model disagree (``"meets the requirement (first-order model); 0.07 µm over on the nonlinear
    model"``), one verdict when they agree or when no nonlinear check was made.

    Parameters
    ----------
    check : dict
        ``meets`` (first-order model) and, when the nonlinear check was made, ``meets_nonlinear``
        and ``over_nonlinear`` (component -> excess, SI), as
        :func:`evotol.summaries.drawing.rounded_design` gives them.

    Returns
    -------
    str
        The verdict.
    """
    first = "meets the requirement" if check["meets"] else "misses the requirement"
    if "meets_nonlinear" not in check:
        return first
    if check["meets_nonlinear"] == check["meets"]:
        return f"{first} (first-order and nonlinear models)"
    if check["meets"]:
        over = ", ".join(f"{_excess(v, c)} over ({c})" for c, v in check["over_nonlinear"].items() if v > 0)
        return f"{first} (first-order model); {over} on the nonlinear model"
    return f"{first} (first-order model); meets it on the nonlinear model (worst-case vertex)"


def tolerance_rows(summary: dict) -> tuple[list[list], list[str]]:
    """Source × method table of the tolerance zones in display units (``±t`` or ``+upper / −lower``).

    Returns
    -------
    rows : list of list
        Per source: name, group, display unit, nominal (display unit, blank where the model
        does not know it: :mod:`evotol.summaries.nominals`), then the zone of each method and of the NSGA-II
        cheapest feasible point and knee (:func:`zone_text` of
        :func:`evotol.summaries.user_study.tolerance_zone`: the deviations the CSV and the
        workbook give).
    header : list of str
        The column titles.
    """
    u = DisplayUnits(**summary["display_units"])
    methods = list(summary["results"])
    extra = {k: summary["nsga2"][k]["tolerances"] for k in ("cheapest_feasible", "knee") if k in summary.get("nsga2", {})}
    columns = [summary["results"][m]["tolerances"] for m in methods] + list(extra.values())
    rows = []
    for s in summary["sources"]:
        mark = " (no effect on the requirement)" if s.get("no_effect") else ""     # issue 33
        rows.append([s["name"], s["group"] + mark, u.unit_for(s["unit"]),
                     f"{clean(u.convert(s['nominal'], s['unit']), 10):.10g}" if "nominal" in s else ""]
                    + [zone_text(tolerance_zone(s, t[s["name"]]), u, s["unit"], s.get("dim", 1)) for t in columns])
    header = ["source", "group", "unit", "nominal"] + methods + [f"NSGA-II {k.replace('_', ' ')}" for k in extra]
    return rows, header


def cost_share(r: dict, name: str) -> float | None:
    """One source's share of a method's cost, in percent: ``100·cost_j / Σ cost`` (the CSV's
    ``cost share (%)`` column, :func:`evotol.reporting.export.tolerance_table`).

    Parameters
    ----------
    r : dict
        One method's entry of a study summary's ``results`` (its ``source_costs``, cost units).
    name : str
        The source.

    Returns
    -------
    float or None
        The share (%); 0 when the design costs nothing, None when ``r`` has no ``source_costs``.
    """
    costs = r.get("source_costs")
    if costs is None:
        return None
    total = sum(costs.values())
    return 100.0 * costs.get(name, 0.0) / total if total else 0.0


def terminal_tolerance_rows(summary: dict) -> tuple[list[list[str]], list[str]]:
    """The tolerance table of ``evotol run`` in the terminal: the page's cells (:func:`tolerance_rows`,
    one zone function for every view), one line per source, each method's zone followed by the
    source's cost share (issue 34: one truth per page).

    Returns
    -------
    rows : list of list of str
        Per source: name, display unit, nominal (blank where unknown), then per method
        ``zone (share %)`` (the NSGA-II points: the zone alone).
    header : list of str
        The column titles.
    """
    rows, header = tolerance_rows(summary)
    results = [summary["results"][m] for m in summary["results"]]
    out = []
    for row in rows:
        cells = []
        for i, cell in enumerate(row[4:]):
            share = cost_share(results[i], row[0]) if i < len(results) else None
            cells.append(cell if share is None else f"{cell} ({share:.1f} %)")
        no_effect = row[1].endswith("(no effect on the requirement)")      # issue 33: marked in every table
        out.append([row[0] + (" (no effect)" if no_effect else ""), row[2], row[3], *cells])
    return out, ["source", "unit", "nominal", *header[4:]]


def nominal_line(summary: dict) -> str:
    """One line under the page's tolerance table saying what its nominal column holds, from the
    sources' ``nominal_note`` (:func:`evotol.summaries.nominals.nominal_notes`).

    Parameters
    ----------
    summary : dict
        A user study's JSON summary (``sources``).

    Returns
    -------
    str
        E.g. ``"Nominal: the 30 placement errors are 0 = the URDF joint origin, the zone is the
        deviation about it; no single nominal for shoulder_pan_joint, ... (varies with the pose);
        the CSV's 'nominal is' column says it per source."``; ``""`` when no source has a note.
    """
    notes = {s["name"]: s["nominal_note"] for s in summary.get("sources", []) if s.get("nominal_note")}
    if not notes:
        return ""
    placed = [n for n, t in notes.items() if t.startswith("0 = the ")]
    entries = [n for n, t in notes.items() if " in the description (" in t]
    varying = [n for n, t in notes.items() if "varies with the pose" in t]
    origin = "URDF joint origin" if any("URDF" in notes[n] for n in placed) else "description's placement"
    parts = ([f"the {len(placed)} placement errors are 0 = the {origin}, the zone is the deviation about it"] if placed else []) \
        + ([f"{', '.join(entries)}: the entry's value in the description"] if entries else []) \
        + ([f"no single nominal for {', '.join(varying)} (varies with the pose)"] if varying else [])
    return "Nominal: " + "; ".join(parts or ["as the model gives it"]) + "; the CSV's 'nominal is' column says it per source."

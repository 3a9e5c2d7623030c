"""The allocated tolerance table as a drawing carries it: CSV and an Excel workbook.

Per source: name, group, nominal (where the model knows it), the tolerance ± in display units
(and the limit deviations for an asymmetric interval [offset − minus·t, offset + plus·t]),
the process (where the study selected one), the source's share of the cost and its contribution
to the error at the worst pose. Read from a user study's JSON summary
(:mod:`evotol.summaries.user_study`) alone, so ``evotol export NAME.json`` writes the same table as
``evotol run``. The workbook is written by pandas through openpyxl: one sheet per method and an
``about`` sheet (study, units, requirement, status of each method).
"""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from evotol._runtime.atomic_files import atomic_path

from evotol.units.display import DisplayUnits
from evotol.errors import ValidationError
from evotol.reporting.callout_frame import frame_text
from evotol.reporting.drawing import drawing_check_text
from evotol.summaries.drawing import clean, tolerance_zone

FORMATS = ("csv", "xlsx")


def chosen_method(summary: dict) -> str:
    """The allocation a drawing would carry: the certified optimum when it meets the requirement,
    else the cheapest method that meets it, else the first method run.

    Budget methods (whose result has a ``budget`` entry) are not candidates for the cheapest.

    Parameters
    ----------
    summary : dict
        A user study's JSON summary (:mod:`evotol.summaries.user_study`) with its ``results`` by method.

    Returns
    -------
    str
        The method's name, a key of ``summary["results"]``.

    Raises
    ------
    ValidationError
        The summary has no results.
    """
    results = summary.get("results") or {}
    if not results:
        raise ValidationError("results", None, "a study summary with at least one allocation")
    opt = results.get("optimum")
    if opt is not None and opt.get("feasible"):
        return "optimum"
    ok = [m for m, r in results.items() if r.get("feasible") and "budget" not in r]
    return min(ok, key=lambda m: results[m]["cost"]) if ok else next(iter(results))


def tolerance_table(summary: dict, method: str | None = None) -> pd.DataFrame:
    """The drawing table of one method's allocation (default :func:`chosen_method`).

    Parameters
    ----------
    summary : dict
        A user study's JSON summary (``evotol run``).
    method : str, optional
        A method of ``summary["results"]``.

    Returns
    -------
    pandas.DataFrame
        Columns: source, group, unit (display), nominal (display unit, where the model knows
        it), nominal is (what the nominal is: the description's entry, the URDF joint origin
        the deviation is about), ± tolerance, lower deviation, upper deviation (display units; the deviations from the nominal that the interval allows),
        process, cost share (%), contribution (%) to the first constrained component's error at
        the worst pose, effect (``"none"`` for a source that cannot move the constrained errors,
        summary ``sources[].no_effect``; its cost is in the cost share, and stated in the
        ``about`` sheet by :func:`no_effect_cost`), callout and datums: a drawing callout is one
        row (named by the callout, its feature control frame with the drawn value and its datums,
        :func:`evotol.reporting.callout_frame.frame_text`) instead of one per zone member.

    Raises
    ------
    ValidationError
        An unknown method, or a summary without results.
    """
    method = method or chosen_method(summary)
    results = summary.get("results") or {}
    if method not in results:
        raise ValidationError("method", method, f"one of {sorted(results)}")
    r = results[method]
    u = DisplayUnits(**summary["display_units"])
    comp = next(iter(summary["requirement"]))
    share = dict(zip(r["contributions"].get(comp, {}).get("source", []), r["contributions"].get(comp, {}).get("percent", [])))
    costs = r.get("source_costs", {})
    total = sum(costs.values())
    processes = r.get("processes", {})
    drawn = (summary.get("drawing") or {}).get(method, {}).get("zones", {})
    callout_of = {m: f for f in (summary.get("callouts") or {}).get("features", []) for m in f["members"]}
    rows = []
    for s in summary["sources"]:
        n, k = s["name"], u.factor(s["unit"])
        f = callout_of.get(n)
        if f is not None:       # a drawing callout: one row with its frame and datums, not one per zone member
            if n == f["members"][0]:
                rows.append(_callout_row(summary, method, f, costs, total, share, comp))
            continue
        z = tolerance_zone(s, r["tolerances"][n])          # the page's zone (one function)
        dz = drawn.get(n, {})
        pc = share.get(n)
        rows.append({"source": n, "group": s["group"], "unit": u.unit_for(s["unit"]),
                     "nominal": clean(s["nominal"] * k) if "nominal" in s else None,
                     "nominal is": s.get("nominal_note", ""),
                     "± tolerance": clean(z["half_width"] * k),
                     "lower deviation": clean(z["lower"] * k),
                     "upper deviation": clean(z["upper"] * k),
                     "drawing lower deviation": dz.get("drawing_lower"),
                     "drawing upper deviation": dz.get("drawing_upper"),
                     "process": processes.get(n, "fixed (bought in)" if s.get("fixed") else ""),
                     "cost share (%)": clean(100 * costs.get(n, 0.0) / total) if total else 0.0,
                     f"contribution to the {comp} error at the worst pose (%)": None if pc is None else clean(pc),
                     "effect": "none" if s.get("no_effect") else "", "callout": "", "datums": ""})   # issue 33
    return pd.DataFrame(rows)


def _callout_row(summary: dict, method: str, f: dict, costs: dict, total: float, share: dict, comp: str) -> dict:
    """The tolerance table's row of one drawing callout: its frame (``⌖ | ⌀3.0 µm | A | B``, the drawn
    value) and datums in place of the ± of its zone members (issue 41: a ⌀ is not a ± on a coordinate)."""
    members = f["members"]
    pc = [share[m] for m in members if share.get(m) is not None]
    datums = f["datums"] + (f" ({f['datum_features']})" if f.get("datum_features") else "")
    return {"source": f["name"], "group": "drawing callout", "unit": "µm", "nominal": None,
            "nominal is": f"the joint's nominal placement in {f['part']}", "± tolerance": None,
            "lower deviation": None, "upper deviation": None, "drawing lower deviation": None,
            "drawing upper deviation": None, "process": "",
            "cost share (%)": clean(100 * sum(costs.get(m, 0.0) for m in members) / total) if total else 0.0,
            f"contribution to the {comp} error at the worst pose (%)": clean(sum(pc)) if pc else None,
            "effect": "", "callout": frame_text(summary, method, f), "datums": datums}


def no_effect_cost(summary: dict, method: str) -> tuple[list[str], float, float]:
    """What the sources with no effect on the requirement cost in one method's allocation (issue 33:
    such a source is marked, and its cost stated).

    Parameters
    ----------
    summary : dict
        A user study's JSON summary (:mod:`evotol.summaries.user_study`); a source row with
        ``no_effect = True`` cannot move any constrained error component.
    method : str
        A method of ``summary["results"]``.

    Returns
    -------
    names : list of str
        The sources with no effect, in source order (empty when none).
    cost : float
        Their summed cost in that allocation (cost models' unit; ``source_costs``).
    total : float
        The allocation's summed source cost.
    """
    costs = summary["results"][method].get("source_costs", {})
    names = [s["name"] for s in summary["sources"] if s.get("no_effect")]
    return names, float(sum(costs.get(n, 0.0) for n in names)), float(sum(costs.values()))


def about_table(summary: dict) -> pd.DataFrame:
    """The ``about`` sheet: study, units, requirement and each method's cost and status.

    Parameters
    ----------
    summary : dict
        A user study's JSON summary (:mod:`evotol.summaries.user_study`).

    Returns
    -------
    pandas.DataFrame
        Two columns, ``item`` and ``value`` (text; requirement in display units; per method, the
        sources with no effect on the requirement and their cost, :func:`no_effect_cost`).
    """
    u = DisplayUnits(**summary["display_units"])
    rows = [("study", summary["name"]), ("robot", summary["robot"]), ("measure", summary["measure"]),
            ("length unit", u.length), ("angle unit", u.angle)]
    rows += [(f"requirement: {c}", u.format(v, summary["error_units"][c])) for c, v in summary["requirement"].items()]
    rows += [(f"method {m}", f"cost {r['cost']:.6g}; {r.get('status', '')}") for m, r in summary["results"].items()]
    rows.append(("values", "± tolerance is the half-width (minus + plus)/2·t; deviations are from the nominal"))
    rows += [(f"drawing, method {m}", drawing_check_text(d)) for m, d in (summary.get("drawing") or {}).items()]
    for m in summary["results"]:
        names, cost, total = no_effect_cost(summary, m)
        if names:
            rows.append((f"no effect on the requirement, method {m}",
                         f"{', '.join(names)} (effect 'none'): together cost {cost:.6g} of the allocation's {total:.6g}"
                         + (f" ({100 * cost / total:.3g} %)" if total else "")
                         + "; they cannot move the constrained errors"))
    return pd.DataFrame(rows, columns=["item", "value"])


def write_tolerance_table(summary: dict, path, method: str | None = None) -> Path:
    """Write the drawing table: ``.csv`` (one method, default :func:`chosen_method`) or ``.xlsx``
    (the ``about`` sheet, then one sheet per method, the chosen one first; ``method`` given: that one).

    Parameters
    ----------
    summary : dict
        A user study's JSON summary (``evotol run``).
    path : str or Path
        Ends in ``.csv`` or ``.xlsx``; missing parent folders are created.
    method : str, optional
        A method of ``summary["results"]``; the only one written when given.

    Returns
    -------
    Path
        ``path``, written.

    Raises
    ------
    ValidationError
        Another file ending, an unknown method, or a summary without results.
    """
    path = Path(path)
    kind = path.suffix.lower().lstrip(".")
    if kind not in FORMATS:
        raise ValidationError("export file", str(path), f"a file name ending in one of {['.' + f for f in FORMATS]}")
    path.parent.mkdir(parents=True, exist_ok=True)
    if kind == "csv":
        with atomic_path(path) as tmp:
            tolerance_table(summary, method).to_csv(tmp, index=False, encoding="utf-8")
        return path
    first = method or chosen_method(summary)
    methods = [first] if method else [first] + [m for m in summary["results"] if m != first]
    with atomic_path(path) as tmp, pd.ExcelWriter(tmp, engine="openpyxl") as xl:
        about_table(summary).to_excel(xl, sheet_name="about", index=False)
        for m in methods:
            tolerance_table(summary, m).to_excel(xl, sheet_name=m[:31], index=False)
    return path

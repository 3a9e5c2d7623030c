"""The page of a stack analysis, drawn from its JSON summary alone (values SI, shown in the
stack's display length unit at a stated drawing precision).

The summary is what :func:`stack_summary` builds from a :class:`evotol.measures.stack_analysis.StackAnalysis`:
``stack`` (the analysis, SI: m), ``display`` (``unit``: ``"mm"``, ``"µm"`` or ``"in"``;
``precision``: the drawing precision in that unit), optional ``published`` (figures of a source,
in the display unit, compared with the computed ones) and the ``units`` block.
"""
from __future__ import annotations

import math

from evotol.reporting.html import Report
from evotol.units.display import LENGTHS

#: default drawing precision per display unit (the unit's smallest digit a drawing gives)
DEFAULT_PRECISION = {"in": 1e-4, "mm": 1e-3, "µm": 0.1}


def length_text(value_si, unit: str, precision: float) -> str:
    """A length (SI, m) in ``unit``, rounded to ``precision`` and written with its decimals (no
    float noise: 0.15699999 in -> ``0.1570``).

    Parameters
    ----------
    value_si : float or None
        The length in m.
    unit : str
        Display unit, a key of :data:`evotol.units.display.LENGTHS`.
    precision : float
        Drawing precision in ``unit`` (e.g. 0.0001 in).

    Returns
    -------
    str
        The rounded number (``"–"`` for None), without the unit.
    """
    if value_si is None:
        return "–"
    v = value_si / LENGTHS[unit]
    decimals = max(0, -int(math.floor(math.log10(precision) + 1e-9)))
    q = round(v / precision) * precision
    return f"{q + 0.0:.{decimals}f}"        # + 0.0: no "-0.0000"


def deviation_text(value_si, unit: str, precision: float) -> str:
    """A signed deviation as a drawing writes it: ``+0.0100``, ``-0.0040``, ``0`` (no sign on zero).

    Parameters
    ----------
    value_si : float
        The deviation in m.
    unit : str
        Display unit, a key of :data:`evotol.units.display.LENGTHS`.
    precision : float
        Drawing precision in ``unit``.

    Returns
    -------
    str
        The rounded deviation with its sign, without the unit.
    """
    text = length_text(value_si, unit, precision)
    if float(text) == 0:
        return "0"
    return text if text.startswith("-") else "+" + text


def fraction_text(p, interval=None) -> str:
    """A fraction of assemblies as ``6.31e-07 (0.631 ppm)``, with its interval when sampled.

    Parameters
    ----------
    p : float or None
        The fraction (1).
    interval : sequence of float, optional
        Its Clopper–Pearson interval.

    Returns
    -------
    str
        The text; ``"no limit"`` for None.
    """
    if p is None:
        return "no limit"
    text = f"{p:.3g} ({1e6 * p:.3g} ppm)"
    if interval is not None:
        text += f", interval [{interval[0]:.3g}, {interval[1]:.3g}]"
    return text


UNIT_WORDS = {"in": "inch", "mm": "mm", "µm": "µm"}


def _formatters(summary: dict):
    disp = summary["display"]
    unit, prec = disp["unit"], disp["precision"]
    return unit, (lambda v: length_text(v, unit, prec)), (lambda v: deviation_text(v, unit, prec))


def limits_verdict(lim, spec, rtol: float = 1e-9) -> str:
    """Pass or fail of a pair of gap limits against the specification (a limit on the spec passes).

    Parameters
    ----------
    lim : (float, float)
        The figure's lower and upper limit of the gap (SI).
    spec : (float or None, float or None)
        LSL and USL (SI; None: no such limit).
    rtol : float
        Relative slack of "on the limit" (round-off), of the specification's width or the limit.

    Returns
    -------
    str
        ``"pass"``, ``"fail: below LSL by x"`` / ``"above USL by x"`` (SI, formatted by the
        caller's unit elsewhere: here in the figure's own numbers), or ``""`` without limits.
    """
    lsl, usl = spec
    if lsl is None and usl is None:
        return ""
    scale = abs(usl - lsl) if lsl is not None and usl is not None else max(abs(v) for v in (lsl, usl) if v is not None)
    slack = rtol * max(scale, 1e-300)
    lo, hi = lim
    bad = []
    if lsl is not None and lo < lsl - slack:
        bad.append("below LSL")
    if usl is not None and hi > usl + slack:
        bad.append("above USL")
    return "fail: " + " and ".join(bad) if bad else "pass"


def gap_rows(summary: dict) -> tuple[list[list[str]], list[str]]:
    """The gap's figures by method: nominal, mean, worst case, RSS, MRSS and the specification,
    each stacking model with its verdict against the specification.

    Parameters
    ----------
    summary : dict
        A stack summary (module docstring).

    Returns
    -------
    rows : list of list of str
        Per figure: its name, its value (the nominal and the mean gap), its lower and upper limit,
        its half-width (upper − lower)/2 (the specification's: (USL − LSL)/2, display unit, rounded
        to the drawing precision), pass/fail against LSL and USL, and its convention.
    header : list of str
        The column titles.
    """
    st = summary["stack"]
    unit, f, _ = _formatters(summary)
    spec = tuple(st["limits"])

    def limits(label, lim, note, judge=True):
        lo, hi = lim
        both = lo is not None and hi is not None
        return [label, "", f(lo), f(hi), f(0.5 * (hi - lo)) if both else "–",
                limits_verdict(lim, spec) if judge else "", note]

    mr = st["mrss"]
    rows = [["nominal gap (Σ a·nominal)", f(st["nominal"]), "", "", "", "", ""],
            ["mean gap (Σ a·zone centre)", f(st["mean"]), "", "", "", "",
             "one-sided and unequal tolerances enter by their zone centre"],
            limits("worst case", st["worst_case"]["limits"], "Σ |a|·h: the extreme corners of the tolerance box"),
            limits("RSS", st["rss"]["limits"], st["rss"]["convention"]),
            limits("modified RSS", mr["limits"], f"C_f = {mr['factor']:.4f} (n = {mr['n']}): {mr['convention']}"),
            limits("specification (LSL, USL)", st["limits"], "the gap's limits; half-width (USL − LSL)/2", judge=False)]
    return rows, ["", f"gap ({unit})", f"lower limit ({unit})", f"upper limit ({unit})",
                  f"half-width (upper − lower)/2 ({unit})", "against LSL/USL", "convention"]


def capability_rows(summary: dict) -> tuple[list[list[str]], list[str]]:
    """Per statistical model: its statement, σ of the gap, mean shift, Cp, Cpk and the fractions
    below LSL and above USL (with how they were obtained).

    Parameters
    ----------
    summary : dict
        A stack summary (module docstring).

    Returns
    -------
    rows : list of list of str
        One row per model.
    header : list of str
        The column titles.
    """
    unit, f, _ = _formatters(summary)
    rows = []
    for name, m in summary["stack"]["models"].items():
        o = m.get("outside", {})
        num = lambda v: "–" if v is None else f"{v:.3f}"      # noqa: E731
        how = o.get("method", "no limits")
        if how == "Monte Carlo":
            how += f" ({o['n_samples']} samples, Clopper–Pearson {100 * o['confidence']:g} %)"
        rows.append([name, m["model"], f(m["sigma"]), f(m["shift"]), num(m["cp"]), num(m["cpk"]),
                     fraction_text(o.get("below"), o.get("below_interval")),
                     fraction_text(o.get("above"), o.get("above_interval")), how])
    return rows, ["model", "statement", f"σ of the gap ({unit})", f"mean shift δ ({unit})", "Cp", "Cpk",
                  "below LSL", "above USL", "how"]


def terminal_rows(summary: dict) -> tuple[list[list[str]], list[str]]:
    """The terminal table of ``evotol run`` for a stack: the gap's figures, then Cp, Cpk and the
    fractions outside per model -- the same cells as the page.

    Parameters
    ----------
    summary : dict
        A stack summary (module docstring).

    Returns
    -------
    rows : list of list of str
        Figure rows (:func:`gap_rows` without the convention), model rows and, for an
        allocation, each method's cost, allocated worst-case limits and verdict (pass/fail and
        the method's status).
    header : list of str
        The column titles.
    """
    rows, header = gap_rows(summary)
    out = [r[:6] for r in rows]
    cap, _ = capability_rows(summary)
    out += [[f"{r[0]}: Cp {r[4]}, Cpk {r[5]}", "", f"below {r[6]}", f"above {r[7]}", "", ""] for r in cap]
    _, f, _ = _formatters(summary)
    spec = tuple(summary["stack"]["limits"])
    for m, r in (summary.get("allocation") or {}).get("methods", {}).items():    # the page's allocation figures
        lo, hi = r["stack"]["worst_case"]["limits"]
        out.append([f"{m}: cost {r['cost']:.6g}, worst case of the allocated design", "", f(lo), f(hi), "",
                    f"{limits_verdict((lo, hi), spec)} ({r['status']})"])
    return out, header[:6]


def allocation_rows(summary: dict) -> tuple[list[list[str]], list[str]]:
    """The allocations of a stack side by side: each dimension's drawn zone per method, then
    cost, the allocated design's worst-case and RSS limits, Cpk and the drawn design's re-check.

    Parameters
    ----------
    summary : dict
        A stack summary with an ``allocation`` block (:func:`evotol.summaries.stack.allocation_summary`).

    Returns
    -------
    rows : list of list of str
        Per dimension its zone ``+upper / lower`` (display unit, rounded inward to the drawing
        precision) and cost share; then the figures.
    header : list of str
        The column titles.
    """
    unit, f, dev = _formatters(summary)
    al = summary["allocation"]["methods"]
    names = [d["name"] for d in summary["stack"]["dimensions"]]
    rows = []
    for n in names:
        row = [n]
        for r in al.values():
            z = r["drawing"]["zones"][n]
            k = LENGTHS[unit]                      # the drawn zone is in the display unit; dev() takes metres
            zone = f"{dev(z['drawing_upper'] * k)} / {dev(z['drawing_lower'] * k)}"
            row.append(f"{zone} ({r['cost_share_percent'][n]:.1f} %)" if n in r["tolerances"] else f"{zone} (kept)")
        rows.append(row)
    first_model = lambda r: next(iter(r["stack"]["models"].values()), {})      # noqa: E731
    rows += [["cost"] + [f"{r['cost']:.6g}" for r in al.values()],
             ["status"] + [r["status"] for r in al.values()],
             ["worst case (lower, upper)"] + [f"{f(r['stack']['worst_case']['limits'][0])}, {f(r['stack']['worst_case']['limits'][1])}"
                                              for r in al.values()],
             ["RSS (lower, upper)"] + [f"{f(r['stack']['rss']['limits'][0])}, {f(r['stack']['rss']['limits'][1])}"
                                       for r in al.values()],
             ["Cpk (first model)"] + ["–" if first_model(r).get("cpk") is None else f"{first_model(r)['cpk']:.3f}"
                                      for r in al.values()],
             ["drawn zones re-checked"] + [("meets" if r["drawing"]["meets"] else "misses")
                                           + (f" ({r['drawing']['normalised_error']:.4f} of the limit)"
                                              if r["drawing"]["normalised_error"] is not None else " (a zone vanishes)")
                                           for r in al.values()]]
    return rows, ["dimension"] + [f"{m}: zone ({unit}), cost share" for m in al]


def allocation_section(rep: Report, summary: dict) -> None:
    """Add the allocation of a stack to its page (:func:`allocation_rows` and the measure stated).

    Parameters
    ----------
    rep : Report
        The page.
    summary : dict
        A stack summary with an ``allocation`` block.
    """
    measure = summary["allocation"]["measure"]
    rep.heading("Allocated tolerances")
    rep.text(f"Half-widths chosen by cost so that the gap stays within [LSL, USL] under the {measure} measure "
             + ("(the worst-case limits inside the specification)" if measure == "worst_case" else
                "(every tolerance 3σ of a normal: the RSS limits inside the specification)")
             + "; each zone keeps its drawing's shape (a one-sided tolerance stays one-sided); zones rounded inward to "
               "the drawing precision and the drawn design re-checked.")
    rep.table(*allocation_rows(summary), table_id="allocation")


def render_stack(summary: dict, title: str | None = None) -> Report:
    """The stack-analysis page (dimensions, gap limits by method, capability and fractions
    outside, contributions to each side, the conventions).

    Parameters
    ----------
    summary : dict
        A stack summary (module docstring).
    title : str, optional
        Page title (default ``"evotol stack analysis: NAME"``).

    Returns
    -------
    Report
        The page, not yet written.
    """
    st = summary["stack"]
    unit, f, dev = _formatters(summary)
    prec = summary["display"]["precision"]
    lsl, usl = st["limits"]
    rep = Report(title or f"evotol stack analysis: {summary['name']}",
                 f"gap '{st['gap']}', lengths in {UNIT_WORDS.get(unit, unit)} rounded to the drawing precision "
                 f"{prec:g} {unit}; limits LSL {f(lsl)}, USL {f(usl)}; the JSON holds SI values (m)")
    for line in summary.get("notes", []):
        rep.text(line, note=True)
    rep.heading("Dimensions")
    rows = [[d["name"], f"{d['sensitivity']:+g}", f(d["nominal"]), dev(d["upper"]), dev(d["lower"]),
             f(d["nominal"] + 0.5 * (d["upper"] + d["lower"])), f(0.5 * (d["upper"] - d["lower"])), d["distribution"],
             d.get("same_part_as", "")] for d in st["dimensions"]]
    rep.table(rows, ["dimension", "direction / sensitivity", f"nominal ({unit})", f"upper deviation ({unit})",
                     f"lower deviation ({unit})", f"zone centre ({unit})", f"± half-width ({unit})", "distribution",
                     "same drawing as"], table_id="dimensions")
    rep.heading(f"Gap '{st['gap']}'")
    rep.table(*gap_rows(summary), table_id="gap")
    if st["models"]:
        rep.heading("Capability and assemblies outside the limits")
        rep.table(*capability_rows(summary), table_id="capability")
    rep.heading("Contributions to each side")
    first = next(iter(st["models"]), None)
    share = st["models"][first]["variance_share"] if first else None
    rows = [[c["name"], f(c["below"]), f"{c['below_percent'] + 0.0:.1f}", f(c["above"]), f"{c['above_percent'] + 0.0:.1f}"]
            + ([f"{100 * share[i]:.1f}"] if share else []) for i, c in enumerate(st["contributions"])]
    rep.table(rows, ["dimension", f"worst case below the nominal gap ({unit})", "share of the lower side (%)",
                     f"worst case above the nominal gap ({unit})", "share of the upper side (%)"]
              + ([f"share of the gap variance, model {first} (%)"] if share else []), table_id="contributions")
    if summary.get("allocation"):
        allocation_section(rep, summary)
    pub = summary.get("published")
    if pub:
        rep.heading("Beside the published figures")
        digits = lambda text: len(text.split(".")[1]) if "." in text else 0     # noqa: E731 -- the published digits
        rows = [[p["figure"], p["published"], length_text(p["computed"], unit, 10.0 ** -digits(p["published"])),
                 p.get("note", "")] for p in pub["figures"]]
        rep.table(rows, ["figure", f"published ({unit})", f"evotol ({unit})", "note"], table_id="published")
        rep.text("Source: " + pub["source"], note=True)
    rep.text("Conventions: a dimension lies in [nominal + lower, nominal + upper] (signed deviations as on the "
             "drawing); the gap is Σ a·dimension; a one-sided or unequal tolerance enters every method through its "
             "zone centre and half-width h. Worst case: mean ± Σ|a|h. RSS: mean ± sqrt(Σ(a h)²), every tolerance ±3σ. "
             "Modified RSS: the RSS times C_f. Cp = (USL − LSL)/(6σ), Cpk = min(USL − μ − δ, μ − δ − LSL)/(3σ) of the "
             "gap under each stated model; fractions outside are exact for normal dimensions, Monte Carlo with a "
             "Clopper–Pearson interval otherwise.")
    return rep

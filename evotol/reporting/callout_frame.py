"""A drawing callout as a drawing states it (issue 41): its feature control frame in text
(``⌖ | ⌀3.0 µm | A | B``; the shoulder face as a profile of a surface ``⌓ | 62.3 µm | A | B``,
ISO 1101 / ASME Y14.5), its value as the design drawn and re-checked (the allocation rounded inward
to the drawing step, :func:`evotol.summaries.drawing.rounded_design`), and its symbols as inline SVG
so that an offline page shows them in any browser without a font that has them. The drawing table
(:mod:`evotol.reporting.callout_drawing`) and the tolerance CSV (:mod:`evotol.reporting.export`)
both take the frame from here.

The parameters several definitions of this module share are described once, here.

Parameters
----------
summary : dict
    A user study's JSON summary with callouts.
method : str
    A method of ``summary["results"]``.
"""
from __future__ import annotations

import math

from evotol.units.display import DisplayUnits

#: the geometric characteristic of each callout kind in a feature control frame (ISO 1101 / ASME
#: Y14.5): position of an axis, perpendicularity, parallelism, and the shoulder face as a profile of a surface
FRAME_SYMBOLS = {"position": "⌖", "perpendicularity": "⊥", "parallelism": "∥", "axial": "⌓"}
#: what the face's zone leaves out, stated wherever it is drawn
AXIAL_TILT = "its tilt inside the zone is not modelled: only its shift along the axis moves the seat"


_SVG = ('<svg class="gdt" viewBox="0 0 16 16" width="1em" height="1em" role="img" aria-label="{name}" '
        'style="vertical-align:-0.15em" fill="none" stroke="currentColor" stroke-width="1.4"><title>{name}</title>'
        '{shape}</svg>')
#: each drawing symbol as inline SVG: no font has to carry ⌖ ⌀ ⌓ (an offline page in any browser)
SVG_SYMBOLS = {
    "⌖": _SVG.format(name="position", shape='<circle cx="8" cy="8" r="4.5"/><path d="M1 8H15M8 1V15"/>'),
    "⌀": _SVG.format(name="diameter", shape='<circle cx="8" cy="8" r="5"/><path d="M3 13L13 3"/>'),
    "⌓": _SVG.format(name="profile of a surface", shape='<path d="M2 12A6 6 0 0 1 14 12Z"/>'),
    "⊥": _SVG.format(name="perpendicularity", shape='<path d="M8 2V13M2 13H14"/>'),
    "∥": _SVG.format(name="parallelism", shape='<path d="M4 14L8 2M9 14L13 2"/>'),
}


def with_svg_symbols(fragment: str) -> str:
    """An HTML fragment with every drawing symbol (:data:`SVG_SYMBOLS`) drawn as inline SVG.

    Parameters
    ----------
    fragment : str
        HTML whose text holds the symbols (a table of :func:`evotol.reporting.html.table_html`).

    Returns
    -------
    str
        The fragment with each symbol replaced by its ``<svg>`` (its name as the title).
    """
    for glyph, svg in SVG_SYMBOLS.items():
        fragment = fragment.replace(glyph, svg)
    return fragment


def frame_text(summary: dict, method: str, feature: dict) -> str:
    """A callout's feature control frame as text, with its drawn value (``⌖ | ⌀3.0 µm | A | B``).

    Parameters
    ----------
    feature : dict
        One entry of ``summary["callouts"]["features"]``.

    Returns
    -------
    str
        The frame: characteristic, zone (⌀ for an axis), datum letters.
    """
    t, um = drawn_value(summary, method, feature["members"][0])
    letters = " | ".join(d.strip() for d in feature["datums"].split("|"))
    dia = "" if feature["kind"] == "axial" else "⌀"
    return f"{FRAME_SYMBOLS[feature['kind']]} | {dia}{micrometres(t, um)} µm | {letters}"


def micrometres(t: float, decimals: int | None) -> str:
    """A zone ``t`` (m) in µm at the drawing's resolution (``decimals``), or with 3 significant
    digits when the summary has no drawn value.

    Parameters
    ----------
    t : float
        The zone (m).
    decimals : int or None
        Decimals of the drawing step in µm (:func:`drawn_value`).

    Returns
    -------
    str
        The number in µm, without unit.
    """
    return f"{t * 1e6:.{decimals}f}" if decimals is not None else f"{t * 1e6:.3g}"


def drawn_value(summary: dict, method: str, member: str) -> tuple[float, int | None]:
    """A callout's value as the drawing carries it: the allocation rounded inward to the drawing
    precision and re-checked (``summary["drawing"][method]``, :func:`evotol.summaries.drawing.rounded_design`)
    -- the one rounding the page, the terminal, the CSV and the workbook show.

    Parameters
    ----------
    member : str
        A member source of the callout.

    Returns
    -------
    value : float
        The drawn value (m): the ⌀ or the face's width.
    decimals : int or None
        Decimals of the drawing step in µm; None when the summary has no drawn value (the
        allocation's own value is returned, unrounded).
    """
    check = (summary.get("drawing") or {}).get(method) or {}
    z = check.get("zones", {}).get(member, {})
    if "drawing_value" not in z:
        return float(summary["results"][method]["tolerances"][member]), None
    u = DisplayUnits(**summary["display_units"])
    src = next(s for s in summary["sources"] if s["name"] == member)
    k = u.factor(src["unit"])
    step_um = check["precision"][u.unit_for(src["unit"])] / k * 1e6
    return z["drawing_value"] / k, max(0, -int(math.floor(math.log10(step_um) + 1e-9)))



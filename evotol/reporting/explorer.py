"""The what-if explorer of a user study's page: move the tolerances, read cost and errors at once.

One log-scale slider and one input (display units) per tolerance variable, within its bounds;
buttons that reset every tolerance to a method's allocation. On every change the page recomputes,
offline and with no server, the cost, the worst-case and RSS errors at every allocation pose, the
worst pose and the contributions there (``explorer.js``, inlined into the page with its data from
:func:`evotol.summaries.explorer_data.explorer_data`). The page's worst case is the maximum over a fixed
sample of directions; the section states how tight that is against the certified value (the
measured shortfall and the guaranteed bound 1 − cos δ).
"""
from __future__ import annotations

import json
from pathlib import Path

from evotol.units.display import DisplayUnits, number

ASSET = Path(__file__).with_name("explorer.js")


def page_config(summary: dict) -> dict:
    """What the script reads: the explorer data, unit factors and labels, the workspace and poses.

    Parameters
    ----------
    summary : dict
        A user study's JSON summary (:mod:`evotol.summaries.user_study`), read through its
        ``display_units``, ``sources``, ``error_units``, ``explorer``, ``workspace`` and
        ``poses`` entries.

    Returns
    -------
    dict
        JSON-ready: ``explorer`` (:func:`evotol.summaries.explorer_data.explorer_data`), ``error_units``,
        ``factors`` (SI-to-display factor per unit name), ``labels`` (display label per unit
        name, empty for ``"1"``), ``workspace`` and ``poses``.
    """
    u = DisplayUnits(**summary["display_units"])
    units = {s["unit"] for s in summary["sources"]} | set(summary["error_units"].values()) | {"m", "rad"}
    return {"explorer": summary["explorer"], "error_units": summary["error_units"],
            "factors": {k: u.factor(k) for k in units}, "labels": {k: ("" if k == "1" else u.unit_for(k)) for k in units},
            "workspace": summary["workspace"], "poses": summary["poses"]}


def tightness_text(tightness: dict) -> str:
    """The sentence saying how far the page's sampled worst case can be and was below the certified one.

    Parameters
    ----------
    tightness : dict
        Per error component, the dict of :func:`evotol.summaries.explorer_data.sample_tightness`
        (``n_directions``, ``covering_angle`` in rad, ``guaranteed``, ``measured``,
        ``measured_any_pose`` as fractions, ``n_designs``).

    Returns
    -------
    str
        One clause per component (fractions shown in %), joined by ``"; "``.
    """
    parts = []
    for comp, t in tightness.items():
        if t["guaranteed"] == 0:
            parts.append(f"{comp}: exact (the error has one direction, {t['n_directions']} sampled)")
            continue
        parts.append(f"{comp}: {t['n_directions']} directions, covering angle {t['covering_angle']:.3g} rad, so the page "
                     f"is never more than {100 * t['guaranteed']:.3g} % below the certified worst case; measured on "
                     f"{t['n_designs']} tolerance vectors (the methods' allocations and random vectors within the bounds) "
                     f"it was at most {100 * t['measured']:.3g} % below at the largest error "
                     f"({100 * t['measured_any_pose']:.3g} % at any pose)")
    return "; ".join(parts)


def explorer_section(rep, summary: dict) -> None:
    """Add the explorer (or the reason it is omitted) to ``rep``.

    Nothing is added when the summary has no explorer data.

    Parameters
    ----------
    rep : Report
        The page being built (:class:`evotol.reporting.html.Report`), appended to in place.
    summary : dict
        A user study's JSON summary (:mod:`evotol.summaries.user_study`) with its ``explorer`` entry
        (or ``{"omitted": reason}``).
    """
    data = summary.get("explorer")
    if not data:
        return
    rep.heading("What if: move the tolerances")
    if "omitted" in data:
        rep.text(f"No explorer for this study: {data['omitted']}.", note=True)
        return
    locked = [s for s in data["sources"] if s["locked"] is not None]
    u = DisplayUnits(**summary["display_units"])
    rep.text("Each tolerance on a log scale within its bounds, or typed in; the buttons reset every tolerance to a "
             "method's allocation. The page recomputes the cost, the worst-case and RSS errors at every allocation pose "
             "(first-order model), the worst pose and the contributions, with no server. The worst case is the largest "
             "value over a fixed sample of directions, a lower bound of the certified value: "
             + tightness_text(data["tightness"]) + "."
             + (" Not adjustable (locked or fixed): " + ", ".join(
                 f"{s['name']} ±{number(u.convert(s['locked'], s['unit']))} {u.unit_for(s['unit'])}" for s in locked) + "."
                if locked else ""))
    payload = json.dumps(page_config(summary), separators=(",", ":")).replace("</", "<\\/")
    rep.html(f'<div id="explorer"></div><script type="application/json" id="explorer-data">{payload}</script>'
             f"<script>{ASSET.read_text(encoding='utf-8')}</script>")

"""Interactive parallel-coordinate reports of design studies (Deng 2012, Figs. VII.1-VII.16).

The section :func:`add_parcoords` adds to a report page: the parallel-coordinate plot
(:mod:`~evotol.reporting.parcoords_plot`; axes :mod:`~evotol.reporting.parcoords_axes`, lines
and the drawn sample :mod:`~evotol.reporting.parcoords_lines`) and the filtering that runs in
the page (``parcoords.js``, inlined with its data).

Named presets (:class:`evotol.design.filtering.Preset`, the filters of the thesis's figures) become
buttons that set the axes' constraint ranges; the page then shows how many entries are kept,
the range each axis keeps and a table of the kept entries. Brushing an axis by hand updates the
same read-outs. A static table beside it lists every preset's count computed in Python by
:meth:`evotol.design.filtering.DesignStudy.filter` (the numbers the page must reproduce;
:func:`preset_table_rows`).

The report reads results; it computes no physics (STYLE.md).
"""
from __future__ import annotations

import base64
import html
import json
from pathlib import Path
from typing import Sequence

import numpy as np
import pandas as pd

from evotol.design import ENTRY, SOURCE
from evotol.errors import ValidationError
from evotol.design.filtering import DesignStudy, Preset
from evotol.reporting.parcoords_axes import Axis, default_axes, format_tick
from evotol.reporting.parcoords_axes import log_ticks  # noqa: F401  (re-exported)
from evotol.reporting.parcoords_lines import DEFAULT_MAX_DRAWN, GPU_MAX_DRAWN, GRID, drawn_lines, parcoords_frame
from evotol.reporting.parcoords_lines import KNEE, PARETO  # noqa: F401  (re-exported)
from evotol.reporting.parcoords_plot import parcoords_figure

#: the script of the filtering page; ``%(payload)s`` is replaced by the section's data (JSON)
ASSET = Path(__file__).with_name("parcoords.js")


def _b64(a: np.ndarray) -> dict:
    """A numpy array as plotly.js's typed-array JSON form ``{dtype, bdata}``."""
    a = np.ascontiguousarray(a)
    code = {np.dtype("float64"): "f8", np.dtype("float32"): "f4", np.dtype("int32"): "i4"}[a.dtype]
    return {"dtype": code, "bdata": base64.b64encode(a.tobytes()).decode("ascii")}


def _preset_ranges(preset: Preset, axes: Sequence[Axis], offset: int, frame: pd.DataFrame) -> list:
    """Constraint ranges ``[dim index, low, high]`` (plotted units) that a preset sets."""
    idx = {a.column: i for i, a in enumerate(axes)}
    out = []
    for col, (lo, hi) in preset.bounds.items():
        if col not in idx:
            raise ValidationError(f"preset {preset.name!r} column", col, f"an axis column {list(idx)}")
        a = axes[idx[col]]
        v = a.values(frame[col])
        span = float(np.nanmax(v) - np.nanmin(v)) or 1.0
        plo = a.transform(lo) if lo is not None else float(np.nanmin(v)) - span
        phi = a.transform(hi) if hi is not None else float(np.nanmax(v)) + span
        out.append([idx[col] + offset, plo, phi])
    return out

def add_parcoords(report, study: DesignStudy, *, axes: Sequence[Axis] | None = None, color: str | None = None,
                  presets: Sequence[Preset] | None = None, extra: pd.DataFrame | None = None,
                  among: pd.DataFrame | None = None, log_objectives: Sequence[str] | None = None,
                  table_rows: int = 50, div_id: str = "pc", title: str = "", height: int = 600,
                  max_drawn: int | None = DEFAULT_MAX_DRAWN, seed: int = 0) -> dict:
    """Add the interactive parallel-coordinate section to ``report`` (an :class:`html.Report`).

    Above ``max_drawn`` lines the page first draws the sample :func:`drawn_lines` picks and
    draws all of them on request or when WebGL is hardware-accelerated.

    Parameters
    ----------
    report : Report
        The page (:class:`evotol.reporting.html.Report`), appended to in place.
    study : DesignStudy
        The evaluated entries.
    axes : sequence of Axis, optional
        The axes; default :func:`default_axes`.
    color : str, optional
        Objective column colouring the lines (an axis column); default the first objective.
    presets : sequence of Preset, optional
        Filters shown as buttons (their columns must be axis columns); default the study's
        presets.
    extra : pandas.DataFrame, optional
        NSGA-II Pareto entries (columns of the axes, optional bool ``knee``) drawn on top.
    among : pandas.DataFrame, optional
        Draw only these entries (e.g. a filtered subset).
    log_objectives : sequence of str, optional
        Objectives on log10, for the default axes (see :func:`default_axes`).
    table_rows : int, default 50
        Rows of the page's table of kept entries.
    div_id : str, default "pc"
        ``id`` of the figure's ``<div>``, prefix of the ids of its controls (unique per page).
    title : str, default ""
        Figure title.
    height : int, default 600
        Figure height (pixels).
    max_drawn : int or None, default DEFAULT_MAX_DRAWN
        Lines drawn at first (1000); ``None`` always draws all of them.
    seed : int, default 0
        Seed of the drawn sample.

    Returns
    -------
    dict
        ``{"n_lines", "n_drawn", "presets": {name: count}}`` -- the Python counts the page shows.

    Raises
    ------
    ValidationError
        ``extra`` lacks an axis column, no entry is left to draw, ``color`` or a preset column
        is not an axis column, an axis column is missing, a log axis has a value <= 0, or
        ``max_drawn`` is below 1.
    """
    axes = list(axes) if axes is not None else default_axes(study, log_objectives)
    color = color or study.objectives[0]
    presets = list(presets) if presets is not None else list(study.presets.values())
    if extra is not None and len(extra):
        missing = [a.column for a in axes if a.column not in extra]
        if missing:
            raise ValidationError("extra (NSGA-II) entries columns", missing, "every axis column")
    frame = parcoords_frame(study, among, extra)
    if frame.empty:
        raise ValidationError("entries to draw", 0, "at least one feasible entry (the filter or study keeps none)")
    fig = parcoords_figure(frame, axes, color, title=title, height=height)
    offset = 1 if fig.data[0].dimensions[0].label == "source" else 0
    filtered = {p.name: study.filter(p, among=frame) for p in presets}
    counts = {name: r.count for name, r in filtered.items()}
    # every line's values go to the page; the figure holds the drawn sample (all lines when few)
    full = [_b64(np.asarray(d.values, dtype=float)) for d in fig.data[0].dimensions]
    color_full = np.asarray(fig.data[0].line.color, dtype=float)
    drawn = drawn_lines(frame, axes, presets, study, max_drawn, seed, kept={n: r.kept.index for n, r in filtered.items()})
    if len(drawn) < len(frame):
        for d in fig.data[0].dimensions:
            d.values = np.asarray(d.values)[drawn]
        fig.data[0].line.color = color_full[drawn]
    log_flags = ([False] * offset) + [a.log for a in axes]
    payload = {
        "div": div_id, "n": int(len(frame)), "first": offset, "log": log_flags,
        "full": full, "color": _b64(color_full), "drawn": _b64(drawn.astype(np.int32)), "gpuMax": GPU_MAX_DRAWN,
        "colorDim": offset + [a.column for a in axes].index(color),
        "cols": list(range(offset, offset + len(axes))), "tableRows": int(table_rows),
        "grid": GRID, "discrete": ([False] * offset) + [bool(a.column in study.factors and study.factors[a.column].is_discrete) for a in axes],
        "entry": frame[ENTRY].astype(int).tolist() if ENTRY in frame else list(range(len(frame))),
        "source": frame[SOURCE].tolist() if SOURCE in frame else [GRID] * len(frame),
        "presets": [{"name": p.name, "ranges": _preset_ranges(p, axes, offset, frame), "count": counts[p.name]}
                    for p in presets],
    }
    e = html.escape
    buttons = [f'<button type="button" data-preset="">all entries ({len(frame)})</button>']
    for p in presets:
        buttons.append(f'<button type="button" data-preset="{e(p.name)}" title="{e(p.query)} — {e(p.figure)}">'
                       f'{e(p.name)}</button>')
    report.html(
        f'<style>#{div_id}-controls button{{margin:.15em .3em .15em 0;padding:.3em .7em;border:1px solid #888;'
        f'border-radius:4px;background:#f7f7f7;cursor:pointer}}#{div_id}-controls button:hover{{background:#e8eefc}}'
        f'.ev-count{{font-size:1.1em}}</style>'
        f'<div id="{div_id}-controls"><b>Presets:</b> {"".join(buttons)}</div>'
        f'<p class="ev-count"><span id="{div_id}-count-n">{len(frame)}</span> of {len(frame)} entries kept '
        f'(preset: <span id="{div_id}-preset">none</span>). Drag along any axis to filter by hand; click an '
        f'axis filter bar to remove it.</p><p class="meta" id="{div_id}-drawn"></p>')
    report.figure(fig, div_id=div_id)
    report.html(f'<div style="display:flex;gap:2em;flex-wrap:wrap"><div><b>Kept range per axis</b>'
                f'<table class="ev" id="{div_id}-ranges"></table></div><div><b>Kept entries</b> '
                f'<span class="meta" id="{div_id}-table-note"></span><table class="ev" id="{div_id}-table"></table>'
                f'</div></div>')
    script = ASSET.read_text(encoding="utf-8") % {"payload": json.dumps(payload)}
    report.html(f'<script type="text/javascript">{script}</script>')
    return {"n_lines": int(len(frame)), "n_drawn": int(len(drawn)), "presets": counts}


def preset_table_rows(study: DesignStudy, presets: Sequence[Preset] | None = None,
                      among: pd.DataFrame | None = None) -> list[list]:
    """Rows ``[preset, figure, query, kept count, kept input ranges]`` for a static report table.

    Parameters
    ----------
    study : DesignStudy
        The evaluated entries, filtered by :meth:`evotol.design.filtering.DesignStudy.filter`.
    presets : sequence of Preset, optional
        The presets; default the study's.
    among : pandas.DataFrame, optional
        Filter these entries instead of all of the study's.

    Returns
    -------
    list of list
        One row per preset: name, figure, resolved query, kept count and the kept range (or
        levels) of each input as text.
    """
    presets = list(presets) if presets is not None else list(study.presets.values())
    rows = []
    for p in presets:
        r = study.filter(p, among=among)
        parts = []
        for name, rg in r.ranges.items():
            label = study.factors[name].label if name in study.factors else name
            if rg.get("levels") is not None:
                parts.append(f"{label}: {', '.join(format_tick(v) for v in rg['levels']) or '–'}")
            elif rg["min"] is not None:
                parts.append(f"{label}: [{format_tick(rg['min'])}, {format_tick(rg['max'])}]")
        rows.append([p.name, p.figure, r.resolved_query, r.count, "; ".join(parts) or "–"])
    return rows

"""The plotly figure of a parallel-coordinate plot (Deng 2012, Figs. VII.1-VII.16;
:mod:`evotol.reporting.parcoords`).

One plotly ``Parcoords`` trace (WebGL, so tens of thousands of lines stay interactive) with an
axis per input and per objective. Lines are coloured by a chosen objective; entries that come
from NSGA-II (``source`` column) and their knee points get their own colours and a ``source``
axis, so they stand out from the level grid.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np
import pandas as pd

from evotol.design import SOURCE
from evotol.errors import ValidationError
from evotol.reporting.parcoords_axes import Axis, format_tick, log_ticks
from evotol.reporting.parcoords_lines import GRID, KNEE, PARETO

_GRID_TOP = 0.75          # grid entries use [0, 0.75] of the colour scale; NSGA-II and knees the rest


def _viridis(n: int = 9) -> list[str]:
    import plotly.colors as pc

    return pc.sample_colorscale("Viridis", [i / (n - 1) for i in range(n)])

def parcoords_figure(frame: pd.DataFrame, axes: Sequence[Axis], color: str, *, title: str = "",
                     height: int = 600):
    """A plotly Parcoords figure of ``frame`` (see :func:`parcoords_frame`), coloured by ``color``.

    The level-grid lines use the Viridis part of the colour scale (scaled to the grid's range of
    ``color``, or to all lines' range when there is no grid line); NSGA-II lines are orange, knees
    red, and a ``source`` axis is added first when there are any.

    Parameters
    ----------
    frame : pandas.DataFrame
        The lines, with every axis column and optionally ``source``.
    axes : sequence of Axis
        The axes, in drawing order.
    color : str
        The axis column that colours the lines.
    title : str, default ""
        Figure title; none when empty.
    height : int, default 600
        Figure height (pixels).

    Returns
    -------
    plotly.graph_objects.Figure
        One ``Parcoords`` trace.

    Raises
    ------
    ValidationError
        ``color`` is not an axis column, an axis column is missing from ``frame``, ``frame``
        has no line, ``color`` has no finite value, or a log axis has a value <= 0.
    """
    import plotly.graph_objects as go

    by_col = {a.column: a for a in axes}
    if color not in by_col:
        raise ValidationError("color", color, f"one of the axis columns {list(by_col)}")
    missing = [a.column for a in axes if a.column not in frame]
    if missing:
        raise ValidationError("axis columns", missing, f"columns of the entries {list(frame.columns)}")
    if len(frame) == 0:
        raise ValidationError("lines to draw", 0, "at least one line (a feasible entry or an extra entry)")
    src = frame[SOURCE].to_numpy() if SOURCE in frame else np.full(len(frame), GRID)
    has_extra = bool(np.any(src != GRID))
    dims = []
    if has_extra:
        code = np.select([src == PARETO, src == KNEE], [1, 2], 0)
        dims.append(dict(label="source", values=code, tickvals=[0, 1, 2], ticktext=[GRID, PARETO, KNEE],
                         range=[-0.1, 2.1]))
    for a in axes:
        v = a.values(frame[a.column])
        lo, hi = float(np.nanmin(v)), float(np.nanmax(v))
        pad = 0.02 * (hi - lo) if hi > lo else (0.5 if a.log else max(abs(lo) * 0.02, 1e-12))
        lo_r = lo - pad if (a.log or lo < 0) else max(lo - pad, 0.0)   # no negative ticks on a positive axis
        d = dict(label=a.label or a.column, values=v, range=[lo_r, hi + pad])
        if a.log:
            d["tickvals"], d["ticktext"] = log_ticks(lo - pad, hi + pad)
        dims.append(d)

    ca = by_col[color]
    cv = ca.values(frame[color])
    finite = np.isfinite(cv)
    ref = cv[finite & (src == GRID)] if np.any(finite & (src == GRID)) else cv[finite]   # no grid line: all lines
    if ref.size == 0:
        raise ValidationError(f"colour column {color}", "no finite value", "a finite value on at least one line")
    lo, hi = float(ref.min()), float(ref.max())
    top = _GRID_TOP if has_extra else 1.0
    c = np.clip((cv - lo) / (hi - lo if hi > lo else 1.0), 0, 1) * top
    c[src == PARETO], c[src == KNEE] = 0.875, 1.0
    vir = _viridis()
    scale = [[top * i / (len(vir) - 1), col] for i, col in enumerate(vir)]
    if has_extra:
        scale += [[0.76, "#ff7f0e"], [0.94, "#ff7f0e"], [0.95, "#d62728"], [1.0, "#d62728"]]
    if ca.log:
        tv, tt = log_ticks(lo, hi)
    else:
        tv = list(np.linspace(lo, hi, 5))
        tt = [format_tick(x) for x in tv]
    cb_vals = [(t - lo) / (hi - lo if hi > lo else 1.0) * top for t in tv]
    cb_text = list(tt)
    if has_extra:
        cb_vals += [0.875, 1.0]
        cb_text += [PARETO, KNEE]
    line = dict(color=c, colorscale=scale, cmin=0.0, cmax=1.0, showscale=True,
                colorbar=dict(title=dict(text=ca.label or color, side="right"), tickvals=cb_vals, ticktext=cb_text,
                              x=1.04, xpad=16, len=0.95, thickness=18))
    fig = go.Figure(go.Parcoords(line=line, dimensions=dims, labelangle=-20, labelside="top",
                                 unselected=dict(line=dict(color="#d9d9d9", opacity=0.25))))
    fig.update_layout(height=height, margin=dict(l=80, r=130, t=120, b=40),
                      title=dict(text=title) if title else None)
    return fig

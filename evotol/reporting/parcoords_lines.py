"""The lines of a parallel-coordinate plot: which entries are drawn, and the sample drawn when
there are many (Deng 2012, Figs. VII.1-VII.16; :mod:`evotol.reporting.parcoords`).

:func:`parcoords_frame` stacks the (feasible) level-grid entries and the NSGA-II entries, knees
last; the ``source`` column tells them apart.

Level of detail. Every entry is filtered, counted and tabulated, but plotly draws a parcoords
line with WebGL, which a machine without a GPU emulates on the CPU (SwiftShader, llvmpipe): there
each brush move redraws every line: 1.3-1.6 s per mouse move with 32 768 lines, 0.1-0.3 s with
1 000 (``benchmarks/bench_synthesis.py``, docs/synthesis.md). So when there are more than
``max_drawn`` lines the page draws a fixed sample of them (:func:`drawn_lines`: every NSGA-II
entry, each preset's kept entries up to a share, the entries at each axis' ends, then a seeded
random fill), says so above the plot, and offers a button that draws all of them; with a
hardware WebGL renderer it draws all of them at once by itself.
"""
from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np
import pandas as pd

from evotol.design import ENTRY, SOURCE
from evotol.errors import ValidationError
from evotol.design.filtering import DesignStudy, Preset
from evotol.reporting.parcoords_axes import Axis

GRID, PARETO, KNEE = "level grid", "NSGA-II", "knee"
#: lines drawn by default when WebGL may be software-rendered (the thesis's own figures draw 1 000)
DEFAULT_MAX_DRAWN = 1000
#: with a hardware WebGL renderer the page draws all lines up to this many
GPU_MAX_DRAWN = 200_000


def parcoords_frame(study: DesignStudy, among: pd.DataFrame | None = None,
                    extra: pd.DataFrame | None = None) -> pd.DataFrame:
    """The lines to draw: the (feasible) study entries, then the ``extra`` (NSGA-II) entries.

    Parameters
    ----------
    study : DesignStudy
        The evaluated entries.
    among : pandas.DataFrame, optional
        Draw these entries instead of all of the study's (e.g. a filtered subset).
    extra : pandas.DataFrame, optional
        NSGA-II entries (the axis columns, optional bool ``knee``) drawn after the grid; without
        an ``entry`` column they are numbered -1, -2, ...

    Returns
    -------
    pandas.DataFrame
        The feasible grid entries (``source = "level grid"``; the ``feasible`` column, when
        present, selects them), then the extra ones (``source`` ``"NSGA-II"`` or ``"knee"``,
        knees last), index reset.
    """
    grid = study.entries if among is None else among
    if "feasible" in grid:
        grid = grid[grid["feasible"].astype(bool)]
    grid = grid.assign(**{SOURCE: GRID})
    parts = [grid]
    if extra is not None and len(extra):
        e = extra.copy()
        knee = e["knee"].astype(bool) if "knee" in e else pd.Series(False, index=e.index)
        e[SOURCE] = np.where(knee, KNEE, PARETO)
        if ENTRY not in e:
            e[ENTRY] = -1 - np.arange(len(e))
        parts.append(e.sort_values(SOURCE, key=lambda s: s.eq(KNEE)))   # knees drawn last
    return pd.concat(parts, ignore_index=True)


def drawn_lines(frame: pd.DataFrame, axes: Sequence[Axis], presets: Sequence[Preset], study: DesignStudy,
                max_drawn: int | None, seed: int = 0, kept: Mapping[str, pd.Index] | None = None) -> np.ndarray:
    """Positions (into ``frame``) of the lines to draw when there are more than ``max_drawn``.

    In this order, until ``max_drawn`` are chosen: every NSGA-II / knee line; for each preset, up to
    ``max_drawn // (2 (presets + 1))`` of the entries it keeps (all of them when fewer), so a preset
    that keeps few entries shows all of them; the entries at both ends of every axis; then a seeded
    uniform sample of the rest. Returns all positions when ``len(frame) <= max_drawn``.
    ``kept``: each preset's kept index in ``frame``, when the caller has filtered already.

    Parameters
    ----------
    frame : pandas.DataFrame
        The lines (:func:`parcoords_frame`).
    axes : sequence of Axis
        The drawn axes (their extreme entries are kept).
    presets : sequence of Preset
        The presets whose kept entries are sampled.
    study : DesignStudy
        Filters ``frame`` by each preset when ``kept`` is None.
    max_drawn : int or None
        Most lines to draw; None draws all.
    seed : int, default 0
        Seed of the random choices.
    kept : mapping of str to pandas.Index, optional
        Each preset's kept index in ``frame``, by preset name.

    Returns
    -------
    ndarray of int
        Sorted positions into ``frame``.

    Raises
    ------
    ValidationError
        ``max_drawn`` is below 1 while ``frame`` has lines, or a log axis has a value <= 0.
    """
    n = len(frame)
    if max_drawn is None or n <= max_drawn:
        return np.arange(n)
    if int(max_drawn) < 1:
        raise ValidationError("max_drawn", max_drawn, "a positive number of lines")
    rng = np.random.default_rng(seed)
    chosen = np.zeros(n, dtype=bool)
    src = frame[SOURCE].to_numpy() if SOURCE in frame else np.full(n, GRID)
    chosen[src != GRID] = True
    share = max(1, int(max_drawn) // (2 * (len(presets) + 1)))
    for p in presets:
        index = kept[p.name] if kept is not None else study.filter(p, among=frame).kept.index
        pos = np.flatnonzero(frame.index.isin(index))
        pos = pos[~chosen[pos]]
        if len(pos) > share:
            pos = rng.choice(pos, share, replace=False)
        chosen[pos] = True
    for a in axes:
        v = a.values(frame[a.column])
        chosen[[int(np.nanargmin(v)), int(np.nanargmax(v))]] = True
    rest = np.flatnonzero(~chosen)
    room = int(max_drawn) - int(chosen.sum())
    if room > 0:
        chosen[rng.choice(rest, min(room, len(rest)), replace=False)] = True
    return np.flatnonzero(chosen)

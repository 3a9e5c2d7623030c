"""The axes of a parallel-coordinate plot: which column, linear or log10, and readable ticks.

Part of the parallel-coordinate report of design studies (:mod:`evotol.reporting.parcoords`;
Deng 2012, Figs. VII.1-VII.16). Tolerance axes spanning decades are drawn on log10 with tick
labels in the axis unit (``0.0001 … 0.1``); :func:`default_axes` puts every input, then every
objective, on an axis.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
import pandas as pd

from evotol.errors import ValidationError
from evotol.design.filtering import DesignStudy

_SUP = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


@dataclass(frozen=True)
class Axis:
    """One parallel-coordinate axis: a column, its label and whether it is drawn on log10.

    Parameters
    ----------
    column : str
        Column of the entries table (values in the unit its name says).
    label : str, default ""
        Axis title; empty means ``column``.
    log : bool, default False
        Draw ``log10`` of the values (for positive values spanning decades).
    """

    column: str
    label: str = ""
    log: bool = False

    def values(self, s: pd.Series) -> np.ndarray:
        """The plotted values of a column: as they are, or their ``log10`` on a log axis.

        Parameters
        ----------
        s : pandas.Series
            The column's values (column unit).

        Returns
        -------
        ndarray
            Float values, ``log10`` of them when ``log``; same length as ``s``.

        Raises
        ------
        ValidationError
            A log axis has a value <= 0.
        """
        v = s.to_numpy(dtype=float)
        if self.log:
            if np.any(v <= 0):
                raise ValidationError(f"log axis {self.column}", float(v[v <= 0][0]), "positive values")
            return np.log10(v)
        return v

    def transform(self, x: float) -> float:
        """One value in plotted units (``log10(x)`` on a log axis).

        Parameters
        ----------
        x : float
            A value in the column unit (> 0 on a log axis).

        Returns
        -------
        float
            The position on the axis.
        """
        return math.log10(x) if self.log else float(x)


def format_tick(v: float) -> str:
    """Readable tick text: plain decimals from 0.0001 to 99 999, else ``2·10⁻⁵``.

    Parameters
    ----------
    v : float
        The value (axis unit).

    Returns
    -------
    str
        Four significant digits, or mantissa (three digits, none when 1) times a power of ten
        with a superscript exponent.
    """
    if v == 0:
        return "0"
    if 1e-4 <= abs(v) < 1e5:
        return f"{v:.4g}"
    e = int(math.floor(math.log10(abs(v)) + 1e-12))
    m = v / 10 ** e
    mant = "" if abs(m - 1) < 1e-9 else f"{m:.3g}·"
    return f"{mant}10{str(e).translate(_SUP)}"


def log_ticks(lo: float, hi: float) -> tuple[list[float], list[str]]:
    """Tick positions (log10 units) and labels (axis units) for a log axis spanning [lo, hi] (log10).

    Ticks at 1 per decade over three decades or more, at 1, 2, 5 over one or more, else at 1,
    1.5, 2, 3, 5, 7; the two ends when fewer than two ticks fall in the range.

    Parameters
    ----------
    lo : float
        Lower end of the axis, ``log10`` of the axis unit.
    hi : float
        Upper end, ``log10`` of the axis unit.

    Returns
    -------
    tickvals : list of float
        Tick positions (log10 units).
    ticktext : list of str
        Their labels in the axis unit (:func:`format_tick`).
    """
    d0, d1 = math.floor(lo + 1e-9), math.ceil(hi - 1e-9)
    mults = (1,) if d1 - d0 >= 3 else ((1, 2, 5) if d1 - d0 >= 1 else (1, 1.5, 2, 3, 5, 7))
    vals = [math.log10(m) + d for d in range(d0, d1 + 1) for m in mults]
    vals = [v for v in vals if lo - 1e-9 <= v <= hi + 1e-9]
    if len(vals) < 2:
        vals = [lo, hi]
    return vals, [format_tick(10 ** v) for v in vals]


def default_axes(study: DesignStudy, log_objectives: Sequence[str] | None = None) -> list[Axis]:
    """Inputs then objectives; factors with ``log=True`` on log10; objectives on log10 when listed
    in ``log_objectives`` or, by default, when positive and spanning more than two decades.

    Parameters
    ----------
    study : DesignStudy
        The evaluated entries, with their inputs, objectives and factors.
    log_objectives : sequence of str, optional
        The objective columns drawn on log10; None decides from the values (positive, max/min
        above 100).

    Returns
    -------
    list of Axis
        One axis per input (the factor's label, its ``log``), then one per objective.
    """
    axes = []
    for c in study.inputs:
        f = study.factors.get(c)
        axes.append(Axis(c, f.label if f else c, bool(f and f.log)))
    for c in study.objectives:
        if log_objectives is None:
            v = pd.to_numeric(study.entries[c], errors="coerce").to_numpy(float)
            v = v[np.isfinite(v)]
            log = bool(v.size and v.min() > 0 and v.max() / v.min() > 100)
        else:
            log = c in log_objectives
        axes.append(Axis(c, c, log))
    return axes

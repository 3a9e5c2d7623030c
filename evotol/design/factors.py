"""Design variables of a study: :class:`Factor` and the column names every entries table shares.

Deng (2012), Sec. VII.1.1: a design study evaluates many **entries** -- one value per design
variable (a tolerance level, a link length). Column values are in the unit their name says
(``db_xy_A_mm`` in mm); ``Factor.si_scale`` converts them to SI for the physics.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Mapping, Sequence

import numpy as np
import pandas as pd

from evotol.errors import ValidationError

#: columns the evaluation adds besides the evaluator's objectives
FEASIBLE, ERROR, ENTRY, SOURCE = "feasible", "error", "entry", "source"


@dataclass(frozen=True)
class Factor:
    """One design variable of a study.

    Values (``levels``, ``low``, ``high``) are in the factor's column unit, the one its name says
    (mm for ``db_xy_A_mm``); ``si_scale`` converts them to SI.

    Parameters
    ----------
    name : str
        Column name in the entries table, a Python identifier; says its unit when not SI
        (``"db_xy_A_mm"``).
    levels : tuple of float, default ()
        The discrete levels (full factorial / random subset), distinct and finite; stored
        sorted. Empty for a continuous factor.
    low : float, optional
        Lower end of the continuous range (Latin hypercube, NSGA-II), column unit; defaults to
        the smallest level.
    high : float, optional
        Upper end of the continuous range, column unit, >= ``low``; defaults to the largest
        level.
    log : bool, default False
        Sample and draw on a log scale (tolerances spanning decades); needs ``low > 0``.
    label : str, default ""
        Axis label for reports (``"Δb_xy A (mm)"``); empty means ``name``.
    si_scale : float, default 1.0
        ``SI value = column value * si_scale`` (1e-3 for mm, pi/180 for deg); positive.
    group : str, default ""
        Family used by reports and findings (``"radial clearance"``, ``"link length"``).

    Raises
    ------
    ValidationError
        ``name`` is not an identifier; levels not distinct and finite; neither levels nor both
        ``low`` and ``high``; a range not finite or with ``low > high``; ``log`` with
        ``low <= 0``; or ``si_scale`` not positive.
    """

    name: str
    levels: tuple[float, ...] = ()
    low: float | None = None
    high: float | None = None
    log: bool = False
    label: str = ""
    si_scale: float = 1.0
    group: str = ""

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise ValidationError("Factor.name", self.name, "a Python identifier (it becomes a query column)")
        levels = tuple(float(v) for v in self.levels)
        object.__setattr__(self, "levels", levels)
        if levels:
            if len(set(levels)) != len(levels) or not all(np.isfinite(levels)):
                raise ValidationError(f"Factor({self.name!r}).levels", levels, "distinct finite values")
            object.__setattr__(self, "levels", tuple(sorted(levels)))
            if self.low is None:
                object.__setattr__(self, "low", min(levels))
            if self.high is None:
                object.__setattr__(self, "high", max(levels))
        if self.low is None or self.high is None:
            raise ValidationError(f"Factor({self.name!r})", (self.low, self.high), "levels or a [low, high] range")
        lo, hi = float(self.low), float(self.high)
        object.__setattr__(self, "low", lo)
        object.__setattr__(self, "high", hi)
        if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
            raise ValidationError(f"Factor({self.name!r}) range", (lo, hi), "finite low <= high")
        if self.log and lo <= 0:
            raise ValidationError(f"Factor({self.name!r}).low", lo, "a positive value on a log-scaled factor")
        if not (self.si_scale > 0):
            raise ValidationError(f"Factor({self.name!r}).si_scale", self.si_scale, "a positive number")
        if not self.label:
            object.__setattr__(self, "label", self.name)

    @property
    def is_discrete(self) -> bool:
        """True when the factor has discrete ``levels`` (else it is continuous on ``[low, high]``)."""
        return bool(self.levels)

    def to_unit(self, u: np.ndarray) -> np.ndarray:
        """Map u in [0, 1] to the factor's range (log-uniform when ``log``); continuous.

        Parameters
        ----------
        u : array_like
            Unit coordinates, nominally in [0, 1] (not clipped), any shape.

        Returns
        -------
        ndarray
            ``low + u * (high - low)``, or ``low * (high / low) ** u`` when ``log``, in the
            factor's column unit; same shape as ``u``. Levels are ignored.
        """
        u = np.asarray(u, dtype=float)
        if self.log:
            a, b = math.log10(self.low), math.log10(self.high)
            return 10.0 ** (a + u * (b - a))
        return self.low + u * (self.high - self.low)

    def to_dict(self) -> dict:
        """The factor as a plain dict (stored in ``df.attrs`` and Parquet metadata).

        Returns
        -------
        dict
            Every field by name, ``levels`` as a list.
        """
        d = asdict(self)
        d["levels"] = list(self.levels)
        return d

    @classmethod
    def from_dict(cls, d: Mapping) -> "Factor":
        """Rebuild a factor from :meth:`to_dict` output.

        Parameters
        ----------
        d : mapping
            Field values by name; ``levels`` optional (any sequence).

        Returns
        -------
        Factor
            The factor, validated as by the constructor.
        """
        return cls(**{**d, "levels": tuple(d.get("levels", ()))})


def _check_factors(factors: Sequence[Factor]) -> tuple[Factor, ...]:
    factors = tuple(factors)
    if not factors or not all(isinstance(f, Factor) for f in factors):
        raise ValidationError("factors", factors, "a non-empty sequence of Factor")
    names = [f.name for f in factors]
    if len(set(names)) != len(names):
        raise ValidationError("factor names", names, "unique names")
    reserved = {FEASIBLE, ERROR, ENTRY, SOURCE}
    if reserved & set(names):
        raise ValidationError("factor names", sorted(reserved & set(names)), f"names other than {sorted(reserved)}")
    return factors


def _attach(df: pd.DataFrame, factors: Sequence[Factor], design: str, **extra) -> pd.DataFrame:
    df.attrs["evotol"] = {"factors": [f.to_dict() for f in factors], "design": design, **extra}
    return df


def factors_of(df: pd.DataFrame) -> tuple[Factor, ...]:
    """The factors stored with an entries table (empty when it carries none, e.g. a plain CSV).

    Parameters
    ----------
    df : pandas.DataFrame
        An entries table (from a design, :func:`~evotol.design.evaluation.evaluate` or a Parquet
        file), read through ``df.attrs["evotol"]["factors"]``.

    Returns
    -------
    tuple of Factor
        The factors, in their design order.
    """
    meta = df.attrs.get("evotol", {})
    return tuple(Factor.from_dict(d) for d in meta.get("factors", ()))



def from_unit(f: Factor, x: np.ndarray) -> np.ndarray:
    """Inverse of :meth:`Factor.to_unit`: values in the factor's unit -> u in [0, 1] (clipped).

    Parameters
    ----------
    f : Factor
        The factor.
    x : array_like
        Values in the factor's column unit, any shape; clipped to ``[low, high]`` first.

    Returns
    -------
    ndarray
        Unit coordinates in [0, 1] (log-scaled when ``f.log``), same shape as ``x``; zeros when
        ``low == high``.
    """
    x = np.clip(np.asarray(x, dtype=float), f.low, f.high)
    if f.high == f.low:
        return np.zeros_like(x)
    if f.log:
        return (np.log10(x) - math.log10(f.low)) / (math.log10(f.high) - math.log10(f.low))
    return (x - f.low) / (f.high - f.low)


"""One error source's tolerance: its cost model, allowed range, distribution and interval shape
(SI units: m or rad; conventions in ``docs/tolerances.md``)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.cost_models.base import CostModel
from evotol.measures.statistical import distributions
from evotol.errors import ValidationError

#: the width a tolerance's cost model is evaluated on: the half-width (minus + plus)/2 t ("half",
#: the default) or the whole zone (minus + plus) t ("full"); the values ``Tolerance.cost_width`` accepts
COST_WIDTHS = ("half", "full")


@dataclass(frozen=True)
class Tolerance:
    """Settings of one error source's tolerance (all keyword fields; SI units: m or rad).

    Parameters
    ----------
    cost : evotol.cost_models.CostModel or None
        Cost model of this tolerance, or None for a fixed source (:meth:`fixed`).
    lower, upper : float
        Allowed range of the tolerance t (m or rad, the source's unit), 0 < lower <= upper.
    locked : float or None
        If given, the tolerance is fixed at this value (m or rad) and not optimised (its cost
        counts).
    distribution : str or evotol.measures.statistical.distributions.Distribution
        How the source is distributed inside its tolerance (Monte Carlo and the ``yield``
        measure): a kind name (``"uniform"``, ``"normal"`` with t = 3σ, ``"truncated_normal"``,
        ``"contact"``) or a :class:`evotol.measures.statistical.distributions.Distribution` (``sigma_k``,
        ``mean_shift``); conventions in :mod:`evotol.measures.statistical.distributions`. For an asymmetric interval
        the distribution is placed on the interval: centre offset + (plus − minus)/2·t,
        half-width (minus + plus)/2·t.
    offset, minus, plus : float
        Interval sources only: the error lies in ``[offset − minus·t, offset + plus·t]``;
        ``offset`` is a fixed mean shift (m or rad), ``minus``/``plus`` fixed ratios (>= 0, not
        both 0). Default: the centred interval ±t.
    cost_width : {"half", "full"}
        Which width the cost model is evaluated on: ``"half"`` (default: the half-width
        (minus + plus)/2·t, which is t for ±t -- the convention of the cost–tolerance literature
        for a symmetric ±t) or ``"full"`` (the whole width (minus + plus)·t, as a drawing states
        a tolerance zone).
    contains_nominal : bool
        If True, every allowed interval must contain 0 (the nominal value), which is checked at
        the smallest allowed tolerance.

    Notes
    -----
    A plain value: nothing is checked at construction. :meth:`validate` (called by
    :class:`evotol.core.problem.ToleranceProblem` for every entry) raises :class:`evotol.errors.ValidationError`.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import Tolerance
    >>> tol = Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-6, upper=1e-4)  # m; cost 1e-3 / t
    >>> float(tol.cost_of(2e-5))
    50.0
    >>> tol.is_fixed
    False
    """

    cost: CostModel | None
    lower: float
    upper: float
    locked: float | None = None
    distribution: "str | distributions.Distribution" = "uniform"
    offset: float = 0.0
    minus: float = 1.0
    plus: float = 1.0
    cost_width: str = "half"
    contains_nominal: bool = False

    @classmethod
    def fixed(cls, t: float, **kwargs) -> "Tolerance":
        """A source with a known error bound t (SI) and no cost: not optimised, never priced.

        Parameters
        ----------
        t : float
            The fixed tolerance (m or rad): ``lower = upper = locked = t``.
        **kwargs
            Further fields of :class:`Tolerance` (``distribution``, ``offset``, ``minus``,
            ``plus``, ``cost_width``, ``contains_nominal``).

        Returns
        -------
        Tolerance
            A tolerance with ``cost=None``, locked at t.
        """
        return cls(cost=None, lower=t, upper=t, locked=t, **kwargs)

    @property
    def is_fixed(self) -> bool:
        """True if the source has no cost model (made by :meth:`fixed`): never optimised or priced."""
        return self.cost is None

    @property
    def rho(self) -> float:
        """Half-width per unit t: (minus + plus)/2 (dimensionless)."""
        return 0.5 * (float(self.minus) + float(self.plus))

    @property
    def kappa(self) -> float:
        """Centre shift per unit t: (plus − minus)/2 (dimensionless)."""
        return 0.5 * (float(self.plus) - float(self.minus))

    @property
    def width_factor(self) -> float:
        """Width the cost model sees per unit t: ρ (``cost_width="half"``) or 2ρ (``"full"``) (dimensionless)."""
        return self.rho if self.cost_width == "half" else 2 * self.rho

    def interval(self, t: float) -> tuple[float, float]:
        """The interval [offset − minus·t, offset + plus·t] (SI) at tolerance t.

        Parameters
        ----------
        t : float
            Tolerance (m or rad).

        Returns
        -------
        tuple of float
            ``(lo, hi)``, the interval's ends (m or rad).
        """
        return self.offset - self.minus * t, self.offset + self.plus * t

    def cost_of(self, t):
        """Cost at tolerance t (array-like): the cost model at the width ``cost_width`` says; 0 if fixed.

        Parameters
        ----------
        t : float or array_like
            Tolerance(s) (m or rad).

        Returns
        -------
        float or ndarray
            Cost (cost units) at each t, shaped like t; zeros for a fixed source.
        """
        if self.cost is None:
            return np.zeros_like(np.asarray(t, dtype=float))
        w = self.width_factor
        return self.cost.cost(t if w == 1 else w * np.asarray(t, dtype=float))

    def dcost_of(self, t):
        """d cost / d t (chain rule through the width factor).

        Parameters
        ----------
        t : float or array_like
            Tolerance(s) (m or rad).

        Returns
        -------
        float or ndarray
            Derivative of the cost with respect to t (cost units per m or rad), shaped like t;
            zeros for a fixed source.
        """
        if self.cost is None:
            return np.zeros_like(np.asarray(t, dtype=float))
        w = self.width_factor
        return self.cost.dcost(t) if w == 1 else w * self.cost.dcost(w * np.asarray(t, dtype=float))

    def validate(self, name: str, dim: int = 1) -> None:
        """Check the settings for source ``name`` of dimension ``dim``.

        Parameters
        ----------
        name : str
            Source name, used in the error message (``tolerances['name'].field``).
        dim : int
            Dimension of the source's error vector (1 interval, 2 disk, 3 ball).

        Raises
        ------
        evotol.errors.ValidationError
            A field out of range (non-positive or inverted bounds, ``locked`` outside them,
            unknown distribution or ``cost_width``, an asymmetric interval on a 2-D/3-D source,
            an interval without 0 when ``contains_nominal``, a cost model undefined on the range).
        """
        f0 = f"tolerances[{name!r}]"
        if self.cost is not None and not isinstance(self.cost, CostModel):
            raise ValidationError(f"{f0}.cost", self.cost, "a evotol.cost_models.CostModel (or None with Tolerance.fixed)")
        if self.cost is None and self.locked is None:
            raise ValidationError(f"{f0}.cost", None, "a cost model; only Tolerance.fixed(t) (locked) may have none")
        for f in ("lower", "upper"):
            v = getattr(self, f)
            if not isinstance(v, (int, float, np.floating)) or not np.isfinite(v) or v <= 0:
                raise ValidationError(f"{f0}.{f}", v, "a positive finite tolerance in SI units (m or rad)")
        if self.lower > self.upper:
            raise ValidationError(f"{f0}.lower", self.lower, f"<= upper ({self.upper})")
        if self.locked is not None and not (isinstance(self.locked, (int, float, np.floating))
                                            and np.isfinite(self.locked) and self.locked > 0):
            raise ValidationError(f"{f0}.locked", self.locked, "a positive tolerance (SI) or None")
        if self.locked is not None and not (self.lower * (1 - 1e-12) <= self.locked <= self.upper * (1 + 1e-12)):
            raise ValidationError(f"{f0}.locked", self.locked,   # issue 15: was silently used
                                  f"a value within [lower, upper] = [{self.lower:.6g}, {self.upper:.6g}]")
        distributions.as_distribution(self.distribution, f"{f0}.distribution")
        for f in ("offset", "minus", "plus"):
            v = getattr(self, f)
            if not isinstance(v, (int, float, np.floating)) or not np.isfinite(v) or (f != "offset" and v < 0):
                raise ValidationError(f"{f0}.{f}", v, "a finite number (SI)" if f == "offset" else "a ratio >= 0")
        if self.minus + self.plus <= 0:
            raise ValidationError(f"{f0}.minus", (self.minus, self.plus), "minus + plus > 0")
        if self.cost_width not in COST_WIDTHS:
            raise ValidationError(f"{f0}.cost_width", self.cost_width, f"one of {COST_WIDTHS}")
        if dim != 1 and (self.offset != 0 or self.minus != 1 or self.plus != 1):
            raise ValidationError(f"{f0}.offset", (self.offset, self.minus, self.plus),
                                  f"offset = 0, minus = plus = 1 for a {dim}-D source (asymmetric intervals are for "
                                  "interval sources)")
        t_small = self.locked if self.locked is not None else self.lower
        lo, hi = self.interval(t_small)
        if self.contains_nominal and not (lo <= 0 <= hi):
            raise ValidationError(f"{f0}.offset", self.offset,
                                  f"an offset whose interval contains 0 at t = {t_small:g} "
                                  f"([{lo:.6g}, {hi:.6g}]; contains_nominal = True)")
        if self.cost is not None:
            w = self.width_factor
            a = min(self.lower, self.locked or self.lower)
            b = max(self.upper, self.locked or self.upper)
            self.cost.validate_range(w * a, w * b)


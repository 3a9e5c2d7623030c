"""The values a stack analysis works on: a dimension (nominal, signed deviations, direction,
distribution), the stack (gap name, limits, unit) and the statistical model (capability, mean
shift). Conventions and equations: :mod:`evotol.measures.stack_analysis`. A stack is the one
linear-stack model with drawn zones: :meth:`Stack.linear_stack` gives its
:class:`evotol.robots.assembly.LinearStack`, and both take their worst case and RSS from
:mod:`evotol.robots.assembly.linear_stack`."""
from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from evotol.errors import ValidationError, is_real
from evotol.robots.assembly import LinearStack

#: the distributions a dimension can have inside its zone
DISTRIBUTIONS = ("normal", "uniform", "triangular")
#: how a mean shift is stacked (module docstring)
SHIFT_MODELS = ("dynamic", "static")


def _finite(field_name: str, v, what: str = "a finite number") -> float:
    if not is_real(v) or not np.isfinite(v):
        raise ValidationError(field_name, v, what)
    return float(v)


@dataclass(frozen=True)
class StackDimension:
    """One dimension of a stack: nominal, signed deviations, sensitivity and distribution.

    Parameters
    ----------
    name : str
        The dimension's name (a drawing callout, e.g. ``"A"``).
    nominal : float
        Nominal value (the stack's length unit).
    upper, lower : float
        Signed upper and lower deviations from the nominal (length unit), ``lower <= upper``:
        ``+0.010 / −0.004`` is ``upper = 0.010, lower = −0.004``.
    sensitivity : float
        ∂gap/∂dimension: +1 or −1 for a direction in a loop diagram (dimensionless).
    distribution : str
        ``"normal"`` (the half-width is ``3 C_p σ``), ``"uniform"`` or ``"triangular"`` over the zone.
    same_part_as : str or None
        Another dimension made to the same drawing (reports only: two parts, two independent values).

    Raises
    ------
    evotol.errors.ValidationError
        A non-finite value, ``lower > upper``, a zero sensitivity or an unknown distribution
        (:meth:`validate`).
    """

    name: str
    nominal: float
    upper: float
    lower: float
    sensitivity: float = 1.0
    distribution: str = "normal"
    same_part_as: str | None = None

    def __post_init__(self):
        self.validate()

    def validate(self, field_name: str | None = None) -> None:
        """Check the values.

        Parameters
        ----------
        field_name : str, optional
            Where the dimension comes from, for messages (default ``dimensions.NAME``).

        Raises
        ------
        evotol.errors.ValidationError
            See the class.
        """
        f = field_name or f"dimensions.{self.name}"
        for k in ("nominal", "upper", "lower", "sensitivity"):
            _finite(f"{f}.{k}", getattr(self, k))
        if self.lower > self.upper:
            raise ValidationError(f"{f}.lower", self.lower, f"<= upper ({self.upper}): signed deviations, e.g. "
                                  "upper = 0.010, lower = -0.004 for +0.010/-0.004")
        if self.sensitivity == 0:
            raise ValidationError(f"{f}.sensitivity", 0, "a non-zero direction (+1, -1) or sensitivity ∂gap/∂dimension")
        if self.distribution not in DISTRIBUTIONS:
            raise ValidationError(f"{f}.distribution", self.distribution, f"one of {DISTRIBUTIONS}")

    @property
    def centre(self) -> float:
        """Zone centre ``n + (l + u)/2`` (length unit)."""
        return self.nominal + 0.5 * (self.lower + self.upper)

    @property
    def half_width(self) -> float:
        """Half-width ``(u − l)/2`` (length unit)."""
        return 0.5 * (self.upper - self.lower)


@dataclass(frozen=True)
class Stack:
    """A gap and the dimensions that make it, with the gap's limits.

    Parameters
    ----------
    dimensions : tuple of StackDimension
        The loop's dimensions (at least one; names unique).
    gap : str
        The gap's name (reports).
    lower_limit, upper_limit : float or None
        The gap's lower and upper specification limits LSL, USL (length unit); None for a
        one-sided requirement.
    unit : str
        The length unit the values are in (reports; the formulas do not depend on it).

    Raises
    ------
    evotol.errors.ValidationError
        No dimensions, duplicate names, a ``same_part_as`` naming no dimension, or
        ``lower_limit >= upper_limit``.
    """

    dimensions: tuple
    gap: str = "gap"
    lower_limit: float | None = None
    upper_limit: float | None = None
    unit: str = "m"

    def __post_init__(self):
        dims = tuple(self.dimensions)
        object.__setattr__(self, "dimensions", dims)
        if not dims or not all(isinstance(d, StackDimension) for d in dims):
            raise ValidationError("dimensions", self.dimensions, "one or more StackDimension values")
        names = [d.name for d in dims]
        dup = sorted(n for n, k in Counter(names).items() if k > 1)       # one pass (5 000 dimensions: 3 s with list.count)
        if dup:
            raise ValidationError(f"dimensions.{dup[0]}", dup[0], "a name used once")
        known = set(names)
        for d in dims:
            if d.same_part_as is not None and d.same_part_as not in known:
                raise ValidationError(f"dimensions.{d.name}.same_part_as", d.same_part_as, f"one of {names}")
        for k in ("lower_limit", "upper_limit"):
            if getattr(self, k) is not None:
                _finite(k, getattr(self, k))
        if self.lower_limit is not None and self.upper_limit is not None and self.lower_limit >= self.upper_limit:
            raise ValidationError("lower_limit", self.lower_limit, f"< upper_limit ({self.upper_limit})")

    @property
    def names(self) -> list[str]:
        """Dimension names, in loop order."""
        return [d.name for d in self.dimensions]

    def deviations(self) -> tuple[np.ndarray, np.ndarray]:
        """``(lower, upper)``: every dimension's signed deviations (length unit).

        Returns
        -------
        tuple of ndarray
            Two arrays of shape (n_dimensions,).
        """
        return np.array([x.lower for x in self.dimensions]), np.array([x.upper for x in self.dimensions])

    def linear_stack(self, limit: float | None = None, *, extra: dict | None = None, name: str | None = None) -> LinearStack:
        """The stack as the one linear-stack model, :class:`evotol.robots.assembly.LinearStack` (a robot
        an allocation works on): ``gap = Σ a_i x_i`` with the allowed deviation ``limit``.

        Parameters
        ----------
        limit : float, optional
            Allowed deviation of the gap (length unit); default the half-width of the limits,
            ``(USL − LSL)/2``.
        extra : dict of str to float, optional
            Further sources after the dimensions: name -> sensitivity (the allocation's fixed
            "limits' centre", :mod:`evotol.allocators.stack_allocation`).
        name : str, optional
            The robot's name (default ``stack 'GAP'``).

        Returns
        -------
        LinearStack
            One response (the gap), the dimensions' sensitivities; no nominals (the drawing table
            leaves them blank, as for a stack given by its sensitivities).

        Raises
        ------
        evotol.errors.ValidationError
            No ``limit`` and not both limits of the gap.
        """
        if limit is None:
            if self.lower_limit is None or self.upper_limit is None:
                raise ValidationError("upper_limit" if self.lower_limit is not None else "lower_limit", None,
                                      "both limits of the gap (or a limit given to linear_stack)")
            limit = 0.5 * (self.upper_limit - self.lower_limit)
        return LinearStack({**{d.name: float(d.sensitivity) for d in self.dimensions}, **(extra or {})}, {self.gap: limit},
                           name=name or f"stack '{self.gap}'")

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(a, n, m, h)``: sensitivities, nominals, zone centres and half-widths (length unit).

        Returns
        -------
        tuple of ndarray
            Four arrays of shape (n_dimensions,).
        """
        d = self.dimensions
        return (np.array([x.sensitivity for x in d]), np.array([x.nominal for x in d]),
                np.array([x.centre for x in d]), np.array([x.half_width for x in d]))


@dataclass(frozen=True)
class StackModel:
    """The statistical model of a stack: capability and mean shift of its dimensions.

    Parameters
    ----------
    cp : float
        Every dimension's process capability: its half-width is ``3 C_p σ`` (1: t = 3σ, the RSS
        convention; 2: six sigma).
    k : float
        Mean shift as a fraction of the half-width, ``0 <= k < 1`` (six sigma's 1.5σ: 0.25 at C_p = 2).
    shift_model : {"dynamic", "static"}
        How the shift is stacked (module docstring).

    Raises
    ------
    evotol.errors.ValidationError
        ``cp <= 0``, ``k`` outside [0, 1) or an unknown ``shift_model``.
    """

    cp: float = 1.0
    k: float = 0.0
    shift_model: str = "dynamic"

    def __post_init__(self):
        if _finite("model.cp", self.cp, "a positive capability C_p") <= 0:
            raise ValidationError("model.cp", self.cp, "a positive capability C_p (half-width = 3 C_p σ)")
        if not 0 <= _finite("model.k", self.k) < 1:
            raise ValidationError("model.k", self.k, "a mean shift 0 <= k < 1 (fraction of the half-width)")
        if self.shift_model not in SHIFT_MODELS:
            raise ValidationError("model.shift_model", self.shift_model, f"one of {SHIFT_MODELS}")

    def describe(self) -> str:
        """One line stating the model.

        Returns
        -------
        str
            E.g. ``"half-width = 3·Cp·σ with Cp = 1, no mean shift"``.
        """
        base = f"half-width = 3·Cp·σ with Cp = {self.cp:g}"
        if self.k == 0:
            return base + ", no mean shift"
        return base + f", mean shift k = {self.k:g} of the half-width, stacked {self.shift_model}ally" \
            + (" (σ_eff = h/(3·Cp·(1 − k)))" if self.shift_model == "dynamic" else " (Σ|a|·k·h toward each limit)")

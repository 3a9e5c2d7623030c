"""Reciprocal-power cost model ``c = a0 + a1/x^k``, x = t/scale (Chase & Greenwood 1988), and its
exponent-1 case ``c = a0 + a1/x``.

One model, the exponent a parameter: :class:`ReciprocalPowerCost` fits ``k`` with the other two
coefficients; :class:`ReciprocalCost` (``k = 1``, Chase & Greenwood 1988) and
:class:`~evotol.cost_models.reciprocal_square.ReciprocalSquareCost` (``k = 2``, Spotts 1973) are the same
model with the exponent fixed by the class (same registry names, same coefficients ``a0, a1``).
"""
from __future__ import annotations

from typing import ClassVar

import numpy as np

from evotol.cost_models.base import CostModel
from evotol.errors import ValidationError

#: exponents tried by :meth:`ReciprocalPowerCost.initial_guess` when ``k`` is fitted
_GUESS_EXPONENTS = (0.5, 1.0, 1.5, 2.0, 2.5, 3.0)


class ReciprocalPowerCost(CostModel):
    """Reciprocal-power cost ``c = a0 + a1/x^k``, ``x = t / scale`` (Chase & Greenwood 1988).

    Decreasing and convex for ``a1 > 0`` and ``k > 0``; positive where ``a0 + a1/x^k >= 0``
    (checked on a given range). ``a0 = 0`` is :class:`~evotol.cost_models.power.PowerCost`'s formula.

    Parameters
    ----------
    *params : float
        ``a0, a1, k``: ``a0`` the fixed cost (cost units), ``a1 > 0`` the reciprocal coefficient
        (cost units times shop units to the power ``k``), ``k > 0`` the exponent (dimensionless).
    scale : float, default 1.0
        SI size (m or rad) of the tolerance unit the coefficients refer to, e.g. ``1e-5`` m.
    t_min : float, optional
        Smallest tolerance used (SI). When ``t_min`` or ``t_max`` is given, the construction
        checks that the cost is non-negative and non-increasing on the range
        (:meth:`~evotol.cost_models.base.CostModel.validate_range`); a missing ``t_min`` then means 0.
    t_max : float, optional
        Largest tolerance used (SI); missing while ``t_min`` is given means ``100 * scale``.
    **kw : float
        The coefficients by name (``a0=..., a1=..., k=...``) instead of positionally, not both.

    Raises
    ------
    ValidationError
        ``a1 <= 0`` or ``k <= 0``. Coefficients missing, unknown or not finite, ``scale`` not
        positive, or the cost negative or increasing on a given range (as for every
        :class:`~evotol.cost_models.base.CostModel`).
    """

    name = "reciprocal_power"
    param_names = ("a0", "a1", "k")
    example_params = (0.2, 1.5, 1.5)
    formula = "a0 + a1/x^k"
    #: the exponent when the class fixes it (then ``k`` is no coefficient); None: ``k`` is the
    #: third coefficient
    fixed_exponent: ClassVar[int | float | None] = None

    @property
    def exponent(self) -> float:
        """The exponent ``k`` (dimensionless): the class's ``fixed_exponent`` or the coefficient ``k``."""
        return self.p[2] if self.fixed_exponent is None else self.fixed_exponent

    def _check_params(self):
        if self.p[1] <= 0:
            raise ValidationError(f"{self.name}.a1", self.p[1], "a positive coefficient (a1 <= 0 makes cost increase with t)")
        if self.fixed_exponent is None and self.p[2] <= 0:
            raise ValidationError(f"{self.name}.k", self.p[2], "a positive exponent (k <= 0 makes cost increase with t)")

    def _f(self, x):
        return self.p[0] + self.p[1] / x ** self.exponent

    def _df(self, x):
        k = self.exponent
        return -k * self.p[1] / x ** (k + 1)

    def _d2f(self, x):
        k = self.exponent
        return k * (k + 1) * self.p[1] / x ** (k + 2)

    @classmethod
    def _guess(cls, x, c):
        # linear least squares in (a0, a1) at the fixed exponent, or at the best of a few exponents
        best = None
        for k in (_GUESS_EXPONENTS if cls.fixed_exponent is None else (cls.fixed_exponent,)):
            A = np.stack([np.ones_like(x), x ** -k], 1)
            sol, res = np.linalg.lstsq(A, c, rcond=None)[:2]
            r = float(res[0]) if res.size else float(np.sum((A @ sol - c) ** 2))
            if best is None or r < best[0]:
                best = (r, sol, k)
        _, sol, k = best
        head = [sol[0], max(sol[1], 1e-9)]
        return np.array(head if cls.fixed_exponent is not None else head + [k])


class ReciprocalCost(ReciprocalPowerCost):
    """Reciprocal cost ``c = a0 + a1/x``, ``x = t / scale`` (Chase & Greenwood 1988):
    :class:`ReciprocalPowerCost` with the exponent fixed at 1.

    Decreasing and convex for ``a1 > 0``; positive where ``a0 + a1/x >= 0`` (checked on a given
    range).

    Parameters
    ----------
    *params : float
        ``a0, a1``: ``a0`` the fixed cost (cost units), ``a1 > 0`` the reciprocal coefficient
        (cost units times shop units).
        ``scale``, ``t_min``, ``t_max`` and the coefficients by name: as for every
        :class:`~evotol.cost_models.base.CostModel`.

    Raises
    ------
    ValidationError
        ``a1 <= 0``. Coefficients missing, unknown or not finite, ``scale`` not positive, or the
        cost negative or increasing on a given range (as for every
        :class:`~evotol.cost_models.base.CostModel`).
    """

    name = "reciprocal"
    param_names = ("a0", "a1")
    example_params = (0.2, 1.5)
    formula = "a0 + a1/x"
    fixed_exponent = 1

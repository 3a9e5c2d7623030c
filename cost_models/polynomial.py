"""Polynomial cost models of 3rd and 4th order ``c = Σ a_k·x^k`` (Dong, Hu & Xue 1994).

Polynomials are monotone and positive only on a range: give ``t_min``/``t_max`` (SI) and the model
checks them (or :meth:`validate_range` is called by the problem with the source's bounds).
"""
import numpy as np

from evotol.cost_models.base import CostModel


class _Polynomial(CostModel):
    convex = False  # depends on the coefficients and the range: see is_convex()

    def _f(self, x):
        return np.polynomial.polynomial.polyval(x, self.p)

    def _df(self, x):
        return np.polynomial.polynomial.polyval(x, np.polynomial.polynomial.polyder(self.p))

    def _d2f(self, x):
        return np.polynomial.polynomial.polyval(x, np.polynomial.polynomial.polyder(self.p, 2))

    @classmethod
    def _guess(cls, x, c):
        # the polynomial is linear in its coefficients: ordinary least squares
        return np.polynomial.polynomial.polyfit(x, c, len(cls.param_names) - 1)


class Polynomial3Cost(_Polynomial):
    """Cubic cost ``c = a0 + a1·x + a2·x² + a3·x³``, ``x = t / scale`` (Dong, Hu & Xue 1994).

    Positive and decreasing only on a range: give ``t_min``/``t_max``. Not flagged convex
    (``convex = False``); :meth:`~evotol.cost_models.base.CostModel.is_convex` checks a range.

    Parameters
    ----------
    *params : float
        ``a0, a1, a2, a3``: ``a_k`` the coefficient of ``x^k`` (cost units per shop unit to the
        power k).
        ``scale``, ``t_min``, ``t_max`` and the coefficients by name: as for every
        :class:`~evotol.cost_models.base.CostModel`.

    Raises
    ------
    ValidationError
        Coefficients missing, unknown or not finite, ``scale`` not positive, or the cost negative
        or increasing on a given range (as for every :class:`~evotol.cost_models.base.CostModel`).
    """

    name = "polynomial3"
    param_names = ("a0", "a1", "a2", "a3")
    example_params = (10.0, -3.0, 0.3, -0.01)
    formula = "a0 + a1·x + a2·x² + a3·x³"


class Polynomial4Cost(_Polynomial):
    """Quartic cost ``c = a0 + a1·x + a2·x² + a3·x³ + a4·x⁴``, ``x = t / scale`` (Dong, Hu & Xue 1994).

    Positive and decreasing only on a range: give ``t_min``/``t_max``. Not flagged convex
    (``convex = False``); :meth:`~evotol.cost_models.base.CostModel.is_convex` checks a range.

    Parameters
    ----------
    *params : float
        ``a0, ..., a4``: ``a_k`` the coefficient of ``x^k`` (cost units per shop unit to the
        power k).
        ``scale``, ``t_min``, ``t_max`` and the coefficients by name: as for every
        :class:`~evotol.cost_models.base.CostModel`.

    Raises
    ------
    ValidationError
        Coefficients missing, unknown or not finite, ``scale`` not positive, or the cost negative
        or increasing on a given range (as for every :class:`~evotol.cost_models.base.CostModel`).
    """

    name = "polynomial4"
    param_names = ("a0", "a1", "a2", "a3", "a4")
    example_params = (12.0, -4.0, 0.6, -0.04, 0.0009)
    formula = "a0 + a1·x + a2·x² + a3·x³ + a4·x⁴"

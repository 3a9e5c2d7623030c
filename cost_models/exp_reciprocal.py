"""Exponential-reciprocal power model ``c = a0·x^(-a1)·exp(-a2·x)`` (Michael & Siddall 1981)."""
import numpy as np

from evotol.cost_models.base import CostModel
from evotol.errors import ValidationError


class ExpReciprocalCost(CostModel):
    """Exponential-reciprocal power cost ``c = a0·x^(-a1)·exp(-a2·x)``, ``x = t / scale`` (Michael & Siddall 1981).

    Positive, decreasing and convex for every valid parameter set.

    Parameters
    ----------
    *params : float
        ``a0, a1, a2``: ``a0 > 0`` the cost coefficient (cost units), ``a1 >= 0`` the power
        exponent (dimensionless), ``a2 >= 0`` the exponential rate (per shop unit); ``a1`` and
        ``a2`` not both zero.
        ``scale``, ``t_min``, ``t_max`` and the coefficients by name: as for every
        :class:`~evotol.cost_models.base.CostModel`.

    Raises
    ------
    ValidationError
        ``a0 <= 0``, ``a1`` or ``a2`` negative, or both zero. Coefficients missing, unknown or not
        finite, ``scale`` not positive, or the cost negative or increasing on a given range (as for
        every :class:`~evotol.cost_models.base.CostModel`).
    """

    name = "exp_reciprocal"
    param_names = ("a0", "a1", "a2")
    example_params = (1.0, 0.5, 0.2)
    formula = "a0·x^(-a1)·exp(-a2·x)"

    def _check_params(self):
        a0, a1, a2 = self.p
        if a0 <= 0:
            raise ValidationError("exp_reciprocal.a0", a0, "a positive cost coefficient")
        if a1 < 0 or a2 < 0 or (a1 == 0 and a2 == 0):
            raise ValidationError("exp_reciprocal.(a1, a2)", (a1, a2), "a1 >= 0 and a2 >= 0, not both zero (else cost does not decrease)")

    def _f(self, x):
        a0, a1, a2 = self.p
        return a0 * np.power(x, -a1) * np.exp(-a2 * x)

    def _df(self, x):
        a0, a1, a2 = self.p
        return -self._f(x) * (a1 / x + a2)

    def _d2f(self, x):
        a0, a1, a2 = self.p
        return self._f(x) * ((a1 / x + a2) ** 2 + a1 / x ** 2)

    @classmethod
    def _guess(cls, x, c):
        # linear least squares of log c = log a0 - a1·log x - a2·x
        A = np.stack([np.ones_like(x), -np.log(x), -x], 1)
        sol = np.linalg.lstsq(A, np.log(np.maximum(c, 1e-300)), rcond=None)[0]
        return np.array([np.exp(sol[0]), max(sol[1], 0.0), max(sol[2], 0.0)])

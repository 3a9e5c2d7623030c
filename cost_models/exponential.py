"""Exponential ("index") cost model ``c = a0·exp(-a1·x)``, x = t/scale (Yao et al. 2013 eq. 13)."""
import numpy as np

from evotol.cost_models.base import CostModel
from evotol.errors import ValidationError


class ExponentialCost(CostModel):
    """Exponential ("index") cost ``c = a0·exp(-a1·x)``, ``x = t / scale`` (Yao et al. 2013 eq. 13).

    Positive, decreasing and convex for every valid parameter set.

    Parameters
    ----------
    *params : float
        ``a0, a1``: ``a0 > 0`` the cost at ``x = 0`` (cost units), ``a1 > 0`` the decay rate
        (per shop unit of tolerance).
        ``scale``, ``t_min``, ``t_max`` and the coefficients by name: as for every
        :class:`~evotol.cost_models.base.CostModel`.

    Raises
    ------
    ValidationError
        ``a0 <= 0`` or ``a1 <= 0``. Coefficients missing, unknown or not finite, ``scale`` not
        positive, or the cost negative or increasing on a given range (as for every
        :class:`~evotol.cost_models.base.CostModel`).
    """

    name = "exponential"
    param_names = ("a0", "a1")
    example_params = (1.9, 0.5)   # Yao et al. 2013 eq. 13, lengths
    formula = "a0·exp(-a1·x)"

    def _check_params(self):
        a0, a1 = self.p
        if a0 <= 0:
            raise ValidationError("exponential.a0", a0, "a positive cost coefficient (a0 <= 0 makes cost non-positive)")
        if a1 <= 0:
            raise ValidationError("exponential.a1", a1, "a positive decay rate (a1 <= 0 makes cost increase with t)")

    def _f(self, x):
        return self.p[0] * np.exp(-self.p[1] * x)

    def _df(self, x):
        return -self.p[1] * self._f(x)

    def _d2f(self, x):
        return self.p[1] ** 2 * self._f(x)

    @classmethod
    def _guess(cls, x, c):
        # log-linear least squares: log c = log a0 - a1·x
        k, b = np.polyfit(x, np.log(np.maximum(c, 1e-300)), 1)
        return np.array([np.exp(b), max(-k, 1e-6)])

"""Power cost model ``c = a0·x^(-a1)``, x = t/scale (Speckhart / Chase–Greenwood reciprocal power)."""
import numpy as np

from evotol.cost_models.base import CostModel
from evotol.errors import ValidationError


class PowerCost(CostModel):
    """Reciprocal power cost ``c = a0·x^(-a1)``, ``x = t / scale`` (Speckhart; Chase & Greenwood).

    Positive, decreasing and convex for every valid parameter set.

    Parameters
    ----------
    *params : float
        ``a0, a1``: ``a0 > 0`` the cost at ``x = 1`` (cost units), ``a1 > 0`` the exponent
        (dimensionless).
        ``scale``, ``t_min``, ``t_max`` and the coefficients by name: as for every
        :class:`~evotol.cost_models.base.CostModel`.

    Raises
    ------
    ValidationError
        ``a0 <= 0`` or ``a1 <= 0``. Coefficients missing, unknown or not finite, ``scale`` not
        positive, or the cost negative or increasing on a given range (as for every
        :class:`~evotol.cost_models.base.CostModel`).
    """

    name = "power"
    param_names = ("a0", "a1")
    example_params = (2.0, 1.3)
    formula = "a0·x^(-a1)"

    def _check_params(self):
        a0, a1 = self.p
        if a0 <= 0:
            raise ValidationError("power.a0", a0, "a positive cost coefficient")
        if a1 <= 0:
            raise ValidationError("power.a1", a1, "a positive exponent (a1 <= 0 makes cost increase with t)")

    def _f(self, x):
        return self.p[0] * np.power(x, -self.p[1])

    def _df(self, x):
        return -self.p[1] * self.p[0] * np.power(x, -self.p[1] - 1)

    def _d2f(self, x):
        a0, a1 = self.p
        return a1 * (a1 + 1) * a0 * np.power(x, -a1 - 2)

    @classmethod
    def _guess(cls, x, c):
        # log-log least squares: log c = log a0 - a1·log x
        k, b = np.polyfit(np.log(x), np.log(np.maximum(c, 1e-300)), 1)
        return np.array([np.exp(b), max(-k, 1e-6)])

"""Reciprocal-square ("negative square") cost model ``c = a0 + a1/x²``, x = t/scale (Spotts 1973)."""
from cost_models.base import CostModel
from evotol.errors import ValidationError


class ReciprocalSquareCost(CostModel):
    """Reciprocal-square ("negative square") cost ``c = a0 + a1/x²``, ``x = t / scale`` (Spotts 1973).

    Decreasing and convex for ``a1 > 0``; positive where ``a0 + a1/x² >= 0`` (checked on a given
    range).

    Parameters
    ----------
    *params : float
        ``a0, a1``: ``a0`` the fixed cost (cost units), ``a1 > 0`` the coefficient (cost units
        times squared shop units).
        ``scale``, ``t_min``, ``t_max`` and the coefficients by name: as for every
        :class:`~cost_models.base.CostModel`.

    Raises
    ------
    ValidationError
        ``a1 <= 0``. Coefficients missing, unknown or not finite, ``scale`` not positive, or the
        cost negative or increasing on a given range (as for every
        :class:`~cost_models.base.CostModel`).
    """

    name = "reciprocal_square"
    param_names = ("a0", "a1")
    example_params = (0.1, 2.0)
    formula = "a0 + a1/x²"

    def _check_params(self):
        if self.p[1] <= 0:
            raise ValidationError("reciprocal_square.a1", self.p[1], "a positive coefficient (a1 <= 0 makes cost increase with t)")

    def _f(self, x):
        return self.p[0] + self.p[1] / x ** 2

    def _df(self, x):
        return -2 * self.p[1] / x ** 3

    def _d2f(self, x):
        return 6 * self.p[1] / x ** 4

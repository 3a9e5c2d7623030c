"""Reciprocal cost model ``c = a0 + a1/x``, x = t/scale (Chase & Greenwood 1988)."""
from cost_models.base import CostModel
from evotol.errors import ValidationError


class ReciprocalCost(CostModel):
    """Reciprocal cost ``c = a0 + a1/x``, ``x = t / scale`` (Chase & Greenwood 1988).

    Decreasing and convex for ``a1 > 0``; positive where ``a0 + a1/x >= 0`` (checked on a given
    range).

    Parameters
    ----------
    *params : float
        ``a0, a1``: ``a0`` the fixed cost (cost units), ``a1 > 0`` the reciprocal coefficient
        (cost units times shop units).
        ``scale``, ``t_min``, ``t_max`` and the coefficients by name: as for every
        :class:`~cost_models.base.CostModel`.

    Raises
    ------
    ValidationError
        ``a1 <= 0``. Coefficients missing, unknown or not finite, ``scale`` not positive, or the
        cost negative or increasing on a given range (as for every
        :class:`~cost_models.base.CostModel`).
    """

    name = "reciprocal"
    param_names = ("a0", "a1")
    example_params = (0.2, 1.5)
    formula = "a0 + a1/x"

    def _check_params(self):
        if self.p[1] <= 0:
            raise ValidationError("reciprocal.a1", self.p[1], "a positive coefficient (a1 <= 0 makes cost increase with t)")

    def _f(self, x):
        return self.p[0] + self.p[1] / x

    def _df(self, x):
        return -self.p[1] / x ** 2

    def _d2f(self, x):
        return 2 * self.p[1] / x ** 3

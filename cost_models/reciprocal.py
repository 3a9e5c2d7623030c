"""Reciprocal cost model ``c = a0 + a1/x``, x = t/scale (Chase & Greenwood 1988)."""
from cost_models.base import CostModel
from evotol.errors import ValidationError


class ReciprocalCost(CostModel):
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

"""Reciprocal-square ("negative square") cost model ``c = a0 + a1/x²``, x = t/scale (Spotts 1973)."""
from cost_models.base import CostModel
from evotol.errors import ValidationError


class ReciprocalSquareCost(CostModel):
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

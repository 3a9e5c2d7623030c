"""Exponential ("index") cost model ``c = a0·exp(-a1·x)``, x = t/scale (Yao et al. 2013 eq. 13)."""
import numpy as np

from cost_models.base import CostModel
from evotol.errors import ValidationError


class ExponentialCost(CostModel):
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

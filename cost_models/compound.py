"""Compound cost models: linear + exponential (Dong, Hu & Xue 1994) and sums of any models."""
from __future__ import annotations

import numpy as np

from cost_models.base import CostModel
from evotol.errors import ValidationError


class LinearExponentialCost(CostModel):
    """``c = a0 + a1·x + a2·exp(-a3·x)``: the linear + exponential hybrid of Dong, Hu & Xue (1994).

    Monotone decreasing needs a1 <= 0 or a range check (``t_max``); convex for a2, a3 >= 0.
    """

    name = "linear_exponential"
    param_names = ("a0", "a1", "a2", "a3")
    example_params = (0.5, -0.01, 3.0, 0.4)
    formula = "a0 + a1·x + a2·exp(-a3·x)"

    def _check_params(self):
        a0, a1, a2, a3 = self.p
        if a2 < 0 or a3 < 0:
            raise ValidationError("linear_exponential.(a2, a3)", (a2, a3), "a2 >= 0 and a3 >= 0")
        if a1 > 0 and a2 * a3 == 0:
            raise ValidationError("linear_exponential.a1", a1, "a1 <= 0 when the exponential term vanishes")

    def _f(self, x):
        a0, a1, a2, a3 = self.p
        return a0 + a1 * x + a2 * np.exp(-a3 * x)

    def _df(self, x):
        a0, a1, a2, a3 = self.p
        return a1 - a2 * a3 * np.exp(-a3 * x)

    def _d2f(self, x):
        a0, a1, a2, a3 = self.p
        return a2 * a3 ** 2 * np.exp(-a3 * x)


class SumCost(CostModel):
    """Sum of cost models (e.g. machining + inspection), each with its own scale."""

    name = "sum"
    param_names = ()

    def __init__(self, *models: CostModel):
        if not models or not all(isinstance(m, CostModel) for m in models):
            raise ValidationError("SumCost models", models, "one or more CostModel instances")
        self.models = tuple(models)
        self.p = np.zeros(0)
        self.scale = 1.0
        self.convex = all(m.convex for m in models)

    @property
    def params(self):
        return {f"{i}.{m.name}.{k}": v for i, m in enumerate(self.models) for k, v in m.params.items()}

    def cost(self, t):
        return sum(m.cost(t) for m in self.models)

    def dcost(self, t):
        return sum(m.dcost(t) for m in self.models)

    def d2cost(self, t):
        return sum(m.d2cost(t) for m in self.models)

    __call__ = cost

    def to_dict(self):
        return {"model": "sum", "terms": [m.to_dict() for m in self.models]}

    def __repr__(self):
        return "SumCost(" + ", ".join(map(repr, self.models)) + ")"

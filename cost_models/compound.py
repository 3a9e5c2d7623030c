"""Compound cost models: linear + exponential (Dong, Hu & Xue 1994) and sums of any models."""
from __future__ import annotations

import numpy as np

from evotol.cost_models.base import CostModel
from evotol.errors import ValidationError


class LinearExponentialCost(CostModel):
    """``c = a0 + a1·x + a2·exp(-a3·x)``: the linear + exponential hybrid of Dong, Hu & Xue (1994).

    Monotone decreasing needs a1 <= 0 or a range check (``t_max``); convex for a2, a3 >= 0.

    Parameters
    ----------
    *params : float
        ``a0, a1, a2, a3``: ``a0`` the fixed cost (cost units), ``a1`` the linear slope (cost
        units per shop unit), ``a2 >= 0`` the exponential amplitude (cost units), ``a3 >= 0`` its
        decay rate (per shop unit).
        ``scale``, ``t_min``, ``t_max`` and the coefficients by name: as for every
        :class:`~evotol.cost_models.base.CostModel`.

    Raises
    ------
    ValidationError
        ``a2 < 0`` or ``a3 < 0``; ``a1 > 0`` while ``a2·a3 = 0``. Coefficients missing, unknown or
        not finite, ``scale`` not positive, or the cost negative or increasing on a given range
        (as for every :class:`~evotol.cost_models.base.CostModel`).
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

    @classmethod
    def _guess(cls, x, c):
        # the exponential term alone, log-linear least squares (a0 = a1 = 0)
        k, b = np.polyfit(x, np.log(np.maximum(c, 1e-300)), 1)
        return np.array([0.0, 0.0, np.exp(b), max(-k, 1e-6)])


class SumCost(CostModel):
    """Sum of cost models (e.g. machining + inspection), each with its own scale.

    Convex (``convex``) when every term is. Its own ``scale`` is 1.0 (each term keeps its own).

    Parameters
    ----------
    *models : CostModel
        The terms, one or more, each a function of the same SI tolerance ``t``.

    Raises
    ------
    ValidationError
        No model given, or a term that is not a :class:`~evotol.cost_models.base.CostModel`.
    """

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
        """The terms' coefficients, keyed ``"<index>.<model name>.<coefficient>"``."""
        return {f"{i}.{m.name}.{k}": v for i, m in enumerate(self.models) for k, v in m.params.items()}

    def cost(self, t):
        """Sum of the terms' costs at tolerance ``t`` (SI)."""
        return sum(m.cost(t) for m in self.models)

    def dcost(self, t):
        """Sum of the terms' d cost / d t."""
        return sum(m.dcost(t) for m in self.models)

    def d2cost(self, t):
        """Sum of the terms' d² cost / d t²."""
        return sum(m.d2cost(t) for m in self.models)

    __call__ = cost

    def to_dict(self):
        """The sum as ``{"model": "sum", "terms": [<each term's to_dict()>, ...]}``."""
        return {"model": "sum", "terms": [m.to_dict() for m in self.models]}

    def __repr__(self):
        return "SumCost(" + ", ".join(map(repr, self.models)) + ")"

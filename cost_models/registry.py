"""Registry of cost models by name (built-ins plus entry points), and construction from dicts/TOML."""
from __future__ import annotations

from cost_models.base import CostModel
from cost_models.compound import LinearExponentialCost, SumCost
from cost_models.exp_reciprocal import ExpReciprocalCost
from cost_models.exponential import ExponentialCost
from cost_models.polynomial import Polynomial3Cost, Polynomial4Cost
from cost_models.power import PowerCost
from cost_models.reciprocal import ReciprocalCost
from cost_models.reciprocal_square import ReciprocalSquareCost
from evotol.errors import ValidationError

BUILTIN: dict[str, type[CostModel]] = {
    cls.name: cls
    for cls in (ExponentialCost, PowerCost, ReciprocalCost, ReciprocalSquareCost, ExpReciprocalCost,
                Polynomial3Cost, Polynomial4Cost, LinearExponentialCost)
}
ALIASES = {"index": "exponential", "negative_square": "reciprocal_square", "michael_siddall": "exp_reciprocal",
           "compound": "linear_exponential"}


def available() -> dict[str, type[CostModel]]:
    from cost_models.user import entry_point_models

    return {**BUILTIN, **entry_point_models()}


def get(name: str) -> type[CostModel]:
    name = ALIASES.get(name, name)
    models = available()
    if name not in models:
        raise ValidationError("cost model", name, f"one of {sorted(models)} (aliases {sorted(ALIASES)})")
    return models[name]


def from_dict(spec: dict) -> CostModel:
    """Build a model from ``{"model": "exponential", "a0": 1.9, "a1": 0.5, "scale": 1e-5}``;
    ``{"model": "sum", "terms": [...]}`` builds a :class:`SumCost`."""
    if not isinstance(spec, dict) or "model" not in spec:
        raise ValidationError("cost", spec, "a table with a 'model' key")
    spec = dict(spec)
    name = spec.pop("model")
    if name == "sum":
        return SumCost(*(from_dict(s) for s in spec.get("terms", [])))
    cls = get(name)
    scale = spec.pop("scale", 1.0)
    return cls(scale=scale, **spec)

"""Registry of cost models by name (built-ins plus entry points), and construction from dicts/TOML."""
from __future__ import annotations

from evotol.cost_models.base import CostModel
from evotol.cost_models.compound import LinearExponentialCost, SumCost
from evotol.cost_models.exp_reciprocal import ExpReciprocalCost
from evotol.cost_models.exponential import ExponentialCost
from evotol.cost_models.polynomial import Polynomial3Cost, Polynomial4Cost
from evotol.cost_models.power import PowerCost
from evotol.cost_models.reciprocal import ReciprocalCost, ReciprocalPowerCost
from evotol.cost_models.reciprocal_square import ReciprocalSquareCost
from evotol.errors import ValidationError

BUILTIN: dict[str, type[CostModel]] = {
    cls.name: cls
    for cls in (ExponentialCost, PowerCost, ReciprocalPowerCost, ReciprocalCost, ReciprocalSquareCost, ExpReciprocalCost,
                Polynomial3Cost, Polynomial4Cost, LinearExponentialCost)
}
ALIASES = {"index": "exponential", "negative_square": "reciprocal_square", "michael_siddall": "exp_reciprocal",
           "compound": "linear_exponential"}


def available() -> dict[str, type[CostModel]]:
    """Every cost model a study file can name: the built-ins and the installed entry points.

    Returns
    -------
    dict of str to type
        ``{name: CostModel subclass}``; an entry point of the same name replaces a built-in.
        Aliases (``ALIASES``) are not keys.

    Raises
    ------
    ValidationError
        An entry point of the group ``evotol.cost_models`` is not a CostModel subclass (from
        :func:`evotol.cost_models.user.entry_point_models`).
    """
    from evotol.cost_models.user import entry_point_models

    return {**BUILTIN, **entry_point_models()}


def get(name: str) -> type[CostModel]:
    """The cost-model class of a name or alias (``"index"`` is ``"exponential"``, ...).

    Parameters
    ----------
    name : str
        A name of :func:`available` or an alias of ``ALIASES``.

    Returns
    -------
    type
        The :class:`~evotol.cost_models.base.CostModel` subclass.

    Raises
    ------
    ValidationError
        The name is unknown (the message lists the names and aliases).
    """
    name = ALIASES.get(name, name)
    models = available()
    if name not in models:
        raise ValidationError("cost model", name, f"one of {sorted(models)} (aliases {sorted(ALIASES)})")
    return models[name]


def from_dict(spec: dict) -> CostModel:
    """Build a model from ``{"model": "exponential", "a0": 1.9, "a1": 0.5, "scale": 1e-5}``;
    ``{"model": "sum", "terms": [...]}`` builds a :class:`SumCost`.

    Parameters
    ----------
    spec : dict
        ``"model"``: a name or alias (see :func:`get`) or ``"sum"``; the coefficients by name
        (shop units); ``"scale"`` (SI size of the shop unit, default 1.0); for a sum,
        ``"terms"``: a list of such tables.

    Returns
    -------
    CostModel
        The model built (a :class:`SumCost` for ``"sum"``).

    Raises
    ------
    ValidationError
        ``spec`` is not a dict with a ``"model"`` key, the name is unknown, or the model rejects
        its coefficients (unknown, missing, invalid) or ``scale``; a sum without terms.
    """
    if not isinstance(spec, dict) or "model" not in spec:
        raise ValidationError("cost", spec, "a table with a 'model' key")
    spec = dict(spec)
    name = spec.pop("model")
    if name == "sum":
        return SumCost(*(from_dict(s) for s in spec.get("terms", [])))
    cls = get(name)
    scale = spec.pop("scale", 1.0)
    return cls(scale=scale, **spec)

"""Reciprocal-square ("negative square") cost model ``c = a0 + a1/x²``, x = t/scale (Spotts 1973):
the reciprocal-power model (:mod:`evotol.cost_models.reciprocal`) with the exponent fixed at 2."""
from evotol.cost_models.reciprocal import ReciprocalPowerCost


class ReciprocalSquareCost(ReciprocalPowerCost):
    """Reciprocal-square ("negative square") cost ``c = a0 + a1/x²``, ``x = t / scale`` (Spotts 1973):
    :class:`~evotol.cost_models.reciprocal.ReciprocalPowerCost` with the exponent fixed at 2.

    Decreasing and convex for ``a1 > 0``; positive where ``a0 + a1/x² >= 0`` (checked on a given
    range).

    Parameters
    ----------
    *params : float
        ``a0, a1``: ``a0`` the fixed cost (cost units), ``a1 > 0`` the coefficient (cost units
        times squared shop units).
        ``scale``, ``t_min``, ``t_max`` and the coefficients by name: as for every
        :class:`~evotol.cost_models.base.CostModel`.

    Raises
    ------
    ValidationError
        ``a1 <= 0``. Coefficients missing, unknown or not finite, ``scale`` not positive, or the
        cost negative or increasing on a given range (as for every
        :class:`~evotol.cost_models.base.CostModel`).
    """

    name = "reciprocal_square"
    param_names = ("a0", "a1")
    example_params = (0.1, 2.0)
    formula = "a0 + a1/x²"
    fixed_exponent = 2

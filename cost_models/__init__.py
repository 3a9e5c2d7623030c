"""Cost–tolerance models (plugins): one model per module, one protocol, one registry.

>>> from cost_models import ExponentialCost
>>> m = ExponentialCost(1.9, 0.5, scale=1e-5)   # Yao et al. 2013: tolerances in units of 1e-5 m
>>> round(float(m.cost(4.94e-5)), 4)
0.1607
"""
from cost_models.base import CostModel
from cost_models.checks import check_cost_model, cost_model_checks
from cost_models.compound import LinearExponentialCost, SumCost
from cost_models.exp_reciprocal import ExpReciprocalCost
from cost_models.exponential import ExponentialCost
from cost_models.fit import FitResult, fit
from cost_models.polynomial import Polynomial3Cost, Polynomial4Cost
from cost_models.power import PowerCost
from cost_models.reciprocal import ReciprocalCost, ReciprocalPowerCost
from cost_models.reciprocal_square import ReciprocalSquareCost
from cost_models.registry import available, from_dict, get
from cost_models.user import CallableCost

__all__ = ["CostModel", "check_cost_model", "ExponentialCost", "PowerCost", "ReciprocalPowerCost", "ReciprocalCost",
           "ReciprocalSquareCost", "ExpReciprocalCost", "Polynomial3Cost", "Polynomial4Cost",
           "LinearExponentialCost", "SumCost", "CallableCost", "fit", "FitResult", "available",
           "get", "from_dict"]

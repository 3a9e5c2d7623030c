"""Cost–tolerance models (plugins): one model per module, one protocol, one registry.

>>> from evotol.cost_models import ExponentialCost
>>> m = ExponentialCost(1.9, 0.5, scale=1e-5)   # Yao et al. 2013: tolerances in units of 1e-5 m
>>> round(float(m.cost(4.94e-5)), 4)
0.1607
"""
from evotol.cost_models.base import CostModel
from evotol.cost_models.checks import check_cost_model, cost_model_checks
from evotol.cost_models.compound import LinearExponentialCost, SumCost
from evotol.cost_models.exp_reciprocal import ExpReciprocalCost
from evotol.cost_models.exponential import ExponentialCost
from evotol.cost_models.fit import FitResult, fit
from evotol.cost_models.polynomial import Polynomial3Cost, Polynomial4Cost
from evotol.cost_models.power import PowerCost
from evotol.cost_models.reciprocal import ReciprocalCost, ReciprocalPowerCost
from evotol.cost_models.reciprocal_square import ReciprocalSquareCost
from evotol.cost_models.registry import available, from_dict, get
from evotol.cost_models.user import CallableCost

__all__ = ["CostModel", "check_cost_model", "ExponentialCost", "PowerCost", "ReciprocalPowerCost", "ReciprocalCost",
           "ReciprocalSquareCost", "ExpReciprocalCost", "Polynomial3Cost", "Polynomial4Cost",
           "LinearExponentialCost", "SumCost", "CallableCost", "fit", "FitResult", "available",
           "get", "from_dict"]

"""Statistical tolerancing: the probability that the end-effector error stays inside its bound.

This package only hands names on: the probability that a 3-D normal error leaves a ball and its
k-sigma equivalent are in :mod:`evotol.measures.statistical.normal_miss`, the first-order yield model of the
``yield`` measure in :mod:`evotol.measures.statistical.first_order`, and the sampled yield of the nonlinear
model in :mod:`evotol.measures.statistical.sampled` (``docs/statistical.md``).

The parameters several definitions of this package share are described once, here.

Parameters
----------
T : array_like, shape (n_designs, n_sources) or (n_sources,)
    Designs (SI: m or rad).
"""
from evotol.measures.statistical.first_order import FirstOrderYield, YieldResult
from evotol.measures.statistical.normal_miss import (chi3_cdf, chi3_survival, k_equivalent, miss_probability,
                                            required_probability, sym3_eigenvalues)
from evotol.measures.statistical.normal_miss import octant_rule, sphere_rule  # noqa: F401  (cached rules, not listed)
from evotol.measures.statistical.sampled import SampledYield, pose_error_nan

__all__ = ["chi3_survival", "chi3_cdf", "sym3_eigenvalues", "miss_probability", "k_equivalent",
           "required_probability", "YieldResult", "FirstOrderYield", "pose_error_nan", "SampledYield"]

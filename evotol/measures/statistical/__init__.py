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
dists : sequence of evotol.measures.statistical.distributions.Distribution
    Each source's distribution inside its tolerance.
bounds : dict of str to float or None
    Component -> bound E (m or rad); None components are not constrained.
radial : str
    Radial law of disk/ball sources (one of ``evotol.measures.statistical.distributions.RADIAL``).
shift : tuple of three array_like, shape (n_sources,), optional
    ``(rho, kappa, offset)`` of asymmetric intervals (dimensionless, dimensionless, SI);
    None: centred ±t.
probability : float
    Required yield p, in (0, 1).
"""
from evotol.measures.statistical.first_order import FirstOrderYield, YieldResult
from evotol.measures.statistical.normal_miss import (chi3_cdf, chi3_survival, k_equivalent, miss_probability,
                                            required_probability, sym3_eigenvalues)
from evotol.measures.statistical.normal_miss import octant_rule, sphere_rule  # noqa: F401  (cached rules, not listed)
from evotol.measures.statistical.sampled import SampledYield, pose_error_nan

__all__ = ["chi3_survival", "chi3_cdf", "sym3_eigenvalues", "miss_probability", "k_equivalent",
           "required_probability", "YieldResult", "FirstOrderYield", "pose_error_nan", "SampledYield"]

"""The printed results of Brahmia et al. 2023 in SI units: Tables A1-A2 and 3
(transcribed in :mod:`evotol.studies._brahmia2023_delta_data`) and the lower limits of eq. (12)
read off Tables A1-A2.

Paper units: mm for the linear parameters, degrees for the angular ones; SI: m and rad, in
:data:`evotol.robots.delta.PARAMETER_NAMES` order.
"""
from __future__ import annotations

import numpy as np

from evotol.studies._brahmia2023_delta_data import TABLE_3, TABLE_A
from evotol.robots.delta import PARAMETER_NAMES
from evotol.robots.delta_synthesis import IS_LINEAR, SYNTHESIS_POSTURES

#: SI -> paper units (mm for linear, degrees for angular)
TO_PAPER = np.where(IS_LINEAR, 1e3, 180 / np.pi)


def inferred_min_magnitude() -> np.ndarray:
    """Lower limits of eq. (12) read off Tables A1-A2 (SI, (47,)): 0.0095 mm and 0.001 deg.

    The paper does not print ΔL_min, Δφ_min; in its 24 solutions every linear value has
    ``|v| >= 0.0095 mm`` and every angular one ``|v| >= 0.00104 deg``, with many values pinned at exactly
    0.00958 mm / 0.00104 deg (P1, test 1) -- an interior-point solution sitting on a lower bound.

    Returns
    -------
    (47,) ndarray
        Lower limit of ``|Δ|`` per parameter, in :data:`evotol.robots.delta.PARAMETER_NAMES` order:
        9.5e-6 m for the linear parameters, ``radians(0.001)`` rad for the angular ones.
    """
    return np.where(IS_LINEAR, 0.0095e-3, np.radians(0.001))


def table3_si() -> tuple[np.ndarray, np.ndarray]:
    """The paper's Table 3 intervals in SI, (lower, upper) arrays (47,).

    Returns
    -------
    lower, upper : (47,) ndarray
        Interval limits per parameter in :data:`evotol.robots.delta.PARAMETER_NAMES` order, m (linear)
        or rad (angular).
    """
    t = np.array([TABLE_3[n] for n in PARAMETER_NAMES])
    return t[:, 0] / TO_PAPER, t[:, 1] / TO_PAPER


def table_a_si() -> np.ndarray:
    """The paper's Tables A1-A2 as (24 runs, 47) SI values, runs ordered P1, P3, P6, P9 x tests 1..6.

    Returns
    -------
    (24, 47) ndarray
        Printed solutions of problem (12), m (linear parameters) or rad (angular).
    """
    return np.concatenate([np.array(TABLE_A[p]).T for p in SYNTHESIS_POSTURES], axis=0) / TO_PAPER


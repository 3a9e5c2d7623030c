"""Accuracy measures of a linear error model: worst case (exact) and RSS.

This package only hands names on: the worst-case and RSS stack-ups are in
:mod:`evotol.measures.linear.stackup`, the support function with asymmetric intervals (interval shape,
mean shift, support coefficients) in :mod:`evotol.measures.linear.support`, and the direction grids with
their covering angle in :mod:`evotol.measures.linear.directions`.

The parameters several definitions of this package share are described once, here.

Parameters
----------
blocks : list of ndarray, each shape (n_poses, 3, dim_j)
    Sensitivity blocks B_j of one component (m or rad per unit of source error).
"""
from evotol.measures.linear.directions import circle, directions_for
from evotol.measures.linear.directions import hemisphere  # noqa: F401  (a cached grid, not listed)
from evotol.measures.linear.stackup import WorstCase, refine_direction, rss, spectral_norms, worst_case, worst_case_errors
from evotol.measures.linear.support import IntervalShape, mean_shift, support_coefficients, support_constant
from evotol.measures.linear.pose_blocks import PoseBlocks, worst_case_by_blocks

__all__ = ["PoseBlocks", "worst_case_by_blocks", "circle", "directions_for", "WorstCase", "IntervalShape", "mean_shift", "support_coefficients",
           "support_constant", "refine_direction", "worst_case", "worst_case_errors", "spectral_norms", "rss"]

"""ISO 9283 pose accuracy and repeatability of a described mechanism (serial or closed-loop) with systematic
and random sources (issue 44):
the test cube and its poses (:mod:`~evotol.measures.iso9283.poses`), the standard's figures and their
first-order prediction (:mod:`~evotol.measures.iso9283.figures`), the prediction and the simulated test of an
arm (:mod:`~evotol.measures.iso9283.budget`). docs/iso9283.md."""
from evotol.measures.iso9283.budget import APPROACHES, predict, predict_orientation, quantile_interval, simulate
from evotol.measures.iso9283.figures import (ap_worst_case, figures_of_test, gaussian_rp, orientation_figures_of_test,
                                             rp_from_errors)
from evotol.measures.iso9283.poses import TestCube, check_cube, iso_positions, largest_cube

__all__ = ["APPROACHES", "TestCube", "ap_worst_case", "check_cube", "figures_of_test", "gaussian_rp", "iso_positions",
           "largest_cube", "orientation_figures_of_test", "predict", "predict_orientation", "quantile_interval",
           "rp_from_errors", "simulate"]

"""Calibrated robots: tolerances that calibration will fix are not paid for twice (issue 36, ``docs/calibration.md``).

* :mod:`evotol.calibration.plan` -- the plan (configurations, measured components, noise, identified sources);
* :mod:`evotol.calibration.configurations` -- its configurations as joint values;
* :mod:`evotol.calibration.identification` -- the identification Jacobian, base set, ``M``, noise covariance;
* :mod:`evotol.calibration.model` -- the calibrated robot error model and the noise's share of the requirement;
* :mod:`evotol.calibration.linear_range` -- upper bounds of the identified sources;
* :mod:`evotol.calibration.problem` -- the calibrated tolerance problem;
* :mod:`evotol.calibration.simulation` -- the calibration simulated on the nonlinear model.

The parameters several definitions of this package share are described once, here.

Parameters
----------
plan : evotol.calibration.plan.CalibrationPlan
    The plan.
robot : evotol.robots.mechanism.model.error_model.MechanismModel
    The uncalibrated model.
"""
from evotol.calibration.identification import Identification, identify
from evotol.calibration.model import CalibratedRobot, noise_allowance
from evotol.calibration.plan import CalibrationPlan, parse_noise
from evotol.calibration.problem import CalibrationInfo, calibrated_problem
from evotol.calibration.simulation import CalibrationCheck, simulate_calibration

__all__ = ["CalibrationPlan", "parse_noise", "Identification", "identify", "CalibratedRobot", "noise_allowance",
           "CalibrationInfo", "calibrated_problem", "CalibrationCheck", "simulate_calibration"]

"""The calibration simulated on the nonlinear model agrees with the first-order prediction (issue 36 item 4):
robots drawn within the allocated tolerances, readings from the nonlinear forward model plus noise, nonlinear
least squares (scipy.optimize.least_squares), the controller's compensation by Newton on the actuators, the
residual at the task poses -- on the UR5 (URDF, Pinocchio-checked kinematics) and on the planar 3-RRR (a TOML
description with closed loops)."""
from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from evotol.allocators import allocate_optimum
from evotol.calibration import CalibrationPlan, calibrated_problem, simulate_calibration
from evotol.studyfile import load_problem

ROOT = Path(__file__).resolve().parents[1]
OFFSETS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint"]


def _problem(name):
    spec = tomllib.loads((ROOT / f"reports/studies/{name}.toml").read_text())
    return load_problem(spec, base_dir=ROOT / "reports/studies")


@pytest.fixture(scope="module")
def ur5_offsets():
    pc = calibrated_problem(_problem("ur5_urdf"), CalibrationPlan(noise="20 um", identify=OFFSETS, count=40, seed=0))
    return pc, allocate_optimum(pc)


def test_ur5_simulated_calibration_agrees_with_first_order(ur5_offsets):
    """At the calibrated optimum the simulated and predicted residuals of the same robots differ by less than the
    linear range's 10 % of the requirement, and every simulated robot holds the 0.5 mm requirement."""
    pc, r = ur5_offsets
    chk = simulate_calibration(pc, r.t, n_samples=60, seed=1)
    E = 5e-4
    assert chk.nls_failures == 0
    assert chk.difference["position"] < pc.calibration.plan.linear_fraction * E
    assert chk.simulated["position"]["max"] <= E and chk.exceed_rate["position"] == 0.0
    assert chk.worst_case["position"] == pytest.approx(E, rel=1e-3)          # the allocation is tight
    assert chk.simulated["position"]["max"] == pytest.approx(chk.predicted["position"]["max"], rel=0.1)


def test_ur5_simulation_converges_to_first_order_for_small_errors(ur5_offsets):
    """The difference is second order: tolerances / 100 -> difference / 1e4 (ratio within 2x)."""
    pc, r = ur5_offsets
    big = simulate_calibration(pc, r.t, n_samples=20, seed=2).difference["position"]
    pc0 = calibrated_problem(pc.uncalibrated, CalibrationPlan(noise=0.0, identify=OFFSETS, count=40, seed=0))
    d1 = simulate_calibration(pc0, r.t, n_samples=20, seed=2).difference["position"]
    d2 = simulate_calibration(pc0, r.t / 100, n_samples=20, seed=2).difference["position"]
    assert big < 5e-5 and d2 < d1 / 5e3 and d2 > d1 / 2e4


def test_planar_3rrr_simulated_calibration_agrees_with_first_order():
    """A TOML mechanism with three closed loops: the actuator offsets q1-q3 calibrated from 30 poses at 5 um."""
    p = _problem("planar3rrr").with_poses(np.arange(0, 75, 5))
    pc = calibrated_problem(p, CalibrationPlan(noise="5 um", identify=["q?"], count=30, seed=0))
    r = allocate_optimum(pc)
    assert r.cost < allocate_optimum(p).cost
    chk = simulate_calibration(pc, r.t, n_samples=30, seed=1)
    E = 1e-4
    assert chk.nls_failures == 0
    assert chk.difference["position"] < 0.01 * E
    assert chk.simulated["position"]["max"] <= E
    assert chk.simulated["position"]["max"] == pytest.approx(chk.predicted["position"]["max"], rel=0.05)

"""ISO 9283 of calibrated robots, simulated (issue 44 item 4; evotol/calibration/iso9283.py).

References: without noise and random sources, a least-squares calibration leaves only second-order
terms (AP after ≤ 1e-3 AP before); RP is the cycle-to-cycle scatter, which a constant joint correction
does not change; the instrument's noise and the random sources keep the calibrated AP above zero.
"""
from pathlib import Path

import numpy as np
import pytest

from evotol.calibration.iso9283 import simulate_calibrated
from evotol.errors import ValidationError
from evotol.measures.iso9283 import TestCube, iso_positions
from evotol.robots.mechanism import MechanismModel
from evotol.robots.mechanism.model.random_sources import RandomSource, encoder_count

UR5 = Path(__file__).resolve().parents[1] / "robots" / "mechanisms" / "ur5.toml"
ARCMIN = np.pi / 180 / 60


@pytest.fixture(scope="module")
def ur5():
    return MechanismModel(UR5)


P = iso_positions(TestCube((0.4, 0.0, 0.3), 0.2))


def test_noiseless_calibration_leaves_only_second_order(ur5):
    o = simulate_calibrated(ur5, P, np.full(ur5.n_columns, 50e-6), [], [], n_robots=30, noise=0.0)
    assert np.all(o["AP_after"] <= 1e-3 * o["AP_before"].max())
    assert o["AP_before"].min() > 1e-5


def test_random_sources_and_noise_keep_ap_above_zero_and_rp_unchanged(ur5):
    J = list(ur5.kin.actuated)
    src = [RandomSource("backlash", j, ARCMIN) for j in J] + [RandomSource("encoder", j, encoder_count(16)) for j in J]
    t = [s.tolerance for s in src]
    quiet = simulate_calibrated(ur5, P, np.full(ur5.n_columns, 50e-6), src, t, n_robots=60, noise=0.0, seed=3)
    noisy = simulate_calibrated(ur5, P, np.full(ur5.n_columns, 50e-6), src, t, n_robots=60, noise=50e-6, seed=3)
    assert quiet["RP_after"] == pytest.approx(quiet["RP_before"], rel=1e-3)
    assert quiet["AP_after"].mean() < 0.6 * quiet["AP_before"].mean()
    # the barycentre of 30 cycles alone moves by about RP/sqrt(30) / 2: a calibrated AP is never 0
    assert quiet["AP_after"].min() > 0.05 * quiet["RP_after"].mean() / np.sqrt(30)
    assert noisy["AP_after"].mean() > quiet["AP_after"].mean()


def test_too_few_configurations_are_refused(ur5):
    with pytest.raises(ValidationError, match="configurations"):
        simulate_calibrated(ur5, P, np.zeros(ur5.n_columns), [], [], n_configurations=5)

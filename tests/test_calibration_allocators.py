"""Every allocator and measure runs on the post-calibration error (issue 36 item 2): the calibrated UR5
(five offsets from 40 box configurations, 20 um). Each design is checked by an independent evaluation of the
post-calibration map: attained errors at the vertices of the tolerance box that maximise the error along 4000
directions (J M from the identification), not the measure that allocated it."""
from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from evotol.allocators import allocate_ga, allocate_nsga2, allocate_optimum, allocate_sensitivity
from evotol.calibration import CalibrationPlan, calibrated_problem
from evotol.studyfile import load_problem
from evotol.verification.montecarlo import verify

ROOT = Path(__file__).resolve().parents[1]
OFFSETS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint"]


@pytest.fixture(scope="module")
def pc():
    spec = tomllib.loads((ROOT / "reports/studies/ur5_urdf.toml").read_text())
    p = load_problem(spec, base_dir=ROOT / "reports/studies")
    return calibrated_problem(p, CalibrationPlan(noise="20 um", identify=OFFSETS, count=40, seed=0), simulate=20)


def _vertex_worst(pc, t, n_dir=4000):
    """Largest |J M e| over the vertices e = t * sign((J M)^T u) of the tolerance box for 4000 directions u, at every
    pose: attained errors, so a lower bound of the worst case that approaches it as the directions fill the sphere."""
    JM = pc.robot.base.sensitivity(pc.poses)[:, :3] @ pc.calibration.identification.M        # (p, 3, n)
    U = np.random.default_rng(0).standard_normal((n_dir, 3))
    U /= np.linalg.norm(U, axis=1, keepdims=True)
    E = np.sign(np.einsum("pin,di->pdn", JM, U)) * t                                         # vertices
    return np.linalg.norm(np.einsum("pin,pdn->pdi", JM, E), axis=2).max()


def test_every_allocator_meets_the_geometric_share(pc):
    E = pc.requirement.position
    designs = {"optimum": allocate_optimum(pc).t, "sensitivity": allocate_sensitivity(pc).t,
               "ga": allocate_ga(pc, pop_size=20, n_gen=15, seed=0, progress=False).t}
    front = allocate_nsga2(pc, pop_size=20, n_gen=8, seed=0, progress=False)
    for name, t in designs.items():
        assert pc.max_errors(t)["position"][0] <= E * (1 + 1e-6), name
        assert _vertex_worst(pc, t) <= E * (1 + 1e-6), name
    assert _vertex_worst(pc, designs["optimum"]) >= 0.99 * E          # the optimum is tight
    assert len(front.cost) > 0
    b = allocate_optimum(pc, budget=3.0)                          # budget mode: best accuracy at cost 3
    assert b.cost <= 3.0 * (1 + 1e-6) and pc.max_errors(b.t)["position"][0] < E


def test_rss_and_yield_measures_on_the_calibrated_error(pc):
    t = allocate_optimum(pc).t
    rss = pc.evaluate(t, "rss").position.max()
    wc = pc.evaluate(t, "worst_case").position.max()
    assert 0 < rss <= wc
    yp = pc.with_requirement(measure="yield", probability=0.99)
    assert yp.first_order_yield().noise["position"].shape == (pc.n_poses, 6)     # the noise is in the yield model
    mc = verify(pc, t, n_samples=100, seed=0)
    assert mc.calibration is not None and mc.calibration.n_samples == 20
    assert mc.to_dict()["calibration"]["simulated"]["position"]["max"] <= 5e-4

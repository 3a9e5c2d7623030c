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
    JM = pc.model.base.sensitivity(pc.poses)[:, :3] @ pc.calibration.identification.M        # (p, 3, n)
    U = np.random.default_rng(0).standard_normal((n_dir, 3))
    U /= np.linalg.norm(U, axis=1, keepdims=True)
    E = np.sign(np.einsum("pin,di->pdn", JM, U)) * t                                         # vertices
    return np.linalg.norm(np.einsum("pin,pdn->pdi", JM, E), axis=2).max()


def test_every_allocator_meets_the_geometric_share(pc):
    E = pc.requirement.position
    designs = {"optimum": allocate_optimum(pc).t, "sensitivity": allocate_sensitivity(pc).t,
               "ga": allocate_ga(pc, pop_size=20, n_gen=15, seed=0, progress=False).t}
    for name, t in designs.items():
        assert pc.max_errors(t)["position"][0] <= E * (1 + 1e-6), name
        assert _vertex_worst(pc, t) <= E * (1 + 1e-6), name
    assert _vertex_worst(pc, designs["optimum"]) >= 0.99 * E          # the optimum is tight
    b = allocate_optimum(pc, budget=3.0)                          # budget mode: best accuracy at cost 3
    assert b.cost <= 3.0 * (1 + 1e-6) and pc.max_errors(b.t)["position"][0] < E


def test_nsga2_front_is_non_dominated_and_bounded_by_the_optimum(pc):
    """The front (cost vs error / requirement), the certified optimum in its first population: no point
    dominates another; each point's error is the vertex check of its design on J M (attained errors, so at
    most the reported worst case and within 1 % of it with 4000 directions); none that meets the requirement
    is cheaper than the certified optimum (a proven lower bound), and the cheapest is within 5 % of it."""
    opt = allocate_optimum(pc)
    front = allocate_nsga2(pc, pop_size=20, n_gen=8, seed=0, progress=False, seeds=[opt.tolerances])
    tab = front.table
    c, e = tab["cost"].to_numpy(), tab["normalised_error"].to_numpy()
    dominated = (c[:, None] <= c[None]) & (e[:, None] <= e[None]) & ((c[:, None] < c[None]) | (e[:, None] < e[None]))
    assert len(tab) >= 5 and not dominated.any()
    E = pc.requirement.position
    designs = np.array([[tab[n].iloc[i] for n in pc.names] for i in range(len(tab))])
    assert np.allclose(pc.cost(designs), c, rtol=1e-9)
    for t, ei in zip(designs, e):
        assert 0.99 * ei * E <= _vertex_worst(pc, t) <= ei * E * (1 + 1e-6)
    ok = e <= 1 + 1e-9
    assert ok.any() and opt.cost * (1 - 1e-6) <= c[ok].min() <= 1.05 * opt.cost


def test_rss_and_yield_measures_on_the_calibrated_error(pc):
    """RSS: its closed form sqrt(Σ_j (t_j ‖(J M)_j‖₂)²) per pose (docs/tolerances.md), J M built here from
    the model's map and the identification's M; it lies below the worst case. Yield: the noise the model adds
    is the propagated instrument noise J_K σ² (A_Kᵀ A_K)⁻¹ J_Kᵀ of an ordinary least-squares fit of the
    readings (one σ on every axis, known instrument), computed here with numpy."""
    t = allocate_optimum(pc).t
    rss = pc.evaluate(t, "rss").position[0]
    wc = pc.evaluate(t, "worst_case").position[0]
    J = pc.model.base.sensitivity(pc.poses)
    idn = pc.calibration.identification
    JM = J[:, :3] @ idn.M
    assert np.allclose(rss, np.sqrt(((t * np.linalg.norm(JM, axis=1)) ** 2).sum(axis=1)), rtol=1e-9)
    assert np.all(rss <= wc * (1 + 1e-9))
    S = pc.model.base.sensitivity_at_joints(idn.joints)
    AK = S[:, :3][:, :, idn.identified].reshape(-1, len(idn.identified))
    cov = 2e-5 ** 2 * np.linalg.inv(AK.T @ AK)
    C = np.einsum("pik,kl,pjl->pij", J[:, :3, idn.identified], cov, J[:, :3, idn.identified])
    pairs = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
    noise = pc.with_requirement(measure="yield", probability=0.99).first_order_yield().noise["position"]
    assert np.allclose(noise, np.stack([C[:, a, b] for a, b in pairs], -1), rtol=1e-8, atol=1e-20)
    mc = verify(pc, t, n_samples=100, seed=0)
    assert mc.part_checks["calibration"].n_samples == 20
    assert mc.to_dict()["calibration"]["simulated"]["position"]["max"] <= 5e-4

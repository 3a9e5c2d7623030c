"""Calibration with grid refinement (refused) and with the RSS measure (an independent convex solve):
the two calibration pairs of docs/combinations.md that were run but not yet held by a reference (issue 39).

* **K + G**: a calibrated problem takes the noise, the random sources and the second-order terms off the
  requirement at its own poses and caps each source at the linear range found there; refined poses would be
  judged against allowances computed elsewhere. Refused in one line naming both, before the calibration is
  identified (study file) or before any allocation runs (Python: the optimum and the GA).
* **K + M(rss)**: the calibrated UR5 allocated for an RSS requirement equals an independent SLSQP solve of
  min cost(t) s.t. Σ_j (t_j ‖(J M)_pj‖₂)² <= E_rss² at every pose, with J M built here from the robot's
  sensitivities and the identification's projection, and E_rss = sqrt((E - d)² - q²) from the noise
  allowance's own terms (its closed form is tests/test_calibration.py's).
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

from evotol.allocators import allocate_ga, allocate_optimum
from evotol.calibration import CalibrationPlan, calibrated_problem
from evotol.errors import ValidationError
from evotol.studyfile.problem import load_problem
from tests.test_combinations import STUDIES, ur5, with_calibration

OFFSETS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint"]


@pytest.fixture(scope="module")
def rss_problem():
    """The small UR5 study of test_combinations with an RSS requirement, calibrated for its five joint
    offsets (40 configurations over the joint limits, 5 um). Upper bounds of 10 mm and second-order terms
    allowed up to 90 % of the requirement keep the linear-range caps loose, so the RSS rows bind (with the
    default 10 % every source sits on its cap and no row is active: issue 44's observation)."""
    spec = ur5()
    spec["requirement"]["measure"] = "rss"
    spec["bounds"]["upper"] = 1e-2
    p = load_problem(spec, base_dir=STUDIES)
    plan = CalibrationPlan(noise="5 um", identify=OFFSETS, count=40, seed=0, linear_fraction=0.9)
    return calibrated_problem(p, plan, simulate=0)


@pytest.mark.parametrize("refine", [True, {"grid": 3}], ids=["true", "table"])
def test_calibration_with_refinement_is_refused_in_a_study_before_the_identification(refine, monkeypatch):
    import evotol.calibration.problem as cp

    monkeypatch.setattr(cp, "identify", lambda *a, **k: (_ for _ in ()).throw(AssertionError("identified")))
    spec = with_calibration(ur5())
    spec["poses"] = {"grid": [2, 2, 2], "refine": refine}
    with pytest.raises(ValidationError, match=r"^poses\.refine = .*: expected no refine beside \[calibration\]: "
                                              r"the calibration's noise allowance") as exc:
        load_problem(spec, base_dir=STUDIES)
    assert "\n" not in str(exc.value)
    spec["poses"]["refine"] = False                # refine = false is no refinement: it goes on to the identification
    with pytest.raises(AssertionError, match="identified"):
        load_problem(spec, base_dir=STUDIES)


def test_calibration_with_refinement_is_refused_in_python_before_any_allocation(rss_problem, monkeypatch):
    import evotol.allocators.ga as ga
    import evotol.allocators.workspace_refinement as wr

    monkeypatch.setattr(wr, "refine_poses", lambda *a, **k: (_ for _ in ()).throw(AssertionError("refined")))
    monkeypatch.setattr(ga, "initial_population", lambda *a, **k: (_ for _ in ()).throw(AssertionError("GA ran")))
    for run in (lambda: allocate_optimum(rss_problem, refine=True),
                lambda: allocate_ga(rss_problem, refine={"grid": 3}, pop_size=10, n_gen=2, progress=False),
                lambda: wr.hold_on_workspace(rss_problem, rss_problem.upper)):
        with pytest.raises(ValidationError, match=r"^refine = 'a calibrated problem': expected a problem without "
                                                  r"calibration: the calibration's noise allowance") as exc:
            run()
        assert "\n" not in str(exc.value)


def test_calibrated_rss_optimum_equals_an_independent_convex_solve(rss_problem):
    pc = rss_problem
    noise = pc.calibration.noise
    assert noise["rule"] == "quadrature"
    n = noise["position"]
    E = np.sqrt((5e-4 - n["second_order"] - n["remainder"]) ** 2 - n["allowance"] ** 2)
    assert pc.requirement.position == pytest.approx(E, rel=1e-12) and 0 < E < 5e-4
    JM = pc.model.base.sensitivity(pc.poses)[:, :3] @ pc.calibration.identification.M       # (p, 3, n)
    a2 = (np.linalg.norm(JM, axis=1) ** 2)                                                    # (p, n)
    free = pc.free
    r = allocate_optimum(pc)
    assert r.feasible and (r.t[free] < 0.99 * pc.upper[free]).sum() >= 10      # rows, not bounds, set the design

    # independent: SLSQP on log-tolerances, the RSS rows written here, the cost from the cost models
    lo, up = np.log(pc.lower[free]), np.log(pc.upper[free])
    scale = float(pc.cost(pc.full(pc.upper[free][None]))[0])

    def full(X):
        return pc.full(np.exp(np.atleast_2d(X)))

    def cost(x):                 # the cost and its central-difference gradient, in one batched call
        h = 1e-6 * np.eye(len(x))
        c = pc.cost(full(np.vstack([x, x + h, x - h]))) / scale
        return float(c[0]), (c[1:len(x) + 1] - c[len(x) + 1:]) / 2e-6

    def row(x):                  # 1 - RSS² / E² at every pose, and its exact gradient (t = exp x)
        t = full(x)[0]
        return 1.0 - (a2 @ t ** 2) / E ** 2, -2.0 * (a2[:, free] * t[free] ** 2) / E ** 2

    rows = {"type": "ineq", "fun": lambda x: row(x)[0], "jac": lambda x: row(x)[1]}
    best = None
    for x0 in (0.5 * (lo + up), lo + 0.25 * (up - lo)):          # two starts far from evotol's design
        s = minimize(cost, x0, jac=True, method="SLSQP", bounds=list(zip(lo, up)), constraints=[rows],
                     options={"maxiter": 400, "ftol": 1e-12})
        if rows["fun"](s.x).min() >= -1e-6 and (best is None or s.fun < best.fun):   # feasible (may stop at maxiter)
            best = s
    assert best is not None
    t_ref = full(best.x)[0]
    assert np.sqrt(a2 @ t_ref ** 2).max() <= E * (1 + 1e-6)          # the reference meets its own rows
    assert np.sqrt(a2 @ r.t ** 2).max() == pytest.approx(E, rel=1e-6)     # evotol's optimum is tight on them
    assert r.cost == pytest.approx(float(pc.cost(t_ref[None])[0]), rel=1e-6)
    assert r.cost <= float(pc.cost(t_ref[None])[0]) * (1 + 1e-7)
    assert np.allclose(pc.evaluate(r.t, "rss").position[0], np.sqrt(a2 @ r.t ** 2), rtol=1e-9)

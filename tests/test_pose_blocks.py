"""Support coefficients by blocks of poses (issue 43 item 4): above ``COEFFICIENT_CACHE_BYTES`` a component's
coefficients are computed for a block of poses, used and dropped. Every consumer -- the worst-case measure
(with and without ``top_only``), the optimum's cutting planes, the nonlinear vertex check, the explorer's
sampled worst case -- must give the numbers of the cached, all-poses path: here the cache is shrunk so the
small UR5 study (8 poses) runs in blocks of one pose, and each number is compared with the same call on the cached
problem. Values and bounds agree to round-off; worst directions to the ascent's own precision (h is
stationary at u*, and the ascent's stopping test is shared by the poses evaluated together)."""
from __future__ import annotations

import copy

import numpy as np
import pytest

import evotol.core.problem.tolerance_problem as tp
from evotol.allocators import allocate_optimum
from evotol.measures.linear import PoseBlocks
from evotol.studyfile.problem import load_problem
from evotol.summaries.explorer_data import sampled_worst_case
from evotol.verification.nonlinear import worst_vertex_errors
from tests.test_combinations import STUDIES, ur5, with_callouts


@pytest.fixture(scope="module", params=["plain", "asymmetric", "joints+callouts"])
def pair(request):
    """The UR5 on 8 task poses, cached, and a copy whose coefficients come in blocks: plain ±t; asymmetric
    intervals (the offsets' ``const`` in every block); callouts on joint configurations (the composed model)."""
    spec = ur5()
    spec["poses"] = {"grid": [2, 2, 2]}
    spec["requirement"]["orientation"] = 2e-3
    if request.param == "joints+callouts":
        with_callouts(spec)
        arm = load_problem(copy.deepcopy(spec), base_dir=STUDIES).model.described
        q = arm.joint_values(arm.workspace.grid(2))
        spec["poses"] = {"joints": np.stack([q[v] for v in arm.kin.variables], axis=1).tolist()}
    cached = load_problem(spec, base_dir=STUDIES)
    if request.param == "asymmetric":
        cached = cached.with_tolerances(minus=0.5, plus=1.5)
    blocked = copy.copy(cached)
    blocked._coeff_cache = {}
    return cached, blocked


@pytest.fixture
def small_cache(pair, monkeypatch):
    cached, _ = pair
    D, _ = cached.directions("position")
    per_pose = 8 * len(D) * (cached.n_sources + 1)
    monkeypatch.setattr(tp, "COEFFICIENT_CACHE_BYTES", 7 * per_pose)     # 8 poses do not fit: blocks of 7 // 4 = 1
    return per_pose


def test_blocks_cover_every_pose_once_with_the_cached_coefficients(pair, small_cache):
    cached, blocked = pair
    for comp in ("position", "orientation"):
        pieces = blocked.coefficient_blocks(comp)
        assert isinstance(pieces, PoseBlocks) and len(pieces) == 8 and comp not in blocked._coeff_cache
        c = np.concatenate([coef[0] for _, coef in pieces])
        assert np.array_equal(c, cached.coefficients(comp)[0])          # the same arithmetic, pose by pose
        assert [sl.start for sl, _ in pieces] == list(range(8))


@pytest.mark.parametrize("top_only", [False, True])
def test_worst_case_in_blocks_equals_all_poses(pair, small_cache, top_only):
    cached, blocked = pair
    rng = np.random.default_rng(0)
    T = np.exp(rng.uniform(np.log(cached.lower), np.log(cached.upper), (5, cached.n_sources)))
    a, b = cached.evaluate(T, top_only=top_only), blocked.evaluate(T, top_only=top_only)
    for comp in ("position", "orientation"):
        assert np.allclose(getattr(a, comp), getattr(b, comp), rtol=1e-12)
        assert np.allclose(getattr(a, f"{comp}_bound"), getattr(b, f"{comp}_bound"), rtol=1e-12)
        if not top_only:
            assert np.allclose(getattr(a, f"{comp}_direction"), getattr(b, f"{comp}_direction"), atol=1e-6)
        assert np.allclose(sampled_worst_case(cached, T, comp), sampled_worst_case(blocked, T, comp), rtol=1e-12)
    t = T[0]
    va, vb = worst_vertex_errors(cached, t), worst_vertex_errors(blocked, t)
    for comp in va:
        assert np.allclose(va[comp], vb[comp], rtol=1e-6)


def test_optimum_in_blocks_equals_the_cached_optimum(pair, small_cache):
    cached, blocked = pair
    ra, rb = allocate_optimum(cached), allocate_optimum(blocked)
    assert ra.feasible and rb.feasible
    assert rb.cost == pytest.approx(ra.cost, rel=1e-7)
    assert np.allclose(rb.t, ra.t, rtol=1e-5)


@pytest.mark.parametrize("top_only", [False, True])
def test_components_computes_the_constrained_ones_to_the_bit(pair, small_cache, top_only):
    """``evaluate(..., components=[...])`` (the constraint rows' check: a position requirement need not
    compute the orientation) gives the full evaluation's numbers for those components, bit for bit, on
    cached and blocked coefficients; the others are None. Refused: a constrained component left out, an
    unknown one, another measure."""
    from evotol.errors import ValidationError

    cached, blocked = pair
    rng = np.random.default_rng(1)
    T = np.exp(rng.uniform(np.log(cached.lower), np.log(cached.upper), (4, cached.n_sources)))
    for problem in (cached, blocked):
        full = problem.evaluate(T, "worst_case", top_only=top_only)
        both = problem.evaluate(T, "worst_case", top_only=top_only, components=["position", "orientation"])
        for field in ("position", "position_bound", "position_direction", "position_contrib", "orientation",
                      "orientation_bound", "violation"):
            assert np.array_equal(getattr(full, field), getattr(both, field)), field
    with pytest.raises(ValidationError, match="components"):
        cached.evaluate(T, "worst_case", components=["position"])          # orientation is constrained here
    with pytest.raises(ValidationError, match="components"):
        cached.evaluate(T, "worst_case", components=["position", "orientation", "force"])
    with pytest.raises(ValidationError, match="components"):
        cached.evaluate(T, "rss", components=["position", "orientation"])


@pytest.mark.parametrize("blocked", [False, True])
def test_a_position_requirement_checks_the_position_only_to_the_bit(monkeypatch, blocked):
    """The constraint rows' check of a position-only requirement: the same violation and worst directions
    as the evaluation of both components, and no orientation computed; cached and blocked coefficients."""
    from evotol.measures.constraints import ConstraintRows

    spec = ur5()
    spec["poses"] = {"grid": [2, 2, 2]}
    problem = load_problem(spec, base_dir=STUDIES)
    if blocked:                                     # 8 poses do not fit: blocks of one pose
        D, _ = problem.directions("position")
        monkeypatch.setattr(tp, "COEFFICIENT_CACHE_BYTES", 7 * 8 * len(D) * (problem.n_sources + 1))
        problem = load_problem(spec, base_dir=STUDIES)
        assert len(problem.coefficient_blocks("position")) == 8
    assert [c for c, _ in problem.components] == ["position"]
    rng = np.random.default_rng(2)
    T = np.exp(rng.uniform(np.log(problem.lower), np.log(problem.upper), (5, problem.n_sources)))
    full = problem.evaluate(T, "worst_case", top_only=True)
    part = problem.evaluate(T, "worst_case", top_only=True, components=["position"])
    assert part.orientation is None and np.array_equal(part.violation, full.violation)
    assert np.array_equal(part.position_direction, full.position_direction)
    rows = ConstraintRows(problem)
    assert np.array_equal(rows.check(T)[0], full.violation)


def test_with_tolerances_keeps_the_coefficients_of_the_same_shape_only(pair):
    """A drawing's re-check (``with_tolerances`` with the zones it had) reuses the support coefficients, and
    evaluates as a problem that computes its own, to the bit; another shape computes its own."""
    cached, _ = pair
    c = cached.coefficients("position")[0]
    sh = cached.shape
    minus, plus = sh.rho - sh.kappa, sh.rho + sh.kappa
    again = cached.with_tolerances(minus=minus, plus=plus)
    assert again.coefficients("position")[0] is c                      # kept, not recomputed
    fresh = copy.copy(again)
    fresh._coeff_cache = {}
    rng = np.random.default_rng(3)
    T = np.exp(rng.uniform(np.log(cached.lower), np.log(cached.upper), (3, cached.n_sources)))
    a, b = again.evaluate(T), fresh.evaluate(T)
    for field in ("position", "position_bound", "orientation", "violation"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field
    j = next(k for k, src in enumerate(cached.error_model.sources) if src.dim == 1)   # an interval source
    moved = minus.copy()
    moved[j] *= 0.5
    other = cached.with_tolerances(minus=moved, plus=plus)
    assert other._coeff_cache == {}

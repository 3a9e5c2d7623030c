"""Joint-clearance engine (evotol.robots.clearance), checked on the 5-bar of Deng 2012 Ch. IV.

Every test names the equation it checks. Numbers come from finite differences, closed forms,
an independent local solver (SLSQP) and the thesis's multistart method -- never from a stored
output of the engine itself.
"""
import numpy as np
import pytest
from scipy.optimize import minimize

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.clearance import (ClearanceEvaluator, max_pose_error, multistart_max_pose_error, twist_between)
from evotol.robots.clearance.kinematics import adjoint, exp_screw, inv_transform, kk_transform, rotation_vector
from evotol.robots.clearance.support import solve_support
from evotol.robots.fivebar import FiveBar
from evotol.units import MM


@pytest.fixture(scope="module")
def fivebar():
    return FiveBar()


@pytest.fixture(scope="module")
def mech(fivebar):
    return fivebar.clearance_mechanism()


# ------------------------------------------------------------------------- kinematics primitives
def test_kk_transform_is_thesis_product_III7():
    """Eq. III.7: S = S_alpha S_d S_theta S_r when gamma = b = 0 (eqs. III.8-III.11)."""
    al, d, th, r = 0.3, 0.05, -1.1, 0.02
    ca, sa, ct, st = np.cos(al), np.sin(al), np.cos(th), np.sin(th)
    Sa = np.array([[1, 0, 0, 0], [0, ca, -sa, 0], [0, sa, ca, 0], [0, 0, 0, 1]])
    Sd = np.eye(4); Sd[0, 3] = d
    St = np.array([[ct, -st, 0, 0], [st, ct, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    Sr = np.eye(4); Sr[2, 3] = r
    assert np.allclose(kk_transform(0, 0, al, d, th, r), Sa @ Sd @ St @ Sr, atol=1e-15)


def test_adjoint_maps_screws_between_frames_III14():
    """Eq. III.14: adj(S) moves a screw from frame j+1 to frame j; adj(S^-1) = adj(S)^-1."""
    T = kk_transform(0.2, 0.01, 0.4, 0.03, 0.7, -0.02)
    s = np.array([1e-6, -2e-6, 3e-6, 4e-7, 1e-7, -2e-7])
    # displacing frame j+1 by exp(s) equals displacing frame j by exp(adj(T) s)
    lhs = T @ exp_screw(s)
    rhs = exp_screw(adjoint(T) @ s) @ T
    assert np.allclose(lhs, rhs, atol=1e-12)
    assert np.allclose(adjoint(inv_transform(T)), np.linalg.inv(adjoint(T)), atol=1e-12)


def test_rotation_vector_inverts_exp():
    w = np.array([0.3, -0.2, 0.5])
    assert np.allclose(rotation_vector(exp_screw(np.r_[w, 0, 0, 0])[:3, :3]), w, atol=1e-12)


# ------------------------------------------------------------------------- error mapping matrices
@pytest.mark.parametrize("L5", [0.0, 0.02])
def test_error_mapping_matches_finite_differences_III24(fivebar, L5):
    """Eqs. III.22-III.24: each column of M_i equals the central finite difference of the
    chain's end-effector pose when joint j's frame is displaced by exp(h e_k)."""
    mech = FiveBar(L5=L5).clearance_mechanism()
    poses = np.array([[0.01, 0.06], [-0.015, 0.035], [0.0, 0.05]])
    h = 1e-6
    for c in mech.chains:
        M, _ = mech.error_mapping(poses, c)
        T0 = mech.chain_end_pose(poses, c)
        for k, jn in enumerate(c.joints):
            for comp in range(6):
                s = np.zeros(6); s[comp] = h
                fd = (twist_between(T0, mech.chain_end_pose(poses, c, {jn: s}))
                      - twist_between(T0, mech.chain_end_pose(poses, c, {jn: -s}))) / (2 * h)
                assert np.allclose(fd, M[:, :, 6 * k + comp], atol=1e-8), (c.name, jn, comp)


def test_error_mapping_equals_thesis_adjoint_products_III24(mech):
    """Our world-pose form of M_j equals the literal product of adjoints of eq. III.24."""
    poses = np.array([[0.012, 0.041], [-0.02, 0.07]])
    for c in mech.chains:
        M, _ = mech.error_mapping(poses, c)
        assert np.allclose(M, mech.error_mapping_thesis(poses, c), atol=1e-14)


def test_consistent_screws_close_the_loop_to_second_order_III13(mech):
    """Eq. III.13 linearised: screws with M_1 s_1 = M_2 s_2 (B^T s = 0) keep the two legs'
    nonlinear end poses together up to O(eps^2)."""
    pose = np.array([[0.008, 0.062]])
    pm = mech.pose_maps(pose, split=False)[0]
    rng = np.random.default_rng(3)
    s = rng.normal(size=pm.n_rows)
    B = pm.B[0]
    s -= B @ np.linalg.lstsq(B, s, rcond=None)[0]           # project onto B^T s = 0
    full = np.zeros(mech.n_screw_variables); full[pm.cols] = s
    screws = {j.name: full[6 * i:6 * i + 6] for i, j in enumerate(mech.joints)}
    mis = []
    for eps in (1e-3, 5e-4):
        T = [mech.chain_end_pose(pose, c, {k: eps * v for k, v in screws.items()}) for c in mech.chains]
        mis.append(np.abs(twist_between(T[0], T[1])).max())
    assert mis[1] < 0.3 * mis[0]             # quadratic: halving eps divides the mismatch by ~4
    # the linear prediction of the platform twist from either leg agrees exactly
    tw = [mech.error_mapping(pose, c)[0][0] @ np.concatenate([screws[j] for j in c.joints]) for c in mech.chains]
    assert np.allclose(tw[0], tw[1], atol=1e-12 * np.abs(tw[0]).max())


def test_planar_blocks_decouple_exactly(mech):
    """In/out-of-plane split: the full 6-D error mapping has no coupling between the blocks."""
    poses = np.array([[0.0, 0.05], [0.02, 0.03]])
    for c in mech.chains:
        M, _ = mech.error_mapping(poses, c)
        inp, out = [2, 3, 4], [0, 1, 5]
        for k in range(len(c.joints)):
            Mj = M[:, :, 6 * k:6 * k + 6]
            assert np.abs(Mj[:, inp][:, :, out]).max() < 1e-15
            assert np.abs(Mj[:, out][:, :, inp]).max() < 1e-15


# ------------------------------------------------------------------------- the convex sub-problem
def test_support_function_matches_slsqp_on_the_convex_problem(mech):
    """Per-direction problem (support function of the feasible set, eqs. III.26 with a linear
    objective): barrier solver's certified bracket contains the SLSQP optimum."""
    poses = np.array([[0.01, 0.06], [0.0, 0.05]])
    pm = mech.pose_maps(poses, split=False)[0]
    D = pm.row_bounds(np.broadcast_to(mech.default_bounds(), (2, 5, 4)))
    rng = np.random.default_rng(0)
    for p in range(2):
        u = rng.normal(size=3); u /= np.linalg.norm(u)
        a = (u @ pm.C_pos[p]) * D[p]
        Bt = pm.B[p] * D[p][:, None]
        res = solve_support(a[None], Bt[None], pm.n_disk, tol=0, rtol=1e-8)
        keep = D[p] > 0
        cones = [np.arange(2 * c, 2 * c + 2) for c in range(pm.n_disk)] + [np.array([r]) for r in range(2 * pm.n_disk, pm.n_rows)]
        act = [c for c in cones if keep[c].all()]
        sel = np.zeros((len(act), pm.n_rows, pm.n_rows))
        for i, c in enumerate(act):
            sel[i, c, c] = 1.0
        cons = [{"type": "eq", "fun": lambda x: Bt.T @ x, "jac": lambda x: Bt.T},
                {"type": "ineq", "fun": lambda x: 1 - np.einsum("r,irs,s->i", x, sel, x),
                 "jac": lambda x: -2 * np.einsum("irs,s->ir", sel, x)}]
        bnds = [(-1, 1) if k else (0, 0) for k in keep]
        best = -np.inf
        for _ in range(2):           # a convex problem: any start reaches the optimum
            x0 = rng.uniform(-0.2, 0.2, pm.n_rows) * keep
            o = minimize(lambda x: (-a @ x, -a), x0, jac=True, bounds=bnds, constraints=cons, method="SLSQP",
                         options=dict(maxiter=500, ftol=1e-15))
            best = max(best, -o.fun)
        assert res.lower[0] <= best * (1 + 1e-6) and best <= res.upper[0] * (1 + 1e-6)
        assert res.upper[0] - res.lower[0] <= 1e-7 * res.upper[0]


# ------------------------------------------------------------------------- global maximum
@pytest.fixture(scope="module")
def few_poses():
    return np.array([[0.0, 0.07], [0.01, 0.05], [-0.015, 0.04], [0.0, 0.05]])


@pytest.fixture(scope="module")
def result(mech, few_poses):
    return max_pose_error(mech, few_poses)


def test_certified_gap_below_0p1_percent(result):
    """Issue target: relative gap between attained value and certified bound <= 0.1 %."""
    assert np.all(result.p_upper >= result.p_max) and np.all(result.r_upper >= result.r_max)
    assert result.gap.max() <= 1e-3


def test_returned_screws_are_feasible_and_attain_the_value_III3_III6(mech, result, few_poses):
    """The explicit screws respect eqs. III.3-III.6, close the loop (M_1 s_1 = M_2 s_2) and
    produce the reported error."""
    b = mech.default_bounds()
    for S, val, w in ((result.p_screws, result.p_max, "p"), (result.r_screws, result.r_max, "r")):
        tilt = np.linalg.norm(S[:, :, 0:2], axis=2); spin = np.abs(S[:, :, 2])
        radial = np.linalg.norm(S[:, :, 3:5], axis=2); axial = np.abs(S[:, :, 5])
        for got, bound in ((tilt, b[:, 0]), (spin, b[:, 1]), (radial, b[:, 2]), (axial, b[:, 3])):
            assert np.all(got <= bound * (1 + 1e-9) + 1e-18)
        legs = []
        for c in mech.chains:
            M, _ = mech.error_mapping(few_poses, c)
            sc = np.concatenate([S[:, mech.joint_index[j]] for j in c.joints], axis=1)
            legs.append(np.einsum("nij,nj->ni", M, sc))
        scale = np.abs(legs[0]).max()
        assert np.abs(legs[0] - legs[1]).max() <= 1e-9 * scale
        tw = result.p_twist if w == "p" else result.r_twist
        assert np.allclose(legs[0], tw, atol=1e-9 * scale)
        norm = np.linalg.norm(tw[:, 3:] if w == "p" else tw[:, :3], axis=1)
        assert np.allclose(norm, val, rtol=1e-9)


def test_never_below_the_thesis_multistart_method(mech, few_poses, result):
    """Sec. IV.3 method (QR elimination III.29-III.48 + multistart local solves): our certified
    bound is never below its best local maximum and our attained value matches it to 0.1 % (either
    side; measured 1.4e-7 at these poses)."""
    ms = multistart_max_pose_error(mech, few_poses[:2], n_starts=6, seed=1)
    assert ms.n_variables == 24                                   # eq. IV.26
    assert np.all(result.p_upper[:2] >= ms.p_max * (1 - 1e-9))
    assert np.all(result.r_upper[:2] >= ms.r_max * (1 - 1e-9))
    np.testing.assert_allclose(result.p_max[:2], ms.p_max, rtol=1e-3)
    np.testing.assert_allclose(result.r_max[:2], ms.r_max, rtol=1e-3)


def test_split_and_unsplit_formulations_agree(mech, few_poses, result):
    """The exact in/out-of-plane split (p^2 = p_in^2 + p_out^2) equals the 6-D problem solved
    with the half-sphere branch and bound."""
    from evotol.robots.clearance import evaluate_cases
    maps = mech.pose_maps(few_poses, split=False)
    full = evaluate_cases(mech, maps, np.arange(len(few_poses)), np.broadcast_to(mech.default_bounds(), (4, 5, 4)))
    assert np.all(full.p_max <= result.p_upper * (1 + 1e-9)) and np.all(result.p_max <= full.p_upper * (1 + 1e-9))
    assert np.all(full.r_max <= result.r_upper * (1 + 1e-9)) and np.all(result.r_max <= full.r_upper * (1 + 1e-9))


def test_maximum_scales_linearly_with_clearances(mech, few_poses, result):
    """The model is linear and the constraint set scales with the bounds: doubling every bound
    doubles both maxima (within the certified brackets)."""
    r2 = max_pose_error(mech, few_poses, 2 * mech.default_bounds())
    assert np.all(r2.p_upper >= 2 * result.p_max * (1 - 1e-12)) and np.all(2 * result.p_upper >= r2.p_max)
    assert np.allclose(r2.p_max, 2 * result.p_max, rtol=1e-3)
    assert np.allclose(r2.r_max, 2 * result.r_max, rtol=1e-3)


# ------------------------------------------------------------------------- serial legs: closed forms
@pytest.mark.parametrize("leg,n_joints", [("leg1", 2), ("leg2", 3)])
def test_serial_leg_rotation_is_sum_of_tilts(fivebar, leg, n_joints):
    """Sec. IV.4, Figs. IV.10/IV.12: with parallel joint axes and locked joints the maximum
    rotational error of an open leg is the sum of the tilt clearances (0.02 / 0.03 rad) -- in
    general sqrt((sum beta_xy)^2 + (sum beta_z)^2) -- at every pose."""
    base = fivebar.clearance_mechanism(beta_z_passive=0.0).sub_mechanism([leg])
    poses = np.array([[0.0, 0.05], [0.02, 0.07], [-0.02, 0.03]])
    r = max_pose_error(base, poses)
    assert np.allclose(r.r_max, 0.01 * n_joints, rtol=1e-9)
    locked = fivebar.clearance_mechanism(beta_z_passive=1e-3, beta_z_active=1e-3).sub_mechanism([leg])
    r = max_pose_error(locked, poses)
    assert np.allclose(r.r_max, np.hypot(0.01 * n_joints, 1e-3 * n_joints), rtol=1e-9)


def test_serial_leg_position_is_support_of_minkowski_sum(fivebar):
    """Open leg (no loop, eq. III.28 case): the bound equals the max over dense directions of the
    closed-form support function sum_j h_K(M_j^T u)."""
    leg = fivebar.clearance_mechanism(beta_z_passive=0.0).sub_mechanism(["leg2"])
    pose = np.array([[0.013, 0.044]])
    r = max_pose_error(leg, pose)
    M, _ = leg.error_mapping(pose, "leg2")
    b = leg.default_bounds()
    phi = np.linspace(0, np.pi, 20001)
    best_in = 0.0
    for f in phi:                                    # in-plane position directions
        u = np.array([0, 0, 0, np.cos(f), np.sin(f), 0])
        v = M[0].T @ u
        h = sum(b[j, 0] * np.hypot(*v[6 * j:6 * j + 2]) + b[j, 1] * abs(v[6 * j + 2]) + b[j, 2] * np.hypot(*v[6 * j + 3:6 * j + 5])
                + b[j, 3] * abs(v[6 * j + 5]) for j in range(3))
        best_in = max(best_in, h)
    uz = np.array([0, 0, 0, 0, 0, 1.0]); v = M[0].T @ uz
    hz = sum(b[j, 0] * np.hypot(*v[6 * j:6 * j + 2]) + b[j, 3] * abs(v[6 * j + 5]) for j in range(3))
    dense = np.hypot(best_in, hz)
    assert r.p_max[0] <= dense * (1 + 1e-9) <= r.p_upper[0] * (1 + 1e-9)
    assert r.p_max[0] >= dense * (1 - 1e-6)


# ------------------------------------------------------------------------- many bound sets at one pose
def test_evaluator_many_bound_sets_matches_per_set_calls(mech):
    """ClearanceEvaluator (maps computed once, duplicates solved once) gives the same brackets
    as separate max_pose_error calls."""
    pose = [[0.0, 0.07]]
    ev = ClearanceEvaluator(mech, pose)
    bxy = np.array([[1e-4, 1e-4, 1e-4, 1e-4, 1e-4], [1e-5, 1e-4, 1e-6, 1e-4, 1e-4], [1e-5, 1e-4, 1e-6, 1e-4, 1e-4]]) * MM * 1e3
    bz = np.array([[1e-4] * 5, [1e-6] * 5, [1e-4] * 5]) * MM * 1e3
    b = mech.thesis_bounds(b_xy=bxy, b_z=bz)
    assert b.shape == (3, 5, 4)
    res = ev.evaluate(b)
    for i in range(3):
        single = max_pose_error(mech, pose, b[i])
        assert single.p_max[0] <= res.p_upper[i] * (1 + 1e-9) and res.p_max[i] <= single.p_upper[0] * (1 + 1e-9)
        assert single.r_max[0] <= res.r_upper[i] * (1 + 1e-9) and res.r_max[i] <= single.r_upper[0] * (1 + 1e-9)
    assert res.gap.max() <= 1e-3


def test_thesis_bounds_convention_III2(mech):
    """Eq. III.2 (beta_xy = b_xy / h) and the active/passive beta_z convention of Sec. III.1.1."""
    b = mech.thesis_bounds(b_xy=2e-5, b_z=1e-5, h=0.01)
    assert np.allclose(b[:, 0], 2e-3) and np.allclose(b[:, 2], 2e-5) and np.allclose(b[:, 3], 1e-5)
    active = np.array([j.active for j in mech.joints])
    assert np.allclose(b[active, 1], 0.0) and np.allclose(b[~active, 1], 0.2)


# ------------------------------------------------------------------------- errors
def test_bad_input_is_named(mech):
    with pytest.raises(ValidationError) as e:
        max_pose_error(mech, [[0.0, 0.05]], np.ones((4, 4)))
    assert "bounds shape" in str(e.value)
    with pytest.raises(ValidationError):
        max_pose_error(mech, [[0.0, 0.05]], -np.ones((5, 4)))
    with pytest.raises(KinematicsError) as e:
        max_pose_error(mech, [[0.0, 0.2]])
    assert "0.2" in str(e.value)


@pytest.mark.parametrize("mode", ["uniform", "boundary"])
def test_sampled_screws_are_consistent_states_inside_the_certified_bound(mech, mode):
    """Random clearance states (``PoseMaps.sample_screws``, the plain Monte Carlo of the 5-bar study)
    lie in the clearance set (disks and intervals, eq. III.2), close the loops (``B^T s = 0``,
    eq. III.13) and never exceed the certified maximum of the branch and bound."""
    from evotol.robots.clearance.maxerror import as_bounds

    pose = [0.01, 0.06]
    b = as_bounds(mech, None, 1)
    cert = max_pose_error(mech, [pose])
    p2 = np.zeros(4000)
    for pm in mech.pose_maps(np.atleast_2d(pose)):
        s = pm.sample_screws(0, b, 4000, np.random.default_rng(7), mode)
        D = pm.row_bounds(b[None])[0]
        nd = pm.n_disk
        assert np.all(s[:, D == 0] == 0)            # rows without clearance stay at zero
        sig = np.divide(s, D, out=np.zeros_like(s), where=D > 0)
        assert np.all(np.hypot(sig[:, 0:2 * nd:2], sig[:, 1:2 * nd:2]) <= 1 + 1e-12)
        assert np.all(np.abs(sig[:, 2 * nd:]) <= 1 + 1e-12)
        np.testing.assert_allclose(s @ pm.B[0], 0.0, atol=1e-12 * np.abs(s).max() * np.abs(pm.B[0]).max())
        p2 += ((s @ pm.C_pos[0].T) ** 2).sum(-1)
    assert np.sqrt(p2).max() <= cert.p_upper[0] * (1 + 1e-12)
    assert np.sqrt(p2).max() > 0.3 * cert.p_max[0]       # the samples are not all trivial

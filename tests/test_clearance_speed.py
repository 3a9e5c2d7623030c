"""Issue 13: the faster branch and bound keeps the certificate and agrees with the engine before it.

* ``patches.patch_bound`` is the exact sublinearity bound ``max_{l >= 0} sum l_i H_i / |sum l_i U_i|``
  over a patch: checked against a dense brute-force maximisation over the simplex, and never
  above the bound used before (``min(max H / d, |X|)``).
* Maps computed by the new settings and by ``options=LEGACY`` (the algorithm before issue 13)
  on the same small grids: every certified bracket ``[max, upper]`` of one overlaps the other's,
  and both keep the gap <= 0.1 %.
"""
import numpy as np
import pytest

from evotol.robots.clearance import max_pose_error
from evotol.robots.clearance import patches as me
from evotol.robots.clearance.options import DEFAULT, LEGACY


def _brute(U, H, n=400):
    """max over a dense grid of the simplex of sum l_i H_i / |sum l_i U_i| (one patch)."""
    q = len(U)
    if q == 2:
        l = np.linspace(0, 1, n)[:, None] * np.array([1.0, -1.0]) + np.array([0.0, 1.0])
    else:
        a, b = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
        m = a + b <= 1
        l = np.stack([a[m], b[m], 1 - a[m] - b[m]], 1)
    return np.max((l @ H) / np.linalg.norm(l @ U, axis=1))


def test_patch_bound_is_the_exact_sublinearity_bound_and_never_above_the_old_one():
    rng = np.random.default_rng(3)
    for k in (2, 3):
        for _ in range(60):
            centre = me.normalise(rng.normal(size=k))
            U = me.normalise(centre + rng.uniform(0.05, 0.6) * rng.normal(size=(k, k)))
            if np.min(U @ U.T) <= 0:                     # the branch and bound's patches span < 90 deg
                continue
            H = rng.uniform(0.5, 1.5, size=k)
            new = me.patch_bound(U[None], H[None])[0]
            old = me.patch_bound(U[None], H[None], legacy=True)[0]
            ref = _brute(U, H)
            assert new >= ref * (1 - 1e-9)               # a valid bound: not below the true sup
            assert new <= ref * (1 + 2e-3) + 1e-12       # and tight (dense sampling)
            assert new <= old * (1 + 1e-12)


def test_initial_patches_use_one_vertex_of_each_antipodal_pair():
    verts, tri, sign = me.initial_patches(3)
    assert len(verts) == 3                                # e_x, e_y, e_z (were 5 with -e_x, -e_y)
    spanned = verts[tri] * sign[..., None]                # the four octants of the upper half sphere
    assert sorted(map(tuple, spanned.sum(1).round(12))) == [(-1, -1, 1), (-1, 1, 1), (1, -1, 1), (1, 1, 1)]


def test_initial_circle_patches_are_three_60_degree_arcs_of_the_half_circle():
    verts, tri, sign = me.initial_patches(2)
    arcs = verts[tri] * sign[..., None]                   # (3, 2, 2): ends of each arc
    assert len(verts) == 3 and len(arcs) == 3             # 0, 60, 120 deg (+ the antipode of 0 deg)
    cosines = np.einsum("ak,ak->a", arcs[:, 0], arcs[:, 1])
    assert np.allclose(cosines, np.cos(np.pi / 3))
    assert np.allclose(arcs[-1, 1], [-1.0, 0.0]) and np.allclose(arcs[0, 0], [1.0, 0.0])


def _block(mech, pose, target):
    """Scaled problem data at ``pose`` of the block of ``mech`` with the most components of target
    "p" or "r" (the 5-bar's out-of-plane block for "r": rotations about x and y)."""
    pm = max(mech.pose_maps(np.atleast_2d(pose)), key=lambda b: (b.C_pos if target == "p" else b.C_rot).shape[1])
    D = pm.row_bounds(np.broadcast_to(mech.default_bounds(), (1, mech.n_joints, 4)))
    Bt = pm.B * D[..., None]
    Ct = (pm.C_pos if target == "p" else pm.C_rot) * D[:, None, :]
    return Ct, Bt, pm.n_disk, pm.groups


@pytest.mark.parametrize("robot, target", [("fivebar", "r"), ("irsbot2", "p"), ("irsbot2", "r")])
def test_interpolated_dual_bound_is_valid_and_never_above_the_vertex_bound(robot, target):
    """For patches around directions of a real error set: the dual-interpolation bound (issue 13)
    is above h at 40 directions inside the patch, each solved to 1e-10, and not above the
    sublinearity bound of the vertex values."""
    from evotol.robots.clearance.support import solve_support, true_dual

    if robot == "fivebar":
        from evotol.robots.fivebar import FiveBar

        Ct, Bt, nd, groups = _block(FiveBar().clearance_mechanism(), [0.0, 0.07], target)
    else:
        from evotol.robots.irsbot2 import IRSBot2

        Ct, Bt, nd, groups = _block(IRSBot2.thesis("VI.1").clearance_mechanism(), [0.0, -0.05], target)
    k = Ct.shape[1]
    rng = np.random.default_rng(5)

    def solve(U, tol):
        a = np.einsum("qr,pq->pr", Ct[0], U)
        n = len(U)
        res = solve_support(a, np.repeat(Bt, n, 0), nd, tol=tol * np.abs(a).sum(1), groups=groups)
        return res, a

    tighter = 0
    for _ in range(12):
        centre = me.normalise(rng.normal(size=k))
        U = me.normalise(centre + rng.uniform(0.05, 0.5) * rng.normal(size=(k, k)))
        if np.min(U @ U.T) <= 0.2:
            continue
        res, a = solve(U, 1e-3)                           # vertex duals of moderate precision
        Y = a + np.einsum("prm,pm->pr", np.repeat(Bt, len(U), 0), res.mu)
        H = true_dual(Y, nd)
        vertex = me.patch_bound(U[None], H[None])[0]
        interp = me.interpolated_bound(U[None], Y[None], nd, 6)[0]
        assert interp <= vertex * (1 + 1e-12)
        tighter += interp < vertex * (1 - 1e-6)
        L = rng.dirichlet(np.ones(k), 40)
        inside = me.normalise(L @ U)
        exact, _ = solve(inside, 1e-10)
        assert np.all(exact.lower <= interp * (1 + 1e-9))
    assert tighter >= 1


def _agree(mech, poses):
    new = max_pose_error(mech, poses)
    old = max_pose_error(mech, poses, options=LEGACY)
    for r in (new, old):
        assert r.gap.max() <= 1e-3
    for a, b in ((new, old), (old, new)):
        assert np.all(a.p_max <= b.p_upper * (1 + 1e-12))
        assert np.all(a.r_max <= b.r_upper * (1 + 1e-12))
    return new, old


def test_fivebar_map_agrees_with_the_engine_before_issue_13():
    from evotol.robots.fivebar import FiveBar

    fb = FiveBar()
    new, old = _agree(fb.clearance_mechanism(), fb.workspace.grid(5))
    assert np.max(np.abs(new.p_max / old.p_max - 1)) < 1e-3


def test_irsbot2_distal_map_agrees_with_the_engine_before_issue_13():
    from evotol.robots.irsbot2 import MAP_WORKSPACE, IRSBot2

    mech = IRSBot2.thesis("VI.1").clearance_mechanism(parallelograms=False)
    new, old = _agree(mech, MAP_WORKSPACE.grid(3))
    assert np.max(np.abs(new.p_max / old.p_max - 1)) < 1e-3


def test_path_predictor_keeps_the_certificate_with_fewer_newton_iterations():
    """The predictor scaled by tau_old / tau_new (mu(tau) ~ mu* + c / tau near the optimum) and the
    growth 16 of the barrier parameter: same brackets as the solver before it, fewer Newton steps
    (counted, not timed)."""
    from dataclasses import replace

    from evotol.robots.fivebar import FiveBar

    fb = FiveBar()
    mech, poses = fb.clearance_mechanism(), fb.workspace.grid(4)
    counts, res = {}, {}
    old_solver = replace(DEFAULT, predictor=LEGACY.predictor, growth=LEGACY.growth)
    for name, opts in (("new", DEFAULT), ("old", old_solver)):
        res[name] = max_pose_error(mech, poses, options=opts)
        counts[name] = res[name].n_newton
    assert counts["new"] < 0.8 * counts["old"]
    a, b = res["new"], res["old"]
    assert a.gap.max() <= 1e-3 and b.gap.max() <= 1e-3
    for x, y in ((a, b), (b, a)):
        assert np.all(x.p_max <= y.p_upper * (1 + 1e-12)) and np.all(x.r_max <= y.r_upper * (1 + 1e-12))

"""The compiled barrier-Newton iteration (evotol.robots.clearance.newton_kernel) against the NumPy one.

The NumPy iteration is the reference: both must take the same step (Hessian, decrement, new
iterate) on the block-sparse loop maps of the IRSBot-2 (one dense group; four overlapping
groups), on tiny planar problems and on problems without disks or intervals, and the whole
support solve must return the same certified brackets and the same Newton work."""
import numpy as np
import pytest

from evotol.robots.clearance import max_pose_error, newton_kernel
from evotol.robots.clearance import support
from evotol.robots.clearance.options import DEFAULT, NUMPY
from evotol.robots.clearance.support import _merge_groups, _numpy_iteration, solve_support

pytestmark = pytest.mark.skipif(not newton_kernel.AVAILABLE, reason="numba not importable: NumPy iteration only")


def _layout(nd, ni, m, groups):
    """Permuted-row layout as solve_support builds it: (grows, gB builder) for given groups
    ((disk cones, interval rows, columns), ...) with disks/intervals contiguous per group."""
    groups = _merge_groups(groups)
    grows, d0, i0 = [], 0, 2 * nd
    for dc, ir, cols in groups:
        grows.append((slice(2 * d0, 2 * d0 + 2 * len(dc)), slice(i0, i0 + len(ir)), np.asarray(cols, int),
                      slice(d0, d0 + len(dc))))
        d0, i0 = d0 + len(dc), i0 + len(ir)
    return grows


CASES = {
    "irsbot2-distal (dense)": (32, 32, 18, [(range(32), range(64, 96), range(18))]),
    "irsbot2-parallelograms (4 groups)": (48, 48, 30, [
        (range(0, 8), range(96, 104), range(12, 24)), (range(8, 24), range(104, 120), [*range(0, 6), *range(12, 18)]),
        (range(24, 32), range(120, 128), range(12, 30)), (range(32, 48), range(128, 144), range(6, 18))]),
    "5-bar (tiny)": (4, 7, 3, [(range(4), range(8, 15), range(3))]),
    "disks only": (6, 0, 4, [(range(6), [], range(4))]),
    "intervals only": (0, 9, 5, [([], range(0, 9), range(5))]),
}


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.parametrize("tau", [0.3, 30.0, 3e4])
def test_one_iteration_equals_numpy(name, tau):
    """One step of the compiled kernel equals one step of the NumPy reference (Hessian to 1e-13).

    Kept on the private ``_numpy_iteration`` and ``_merge_groups``: a single iteration is internal
    to ``solve_support``; its public ``kernel=True/False`` flag is compared on whole solves below
    (test_solve_support_kernel_flag, test_certified_maps_agree_with_the_numpy_iteration), which
    would not locate a wrong step."""
    nd, ni, m, groups = CASES[name]
    R = 2 * nd + ni
    rng = np.random.default_rng(hash(name) % 2 ** 32)
    k = 64
    grows = _layout(nd, ni, m, groups)
    mask = np.zeros((R, m), bool)
    for dr, ir, cols, _ in grows:
        mask[dr, cols[:, None]] = True
        mask[ir, cols[:, None]] = True
    B = rng.standard_normal((k, R, m)) * mask
    Y = rng.standard_normal((k, R)) / tau
    mu = rng.standard_normal((k, m))
    taus = np.full(k, tau) * rng.uniform(0.5, 2.0, k)
    gB = [(B[:, dr][:, :, cols], B[:, ir][:, :, cols]) for dr, ir, cols, _ in grows]
    dense = len(grows) == 1 and np.array_equal(grows[0][2], np.arange(m))
    H1, l1, mu1, Y1, f1 = _numpy_iteration(Y.copy(), mu.copy(), taus, nd, R, m, grows, gB, dense, True)
    Y2, mu2 = Y.copy(), mu.copy()
    rows = np.arange(k)[::-1].copy()             # working problem i reads original problem rows[i]
    blocks = newton_kernel.group_blocks(B, grows)
    GB = np.empty_like(blocks)
    GB[rows] = blocks
    H2, l2, f2, fail = newton_kernel.newton_iterate(Y2, mu2, GB, rows, taus, nd, newton_kernel.group_arrays(grows, nd), True)
    assert not fail.any()
    scale = np.abs(H1).max(axis=(1, 2))[:, None, None]
    np.testing.assert_allclose(H2 / scale, H1 / scale, rtol=0, atol=1e-13)
    np.testing.assert_allclose(l2, l1, rtol=1e-9, atol=1e-12 * l1.max())
    np.testing.assert_allclose(Y2, Y1, rtol=0, atol=1e-9 * np.abs(Y1).max())
    np.testing.assert_allclose(mu2, mu1, rtol=0, atol=1e-9 * np.abs(mu1).max())
    np.testing.assert_allclose(f2, f1, rtol=1e-12)


def test_kernel_rejects_arrays_it_cannot_update_in_place():
    Y = np.zeros((2, 6))[:, ::2]
    with pytest.raises(ValueError, match="Y must be a writeable C-contiguous"):
        newton_kernel.newton_iterate(Y, np.zeros((2, 2)), np.zeros((2, 6)), np.arange(2), np.ones(2), 0,
                                     newton_kernel.group_arrays([(slice(0, 0), slice(0, 3), np.arange(2), slice(0, 0))], 0), False)


@pytest.fixture(scope="module")
def irsbot2_poses():
    from evotol.robots.irsbot2 import MAP_WORKSPACE, IRSBot2
    W = MAP_WORKSPACE
    rng = np.random.default_rng(3)
    pts = np.column_stack([rng.uniform(W.low[0], 0.0, 6), rng.uniform(W.low[1], W.high[1], 6)])
    return IRSBot2.thesis("VI.1"), pts


@pytest.mark.parametrize("parallelograms", [False, True])
def test_certified_maps_agree_with_the_numpy_iteration(irsbot2_poses, parallelograms):
    """Whole engine, both iterations: brackets overlap, gaps <= 0.1 %, the same Newton work
    to within a few iterations (round-off can move a stopping test by one iteration)."""
    robot, pts = irsbot2_poses
    mech = robot.clearance_mechanism(parallelograms=parallelograms)
    out = {}
    for kern, opts in ((False, NUMPY), (True, DEFAULT)):
        res = max_pose_error(mech, pts, options=opts)
        out[kern] = (res, res.n_newton)
    (a, na), (b, nb) = out[False], out[True]
    for lo, up in (("p_max", "p_upper"), ("r_max", "r_upper")):
        la, ua, lb, ub = (getattr(r, f) for r in (a, b) for f in (lo, up))
        assert np.all(np.maximum(la, lb) <= np.minimum(ua, ub) * (1 + 1e-12))
    assert a.gap.max() <= 1e-3 and b.gap.max() <= 1e-3
    assert abs(na - nb) <= 0.02 * na


def test_solve_support_kernel_flag(irsbot2_poses):
    """kernel=True and kernel=False certify the same support values on one batch of directions."""
    robot, pts = irsbot2_poses
    mech = robot.clearance_mechanism()
    pm = mech.pose_maps(pts[:2])[0]
    D = pm.row_bounds(mech.default_bounds()[None].repeat(2, 0))
    Bt = pm.B * D[..., None]
    u = np.random.default_rng(0).standard_normal((2, 5, 3))
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    Ct = pm.C_pos * D[:, None, :]
    a = np.einsum("kqr,kdq->kdr", Ct, u).reshape(10, -1)
    B = np.repeat(Bt, 5, axis=0)
    r0 = solve_support(a, B, pm.n_disk, tol=1e-9 * np.abs(a).sum(-1), groups=pm.groups, kernel=False)
    r1 = solve_support(a, B, pm.n_disk, tol=1e-9 * np.abs(a).sum(-1), groups=pm.groups, kernel=True)
    for r in (r0, r1):
        assert np.all(r.lower <= r.upper * (1 + 1e-12))
    np.testing.assert_allclose(r1.upper, r0.upper, rtol=1e-8)
    np.testing.assert_allclose(r1.lower, r0.lower, rtol=1e-8)


def test_without_numba_the_numpy_iteration_runs(monkeypatch):
    """EVOTOL_NO_NUMBA=1 (or numba missing): no kernel, same certified result; asking for the
    kernel then is an error naming the field."""
    import json
    import os
    import subprocess
    import sys

    from evotol.errors import ValidationError
    from evotol.robots.fivebar import FiveBar

    code = ("import json, numpy as np\n"
            "from evotol.robots.clearance import newton_kernel, max_pose_error\n"
            "from evotol.robots.fivebar import FiveBar\n"
            "r = max_pose_error(FiveBar().clearance_mechanism(), [[0.0, 0.07], [0.01, 0.05]])\n"
            "import sys; print(json.dumps([newton_kernel.AVAILABLE, 'numba' in sys.modules, r.p_max.tolist(), r.p_upper.tolist()]))\n")
    env = {**os.environ, "EVOTOL_NO_NUMBA": "1"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    available, imported, p_max, p_upper = json.loads(out.stdout.strip().splitlines()[-1])
    assert available is False and imported is False
    ref = max_pose_error(FiveBar().clearance_mechanism(), [[0.0, 0.07], [0.01, 0.05]])
    assert np.all(np.maximum(ref.p_max, p_max) <= np.minimum(ref.p_upper, p_upper) * (1 + 1e-12))
    monkeypatch.setattr(newton_kernel, "AVAILABLE", False)
    with pytest.raises(ValidationError, match="kernel"):
        solve_support(np.ones((1, 4)), np.ones((1, 4, 1)), 1, tol=1e-6, kernel=True)


def test_first_compile_is_announced(tmp_path, caplog, capsys):
    """A fresh install compiles the kernels on the first solve (~10 s): one log line says so (INFO,
    through ``logging``, never a print: issue 40)."""
    import logging
    from types import SimpleNamespace

    def fake(index):
        return SimpleNamespace(_cache=SimpleNamespace(_cache_file=SimpleNamespace(_index_path=str(index))))

    with caplog.at_level(logging.INFO, logger="evotol.robots.clearance.newton_kernel"):
        newton_kernel._say_if_compiling(fake(tmp_path / "missing.nbi"))
        assert [r.name for r in caplog.records] == ["evotol.robots.clearance.newton_kernel"]
        assert "compiling the clearance engine's Newton kernels" in caplog.records[0].getMessage()
        caplog.clear()
        (tmp_path / "there.nbi").write_text("")
        newton_kernel._say_if_compiling(fake(tmp_path / "there.nbi"))
        newton_kernel._say_if_compiling(object())          # numba internals changed: silent
        assert caplog.records == []
    assert capsys.readouterr().out == ""


def test_warm_up_compiles_every_signature_the_solver_uses():
    """warm_up() (run before worker pools start) leaves nothing to compile for a real solve."""
    from evotol.robots.fivebar import FiveBar
    from evotol.robots.irsbot2 import MAP_WORKSPACE, IRSBot2

    assert support.warm_up() is True
    before = [len(f.signatures) for f in newton_kernel._kernel()]
    centre = (np.array(MAP_WORKSPACE.low) + np.array(MAP_WORKSPACE.high)) / 2
    max_pose_error(IRSBot2.thesis("VI.1").clearance_mechanism(parallelograms=True), centre[None])
    max_pose_error(FiveBar().clearance_mechanism(), [[0.0, 0.07]])
    assert [len(f.signatures) for f in newton_kernel._kernel()] == before


def _cholesky_row_by_row(H):
    """The textbook Cholesky-Crout order (row by row, each sum from the first column on), in plain
    Python floats: the reference of the blocked factor's bits."""
    m = len(H)
    L = [[0.0] * m for _ in range(m)]
    for a in range(m):
        for b in range(a + 1):
            v = float(H[a][b])
            for c in range(b):
                v -= L[a][c] * L[b][c]
            if a == b:
                if v <= 0.0:
                    return None
                L[a][a] = v ** 0.5
            else:
                L[a][b] = v / L[b][b]
    return np.array(L)


@pytest.mark.parametrize("m", [1, 3, 4, 5, 8, 18, 30, 33])
def test_blocked_cholesky_is_the_row_by_row_factor_to_the_last_bit(m):
    """The factor of the Newton step and of the predictor (rows four at a time, the sums left of the
    block side by side) is the textbook row-by-row factor bit for bit, ``L L^T = H`` to round-off, and
    it refuses an indefinite matrix as the row-by-row factor does."""
    from evotol.robots.clearance.newton_kernel_bodies import _chol_factor

    rng = np.random.default_rng(m)
    A = rng.standard_normal((m, 2 * m + 1))
    H = A @ A.T
    L = np.zeros((m, m))
    assert _chol_factor(H, L, m)
    ref = _cholesky_row_by_row(H)
    assert np.array_equal(np.tril(L), ref)
    np.testing.assert_allclose(np.tril(L) @ np.tril(L).T, H, rtol=0, atol=1e-12 * np.abs(H).max())
    if m > 1:
        H[m - 1, m - 1] = -1.0
        assert _cholesky_row_by_row(H) is None
        assert not _chol_factor(H, np.zeros((m, m)), m)

"""Accuracy measures: exact worst case (support function) vs brute force and closed forms; RSS."""
import numpy as np
import pytest

from evotol.measures import linear as measures
def _blocks(rng, n_poses, dims):
    return [rng.normal(size=(n_poses, 3, d)) for d in dims]


def test_worst_case_of_intervals_matches_vertex_enumeration():
    """For intervals only, K is a zonotope: the farthest point is a vertex Σ ±t_j b_j."""
    rng = np.random.default_rng(0)
    blocks = _blocks(rng, 4, [1] * 7)
    t = rng.uniform(0.5, 2, 7)
    wc = measures.worst_case(blocks, t)
    signs = np.array(np.meshgrid(*[[-1, 1]] * 7)).reshape(7, -1).T
    for p in range(4):
        B = np.stack([b[p, :, 0] for b in blocks], 1)
        brute = np.max(np.linalg.norm((signs * t) @ B.T, axis=1))
        assert wc.value[p] == pytest.approx(brute, rel=1e-10)
        assert wc.bound[p] >= brute * (1 - 1e-12)
        assert wc.bound[p] <= brute * 1.005


def test_worst_case_with_disks_is_attained_and_bounded():
    """Disks: h(u*) is attained by explicit errors and never exceeds the proven bound; random
    points of K never exceed it."""
    rng = np.random.default_rng(1)
    blocks = _blocks(rng, 3, [1, 2, 2, 3, 1])
    t = rng.uniform(0.2, 1.0, 5)
    wc = measures.worst_case(blocks, t)
    errs = measures.worst_case_errors(blocks, t, wc.direction)
    for p in range(3):
        x = sum(B[p] @ e[p] for B, e in zip(blocks, errs))
        assert np.linalg.norm(x) == pytest.approx(wc.value[p], rel=1e-9)
        assert all(np.linalg.norm(e[p]) <= tj * (1 + 1e-12) for e, tj in zip(errs, t))
        # random boundary points of every source never beat it
        for _ in range(200):
            pts = []
            for B, tj in zip(blocks, t):
                v = rng.normal(size=B.shape[2])
                pts.append(B[p] @ (tj * v / np.linalg.norm(v)))
            assert np.linalg.norm(sum(pts)) <= wc.value[p] * (1 + 1e-9)
    assert np.all(wc.bound >= wc.value) and np.all(wc.bound <= wc.value * 1.005)
    np.testing.assert_allclose(wc.contributions.sum(axis=-1), 1.0)


def test_serial_closed_form_parallel_columns_add_up():
    """Collinear effects add linearly: worst case = Σ t_j |b_j| when all b_j are parallel."""
    b = np.array([0.3, -0.4, 1.2])
    blocks = [np.tile((k * b)[None, :, None], (2, 1, 1)) for k in (1.0, 2.0, -0.5)]
    t = np.array([1.0, 0.5, 2.0])
    wc = measures.worst_case(blocks, t)
    np.testing.assert_allclose(wc.value, np.sum(t * np.array([1, 2, 0.5])) * np.linalg.norm(b), rtol=1e-10)


def test_hemisphere_covering_angle_is_exact():
    D, delta = measures.hemisphere(300)
    rng = np.random.default_rng(2)
    probe = rng.normal(size=(50000, 3))
    probe /= np.linalg.norm(probe, axis=1, keepdims=True)
    worst = np.arccos(np.max(np.abs(probe @ D.T), axis=1)).max()
    assert worst <= delta and worst > 0.8 * delta


def test_rss_is_root_sum_square_of_spectral_norms():
    rng = np.random.default_rng(3)
    blocks = _blocks(rng, 5, [1, 2, 3])
    s = measures.spectral_norms(blocks)
    for j, B in enumerate(blocks):
        for p in range(5):
            assert s[p, j] == pytest.approx(np.linalg.svd(B[p], compute_uv=False)[0])
    t = np.array([1.0, 2.0, 0.5])
    np.testing.assert_allclose(measures.rss(s, t), np.sqrt(((s * t) ** 2).sum(1)))

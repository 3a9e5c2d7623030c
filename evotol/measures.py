"""Accuracy measures of a linear error model: worst case (exact) and RSS.

Notation: at one pose, source j (tolerance t_j, error vector e_j with |e_j| <= t_j, dimension 1, 2
or 3) moves the end-effector by B_j e_j, where B_j is the 3×dim block of the sensitivity for the
position (m/m or m/rad) or the orientation (rad/...).

Worst case. The reachable error set is the Minkowski sum of the segments/disks/balls t_j·B_j·𝔹,
a convex symmetric set K. Its largest norm is the maximum of its support function over unit
directions u:   max_{e ∈ K} |e| = max_{|u|=1} h(u),   h(u) = Σ_j t_j ‖B_jᵀ u‖.
h is convex and positively homogeneous, so the fixed-point step u ← ∇h(u)/‖∇h(u)‖ never decreases
h (h(v) ≥ ∇h(u)·v by convexity + Euler). We start it from the best point of a hemisphere grid
with covering angle δ and report:
  * ``value``  – h(u*) after refinement: *attained* by the explicit errors e_j = t_j B_jᵀu*/‖B_jᵀu*‖;
  * ``bound``  – max over the grid / cos δ: a *proven* upper bound (for every u there is a grid
    direction g with angle ≤ δ, and h(g) ≥ g·x* ≥ |x*| cos δ at the farthest point x*).
For a planar output (one non-zero row) the same formulas hold with a circle of directions.

RSS (statistical). ``rss = sqrt(Σ_j (t_j ‖B_j‖₂)²)``: the root sum square of every source's
worst-case contribution (‖B_j‖₂ = largest singular value). It is the usual statistical stack-up
with each tolerance taken as the same multiple of its standard deviation.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

MEASURES = ("worst_case", "rss", "mc_quantile", "yield")   # yield: evotol.statistical


@lru_cache(maxsize=16)
def hemisphere(n: int = 600) -> tuple[np.ndarray, float]:
    """Fibonacci directions on the upper unit hemisphere (z >= 0), shape (n, 3), and the covering
    angle δ (rad) of the full sphere by ±these directions (measured by dense random probing and
    inflated by 10 %, so 1/cos δ is a safe bound factor)."""
    i = np.arange(n) + 0.5
    z = i / n                       # uniform in (0, 1): equal-area on the hemisphere
    phi = np.pi * (1 + 5 ** 0.5) * i
    r = np.sqrt(1 - z ** 2)
    D = np.stack([r * np.cos(phi), r * np.sin(phi), z], 1)
    # Exact covering angle of the sphere by ±D: the largest angle between a vertex of the
    # spherical Voronoi diagram of ±D and its generator (the points farthest from the set).
    from scipy.spatial import SphericalVoronoi

    pts = np.concatenate([D, -D])
    sv = SphericalVoronoi(pts, radius=1.0, threshold=1e-9)
    best = np.max(sv.vertices @ pts.T, axis=1)   # cos of the angle to the nearest point
    delta = float(np.arccos(np.clip(best.min(), -1, 1))) * (1 + 1e-9)
    return D, delta


def circle(n: int = 360) -> tuple[np.ndarray, float]:
    """Half circle of directions in the xy plane, (n, 3), covering angle δ = π/(2n)."""
    a = (np.arange(n) + 0.5) * np.pi / n
    return np.stack([np.cos(a), np.sin(a), np.zeros(n)], 1), np.pi / (2 * n)


def directions_for(blocks: np.ndarray, n: int = 600) -> tuple[np.ndarray, float]:
    """Pick sphere or circle directions for position/orientation blocks (..., 3, k)."""
    active = np.any(np.abs(blocks) > 0, axis=tuple(i for i in range(blocks.ndim) if i != blocks.ndim - 2))
    if not active[2] and active[:2].any():
        return circle(max(n // 2, 90))
    if not active[0] and not active[1] and active[2]:
        return np.array([[0.0, 0.0, 1.0]]), 0.0
    return hemisphere(n)


@dataclass(frozen=True)
class WorstCase:
    """Worst-case error at each pose: attained value, certified bound, worst direction, errors."""

    value: np.ndarray       # (..., n_poses) attained maximum |error|
    bound: np.ndarray       # (..., n_poses) proven upper bound
    direction: np.ndarray   # (..., n_poses, 3) worst direction u*
    contributions: np.ndarray  # (..., n_poses, n_sources) t_j ‖B_jᵀu*‖ / h(u*)


def support_coefficients(blocks: list[np.ndarray], D: np.ndarray) -> np.ndarray:
    """c[p, d, j] = ‖B_jᵀ u_d‖ for blocks B_j (n_poses, 3, dim_j); shape (n_poses, n_dir, n_src)."""
    out = np.empty((blocks[0].shape[0], D.shape[0], len(blocks)))
    for j, B in enumerate(blocks):
        proj = np.matmul(np.swapaxes(B, 1, 2), D.T)          # (p, k, d)
        out[:, :, j] = np.sqrt(np.sum(proj * proj, axis=1))
    return out


def _stack(blocks: list[np.ndarray]):
    """Concatenate blocks along columns; returns (Bcat (p, 3, K), column -> source index)."""
    Bcat = np.concatenate(blocks, axis=2)
    owner = np.repeat(np.arange(len(blocks)), [B.shape[2] for B in blocks])
    return Bcat, owner


def _h_and_grad(Bcat, owner, starts, t, u):
    """h(u) and ∇h(u) for designs t (n, n_src), directions u (n, p, 3)."""
    w = np.matmul(u[:, :, None, :], Bcat[None])[:, :, 0, :]            # (n, p, K) = B_jᵀ u
    nw = np.sqrt(np.add.reduceat(w * w, starts, axis=2))              # (n, p, n_src)
    h = np.einsum("npj,nj->np", nw, t)
    scale = np.where(nw > 0, t[:, None, :] / np.where(nw > 0, nw, 1.0), 0.0)[:, :, owner]
    grad = np.matmul(Bcat[None], (w * scale)[..., None])[..., 0]      # (n, p, 3)
    return h, grad, nw


def refine_direction(blocks: list[np.ndarray], t: np.ndarray, u: np.ndarray, iters: int = 60) -> tuple[np.ndarray, np.ndarray]:
    """Ascent u ← ∇h/‖∇h‖ on h(u) = Σ_j t_j ‖B_jᵀu‖, vectorised over designs and poses.

    blocks: list of (n_poses, 3, dim); t: (n_designs, n_src); u: (n_designs, n_poses, 3).
    Returns (u*, h(u*)) with shapes (n_designs, n_poses, 3) and (n_designs, n_poses).
    """
    Bcat, owner = _stack(blocks)
    starts = np.concatenate([[0], np.cumsum([B.shape[2] for B in blocks])[:-1]])
    h_prev = None
    for _ in range(iters):
        h, grad, _ = _h_and_grad(Bcat, owner, starts, t, u)
        g = np.linalg.norm(grad, axis=-1, keepdims=True)
        u_new = np.where(g > 0, grad / np.where(g > 0, g, 1.0), u)
        if h_prev is not None and np.max(np.abs(h - h_prev)) <= 1e-14 * max(np.max(h), 1e-300):
            break
        u, h_prev = u_new, h
    h, _, _ = _h_and_grad(Bcat, owner, starts, t, u)
    return u, h


def worst_case(blocks: list[np.ndarray], t: np.ndarray, n_directions: int = 600,
               coefficients: tuple[np.ndarray, np.ndarray, float] | None = None, top_only: bool = False) -> WorstCase:
    """Exact worst-case error norm at every pose for designs ``t`` (n_designs, n_src) or (n_src,).

    ``coefficients`` = (c, D, δ) from :func:`support_coefficients` may be passed to reuse them.
    ``top_only``: refine only the poses that can hold the maximum (others keep their grid value,
    a lower estimate) -- enough for the largest error, much faster on many poses.
    """
    t = np.asarray(t, dtype=float)
    single = t.ndim == 1
    T = np.atleast_2d(t)
    if coefficients is None:
        D, delta = directions_for(np.concatenate(blocks, axis=2), n_directions)
        c = support_coefficients(blocks, D)
    else:
        c, D, delta = coefficients
    grid = np.moveaxis((c.reshape(-1, c.shape[2]) @ T.T).reshape(c.shape[0], c.shape[1], -1), 2, 0)  # (n, p, d)
    k = np.argmax(grid, axis=2)
    gmax = np.take_along_axis(grid, k[..., None], axis=2)[..., 0]
    u0 = D[k]
    if top_only:
        # poses whose proven bound is below the best attained grid value cannot hold the maximum
        keep = np.flatnonzero(np.any(gmax / np.cos(delta) >= gmax.max(axis=1, keepdims=True), axis=0))
        u, h = u0.copy(), gmax.copy()
        if keep.size:
            u_k, h_k = refine_direction([B[keep] for B in blocks], T, u0[:, keep])
            u[:, keep], h[:, keep] = u_k, h_k
    else:
        u, h = refine_direction(blocks, T, u0)
    h = np.maximum(h, gmax)
    bound = np.maximum(gmax / np.cos(delta), h)
    contrib = np.empty(T.shape[:1] + (blocks[0].shape[0], len(blocks)))
    for j, B in enumerate(blocks):
        w = np.einsum("pik,npi->npk", B, u)
        contrib[:, :, j] = T[:, j:j + 1] * np.sqrt(np.einsum("npk,npk->np", w, w))
    contrib /= np.where(h > 0, h, 1.0)[..., None]
    res = WorstCase(h, bound, u, contrib)
    if single:
        res = WorstCase(h[0], bound[0], u[0], contrib[0])
    return res


def worst_case_errors(blocks: list[np.ndarray], t: np.ndarray, u: np.ndarray) -> list[np.ndarray]:
    """The explicit source errors that attain h(u) at each pose: e_j = t_j B_jᵀu/‖B_jᵀu‖.

    t: (n_src,), u: (n_poses, 3); returns a list of (n_poses, dim_j) arrays.
    """
    out = []
    for j, B in enumerate(blocks):
        w = np.einsum("pik,pi->pk", B, u)
        nw = np.linalg.norm(w, axis=1, keepdims=True)
        out.append(np.where(nw > 0, t[j] * w / np.where(nw > 0, nw, 1.0), 0.0))
    return out


def spectral_norms(blocks: list[np.ndarray]) -> np.ndarray:
    """‖B_j‖₂ at every pose, shape (n_poses, n_src): each source's largest effect per unit tolerance."""
    return np.stack([np.linalg.norm(B, ord=2, axis=(1, 2)) if B.shape[2] > 1 else np.linalg.norm(B[:, :, 0], axis=1)
                     for B in blocks], axis=1)


def rss(sens: np.ndarray, t: np.ndarray) -> np.ndarray:
    """RSS error sqrt(Σ_j (t_j s_pj)²) for sensitivities (n_poses, n_src) and t (..., n_src) -> (..., n_poses)."""
    t = np.asarray(t, dtype=float)
    return np.sqrt(np.einsum("pj,...j->...p", sens ** 2, t ** 2))

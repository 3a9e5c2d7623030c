"""Accuracy measures of a linear error model: worst case (exact) and RSS.

Notation: at one pose, source j (tolerance t_j, error vector e_j with ``|e_j| <= t_j``, dimension 1, 2
or 3) moves the end-effector by B_j e_j, where B_j is the 3×dim block of the sensitivity for the
position (m/m or m/rad) or the orientation (rad/...).

Worst case. The reachable error set is the Minkowski sum of the segments/disks/balls t_j·B_j·𝔹,
a convex symmetric set K. Its largest norm is the maximum of its support function over unit
directions u:   ``max_{e ∈ K} |e| = max_{|u|=1} h(u)``,   h(u) = Σ_j t_j ‖B_jᵀ u‖.
h is convex and positively homogeneous, so the fixed-point step u ← ∇h(u)/‖∇h(u)‖ never decreases
h (h(v) ≥ ∇h(u)·v by convexity + Euler). We start it from the best point of a hemisphere grid
with covering angle δ and report:

* ``value``  – h(u*) after refinement: *attained* by the explicit errors ``e_j = t_j B_jᵀu*/‖B_jᵀu*‖``;
* ``bound``  – max over the grid / cos δ: a *proven* upper bound (for every u there is a grid
  direction g with angle ≤ δ, and ``h(g) ≥ g·x* ≥ |x*| cos δ`` at the farthest point x*).

For a planar output (one non-zero row) the same formulas hold with a circle of directions.

RSS (statistical). ``rss = sqrt(Σ_j (t_j ‖B_j‖₂)²)``: the root sum square of every source's
worst-case contribution (‖B_j‖₂ = largest singular value). It is the usual statistical stack-up
with each tolerance taken as the same multiple of its standard deviation.

Asymmetric intervals (``docs/tolerances.md``; the support function with a mean shift and the RSS
with a shift ``|s(t)| + sqrt(Σ_j (ρ_j t_j ‖B_j‖₂)²)``): :mod:`evotol.measures.linear.support`. The
direction grids and their covering angle δ: :mod:`evotol.measures.linear.directions`.

The parameters several definitions of this module share are described once, here.

Parameters
----------
shape : IntervalShape, optional
    Interval shape; None: plain ±t.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.measures.linear.directions import directions_for
from evotol.measures.linear.support import IntervalShape, mean_shift, support_coefficients, support_constant
from evotol.measures.linear.support_grid import support_grid


@dataclass(frozen=True)
class WorstCase:
    """Worst-case error at each pose: attained value, certified bound, worst direction, errors.

    Units follow the component: m for position, rad for orientation.

    Parameters
    ----------
    value : ndarray, shape (..., n_poses)
        Attained maximum error norm h(u*) (m or rad).
    bound : ndarray, shape (..., n_poses)
        Proven upper bound on the error norm (grid maximum / cos δ, at least ``value``).
    direction : ndarray, shape (..., n_poses, 3)
        The worst direction u* (unit vector).
    contributions : ndarray, shape (..., n_poses, n_sources)
        Each source's share of h(u*) (dimensionless fraction, mean shift included).
    """

    value: np.ndarray       # (..., n_poses) attained maximum |error|
    bound: np.ndarray       # (..., n_poses) proven upper bound
    direction: np.ndarray   # (..., n_poses, 3) worst direction u*
    contributions: np.ndarray  # (..., n_poses, n_sources) share of h(u*), mean shift included


#: bytes of the (designs, poses, directions) grid and the ascent's temporaries evaluated at once: more designs
#: than fit are evaluated in blocks of designs (each design's numbers are computed alike; issue 43 item 4)
DESIGN_BLOCK_BYTES = 64 * 2 ** 20


def _stack(blocks: list[np.ndarray]):
    """Concatenate blocks along columns; returns (Bcat (p, 3, K), column -> source index)."""
    Bcat = np.concatenate(blocks, axis=2)
    owner = np.repeat(np.arange(len(blocks)), [B.shape[2] for B in blocks])
    return Bcat, owner


def _h_and_grad(Bcat, owner, starts, t, u, shift=None):
    """h(u) and ∇h(u) for half-widths t (n, n_src), directions u (n, p, 3), mean shift (n, p, 3)."""
    w = np.matmul(u[:, :, None, :], Bcat[None])[:, :, 0, :]            # (n, p, K) = B_jᵀ u
    nw = np.sqrt(np.add.reduceat(w * w, starts, axis=2))              # (n, p, n_src)
    h = np.einsum("npj,nj->np", nw, t)
    scale = np.where(nw > 0, t[:, None, :] / np.where(nw > 0, nw, 1.0), 0.0)[:, :, owner]
    grad = np.matmul(Bcat[None], (w * scale)[..., None])[..., 0]      # (n, p, 3)
    if shift is not None:
        h = h + np.einsum("npi,npi->np", u, shift)
        grad = grad + shift
    return h, grad, nw


def refine_direction(blocks: list[np.ndarray], t: np.ndarray, u: np.ndarray, iters: int = 60,
                     shift: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Ascent u ← ∇h/‖∇h‖ on h(u) = u·s + Σ_j t_j ‖B_jᵀu‖, vectorised over designs and poses.

    Parameters
    ----------
    t : ndarray, shape (n_designs, n_src)
        Half-widths ρ_j t_j (SI: m or rad).
    u : ndarray, shape (n_designs, n_poses, 3)
        Starting unit directions.
    iters : int
        Maximum number of ascent steps (stops earlier once h stops changing).
    shift : ndarray, shape (n_designs, n_poses, 3), optional
        Mean shift s (m or rad); None: centred set.

    Returns
    -------
    u : ndarray, shape (n_designs, n_poses, 3)
        The refined directions u*.
    h : ndarray, shape (n_designs, n_poses)
        h(u*), the attained error norm (m or rad).
    """
    Bcat, owner = _stack(blocks)
    starts = np.concatenate([[0], np.cumsum([B.shape[2] for B in blocks])[:-1]])
    h_prev = None
    for _ in range(iters):
        h, grad, _ = _h_and_grad(Bcat, owner, starts, t, u, shift)
        g = np.linalg.norm(grad, axis=-1, keepdims=True)
        u_new = np.where(g > 0, grad / np.where(g > 0, g, 1.0), u)
        if h_prev is not None and np.max(np.abs(h - h_prev)) <= 1e-14 * max(np.max(np.abs(h)), 1e-300):
            break
        u, h_prev = u_new, h
    h, _, _ = _h_and_grad(Bcat, owner, starts, t, u, shift)
    return u, h


def worst_case(blocks: list[np.ndarray], t: np.ndarray, n_directions: int = 600,
               coefficients: tuple | None = None, top_only: bool = False,
               shape: IntervalShape | None = None, n_starts: int = 8, top_level: np.ndarray | None = None) -> WorstCase:
    """Exact worst-case error norm at every pose for designs ``t`` (n_designs, n_src) or (n_src,).

    ``coefficients`` = (c, D, δ[, const]) from :func:`support_coefficients` /
    :func:`support_constant` may be passed to reuse them (they must match ``shape``).
    ``top_only``: refine only the poses that can hold the maximum (others keep their grid value,
    a lower estimate) -- enough for the largest error, much faster on many poses.
    ``shape``: asymmetric intervals (:class:`IntervalShape`); the maximum is then taken over the
    full sphere of directions, and the ascent is also started from ``n_starts`` − 1 other good
    grid directions (h has more separated local maxima without central symmetry).
    Many designs are evaluated in blocks of designs whose grid and ascent temporaries fit in
    :data:`DESIGN_BLOCK_BYTES` (a GA population over thousands of poses; issue 43).

    Parameters
    ----------
    t : array_like, shape (n_designs, n_src) or (n_src,)
        Tolerances (SI: m or rad).
    n_directions : int
        Grid directions when ``coefficients`` is not given (more: smaller δ, tighter bound).
    coefficients : tuple, optional
        Precomputed ``(c, D, delta[, const])``.
    top_only : bool
        Refine only the poses that can hold the maximum.
    n_starts : int
        Ascent starts per pose for non-plain shapes.
    top_level : ndarray, shape (n_designs,), optional
        With ``top_only``: each design's largest grid value over every pose, when ``blocks`` hold
        only some of them (:func:`evotol.measures.linear.pose_blocks.worst_case_by_blocks`); default
        the largest over ``blocks``' poses.

    Returns
    -------
    WorstCase
        Per design and pose (the design axis dropped for a single design ``t``).
    """
    t = np.asarray(t, dtype=float)
    single = t.ndim == 1
    T = np.atleast_2d(t)
    plain = shape is None or shape.plain
    if coefficients is None:
        D, delta = directions_for(np.concatenate(blocks, axis=2), n_directions,
                                  full_sphere=not (shape is None or shape.centred))
        c = support_coefficients(blocks, D, None if plain else shape)
        const = None if plain else support_constant(blocks, D, shape)
    else:
        c, D, delta = coefficients[:3]
        const = coefficients[3] if len(coefficients) > 3 else None
    per_design = 8 * c.shape[0] * max(c.shape[1], 4 * sum(B.shape[2] for B in blocks))     # bytes of its largest temporaries
    if T.shape[0] > 1 and T.shape[0] * per_design > DESIGN_BLOCK_BYTES:      # designs in blocks: memory bounded (issue 43)
        step = max(1, DESIGN_BLOCK_BYTES // per_design)
        coef = (c, D, delta) if const is None else (c, D, delta, const)
        parts = [worst_case(blocks, T[i:i + step], coefficients=coef, top_only=top_only, shape=shape, n_starts=n_starts,
                            top_level=None if top_level is None else top_level[i:i + step])
                 for i in range(0, T.shape[0], step)]
        return WorstCase(*(np.concatenate([getattr(r, f) for r in parts]) for f in WorstCase.__dataclass_fields__))
    grid = support_grid((c, D, delta) if const is None else (c, D, delta, const), T)      # (n, p, d)
    k = np.argmax(grid, axis=2)
    gmax = np.take_along_axis(grid, k[..., None], axis=2)[..., 0]
    u0 = D[k]
    if plain:
        Th, shift = T, None
    else:
        Th, shift = T * shape.rho, mean_shift(blocks, shape, T)
    level = gmax.max(axis=1, keepdims=True) if top_level is None else np.asarray(top_level, float)[:, None]
    if top_only:
        # poses whose proven bound is below the best attained grid value cannot hold the maximum
        keep = np.flatnonzero(np.any(gmax / np.cos(delta) >= level, axis=0))
        u, h = u0.copy(), gmax.copy()
        if keep.size:
            u_k, h_k = refine_direction([B[keep] for B in blocks], Th, u0[:, keep],
                                        shift=None if shift is None else shift[:, keep])
            u[:, keep], h[:, keep] = u_k, h_k
    else:
        u, h = refine_direction(blocks, Th, u0, shift=shift)
    if not plain and n_starts > 1 and grid.shape[2] > 1:
        # a non-centred set has more separated local maxima of h: also ascend from the best grid
        # direction of each of a few cones around other good grid points, keep the largest
        keep_all = np.flatnonzero(np.any(gmax / np.cos(delta) >= level, axis=0)) \
            if top_only else np.arange(grid.shape[1])
        g = grid[:, keep_all]                                            # (n, k, d)
        order = np.argsort(-g, axis=2)[:, :, :max(4 * n_starts, 16)]
        # no pose of this block can hold a maximum (blocks of poses, top_only): nothing to ascend from
        for s_ in range(1, n_starts if keep_all.size else 1):
            pick = order[:, :, min(s_ * order.shape[2] // n_starts, order.shape[2] - 1)]
            u_s, h_s = refine_direction([B[keep_all] for B in blocks], Th, D[pick],
                                        shift=None if shift is None else shift[:, keep_all])
            better = h_s > h[:, keep_all]
            hk, uk = h[:, keep_all], u[:, keep_all]
            hk[better], uk[better] = h_s[better], u_s[better]
            h[:, keep_all], u[:, keep_all] = hk, uk
    h = np.maximum(h, gmax)
    bound = np.maximum(gmax / np.cos(delta), h)
    contrib = np.empty(T.shape[:1] + (blocks[0].shape[0], len(blocks)))
    for j, B in enumerate(blocks):
        w = np.einsum("pik,npi->npk", B, u)
        contrib[:, :, j] = Th[:, j:j + 1] * np.sqrt(np.einsum("npk,npk->np", w, w))
        if not plain and B.shape[2] == 1:
            contrib[:, :, j] += (shape.offset[j] + shape.kappa[j] * T[:, j:j + 1]) * w[:, :, 0]
    contrib /= np.where(h > 0, h, 1.0)[..., None]
    res = WorstCase(h, bound, u, contrib)
    if single:
        res = WorstCase(h[0], bound[0], u[0], contrib[0])
    return res


def worst_case_errors(blocks: list[np.ndarray], t: np.ndarray, u: np.ndarray,
                      shape: IntervalShape | None = None) -> list[np.ndarray]:
    """The explicit source errors that attain h(u) at each pose: e_j = c_j + ρ_j t_j B_jᵀu/‖B_jᵀu‖
    (c_j: the interval's centre, 0 for centred tolerances; for an interval source this is the end
    of the interval on the side of u).

    Parameters
    ----------
    t : ndarray, shape (n_src,)
        One design (SI: m or rad).
    u : ndarray, shape (n_poses, 3)
        Worst direction at each pose (unit vectors).

    Returns
    -------
    list of ndarray, each shape (n_poses, dim_j)
        Source errors (SI: m or rad).
    """
    out = []
    for j, B in enumerate(blocks):
        w = np.einsum("pik,pi->pk", B, u)
        nw = np.linalg.norm(w, axis=1, keepdims=True)
        r = t[j] if shape is None else shape.rho[j] * t[j]
        e = np.where(nw > 0, r * w / np.where(nw > 0, nw, 1.0), 0.0)
        if shape is not None and B.shape[2] == 1:
            e = e + shape.offset[j] + shape.kappa[j] * t[j]
        out.append(e)
    return out


def spectral_norms(blocks: list[np.ndarray]) -> np.ndarray:
    """‖B_j‖₂ at every pose, shape (n_poses, n_src): each source's largest effect per unit tolerance.

    Returns
    -------
    ndarray, shape (n_poses, n_src)
        Largest singular value of each block (m or rad per m or rad of source error).
    """
    return np.stack([np.linalg.norm(B, ord=2, axis=(1, 2)) if B.shape[2] > 1 else np.linalg.norm(B[:, :, 0], axis=1)
                     for B in blocks], axis=1)


def rss(sens: np.ndarray, t: np.ndarray, shift_norm: np.ndarray | None = None) -> np.ndarray:
    """RSS error sqrt(Σ_j (t_j s_pj)²) for sensitivities (n_poses, n_src) and t (..., n_src) -> (..., n_poses).

    ``shift_norm`` (..., n_poses): ``|mean shift|``, added linearly (``|s| + RSS``, module docstring);
    pass half-widths ρ_j t_j as ``t`` for asymmetric intervals.

    Parameters
    ----------
    sens : ndarray, shape (n_poses, n_src)
        Spectral norms ‖B_j‖₂ (:func:`spectral_norms`).
    t : array_like, shape (..., n_src)
        Tolerances or half-widths (SI: m or rad).
    shift_norm : ndarray, shape (..., n_poses), optional
        Norm of the mean shift (m or rad), added linearly.

    Returns
    -------
    ndarray, shape (..., n_poses)
        RSS error (m or rad).
    """
    t = np.asarray(t, dtype=float)
    out = np.sqrt(np.einsum("pj,...j->...p", sens ** 2, t ** 2))
    return out if shift_norm is None else out + shift_norm

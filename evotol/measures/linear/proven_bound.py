"""A proven upper bound on the largest error norm, tightened to a relative tolerance.

The worst-case measure (:mod:`evotol.measures.linear`) reports, at each pose, the attained maximum
``L = h(u*)`` of the support function h of the reachable error set K, and the proven bound
``max_g h(g) / cos δ`` of a direction grid with covering angle δ. With 600 directions that bound
sits up to ~0.3 % above L: enough to rank designs, too loose to *prove* that a design meets a
requirement it is allocated to hold with equality.

Here the bound is tightened by branch and bound over spherical caps. Let x* be the farthest point
of K, ``H = |x*| = max_{|u|=1} h(u)``, and u* = x*/H. For a cap C of centre c and angular radius r:
if u* ∈ C then h(c) ≥ c·x* ≥ H cos r, so H ≤ h(c) / cos r. Hence a cap with
h(c) / cos r < L (≤ H) cannot hold u* and is dropped; every other cap is split, and
``H ≤ max(L, max over live caps h(c) / cos r)`` at every step (the caps always cover every
direction u* may take). It stops when that bound is within ``rtol`` of L.

Splitting a cap: its gnomonic image (tangent plane at c, point c + a e1 + b e2) contains the disk
of radius tan r; an m × m grid of squares of side s = 2 tan r / m covers that disk with covering
radius s/√2 in the plane, and the inverse gnomonic map is 1-Lipschitz (its differential has norms
1/(1+ρ²) radially and 1/√(1+ρ²) tangentially), so the children have angular radius
r' = √2 tan r / m (≈ 0.47 r for m = 3). Planar outputs (directions in the xy plane) split arcs
instead: an arc of half-width r into two of half-width r/2.
"""
from __future__ import annotations

import numpy as np

from evotol.measures import linear as measures
#: children per side when a cap is split (9 children, radius ≈ 0.47 r)
SPLIT = 3


def _h(blocks_p: list[np.ndarray], t: np.ndarray, U: np.ndarray, shape) -> np.ndarray:
    """h(u) at one pose for directions U (k, 3): support coefficients · t (+ constant)."""
    c = measures.support_coefficients(blocks_p, U, shape)[0]       # (k, n_src)
    h = c @ t
    if shape is not None:
        h = h + measures.support_constant(blocks_p, U, shape)[0]
    return h


def _children_caps(C: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split caps (centres C (k, 3), radii r (k,)) into SPLIT² children each (gnomonic grid)."""
    helper = np.where(np.abs(C[:, [0]]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    e1 = np.cross(C, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(C, e1)
    side = 2 * np.tan(r) / SPLIT                                      # (k,)
    offs = (np.arange(SPLIT) + 0.5) / SPLIT * 2 - 1                   # centres of the squares in [-1, 1]
    a, b = np.meshgrid(offs, offs, indexing="ij")
    a, b = a.ravel(), b.ravel()                                       # (m²,)
    P = (C[:, None, :] + np.tan(r)[:, None, None] * (a[None, :, None] * e1[:, None, :] + b[None, :, None] * e2[:, None, :]))
    P /= np.linalg.norm(P, axis=2, keepdims=True)
    rc = np.repeat(np.minimum(side / np.sqrt(2), r), SPLIT * SPLIT)
    return P.reshape(-1, 3), rc


def _children_arcs(C: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split arcs of the xy circle (centres C, half-widths r) into two halves each."""
    ang = np.arctan2(C[:, 1], C[:, 0])
    a = np.concatenate([ang - r / 2, ang + r / 2])
    return np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], 1), np.concatenate([r / 2, r / 2])


def certified_max(blocks_p: list[np.ndarray], t: np.ndarray, D: np.ndarray, delta: float, attained: float,
                  shape=None, rtol: float = 1e-9, max_rounds: int = 40, max_caps: int = 200_000,
                  return_direction: bool = False):
    """Proven upper bound and attained value of ``max_{|u|=1} h(u)`` at one pose.

    Parameters
    ----------
    blocks_p : list of ndarray
        The sources' sensitivity blocks at this pose, each (1, 3, dim_j) (m/m, m/rad, rad/...).
    t : ndarray
        Tolerances (n_src,), SI.
    D : ndarray
        The measure's direction grid (k, 3); ±D (or D, when it holds both halves) covers the
        sphere, or the xy circle, with angle ``delta`` (rad).
    delta : float
        Covering angle of the grid (rad); <= 0 means D is the single exact direction, and
        ``attained`` is returned as the bound.
    attained : float
        A value of h already attained (the refined maximum), SI.
    shape : IntervalShape, optional
        Asymmetric intervals (D must then be the full-sphere grid).
    rtol : float
        Stop when the bound is within ``rtol`` (relative) of the best attained value.
    max_rounds : int
        Largest number of split rounds.
    max_caps : int
        Largest number of caps (or arcs) a round may split into; the search stops with the
        current bound beyond it.
    return_direction : bool
        Also return the direction (3,) where ``attained`` was reached (``None`` when the value
        passed in was not beaten).

    Returns
    -------
    (bound, attained[, direction]) : tuple
        ``attained ≤ max h ≤ bound`` (SI); ``bound`` is within ``rtol`` of ``attained`` unless
        ``max_rounds`` or ``max_caps`` stopped the search first.
    """
    t = np.asarray(t, dtype=float)
    best_u = [None]

    def out(bound, L):
        return (bound, L, best_u[0]) if return_direction else (bound, L)

    if delta <= 0:                      # a single exact direction (z-only output)
        return out(float(attained), float(attained))
    planar = bool(np.all(D[:, 2] == 0))
    symmetric = shape is None or shape.centred
    C = np.concatenate([D, -D]) if symmetric else D
    r = np.full(len(C), float(delta))
    L = float(attained)
    # the largest bound of the caps dropped so far: each was within rtol of the attained value when
    # it was dropped, but it still bounds h on its cap, so the proven bound is never below it
    dropped = -np.inf
    for _ in range(max_rounds):
        h = _h(blocks_p, t, C, shape)
        k = int(np.argmax(h))
        if h[k] > L:
            L, best_u[0] = float(h[k]), C[k].copy()
        ub = h / np.cos(r)
        live = ub > L * (1 + rtol)
        if not live.all():
            dropped = max(dropped, float(ub[~live].max()))
        if not live.any():
            return out(max(L, dropped), L)
        if live.sum() * SPLIT * SPLIT > max_caps:
            return out(max(float(ub[live].max()), dropped), L)
        C, r = (_children_arcs if planar else _children_caps)(C[live], r[live])
    h = _h(blocks_p, t, C, shape)
    k = int(np.argmax(h))
    if h[k] > L:
        L, best_u[0] = float(h[k]), C[k].copy()
    return out(float(max(L, (h / np.cos(r)).max(), dropped)), L)

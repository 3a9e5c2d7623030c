"""Patches of unit directions and their certified bounds, for the branch and bound over directions
(:mod:`evotol.robots.clearance.branch_bound`; Deng 2012 eqs. III.26-III.27 maximised as max_|u|=1 h(u)).

A patch is the cone spanned by q unit vectors (an arc of the circle, q = 2, for 2-component
targets; a spherical triangle of the half sphere, q = 3, for 3-component targets). Given certified
upper values of the support function h at its vertices, :func:`patch_bound` bounds h over the whole
patch (sublinearity), :func:`interpolated_bound` does so from the vertices' dual points (weak
duality), and :func:`children` splits patches at their edge midpoints.

The parameters several definitions of this module share are described once, here.

Parameters
----------
t : (T, 3, 3) ndarray
    Triangles as three unit vertices.
U : (P, q, k) ndarray
    Unit vertices of ``P`` patches.
"""
from __future__ import annotations

import numpy as np

from evotol.robots.clearance.certificate import true_dual
from evotol.robots.clearance.options import DEFAULT, EngineOptions


def octa_hemisphere(levels: int = 2):
    """Upper-hemisphere triangles of a subdivided octahedron: (T, 3, 3) unit vertices.

    Parameters
    ----------
    levels : int, optional
        Number of subdivisions (default 2); each splits every triangle into four.

    Returns
    -------
    (T, 3, 3) ndarray
        ``T = 4 * 4 ** levels`` triangles as three unit vertices each (dimensionless directions,
        ``z >= 0``).
    """
    e = np.eye(3)
    tris = [np.stack([a, b, e[2]]) for a, b in ((e[0], e[1]), (e[1], -e[0]), (-e[0], -e[1]), (-e[1], e[0]))]
    tris = np.array(tris)
    for _ in range(levels):
        tris = split_tris(tris)
    return tris


def normalise(v):
    """Vectors scaled to unit length along the last axis.

    Parameters
    ----------
    v : (..., k) ndarray
        Nonzero vectors.

    Returns
    -------
    (..., k) ndarray
        ``v / ||v||``.
    """
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def split_tris(t):
    """Split spherical triangles into four at their edge midpoints (projected to the sphere).

    Returns
    -------
    (4 T, 3, 3) ndarray
        The children, stacked child-kind by child-kind (corner 0, 1, 2 children, then the middle).
    """
    a, b, c = t[:, 0], t[:, 1], t[:, 2]
    ab, bc, ca = normalise(a + b), normalise(b + c), normalise(c + a)
    return np.concatenate([np.stack(x, 1) for x in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])


def tri_depth(t):
    """Distance from the origin to the plane through each triangle's three vertices.

    Returns
    -------
    (T,) ndarray
        Distances (dimensionless, in (0, 1] for unit vertices).
    """
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    n = normalise(n)
    return np.abs((n * t[:, 0]).sum(-1))


def depth(U):
    """Distance from the origin to the flat patch spanned by unit vectors U (P, q, k).

    Parameters
    ----------
    U : (P, q, k) ndarray
        Unit vertices of ``P`` patches (``q = 2``: arcs, ``q = 3``: triangles with ``k = 3``).

    Returns
    -------
    (P,) ndarray
        Distance to the chord's midpoint (arcs) or to the triangle's plane, dimensionless.
    """
    if U.shape[1] == 2:
        return np.linalg.norm(U[:, 0] + U[:, 1], axis=-1) / 2
    return tri_depth(U)


def arc_bound(A, B, HA, HB):
    """``max u^T X`` over the unit vectors ``u`` of the arc from A to B (P, k), where ``A^T X = HA``
    and ``B^T X = HB``: with ``X_p = alpha A + beta B`` the projection of X on the plane of the arc
    (Gram system), the maximum is ``|X_p|`` if ``alpha, beta >= 0`` (X_p points into the arc),
    else the larger end value.

    Parameters
    ----------
    A : (P, k) ndarray
        Unit start vectors of the arcs.
    B : (P, k) ndarray
        Unit end vectors of the arcs.
    HA : (P,) ndarray
        Values ``A . X`` (upper values of the support function at ``A``; m or rad).
    HB : (P,) ndarray
        Values ``B . X``, same units.

    Returns
    -------
    (P,) ndarray
        ``max u . X`` over the arc, in the units of ``HA``.
    """
    c = (A * B).sum(-1)
    det = 1.0 - c * c
    with np.errstate(all="ignore"):
        al = (HA - c * HB) / det
        be = (HB - c * HA) / det
        inside = (al >= 0) & (be >= 0) & (det > 1e-14)
        xp = np.sqrt(np.maximum(al * HA + be * HB, 0.0))
    return np.where(inside, np.maximum(xp, np.maximum(HA, HB)), np.maximum(HA, HB))


def patch_bound(U, H, legacy: bool = False):
    """Certified bound of ``max h(u)`` over the patch (cone) spanned by unit vectors U (P, q, k)
    with ``h(U_i) <= H_i`` (P, q).

    Every ``x`` of the error set satisfies ``U_i . x <= H_i``; for ``u = sum l_i U_i`` (``l >= 0``)
    therefore ``u . x <= sum l_i H_i = u . X`` with ``U_i . X = H_i``, so
    ``max_patch h <= max_{u in patch} u . X`` -- the exact value of the sublinearity bound
    ``sum l_i H_i / |sum l_i U_i|``. It is ``|X|`` when X points into the patch (exact when the
    vertices share their support point, a vertex of the error set), else the maximum over the
    patch's edges (:func:`arc_bound`). Before issue 13 the looser ``min(max_i H_i / d, |X|)``
    (``d`` = distance from the origin to the flat patch) was used; it is kept as the fall-back
    for degenerate patches and as a second valid bound (``legacy=True`` returns it alone).

    Parameters
    ----------
    H : (P, q) ndarray
        Certified upper values of ``h`` at the vertices (m or rad, or scaled).
    legacy : bool, optional
        True: the bound before issue 13, ``min(max_i H_i / d, |X|)``; False (default): the exact
        sublinearity bound (never above the legacy one).

    Returns
    -------
    (P,) ndarray
        Upper bound of ``h`` over each patch, in the units of ``H`` (``max_i H_i / d`` when
        ``q != k``).
    """
    b1 = H.max(-1) / depth(U)
    q, k = U.shape[1], U.shape[2]
    if q == k:
        with np.errstate(all="ignore"):
            det = np.linalg.det(U)
            ok = np.abs(det) > 1e-12
            X = np.zeros(H.shape[:-1] + (k,))
            cX = np.zeros(H.shape[:-1] + (k,))
            if ok.any():
                X[ok] = np.linalg.solve(U[ok], H[ok][..., None])[..., 0]
                cX[ok] = np.linalg.solve(np.swapaxes(U[ok], 1, 2), X[ok][..., None])[..., 0]   # X = sum c_i U_i
        nX = np.linalg.norm(X, axis=-1)
        b2 = np.where(ok, nX, np.inf)
        if legacy:
            return np.minimum(b1, b2)
        inside = ok & np.all(cX >= 0, axis=-1)
        edges = ((0, 1),) if q == 2 else ((0, 1), (1, 2), (2, 0))
        be = np.max([arc_bound(U[:, i], U[:, j], H[:, i], H[:, j]) for i, j in edges], axis=0)
        b3 = np.where(inside, nX, be)
        return np.minimum(b1, np.where(ok, b3, np.inf))
    return b1


def sub_points(q: int, n: int):
    """Conic weights (S, q) of the sub-points of a patch split ``n`` times along each edge, and the
    sub-patches (T, q) as indices into them: the arc cut into ``n`` arcs, or the triangle into
    ``n^2`` triangles.

    Parameters
    ----------
    q : int
        Vertices per patch (2: arc, 3: triangle).
    n : int
        Divisions per edge (>= 1).

    Returns
    -------
    W : (S, q) ndarray
        Conic (barycentric) weights of the sub-points, rows summing to 1.
    sub : (T, q) int ndarray
        Sub-patches as indices into the rows of ``W``.
    """
    if q == 2:
        t = np.arange(n + 1) / n
        return np.stack([1 - t, t], 1), np.stack([np.arange(n), np.arange(1, n + 1)], 1)
    pts = [(i, j) for i in range(n + 1) for j in range(n + 1 - i)]
    at = {p: c for c, p in enumerate(pts)}
    W = np.array([(n - i - j, i, j) for i, j in pts], float) / n
    tris = []
    for i in range(n):
        for j in range(n - i):
            tris.append((at[(i, j)], at[(i + 1, j)], at[(i, j + 1)]))
            if i + j < n - 1:
                tris.append((at[(i + 1, j)], at[(i + 1, j + 1)], at[(i, j + 1)]))
    return W, np.array(tris)


def interpolated_bound(U, Y, nd: int, n: int):
    """Certified bound of ``max h(u)`` over the patches spanned by unit vectors U (P, q, k), from the
    dual vectors ``Y`` (P, q, R) of their vertices (``y_i = a(U_i) + B mu_i``, whose cone norms sum
    to the vertex bound ``f(mu_i, U_i)``).

    For ``u = sum l_i U_i`` (``l >= 0``) the dual point ``mu = sum l_i mu_i`` is feasible, so by weak
    duality and the linearity of ``a(u)``, ``h(u) <= f(mu, u) = sum_c ||sum_i l_i y_{c,i}||`` -- the
    interpolated bound G(u). It is never above the vertex bound ``sum l_i f(mu_i, U_i)`` (triangle
    inequality) and is exact where the optimal dual is linear across the patch (a round part of the
    error set), so patches on curved parts prune without being split. G is sublinear on the patch's
    cone, so its maximum over the patch is bounded by :func:`patch_bound` on ``n`` sub-patches per
    edge with G at their vertices.

    Parameters
    ----------
    Y : (P, q, R) ndarray
        Dual vectors ``y_i`` (scaled rows) at the vertices.
    nd : int
        Number of disk cones (the first ``2 nd`` entries of ``y`` in pairs; intervals after).
    n : int
        Sub-patches per edge (>= 1).

    Returns
    -------
    (P,) ndarray
        Upper bound of ``h`` over each patch, in the units of the dual values.
    """
    P, q, k = U.shape
    W, sub = sub_points(q, n)
    V = np.einsum("sq,pqk->psk", W, U)                              # (P, S, k) sub-points in the cone
    nv = np.linalg.norm(V, axis=-1)
    G = true_dual(np.einsum("sq,pqr->psr", W, Y), nd) / nv          # (P, S) bound at the unit sub-points
    V = V / nv[..., None]
    T = len(sub)
    SU = V[:, sub].reshape(P * T, q, k)
    SH = G[:, sub].reshape(P * T, q)
    return patch_bound(SU, SH).reshape(P, T).max(axis=1)


_KIDS = ((0, 3, 5), (3, 1, 4), (5, 4, 2), (3, 4, 5))   # a triangle's four children: vertices 0-2, edge midpoints 3-5


def children(parent, mid):
    """A per-vertex array of the children of split patches: ``parent`` (P, q, ...) at the patches'
    vertices, ``mid`` (P, e, ...) at their new midpoints (edges 01, 12, 20). An arc gives two arcs,
    a triangle four triangles; children are stacked child-kind by child-kind (as ``np.tile(pc, .)``).

    Parameters
    ----------
    parent : (P, q, ...) ndarray
        A per-vertex quantity of the parent patches (directions, values, dual points ...).
    mid : (P, e, ...) ndarray
        The same quantity at the new edge midpoints (``e = 1`` for arcs, 3 for triangles).

    Returns
    -------
    (2 P, 2, ...) or (4 P, 3, ...) ndarray
        The quantity at the vertices of the children.
    """
    if parent.shape[1] == 2:
        return np.concatenate([np.stack([parent[:, 0], mid[:, 0]], 1), np.stack([mid[:, 0], parent[:, 1]], 1)])
    v = [parent[:, 0], parent[:, 1], parent[:, 2], mid[:, 0], mid[:, 1], mid[:, 2]]
    return np.concatenate([np.stack([v[i] for i in c], 1) for c in _KIDS])


def initial_patches(k: int, options: EngineOptions = DEFAULT):
    """The first patches of the branch and bound: unit vertices (V, k), patches as vertex indices
    (T, q) and the sign of each patch vertex (T, q) (a vertex stored once for an antipodal pair).

    Parameters
    ----------
    k : int
        Number of target components (2: half circle of arcs; otherwise 3: half sphere of triangles).
    options : EngineOptions, optional
        The engine's settings: ``n_circle0``, ``level0``, ``dedup_antipodes`` (default
        :data:`evotol.robots.clearance.options.DEFAULT`).

    Returns
    -------
    verts : (V, k) ndarray
        Unit vertices to solve.
    patches : (T, q) int ndarray
        Patches as indices into ``verts``.
    sign : (T, q) ndarray
        +1 or -1: a patch vertex is ``sign * verts[index]``.
    """
    if k == 2:
        n0 = options.n_circle0
        phi = np.arange(n0 + 1) * np.pi / n0
        verts = np.stack([np.cos(phi[:-1]), np.sin(phi[:-1])], -1)
        # arc i joins vertex i and i+1; vertex n0 is -vertex 0 (h(-u) = h(u), mu(-u) = -mu(u))
        tri = np.stack([np.arange(n0), np.arange(1, n0 + 1)], 1)
        sign = np.ones_like(tri, dtype=float)
        sign[-1, 1] = -1.0
        tri[-1, 1] = 0
        return verts, tri, sign
    tris0 = octa_hemisphere(options.level0).reshape(-1, 3)
    # equator vertices come in antipodal pairs: solve one of each (h(-u) = h(u), mu(-u) = -mu(u))
    v = np.round(tris0, 12)
    flip = (v[:, 2] == 0) & ((v[:, 1] < 0) | ((v[:, 1] == 0) & (v[:, 0] < 0)))
    v[flip] *= -1.0
    sign = np.where(flip, -1.0, 1.0)
    if not options.dedup_antipodes:
        v, sign = np.round(tris0, 12), np.ones(len(tris0))
    verts, inv = np.unique(v, axis=0, return_inverse=True)
    return normalise(verts), inv.reshape(-1, 3), sign.reshape(-1, 3)

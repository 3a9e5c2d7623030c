"""Global maximum pose error under joint clearances, with a certificate (Deng 2012 eqs. III.26-III.27).

The thesis maximises ``||dp||^2`` (or ``||dtheta||^2``) over the clearance screws -- a nonconvex
problem it attacks with 200 local solves per pose. The feasible error twists form a convex,
centrally symmetric set ``P`` (an intersection over chains of Minkowski sums of the joints'
disk x interval x disk x interval sets), so

    p_max = max_{x in P} ||x_pos|| = max_{|u| = 1} h_P(u),      h_P = support function of P.

Each ``h_P(u)`` is a small convex problem solved with a two-sided certificate
(:mod:`robots.clearance.support`). The maximum over unit directions ``u`` is found by
branch and bound on the circle (2 target components) or the half sphere (3 components;
``h(u) = h(-u)`` by symmetry): for a patch spanned by unit vectors ``u_1..u_q``,
``max_patch h <= max_i h(u_i) / d`` where ``d`` is the distance from the origin to the flat
patch (positive homogeneity + subadditivity of ``h``); patches whose bound does not exceed the
best attained norm by more than the tolerance are discarded, the others are split. A second,
often much tighter bound interpolates the vertices' **dual points** across the patch (weak
duality holds for any dual point and the problem's data are linear in the direction:
:func:`_interpolated_bound`), so patches on round parts of the error set prune without being
split. The result carries

* ``p_max``: a value **attained** by an explicit feasible set of joint error screws (returned);
* ``p_upper``: a **certified** upper bound (dual certificates on the directions + patch bound);

and likewise for the rotation. Their relative gap is at most ``tol`` (default 1e-3).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from evotol.errors import ConvergenceError, ValidationError
from evotol.executor import parallel_map
from evotol.threads import one_blas_thread
from robots.clearance.model import ClearanceMechanism, PoseMaps
from robots.clearance import support
from robots.clearance.support import _gram_pinv, solve_support, true_dual, warm_up


# ---------------------------------------------------------------------------- geometry of directions
def _octa_hemisphere(levels: int = 2):
    """Upper-hemisphere triangles of a subdivided octahedron: (T, 3, 3) unit vertices."""
    e = np.eye(3)
    tris = [np.stack([a, b, e[2]]) for a, b in ((e[0], e[1]), (e[1], -e[0]), (-e[0], -e[1]), (-e[1], e[0]))]
    tris = np.array(tris)
    for _ in range(levels):
        tris = _split_tris(tris)
    return tris


def _normalise(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _split_tris(t):
    a, b, c = t[:, 0], t[:, 1], t[:, 2]
    ab, bc, ca = _normalise(a + b), _normalise(b + c), _normalise(c + a)
    return np.concatenate([np.stack(x, 1) for x in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])


def _tri_depth(t):
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    n = _normalise(n)
    return np.abs((n * t[:, 0]).sum(-1))


# ---------------------------------------------------------------------------- one target of one block
@dataclass
class _Target:
    lower: np.ndarray      # (K,) attained norm
    upper: np.ndarray      # (K,) certified bound
    sigma: np.ndarray      # (K, R) attaining scaled screws
    n_solves: int = 0


class _Evaluator:
    """Support values for (case, direction) pairs; keeps the best attained point of each case.

    ``exact`` solves the convex problem (certified upper value + feasible primal point);
    ``cheap`` only evaluates the dual objective at a given ``mu`` -- still a certified upper
    bound of the support value (weak duality), at the cost of one matrix-vector product.
    """

    def __init__(self, Ct, Bt, gi, nd, tol_solve, groups=None):
        self.Ct, self.Bt, self.gi, self.nd, self.groups = Ct, Bt, gi, nd, groups
        K, k, R = Ct.shape
        self.best = np.zeros(K)
        self.sigma = np.zeros((K, R))
        self.mu = np.zeros((K, Bt.shape[-1]))
        self.tol_solve = tol_solve
        self.n_solves = 0
        self.n_cheap = 0

    def exact(self, case, u, mu0=None, scale=None, rtol=None, stop_below=None):
        a = np.einsum("kqr,kq->kr", self.Ct[case], u)
        rtol = self.tol_solve if rtol is None else rtol
        tol = 0.0 if scale is None else rtol * scale
        gap0 = None
        if mu0 is not None:
            # start the barrier at the certified gap of the warm start: f(mu0) - u^T x_best
            f0 = true_dual(a + (self.Bt[case] @ mu0[..., None])[..., 0], self.nd)
            lo = np.einsum("kq,kq->k", u, np.einsum("kqr,kr->kq", self.Ct[case], self.sigma[case]))
            gap0 = np.maximum(f0 - np.maximum(lo, 0.0), np.maximum(tol, rtol * f0))
        res = solve_support(a, self.Bt[case], self.nd, tol=tol, rtol=rtol, mu0=mu0, gap0=gap0, gram_inv=self.gi[case],
                            groups=self.groups, stop_below=stop_below)
        self.n_solves += len(case)
        norms = np.linalg.norm(np.einsum("kqr,kr->kq", self.Ct[case], res.sigma), axis=-1)
        order = np.argsort(norms)          # last write wins -> the largest per case
        c_sorted = case[order]
        better = norms[order] > self.best[c_sorted]
        cs, idx = c_sorted[better], order[better]
        self.best[cs] = norms[idx]
        self.sigma[cs] = res.sigma[idx]
        self.mu[cs] = res.mu[idx]
        return res.upper, res.mu

    def cheap(self, case, u, mu):
        self.n_cheap += len(case)
        return true_dual(self.dual_vectors(case, u, mu), self.nd)

    def dual_vectors(self, case, u, mu):
        """``y = D C^T u + D B mu`` (K, R): the cone-wise vectors whose norms sum to the dual bound."""
        return np.einsum("kqr,kq->kr", self.Ct[case], u) + (self.Bt[case] @ mu[..., None])[..., 0]

    def polish(self, n_iter: int = 2, rtol: float | None = None, cases=None):
        """Local ascent from the best attained point: u <- x / ||x||, x <- argmax u^T x; monotone
        (||x_new|| >= u^T x_new = h(u) >= u^T x_old = ||x_old||). Tightens the attained value."""
        cases = np.arange(len(self.best)) if cases is None else cases
        rtol = _POLISH_RTOL if rtol is None else rtol
        for _ in range(n_iter):
            x = np.einsum("kqr,kr->kq", self.Ct[cases], self.sigma[cases])
            nrm = np.linalg.norm(x, axis=-1)
            ok = nrm > 0
            if not ok.any():
                break
            c = cases[ok]
            self.exact(c, x[ok] / nrm[ok, None], mu0=self.mu[c], scale=nrm[ok], rtol=rtol)


def _depth(U):
    """Distance from the origin to the flat patch spanned by unit vectors U (P, q, k)."""
    if U.shape[1] == 2:
        return np.linalg.norm(U[:, 0] + U[:, 1], axis=-1) / 2
    return _tri_depth(U)


def _arc_bound(A, B, HA, HB):
    """``max u . X`` over the unit vectors ``u`` of the arc from A to B (P, k), where ``A . X = HA``
    and ``B . X = HB``: with ``X_p = alpha A + beta B`` the projection of X on the plane of the arc
    (Gram system), the maximum is ``|X_p|`` if ``alpha, beta >= 0`` (X_p points into the arc),
    else the larger end value."""
    c = (A * B).sum(-1)
    det = 1.0 - c * c
    with np.errstate(all="ignore"):
        al = (HA - c * HB) / det
        be = (HB - c * HA) / det
        inside = (al >= 0) & (be >= 0) & (det > 1e-14)
        xp = np.sqrt(np.maximum(al * HA + be * HB, 0.0))
    return np.where(inside, np.maximum(xp, np.maximum(HA, HB)), np.maximum(HA, HB))


def _patch_bound(U, H):
    """Certified bound of ``max h(u)`` over the patch (cone) spanned by unit vectors U (P, q, k)
    with ``h(U_i) <= H_i`` (P, q).

    Every ``x`` of the error set satisfies ``U_i . x <= H_i``; for ``u = sum l_i U_i`` (``l >= 0``)
    therefore ``u . x <= sum l_i H_i = u . X`` with ``U_i . X = H_i``, so
    ``max_patch h <= max_{u in patch} u . X`` -- the exact value of the sublinearity bound
    ``sum l_i H_i / |sum l_i U_i|``. It is ``|X|`` when X points into the patch (exact when the
    vertices share their support point, a vertex of the error set), else the maximum over the
    patch's edges (:func:`_arc_bound`). Before issue 13 the looser ``min(max_i H_i / d, |X|)``
    (``d`` = distance from the origin to the flat patch) was used; it is kept as the fall-back
    for degenerate patches and as a second valid bound (``legacy=True`` returns it alone).
    """
    b1 = H.max(-1) / _depth(U)
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
        if _PATCH_BOUND == "legacy":
            return np.minimum(b1, b2)
        inside = ok & np.all(cX >= 0, axis=-1)
        edges = ((0, 1),) if q == 2 else ((0, 1), (1, 2), (2, 0))
        be = np.max([_arc_bound(U[:, i], U[:, j], H[:, i], H[:, j]) for i, j in edges], axis=0)
        b3 = np.where(inside, nX, be)
        return np.minimum(b1, np.where(ok, b3, np.inf))
    return b1


def _sub_points(q: int, n: int):
    """Conic weights (S, q) of the sub-points of a patch split ``n`` times along each edge, and the
    sub-patches (T, q) as indices into them: the arc cut into ``n`` arcs, or the triangle into
    ``n^2`` triangles."""
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


def _interpolated_bound(U, Y, nd: int, n: int):
    """Certified bound of ``max h(u)`` over the patches spanned by unit vectors U (P, q, k), from the
    dual vectors ``Y`` (P, q, R) of their vertices (``y_i = a(U_i) + B mu_i``, whose cone norms sum
    to the vertex bound ``f(mu_i, U_i)``).

    For ``u = sum l_i U_i`` (``l >= 0``) the dual point ``mu = sum l_i mu_i`` is feasible, so by weak
    duality and the linearity of ``a(u)``, ``h(u) <= f(mu, u) = sum_c ||sum_i l_i y_{c,i}||`` -- the
    interpolated bound G(u). It is never above the vertex bound ``sum l_i f(mu_i, U_i)`` (triangle
    inequality) and is exact where the optimal dual is linear across the patch (a round part of the
    error set), so patches on curved parts prune without being split. G is sublinear on the patch's
    cone, so its maximum over the patch is bounded by :func:`_patch_bound` on ``n`` sub-patches per
    edge with G at their vertices."""
    P, q, k = U.shape
    W, sub = _sub_points(q, n)
    V = np.einsum("sq,pqk->psk", W, U)                              # (P, S, k) sub-points in the cone
    nv = np.linalg.norm(V, axis=-1)
    G = true_dual(np.einsum("sq,pqr->psr", W, Y), nd) / nv          # (P, S) bound at the unit sub-points
    V = V / nv[..., None]
    T = len(sub)
    SU = V[:, sub].reshape(P * T, q, k)
    SH = G[:, sub].reshape(P * T, q)
    return _patch_bound(SU, SH).reshape(P, T).max(axis=1)


_KIDS = ((0, 3, 5), (3, 1, 4), (5, 4, 2), (3, 4, 5))   # a triangle's four children: vertices 0-2, edge midpoints 3-5


def _children(parent, mid):
    """A per-vertex array of the children of split patches: ``parent`` (P, q, ...) at the patches'
    vertices, ``mid`` (P, e, ...) at their new midpoints (edges 01, 12, 20). An arc gives two arcs,
    a triangle four triangles; children are stacked child-kind by child-kind (as ``np.tile(pc, .)``)."""
    if parent.shape[1] == 2:
        return np.concatenate([np.stack([parent[:, 0], mid[:, 0]], 1), np.stack([mid[:, 0], parent[:, 1]], 1)])
    v = [parent[:, 0], parent[:, 1], parent[:, 2], mid[:, 0], mid[:, 1], mid[:, 2]]
    return np.concatenate([np.stack([v[i] for i in c], 1) for c in _KIDS])


def _initial_patches(k: int):
    if k == 2:
        n0 = _N_CIRCLE0
        phi = np.arange(n0 + 1) * np.pi / n0
        verts = np.stack([np.cos(phi[:-1]), np.sin(phi[:-1])], -1)
        # arc i joins vertex i and i+1; vertex n0 is -vertex 0 (h(-u) = h(u), mu(-u) = -mu(u))
        tri = np.stack([np.arange(n0), np.arange(1, n0 + 1)], 1)
        sign = np.ones_like(tri, dtype=float)
        sign[-1, 1] = -1.0
        tri[-1, 1] = 0
        return verts, tri, sign
    tris0 = _octa_hemisphere(_LEVEL0).reshape(-1, 3)
    # equator vertices come in antipodal pairs: solve one of each (h(-u) = h(u), mu(-u) = -mu(u))
    v = np.round(tris0, 12)
    flip = (v[:, 2] == 0) & ((v[:, 1] < 0) | ((v[:, 1] == 0) & (v[:, 0] < 0)))
    v[flip] *= -1.0
    sign = np.where(flip, -1.0, 1.0)
    if _DEDUP_ANTIPODES == "off":
        v, sign = np.round(tris0, 12), np.ones(len(tris0))
    verts, inv = np.unique(v, axis=0, return_inverse=True)
    return _normalise(verts), inv.reshape(-1, 3), sign.reshape(-1, 3)


_STOP_BELOW = 0.06   # B&B vertices certified 6 % below the best value need no more precision (1 % before issue 13, 3 % until every iterate's dual value was checked)
_N_CIRCLE0 = 3       # initial vertices on the half circle for 2-component targets (6 before issue 13, 4 until
                     # the dual-interpolation bound: three 60 deg arcs then need fewer Newton iterations)
_LEVEL0 = 0          # initial subdivision of the half-sphere octants
_POLISH_RTOL0 = 1e-6  # precision of the ascent from the initial vertices' best point
_POLISH_RTOL = 1e-6   # precision of the final ascent (1e-8 before issue 13; the gap target is 1e-3)
_DEDUP_ANTIPODES = "on"  # "off": solve both vertices of an antipodal pair (before issue 13)
_PATCH_BOUND = "exact"  # "legacy": today's min(max H / d, |X|) (issue 13 comparison)
_INTERPOLATE = 6        # sub-patches per edge of the dual-interpolation bound on triangles (0: off, the bound before it)
_INTERPOLATE_ARC = 24   # ... and sub-arcs per arc (2-component targets: cheap, and round sets need them)


#: the engine's settings before issue 13 (for the agreement test and the benchmark)
LEGACY_OPTIONS = {"_STOP_BELOW": 0.01, "_N_CIRCLE0": 6, "_POLISH_RTOL": 1e-8, "_DEDUP_ANTIPODES": "off", "_PATCH_BOUND": "legacy",
                  "_INTERPOLATE": 0}
#: ... and of the convex solver (robots.clearance.support)
LEGACY_SUPPORT_OPTIONS = {"_PRED": "legacy", "_GROWTH": 8.0}


class legacy_engine:
    """Context manager running the branch and bound with its settings before issue 13 (looser
    patch bound, both vertices of antipodal pairs solved, finer vertex and polish precision):
    ``with legacy_engine(): max_pose_error(...)``. Not thread safe (module settings)."""

    def __enter__(self):
        g = globals()
        self._saved = {k: g[k] for k in LEGACY_OPTIONS}
        self._saved_support = {k: getattr(support, k) for k in LEGACY_SUPPORT_OPTIONS}
        g.update(LEGACY_OPTIONS)
        for k, v in LEGACY_SUPPORT_OPTIONS.items():
            setattr(support, k, v)
        return self

    def __exit__(self, *exc):
        globals().update(self._saved)
        for k, v in self._saved_support.items():
            setattr(support, k, v)
        return False


def _maximise_norm(Ct, Bt, gi, nd, *, tol=1e-3, tol_solve=1e-5, max_rounds=40, groups=None) -> _Target:
    """max ||Ct sigma|| over feasible scaled screws for every case (Ct: (K, k, R), k in 1..3)."""
    K, k, R = Ct.shape
    m = Bt.shape[-1]
    ev = _Evaluator(Ct, Bt, gi, nd, tol_solve, groups)
    cases = np.arange(K)
    tol_bb = 0.5 * tol
    if k == 1:
        up, _ = ev.exact(cases, np.ones((K, 1)), rtol=1e-9)
        return _Target(ev.best.copy(), np.maximum(up, ev.best), ev.sigma, ev.n_solves)
    verts, tri, sign = _initial_patches(k)
    nv, T = len(verts), len(tri)
    up, mu = ev.exact(np.repeat(cases, nv), np.tile(verts, (K, 1)))
    up, mu = up.reshape(K, nv), mu.reshape(K, nv, m)
    ev.polish(rtol=_POLISH_RTOL0)
    best_before = ev.best.copy()
    pc = np.repeat(cases, T)                                       # patch -> case
    PU = np.tile(verts[tri] * sign[..., None], (K, 1, 1))         # (P, q, k)
    PH = up[:, tri].reshape(K * T, -1)                             # (P, q) certified upper values
    PM = (mu[:, tri] * sign[None, :, :, None]).reshape(K * T, tri.shape[1], m)
    interp = _INTERPOLATE and m
    n_sub = _INTERPOLATE_ARC if k == 2 else _INTERPOLATE
    if interp:
        PY = ev.dual_vectors(np.repeat(pc, tri.shape[1]), PU.reshape(-1, k), PM.reshape(-1, m)).reshape(PU.shape[:2] + (R,))
    pruned = np.zeros(K)
    q = PU.shape[1]
    for _ in range(max_rounds):
        bound = _patch_bound(PU, PH)
        if interp:        # the finer (costlier) bound only where the vertex bound does not prune
            loose = np.nonzero(bound > ev.best[pc] * (1 + tol_bb))[0]
            bound[loose] = np.minimum(bound[loose], _interpolated_bound(PU[loose], PY[loose], nd, n_sub))
        keep = bound > ev.best[pc] * (1 + tol_bb)
        np.maximum.at(pruned, pc[~keep], bound[~keep])
        pc, PU, PH, PM = pc[keep], PU[keep], PH[keep], PM[keep]
        if interp:
            PY = PY[keep]
        if not pc.size:
            break
        if q == 2:
            mids = _normalise(PU[:, 0] + PU[:, 1])[:, None]
            mmu = ((PM[:, 0] + PM[:, 1]) / 2)[:, None]
        else:
            mids = _normalise(np.stack([PU[:, 0] + PU[:, 1], PU[:, 1] + PU[:, 2], PU[:, 2] + PU[:, 0]], 1))
            mmu = np.stack([PM[:, 0] + PM[:, 1], PM[:, 1] + PM[:, 2], PM[:, 2] + PM[:, 0]], 1) / 2
        e = mids.shape[1]
        key = np.concatenate([np.repeat(pc, e)[:, None].astype(float), np.round(mids.reshape(-1, k), 12)], 1)
        _, first, back = np.unique(key, axis=0, return_index=True, return_inverse=True)
        back = back.ravel()
        uc = np.repeat(pc, e)[first]
        uu = mids.reshape(-1, k)[first]
        um = mmu.reshape(len(pc) * e, m)[first]
        hm = ev.cheap(uc, uu, um)
        need = np.nonzero(hm > ev.best[uc] * (1 + tol_bb))[0]
        if need.size:
            sc = np.maximum(ev.best[uc[need]], 1e-300)
            he, me = ev.exact(uc[need], uu[need], mu0=um[need], scale=sc, rtol=tol_bb / 4,
                              stop_below=sc * (1 - _STOP_BELOW))
            hm[need] = np.minimum(hm[need], he)
            um[need] = me
        if interp:
            ym = ev.dual_vectors(uc, uu, um)[back].reshape(len(pc), e, R)
        hm = hm[back].reshape(len(pc), e)
        mm = um[back].reshape(len(pc), e, m)
        PU, PH, PM = _children(PU, mids), _children(PH, hm), _children(PM, mm)
        if interp:
            PY = _children(PY, ym)
        pc = np.tile(pc, 2 if q == 2 else 4)
    alive = np.zeros(K)
    if pc.size:
        ab = _patch_bound(PU, PH)
        if interp:
            ab = np.minimum(ab, _interpolated_bound(PU, PY, nd, n_sub))   # the few still alive
        np.maximum.at(alive, pc, ab)
    changed = np.nonzero(ev.best > best_before)[0]
    ev.polish(n_iter=1, cases=np.arange(K))         # final tightening of the attained value
    if changed.size:
        ev.polish(n_iter=1, cases=changed)
    upper = np.maximum.reduce([pruned, alive, ev.best])
    return _Target(ev.best.copy(), upper, ev.sigma, ev.n_solves)


# ---------------------------------------------------------------------------- public API
@dataclass
class MaxPoseError:
    """Global maximum pose errors of a set of cases (poses and/or clearance-bound sets).

    p_max (m), r_max (rad): values attained by the explicit screws ``p_screws``/``r_screws``
    (``(n, n_joints, 6)``, each joint's ``[dr; dt]`` in its own frame, rad and m);
    p_upper, r_upper: certified upper bounds; p_twist, r_twist: end-effector error twists
    ``[dtheta; dp]`` (base axes) produced by those screws; gap: largest relative gap per case.
    """

    p_max: np.ndarray
    p_upper: np.ndarray
    r_max: np.ndarray
    r_upper: np.ndarray
    p_screws: np.ndarray
    r_screws: np.ndarray
    p_twist: np.ndarray
    r_twist: np.ndarray
    joint_names: tuple[str, ...]
    n_solves: int = 0
    seconds: float = 0.0
    p_extra: np.ndarray | None = None   # (n, q) values of the extra sources at the p maximiser
    r_extra: np.ndarray | None = None

    @classmethod
    def concat(cls, parts) -> "MaxPoseError":
        """The cases of several results in order (chunks of a grid); ``n_solves``, ``seconds`` summed."""
        cat = {f: np.concatenate([getattr(p, f) for p in parts]) for f in
               ("p_max", "p_upper", "r_max", "r_upper", "p_screws", "r_screws", "p_twist", "r_twist")}
        return cls(**cat, joint_names=parts[0].joint_names, n_solves=sum(p.n_solves for p in parts),
                   seconds=sum(p.seconds for p in parts))

    def take(self, idx) -> "MaxPoseError":
        """The cases ``idx`` (index array), in that order."""
        per_case = {f: getattr(self, f)[idx] for f in
                    ("p_max", "p_upper", "r_max", "r_upper", "p_screws", "r_screws", "p_twist", "r_twist")}
        extra = {f: None if getattr(self, f) is None else getattr(self, f)[idx] for f in ("p_extra", "r_extra")}
        return replace(self, **per_case, **extra)

    @property
    def p_gap(self) -> np.ndarray:
        return (self.p_upper - self.p_max) / np.maximum(self.p_upper, 1e-300)

    @property
    def r_gap(self) -> np.ndarray:
        return (self.r_upper - self.r_max) / np.maximum(self.r_upper, 1e-300)

    @property
    def gap(self) -> np.ndarray:
        return np.maximum(self.p_gap, self.r_gap)

    def dominant_joints(self, i: int = 0, which: str = "p") -> list[tuple[str, float]]:
        """Joints ranked by the share of their clearance used at the maximiser of case ``i``."""
        S = (self.p_screws if which == "p" else self.r_screws)[i]
        mag = np.linalg.norm(S, axis=1)
        order = np.argsort(mag)[::-1]
        return [(self.joint_names[j], float(mag[j])) for j in order]


def _as_bounds(mech: ClearanceMechanism, bounds, n: int) -> np.ndarray:
    if bounds is None:
        b = mech.default_bounds()
    else:
        b = np.asarray(bounds, float)
    if b.shape[-2:] != (mech.n_joints, 4):
        raise ValidationError("bounds shape", b.shape, f"(..., {mech.n_joints}, 4): [beta_xy, beta_z, b_xy, b_z] per joint "
                              f"{[j.name for j in mech.joints]}")
    if not np.all(np.isfinite(b)) or np.any(b < 0):
        raise ValidationError("bounds", "negative or non-finite entries", "finite values >= 0 (rad, m)")
    return b


def evaluate_cases(mech: ClearanceMechanism, maps: list[PoseMaps], pose_index: np.ndarray, bounds: np.ndarray, *,
                   tol: float = 1e-3, tol_solve: float = 2e-5, extra=None) -> MaxPoseError:
    # the batched 30x30 solves are several times faster without OpenBLAS threading, and grid
    # workers must not oversubscribe the cores
    with one_blas_thread():
        return _evaluate_cases(mech, maps, pose_index, bounds, tol=tol, tol_solve=tol_solve, extra=extra)


def _evaluate_cases(mech: ClearanceMechanism, maps: list[PoseMaps], pose_index: np.ndarray, bounds: np.ndarray, *,
                    tol: float = 1e-3, tol_solve: float = 2e-5, extra=None) -> MaxPoseError:
    """Maximum pose errors for cases ``(pose_index[i], bounds[i])`` using precomputed ``maps``
    (``mech.pose_maps(poses)``). bounds: (n_cases, n_joints, 4). Identical sub-problems (same
    pose and same bounds on a decoupled block) are solved once.

    extra: optional ``(J, t)``: other independent error sources added to the clearance error --
    ``J`` (n_poses, 6, q) maps them to the end-effector twist ``[dtheta; dp]`` (thesis order, base
    axes), ``t`` (q,) or (n_cases, q) are their interval half-widths (e.g. link-length and
    actuator tolerances through the geometric sensitivity J_p). The support functions of the
    clearance set and of the box ``|e_k| <= t_k`` add up (Minkowski sum), so the combined
    worst case is computed by the same certified method."""

    t0 = time.perf_counter()
    pose_index = np.asarray(pose_index, int)
    n = len(pose_index)
    bounds = np.broadcast_to(bounds, (n, mech.n_joints, 4))
    screws = {w: np.zeros((n, mech.n_joints * 6)) for w in ("p", "r")}
    sq = {w: np.zeros((n, 2)) for w in ("p", "r")}   # squared (lower, upper) summed over blocks
    q = 0
    if extra is not None:
        J, t = np.asarray(extra[0], float), np.asarray(extra[1], float)
        q = J.shape[-1]
        if J.ndim != 3 or J.shape[1] != 6 or J.shape[0] != maps[0].C_pos.shape[0]:
            raise ValidationError("extra J shape", J.shape, f"(n_poses={maps[0].C_pos.shape[0]}, 6, q)")
        t = np.broadcast_to(t, (n, q))
        if np.any(t < 0) or not np.all(np.isfinite(t)):
            raise ValidationError("extra tolerances", "negative or non-finite", "half-widths >= 0")
        owner = -np.ones(q, int)
        for b, pm in enumerate(maps):
            comps = list(pm.block.components)
            hit = np.abs(J[:, comps, :]).max(axis=(0, 1)) > 0
            if np.any(hit & (owner >= 0)):
                raise ValidationError("extra J", "a source acting on two decoupled blocks",
                                      "sources that act in-plane or out-of-plane only (or a non-planar mechanism)")
            owner[hit] = b
    extra_val = {w: np.zeros((n, q)) for w in ("p", "r")}
    n_solves = 0
    for b, pm in enumerate(maps):
        D = pm.row_bounds(bounds)                                   # (n, R)
        Cp, Cr, B = pm.C_pos, pm.C_rot, pm.B
        mine = np.nonzero(owner == b)[0] if q else np.zeros(0, int)
        if mine.size:
            comps = list(pm.block.components)
            Jb = J[:, :, mine]
            Cp = np.concatenate([Cp, Jb[:, list(pm.pos_comps), :]], axis=2)
            Cr = np.concatenate([Cr, Jb[:, list(pm.rot_comps), :]], axis=2)
            B = np.concatenate([B, np.zeros((B.shape[0], mine.size, B.shape[2]))], axis=1)
            D = np.concatenate([D, t[:, mine]], axis=1)
        key = np.concatenate([pose_index[:, None].astype(float), D], axis=1)
        _, first, back = np.unique(key, axis=0, return_index=True, return_inverse=True)
        back = back.ravel()
        pidx, Du = pose_index[first], D[first]
        Bt = B[pidx] * Du[..., None]
        gi = _gram_pinv(Bt) if pm.n_loops else np.zeros((len(pidx), 0, 0))
        R = pm.n_rows
        for w, C in (("p", Cp), ("r", Cr)):
            if C.shape[1] == 0:
                continue
            Ct = C[pidx] * Du[:, None, :]
            tgt = _maximise_norm(Ct, Bt, gi, pm.n_disk, tol=tol, tol_solve=tol_solve, groups=pm.groups)
            n_solves += tgt.n_solves
            sq[w][:, 0] += tgt.lower[back] ** 2
            sq[w][:, 1] += tgt.upper[back] ** 2
            sfull = tgt.sigma[back] * D
            screws[w][:, pm.cols] = sfull[:, :R]
            if mine.size:
                extra_val[w][:, mine] = sfull[:, R:]
    twists = {}
    for w in ("p", "r"):
        tw = np.zeros((n, 6))
        for pm in maps:
            s = screws[w][:, pm.cols]
            tw[:, list(pm.pos_comps)] = np.einsum("nkr,nr->nk", pm.C_pos[pose_index], s)
            tw[:, list(pm.rot_comps)] = np.einsum("nkr,nr->nk", pm.C_rot[pose_index], s)
        if q:
            tw += np.einsum("nkq,nq->nk", J[pose_index], extra_val[w])
        twists[w] = tw
    res = MaxPoseError(
        p_max=np.sqrt(sq["p"][:, 0]), p_upper=np.sqrt(sq["p"][:, 1]),
        r_max=np.sqrt(sq["r"][:, 0]), r_upper=np.sqrt(sq["r"][:, 1]),
        p_screws=screws["p"].reshape(n, -1, 6), r_screws=screws["r"].reshape(n, -1, 6),
        p_twist=twists["p"], r_twist=twists["r"], joint_names=tuple(j.name for j in mech.joints),
        n_solves=n_solves, seconds=time.perf_counter() - t0,
        p_extra=extra_val["p"] if q else None, r_extra=extra_val["r"] if q else None)
    return res


def max_pose_error(mech: ClearanceMechanism, poses, bounds=None, *, tol: float = 1e-3, extra=None) -> MaxPoseError:
    """Global maximum positional and rotational error at each pose (Deng 2012 eqs. III.26-III.27,
    V.8, V.13), with explicit maximising screws and certified upper bounds.

    poses: (n, d) in the mechanism's pose coordinates (m); bounds: None (the joints' own bounds),
    an array (n_joints, 4) for all poses or (n, n_joints, 4) per pose, columns
    ``[beta_xy (rad), beta_z (rad), b_xy (m), b_z (m)]`` in the order of ``mech.joints``.
    tol: relative gap between the attained value and the certified bound (default 0.1 %).
    extra: optional ``(J, t)`` of other interval error sources added to the clearances (see
    :func:`evaluate_cases`), e.g. geometric tolerances through the 5-bar's J_p.
    """
    poses = np.atleast_2d(np.asarray(poses, float))
    b = _as_bounds(mech, bounds, len(poses))
    maps = mech.pose_maps(poses)
    idx = np.arange(len(poses))
    return evaluate_cases(mech, maps, idx, np.broadcast_to(b, (len(poses),) + b.shape[-2:]), tol=tol, extra=extra)


def _evaluate_chunk(args):
    mech, maps, idx, b, tol = args
    return evaluate_cases(mech, maps, idx, b, tol=tol)


class ClearanceEvaluator:
    """Evaluate many clearance-bound sets at fixed poses; the per-pose maps are computed once.

    >>> ev = ClearanceEvaluator(mech, poses)           # poses (n, d), metres
    >>> ev.evaluate(bounds, pose_index=0)              # bounds (n_sets, n_joints, 4)
    >>> ev.evaluate_poses(bounds)                      # bounds (n_joints, 4) or (n, n_joints, 4)
    """

    def __init__(self, mech: ClearanceMechanism, poses, *, tol: float = 1e-3):
        self.mech = mech
        self.poses = np.atleast_2d(np.asarray(poses, float))
        self.maps = mech.pose_maps(self.poses)
        self.tol = tol

    def evaluate(self, bounds, pose_index=0, *, workers: int = 1, scheduler=None, chunk_size: int = 4096) -> MaxPoseError:
        """All bound sets at their poses. ``workers > 1`` (local processes) or ``scheduler`` (a
        Dask address or Client) split the sets into chunks of ``chunk_size`` solved in parallel;
        results come back in order."""
        b = _as_bounds(self.mech, bounds, 0)
        b = b.reshape((-1,) + b.shape[-2:])
        idx = np.broadcast_to(np.asarray(pose_index, int), (len(b),))
        if idx.size and (idx.min() < 0 or idx.max() >= len(self.poses)):
            raise ValidationError("pose_index", pose_index, f"indices in [0, {len(self.poses)})")
        if (workers is None or workers > 1 or scheduler is not None) and len(b) > chunk_size:
            t0 = time.perf_counter()
            items = [(self.mech, self.maps, idx[s:s + chunk_size], b[s:s + chunk_size], self.tol)
                     for s in range(0, len(b), chunk_size)]
            warm_up()     # compile the solver's kernels once here, not once per worker
            out = MaxPoseError.concat(parallel_map(_evaluate_chunk, items, workers=workers, scheduler=scheduler))
            out.seconds = time.perf_counter() - t0
            return out
        return evaluate_cases(self.mech, self.maps, idx, b, tol=self.tol)

    def evaluate_poses(self, bounds=None) -> MaxPoseError:
        n = len(self.poses)
        b = _as_bounds(self.mech, bounds, n)
        return evaluate_cases(self.mech, self.maps, np.arange(n), np.broadcast_to(b, (n,) + b.shape[-2:]), tol=self.tol)


def sample_max_errors(mech: ClearanceMechanism, pose, bounds=None, *, n_samples: int = 10 ** 6, seed: int = 0,
                      mode: str = "boundary", chunk: int = 100_000) -> tuple[float, float]:
    """Largest positional and rotational error reached by **random** clearance states at one pose
    -- what plain Monte Carlo verification would report (compare with :func:`max_pose_error`).

    Each sample draws every joint's screw at random in its clearance set (``mode="uniform"``:
    uniformly inside the disks and intervals; ``"boundary"``: on their boundaries, i.e. every
    clearance fully taken up in a random direction), removes the part that violates the loop
    equations (orthogonal projection onto ``B^T s = 0``) and scales back into the clearance set,
    so every sample is a feasible, consistent clearance state. Returns (p, r) in m and rad.
    """
    if mode not in ("uniform", "boundary"):
        raise ValidationError("mode", mode, "'uniform' or 'boundary'")
    rng = np.random.default_rng(seed)
    maps = mech.pose_maps(np.atleast_2d(np.asarray(pose, float)))
    b = _as_bounds(mech, bounds, 1)
    best = {"p": np.zeros(1), "r": np.zeros(1)}
    left = int(n_samples)
    while left > 0:
        n = min(chunk, left)
        left -= n
        tot = {"p": np.zeros(n), "r": np.zeros(n)}
        for pm in maps:
            s = pm.sample_screws(0, b, n, rng, mode)
            tot["p"] += ((s @ pm.C_pos[0].T) ** 2).sum(-1)
            tot["r"] += ((s @ pm.C_rot[0].T) ** 2).sum(-1)
        for w in ("p", "r"):
            best[w] = np.maximum(best[w], np.sqrt(tot[w].max()))
    return float(best["p"][0]), float(best["r"][0])

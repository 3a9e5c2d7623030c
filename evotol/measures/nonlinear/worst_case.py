"""Worst case of an assembly's **nonlinear** response over the tolerance box, with a proof.

For an assembly function ``y_k = f_k(x)`` (:class:`evotol.robots.assembly.AssemblyFunction`) and
tolerances ``t`` the box is ``x0 ± t``; the quantity is ``W_k = max_box |f_k(x) − f_k(x0)| / L_k``
(the nonlinear counterpart of the arithmetic stack ``Σ_j |∂f_k/∂x_j| t_j / L_k``). Two routes, and
the result says which one applied:

* **monotone** -- the interval enclosure of every partial derivative ``∂f_k/∂x_j`` over the whole
  box (:class:`evotol.measures.nonlinear.interval.Dual`, forward mode on intervals with outward rounding) excludes 0:
  ``f_k`` is monotone in every dimension on the box, so its extremes are attained at two vertices
  and **vertex enumeration** (all 2^n vertices evaluated, n <= 16) is exact;
* otherwise **branch and bound**: boxes bisected along their widest side (relative to t), each
  bounded by the intersection of the natural interval extension and the mean-value form
  ``f(c) + Σ_j ∂f/∂x_j(B)·[−w_j, w_j]`` (Moore 1966; Hansen & Walster 2004); the lower bound is
  the best value at box centres and vertices. It stops when the largest bound of an unexplored
  box is within ``rtol`` (relative to the limit) of the attained value: ``proven_bound`` then
  holds for the whole box, ``attained`` is reached at ``worst_point``.
"""
from __future__ import annotations

import heapq
import itertools

import numpy as np

from evotol.errors import ValidationError, is_integer, is_real
from evotol.measures.nonlinear.interval import Dual, Interval
from evotol.robots.assembly import AssemblyFunction, LinearStack


def _responses(asm, X):
    """The assembly function at X (list of per-dimension arrays / Intervals / Duals) -> list per response."""
    out = asm.function(**dict(zip(asm.dimension_names, X)))
    if isinstance(out, dict):
        out = [out[n] for n in asm.response_names]
    return list(out) if isinstance(out, (tuple, list)) else [out]


def _check(asm, t) -> np.ndarray:
    if not isinstance(asm, AssemblyFunction):
        raise ValidationError("robot", getattr(asm, "name", asm), "an assembly function (evotol.robots.assembly.AssemblyFunction)")
    t = np.asarray(t, dtype=float)
    if t.shape != (len(asm.dimension_names),) or not np.all(np.isfinite(t)) or np.any(t < 0):
        raise ValidationError("tolerances", t.tolist(), f"{len(asm.dimension_names)} finite tolerances >= 0 (SI)")
    return t


def _bound_boxes(asm, k: int, sign: float, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Upper bounds of sign·(f_k − f_k(x0)) over boxes [lo, hi] (m, n): natural ∩ mean-value form."""
    y0 = asm.y0[k]
    nat = _responses(asm, [Interval(lo[:, j], hi[:, j]) for j in range(lo.shape[1])])[k]
    d = _responses(asm, Dual.variables(lo, hi))[k]
    c = 0.5 * (lo + hi)
    w = 0.5 * (hi - lo)
    with np.errstate(all="ignore"):
        fc = np.asarray(asm.evaluate(c)[:, k], dtype=float)
        slope = np.maximum(np.abs(d.grad.lo), np.abs(d.grad.hi))
        mv_hi = fc + np.sum(slope * w, axis=1) * (1 + 1e-12)
        mv_lo = fc - np.sum(slope * w, axis=1) * (1 + 1e-12)
    up = np.minimum(nat.hi, np.where(np.isfinite(mv_hi), mv_hi, np.inf))
    dn = np.maximum(nat.lo, np.where(np.isfinite(mv_lo), mv_lo, -np.inf))
    return (up - y0) if sign > 0 else (y0 - dn)


def nonlinear_worst_case(asm, t, *, rtol: float = 1e-6, max_boxes: int = 200_000) -> dict:
    """Proven worst case of every response of ``asm`` over the box ``x0 ± t`` (module docstring).

    Parameters
    ----------
    asm : evotol.robots.assembly.AssemblyFunction
        The assembly (its function is evaluated on intervals: write it with numpy ufuncs).
    t : array_like
        Tolerances (SI), one per dimension.
    rtol : float
        Branch and bound stops when the bound is within ``rtol`` × limit of the attained value.
    max_boxes : int
        Budget of boxes for branch and bound, a positive integer (the bound reported is valid
        whenever it stops).

    Returns
    -------
    dict
        ``max_over_limit`` (the largest proven bound / limit over responses), ``attained_over_limit``,
        and ``responses``: a list with, per response, ``name``, ``method`` ("monotone: vertex enumeration" or "branch and bound"),
        ``proven_bound_over_limit``, ``attained_over_limit``, ``worst_point_offsets`` (δx at the
        attained extreme, SI), ``side`` (+1: above the nominal response, −1: below), ``linear_over_limit``
        (the arithmetic stack), ``n_boxes``.

    Raises
    ------
    evotol.errors.ValidationError
        Not an assembly function, bad tolerances, ``max_boxes`` not a positive integer, or an
        ``rtol`` that is not a finite non-negative number.
    """
    t = _check(asm, t)
    if not is_integer(max_boxes, 1):
        raise ValidationError("max_boxes", max_boxes, "a positive integer")
    if not (is_real(rtol) and 0 <= rtol < np.inf):
        raise ValidationError("rtol", rtol, "a finite non-negative tolerance relative to the limit")
    if isinstance(asm, LinearStack):         # linear: the arithmetic stack is the exact worst case
        out = []
        for k, name in enumerate(asm.response_names):
            v = float(np.abs(asm.gradient[k]) @ t) / float(asm.limits[k])
            out.append({"name": name, "method": "linear stack: the arithmetic stack is exact", "proven_bound_over_limit": v,
                        "attained_over_limit": v, "worst_point_offsets": (np.sign(asm.gradient[k]) * t).tolist(),
                        "side": 1, "linear_over_limit": v, "n_boxes": 0})
        return {"max_over_limit": max(r["proven_bound_over_limit"] for r in out),
                "attained_over_limit": max(r["attained_over_limit"] for r in out), "responses": out}
    n = t.size
    x0 = asm.x0
    lo, hi = x0 - t, x0 + t
    d = _responses(asm, Dual.variables(lo[None], hi[None]))
    out = []
    for k, name in enumerate(asm.response_names):
        L = float(asm.limits[k])
        g = d[k].grad
        monotone = bool(np.all((g.lo > 0) | (g.hi < 0) | (t[None] == 0)))
        lin = float(np.abs(asm.gradient[k]) @ t) / L
        best = {"value": -np.inf}
        if monotone and n <= 16:
            V = np.array(list(itertools.product((-1.0, 1.0), repeat=n))) * t
            with np.errstate(all="ignore"):
                dy = np.asarray(asm.evaluate(x0 + V)[:, k], dtype=float) - asm.y0[k]
            i = int(np.nanargmax(np.abs(dy)))
            val = float(abs(dy[i])) / L
            out.append({"name": name, "method": "monotone: vertex enumeration", "proven_bound_over_limit": val,
                        "attained_over_limit": val, "worst_point_offsets": V[i].tolist(), "side": int(np.sign(dy[i])),
                        "linear_over_limit": lin, "n_boxes": int(len(V))})
            continue
        proven, n_boxes = -np.inf, 0
        for sign in (1.0, -1.0):
            heap, count = [], 0
            ub = _bound_boxes(asm, k, sign, lo[None], hi[None])[0]
            heapq.heappush(heap, (-ub, count, lo.copy(), hi.copy()))
            side_bound = ub
            while heap:
                neg_ub, _, blo, bhi = heapq.heappop(heap)
                side_bound = -neg_ub
                if side_bound <= best["value"] * L + rtol * L or n_boxes >= max_boxes:
                    break
                j = int(np.argmax((bhi - blo) / np.where(t > 0, t, 1.0)))
                mid = 0.5 * (blo[j] + bhi[j])
                kids_lo = np.array([blo, blo]); kids_hi = np.array([bhi, bhi])
                kids_hi[0, j], kids_lo[1, j] = mid, mid
                pts = np.concatenate([0.5 * (kids_lo + kids_hi), kids_lo, kids_hi])
                with np.errstate(all="ignore"):
                    vals = sign * (np.asarray(asm.evaluate(pts)[:, k], dtype=float) - asm.y0[k])
                i = int(np.nanargmax(vals))
                if vals[i] / L > best["value"]:
                    best = {"value": float(vals[i]) / L, "point": pts[i] - x0, "side": int(sign)}
                ubs = _bound_boxes(asm, k, sign, kids_lo, kids_hi)
                n_boxes += 2
                for c in range(2):
                    count += 1
                    heapq.heappush(heap, (-ubs[c], count, kids_lo[c], kids_hi[c]))
            else:
                side_bound = best["value"] * L
            proven = max(proven, min(side_bound, ub) / L)
        out.append({"name": name, "method": "branch and bound (not proven monotone on the box)",
                    "proven_bound_over_limit": float(max(proven, best["value"])), "attained_over_limit": best["value"],
                    "worst_point_offsets": best["point"].tolist(), "side": best["side"], "linear_over_limit": lin,
                    "n_boxes": n_boxes})
    return {"max_over_limit": max(r["proven_bound_over_limit"] for r in out),
            "attained_over_limit": max(r["attained_over_limit"] for r in out), "responses": out}

"""ISO 9283 position figures: the standard's formulas on attained positions, and their prediction from
the first-order model (docs/iso9283.md).

Standard (ISO 9283:1998 §7.2.1, §7.2.2), at one pose, commanded ``x_c``, attained ``x_j`` in cycles
``j = 1..n``: barycentre ``x̄ = (1/n) Σ x_j``; ``AP = |x̄ − x_c|``; ``l_j = |x_j − x̄|``,
``l̄ = (1/n) Σ l_j``, ``S_l = sqrt(Σ (l_j − l̄)² / (n − 1))``, ``RP = l̄ + 3 S_l``; multi-directional
``vAP = max_{h,k} |x̄_h − x̄_k|`` over approach directions.

Prediction (first order, position rows ``J`` of the sensitivity at a pose, columns of the model):

* **AP, worst case.** A robot's barycentre error is ``J (δ + o)``: ``δ`` its systematic errors, each in
  ``[−t_i, t_i]``, ``o`` the lost motion taken up from the approach side, ``o_J = −s_J b'_J / 2`` with the
  as-built lost motion ``b'_J ∈ [0, b_J]`` (a joint the approach does not move: ``o_J ∈ ±b'_J/2``). The set of barycentre errors is a zonotope ``K`` (a box's
  image, shifted); its largest norm is ``max_{|u|=1} h_K(u)``, ``h_K(u) = u·c + Σ_i w_i |u·J_i|``
  (centre ``c``, half-widths ``w``) -- the support-function stack-up of
  :mod:`evotol.measures.linear.stackup`, which returns the value attained by explicit errors and a
  proven upper bound (grid maximum / cos δ).
* **AP at a yield.** Robots drawn uniformly within the tolerances (``b'_J ~ U(0, b_J)``), the yield
  quantile of ``|J (δ + o)|`` (sampled).
* **RP.** Cycle errors ``e = J Σ_k t_k G_k d_k`` (unit draws ``d_k`` of each random source,
  :mod:`evotol.robots.mechanism.model.random_sources`); ``RP = E l + 3 std l`` with ``l = |e − E e|``, the limit of the
  standard's estimate for many cycles -- **sampled** (``n_samples`` draws), not a Gaussian: bounded errors
  have lighter tails, and :func:`gaussian_rp` (the same covariance, a normal law) over-predicts RP (by
  ~10 % when one uniform joint error dominates: ``1.505 a`` against ``1.366 a``).

The parameters several functions share are described once, here.

Parameters
----------
J : (p, 3, n_columns) ndarray
    Position rows of the first-order map per pose (m per m or rad).
loadings : list of (n_columns, dim) ndarray
    Per random source its column loading (:func:`evotol.robots.mechanism.model.random_sources.column_loading`).
tolerances : (n_random,) array_like
    Tolerances of the random sources (SI).
draws : list of (n, dim) ndarray
    Unit draws per source (:func:`evotol.robots.mechanism.model.random_sources.unit_draws`).
n_samples : int
    Number of draws.
seed : int or None
    Seed of the draws.
e : (..., n, 3) ndarray
    Position errors (m), samples along axis -2.
"""
from __future__ import annotations

import numpy as np

from evotol.measures.linear.directions import directions_for
from evotol.measures.linear.stackup import refine_direction


def figures_of_test(attained, commanded) -> dict:
    """AP and RP of one ISO test by the standard's formulas (module docstring).

    Parameters
    ----------
    attained : (..., n, 3) array_like
        Attained positions of ``n`` cycles (m); leading axes (robots, poses) are kept.
    commanded : (..., 3) array_like
        The commanded position (m), broadcast against the leading axes.

    Returns
    -------
    dict
        ``barycentre`` (..., 3), ``AP`` (...), ``l_mean`` (...), ``S_l`` (...), ``RP`` (...), m.

    Examples
    --------
    >>> x = [[0.0, 0, 0], [2.0, 0, 0]]
    >>> f = figures_of_test(x, [0.0, 1.0, 0.0])
    >>> float(f["AP"]) == 2 ** 0.5, float(f["RP"])     # l = (1, 1): l̄ = 1, S_l = 0
    (True, 1.0)
    """
    X = np.asarray(attained, float)
    xb = X.mean(axis=-2)
    l = np.linalg.norm(X - xb[..., None, :], axis=-1)
    lm, S = l.mean(axis=-1), l.std(axis=-1, ddof=1)
    return {"barycentre": xb, "AP": np.linalg.norm(xb - np.asarray(commanded, float), axis=-1),
            "l_mean": lm, "S_l": S, "RP": lm + 3 * S}


def ap_worst_case(J, centre, half) -> tuple[np.ndarray, np.ndarray]:
    """Largest barycentre error ``max |J x|`` over the box ``x ∈ centre ± half`` at each pose.

    Parameters
    ----------
    J : (p, 3, m) ndarray
        Position rows of the first-order map per pose (m per m or rad).
    centre, half : (m,) ndarray
        Centre and half-widths of the box of column errors (m or rad).

    Returns
    -------
    value : (p,) ndarray
        Attained by an explicit corner of the box (m).
    bound : (p,) ndarray
        Proven upper bound (m): grid maximum of ``h_K`` / cos δ.
    """
    J = np.asarray(J, float)
    keep = np.asarray(half) > 0
    blocks = [J[:, :, [i]] for i in np.flatnonzero(keep)]
    shift = np.einsum("pim,m->pi", J, np.asarray(centre, float))
    if not blocks:
        n = np.linalg.norm(shift, axis=1)
        return n, n
    D, delta = directions_for(J, 600, full_sphere=True)
    grid = shift @ D.T + np.abs(np.einsum("dk,pkm->pdm", D, J[:, :, keep])) @ np.asarray(half)[keep]   # (p, d)
    k = np.argmax(grid, axis=1)
    gmax = grid[np.arange(len(J)), k]
    u, h = refine_direction(blocks, np.asarray(half)[keep][None], D[k][None], shift=shift[None])
    value = np.maximum(h[0], gmax)
    return value, np.maximum(gmax / np.cos(delta), value)


def ap_at_yield(J, half, lost_motion, free, yield_, n_samples: int = 20000, seed=0) -> np.ndarray:
    """The ``yield_`` quantile of the barycentre error over robots drawn within the tolerances.

    Parameters
    ----------
    J : (p, 3, m) ndarray
        Position rows of the first-order map per pose.
    half : (m,) ndarray
        Systematic errors uniform in ``± half`` (m or rad).
    lost_motion : (m,) ndarray
        Per column the lost-motion offset at full lost motion ``−s b/2`` (rad); a robot's is that
        times ``b'/b ~ U(0, 1)``.
    free : (m,) ndarray
        Per column ``b/2`` of lost motion the approach does not take up (rad); a robot's offset is
        ``(b'/b) free U(−1, 1)``.
    yield_ : float
        Share of robots that must meet the figure, in (0, 1).
    n_samples : int
        Robots drawn.
    seed : int or None
        Seed of the draws.

    Returns
    -------
    (p,) ndarray
        AP (m) at the yield, per pose (sampled).
    """
    rng = np.random.default_rng(seed)
    m = len(half)
    share = rng.random((n_samples, m))
    x = half * rng.uniform(-1, 1, (n_samples, m)) + share * (lost_motion + free * rng.uniform(-1, 1, (n_samples, m)))
    e = np.einsum("pim,nm->pni", J, x)
    return np.quantile(np.linalg.norm(e, axis=-1), yield_, axis=1)


def orientation_figures_of_test(angles) -> dict:
    """Orientation AP and RP of one ISO test (ISO 9283 §7.2.1-7.2.2): per angle ``a, b, c``
    ``AP_a = ā − a_c`` and ``RP_a = ±3 S_a``, ``S_a = sqrt(Σ (a_j − ā)² / (n − 1))``.

    Parameters
    ----------
    angles : (..., n, 3) array_like
        Attained minus commanded orientation of ``n`` cycles about the base axes x, y, z (rad): the
        rotation vector of each cycle's orientation error (docs/iso9283.md: first order in the angles).

    Returns
    -------
    dict
        ``AP`` (..., 3) signed ``ā − a_c`` and ``RP`` (..., 3) ``3 S_a``, rad.

    Examples
    --------
    >>> f = orientation_figures_of_test([[1e-3, 0, 0], [3e-3, 0, 2e-3]])
    >>> [round(float(v), 6) for v in f["AP"]], round(float(f["RP"][0]) / 3, 7)
    ([0.002, 0.0, 0.001], 0.0014142)
    """
    A = np.asarray(angles, float)
    return {"AP": A.mean(axis=-2), "RP": 3 * A.std(axis=-2, ddof=1)}


def cycle_errors_linear(J, loadings, tolerances, draws) -> np.ndarray:
    """First-order cycle errors at each pose: ``J Σ_k t_k G_k d_k``.

    Returns
    -------
    (p, n, 3) ndarray
        Position errors (m).
    """
    cols = sum(t * d @ G.T for G, t, d in zip(loadings, tolerances, draws))
    return np.einsum("pim,nm->pni", J, cols)


def rp_from_errors(e) -> np.ndarray:
    """``E l + 3 std l`` with ``l = |e − mean e|`` over the sample axis -2 of ``e``.

    Returns
    -------
    (...) ndarray
        RP (m).
    """
    l = np.linalg.norm(e - e.mean(axis=-2, keepdims=True), axis=-1)
    return l.mean(axis=-1) + 3 * l.std(axis=-1, ddof=1)


def gaussian_rp(J, loadings, tolerances, variances, n_samples: int = 200000, seed=0) -> np.ndarray:
    """The Gaussian shortcut (for comparison only): RP of a normal law with the linearised covariance
    ``Σ = Σ_k t_k² J G_k diag(var_k) G_kᵀ Jᵀ`` (m).

    Parameters
    ----------
    variances : list of (dim,) array_like
        Variance of each source's unit draw (``w²/12`` for ``U(±w/2)``, ``1/16`` per axis for the
        disc of radius 1/2).

    Returns
    -------
    (p,) ndarray
        RP of the normal law per pose (m).
    """
    C = sum(t * t * (G * np.asarray(v)) @ G.T for G, t, v in zip(loadings, tolerances, variances))
    S = np.einsum("pim,mk,pjk->pij", J, C, J)
    w, V = np.linalg.eigh(S)
    L = V * np.sqrt(np.maximum(w, 0.0))[:, None, :]
    z = np.random.default_rng(seed).standard_normal((n_samples, 3))
    return rp_from_errors(np.einsum("pij,nj->pni", L, z))


def worst_direction(J, c, h, n_iter: int = 60) -> np.ndarray:
    """The direction ``u*`` maximising ``h_K(u) = u·J c + Σ_i h_i |u·J_i|`` at one pose (grid start,
    fixed-point ascent ``u ← ∇h/|∇h|``, which never decreases the convex ``h_K``).

    Parameters
    ----------
    J : (3, m) ndarray
        Position rows of the first-order map at the pose.
    c, h : (m,) ndarray
        Centre and half-widths of the box of column errors (m or rad).
    n_iter : int
        Ascent steps at most.

    Returns
    -------
    (3,) ndarray
        Unit direction.
    """
    D, _ = directions_for(J[None], 600, full_sphere=True)
    u = D[np.argmax(D @ (J @ c) + np.abs(D @ J) @ h)]
    for _ in range(n_iter):
        g = J @ c + J @ (h * np.sign(u @ J))
        nu = g / max(np.linalg.norm(g), 1e-300)
        if np.allclose(nu, u, atol=1e-13):
            break
        u = nu
    return u

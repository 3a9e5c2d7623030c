"""The two sides of the support function's certificate (Deng 2012 eqs. III.26-III.27, V.8, V.13).

For a dual point ``mu`` the vectors ``y = a + Bt mu`` give the **upper bound**
``f(mu) = sum_c ||y_c|| >= h(w)`` (weak duality, :func:`true_dual`; its smoothing ``f_eps`` adds
``eps^2`` under each root). The **lower bound** is ``a^T sigma`` of feasible scaled screws
``sigma``: the cone-wise ``sigma_c = y_c / sqrt(||y_c||^2 + eps^2)``
(:func:`recover_primal`) or the barrier point, with the loop residual ``Bt^T sigma`` projected
out and ``sigma`` scaled back into the unit cones, optionally after the complementary-slackness
repair (cones on their boundary fixed to ``y_c / ||y_c||``). Rows: ``nd`` disk cones as pairs
first, then interval rows. Used by :func:`evotol.robots.clearance.support.solve_support` and its
compiled steps.
"""
from __future__ import annotations

import numpy as np


def _cone_norms(Y: np.ndarray, nd: int) -> tuple[np.ndarray, np.ndarray]:
    K = Y.shape[:-1]
    Yd = Y[..., :2 * nd].reshape(K + (nd, 2))
    return np.sqrt((Yd ** 2).sum(-1)), np.abs(Y[..., 2 * nd:])


def true_dual(Y: np.ndarray, nd: int) -> np.ndarray:
    """Dual objective ``f = sum_c ||y_c||`` of the cone-wise vectors ``y``.

    Parameters
    ----------
    Y : (..., R) ndarray
        Vectors ``y = a + B mu``: ``nd`` disk pairs first, then interval rows.

    Returns
    -------
    (...,) ndarray
        Sum of the disks' Euclidean norms and the intervals' absolute values (a certified upper
        bound of the support value by weak duality).
    """
    nd_, ni_ = _cone_norms(Y, nd)
    return nd_.sum(-1) + ni_.sum(-1)


def recover_primal(Y: np.ndarray, a: np.ndarray, B: np.ndarray, nd: int, eps: np.ndarray,
                   gram_inv: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Feasible scaled screws from the smoothed optimality condition; returns (sigma, a^T sigma).

    ``sigma_c = y_c / sqrt(||y_c||^2 + eps^2)``, then the loop residual is projected out and
    ``sigma`` scaled back into the unit cones.

    Parameters
    ----------
    Y : (K, R) ndarray
        Dual vectors ``y = a + B mu``.
    a : (K, R) ndarray
        Scaled linear terms.
    B : (K, R, m) ndarray
        Scaled loop maps.
    nd : int
        Number of disk cones (rows in pairs first; intervals after).
    eps : (K,) ndarray
        Smoothing parameters (0: ``sigma_c = y_c / ||y_c||``).

    Returns
    -------
    sigma : (K, R) ndarray
        Feasible scaled screws.
    lower : (K,) ndarray
        ``a^T sigma``: lower bounds of the support values.
    """
    K = Y.shape[0]
    Yd = Y[:, :2 * nd].reshape(K, nd, 2)
    rd = np.sqrt((Yd ** 2).sum(-1) + eps[:, None] ** 2)
    ri = np.sqrt(Y[:, 2 * nd:] ** 2 + eps[:, None] ** 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        sd = np.where(rd[..., None] > 0, Yd / rd[..., None], 0.0)
        si = np.where(ri > 0, Y[:, 2 * nd:] / ri, 0.0)
    sigma = np.concatenate([sd.reshape(K, 2 * nd), si], axis=1)
    if not B.shape[-1]:           # no loop equation: nothing to project out
        gram_inv = np.zeros((K, 0, 0))
    elif gram_inv is None:
        gram_inv = _gram_pinv(B)
    return _project(sigma, a, B, nd, gram_inv)


def _gram_pinv(B: np.ndarray) -> np.ndarray:
    G = np.swapaxes(B, 1, 2) @ B
    return np.linalg.pinv(G, rcond=1e-12, hermitian=True)


def _project_free(sigma: np.ndarray, Y: np.ndarray, a: np.ndarray, B: np.ndarray, nd: int, gram_inv: np.ndarray,
                  cut: float = 1e-3):
    """Primal repair: cones whose barrier point is on the boundary (``||sigma_c|| > 1 - cut``) are
    fixed to ``y_c / ||y_c||`` (complementary slackness); the loop residual is removed by moving
    only the other (interior) cones, then everything is scaled back into the cones if needed."""
    K, R = sigma.shape
    nrm_d, nrm_i = _cone_norms(sigma, nd)
    act = np.concatenate([np.repeat(nrm_d > 1 - cut, 2, axis=1), nrm_i > 1 - cut], axis=1)
    yd, yi = _cone_norms(Y, nd)
    ynorm = np.concatenate([np.repeat(yd, 2, axis=1), yi], axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.where(ynorm > 0, Y / ynorm, 0.0)
    s = np.where(act, unit, sigma)
    Bf = B * (~act)[..., None]
    r = np.einsum("kr,krm->km", s, B)
    G = np.swapaxes(Bf, 1, 2) @ Bf
    m = G.shape[-1]
    G += (1e-10 * np.trace(G, axis1=1, axis2=2) / max(m, 1) + 1e-300)[:, None, None] * np.eye(m)
    s = s - (Bf @ np.linalg.solve(G, r[..., None]))[..., 0]   # the small remainder is removed below
    return _project(s, a, B, nd, gram_inv)


def _project(sigma: np.ndarray, a: np.ndarray, B: np.ndarray, nd: int, gram_inv: np.ndarray):
    """Remove the loop residual ``B^T sigma`` and scale back into the unit cones."""
    r = np.einsum("kr,krm->km", sigma, B)
    sigma = sigma - np.einsum("krm,km->kr", B, np.einsum("kmn,kn->km", gram_inv, r))
    nd_, ni_ = _cone_norms(sigma, nd)
    worst = np.maximum(nd_.max(-1, initial=0.0), ni_.max(-1, initial=0.0))
    sigma = sigma / np.maximum(worst, 1.0)[:, None]
    return sigma, np.einsum("kr,kr->k", a, sigma)

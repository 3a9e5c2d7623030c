"""The noise's share of the requirement as a probability: a quantile of the propagated noise's norm.

After calibration the instrument noise leaves, at a task pose, a normal error ``n ~ N(0, C)``
(``C`` the 3×3 position or orientation block of ``J_K Σ_K J_Kᵀ``,
:meth:`evotol.calibration.model.CalibratedRobot.noise_covariance`). Its norm ``|n|`` is the length of a
normal vector with unequal variances: ``|n|² = Σ λ_i z_i²`` (``λ_i`` the eigenvalues of ``C``, ``z_i``
standard normal), a weighted sum of χ²₁ variables. With ``λ_1 ≥ λ_2 ≥ λ_3`` its distribution function is
an integral over the two larger ones of the closed form in the smallest::

    P(|n|² ≤ x) = ∫∫_{λ_1 z_1² + λ_2 z_2² ≤ x} φ(z_1) φ(z_2) (2 Φ(sqrt((x − λ_1 z_1² − λ_2 z_2²) / λ_3)) − 1) dz_2 dz_1,

taken by Gauss-Legendre quadrature after ``z = L sin s`` on each bounded range (which removes the
square-root edge of the ellipse), or on ``[−10, 10]`` where the range is wider (``φ(10) ≈ 8e-23``);
with two or one positive eigenvalues the same formula has one integral or none. The quantile at
probability ``p`` is its root in ``x`` (:func:`norm_quantile`). With
``|e| ≤ |g| + |n|`` the residual of a robot whose geometric part is ``g`` stays below
``|g| + q_p`` at a pose with probability at least ``p``: the noise's share stated as a probability.
The level used is ``P(|z| ≤ k)`` of the plan's ``k`` (99.73 % at ``k = 3``), the 1-D meaning of
``k`` sigma carried over to the 3-D norm.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq
from scipy.special import ndtr
from scipy.stats import norm

from evotol.errors import ValidationError


def level_of(k: float) -> float:
    """The probability ``P(|z| ≤ k)`` of a standard normal ``z`` (0.9973 at ``k = 3``).

    Parameters
    ----------
    k : float
        Coverage factor (> 0).

    Returns
    -------
    float
        The two-sided probability.
    """
    return float(2 * norm.cdf(k) - 1)


#: Gauss-Legendre nodes per integral, and where a normal range is cut (standard deviations)
NODES, CUT = 96, 10.0
_S, _W = np.polynomial.legendre.leggauss(NODES)
_ROOT_2PI = np.sqrt(2 * np.pi)
_SIN, _COS = np.sin(np.pi / 2 * _S), np.cos(np.pi / 2 * _S)          # the substitution's, computed once


def _pdf(z):
    """The standard normal density, as scipy.stats.norm.pdf computes it, without its argument checks (the
    quantile's root solve calls it thousands of times: 3x faster)."""
    return np.exp(-z ** 2 / 2.0) / _ROOT_2PI


def _over(L):
    """Nodes z (k, NODES) and weights over [−L, L] for each half-width L (k,): ``z = L sin(πs/2)`` when L ≤ CUT."""
    L = np.asarray(L, float)[:, None]
    bounded = L <= CUT
    z = np.where(bounded, L * _SIN, CUT * _S)
    w = np.where(bounded, L * _COS * np.pi / 2 * _W, CUT * _W)
    return z, w


def _cdf(x: float, lam: np.ndarray) -> float:
    """``P(Σ λ_i z_i² ≤ x)`` (module docstring) for 1 to 3 eigenvalues ``lam`` > 0, sorted descending."""
    last = lambda rest: 2 * ndtr(np.sqrt(np.maximum(rest, 0.0) / lam[-1])) - 1         # noqa: E731
    if len(lam) == 1:
        return float(last(x))
    z1, w1 = _over([np.sqrt(x / lam[0])])
    r1 = x - lam[0] * z1[0] ** 2                                          # (NODES,)
    if len(lam) == 2:
        return float(np.sum(w1[0] * _pdf(z1[0]) * last(r1)))
    z2, w2 = _over(np.sqrt(np.maximum(r1, 0.0) / lam[1]))                 # (NODES, NODES)
    inner = np.sum(w2 * _pdf(z2) * last(r1[:, None] - lam[1] * z2 ** 2), axis=1)
    return float(np.sum(w1[0] * _pdf(z1[0]) * inner))


def norm_quantile(cov, p: float) -> np.ndarray:
    """Quantile ``q_p`` of ``|n|``, ``n ~ N(0, C)``, for each covariance (module docstring).

    Parameters
    ----------
    cov : (..., d, d) array_like
        Covariances (m² or rad²), symmetric positive semi-definite.
    p : float
        Probability in (0, 1).

    Returns
    -------
    (...) ndarray
        ``q`` with ``P(|n| ≤ q) = p`` (m or rad); 0 for a zero covariance.

    Raises
    ------
    evotol.errors.ValidationError
        ``p`` outside (0, 1).
    """
    C = np.asarray(cov, float)
    out = np.zeros(C.shape[:-2]).ravel()
    for i, (top, lam) in enumerate(_scaled_eigenvalues(C, p)):
        if not lam.size:
            continue
        # P(|n|² ≤ x) = p; bracket: 0 at x = 0, and at least p once x/d is the 1-D quantile of the largest variance
        hi = len(lam) * norm.ppf(0.5 + p / 2) ** 2 * 1.01
        out[i] = np.sqrt(top * brentq(lambda x: _cdf(x, lam) - p, 0.0, hi, xtol=1e-13, rtol=1e-12))
    return out.reshape(C.shape[:-2])


def _scaled_eigenvalues(C: np.ndarray, p: float) -> list[tuple[float, np.ndarray]]:
    """Per covariance ``(λ_max, the eigenvalues above 1e-12 λ_max over λ_max, descending)``; ``p`` checked."""
    if not (0 < p < 1):
        raise ValidationError("probability", p, "a number in (0, 1)")
    out = []
    for lam in np.linalg.eigvalsh(C.reshape(-1, C.shape[-1], C.shape[-1])):
        top = lam.max(initial=0.0)
        out.append((top, np.sort(lam[lam > 1e-12 * top] / top)[::-1] if top > 0 else lam[:0]))
    return out


#: relative margin of :func:`norm_within` below each limit: wider than the quantile's root tolerance (about
#: 5e-13 relative in ``q``), so that a design it accepts has every :func:`norm_quantile` below its limit too
WITHIN_MARGIN = 1e-11


def norm_within(cov, p: float, limits) -> bool:
    """Whether every quantile ``q_p`` of ``|n|``, ``n ~ N(0, C)``, is at most its limit, without solving for it:
    ``q_p ≤ L`` exactly when ``P(|n|² ≤ L²) ≥ p`` (the distribution function grows with ``x``), one evaluation of
    it per covariance instead of the root solve's dozen or so. The limits are taken :data:`WITHIN_MARGIN` lower,
    so an accepted design's :func:`norm_quantile` values are below them too.

    Parameters
    ----------
    cov, p
        As :func:`norm_quantile`.
    limits : float or (...) array_like
        The largest quantile allowed for each covariance (m or rad); a negative limit is missed.

    Returns
    -------
    bool
        True when every covariance's quantile is within its limit; the covariances after the first one
        that misses are not evaluated.

    Raises
    ------
    evotol.errors.ValidationError
        As :func:`norm_quantile`.
    """
    C = np.asarray(cov, float)
    L = np.broadcast_to(np.asarray(limits, float), C.shape[:-2]).ravel() * (1 - WITHIN_MARGIN)
    if np.any(L < 0):
        return False
    for (top, lam), lim in zip(_scaled_eigenvalues(C, p), L):
        if lam.size and _cdf(lim * lim / top, lam) < p:
            return False
    return True

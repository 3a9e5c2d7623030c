"""The probability that a 3-D normal error leaves a ball, and its k-sigma equivalent.

For x ~ N(μ, Σ) in 3-D (the first-order error of one component at one pose,
:mod:`evotol.measures.statistical.first_order`).

Probability of ``|x| ≤ E`` (a generalised chi-square CDF). Write x = μ + L z with L Lᵀ = Σ and
z ~ N(0, I₃) = ρ v, where ρ ~ χ₃ and v is uniform on the unit sphere, independent. Along the ray of
direction v, ``|μ + ρ L v| > E`` exactly when ρ > ρ₊(v), the positive root of
``|L v|² ρ² + 2 (μ·L v) ρ + |μ|² − E² = 0`` (one positive root whenever ``|μ| < E``). Hence

    P(``|x|`` > E) = (1/4π) ∫_{S²} S_χ₃(ρ₊(v)) dv,     S_χ₃(r) = erfc(r/√2) + √(2/π) r e^{−r²/2},

an integral of a smooth, *positive* function over the sphere: the miss probability has small
relative error even at ppm levels (no cancellation as in Imhof's formula). For μ = 0,
ρ₊ = E/√(vᵀΣv) and in Σ's eigenbasis vᵀΣv = Σ λ_i v_i², so only the eigenvalues are needed
(closed form for symmetric 3×3, Smith 1961) and the integrand is symmetric in every coordinate:
one octant, Gauss–Legendre in v_z × midpoint rule in the azimuth. With a mean, the full sphere
in the eigenbasis is used. Rank-deficient Σ (planar robots) needs no special case.

The miss probability q is then read as its two-sided normal equivalent k(q) = Φ⁻¹(1 − q/2)
(:func:`k_equivalent`; q = 0.0027 → k = 3), and a required yield is checked to be a probability
(:func:`required_probability`).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy import special

from evotol.errors import ValidationError

_SQRT_2_PI = np.sqrt(2.0 / np.pi)


def chi3_survival(r: np.ndarray) -> np.ndarray:
    """P(ρ > r) for ρ ~ χ₃ (the norm of a standard normal 3-vector); r ≥ 0, inf allowed.

    Parameters
    ----------
    r : array_like
        Radii (dimensionless, in standard deviations), r ≥ 0; values above 1e3 are clipped.

    Returns
    -------
    ndarray
        Survival probability S_χ₃(r), same shape as ``r``.
    """
    x2 = 0.5 * np.minimum(np.asarray(r, dtype=float), 1e3) ** 2
    return _chi3_sf_half_square(x2)


def _chi3_sf_half_square(x2: np.ndarray) -> np.ndarray:
    """S_χ₃(r) from x2 = r²/2 (overwrites x2): erfc(x) + (2/√π) x e^{−x²}, x = √x2."""
    x = np.sqrt(x2)
    v = special.erfc(x)
    np.negative(x2, out=x2)
    np.exp(x2, out=x2)
    x2 *= x
    x2 *= 2 / np.sqrt(np.pi)
    v += x2
    return v


def chi3_cdf(r: np.ndarray) -> np.ndarray:
    """P(ρ ≤ r) for ρ ~ χ₃: erf(r/√2) − √(2/π) r e^{−r²/2}.

    Parameters
    ----------
    r : array_like
        Radii (dimensionless, in standard deviations), r ≥ 0, inf allowed.

    Returns
    -------
    ndarray
        Cumulative probability, same shape as ``r`` (1 at r = inf).
    """
    r = np.asarray(r, dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):
        out = special.erf(r / np.sqrt(2.0)) - _SQRT_2_PI * r * np.exp(-0.5 * r * r)
    return np.where(np.isinf(r), 1.0, out)


@lru_cache(maxsize=8)
def octant_rule(n_z: int = 12, n_phi: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Squared direction components W (3, m) = (v_x², v_y², v_z²) and weights w (m,) summing to 1
    for the mean over the unit sphere of a function of (v_x², v_y², v_z²) (one octant)."""
    x, wx = np.polynomial.legendre.leggauss(n_z)
    z, wz = 0.5 * (x + 1), 0.5 * wx                     # Gauss-Legendre on v_z in [0, 1]
    phi = (np.arange(n_phi) + 0.5) * (0.5 * np.pi / n_phi)
    Z, P = np.meshgrid(z, phi, indexing="ij")
    s2 = 1 - Z ** 2
    W = np.stack([s2 * np.cos(P) ** 2, s2 * np.sin(P) ** 2, Z ** 2]).reshape(3, -1)
    w = np.repeat(wz, n_phi) / n_phi
    return W, w


@lru_cache(maxsize=8)
def sphere_rule(n_z: int = 32, n_phi: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Directions V (3, m) and weights (m,) summing to 1 for the mean over the whole unit sphere."""
    z, wz = np.polynomial.legendre.leggauss(n_z)
    phi = (np.arange(n_phi) + 0.5) * (2 * np.pi / n_phi)
    Z, P = np.meshgrid(z, phi, indexing="ij")
    s = np.sqrt(1 - Z ** 2)
    V = np.stack([s * np.cos(P), s * np.sin(P), Z]).reshape(3, -1)
    return V, np.repeat(0.5 * wz, n_phi) / n_phi


def sym3_eigenvalues(S6: np.ndarray) -> np.ndarray:
    """Eigenvalues (..., 3), descending, of symmetric 3×3 matrices given by their six entries
    (..., 6) = (xx, yy, zz, xy, xz, yz); closed form (Smith 1961, trigonometric), clipped at 0.

    Parameters
    ----------
    S6 : ndarray, shape (..., 6)
        Entries (xx, yy, zz, xy, xz, yz) of symmetric matrices (e.g. covariances in m² or rad²).

    Returns
    -------
    ndarray, shape (..., 3)
        Eigenvalues, descending, negative ones set to 0 (units of ``S6``).
    """
    a, b, c, d, e, f = np.moveaxis(S6, -1, 0)
    q = (a + b + c) / 3
    p1 = d * d + e * e + f * f
    p2 = (a - q) ** 2 + (b - q) ** 2 + (c - q) ** 2 + 2 * p1
    p = np.sqrt(p2 / 6)
    ps = np.where(p > 0, p, 1.0)
    A, B, C = (a - q) / ps, (b - q) / ps, (c - q) / ps
    D, E, F = d / ps, e / ps, f / ps
    r = 0.5 * (A * (B * C - F * F) - D * (D * C - F * E) + E * (D * F - B * E))
    phi = np.arccos(np.clip(r, -1, 1)) / 3
    l1 = q + 2 * p * np.cos(phi)
    l3 = q + 2 * p * np.cos(phi + 2 * np.pi / 3)
    l2 = 3 * q - l1 - l3
    return np.maximum(np.stack([l1, l2, l3], -1), 0.0)


def _full(S6: np.ndarray) -> np.ndarray:
    a, b, c, d, e, f = np.moveaxis(S6, -1, 0)
    return np.stack([np.stack([a, d, e], -1), np.stack([d, b, f], -1), np.stack([e, f, c], -1)], -2)


def miss_probability(cov6: np.ndarray, bound: float, mean: np.ndarray | None = None,
                     n_z: int = 8, n_phi: int = 8, chunk: int = 2048) -> np.ndarray:
    """P(``|x|`` > bound) for x ~ N(mean, Σ) in 3-D (see module docstring), vectorised.

    Parameters
    ----------
    cov6 : array_like, shape (..., 6)
        Covariance entries (xx, yy, zz, xy, xz, yz) (m² or rad²).
    bound : float
        The bound E (> 0; m or rad).
    mean : array_like, shape (..., 3), optional
        Mean of x (m or rad); None or all zero: the zero-mean octant rule.
    n_z : int
        Gauss–Legendre nodes in v_z of the zero-mean octant rule (the rule with a mean uses
        3× as many over the whole sphere).
    n_phi : int
        Azimuth nodes of the zero-mean octant rule (with a mean: 6× as many over 2π).
    chunk : int
        Covariances processed per block (memory; an eighth of it with a mean).

    Returns
    -------
    ndarray, shape (...)
        Miss probability ``P(|x| > E)`` (dimensionless).
    """
    cov6 = np.asarray(cov6, dtype=float)
    shape = cov6.shape[:-1]
    flat = cov6.reshape(-1, 6)
    out = np.empty(flat.shape[0])
    lam = sym3_eigenvalues(flat)
    E = float(bound)
    if mean is None:
        mu = None
    else:
        mu = np.broadcast_to(np.asarray(mean, dtype=float), shape + (3,)).reshape(-1, 3)
        if not np.any(mu):
            mu = None
    if mu is None:
        W, w = octant_rule(n_z, n_phi)
        for a in range(0, len(flat), chunk):
            s2 = lam[a:a + chunk] @ W                         # vᵀΣv in the eigenbasis
            np.maximum(s2, 1e-300, out=s2)
            x2 = np.divide(0.5 * E * E, s2)                   # (E/σ(v))² / 2
            np.minimum(x2, 1e6, out=x2)
            out[a:a + chunk] = _chi3_sf_half_square(x2) @ w
        return out.reshape(shape)
    shifted = np.any(mu != 0, axis=1)
    idx0 = np.flatnonzero(~shifted)
    if idx0.size:
        out[idx0] = miss_probability(flat[idx0], E, None, n_z, n_phi)
    idx = np.flatnonzero(shifted)
    lam_s, Q = np.linalg.eigh(_full(flat[idx]))
    lam_s = np.maximum(lam_s, 0.0)
    mu_e = np.einsum("nij,ni->nj", Q, mu[idx]) * np.sqrt(lam_s)      # Lᵀμ with L = Q √Λ
    V, wv = sphere_rule(3 * n_z, 6 * n_phi)
    m2 = np.sum(mu[idx] ** 2, axis=1)
    c = E * E - m2
    for a in range(0, idx.size, max(1, chunk // 8)):
        sl = slice(a, a + max(1, chunk // 8))
        A = lam_s[sl] @ (V * V)                                         # |L v|²
        B = mu_e[sl] @ V                                                # μ·L v
        cc = c[sl, None]
        disc = B * B + A * cc
        with np.errstate(divide="ignore", invalid="ignore"):
            root = np.sqrt(np.maximum(disc, 0.0))
            inside_start = cc > 0
            # |μ| < E: one positive root; stable form for each sign of B
            rp = np.where(B >= 0, cc / (B + root), (root - B) / np.where(A > 0, A, 1.0))
            rp = np.where((B < 0) & (A <= 0), np.inf, rp)
            miss_in = chi3_survival(rp) @ wv
            # |μ| >= E: the ray enters the ball only when B < 0 and disc > 0
            r_lo = np.where(A > 0, (-B - root) / np.where(A > 0, A, 1.0), np.inf)
            r_hi = np.where(A > 0, (-B + root) / np.where(A > 0, A, 1.0), np.inf)
            hit = (B < 0) & (disc > 0) & (A > 0)
            inside = np.where(hit, chi3_cdf(r_hi) - chi3_cdf(np.maximum(r_lo, 0.0)), 0.0) @ wv
        out[idx[sl]] = np.where(inside_start[:, 0], miss_in, 1.0 - inside)
    return out.reshape(shape)


def k_equivalent(q: np.ndarray) -> np.ndarray:
    """Two-sided normal equivalent k(q) = Φ⁻¹(1 − q/2) of a miss probability q (inf for q = 0).

    Parameters
    ----------
    q : array_like
        Miss probabilities (clipped to [0, 1]).

    Returns
    -------
    ndarray
        k(q) (dimensionless, number of standard deviations), same shape as ``q``.
    """
    q = np.clip(np.asarray(q, dtype=float), 0.0, 1.0)
    with np.errstate(divide="ignore"):
        return -special.ndtri(0.5 * q)


def required_probability(probability: float) -> float:
    """A required yield checked to be a probability in (0, 1).

    Parameters
    ----------
    probability : float
        The required yield p (dimensionless).

    Returns
    -------
    float
        ``probability`` as a float.

    Raises
    ------
    evotol.errors.ValidationError
        Not a number strictly between 0 and 1.
    """
    if not (isinstance(probability, (int, float, np.floating)) and 0 < probability < 1):
        raise ValidationError("requirement.probability", probability, "a probability in (0, 1)")
    return float(probability)

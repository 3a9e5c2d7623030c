"""Statistical tolerancing: the probability that the end-effector error stays inside its bound.

First-order model. At one pose the position (or orientation) error is x = Σ_j B_j e_j with source
errors e_j = t_j z_j (:mod:`evotol.distributions`). Its mean and covariance are

    μ = Σ_j B_j m_j t_j,        Σ = Σ_j t_j² v_j B_j B_jᵀ        (3×3),

with (m_j, v_j) the mean / per-component variance of z_j (:func:`evotol.distributions.unit_moments`).
With normal sources x ~ N(μ, Σ) exactly; with other sources x is replaced by the normal of the
same mean and covariance (central limit theorem; CETOL's and 3DCS's "RSS" analysis do the same) and
the result is flagged as approximate (:attr:`YieldResult.exact`).

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

Both components. P(``|δp|`` ≤ E and ``|δθ|`` ≤ Θ) is bounded from below by Bonferroni's inequality,
P(A ∩ B) ≥ 1 − P(Aᶜ) − P(Bᶜ): the requirement "yield ≥ p" is checked on this proven lower bound
(conservative by at most the probability that both components miss together).

Smooth violation. A miss probability q is turned into its two-sided normal equivalent
k(q) = Φ⁻¹(1 − q/2) (q = 0.0027 → k = 3). The requirement p gives k_req; the violation at a pose is
k_req / k(q) − 1, which for a one-dimensional normal error is exactly k_req·σ/E − 1, the "k-sigma
stack-up over bound" -- linear in the tolerances, like the worst-case measure. The matching
*equivalent error* E·k_req/k(q) (m or rad) is what :class:`evotol.problem.Evaluation` reports
per component: it equals E exactly when that component's yield equals p.
"""
from __future__ import annotations

from dataclasses import dataclass
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


@dataclass
class YieldResult:
    """First-order yield of designs at every pose (SI units).

    Parameters
    ----------
    miss : dict of str to ndarray, shape (n_designs, n_poses)
        Component -> ``P(|error| > bound)`` (dimensionless).
    probability : ndarray, shape (n_designs, n_poses)
        Lower bound of the joint yield ``1 − Σ miss`` (Bonferroni); for :class:`SampledYield`
        the joint yield counted directly.
    equivalent : dict of str to ndarray, shape (n_designs, n_poses)
        Component -> k-sigma equivalent error ``bound·k_req/k(miss)`` (m or rad); for
        :class:`SampledYield` the sampled quantile of the error norm.
    violation : ndarray, shape (n_designs,)
        Max over poses of ``k_req/k(Σ miss) − 1`` (dimensionless; <= 0 meets the requirement).
    contributions : dict of str to ndarray, shape (n_designs, n_poses, n_sources)
        Component -> each source's variance share (dimensionless fraction); empty for
        :class:`SampledYield`.
    exact : bool
        Every contributing source is normal (otherwise moment-matched normal, CLT).
    """

    miss: dict
    probability: np.ndarray
    equivalent: dict
    violation: np.ndarray
    contributions: dict
    exact: bool


class FirstOrderYield:
    """Cached moments of one problem's linear error model for the ``yield`` measure.

    With ``shift`` (asymmetric intervals, ``docs/tolerances.md``) the unit distribution is placed
    on [offset + (κ − ρ)t, offset + (κ + ρ)t], i.e. e = offset + t (κ + ρ z): mean
    offset + t (κ + ρ m), variance t² ρ² v.

    Parameters
    ----------
    blocks : dict of str to list of ndarray, each shape (n_poses, 3, dim_j)
        Component -> sensitivity blocks per source (m or rad per unit of source error).
    dists : sequence of evotol.distributions.Distribution
        Each source's distribution inside its tolerance.
    bounds : dict of str to float or None
        Component -> bound E (m or rad); None components are not constrained.
    radial : str
        Radial law of disk/ball sources (one of ``evotol.distributions.RADIAL``).
    shift : tuple of three array_like, shape (n_sources,), optional
        ``(rho, kappa, offset)`` of asymmetric intervals (dimensionless, dimensionless, SI);
        None: centred ±t.
    """

    _PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))

    def __init__(self, blocks: dict, dists, bounds: dict, radial: str = "uniform", shift=None):
        from evotol.distributions import unit_moments

        self.bounds = {c: float(E) for c, E in bounds.items() if E is not None}
        dims = [B.shape[2] for B in next(iter(blocks.values()))]
        mom = np.array([unit_moments(d, dim, radial) for d, dim in zip(dists, dims)])
        n = len(dims)
        rho, kappa, offset = (np.ones(n), np.zeros(n), np.zeros(n)) if shift is None else \
            (np.asarray(a, dtype=float) for a in shift)
        self.unit_mean = kappa + rho * mom[:, 0]
        self.unit_var = rho ** 2 * mom[:, 1]
        self.offsets = offset
        contributing = [j for j in range(len(dims)) if any(np.any(blocks[c][j]) for c in self.bounds)]
        self.exact = all(dists[j].is_normal for j in contributing)
        self.G, self.Bmean, self.frob = {}, {}, {}
        for c in self.bounds:
            G = np.stack([np.einsum("pik,pjk->pij", B, B) for B in blocks[c]], 1)   # (p, n_src, 3, 3)
            self.G[c] = np.stack([G[..., a, b] for a, b in self._PAIRS], -1)         # (p, n_src, 6)
            self.frob[c] = np.einsum("pjk->pj", self.G[c][..., :3])
            # mean direction of interval sources (B_j is a single column there)
            self.Bmean[c] = np.stack([B[:, :, 0] if B.shape[2] == 1 else np.zeros(B.shape[:2]) for B in blocks[c]], 1)

    def moments(self, comp: str, T: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """(cov6 (n, p, 6), mean (n, p, 3) or None) of the component for designs T (n, n_src).

        Parameters
        ----------
        comp : str
            A constrained component, ``"position"`` or ``"orientation"``.
        T : ndarray, shape (n, n_src)
            Designs (SI: m or rad).

        Returns
        -------
        cov6 : ndarray, shape (n, n_poses, 6)
            Covariance entries (xx, yy, zz, xy, xz, yz) of the error (m² or rad²).
        mean : ndarray, shape (n, n_poses, 3), or None
            Mean error (m or rad); None when every source is centred.
        """
        S = np.einsum("pjk,nj->npk", self.G[comp], T * T * self.unit_var)
        m = T * self.unit_mean + self.offsets
        mean = np.einsum("pji,nj->npi", self.Bmean[comp], m) if np.any(m) else None
        return S, mean

    def evaluate(self, T: np.ndarray, probability: float) -> YieldResult:
        """Miss probabilities, Bonferroni yield bound, equivalent errors and violation (module
        docstring) of designs at every pose.

        Parameters
        ----------
        T : array_like, shape (n_designs, n_sources) or (n_sources,)
            Designs (SI: m or rad).
        probability : float
            Required yield p, in (0, 1).

        Returns
        -------
        YieldResult
            Per design and pose; ``exact`` as computed from the distributions.

        Raises
        ------
        evotol.errors.ValidationError
            ``probability`` not in (0, 1).
        """
        T = np.atleast_2d(np.asarray(T, dtype=float))
        k_req = float(k_equivalent(1.0 - required_probability(probability)))
        miss, eq, contrib = {}, {}, {}
        for c, E in self.bounds.items():
            S, mean = self.moments(c, T)
            miss[c] = miss_probability(S, E, mean)
            with np.errstate(divide="ignore"):
                eq[c] = E * k_req / k_equivalent(miss[c])
            share = self.frob[c][None] * (T * T * self.unit_var)[:, None, :]
            tot = share.sum(-1, keepdims=True)
            contrib[c] = share / np.where(tot > 0, tot, 1.0)
        q = np.minimum(sum(miss.values()), 1.0)
        with np.errstate(divide="ignore"):
            viol = np.max(k_req / np.maximum(k_equivalent(q), 1e-3), axis=1) - 1   # finite for q -> 1
        return YieldResult(miss, 1.0 - q, eq, viol, contrib, self.exact)


def pose_error_nan(robot, poses: np.ndarray, errors: np.ndarray) -> np.ndarray:
    """robot.pose_error with samples that cannot be assembled as NaN (they count as misses):
    robots whose ``pose_error`` accepts ``failures="nan"`` report them per sample.

    Parameters
    ----------
    robot : robots.base.RobotErrorModel
        A robot with a nonlinear ``pose_error``.
    poses : ndarray, shape (n_poses, workspace.dim)
        Workspace poses (SI: m, rad).
    errors : ndarray, shape (n_poses, n_samples, n_columns)
        Stacked source errors per pose and sample (SI: m or rad).

    Returns
    -------
    ndarray, shape (n_poses, n_samples, 6)
        End-effector error twists (position m, orientation rad); NaN where a robot accepting
        ``failures="nan"`` reports a sample that cannot be assembled.
    """
    import inspect

    if "failures" in inspect.signature(robot.pose_error).parameters:
        return robot.pose_error(poses, errors, failures="nan")
    return robot.pose_error(poses, errors)


class SampledYield:
    """Yield of the *nonlinear* model (``robot.pose_error``) estimated with common random numbers.

    One set of ``n_samples`` unit-tolerance samples (Latin hypercube by default, ``seed``) is drawn
    once and rescaled by every design's tolerances, so the estimate is a deterministic function of
    the design and a GA compares designs without sampling noise. A sample misses when the position
    or the orientation error exceeds its bound, or when the mechanism cannot be assembled (NaN):
    the joint yield is counted directly (no Bonferroni bound). Per component, the reported error is
    the sampled ``probability``-quantile of ``|error|`` (m or rad). The violation is
    k_req/k(miss) − 1 as for the first-order measure (piecewise constant in the design).
    Sources with a process mean shift or asymmetric interval are sampled as their distributions say.

    Parameters
    ----------
    robot : robots.base.RobotErrorModel
        A robot with a nonlinear ``pose_error``.
    poses : array_like, shape (n_poses, workspace.dim)
        Workspace poses (SI: m, rad).
    dists : sequence of evotol.distributions.Distribution
        Each source's distribution inside its tolerance.
    bounds : dict of str to float or None
        Component -> bound E (m or rad); None components are not constrained.
    n_samples : int
        Common samples per design and pose.
    seed : int or None
        Seed of the common samples.
    method : str
        ``"lhs"`` (Latin hypercube) or ``"mc"``.
    radial : str
        Radial law of disk/ball sources (one of ``evotol.distributions.RADIAL``).
    shift : tuple of three array_like, shape (n_sources,), optional
        ``(rho, kappa, offset)`` of asymmetric intervals (dimensionless, dimensionless, SI);
        None: centred ±t.
    max_rows : int
        Largest number of (design, pose, sample) rows passed to ``pose_error`` at once (memory).

    Raises
    ------
    evotol.errors.ValidationError
        The robot has no nonlinear model.
    """

    def __init__(self, robot, poses: np.ndarray, dists, bounds: dict, n_samples: int = 1024, seed=0,
                 method: str = "lhs", radial: str = "uniform", shift=None, max_rows: int = 2_000_000):
        from evotol.distributions import unit_samples

        if not robot.has_nonlinear_model:
            raise ValidationError("requirement.model", "nonlinear", f"a robot with pose_error ({robot.name} has none)")
        self.robot, self.poses = robot, np.asarray(poses, dtype=float)
        self.bounds = {c: float(E) for c, E in bounds.items() if E is not None}
        self.dims = [s.dim for s in robot.sources]
        Z = unit_samples(self.dims, dists, int(n_samples), method, seed, radial)
        self.unit = np.concatenate(Z, axis=1)                     # (n_samples, n_columns)
        self.owner = np.repeat(np.arange(len(self.dims)), self.dims)
        # per-column affine map e = offset + t (kappa + rho z) (asymmetric intervals; 0/1 if none)
        rho, kappa, offset = (np.ones(len(self.dims)), np.zeros(len(self.dims)), np.zeros(len(self.dims))) \
            if shift is None else shift
        self.rho, self.kappa, self.offset = (np.asarray(a, dtype=float)[self.owner] for a in (rho, kappa, offset))
        self.n_samples = int(n_samples)
        self.max_rows = int(max_rows)

    def errors(self, t: np.ndarray) -> np.ndarray:
        """Stacked source errors (n_samples, n_columns) of one design t (n_sources,).

        Parameters
        ----------
        t : array_like, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        ndarray, shape (n_samples, n_columns)
            ``offset + t (κ + ρ z)`` per sample and error column (SI: m or rad).
        """
        tc = np.asarray(t, dtype=float)[self.owner]
        return self.offset + tc * (self.kappa + self.rho * self.unit)

    def norms(self, T: np.ndarray) -> dict:
        """component -> ``|error|`` (n_designs, n_poses, n_samples), NaN where not assembled.

        Parameters
        ----------
        T : array_like, shape (n_designs, n_sources) or (n_sources,)
            Designs (SI: m or rad).

        Returns
        -------
        dict of str to ndarray, shape (n_designs, n_poses, n_samples)
            Constrained component -> error norm of the nonlinear model (m or rad).
        """
        T = np.atleast_2d(np.asarray(T, dtype=float))
        P, S = len(self.poses), self.n_samples
        out = {c: np.empty((len(T), P, S)) for c in self.bounds}
        rows = {"position": slice(0, 3), "orientation": slice(3, 6)}
        step = max(1, self.max_rows // (P * S))
        for a in range(0, len(T), step):
            E = np.concatenate([self.errors(t) for t in T[a:a + step]], axis=0)    # (m·S, cols)
            err = pose_error_nan(self.robot, self.poses, np.broadcast_to(E, (P,) + E.shape))
            m = len(T[a:a + step])
            for c in self.bounds:
                nrm = np.linalg.norm(err[:, :, rows[c]], axis=2).reshape(P, m, S)
                out[c][a:a + m] = np.moveaxis(nrm, 1, 0)
        return out

    def evaluate(self, T: np.ndarray, probability: float) -> YieldResult:
        """Sampled miss rates, joint yield, error quantiles and violation of designs at every pose.

        Parameters
        ----------
        T : array_like, shape (n_designs, n_sources) or (n_sources,)
            Designs (SI: m or rad).
        probability : float
            Required yield p, in (0, 1).

        Returns
        -------
        YieldResult
            Per design and pose; ``exact`` False, no ``contributions``.

        Raises
        ------
        evotol.errors.ValidationError
            ``probability`` not in (0, 1).
        """
        k_req = float(k_equivalent(1.0 - required_probability(probability)))
        nrm = self.norms(T)
        miss, eq = {}, {}
        joint = None
        for c, E in self.bounds.items():
            out = ~(nrm[c] <= E)                                   # NaN (not assembled) is a miss
            miss[c] = out.mean(axis=2)
            joint = out if joint is None else joint | out
            eq[c] = np.quantile(np.where(np.isnan(nrm[c]), np.inf, nrm[c]), probability, axis=2, method="inverted_cdf")
        q = joint.mean(axis=2)
        viol = np.max(k_req / np.maximum(k_equivalent(q), 1e-3), axis=1) - 1
        return YieldResult(miss, 1.0 - q, eq, viol, {}, False)

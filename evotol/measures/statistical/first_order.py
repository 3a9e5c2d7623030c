"""The first-order yield model of the ``yield`` measure (``docs/statistical.md``).

First-order model. At one pose the position (or orientation) error is x = Σ_j B_j e_j with source
errors e_j = t_j z_j (:mod:`evotol.measures.statistical.distributions`). Its mean and covariance are

    μ = Σ_j B_j m_j t_j,        Σ = Σ_j t_j² v_j B_j B_jᵀ        (3×3),

with (m_j, v_j) the mean / per-component variance of z_j (:func:`evotol.measures.statistical.distributions.unit_moments`).
With normal sources x ~ N(μ, Σ) exactly; with other sources x is replaced by the normal of the
same mean and covariance (central limit theorem; CETOL's and 3DCS's "RSS" analysis do the same) and
the result is flagged as approximate (:attr:`YieldResult.exact`).

The probability of ``|x| ≤ E`` is :func:`evotol.measures.statistical.normal_miss.miss_probability`.

Both components. P(``|δp|`` ≤ E and ``|δθ|`` ≤ Θ) is bounded from below by Bonferroni's inequality,
P(A ∩ B) ≥ 1 − P(Aᶜ) − P(Bᶜ): the requirement "yield ≥ p" is checked on this proven lower bound
(conservative by at most the probability that both components miss together).

Smooth violation. A miss probability q is turned into its two-sided normal equivalent
k(q) = Φ⁻¹(1 − q/2) (q = 0.0027 → k = 3). The requirement p gives k_req; the violation at a pose is
k_req / k(q) − 1, which for a one-dimensional normal error is exactly k_req·σ/E − 1, the "k-sigma
stack-up over bound" -- linear in the tolerances, like the worst-case measure. The matching
*equivalent error* E·k_req/k(q) (m or rad) is what :class:`evotol.core.problem.Evaluation` reports
per component: it equals E exactly when that component's yield equals p.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.measures.statistical.normal_miss import k_equivalent, miss_probability, required_probability


@dataclass
class YieldResult:
    """First-order yield of designs at every pose (SI units).

    Parameters
    ----------
    miss : dict of str to ndarray, shape (n_designs, n_poses)
        Component -> ``P(|error| > bound)`` (dimensionless).
    probability : ndarray, shape (n_designs, n_poses)
        Lower bound of the joint yield ``1 − Σ miss`` (Bonferroni); for :class:`~evotol.measures.statistical.sampled.SampledYield`
        the joint yield counted directly.
    equivalent : dict of str to ndarray, shape (n_designs, n_poses)
        Component -> k-sigma equivalent error ``bound·k_req/k(miss)`` (m or rad); for
        :class:`~evotol.measures.statistical.sampled.SampledYield` the sampled quantile of the error norm.
    violation : ndarray, shape (n_designs,)
        Max over poses of ``k_req/k(Σ miss) − 1`` (dimensionless; <= 0 meets the requirement).
    contributions : dict of str to ndarray, shape (n_designs, n_poses, n_sources)
        Component -> each source's variance share (dimensionless fraction); empty for
        :class:`~evotol.measures.statistical.sampled.SampledYield`.
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
    noise : dict of str to ndarray, shape (n_poses, 6), optional
        Component -> covariance (xx, yy, zz, xy, xz, yz; m² or rad²) of a normal error
        independent of the sources, added at every pose (a calibrated robot's instrument noise,
        :meth:`evotol.calibration.model.CalibratedRobot.noise_cov6`); None: none.
    """

    _PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))

    def __init__(self, blocks: dict, dists, bounds: dict, radial: str = "uniform", shift=None, noise=None):
        from evotol.measures.statistical.distributions import unit_moments

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
        self.noise = {c: np.asarray(v, float) for c, v in (noise or {}).items()}
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
        if comp in self.noise:
            S = S + self.noise[comp][None]
        m = T * self.unit_mean + self.offsets
        mean = np.einsum("pji,nj->npi", self.Bmean[comp], m) if np.any(m) else None
        return S, mean

    def evaluate(self, T: np.ndarray, probability: float) -> YieldResult:
        """Miss probabilities, Bonferroni yield bound, equivalent errors and violation (module
        docstring) of designs at every pose.

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

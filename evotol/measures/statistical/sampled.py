"""The sampled yield of the *nonlinear* model (``Requirement(model="nonlinear")``,
``docs/statistical.md``): :class:`SampledYield` counts misses of ``robot.pose_error`` on common
random samples, and :func:`pose_error_nan` lets a sample that cannot be assembled count as a miss
(also for :mod:`evotol.verification.montecarlo` and :mod:`evotol.verification.nonlinear`).

The parameters several definitions of this module share are described once, here.

Parameters
----------
robot : evotol.robots.base.RobotErrorModel
    A robot with a nonlinear ``pose_error``.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import ValidationError
from evotol.measures.statistical.first_order import YieldResult
from evotol.measures.statistical.normal_miss import k_equivalent, required_probability


def pose_error_nan(robot, poses: np.ndarray, errors: np.ndarray) -> np.ndarray:
    """robot.pose_error with samples that cannot be assembled as NaN (they count as misses):
    robots whose ``pose_error`` accepts ``failures="nan"`` report them per sample.

    Parameters
    ----------
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
    poses : array_like, shape (n_poses, workspace.dim)
        Workspace poses (SI: m, rad).
    n_samples : int
        Common samples per design and pose.
    seed : int or None
        Seed of the common samples.
    method : str
        ``"lhs"`` (Latin hypercube) or ``"mc"``.
    max_rows : int
        Largest number of (design, pose, sample) rows passed to ``pose_error`` at once (memory).

    Raises
    ------
    evotol.errors.ValidationError
        The robot has no nonlinear model.
    """

    def __init__(self, robot, poses: np.ndarray, dists, bounds: dict, n_samples: int = 1024, seed=0,
                 method: str = "lhs", radial: str = "uniform", shift=None, max_rows: int = 2_000_000):
        from evotol.measures.statistical.distributions import unit_samples

        if not robot.has_nonlinear_model:
            raise ValidationError("requirement.model", "nonlinear", f"a robot with pose_error ({robot.without_nonlinear_model()})")
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

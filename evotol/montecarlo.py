"""Monte Carlo verification of an allocation: sample the source errors inside their tolerances at
every pose, propagate them (first-order map and, where the robot has one, the nonlinear model),
and report the rate at which the end-effector error exceeds the requirement (Yao 2013 Sec. 5).

Sampling (per source, ``Tolerance.distribution``; conventions in :mod:`evotol.distributions`):
unit-tolerance errors drawn by inverse CDF from Latin-hypercube or plain uniforms, then scaled
by t_j -- uniform, normal (t = k·σ), truncated normal, contact (clearances), process mean shift;
disk/ball radius r ~ U(0, t) (``radial="uniform"``, Yao 2013 eq. 12) or uniform over the
disk/ball (``radial="area"``).
Latin hypercube (scipy.stats.qmc.LatinHypercube) or plain Monte Carlo, independent per pose,
reproducible from ``seed``. Vectorised over all poses × samples; poses are processed in chunks.

Plain sampling cannot *verify* a worst-case requirement: the worst case needs every clearance at
its bound in one particular direction at once, which sampling reaches with vanishing probability.
``max_error_over_worst_case`` shows how far sampling falls short.
"""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field

import numpy as np

from evotol import distributions
from evotol.distributions import METHODS
from evotol.errors import ValidationError
from evotol.problem import ToleranceProblem
from evotol.threads import single_threaded_blas

RADIAL = distributions.RADIAL


@dataclass
class MonteCarloResult:
    """Per-pose statistics of sampled end-effector errors (SI units)."""

    method: str
    n_samples: int
    seed: int
    exceed_rate: dict[str, np.ndarray]            # component -> (n_poses,) linear model
    max_error: dict[str, np.ndarray]              # component -> (n_poses,) largest sampled |error|
    quantile_95: dict[str, np.ndarray]
    nonlinear_exceed_rate: dict[str, np.ndarray] = field(default_factory=dict)
    linearisation_error: float | None = None      # max |nonlinear − linear| / max |linear|
    max_error_over_worst_case: dict[str, float] = field(default_factory=dict)
    seconds: float = 0.0

    def max_exceed_rate(self, nonlinear: bool = False) -> float:
        rates = self.nonlinear_exceed_rate if nonlinear and self.nonlinear_exceed_rate else self.exceed_rate
        return float(max(np.max(v) for v in rates.values()))

    def to_dict(self) -> dict:
        d = {"method": self.method, "n_samples": self.n_samples, "seed": self.seed, "seconds": self.seconds,
             "max_exceed_rate": self.max_exceed_rate(), "linearisation_error": self.linearisation_error,
             "max_error_over_worst_case": self.max_error_over_worst_case}
        if self.nonlinear_exceed_rate:
            d["max_exceed_rate_nonlinear"] = self.max_exceed_rate(True)
        return d


@single_threaded_blas
def verify(problem: ToleranceProblem, tolerances, n_samples: int = 1000, method: str = "lhs", seed: int = 0,
           nonlinear: bool = True, radial: str = "uniform", chunk_poses: int = 64,
           progress: bool | None = None) -> MonteCarloResult:
    """Monte Carlo verification of ``tolerances`` (mapping or array, SI) at every problem pose."""
    t0 = time.perf_counter()
    if method not in METHODS:
        raise ValidationError("method", method, f"one of {METHODS}")
    if radial not in RADIAL:
        raise ValidationError("radial", radial, f"one of {RADIAL}")
    if not isinstance(n_samples, (int, np.integer)) or n_samples < 1:
        raise ValidationError("n_samples", n_samples, "a positive integer")
    t = problem.as_array(tolerances)
    robot = problem.robot
    dims = [s.dim for s in robot.sources]
    dists = problem.distributions
    comps = problem.components
    seeds = [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(problem.n_poses)]
    P = problem.n_poses
    exceed = {c: np.zeros(P) for c, _ in comps}
    exceed_nl = {c: np.zeros(P) for c, _ in comps} if (nonlinear and robot.has_nonlinear_model) else {}
    maxerr = {c: np.zeros(P) for c, _ in comps}
    q95 = {c: np.zeros(P) for c, _ in comps}
    lin_err, lin_scale = 0.0, 0.0
    rows = {"position": slice(0, 3), "orientation": slice(3, 6)}
    from tqdm.auto import tqdm
    bar = tqdm(total=P, desc="Monte Carlo", unit="pose", leave=False,
               disable=(not sys.stderr.isatty()) if progress is None else not progress)
    for start in range(0, P, chunk_poses):
        idx = np.arange(start, min(start + chunk_poses, P))
        E = np.empty((idx.size, n_samples, robot.n_columns))
        for a, p in enumerate(idx):
            Z = distributions.draw(distributions.uniforms(n_samples, sum(dims), method, seeds[p]), dims, dists, radial)
            E[a] = np.concatenate(problem.source_errors(Z, t), axis=1)   # inside shifted intervals too
        lin = np.einsum("pij,psj->psi", problem.jacobian[idx], E)
        for c, lim in comps:
            nrm = np.linalg.norm(lin[:, :, rows[c]], axis=2)
            exceed[c][idx] = np.mean(nrm > lim, axis=1)
            maxerr[c][idx] = nrm.max(axis=1)
            q95[c][idx] = np.quantile(nrm, 0.95, axis=1)
        if exceed_nl:
            nl = robot.pose_error(problem.poses[idx], E)
            lin_err = max(lin_err, float(np.max(np.abs(nl - lin))))
            lin_scale = max(lin_scale, float(np.max(np.abs(lin))))
            for c, lim in comps:
                exceed_nl[c][idx] = np.mean(np.linalg.norm(nl[:, :, rows[c]], axis=2) > lim, axis=1)
        bar.update(idx.size)
    bar.close()
    res = MonteCarloResult(method, int(n_samples), seed, exceed, maxerr, q95, exceed_nl,
                           (lin_err / lin_scale) if exceed_nl and lin_scale > 0 else None)
    ev = problem.evaluate(t[None], "worst_case")
    for c, _ in comps:
        res.max_error_over_worst_case[c] = float(np.max(maxerr[c] / np.maximum(getattr(ev, c)[0], 1e-300)))
    res.seconds = time.perf_counter() - t0
    return res

"""Verification of an allocation through the robot's **nonlinear** error model (``robot.pose_error``).

Two checks, for any robot that has ``pose_error`` and any tolerance specification (asymmetric,
shared, fixed sources included):

* **worst vertex**: at each pose, the source errors that attain the linear worst case
  (:func:`evotol.measures.linear.worst_case_errors`: e_j = c_j + ρ_j t_j B_jᵀu*/‖B_jᵀu*‖, the interval end
  on the side of the worst direction u*) are pushed through the nonlinear model; the ratio to the
  linear worst case measures how far the first-order model is from the real robot where it matters;
* **Monte Carlo**: errors sampled uniformly in every interval (Latin hypercube,
  ``scipy.stats.qmc``; the same samples at every pose) through the nonlinear model; reports the
  largest error, the 99.9 % quantile and the rate of exceeding the requirement. A sample the
  mechanism cannot assemble (NaN, :func:`evotol.measures.statistical.pose_error_nan`) is a miss, as in
  :func:`evotol.verification.montecarlo.verify`: it counts as an infinite error.

Plain sampling cannot verify a worst-case requirement (all sources at the right end at once is
rare); the worst-vertex check is the nonlinear counterpart of the worst case.

The parameters several definitions of this module share are described once, here.

Parameters
----------
t : mapping or array_like, shape (n_sources,)
    The design (SI: m or rad).
problem : ToleranceProblem
    A problem whose robot has a nonlinear ``pose_error``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import qmc

from evotol.measures.statistical import distributions

from evotol.measures import linear as measures
from evotol.errors import ValidationError, is_integer
from evotol.core.problem import ToleranceProblem
from evotol.measures.statistical import pose_error_nan
from evotol._runtime.blas_threads import single_threaded_blas
from evotol._runtime.random_state import seed_from

ROWS = {"position": slice(0, 3), "orientation": slice(3, 6)}


def _norms(x: np.ndarray, rows: slice) -> np.ndarray:
    """``np.linalg.norm(x[..., rows], axis=-1)`` for three rows, the squares summed in NumPy's order
    (so equal to it bit for bit), without the strided copy ``norm`` makes (4x faster on 1 000 poses x
    300 samples)."""
    a, b, c = (x[..., rows.start + k] for k in range(3))
    return np.sqrt(a * a + b * b + c * c)


def _check(problem: ToleranceProblem, seed=0) -> None:
    if not problem.error_model.has_nonlinear_model:
        raise ValidationError("model", "nonlinear",
                              f"a robot with pose_error ({problem.error_model.without_nonlinear_model()})")
    if not is_integer(seed, 0):
        raise ValidationError("seed", seed, "a non-negative integer")


def worst_vertex_errors(problem: ToleranceProblem, t) -> dict[str, np.ndarray]:
    """Nonlinear ``|error|`` per pose at each pose's linear worst-case error vector, per constrained
    component (SI, (n_poses,)). The vertex is the one that attains the linear worst case of that
    component.

    Returns
    -------
    dict of str to ndarray, shape (n_poses,)
        Constrained component -> nonlinear error norm at the worst vertex (m for position, rad
        for orientation).

    Raises
    ------
    evotol.errors.ValidationError
        The robot has no nonlinear model, or a bad design.
    """
    _check(problem)
    return _vertices_and_linear(problem, problem.as_array(t))[0]


def _vertices_and_linear(problem: ToleranceProblem, t: np.ndarray) -> tuple[dict, dict]:
    """(nonlinear error at each pose's worst vertex, linear worst case) per constrained component, from
    one linear worst case per component (the vertex is its maximiser; the value is the ``worst_case``
    measure's, computed by the same call)."""
    vertex, linear = {}, {}
    shape = None if problem.shape.plain else problem.shape
    for comp, _ in problem.components:
        wc = measures.worst_case_by_blocks(problem.blocks[comp], t, problem.coefficient_blocks(comp), shape=shape)
        errs = measures.worst_case_errors(problem.blocks[comp], t, wc.direction, shape)
        E = np.concatenate(errs, axis=1)                                   # (p, n_columns)
        nl = problem.error_model.pose_error(problem.poses, E[:, None, :])[:, 0]
        vertex[comp], linear[comp] = _norms(nl, ROWS[comp]), wc.value
    return vertex, linear


def uniform_interval_samples(problem: ToleranceProblem, t, n_samples: int, seed: int = 0) -> np.ndarray:
    """(n_samples, n_columns) errors uniform in every interval [offset − minus·t, offset + plus·t]
    (Latin hypercube, one column per interval source; disks/balls: uniform direction, radius
    uniform in [0, t] as :mod:`evotol.verification.montecarlo`).

    Parameters
    ----------
    problem : ToleranceProblem
        The problem (sources, interval shapes).
    n_samples : int
        Number of samples.
    seed : int
        Seed of the Latin hypercube.

    Returns
    -------
    ndarray, shape (n_samples, n_columns)
        Stacked source errors (SI: m or rad), the same for every pose.

    Raises
    ------
    evotol.errors.ValidationError
        A bad design.
    """
    t = problem.as_array(t)
    dims = [s.dim for s in problem.error_model.sources]
    U = qmc.LatinHypercube(d=sum(dims), seed=seed).random(int(n_samples))
    if all(d == 1 for d in dims):
        iv = problem.intervals(t)
        return iv[:, 0] + U * (iv[:, 1] - iv[:, 0])
    Z = distributions.draw(U, dims, ["uniform"] * len(dims), "uniform")
    return np.concatenate(problem.source_errors(Z, t), axis=1)


@dataclass
class NonlinearCheck:
    """Nonlinear verification of one design (SI units; ``*_over_requirement``: error / bound).

    Component dictionaries are keyed by the constrained components, ``"position"`` (m) and/or
    ``"orientation"`` (rad).

    Parameters
    ----------
    worst_vertex : dict of str to ndarray, shape (n_poses,)
        Nonlinear error norm at each pose's linear worst-case vertex.
    linear_worst_case : dict of str to ndarray, shape (n_poses,)
        The linear (first-order) worst case.
    mc_max : dict of str to float
        Largest nonlinear error norm over every Monte Carlo sample and pose; ``inf`` when some
        sample cannot be assembled (a miss counts as an infinite error).
    mc_q999 : dict of str to float
        99.9 % quantile of the nonlinear error norm over every sample and pose, misses counted as
        infinite errors (``inf`` when the quantile reaches them).
    mc_exceed_rate : dict of str to float
        Fraction of (pose, sample) pairs whose error exceeds the requirement or that cannot be
        assembled (dimensionless).
    n_samples : int
        Monte Carlo samples (shared by every pose).
    n_poses : int
        Number of poses checked.
    seed : int
        Seed of the samples.
    seconds : float
        Wall-clock time (s).
    requirement : dict of str to float
        Component -> bound (m or rad).
    """

    worst_vertex: dict[str, np.ndarray]        # component -> (n_poses,) nonlinear error at the worst vertex
    linear_worst_case: dict[str, np.ndarray]   # component -> (n_poses,) linear worst case
    mc_max: dict[str, float]
    mc_q999: dict[str, float]
    mc_exceed_rate: dict[str, float]
    n_samples: int
    n_poses: int
    seed: int
    seconds: float = 0.0
    requirement: dict[str, float] = field(default_factory=dict)

    @property
    def meets_requirement(self) -> bool:
        """The nonlinear robot holds the requirement at every worst vertex."""
        return all(np.max(v) <= self.requirement[c] * (1 + 1e-9) for c, v in self.worst_vertex.items())

    def to_dict(self) -> dict:
        """The check as plain data (for JSON/YAML reports).

        Returns
        -------
        dict
            ``model``, ``n_samples``, ``n_poses``, ``seed``, ``seconds``,
            ``meets_requirement_nonlinear``, ``max_exceed_rate``,
            ``max_worst_vertex_over_requirement`` and per component ``<c>_worst_vertex_max``,
            ``<c>_linear_worst_case_max``, ``<c>_mc_max``, ``<c>_mc_q999``,
            ``<c>_mc_exceed_rate`` (SI).
        """
        d = {"model": "nonlinear", "n_samples": self.n_samples, "n_poses": self.n_poses, "seed": self.seed,
             "seconds": self.seconds, "meets_requirement_nonlinear": self.meets_requirement,
             "max_exceed_rate": max(self.mc_exceed_rate.values()),
             "max_worst_vertex_over_requirement": max(float(np.max(v)) / self.requirement[c]
                                                      for c, v in self.worst_vertex.items())}
        for c in self.worst_vertex:
            d[f"{c}_worst_vertex_max"] = float(np.max(self.worst_vertex[c]))
            d[f"{c}_linear_worst_case_max"] = float(np.max(self.linear_worst_case[c]))
            d[f"{c}_mc_max"] = self.mc_max[c]
            d[f"{c}_mc_q999"] = self.mc_q999[c]
            d[f"{c}_mc_exceed_rate"] = self.mc_exceed_rate[c]
        return d


def _quantile_misses(e: np.ndarray, q: float) -> float:
    """``np.quantile(e, q)`` (linear interpolation) where ``+inf`` entries (misses) count as larger
    than any error: ``inf`` as soon as the interpolation puts weight on a miss."""
    miss = np.isinf(e)
    if not miss.any():
        return float(np.quantile(e, q))
    if np.quantile(miss.astype(float), q) > 0:      # same order statistics as e: a miss takes part
        return np.inf
    return float(np.quantile(np.where(miss, np.max(e[~miss]), e), q))   # the misses' order unchanged


@single_threaded_blas
def verify_nonlinear(problem: ToleranceProblem, t, n_samples: int = 1000, seed: int = 0,
                     chunk_poses: int = 64, rng: int | np.random.Generator | None = None) -> NonlinearCheck:
    """Worst-vertex check and Monte Carlo through ``robot.pose_error`` (module docstring).

    Parameters
    ----------
    n_samples : int
        Monte Carlo samples (>= 1), the same set at every pose.
    seed : int
        Seed of the samples (non-negative).
    chunk_poses : int
        Poses passed to ``pose_error`` at once (memory; default 64). The result does not depend on
        it. Larger chunks help a compiled serial arm (1 000 UR5 poses x 300 samples: 0.106 s in
        chunks of 64, 0.078 s in chunks of 218) but not the general description path, whose
        ``pose_error`` holds 4-7 kB a pose-sample (a planar 3-RRR, 576 poses x 300 samples: +85 MB
        and 5.6 s in chunks of 64, +450 MB and 6.9 s in chunks of 218).
    rng : int, numpy.random.Generator or None, optional
        As SciPy's ``rng``: an integer seed, or a Generator drawn from once for the seed of the run;
        replaces ``seed`` (which keeps working).

    Returns
    -------
    NonlinearCheck
        Worst-vertex errors, linear worst case and Monte Carlo statistics (a sample that cannot
        be assembled is a miss: an infinite error in ``mc_max`` and ``mc_q999``).

    Raises
    ------
    evotol.errors.ValidationError
        A robot without a nonlinear model, a bad ``seed``, ``n_samples`` or ``chunk_poses``, or a
        bad design.
    """
    t0 = time.perf_counter()
    seed = seed_from(rng, seed)
    _check(problem, seed)
    if not is_integer(n_samples, 1):
        raise ValidationError("n_samples", n_samples, "a positive integer")
    if not is_integer(chunk_poses, 1):
        raise ValidationError("chunk_poses", chunk_poses, "a positive integer")
    t = problem.as_array(t)
    vertex, lin = _vertices_and_linear(problem, t)
    E = uniform_interval_samples(problem, t, n_samples, seed)
    mx = {c: 0.0 for c, _ in problem.components}
    exceed = {c: 0 for c, _ in problem.components}
    errs = {c: [] for c, _ in problem.components}
    for start in range(0, problem.n_poses, chunk_poses):
        P = problem.poses[start:start + chunk_poses]
        nl = pose_error_nan(problem.error_model, P, np.broadcast_to(E, (len(P),) + E.shape))
        for c, lim in problem.components:
            e = _norms(nl, ROWS[c])
            e[np.isnan(e)] = np.inf                     # not assembled: a miss, larger than any bound
            mx[c] = max(mx[c], float(e.max()))
            exceed[c] += int(np.sum(e > lim))
            errs[c].append(e.ravel())
    total = problem.n_poses * int(n_samples)
    res = NonlinearCheck(vertex, lin, mx, {c: _quantile_misses(np.concatenate(v), 0.999) for c, v in errs.items()},
                         {c: exceed[c] / total for c in exceed}, int(n_samples), problem.n_poses, int(seed),
                         requirement=dict(problem.components))
    res.seconds = time.perf_counter() - t0
    return res

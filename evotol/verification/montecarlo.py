"""Monte Carlo verification of an allocation: sample the source errors inside their tolerances at
every pose, propagate them (first-order map and, where the robot has one, the nonlinear model),
and report the rate at which the end-effector error exceeds the requirement (Yao 2013 Sec. 5).

Sampling (per source, ``Tolerance.distribution``; conventions in :mod:`evotol.measures.statistical.distributions`):
unit-tolerance errors drawn by inverse CDF from Latin-hypercube or plain uniforms, then scaled
by t_j -- uniform, normal (t = k·σ), truncated normal, contact (clearances), process mean shift;
disk/ball radius r ~ U(0, t) (``radial="uniform"``, Yao 2013 eq. 12) or uniform over the
disk/ball (``radial="area"``).
Latin hypercube (scipy.stats.qmc.LatinHypercube) or plain Monte Carlo, independent per pose,
reproducible from ``seed``. Vectorised over all poses × samples; poses are processed in chunks.

Plain sampling cannot *verify* a worst-case requirement: the worst case needs every clearance at
its bound in one particular direction at once, which sampling reaches with vanishing probability.
``max_error_over_worst_case`` shows how far sampling falls short.

Clearance sources (:mod:`evotol.measures.clearances`): every sample adds a random consistent clearance
state -- each joint's screw uniform inside its disks and intervals, projected onto the loop
equations and scaled back into the set (:func:`evotol.measures.clearances.sample_twists`); first order
(there is no nonlinear clearance model).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from evotol.measures import clearances

from evotol.measures.statistical import distributions
from evotol.measures.statistical.distributions import METHODS
from evotol.measures.statistical.lhs_compiled import MIN_POSES as LHS_MIN_POSES, latin_hypercubes, pose_lhs_generator
from evotol.errors import ValidationError, is_integer, is_real
from evotol.verification.mc_tally import Tally
from evotol.verification.nonlinear import verify_nonlinear
from evotol.core.problem import ToleranceProblem
from evotol._runtime.progress import progress_bar
from evotol.measures.statistical import pose_error_nan
from evotol._runtime.blas_threads import single_threaded_blas
from evotol._runtime.random_state import seed_from

RADIAL = distributions.RADIAL
#: linearisation error (max |nonlinear − linear| / max |linear|) up to which the first-order model
#: is read as adequate, and up to which as approximate (:attr:`MonteCarloResult.linearisation_verdict`)
LINEAR_OK, LINEAR_ROUGH = 0.01, 0.10


@dataclass
class MonteCarloResult:
    """Per-pose statistics of sampled end-effector errors (SI units).

    Component dictionaries are keyed by the constrained components, ``"position"`` (m) and/or
    ``"orientation"`` (rad).

    Parameters
    ----------
    method : str
        Sampling method, ``"lhs"`` or ``"mc"``.
    n_samples : int
        Samples per pose.
    seed : int
        The seed the samples were drawn from.
    exceed_rate : dict of str to ndarray, shape (n_poses,)
        Fraction of samples whose first-order error exceeds the requirement (dimensionless).
    max_error : dict of str to ndarray, shape (n_poses,)
        Largest sampled first-order error norm (m or rad).
    quantile_95 : dict of str to ndarray, shape (n_poses,)
        95 % quantile of the sampled first-order error norm (m or rad).
    nonlinear_exceed_rate : dict of str to ndarray, shape (n_poses,)
        The exceed rate on the robot's nonlinear ``pose_error`` (an unassembled sample counts
        as a miss); empty without a nonlinear model.
    linearisation_error : float, optional
        ``max |nonlinear − linear| / max |linear|`` over the samples (dimensionless); None without
        a nonlinear model.
    max_error_over_worst_case : dict of str to float
        Largest over the poses of the sampled maximum / the attained worst case (dimensionless;
        normally below 1).
    seconds : float
        Wall-clock time (s).
    yield_linear : ndarray, shape (n_poses,), optional
        Fraction of samples inside every bound, first-order model.
    yield_nonlinear : ndarray, shape (n_poses,), optional
        The same on the nonlinear model (unassembled = miss).
    yield_check : dict
        :func:`yield_check` of the nonlinear yield where there is one, else the linear.
    part_checks : dict
        The checks the parts of the composed model add on the nonlinear model
        (:meth:`evotol.robots.base.RobotErrorModel.nonlinear_checks`): ``"calibration"`` for a
        calibrated problem (:func:`evotol.calibration.calibrated_problem`: the calibration simulated
        beside the first-order prediction); empty otherwise.
    sampled : evotol.measures.statistical.distributions.Distribution, optional
        The distribution every source was sampled from (``verify(distribution=...)``); None: each
        source's own.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import allocate_optimum, verify
    >>> mc = verify(problem, allocate_optimum(problem).tolerances, n_samples=500, seed=0)
    >>> mc.requirement_missed                                   # no sample beyond the limit
    False
    >>> mc.to_dict()["linearisation_verdict"]                   # doctest: +ELLIPSIS
    'first-order model adequate: ...'
    """

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
    yield_linear: np.ndarray | None = None        # (n_poses,) fraction of samples inside every bound
    yield_nonlinear: np.ndarray | None = None     # the same on robot.pose_error (unassembled = miss)
    yield_check: dict = field(default_factory=dict)
    part_checks: dict = field(default_factory=dict)   # name -> a part's own nonlinear check (to_dict())
    sampled: object = None        # verify(distribution=...): the one distribution every source was sampled from

    @property
    def requirement_missed(self) -> bool:
        """True when the Monte Carlo shows, at the stated confidence, that the yield requirement
        is missed at some pose (nonlinear model where the robot has one)."""
        return self.yield_check.get("verdict") == "missed"

    def max_exceed_rate(self, nonlinear: bool = False) -> float:
        """Largest exceed rate over components and poses.

        Parameters
        ----------
        nonlinear : bool
            Read the nonlinear model's rates (falls back to the linear ones without them).

        Returns
        -------
        float
            The rate (dimensionless fraction of samples).
        """
        rates = self.nonlinear_exceed_rate if nonlinear and self.nonlinear_exceed_rate else self.exceed_rate
        return float(max(np.max(v) for v in rates.values()))

    @property
    def linearisation_verdict(self) -> str | None:
        """The linearisation check read as a sentence (None when the robot has no nonlinear model).

        ``linearisation_error`` is ``max |nonlinear − linear| / max |linear|`` error over the sampled
        designs and poses (dimensionless); below :data:`LINEAR_OK` the first-order results (worst
        case, RSS, yield, the allocators' certificates) hold for the robot itself, below
        :data:`LINEAR_ROUGH` they are approximate, above it they are unreliable.
        """
        e = self.linearisation_error
        if e is None:
            return None
        pct = f"{100 * e:.3g} % of the largest first-order error"
        if e <= LINEAR_OK:
            return f"first-order model adequate: the nonlinear model differs by at most {pct} (<= {100 * LINEAR_OK:g} %)"
        if e <= LINEAR_ROUGH:
            return (f"first-order model approximate: the nonlinear model differs by up to {pct} "
                    f"(> {100 * LINEAR_OK:g} %); read the nonlinear exceed rate")
        return (f"first-order model unreliable: the nonlinear model differs by up to {pct} "
                f"(> {100 * LINEAR_ROUGH:g} %); judge the design by the nonlinear Monte Carlo")

    def __repr__(self) -> str:
        """One line: sampling, size, seed, the largest exceed rate and the smallest yield."""
        n_poses = len(next(iter(self.exceed_rate.values()))) if self.exceed_rate else 0
        text = (f"MonteCarloResult(method={self.method!r}, n_samples={self.n_samples}, {n_poses} poses, "
                f"seed={self.seed}, max exceed rate {100 * self.max_exceed_rate():.3g} %")
        if self.nonlinear_exceed_rate:
            text += f" (nonlinear {100 * self.max_exceed_rate(True):.3g} %)"
        if self.yield_linear is not None:
            text += f", min yield {float(np.min(self.yield_linear)):.4g}"
        return text + ")"

    def to_frame(self) -> pd.DataFrame:
        """The per-pose figures as a table, one row per pose (pandas; ``to_dict`` gives the summary).

        Returns
        -------
        pandas.DataFrame
            Indexed by pose index: ``exceed_rate_<component>`` and ``max_error_<component>``
            (m or rad) of the linear model, ``exceed_rate_nonlinear_<component>`` where the
            robot has a nonlinear model, and ``yield_linear`` / ``yield_nonlinear`` where computed.
        """
        cols = {}
        for c, v in self.exceed_rate.items():
            cols[f"exceed_rate_{c}"] = np.asarray(v, dtype=float)
            cols[f"max_error_{c}"] = np.asarray(self.max_error[c], dtype=float)
        for c, v in self.nonlinear_exceed_rate.items():
            cols[f"exceed_rate_nonlinear_{c}"] = np.asarray(v, dtype=float)
        for name in ("yield_linear", "yield_nonlinear"):
            if getattr(self, name) is not None:
                cols[name] = np.asarray(getattr(self, name), dtype=float)
        frame = pd.DataFrame(cols)
        frame.index.name = "pose"
        return frame

    def to_dict(self) -> dict:
        """The summary as plain data (for JSON/YAML reports).

        Returns
        -------
        dict
            ``method``, ``n_samples``, ``seed``, ``seconds``, ``max_exceed_rate``,
            ``linearisation_error``, ``max_error_over_worst_case`` and, where available,
            ``linearisation_verdict``, ``max_exceed_rate_nonlinear``, ``yield``
            (:func:`yield_check`'s entries), each of ``part_checks`` under its name (``calibration``:
            the simulated calibration of a calibrated problem) and ``sampled_distribution`` (``kind``, ``sigma_k``,
            ``mean_shift``: the one distribution every source was sampled from, when
            ``verify`` was given one); no per-pose arrays.
        """
        d = {"method": self.method, "n_samples": self.n_samples, "seed": self.seed, "seconds": self.seconds,
             "max_exceed_rate": self.max_exceed_rate(), "linearisation_error": self.linearisation_error,
             "max_error_over_worst_case": self.max_error_over_worst_case}
        if self.linearisation_verdict is not None:
            d["linearisation_verdict"] = self.linearisation_verdict
        if self.nonlinear_exceed_rate:
            d["max_exceed_rate_nonlinear"] = self.max_exceed_rate(True)
        if self.yield_check:
            d["yield"] = dict(self.yield_check)
        for name, check in self.part_checks.items():     # e.g. "calibration": the simulated calibration
            d[name] = check.to_dict()
        if self.sampled is not None:
            d["sampled_distribution"] = {"kind": self.sampled.kind, "sigma_k": float(self.sampled.sigma_k),
                                         "mean_shift": float(self.sampled.mean_shift)}
        return d


def yield_check(inside: np.ndarray, n: int, required: float | None, confidence: float = 0.95,
                model: str = "linear") -> dict:
    """Clopper-Pearson interval (exact binomial, via scipy.stats.beta quantiles) of the yield at the
    worst pose and the verdict against ``required``: "met" (lower bound >= required at every pose),
    "missed" (upper bound < required at some pose) or "undecided". inside: (n_poses,) fractions of
    n samples. The verdict holds for all poses together at ``confidence``: each pose's interval
    is taken at level 1 − (1 − confidence)/n_poses (Bonferroni), since the smallest of many
    estimates at the bound is biased low. The reported interval (``yield_lower``, ``yield_upper``)
    is the worst pose's at ``confidence``; ``verdict_interval`` is the worst pose's at the
    Bonferroni level ``verdict_level`` -- the interval the verdict reads (all poses share n, so the
    worst pose has the smallest bounds: "met" iff its lower end >= required, "missed" iff its
    upper end < required).
    The interval assumes independent samples (exact for method="mc"; Latin hypercube samples
    usually vary less, so the interval is then conservative).

    Parameters
    ----------
    inside : ndarray, shape (n_poses,)
        Fraction of the samples inside every bound, per pose (dimensionless).
    n : int
        Samples per pose.
    required : float or None
        Required yield (dimensionless, 0 to 1); None: no verdict.
    confidence : float
        Confidence level of the intervals, in (0, 1).
    model : str
        Label of the model sampled (``"linear"`` or ``"nonlinear"``), copied to the output.

    Returns
    -------
    dict
        ``model``, ``n_samples``, ``confidence``, ``worst_pose`` (index), ``yield_estimate``,
        ``yield_lower``, ``yield_upper``, ``yield_required``, ``verdict_level``,
        ``verdict_interval`` ([lower, upper]) and, when ``required`` is given, ``verdict``
        (``"met"``, ``"missed"`` or ``"undecided"``).
    """
    from scipy.stats import beta

    k = np.rint(np.asarray(inside) * n).astype(int)

    def interval(a):
        lo = np.where(k > 0, beta.ppf(a / 2, np.maximum(k, 1), n - k + 1), 0.0)
        hi = np.where(k < n, beta.ppf(1 - a / 2, k + 1, np.maximum(n - k, 1)), 1.0)
        return lo, hi

    lo, hi = interval(1 - confidence)
    worst = int(np.argmin(k))
    out = {"model": model, "n_samples": int(n), "confidence": confidence, "worst_pose": worst,
           "yield_estimate": float(k[worst] / n), "yield_lower": float(lo[worst]), "yield_upper": float(hi[worst]),
           "yield_required": required}
    lo, hi = interval((1 - confidence) / len(k))
    out["verdict_level"] = float(1 - (1 - confidence) / len(k))
    out["verdict_interval"] = [float(lo[worst]), float(hi[worst])]
    if required is not None:
        out["verdict"] = ("missed" if np.any(hi < required) else "met" if np.all(lo >= required) else "undecided")
    return out


def pose_uniforms(root: np.random.SeedSequence, p: int, n: int, d: int, method: str) -> np.ndarray:
    """Pose ``p``'s (n, d) uniforms: :func:`~evotol.measures.statistical.distributions.uniforms` with
    the Generator of ``root.spawn(P)[p]``, made directly from its spawn key (as is the child a Latin
    hypercube spawns from it): the draws of ``uniforms(n, d, method, default_rng(root.spawn(P)[p]))``.

    Parameters
    ----------
    root : numpy.random.SeedSequence
        The run's seed sequence (nothing spawned from it yet).
    p : int
        The pose's index.
    n, d : int
        Rows (samples) and columns (the sum of the source dimensions).
    method : {"lhs", "mc"}
        As :func:`~evotol.measures.statistical.distributions.uniforms`.

    Returns
    -------
    numpy.ndarray
        (n, d) uniforms in [0, 1).
    """
    if method == "lhs":
        rng = np.random.Generator(pose_lhs_generator(root, p))
        return distributions.latin_hypercube_from(n, d, rng)
    return np.random.default_rng(np.random.SeedSequence(root.entropy, spawn_key=(p,))).random((n, d))


@single_threaded_blas
def verify(problem: ToleranceProblem, tolerances, n_samples: int = 1000, method: str = "lhs", seed: int = 0,
           nonlinear: bool = True, radial: str = "uniform", chunk_poses: int = 64,
           progress: bool | None = None, confidence: float = 0.95, model: str = "linear",
           distribution=None, rng: int | np.random.Generator | None = None) -> MonteCarloResult:
    """Monte Carlo verification of ``tolerances`` (mapping or array, SI) at every problem pose.

    Besides exceedance rates, reports the yield (fraction of samples inside every bound) per pose,
    on the linear and, where the robot has one, the nonlinear model, with the Clopper-Pearson
    interval at the worst pose (``confidence``) and, for a ``yield`` requirement, the verdict
    (:func:`yield_check`; ``requirement_missed`` flags a requirement the robot misses).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem whose poses, requirement and distributions are sampled.
    tolerances : mapping or array_like
        The design: source name -> tolerance, or one value per source (SI: m or rad).
    n_samples : int
        Samples per pose (>= 1).
    method : {"lhs", "mc"}
        Latin hypercube or plain Monte Carlo sampling.
    seed : int
        Seed; each pose gets its own stream (``SeedSequence(seed).spawn``).
    rng : int, numpy.random.Generator or None, optional
        As SciPy's ``rng``: an integer seed, or a Generator drawn from once for the seed of the run
        (recorded in the result); replaces ``seed`` (which keeps working, and also takes a Generator).
    nonlinear : bool
        Also sample the robot's nonlinear ``pose_error`` where it has one.
    radial : str
        Radial law of disk/ball sources, one of ``evotol.measures.statistical.distributions.RADIAL``.
    chunk_poses : int
        Poses sampled per chunk (memory; default 64). The result does not depend on it.
    progress : bool or None
        tqdm bar over the chunks (default: only on an interactive terminal).
    confidence : float
        Confidence of the Clopper-Pearson intervals of the yield, in (0, 1).
    model : {"linear", "nonlinear"}
        ``"nonlinear"``: the worst-vertex check and interval Monte Carlo through the robot's
        ``pose_error`` instead (:func:`evotol.verification.nonlinear.verify_nonlinear`).
    distribution : str, dict or Distribution, optional
        Sample every source from this one distribution, e.g. ``Distribution("normal", sigma_k=3)``:
        the ``rss`` measure's model (normal about each zone's centre, σ = half-width / 3). None
        (default): each source's own distribution.

    Returns
    -------
    MonteCarloResult or evotol.verification.nonlinear.NonlinearCheck
        Per pose: exceedance rates, largest sampled errors and their 95 % quantile (m, rad), the
        yield (1) and its interval; the ratio of the sampled maximum to the worst case (1). With
        ``model="nonlinear"``: the :class:`evotol.verification.nonlinear.NonlinearCheck`.

    Raises
    ------
    evotol.errors.ValidationError
        An unknown ``model``, ``method`` or ``radial``, ``n_samples`` < 1, ``"nonlinear"`` with
        clearance sources or with a ``distribution``, a ``distribution`` that does not suit a
        source, or a design that does not match the problem's sources.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import allocate_optimum, verify
    >>> opt = allocate_optimum(problem)
    >>> mc = verify(problem, opt.tolerances, n_samples=500, seed=0)
    >>> float(mc.exceed_rate["position"][0]), bool(mc.max_error["position"][0] <= 1.0)
    (0.0, True)
    """
    seed = seed_from(rng, seed)
    if model == "nonlinear" and problem.clearances is not None:
        raise ValidationError("model", model, "'linear' with clearance sources (the clearance model is first order)")
    if model == "nonlinear" and distribution is not None:
        raise ValidationError("distribution", distribution, "None with model='nonlinear' (its interval Monte Carlo "
                                                            "samples each source's own distribution)")
    if model == "nonlinear":
        return verify_nonlinear(problem, tolerances, n_samples=n_samples, seed=seed, chunk_poses=chunk_poses)
    if model != "linear":
        raise ValidationError("model", model, "'linear' (first-order samples, plus nonlinear exceed rates) or 'nonlinear'")
    return verify_designs(problem, [tolerances], n_samples=n_samples, method=method, seed=seed, nonlinear=nonlinear,
                          radial=radial, chunk_poses=chunk_poses, progress=progress, confidence=confidence,
                          distribution=distribution)[0]


@single_threaded_blas
def verify_designs(problem: ToleranceProblem, designs, n_samples: int = 1000, method: str = "lhs", seed: int = 0,
                   nonlinear: bool = True, radial: str = "uniform", chunk_poses: int = 64,
                   progress: bool | None = None, confidence: float = 0.95, distribution=None,
                   rng: int | np.random.Generator | None = None) -> list[MonteCarloResult]:
    """:func:`verify` (``model="linear"``) of several designs on one set of samples.

    Each chunk's unit samples (a pose's uniforms from its own stream, then each source's
    distribution per unit tolerance) do not depend on the design: they are drawn once and scaled by
    every design, so each result equals ``verify`` of that design alone with the same arguments, bit
    for bit, and the designs are compared on common random numbers (Yao 2013 checks five designs
    this way). Only the draws are shared; memory stays one chunk of samples a design at a time.

    Parameters
    ----------
    designs : sequence of mapping or array_like
        The designs: each a mapping source name -> tolerance, or one value per source (SI: m or rad).
    problem, n_samples, method, seed, nonlinear, radial, chunk_poses, progress, confidence, distribution, rng
        As :func:`verify`.

    Returns
    -------
    list of MonteCarloResult
        One per design, in order; ``seconds`` is the wall time of the call up to that result.

    Raises
    ------
    evotol.errors.ValidationError
        As :func:`verify`, or no design.
    """
    seed = seed_from(rng, seed)
    if not is_integer(chunk_poses, 1):
        raise ValidationError("chunk_poses", chunk_poses, "a positive integer")
    t0 = time.perf_counter()
    if method not in METHODS:
        raise ValidationError("method", method, f"one of {METHODS}")
    if radial not in RADIAL:
        raise ValidationError("radial", radial, f"one of {RADIAL}")
    if not isinstance(n_samples, (int, np.integer)) or n_samples < 1:
        raise ValidationError("n_samples", n_samples, "a positive integer")
    designs = [problem.as_array(t) for t in designs]
    if not designs:
        raise ValidationError("designs", designs, "at least one design")
    robot = problem.error_model
    dims = [s.dim for s in robot.sources]
    dists = problem.distributions if distribution is None else \
        [distributions.as_distribution(distribution, f"distribution (source {s.name})", s.dim) for s in robot.sources]
    comps = problem.components
    root = np.random.SeedSequence(seed)      # pose p's stream: its child p, made when its chunk is sampled
    P = problem.n_poses
    with_nl = bool(nonlinear and robot.has_nonlinear_model)
    tallies = [Tally(comps, P, with_nl) for _ in designs]
    bar = progress_bar(P, "Monte Carlo", "pose", progress, size=f"{P} poses × {n_samples} samples"
                       + (" (nonlinear model)" if with_nl else "") + (f", {len(designs)} designs" if len(designs) > 1 else ""))
    for start in range(0, P, chunk_poses):
        idx = np.arange(start, min(start + chunk_poses, P))
        U = latin_hypercubes(root, idx, n_samples, sum(dims)) if method == "lhs" and P >= LHS_MIN_POSES else None
        U = (np.concatenate([pose_uniforms(root, int(p), n_samples, sum(dims), method) for p in idx]) if U is None
             else U.reshape(-1, U.shape[2]))                            # the same draws, compiled (many poses)
        Z = distributions.draw(U, dims, dists, radial)                  # row by row: the chunk's poses at once
        J = problem.jacobian[idx]                                       # the chunk's maps, taken once for all designs
        for t, tally in zip(designs, tallies):
            E = np.concatenate(problem.source_errors(Z, t), axis=1).reshape(idx.size, n_samples, robot.n_columns)
            lin = np.einsum("pij,psj->psi", J, E)
            if problem.clearances is not None:   # consistent clearance states inside the classes' bounds
                lin = lin + clearances.sample_twists(robot, problem.poses[idx], t[robot.n_geometric:], n_samples,
                                                     np.random.default_rng([seed, start]))
            tally.add(idx, lin, pose_error_nan(robot, problem.poses[idx], E) if with_nl else None)
        bar.update(idx.size)
    bar.close()
    req = problem.requirement.required_yield if problem.requirement.measure == "yield" else None
    out = []
    for t, tally in zip(designs, tallies):
        res = MonteCarloResult(method, int(n_samples), seed, tally.exceed, tally.maxerr, tally.q95, tally.exceed_nl,
                               tally.linearisation_error)
        res.yield_linear, res.yield_nonlinear = tally.inside_lin, tally.inside_nl
        res.sampled = None if distribution is None else dists[0]
        inside = tally.inside_nl if tally.inside_nl is not None else tally.inside_lin
        res.yield_check = yield_check(inside, n_samples, req, confidence,
                                      "nonlinear" if tally.inside_nl is not None else "linear")
        ev = problem.evaluate(t[None], "worst_case")
        for c, _ in comps:
            res.max_error_over_worst_case[c] = float(np.max(tally.maxerr[c] / np.maximum(getattr(ev, c)[0], 1e-300)))
        if nonlinear:       # each part's own check on the nonlinear model (a calibration: simulated)
            res.part_checks = problem.error_model.nonlinear_checks(problem, t, seed)
        res.seconds = time.perf_counter() - t0
        out.append(res)
    return out


def calibrate_scale(problem: ToleranceProblem, tolerances, n_samples: int, seed=1, confidence: float = 0.95,
                    iters: int = 40) -> dict:
    """Largest common factor s applied to the free tolerances of a design such that, at every
    pose, the one-sided Clopper-Pearson upper bound (``confidence``) of the miss probability on an
    independent common sample set (``n_samples`` Latin-hypercube rows from ``seed``, nonlinear
    model where the robot has one) stays within 1 − p of the ``yield`` requirement.

    A GA that optimises a sampled yield sits on its own sample's constraint, so its design is
    optimistic; this rescales it on fresh samples (geometric bisection; the miss probability
    grows with every tolerance, so the test is monotone in s). Locked and fixed sources keep their
    values; s stays within the tolerance bounds. Asymmetric and offset intervals are sampled as
    the yield measure samples them. Returns {"scale", "tolerances" (SI array),
    "certified" (bool), "n_samples", "confidence"}.

    Parameters
    ----------
    problem : ToleranceProblem
        A problem with a ``yield`` requirement and a robot with a nonlinear ``pose_error``.
    tolerances : mapping or array_like
        The design: source name -> tolerance, or one value per source (SI: m or rad).
    n_samples : int
        Size of the fresh common sample set (>= 10).
    seed : int
        Seed of the fresh samples (differ from the optimiser's to be independent).
    confidence : float
        One-sided confidence of the miss probability's upper bound, in (0, 1).
    iters : int
        Bisection steps on s.

    Returns
    -------
    dict
        ``scale`` (s, dimensionless), ``tolerances`` ((n_sources,) SI array, free sources scaled
        by s), ``certified`` (False when even the lower tolerance bounds miss; ``scale`` is then
        the one at the lower bounds), ``n_samples`` and ``confidence``.

    Raises
    ------
    evotol.errors.ValidationError
        A requirement measure other than ``yield``, ``n_samples`` not an integer >= 10, a
        ``confidence`` outside (0, 1), ``iters`` not a positive integer, no free
        source (every source locked or fixed), a bad design (a zero tolerance on a free source
        included), or a robot without a nonlinear model.
    """
    from scipy.stats import beta

    from evotol.measures import statistical
    r = problem.requirement
    if r.measure != "yield":
        raise ValidationError("requirement.measure", r.measure, "'yield' for calibrate_scale")
    if not is_integer(n_samples, 10):
        raise ValidationError("n_samples", n_samples, "an integer >= 10")
    if not (is_real(confidence) and 0 < confidence < 1):
        raise ValidationError("confidence", confidence, "a probability in (0, 1)")
    if not is_integer(iters, 1):
        raise ValidationError("iters", iters, "a positive integer (bisection steps)")
    t = problem.as_array(tolerances)
    free = np.isnan(problem.locked_values)
    if not free.any():      # ToleranceProblem refuses this; guards a problem whose sources were locked after
        raise ValidationError("tolerances", "all locked", "at least one free source for calibrate_scale to scale")
    zero = np.flatnonzero(free & (t == 0))
    if zero.size:
        raise ValidationError(f"tolerances[{problem.names[zero[0]]!r}]", t[zero[0]],
                              "a positive tolerance for a free source (calibrate_scale multiplies it by the factor s)")
    if not problem.error_model.has_nonlinear_model:
        raise ValidationError("robot", problem.error_model.name, "a robot with pose_error (calibration samples the exact model)")
    shift = None if problem.shape.plain else (problem.shape.rho, problem.shape.kappa, problem.shape.offset)
    model = statistical.SampledYield(problem.error_model, problem.poses, problem.distributions, dict(problem.components),
                                     int(n_samples), seed, shift=shift)
    p_max = 1.0 - r.required_yield

    def ok(s):
        T = t.copy()
        T[free] *= s
        q = 1.0 - model.evaluate(T[None], r.required_yield).probability[0]
        k = np.rint(q * n_samples).astype(int)
        upper = np.where(k >= n_samples, 1.0, beta.ppf(confidence, k + 1, np.maximum(n_samples - k, 1)))
        return bool(np.max(upper) <= p_max)

    lo = float(np.max(problem.lower[free] / t[free]))
    hi = float(np.min(problem.upper[free] / t[free]))
    certified = ok(lo)
    if certified:
        if ok(hi):
            lo = hi
        else:
            for _ in range(iters):
                mid = np.sqrt(lo * hi)
                lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    T = t.copy()
    T[free] *= lo
    return {"scale": lo, "tolerances": T, "certified": certified, "n_samples": int(n_samples), "confidence": confidence}

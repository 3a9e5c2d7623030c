"""The process-selection problem: choose a process and a tolerance for every source (conventions:
:mod:`evotol.allocators.process`), and the problem check every process allocator starts with.

Its parts: the candidate processes (:mod:`~evotol.allocators.process.candidates`), the result of an
allocation (:mod:`~evotol.allocators.process.result`).

The parameters several definitions of this module share are described once, here.

Parameters
----------
T : array_like, (n, n_sources) or (n_sources,)
    Designs (m or rad).
choice : sequence of int, (n_sources,)
    Index of the chosen process of every source.
"""
from __future__ import annotations

import copy
from dataclasses import replace
from typing import Mapping, Sequence, overload

import numpy as np

from evotol.cost_models.power import PowerCost
from evotol.cost_models.quality_loss import QualityLossCost
from evotol.allocators.process.candidates import Process, checked_processes
from evotol.allocators.process.result import FEAS_TOL, ProcessResult  # noqa: F401  (re-exported)
from evotol.errors import ValidationError
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from evotol.core.quality_loss import loss_coefficients, with_quality_loss
from evotol.robots.base import RobotErrorModel



class ProcessProblem:
    """Tolerance allocation with a process choice per source (see the module docstring).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        Any error model (e.g. :class:`evotol.robots.assembly.AssemblyFunction`).
    processes : Mapping[str, Sequence[Process]]
        Source name -> non-empty list of :class:`Process`.
    requirement : evotol.core.problem.Requirement
        As for :class:`evotol.core.problem.ToleranceProblem`.
    poses : array_like, shape (n_poses, workspace.dim)
        As for :class:`evotol.core.problem.ToleranceProblem` (SI).
    n_directions : int
        Hemisphere directions for the worst-case measure.
    check_dominance : bool
        Refuse a process that another one of the same source covers and undercuts everywhere
        (usually a unit slip in a cost curve).

    Raises
    ------
    evotol.errors.ValidationError
        A robot or requirement of the wrong type, a source without processes or a process for
        no source, a process that is not a :class:`Process`, duplicate process names, a negative
        or non-finite ``fixed_cost``, a cost model invalid on its range, or a dominated process.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import Process
    >>> turn = Process("turning", PowerCost(1.0, 1.0, scale=1e-3), lower=3e-5, upper=1e-4)
    >>> grind = Process("grinding", PowerCost(3.0, 1.0, scale=1e-3), lower=2e-6, upper=3e-5)
    >>> pp = assembly_problem(stack, processes={n: [turn, grind] for n in stack.source_names})
    >>> pp.n_sources, pp.n_combinations
    (3, 8)
    """

    #: a process problem is never calibrated (as ToleranceProblem.calibration)
    calibration = None

    def __init__(self, robot: RobotErrorModel, processes: Mapping[str, Sequence[Process]], requirement: Requirement,
                 poses, *, n_directions: int = 600, check_dominance: bool = True):
        if not isinstance(robot, RobotErrorModel):
            raise ValidationError("robot", robot, "a evotol.robots.base.RobotErrorModel")
        self.processes: dict[str, tuple[Process, ...]] = checked_processes(robot, processes, check_dominance=check_dominance)
        names = self.names = robot.source_names
        self.n_processes = np.array([len(self.processes[n]) for n in names])
        lo = {n: min(p.lower for p in self.processes[n]) for n in names}
        hi = {n: max(p.upper for p in self.processes[n]) for n in names}
        # geometry-only base problem: costs are placeholders, replaced in every subproblem
        placeholder = {n: Tolerance(PowerCost(1.0, 1.0, scale=hi[n]), lo[n], hi[n]) for n in names}
        self.base = ToleranceProblem(robot, placeholder, requirement, poses, n_directions=n_directions)
        self.model, self.requirement = robot, requirement     # as ToleranceProblem: model passed in, robot described
        P = int(self.n_processes.max())
        self.lo = np.full((len(names), P), np.nan)
        self.hi = np.full((len(names), P), np.nan)
        for j, n in enumerate(names):
            for k, p in enumerate(self.processes[n]):
                self.lo[j, k], self.hi[j, k] = p.lower, p.upper
        #: per-source coefficients q_j of the expected quality loss Σ q_j t_j² inside the process
        #: costs (zero unless built by :meth:`with_quality_loss`)
        self.loss_coefficients = np.zeros(len(names))
        self.quality_loss_A = None


    @property
    def robot(self) -> RobotErrorModel:
        """The robot as the user described it (the innermost part of :attr:`model`; an assembly is its own)."""
        return self.model.described
    def with_quality_loss(self, A) -> "ProcessProblem":
        """The same problem with every process's cost = machining cost + expected Taguchi loss:
        :func:`evotol.core.quality_loss.with_quality_loss` ``(self, A)``, the one entry point.

        Parameters
        ----------
        A : float or mapping
            Loss at the limit (cost units) per response (:func:`evotol.core.quality_loss.loss_coefficients`;
            K = A / L², σ = t / 3).

        Returns
        -------
        ProcessProblem
            Processes' costs wrapped in :class:`evotol.cost_models.quality_loss.QualityLossCost`;
            ``loss_coefficients`` holds q_j. ``A = 0`` gives the same optimum as this problem.

        Raises
        ------
        ValidationError
            A negative or unknown coefficient; a problem that already carries a loss.
        """
        return with_quality_loss(self, A)

    def quality_loss(self, T) -> np.ndarray:
        """Expected quality loss Σ_j q_j t_j² of designs T (n, n_sources) SI -> (n,) (0 without a loss term).

        Returns
        -------
        numpy.ndarray
            (n,) expected loss (cost units).
        """
        return np.atleast_2d(np.asarray(T, dtype=float)) ** 2 @ self.loss_coefficients

    # --- basics -----------------------------------------------------------------------------------
    @property
    def n_sources(self) -> int:
        """Number of sources."""
        return len(self.names)

    @property
    def n_combinations(self) -> int:
        """Number of process combinations (product of the processes per source)."""
        return int(np.prod(self.n_processes.astype(float)))

    def choice_names(self, choice) -> dict[str, str]:
        """Process names of a choice.

        Returns
        -------
        dict of str to str
            Source name -> process name.
        """
        return {n: self.processes[n][int(k)].name for n, k in zip(self.names, choice)}

    def choice_index(self, names: Mapping[str, str]) -> np.ndarray:
        """Process indices of a choice given by names (inverse of :meth:`choice_names`).

        Parameters
        ----------
        names : Mapping[str, str]
            Source name -> process name, for every source.

        Returns
        -------
        numpy.ndarray of int
            (n_sources,) index of the chosen process of every source.

        Raises
        ------
        ValidationError
            A source missing, or a process name that source does not have.
        """
        out = []
        for n in self.names:
            pn = [p.name for p in self.processes[n]]
            if names.get(n) not in pn:
                raise ValidationError(f"process choice[{n!r}]", names.get(n), f"one of {pn}")
            out.append(pn.index(names[n]))
        return np.array(out)

    def subproblem(self, choice) -> ToleranceProblem:
        """The convex allocation problem of one process choice (shares the cached geometry).

        Returns
        -------
        ToleranceProblem
            The problem with each source's cost model and bounds (m or rad) those of its chosen
            process; fixed costs are not included (:meth:`fixed_cost`), nor the quality loss
            unless it is in the process costs.
        """
        choice = np.asarray(choice, dtype=int)
        sub = copy.copy(self.base)
        sub.tolerances = {n: Tolerance(self.processes[n][k].cost, self.processes[n][k].lower, self.processes[n][k].upper)
                          for n, k in zip(self.names, choice)}
        sub.lower = self.lo[np.arange(self.n_sources), choice].copy()
        sub.upper = self.hi[np.arange(self.n_sources), choice].copy()
        sub._mc_cache = None
        return sub

    def fixed_cost(self, choice) -> float:
        """Sum of the set-up costs of a choice.

        Returns
        -------
        float
            Total fixed cost (cost units).
        """
        return float(sum(self.processes[n][int(k)].fixed_cost for n, k in zip(self.names, choice)))

    def cost(self, choices, T) -> np.ndarray:
        """Total cost of designs (choices (n, S) int, T (n, S) SI) -> (n,).

        Parameters
        ----------
        choices : array_like of int, (n, n_sources) or (n_sources,)
            Process index per source of every design.
        T : array_like, (n, n_sources) or (n_sources,)
            Tolerances (m or rad).

        Returns
        -------
        numpy.ndarray
            (n,) total cost (set-up + process cost models, cost units); ranges are not checked
            (:meth:`in_ranges`).
        """
        choices = np.atleast_2d(np.asarray(choices, dtype=int))
        T = np.atleast_2d(np.asarray(T, dtype=float))
        c = np.zeros(T.shape[0])
        for j, n in enumerate(self.names):
            for k, p in enumerate(self.processes[n]):
                m = choices[:, j] == k
                if m.any():
                    c[m] += p.total(T[m, j])
        return c

    def in_ranges(self, choices, T, rtol: float = 1e-9) -> np.ndarray:
        """Whether every tolerance lies in the range of its chosen process.

        Parameters
        ----------
        choices : array_like of int, (n, n_sources) or (n_sources,)
            Process index per source of every design.
        T : array_like, (n, n_sources) or (n_sources,)
            Tolerances (m or rad).
        rtol : float
            Relative slack on both ends of each range (dimensionless).

        Returns
        -------
        numpy.ndarray of bool
            (n,) True where every source is within ``[lower (1 − rtol), upper (1 + rtol)]``.
        """
        choices = np.atleast_2d(np.asarray(choices, dtype=int))
        T = np.atleast_2d(T)
        idx = np.arange(self.n_sources)
        lo, hi = self.lo[idx, choices], self.hi[idx, choices]
        return np.all((T >= lo * (1 - rtol)) & (T <= hi * (1 + rtol)), axis=1)

    def normalised_error(self, T) -> np.ndarray:
        """Exact max error / bound over poses and components (<= 1: feasible).

        Returns
        -------
        numpy.ndarray
            (n,) normalised error (dimensionless).
        """
        return self.base.evaluate(np.atleast_2d(T), top_only=True).violation + 1

    def yield_model(self, distribution="normal"):
        """First-order statistical model of the responses (:class:`evotol.measures.statistical.FirstOrderYield`,
        ``docs/statistical.md``) with every source distributed as ``distribution`` (a kind name or an
        :class:`evotol.measures.statistical.distributions.Distribution`; default normal with t = 3σ).

        Parameters
        ----------
        distribution : str or evotol.measures.statistical.distributions.Distribution
            Distribution of every source inside its tolerance.

        Returns
        -------
        evotol.measures.statistical.FirstOrderYield
            The first-order model on the problem's poses (the responses).

        Raises
        ------
        ValidationError
            If ``distribution`` is neither a kind name nor a Distribution (or is invalid).
        """
        from evotol.measures.statistical.distributions import Distribution

        if not isinstance(distribution, (str, Distribution)):
            raise ValidationError("distribution", distribution, "a distribution kind name or evotol.measures.statistical.distributions.Distribution")
        tol = {n: Tolerance(t.cost, t.lower, t.upper, distribution=distribution) for n, t in self.base.tolerances.items()}
        req = replace(self.requirement, measure="yield", probability=None, ppm=None)
        return ToleranceProblem(self.robot, tol, req, self.base.poses).first_order_yield()

    def assembly_yield(self, T, model=None) -> np.ndarray:
        """Yield of designs ``T`` (n, n_sources), SI: P(every response within its limit) of the
        first-order model, as the Bonferroni bound 1 − Σ_k P(``|Δy_k|`` > L_k) over the responses
        (poses); exact for one response (the clutch). ``model``: :meth:`yield_model` (default normal).

        The response mean m_k and variance s_k² (in units of L_k) are the model's moments
        (:meth:`evotol.measures.statistical.FirstOrderYield.moments`); an assembly response is a scalar (row z
        of the error twist), so P(``|Δy_k|`` > L_k) = Φ((−1 − m_k)/s_k) + Φ((m_k − 1)/s_k) exactly
        (normal sources; moment-matched normal otherwise, ``model.exact``) -- the 3-D octant rule
        of :func:`evotol.measures.statistical.miss_probability` is built for full-rank covariances and is off
        by up to ~1e-4 of the miss probability on this rank-one case.

        Parameters
        ----------
        model : evotol.measures.statistical.FirstOrderYield or None
            The statistical model (default: :meth:`yield_model` with normal sources).

        Returns
        -------
        numpy.ndarray
            (n,) yield, a probability in [0, 1] (a lower bound with several responses).
        """
        from scipy.stats import norm

        model = self.yield_model() if model is None else model
        T = np.atleast_2d(np.asarray(T, dtype=float))
        S, mean = model.moments("position", T)
        s = np.sqrt(np.maximum(S[..., 2], 1e-300))
        m = 0.0 if mean is None else mean[..., 2]
        miss = (norm.cdf((-1.0 - m) / s) + norm.sf((1.0 - m) / s)).sum(axis=1)
        return 1.0 - np.minimum(miss, 1.0)

    def judge(self, processes: Mapping[str, str], tolerances: Mapping[str, float]) -> dict:
        """Recompute a published design: its cost, its normalised error (max error / bound; > 1
        means the requirement is violated) and whether each tolerance lies in its process's range.

        Parameters
        ----------
        processes : Mapping[str, str]
            Source name -> process name, for every source.
        tolerances : Mapping[str, float]
            Source name -> tolerance (m or rad), for every source.

        Returns
        -------
        dict
            ``cost`` (cost units), ``normalised_error`` (dimensionless), ``holds_requirement``
            (bool, normalised error <= 1 + ``FEAS_TOL`` = 1e-9, as a result's ``feasible``) and ``outside_process_range`` (list of source
            names).

        Raises
        ------
        ValidationError
            An unknown process, a source without a tolerance, or a tolerance that is not positive
            and finite.
        """
        ch = self.choice_index(processes)
        missing = [n for n in self.names if n not in tolerances]
        if missing:
            raise ValidationError("tolerances", sorted(tolerances), f"a tolerance for every source; missing {missing}")
        t = np.array([float(tolerances[n]) for n in self.names])
        if not np.all(np.isfinite(t)) or np.any(t <= 0):
            raise ValidationError("tolerances", t.tolist(), "positive finite tolerances (SI)")
        idx = np.arange(self.n_sources)
        outside = [n for n, ok in zip(self.names, (t >= self.lo[idx, ch] * (1 - 1e-9)) & (t <= self.hi[idx, ch] * (1 + 1e-9))) if not ok]
        ne = float(self.normalised_error(t)[0])
        return {"cost": float(self.cost(ch, t)[0]), "normalised_error": ne, "holds_requirement": bool(ne <= 1 + FEAS_TOL),
                "outside_process_range": outside}

    def describe(self) -> str:
        """A printable summary: robot, sources, number of combinations, measure and every process.

        Returns
        -------
        str
            One line for the problem, then one per source listing its processes (range in SI,
            cost model, fixed cost).
        """
        lines = [f"ProcessProblem: {self.robot.name}, {self.n_sources} sources, {self.n_combinations} process combinations, "
                 f"measure {self.requirement.measure}"]
        for n in self.names:
            lines.append(f"  {n}: " + "; ".join(f"{p.name} [{p.lower:.3g}, {p.upper:.3g}] {p.cost!r}"
                                              + (f" + {p.fixed_cost:g}" if p.fixed_cost else "") for p in self.processes[n]))
        return "\n".join(lines)

    __repr__ = describe


@overload
def assembly_problem(assembly, tolerances: Mapping[str, Tolerance] | None = None, measure: str = "worst_case", *,
                     processes: None = None, **requirement) -> ToleranceProblem: ...


@overload
def assembly_problem(assembly, tolerances: Mapping[str, Tolerance] | None = None, measure: str = "worst_case", *,
                     processes: Mapping[str, Sequence[Process]], **requirement) -> ProcessProblem: ...


def assembly_problem(assembly, tolerances: Mapping[str, Tolerance] | None = None, measure: str = "worst_case", *,
                     processes: Mapping[str, Sequence[Process]] | None = None,
                     **requirement) -> ToleranceProblem | ProcessProblem:
    """"Every response of an assembly within its limit" (see :mod:`evotol.robots.assembly`).

    Parameters
    ----------
    assembly : evotol.robots.assembly.AssemblyFunction
        The assembly (its responses are the "poses"; each response's limit is its bound).
    tolerances : Mapping[str, evotol.core.problem.Tolerance] or None
        Dimension name -> tolerance (SI), for a tolerance problem; or
    measure : str
        Accuracy measure of the requirement (a registered measure name).
    processes : Mapping[str, Sequence[Process]] or None
        Dimension name -> candidate processes, for a process-selection problem.
    **requirement
        Further :class:`evotol.core.problem.Requirement` fields (``probability``, ``ppm``...).

    Returns
    -------
    evotol.core.problem.ToleranceProblem or ProcessProblem
        A :class:`evotol.core.problem.ToleranceProblem` when ``tolerances`` are given, a
        :class:`ProcessProblem` when ``processes`` are; the requirement is normalised (the
        response over its limit, 1).

    Raises
    ------
    evotol.errors.ValidationError
        Neither or both of ``tolerances`` and ``processes``, or what the problem's constructor
        refuses.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> problem.n_poses, problem.n_sources                     # one response, three dimensions
    (1, 3)
    >>> ev = problem.evaluate([[1e-5, 1e-5, 1e-5]])            # error / limit: (1 + 2 + 0.5) * 1e-5 / 1e-4
    >>> round(float(ev.position[0, 0]), 12)
    0.35
    """
    req = Requirement(position=1.0, measure=measure, **requirement)
    if (tolerances is None) == (processes is None):
        raise ValidationError("assembly_problem", "tolerances/processes", "exactly one of tolerances= or processes=")
    if processes is not None:
        return ProcessProblem(assembly, processes, req, assembly.response_poses)
    return ToleranceProblem(assembly, tolerances, req, assembly.response_poses)

def check_no_budget(problem: ProcessProblem, budget, name: str) -> ProcessProblem:
    """The one allocator shape: process allocators take ``budget=None`` and refuse a budget in one line
    (process selection minimises cost at the requirement). Returns the problem, checked to be a
    :class:`ProcessProblem`.

    Parameters
    ----------
    problem : ProcessProblem
        The problem passed to the allocator.
    budget : object
        The allocator's ``budget`` argument; must be None.
    name : str
        Name of the allocator, for the error message.

    Returns
    -------
    ProcessProblem
        ``problem`` itself.

    Raises
    ------
    ValidationError
        A ``budget`` that is not None, or a ``problem`` that is not a :class:`ProcessProblem`.
    """
    if budget is not None:
        raise ValidationError("budget", budget, f"None for {name} (process selection minimises cost at the requirement)")
    if not isinstance(problem, ProcessProblem):
        raise ValidationError("problem", type(problem).__name__, f"a ProcessProblem for {name} (evotol.allocators.process)")
    return problem


@with_quality_loss.register
def _process_problem_with_quality_loss(problem: ProcessProblem, A) -> ProcessProblem:
    # the process-selection side of evotol.core.quality_loss.with_quality_loss: the same
    # coefficients (on the geometry-only base problem), each process's cost wrapped
    if problem.quality_loss_A is not None:
        raise ValidationError("quality_loss", A, f"a problem without a loss term (this one has A = {problem.quality_loss_A})")
    q = loss_coefficients(problem.base, A)
    procs = {n: [replace(p, cost=QualityLossCost(p.cost, qj)) for p in problem.processes[n]]
             for n, qj in zip(problem.names, q)}
    out = ProcessProblem(problem.robot, procs, problem.requirement, problem.base.poses,
                         n_directions=problem.base.n_directions, check_dominance=False)
    out.loss_coefficients, out.quality_loss_A = q, A
    return out

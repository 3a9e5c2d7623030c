"""Process selection: choose a manufacturing process *and* a tolerance for every source.

Each source ``j`` has a list of candidate processes ``p`` (turning, grinding, honing...), each a
cost model ``c_p(t)``, a feasible tolerance range ``[lo_p, hi_p]`` and an optional fixed (set-up)
cost ``F_p``. A design picks one process per source and a tolerance inside that process's range:

    min_{p, t}  Σ_j [F_{p_j} + c_{p_j}(t_j)]   s.t.  the accuracy requirement,  lo_{p_j} <= t_j <= hi_{p_j}

(Chase, Greenwood, Loosli & Hauglund 1990; Loosli 1987, ADCATS report 87-4). Conventions:

* **a range clips the cost curve**: outside ``[lo_p, hi_p]`` a process cannot hold (below) or is
  not used for (above) the tolerance, so a design outside every range of a source is infeasible;
  inside it the cost is the curve's value (no extrapolation);
* **worst case vs. RSS** is the problem's ``Requirement.measure``: arithmetic stack
  ``Σ|S_j| t_j <= L`` or statistical stack ``sqrt(Σ (S_j t_j)²) <= L``;
* a process that costs more than another process of the same source everywhere on its range
  while the other's range covers it can never be chosen: evotol reports it as inconsistent data
  (usually a unit slip) unless ``check_dominance=False``.

Process selection is a layer over :class:`evotol.problem.ToleranceProblem`: a *process choice*
turns the problem into an ordinary convex allocation problem (:meth:`ProcessProblem.subproblem`),
which :func:`evotol.allocators.optimum.allocate_optimum` solves with a certificate. Methods:

* :func:`allocate_process_optimum` — exact: **branch and bound** over process choices (depth-first,
  children in order of their bound) or full enumeration. Node bound: the Lagrange dual
  ``q(λ) = Σ_j min_{p∈P_j} min_{t∈[lo_p,hi_p]} [F_p + c_p(t) + w_j t + v_j t²] − Σλ − Σμ``
  with ``w = Aᵀλ, v = Bᵀμ`` over the constraint rows (:mod:`evotol.constraints`), sources already
  fixed taking their process only. Weak duality makes ``q(λ)`` a lower bound of every completion
  of the node for **any** ``λ, μ >= 0`` (no convexity needed); we take the best over a log-spaced
  family ``s·λ̂`` along the KKT multipliers ``λ̂`` of every leaf solved so far. A node whose
  tightest design (every tolerance at its smallest possible value) violates the rows is pruned as
  infeasible. Leaves are solved with ``allocate_optimum``. The result reports nodes, convex solves
  and the certificate (incumbent, smallest pruned bound, leaf duality gap).
* :func:`allocate_process_ga` — pymoo GA over one real gene per source, ``z_j ∈ [0, P_j)``:
  process ``⌊z_j⌋``, tolerance ``lo·(hi/lo)^{frac(z_j)}`` (log-uniform inside the range). One gene
  per source keeps the standard SBX / polynomial-mutation operators and a vectorised evaluation;
  crossing an integer moves to a neighbouring process. A boundary repair scales each design's
  tolerances onto the constraint boundary inside its processes' ranges (as ``allocate_ga`` does)
  and writes the genes back (Lamarckian).
* :func:`process_front` — NSGA-II, cost vs. normalised error (``max error / bound``).
* :func:`allocate_process_baselines` — the textbook route: cheapest feasible process per source
  (:func:`cheapest_feasible_processes`), then the sensitivity rule or the Lagrange closed form.
"""
from __future__ import annotations

import copy
import itertools
import time
from dataclasses import dataclass, field, replace
from typing import Mapping, Sequence

import numpy as np
import pandas as pd
from scipy.optimize import nnls

from pymoo.core.callback import Callback
from pymoo.core.problem import Problem
from pymoo.core.repair import Repair

from cost_models.base import CostModel
from cost_models.power import PowerCost
from evotol.allocators.baselines import allocate_lagrange
from evotol.allocators.optimum import allocate_optimum
from evotol.allocators.sensitivity import allocate_sensitivity
from evotol.constraints import ConstraintRows
from evotol.errors import ValidationError
from evotol.problem import Requirement, Tolerance, ToleranceProblem
from evotol.threads import single_threaded_blas
from robots.base import RobotErrorModel

FEAS_TOL = 1e-9


@dataclass(frozen=True)
class Process:
    """One candidate manufacturing process of a source.

    name: e.g. ``"turn"``, ``"grind"``.
    cost: cost model of the tolerance (SI t), valid (positive, non-increasing) on the range.
    lower, upper: tolerances this process holds (SI), 0 < lower <= upper.
    fixed_cost: set-up cost added when the process is chosen (cost units, >= 0).
    """

    name: str
    cost: CostModel
    lower: float
    upper: float
    fixed_cost: float = 0.0

    def total(self, t) -> np.ndarray:
        return self.fixed_cost + self.cost.cost(t)


def _dominated(a: Process, b: Process, n: int = 33) -> bool:
    """True when b covers a's range and is cheaper everywhere on it (a can never be chosen)."""
    if not (b.lower <= a.lower and b.upper >= a.upper):
        return False
    t = np.geomspace(a.lower, a.upper, n)
    return bool(np.all(b.total(t) < a.total(t)))


class ProcessProblem:
    """Tolerance allocation with a process choice per source (see the module docstring).

    robot: any :class:`robots.base.RobotErrorModel` (e.g. :class:`robots.assembly.AssemblyFunction`).
    processes: source name -> non-empty list of :class:`Process`.
    requirement, poses: as for :class:`ToleranceProblem`.
    """

    def __init__(self, robot: RobotErrorModel, processes: Mapping[str, Sequence[Process]], requirement: Requirement,
                 poses, *, n_directions: int = 600, check_dominance: bool = True):
        if not isinstance(robot, RobotErrorModel):
            raise ValidationError("robot", robot, "a robots.base.RobotErrorModel")
        if not isinstance(processes, Mapping):
            raise ValidationError("processes", processes, "a mapping source name -> list of Process")
        names = robot.source_names
        missing = [n for n in names if n not in processes]
        if missing:
            raise ValidationError("processes", sorted(processes), f"a process list for every source of {robot.name}; missing {missing}")
        extra = [n for n in processes if n not in names]
        if extra:
            raise ValidationError(f"processes[{extra[0]!r}]", extra[0], f"a source of {robot.name}: {list(names)}")
        self.processes: dict[str, tuple[Process, ...]] = {}
        for n in names:
            plist = processes[n]
            if isinstance(plist, Process) or not isinstance(plist, Sequence) or len(plist) == 0:
                raise ValidationError(f"processes[{n!r}]", plist, "a non-empty list of Process (at least one way to make it)")
            seen = set()
            for p in plist:
                if not isinstance(p, Process):
                    raise ValidationError(f"processes[{n!r}] entry", p, "an evotol.allocators.process.Process")
                field_ = f"processes[{n!r}][{p.name!r}]"
                if p.name in seen:
                    raise ValidationError(f"processes[{n!r}] name", p.name, "unique process names per source")
                seen.add(p.name)
                if not isinstance(p.fixed_cost, (int, float, np.floating)) or not np.isfinite(p.fixed_cost) or p.fixed_cost < 0:
                    raise ValidationError(f"{field_}.fixed_cost", p.fixed_cost, "a finite cost >= 0")
                try:
                    Tolerance(p.cost, p.lower, p.upper).validate(n)
                except ValidationError as exc:
                    raise ValidationError(f"{field_}: {exc.field}", exc.value, exc.expected) from None
            if check_dominance:
                for a, b in itertools.permutations(plist, 2):
                    if _dominated(a, b):
                        t = np.sqrt(a.lower * a.upper)
                        raise ValidationError(
                            f"processes[{n!r}][{a.name!r}]", f"cost {float(a.total(t)):.4g} at t = {t:.3g}",
                            f"a process that can be the cheapest somewhere: {b.name!r} covers its range "
                            f"[{a.lower:.3g}, {a.upper:.3g}] and costs less everywhere on it (here {float(b.total(t)):.4g}); "
                            "check the units of the cost curves, or pass check_dominance=False")
            self.processes[n] = tuple(plist)
        self.names = names
        self.n_processes = np.array([len(self.processes[n]) for n in names])
        lo = {n: min(p.lower for p in self.processes[n]) for n in names}
        hi = {n: max(p.upper for p in self.processes[n]) for n in names}
        # geometry-only base problem: costs are placeholders, replaced in every subproblem
        placeholder = {n: Tolerance(PowerCost(1.0, 1.0, scale=hi[n]), lo[n], hi[n]) for n in names}
        self.base = ToleranceProblem(robot, placeholder, requirement, poses, n_directions=n_directions)
        self.robot, self.requirement = robot, requirement
        P = int(self.n_processes.max())
        self.lo = np.full((len(names), P), np.nan)
        self.hi = np.full((len(names), P), np.nan)
        for j, n in enumerate(names):
            for k, p in enumerate(self.processes[n]):
                self.lo[j, k], self.hi[j, k] = p.lower, p.upper

    # --- basics -----------------------------------------------------------------------------------
    @property
    def n_sources(self) -> int:
        return len(self.names)

    @property
    def n_combinations(self) -> int:
        return int(np.prod(self.n_processes.astype(float)))

    def choice_names(self, choice) -> dict[str, str]:
        return {n: self.processes[n][int(k)].name for n, k in zip(self.names, choice)}

    def choice_index(self, names: Mapping[str, str]) -> np.ndarray:
        out = []
        for n in self.names:
            pn = [p.name for p in self.processes[n]]
            if names.get(n) not in pn:
                raise ValidationError(f"process choice[{n!r}]", names.get(n), f"one of {pn}")
            out.append(pn.index(names[n]))
        return np.array(out)

    def subproblem(self, choice) -> ToleranceProblem:
        """The convex allocation problem of one process choice (shares the cached geometry)."""
        choice = np.asarray(choice, dtype=int)
        sub = copy.copy(self.base)
        sub.tolerances = {n: Tolerance(self.processes[n][k].cost, self.processes[n][k].lower, self.processes[n][k].upper)
                          for n, k in zip(self.names, choice)}
        sub.lower = self.lo[np.arange(self.n_sources), choice].copy()
        sub.upper = self.hi[np.arange(self.n_sources), choice].copy()
        sub._mc_cache = None
        return sub

    def fixed_cost(self, choice) -> float:
        return float(sum(self.processes[n][int(k)].fixed_cost for n, k in zip(self.names, choice)))

    def cost(self, choices, T) -> np.ndarray:
        """Total cost of designs (choices (n, S) int, T (n, S) SI) -> (n,)."""
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
        choices = np.atleast_2d(np.asarray(choices, dtype=int))
        T = np.atleast_2d(T)
        idx = np.arange(self.n_sources)
        lo, hi = self.lo[idx, choices], self.hi[idx, choices]
        return np.all((T >= lo * (1 - rtol)) & (T <= hi * (1 + rtol)), axis=1)

    def normalised_error(self, T) -> np.ndarray:
        """Exact max error / bound over poses and components (<= 1: feasible)."""
        return self.base.evaluate(np.atleast_2d(T), top_only=True).violation + 1

    def yield_model(self, distribution="normal"):
        """First-order statistical model of the responses (:class:`evotol.statistical.FirstOrderYield`,
        ``docs/statistical.md``) with every source distributed as ``distribution`` (a kind name or an
        :class:`evotol.distributions.Distribution`; default normal with t = 3σ)."""
        from evotol.distributions import Distribution

        if not isinstance(distribution, (str, Distribution)):
            raise ValidationError("distribution", distribution, "a distribution kind name or evotol.distributions.Distribution")
        tol = {n: Tolerance(t.cost, t.lower, t.upper, distribution=distribution) for n, t in self.base.tolerances.items()}
        req = replace(self.requirement, measure="yield", probability=None, ppm=None)
        return ToleranceProblem(self.robot, tol, req, self.base.poses).first_order_yield()

    def assembly_yield(self, T, model=None) -> np.ndarray:
        """Yield of designs ``T`` (n, n_sources), SI: P(every response within its limit) of the
        first-order model, as the Bonferroni bound 1 − Σ_k P(|Δy_k| > L_k) over the responses
        (poses); exact for one response (the clutch). ``model``: :meth:`yield_model` (default normal).

        The response mean m_k and variance s_k² (in units of L_k) are the model's moments
        (:meth:`evotol.statistical.FirstOrderYield.moments`); an assembly response is a scalar (row z
        of the error twist), so P(|Δy_k| > L_k) = Φ((−1 − m_k)/s_k) + Φ((m_k − 1)/s_k) exactly
        (normal sources; moment-matched normal otherwise, ``model.exact``) -- the 3-D octant rule
        of :func:`evotol.statistical.miss_probability` is built for full-rank covariances and is off
        by up to ~1e-4 of the miss probability on this rank-one case.
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
        means the requirement is violated) and whether each tolerance lies in its process's range."""
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
        return {"cost": float(self.cost(ch, t)[0]), "normalised_error": ne, "holds_requirement": bool(ne <= 1 + 1e-9),
                "outside_process_range": outside}

    def describe(self) -> str:
        lines = [f"ProcessProblem: {self.robot.name}, {self.n_sources} sources, {self.n_combinations} process combinations, "
                 f"measure {self.requirement.measure}"]
        for n in self.names:
            lines.append(f"  {n}: " + "; ".join(f"{p.name} [{p.lower:.3g}, {p.upper:.3g}] {p.cost!r}"
                                              + (f" + {p.fixed_cost:g}" if p.fixed_cost else "") for p in self.processes[n]))
        return "\n".join(lines)

    __repr__ = describe


def assembly_problem(assembly, tolerances: Mapping[str, Tolerance] | None = None, measure: str = "worst_case", *,
                     processes: Mapping[str, Sequence[Process]] | None = None, **requirement):
    """"Every response of an assembly within its limit" (see :mod:`robots.assembly`): a
    :class:`ToleranceProblem` when ``tolerances`` are given, a :class:`ProcessProblem` when
    ``processes`` are."""
    req = Requirement(position=1.0, measure=measure, **requirement)
    if (tolerances is None) == (processes is None):
        raise ValidationError("assembly_problem", "tolerances/processes", "exactly one of tolerances= or processes=")
    if processes is not None:
        return ProcessProblem(assembly, processes, req, assembly.response_poses)
    return ToleranceProblem(assembly, tolerances, req, assembly.response_poses)


# --- results -----------------------------------------------------------------------------------------
@dataclass
class ProcessResult:
    """A process choice and tolerances (SI), with its cost and how it was found."""

    method: str
    processes: dict[str, str]
    tolerances: dict[str, float]
    cost: float
    feasible: bool
    normalised_error: float
    seconds: float = 0.0
    n_nodes: int | None = None
    n_convex_solves: int | None = None
    n_combinations: int | None = None
    certificate: dict | None = None
    history: list | None = field(default=None, repr=False)

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in ("method", "processes", "tolerances", "cost", "feasible", "normalised_error",
                                            "seconds", "n_nodes", "n_convex_solves", "n_combinations", "certificate")}
        return {k: v for k, v in d.items() if v is not None}

    def table(self, problem: ProcessProblem, unit: float = 1e-3, unit_name: str = "mm") -> pd.DataFrame:
        ch = problem.choice_index(self.processes)
        t = np.array([self.tolerances[n] for n in problem.names])
        return pd.DataFrame({"source": problem.names, "process": [self.processes[n] for n in problem.names],
                             f"tolerance ({unit_name})": t / unit,
                             "cost": [float(problem.processes[n][k].total(t[j])) for j, (n, k) in enumerate(zip(problem.names, ch))]})


def _result(pp: ProcessProblem, method: str, choice, t, t0: float, **kw) -> ProcessResult:
    t = np.asarray(t, dtype=float)
    ne = float(pp.normalised_error(t)[0])
    ok = bool(ne <= 1 + 1e-7 and pp.in_ranges(choice, t)[0])
    return ProcessResult(method, pp.choice_names(choice), dict(zip(pp.names, t.tolist())), float(pp.cost(choice, t)[0]),
                         ok, ne, seconds=time.perf_counter() - t0, **kw)


# --- exact: branch and bound ---------------------------------------------------------------------------
def _multipliers(sub: ToleranceProblem, rows: ConstraintRows, t: np.ndarray, active_tol: float = 1e-6):
    """KKT multipliers (λ on linear rows, μ on quadratic rows) of a solved subproblem, by NNLS."""
    grad = sub.dcost(t)
    ga = rows.A @ t if rows.A.shape[0] else np.zeros(0)
    gb = rows.B @ t ** 2 if rows.B.shape[0] else np.zeros(0)
    act_a = np.flatnonzero(ga >= 1 - active_tol)
    act_b = np.flatnonzero(gb >= 1 - 2 * active_tol)
    interior = (t > sub.lower * (1 + 1e-9)) & (t < sub.upper * (1 - 1e-9))
    M = np.concatenate([rows.A[act_a].T, (2 * rows.B[act_b] * t).T], axis=1)[interior]
    lam, mu = np.zeros(rows.A.shape[0]), np.zeros(rows.B.shape[0])
    if M.shape[0] and M.shape[1]:
        coef, _ = nnls(M, -grad[interior], maxiter=50 * M.shape[1])
        lam[act_a], mu[act_b] = coef[:act_a.size], coef[act_a.size:]
    elif act_a.size + act_b.size:  # every source at a bound: any positive direction is a valid multiplier
        lam[act_a], mu[act_b] = 1.0, 1.0
    return lam, mu


class _DualTables:
    """Per (scale s, source j, process p) inner minima of the Lagrangian, for node bounds."""

    def __init__(self, pp: ProcessProblem, rows: ConstraintRows, scales: np.ndarray):
        self.pp, self.rows, self.scales = pp, rows, scales
        self.tables: list[tuple[np.ndarray, np.ndarray]] = []   # (M (s, j, p), offset (s,))

    def add(self, lam: np.ndarray, mu: np.ndarray, scales: np.ndarray | None = None) -> None:
        pp, s = self.pp, (self.scales if scales is None else np.asarray(scales, dtype=float))
        w = self.rows.A.T @ lam if lam.size else np.zeros(pp.n_sources)
        v = self.rows.B.T @ mu if mu.size else np.zeros(pp.n_sources)
        P = pp.lo.shape[1]
        M = np.full((s.size, pp.n_sources, P), np.inf)
        for j, n in enumerate(pp.names):
            for k, p in enumerate(pp.processes[n]):
                W, V = s * w[j], s * v[j]
                lo, hi = np.full(s.size, p.lower), np.full(s.size, p.upper)

                def deriv(t):
                    return p.cost.dcost(t) + W + 2 * V * t

                a, b = lo.copy(), hi.copy()
                for _ in range(60):
                    mid = np.sqrt(a * b)
                    neg = deriv(mid) < 0
                    a, b = np.where(neg, mid, a), np.where(neg, b, mid)
                t = np.sqrt(a * b)
                t = np.where(deriv(lo) >= 0, lo, np.where(deriv(hi) <= 0, hi, t))
                M[:, j, k] = p.total(t) + W * t + V * t ** 2
        self.tables.append((M, s * (lam.sum() + mu.sum())))

    def bound(self, fixed: Sequence[int]) -> float:
        d = len(fixed)
        best = -np.inf
        for M, off in self.tables:
            val = -off
            if d:
                val = val + M[:, np.arange(d), np.asarray(fixed)].sum(axis=1)
            if d < M.shape[1]:
                val = val + M[:, d:, :].min(axis=2).sum(axis=1)
            best = max(best, float(np.max(val)))
        return best


@single_threaded_blas
def allocate_process_optimum(pp: ProcessProblem, method: str = "branch_and_bound", *, rtol: float = 1e-7,
                             incumbent: ProcessResult | None = None) -> ProcessResult:
    """Exact minimum-cost process choice and tolerances (see the module docstring).

    method: ``"branch_and_bound"`` or ``"enumerate"`` (every combination's convex optimum).
    rtol: a node is pruned when its bound >= incumbent × (1 − rtol).
    """
    if method not in ("branch_and_bound", "enumerate"):
        raise ValidationError("method", method, "'branch_and_bound' or 'enumerate'")
    t0 = time.perf_counter()
    rows = ConstraintRows(pp.base)
    S = pp.n_sources
    state = {"cost": np.inf, "choice": None, "t": None, "cert": None, "solves": 0, "nodes": 0}
    lo_min = np.nanmin(pp.lo, axis=1)

    def tight_violation(fixed) -> float:
        d = len(fixed)
        t = lo_min.copy()
        if d:
            t[:d] = pp.lo[np.arange(d), np.asarray(fixed)]
        return float(rows.violation(t[None])[0])

    def solve_leaf(choice):
        sub = pp.subproblem(choice)
        state["solves"] += 1
        r = allocate_optimum(sub)
        if not r.feasible:
            return None
        cost = r.cost + pp.fixed_cost(choice)
        return cost, r.t, r.certificate, sub

    tables = None
    if method == "branch_and_bound":
        tables = _DualTables(pp, rows, np.geomspace(1e-4, 1e4, 81))
        # λ = 0: the cheapest tolerance per source, ignoring the requirement (prunes everything when
        # the requirement is loose and the leaf multipliers are all zero)
        tables.add(np.zeros(rows.A.shape[0]), np.zeros(rows.B.shape[0]), scales=[1.0])

    def offer(choice, leaf):
        cost, t, cert, sub = leaf
        if tables is not None:
            lam, mu = _multipliers(sub, rows, t)
            if lam.sum() + mu.sum() > 0:
                tables.add(lam, mu)
        if cost < state["cost"]:
            state.update(cost=cost, choice=np.array(choice), t=t, cert=cert)

    if incumbent is not None:
        ch = pp.choice_index(incumbent.processes)
        leaf = solve_leaf(ch)
        if leaf is not None:
            offer(ch, leaf)
    pruned_bounds = []
    if method == "enumerate":
        for choice in itertools.product(*[range(k) for k in pp.n_processes]):
            state["nodes"] += 1
            if tight_violation(list(choice)) > FEAS_TOL:
                continue
            leaf = solve_leaf(choice)
            if leaf is not None:
                offer(choice, leaf)
    else:
        # a first incumbent: the cheapest feasible processes (gives the first multipliers)
        if state["choice"] is None:
            try:
                ch = cheapest_feasible_processes(pp, rows)
            except ValidationError:
                ch = None
            if ch is not None:
                leaf = solve_leaf(ch)
                if leaf is not None:
                    offer(ch, leaf)

        def visit(fixed):
            state["nodes"] += 1
            if tight_violation(fixed) > FEAS_TOL:
                return
            if len(fixed) == S:
                if state["choice"] is not None and tuple(state["choice"]) == tuple(fixed):
                    return
                leaf = solve_leaf(fixed)
                if leaf is not None:
                    offer(fixed, leaf)
                return
            kids = [fixed + [k] for k in range(pp.n_processes[len(fixed)])]
            bounds = [tables.bound(c) if tables.tables else -np.inf for c in kids]
            for b, c in sorted(zip(bounds, kids), key=lambda x: x[0]):
                b = tables.bound(c) if tables.tables else -np.inf   # tables may have grown
                if b >= state["cost"] * (1 - rtol):
                    pruned_bounds.append(b)
                    continue
                visit(c)

        visit([])
    if state["choice"] is None:
        raise ValidationError("processes", pp.describe(), "at least one process choice that can hold the requirement")
    cert = {"leaf_gap": state["cert"].get("gap"), "leaf_kkt_residual": state["cert"].get("kkt_residual"),
            "incumbent": state["cost"], "rtol": rtol,
            "smallest_pruned_bound": float(min(pruned_bounds)) if pruned_bounds else None,
            "proof": ("every combination's convex optimum was computed" if method == "enumerate" else
                      "every unexplored node has a Lagrange-dual lower bound >= incumbent·(1 − rtol) or an infeasible tightest design")}
    return _result(pp, f"exact ({method.replace('_', ' ')})", state["choice"], state["t"], t0, n_nodes=state["nodes"],
                   n_convex_solves=state["solves"], n_combinations=pp.n_combinations, certificate=cert)


# --- baselines ------------------------------------------------------------------------------------------
def cheapest_feasible_processes(pp: ProcessProblem, rows: ConstraintRows | None = None) -> np.ndarray:
    """Per source the cheapest process (lowest cost at its loosest tolerance); while even the
    tightest tolerances of that choice cannot hold the requirement, move the source with the
    largest tightest-tolerance effect to its next finer process (smaller lower limit)."""
    rows = rows or ConstraintRows(pp.base)
    S = pp.n_sources
    choice = np.array([int(np.argmin([float(p.total(p.upper)) for p in pp.processes[n]])) for n in pp.names])
    sens = np.max(np.concatenate([rows.A, np.sqrt(rows.B)], axis=0), axis=0) if rows.n_rows else np.ones(S)
    for _ in range(int(pp.n_processes.sum())):
        t = pp.lo[np.arange(S), choice]
        if rows.violation(t[None])[0] <= FEAS_TOL:
            return choice
        order = np.argsort(-sens * t)
        for j in order:
            finer = [k for k, p in enumerate(pp.processes[pp.names[j]]) if p.lower < t[j]]
            if finer:
                # the cheapest (at its own loosest tolerance) of the processes that go finer
                choice[j] = min(finer, key=lambda k: float(pp.processes[pp.names[j]][k].total(pp.processes[pp.names[j]][k].upper)))
                break
        else:
            break
    raise ValidationError("processes", pp.describe(), "processes fine enough to hold the requirement")


@single_threaded_blas
def allocate_process_baselines(pp: ProcessProblem) -> dict[str, ProcessResult]:
    """Sensitivity rule and Lagrange closed form on the cheapest feasible processes."""
    out = {}
    t0 = time.perf_counter()
    choice = cheapest_feasible_processes(pp)
    sub = pp.subproblem(choice)
    for key, fn in (("sensitivity", allocate_sensitivity), ("lagrange", allocate_lagrange)):
        t1 = time.perf_counter()
        r = fn(sub)
        res = _result(pp, f"{r.method} on the cheapest feasible processes", choice, r.t, t1)
        res.seconds += t1 - t0
        out[key] = res
    return out


# --- GA ------------------------------------------------------------------------------------------------
def _decode(pp: ProcessProblem, X: np.ndarray):
    k = np.clip(np.floor(X).astype(int), 0, pp.n_processes - 1)
    u = np.clip(X - k, 0.0, 1.0)
    idx = np.arange(pp.n_sources)
    lo, hi = pp.lo[idx, k], pp.hi[idx, k]
    return k, lo * (hi / lo) ** u, lo, hi


def _encode(k, T, lo, hi):
    span = np.log(hi / lo)
    u = np.where(span > 0, np.log(np.clip(T, lo, hi) / lo) / np.where(span > 0, span, 1.0), 0.0)
    return k + np.clip(u, 0.0, 1 - 1e-12)


def _repair(pp, rows, X, iters: int = 25):
    k, T, lo, hi = _decode(pp, X)
    for _ in range(iters):
        ne = rows.normalised_error(T)
        Tn = np.clip(T / ne[:, None], lo, hi)
        if np.allclose(Tn, T, rtol=1e-13, atol=0):
            break
        T = Tn
    return _encode(k, T, lo, hi)


class _ProcessRepair(Repair):
    """Scale every design's tolerances onto the constraint (see :func:`_repair`)."""

    def __init__(self, pp: ProcessProblem, rows: ConstraintRows):
        super().__init__()
        self.pp, self.rows = pp, rows

    def _do(self, problem, X, **kwargs):
        return _repair(self.pp, self.rows, X)


class _ProcessGAProblem(Problem):
    """One gene per source (process index + position in its range): cost, one constraint max error/bound − 1."""

    def __init__(self, pp: ProcessProblem):
        super().__init__(n_var=pp.n_sources, n_obj=1, n_ieq_constr=1, xl=np.zeros(pp.n_sources),
                         xu=pp.n_processes - 1e-9)
        self.pp = pp

    def _evaluate(self, X, out, *args, **kwargs):
        k, T, _, _ = _decode(self.pp, X)
        out["F"] = self.pp.cost(k, T)[:, None]
        out["G"] = (self.pp.normalised_error(T) - 1)[:, None]


class _ProcessFrontProblem(Problem):
    """Two objectives on the GA's encoding: cost and either the normalised worst-case/RSS error
    (``objective="error"``) or the miss probability 1 − yield (``objective="yield"``, see
    :meth:`ProcessProblem.assembly_yield`)."""

    def __init__(self, pp: ProcessProblem, objective: str, yield_model=None):
        super().__init__(n_var=pp.n_sources, n_obj=2, xl=np.zeros(pp.n_sources), xu=pp.n_processes - 1e-9)
        self.pp, self.objective, self.yield_model = pp, objective, yield_model

    def second(self, T) -> np.ndarray:
        if self.objective == "yield":
            return 1.0 - self.pp.assembly_yield(T, self.yield_model)
        return self.pp.normalised_error(T)

    def _evaluate(self, X, out, *args, **kwargs):
        k, T, _, _ = _decode(self.pp, X)
        out["F"] = np.column_stack([self.pp.cost(k, T), self.second(T)])


class _History(Callback):
    """Best feasible cost after every generation (NaN before the first feasible design)."""

    def __init__(self):
        super().__init__()
        self.costs: list[float] = []

    def notify(self, algorithm):
        opt = algorithm.opt
        self.costs.append(float(opt.get("F")[0, 0]) if opt.get("CV")[0, 0] <= 0 else float("nan"))


@single_threaded_blas
def allocate_process_ga(pp: ProcessProblem, *, pop_size: int = 60, n_gen: int = 100, seed: int = 0,
                        repair: bool = True) -> ProcessResult:
    """pymoo GA over process choices and tolerances (encoding and repair: module docstring)."""
    from pymoo.algorithms.soo.nonconvex.ga import GA
    from pymoo.optimize import minimize

    t0 = time.perf_counter()
    rows = ConstraintRows(pp.base)
    hist = _History()
    alg = GA(pop_size=pop_size, repair=_ProcessRepair(pp, rows) if repair else None, eliminate_duplicates=True)
    res = minimize(_ProcessGAProblem(pp), alg, ("n_gen", n_gen), seed=seed, verbose=False, callback=hist)
    if res.X is None:
        raise ValidationError("processes", pp.describe(), "a feasible design found by the GA (raise n_gen / pop_size)")
    k, T, _, _ = _decode(pp, np.atleast_2d(res.X))
    return _result(pp, "GA (pymoo, one gene per source)", k[0], T[0], t0, history=hist.costs)


FRONT_OBJECTIVES = ("error", "yield")


@single_threaded_blas
def process_front(pp: ProcessProblem, *, objective: str = "error", pop_size: int = 60, n_gen: int = 100,
                  seed: int = 0, distribution="normal") -> pd.DataFrame:
    """NSGA-II front (:func:`evotol.allocators.nsga.run_nsga2`) of cost vs. a second objective:

    * ``objective="error"``: the normalised error (max error / bound, the problem's measure);
    * ``objective="yield"``: the miss probability 1 − yield of the first-order statistical model
      (``distribution`` per source, default normal with t = 3σ; :meth:`ProcessProblem.assembly_yield`).

    Returns one row per front member (cost, the objective, the yield when asked, processes, t in m)
    sorted by cost.
    """
    from evotol.allocators.nsga import run_nsga2

    if objective not in FRONT_OBJECTIVES:
        raise ValidationError("objective", objective, f"one of {FRONT_OBJECTIVES}")
    model = pp.yield_model(distribution) if objective == "yield" else None
    prob = _ProcessFrontProblem(pp, objective, model)
    algo = run_nsga2(prob, pop_size=pop_size, n_gen=n_gen, seed=seed)
    X, F = algo.opt.get("X"), algo.opt.get("F")
    k, T, _, _ = _decode(pp, np.atleast_2d(X))
    df = pd.DataFrame({"cost": F[:, 0]})
    if objective == "yield":
        df["miss_probability"] = F[:, 1]
        df["yield"] = 1.0 - F[:, 1]
    else:
        df["normalised_error"] = F[:, 1]
    for j, n in enumerate(pp.names):
        df[f"{n}_process"] = [pp.processes[n][i].name for i in k[:, j]]
        df[f"{n}_t"] = T[:, j]
    return df.sort_values("cost", ignore_index=True)

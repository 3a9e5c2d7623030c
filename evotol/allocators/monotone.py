"""Global optimum bracket of a monotone allocation problem: polyblock outer approximation.

With joint clearances the worst case W(t) (:mod:`evotol.measures.clearances`) is not convex, so the
certified optimum's cutting planes do not apply. What always holds is **monotonicity**: every
cost model decreases with its tolerance and W never decreases when a tolerance grows. Minimising
a decreasing cost over the normal set G = {t : W(t) <= E} (t in G and t' <= t imply t' in G) is a
*monotonic optimisation* problem (Tuy 2000, "Monotonic optimization: problems and solution
approaches", SIAM J. Optim. 11(2); Tuy, Al-Khayyal & Thach 2005), solved by the polyblock
algorithm, here in x = log t:

  * a polyblock P = union of boxes [lo, v] over its vertices v contains G; the cheapest vertex
    gives a **proven lower bound** on the optimal cost (cost decreases, so min over [lo, v] is at v);
  * the cheapest vertices are projected onto the boundary of G along the segment lo -> v
    (bisection; W is monotone along it): the inner point is feasible (an incumbent), and the
    outer point z has W(z) > E attained by explicit errors (the engine's attained value is a
    true lower bound of W), so no t > z is feasible: every vertex v > z is replaced by the n
    vertices v + (z_i - v_i) e_i, and vertices dominated by others are dropped;
  * vertices whose cost is not below the incumbent's are pruned, and each box is reduced by the
    incumbent: a design x <= v cheaper than it has c_i(x_i) < ub - sum_{j != i} c_j(v_j), which
    gives a lower corner l(v) > lo (closed form through the one-variable costs); a box whose
    lower corner misses E is dropped, and the projection runs along l(v) -> v (Tuy, Al-Khayyal &
    Thach 2005's reduction, lower side).

The result is a bracket [lower bound, cost of the best feasible design found]; its relative gap
is reported in the certificate (a loose bracket is reported as such, never as optimal). A
given incumbent (e.g. the GA's design) tightens the pruning.

The algorithm (:func:`polyblock_search`) runs on any :class:`MonotoneProblem`: log bounds, a batched
feasibility check, the cost and the cost per variable. :func:`polyblock` builds one from a
:class:`ToleranceProblem` (feasibility by its exact measure, as above);
:mod:`evotol.allocators.iso9283_monotone` from the ISO 9283 AP/RP problem.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from evotol.measures.constraints import ExactRows
from evotol.errors import ValidationError, is_integer, is_real
from evotol.core.problem import ToleranceProblem
from evotol.core.plausibility import issue
from evotol.measures import feasibility
from evotol.core.result import AllocationResult, make_result


def new_vertices(V: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The vertices a cut at ``z`` keeps and the new ones it proposes, before the dominance check.

    Parameters
    ----------
    V : (M, n) ndarray
        The polyblock's vertices (log tolerances).
    z : (n,) ndarray
        The cut point: no design above it is feasible.

    Returns
    -------
    tuple of ndarray or None
        ``keep`` (the vertices not above ``z``) and ``cand`` (unique ``v + (z_i - v_i) e_i`` of every vertex
        ``v > z``, sorted); None when no vertex is above ``z``.
    """
    above = np.all(V > z, axis=1)
    if not above.any():
        return None
    keep, up = V[~above], V[above]
    n = V.shape[1]
    cand = np.repeat(up, n, axis=0)
    k = np.tile(np.arange(n), len(up))
    cand[np.arange(len(cand)), k] = z[k]
    return keep, np.unique(cand, axis=0)


def _cut(V: np.ndarray, z: np.ndarray, chunk_bytes: int = 1 << 24) -> np.ndarray:
    """The polyblock's vertices after removing {x > z}: every vertex v > z is replaced by
    v + (z_i - v_i) e_i (i = 1..n), and new vertices dominated by another vertex are dropped.

    Which vertices can dominate a new one ``c = v + (z_i - v_i) e_i`` (``u >= c``, ``u != c``): ``u_j >= v_j > z_j``
    for every ``j != i`` and ``u_i >= z_i``. A kept vertex (not above ``z``) then has ``u_i = z_i``: it lies on the
    cut's face (rare; checked one by one). A new vertex ``u = w + (z_k - w_k) e_k`` needs ``k = i`` and
    ``w_j >= v_j`` for every ``j != i``: so ``v``'s new vertex in ``i`` is dominated exactly when another vertex
    above ``z`` is below ``v`` in coordinate ``i`` alone (or nowhere, with another coordinate differing). One
    pass over the pairs of vertices above ``z`` counts, per pair, the coordinates where ``w < v`` -- all ``n``
    coordinates' groups at once. The vertices kept are those of comparing every pair (a test checks it on
    random cuts with ties); the 49 cuts of the UR5 study's 36-source search (up to 3 341 vertices above ``z``)
    take 1.5 s instead of 35 s.

    Parameters
    ----------
    V : (M, n) ndarray
        The polyblock's vertices (log tolerances), none dominating another.
    z : (n,) ndarray
        The cut point: no design above it is feasible.
    chunk_bytes : int
        Size of one block of pair comparisons (bytes of booleans).

    Returns
    -------
    (M', n) ndarray
        The vertices not above ``z``, then the new ones not dominated (unique, sorted).
    """
    above = np.all(V > z, axis=1)
    if not above.any():
        return V
    keep, up = V[~above], np.unique(V[above], axis=0)
    K, n = up.shape
    kill = np.zeros((K, n), bool)                              # kill[v, i]: v's new vertex in i is dominated
    step = max(1, chunk_bytes // (K * n))
    for s in range(0, K, step):
        w = up[s:s + step]                                                   # the would-be dominators
        less = w[:, None, :] < up[None, :, :]                                # (k, K, n): w_j < v_j
        n_less = less.sum(2)
        n_diff = (w[:, None, :] != up[None, :, :]).sum(2)
        a, b = np.nonzero((n_less == 1) & (n_diff > 1))       # w below v in one coordinate i: w^i > v^i
        kill[b, np.argmax(less[a, b], axis=1)] = True
        a, b = np.nonzero((n_less == 0) & (n_diff > 0))       # w >= v, w != v (no such pair without dominance)
        np.logical_or.at(kill, b, (n_diff[a, b] > 1)[:, None] | (w[a] == up[b]))   # w^i > v^i unless only i differs
    low = keep <= z
    face = (low.sum(1) == 1) & np.any(low & (keep == z), axis=1)
    for u in keep[face]:                                      # a kept vertex with u_i = z_i
        i = int(np.argmax(u <= z))
        c = up.copy()
        c[:, i] = z[i]
        kill[:, i] |= np.all(u >= c, axis=1) & ~np.all(u == c, axis=1)
    vi, ii = np.nonzero(~kill)
    cand = up[vi]
    cand[np.arange(len(cand)), ii] = z[ii]
    return np.concatenate([keep, np.unique(cand, axis=0)])


def check_monotone_options(*, max_evaluations=4000, rel_gap=1e-2, batch=16) -> None:
    """The polyblock's settings checked before any work (a ``batch`` of 0 ended in an argmin of an empty sequence, a
    text ``rel_gap`` in a ``TypeError``, after the study's other methods had run).

    Parameters
    ----------
    max_evaluations, rel_gap, batch
        As :func:`polyblock_search`.

    Raises
    ------
    evotol.errors.ValidationError
        ``max_evaluations`` or ``batch`` not an integer of at least 1, ``rel_gap`` not a finite number above 0.
    """
    for field, value in (("max_evaluations", max_evaluations), ("batch", batch)):
        if not is_integer(value, 1):
            raise ValidationError(field, value, "an integer >= 1")
    if not (is_real(rel_gap) and 0 < float(rel_gap) < np.inf):
        raise ValidationError("rel_gap", rel_gap, "a number > 0 (the relative gap at which the bracket stops)")


@dataclass(frozen=True)
class MonotoneProblem:
    """A monotone minimisation in log variables, the polyblock's input (module docstring): minimise ``cost(x)``
    over ``lo <= x <= hi`` subject to ``feasible(x)``, where ``cost`` decreases and feasibility can only be lost
    when a variable grows (the feasible set is normal: x feasible and x' <= x imply x' feasible).

    Parameters
    ----------
    lo, hi : (n,) ndarray
        Bounds of the variables (log tolerances, log of m or rad).
    feasible : callable
        ``feasible(X) -> (k,) bool`` for designs ``X`` (k, n): whether each meets the requirement.
    cost : callable
        ``cost(X) -> (k,)``: the cost of each design (cost models' unit), ``const + Σ_i var_costs(X)[:, i]``.
    var_costs : callable
        ``var_costs(X) -> (k, n)``: the cost carried by each variable, ``c_i(x_i)``, decreasing (the box reduction).
    """

    lo: np.ndarray
    hi: np.ndarray
    feasible: Callable[[np.ndarray], np.ndarray]
    cost: Callable[[np.ndarray], np.ndarray]
    var_costs: Callable[[np.ndarray], np.ndarray]


def polyblock_search(mp: MonotoneProblem, *, upper_bound: float = np.inf, spent: int = 0, rel_gap: float = 1e-2,
                     max_evaluations: int = 4000, batch: int = 16, bisections: int = 14, max_vertices: int = 20000,
                     max_seconds: float | None = None, max_new_vertices: int | None = None,
                     reduce_upper: bool = False) -> dict:
    """The polyblock algorithm on a generic monotone problem (module docstring).

    Parameters
    ----------
    mp : MonotoneProblem
        The problem in log variables.
    upper_bound : float
        The cost of a feasible design already known (the incumbent's; cost units), inf without one.
    spent : int
        Evaluations already spent (counted against ``max_evaluations``).
    rel_gap, max_evaluations, batch, bisections, max_vertices, max_seconds
        As :func:`polyblock`; ``max_seconds`` is checked once per round and after every cut.
    max_new_vertices : int or None
        Stop before a cut that would propose more new vertices than this (one cut's dominance check grows with
        their number times the vertices kept: in 54 dimensions one cut of 1 947 vertices took 16 s); None: no limit.
    reduce_upper : bool
        Start from the reduced upper corner (:func:`upper_reduction`) instead of ``hi``.

    Returns
    -------
    dict
        ``lower_bound``, ``upper_bound``, ``x`` (the best feasible log design found, or None where none beat
        ``upper_bound``), ``gap``, ``evaluations``, ``vertices``, ``rounds``, ``converged`` and ``stop`` (what ended
        the search: ``"gap"``, ``"loosest design"``, ``"evaluations"``, ``"vertices"``, ``"time"``, ``"cut size"``).
    """
    check_monotone_options(max_evaluations=max_evaluations, rel_gap=rel_gap, batch=batch)
    t0 = time.perf_counter()
    lo, hi, cost = mp.lo, mp.hi, mp.cost

    def lower_corner(v, cv):
        """Reduction of the boxes [lo, v] by the incumbent: a design x <= v cheaper than ub has
        c_i(x_i) < ub - sum_{j != i} c_j(v_j) (every other c_j(x_j) >= c_j(v_j)), so x_i is above
        the root of that equation (bisection on the decreasing one-variable costs)."""
        r = ub - cv[:, None] + mp.var_costs(v)
        a, b = np.broadcast_to(lo, v.shape).copy(), v.copy()
        for _ in range(50):
            m = 0.5 * (a + b)
            dear = mp.var_costs(m) >= r
            a, b = np.where(dear, m, a), np.where(dear, b, m)
        return np.minimum(a, v)

    n_eval, best_x, ub = spent, None, upper_bound
    V = hi[None].copy()
    if mp.feasible(V)[0]:                             # the loosest design already holds
        c = float(cost(V)[0])
        return {"lower_bound": c, "upper_bound": c, "x": V[0], "gap": 0.0, "evaluations": 1, "vertices": 1,
                "rounds": 0, "converged": True, "stop": "loosest design"}
    n_eval += 1
    if reduce_upper:
        V = upper_reduction(mp)[None]
        n_eval += 31 * len(lo)
    rounds, stop = 0, None
    lb = float(cost(V)[0])
    while True:
        cV = cost(V)
        alive = cV < ub
        V, cV = V[alive], cV[alive]
        lb = float(cV.min()) if len(V) else ub
        if ub < np.inf and (ub - lb) <= rel_gap * ub or not len(V):
            stop = "gap"
            break
        stop = stop or ("evaluations" if n_eval >= max_evaluations else "vertices" if len(V) > max_vertices else
                        "time" if max_seconds and time.perf_counter() - t0 > max_seconds else None)
        if stop:
            break
        rounds += 1
        pick = np.argsort(cV)[:batch]
        v = V[pick]
        base = lower_corner(v, cV[pick]) if np.isfinite(ub) else np.broadcast_to(lo, v.shape).copy()
        # a box [base, v] whose lower corner already misses E holds no design cheaper than ub
        empty = ~mp.feasible(base)
        n_eval += len(v)
        if empty.any():
            V = np.delete(V, pick[empty], axis=0)
            v, base = v[~empty], base[~empty]
            if not len(v):
                continue
        # bisection on lambda in [0, 1] along base -> v (monotone), all picked vertices at once
        a, b = np.zeros(len(v)), np.ones(len(v))
        for _ in range(bisections):
            m = 0.5 * (a + b)
            ok = mp.feasible(base + m[:, None] * (v - base))
            n_eval += len(v)
            a, b = np.where(ok, m, a), np.where(ok, b, m)
        inner = base + a[:, None] * (v - base)
        outer = base + b[:, None] * (v - base)
        ci = cost(inner)
        i = int(np.argmin(ci))
        if ci[i] < ub:
            best_x, ub = inner[i], float(ci[i])
        # cut every vertex strictly above an outer point (no design there is feasible)
        for z in outer:
            if max_new_vertices and np.all(V > z, axis=1).sum() * len(z) > max_new_vertices:
                stop = "cut size"                     # the polyblock without this cut still holds G
                break
            V = _cut(V, z)
            V = V[cost(V) < ub]
            if max_seconds and time.perf_counter() - t0 > max_seconds:   # fewer cuts: the polyblock still holds G
                break
    gap = (ub - lb) / ub if np.isfinite(ub) else np.inf
    return {"lower_bound": lb, "upper_bound": ub, "x": best_x, "gap": gap, "evaluations": int(n_eval),
            "vertices": int(len(V)), "rounds": rounds, "converged": bool(gap <= rel_gap), "stop": stop}


def upper_reduction(mp: MonotoneProblem, steps: int = 30) -> np.ndarray:
    """The upper side of Tuy, Al-Khayyal & Thach 2005's box reduction: no feasible design exceeds ``b_i`` in
    variable ``i``, where ``b_i`` is the outer end of a bisection on the design with every other variable at its
    lower bound (``x`` feasible implies that design, which is ``<= x``, feasible: the set is normal).

    Parameters
    ----------
    mp : MonotoneProblem
        The problem (its ``feasible`` called ``steps + 1`` times on ``n`` designs).
    steps : int
        Bisection steps in each log variable.

    Returns
    -------
    (n,) ndarray
        The reduced upper corner, ``<= hi`` (``hi`` where that design holds at ``hi_i``).
    """
    n = len(mp.lo)
    idx = np.arange(n)

    def axis_designs(x):
        X = np.repeat(mp.lo[None], n, 0)
        X[idx, idx] = x
        return X

    a, b = mp.lo.copy(), mp.hi.copy()
    for _ in range(steps):
        m = 0.5 * (a + b)
        ok = mp.feasible(axis_designs(m))
        a, b = np.where(ok, m, a), np.where(ok, b, m)
    return np.where(mp.feasible(axis_designs(mp.hi)), mp.hi, b)


def polyblock(problem: ToleranceProblem, *, incumbent=None, rel_gap: float = 1e-2, max_evaluations: int = 4000,
              batch: int = 16, bisections: int = 14, max_vertices: int = 20000, max_seconds: float | None = None) -> dict:
    """Bracket of the minimum cost of a :class:`ToleranceProblem` (module docstring): :func:`polyblock_search` on
    its free log tolerances, feasibility by its exact measure. Returns {"lower_bound", "upper_bound",
    "t" (best feasible design, SI, or None), "gap", "evaluations", "vertices", "rounds", "converged"}.
    ``incumbent``: a feasible design (SI) to start the upper bound from.

    Parameters
    ----------
    problem : ToleranceProblem
        The problem, judged by its exact measure (:class:`evotol.measures.constraints.ExactRows`).
    incumbent : mapping or array_like or None
        A design (m or rad per source); used as the first upper bound if it holds the
        requirement.
    rel_gap : float
        Stop when ``(upper − lower) <= rel_gap × upper`` (dimensionless).
    max_evaluations : int
        Stop after about this many design evaluations (checked once per round).
    batch : int
        Cheapest vertices projected per round.
    bisections : int
        Bisection steps of each projection onto the boundary of the feasible set.
    max_vertices : int
        Stop when the polyblock has more vertices.
    max_seconds : float or None
        Stop after this wall time (s); None: no limit.

    Returns
    -------
    dict
        ``lower_bound`` (proven, cost units), ``upper_bound`` (cost of ``t``; inf if none
        found), ``t`` ((n_sources,) best feasible design, m or rad, or None), ``gap`` (relative,
        inf without a design), ``evaluations``, ``vertices``, ``rounds``, ``converged``
        (``gap <= rel_gap``) and ``stop`` (:func:`polyblock_search`).
    """
    rows = ExactRows(problem)
    f = problem.free
    M, w = problem.variable_matrix, problem.cost_weight

    def design(X):
        return problem.full(np.exp(X))

    def var_costs(X):
        """Cost carried by each free variable at log-tolerances X (m, n): c_i(x_i)."""
        T = design(X)
        C = np.stack([problem.tolerances[nm].cost_of(T[:, j]) * w[j] for j, nm in enumerate(problem.names)], 1)
        return C @ M

    mp = MonotoneProblem(np.log(problem.lower[f]), np.log(problem.upper[f]),
                         feasible=lambda X: rows.violation(design(X)) <= 1e-9,
                         cost=lambda X: problem.cost(design(np.atleast_2d(X))), var_costs=var_costs)
    best_t, ub, spent = None, np.inf, 0
    if incumbent is not None:
        t_inc = problem.as_array(incumbent)
        if rows.violation(t_inc[None])[0] <= 1e-9:
            best_t, ub = t_inc, float(problem.cost(t_inc))
        spent = 1
    res = polyblock_search(mp, upper_bound=ub, spent=spent, rel_gap=rel_gap, max_evaluations=max_evaluations,
                           batch=batch, bisections=bisections, max_vertices=max_vertices, max_seconds=max_seconds)
    x = res.pop("x")
    return {**res, "t": best_t if x is None else design(x[None])[0]}


def allocate_monotone(problem: ToleranceProblem, *, budget: float | None = None, incumbent=None, rel_gap: float = 1e-2,
                      max_evaluations: int = 4000, batch: int = 16) -> AllocationResult:
    """Best design found with a proven lower bound on the optimal cost, for a problem whose measure
    is monotone but not convex (clearance sources): polyblock outer approximation (Tuy 2000).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem (tolerances in SI: m or rad).
    budget : None
        Accepted for the shape every allocator shares and must be None (the bracket is of the
        minimum cost at the requirement).
    incumbent : mapping or array or None
        A feasible design (SI) to start from.
    rel_gap : float
        Relative gap (1, dimensionless) between the design's cost and the lower bound at which
        the search stops.
    max_evaluations : int
        Largest number of designs evaluated.
    batch : int
        Designs evaluated per round.

    Returns
    -------
    evotol.core.result.AllocationResult
        The best design (SI) and its cost (cost models' unit); the certificate carries
        ``lower_bound``, ``gap`` (relative to the design's cost) and the polyblock's counts;
        ``result.verdict`` reads it (a gap above 1e-6 is reported as "not certified").

    Raises
    ------
    evotol.errors.ValidationError
        A ``budget`` that is not None, ``max_evaluations`` too few to find a feasible design, or a setting out of
        range (:func:`check_monotone_options`).
    evotol.errors.InfeasibleError
        Even every free tolerance at its lower bound misses the requirement.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import allocate_monotone
    >>> res = allocate_monotone(problem, rel_gap=0.05)         # a bracket [lower_bound, cost]
    >>> res.feasible, res.certificate["lower_bound"] <= 97.4264 <= res.cost
    (True, True)
    """
    t0 = time.perf_counter()
    if budget is not None:
        raise ValidationError("budget", budget, "None for allocate_monotone (it brackets the minimum cost at the "
                              "requirement; allocate_ga(problem, budget=...) gives the best accuracy at a budget)")
    check_monotone_options(max_evaluations=max_evaluations, rel_gap=rel_gap, batch=batch)
    problem.check_feasible()
    res = polyblock(problem, incumbent=incumbent, rel_gap=rel_gap, max_evaluations=max_evaluations, batch=batch)
    if res["t"] is None:
        raise ValidationError("max_evaluations", max_evaluations, "enough evaluations to find a feasible design")
    cert = {"lower_bound": res["lower_bound"], "gap": res["gap"],
            "solver": "polyblock (monotonic optimisation, Tuy 2000)", "evaluations": res["evaluations"],
            "vertices": res["vertices"], "rounds": res["rounds"], "converged": res["converged"]}
    t, ev, repair = feasibility.hold_to_rule(problem, res["t"], max_miss=np.inf)     # a search method: any miss
    return issue(make_result(problem, "optimum bracket (polyblock)", t, evaluation=ev, certificate=cert,
                             seconds=time.perf_counter() - t0, info=repair))

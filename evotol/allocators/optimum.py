"""Exact optimum of the convex allocation problem, with a certificate. The yardstick for the GA.

Minimum cost at a required accuracy::

    min Σ_j c_j(t_j)  s.t.  worst case: a_r·t <= 1 for every (pose, direction) row r,
                            or RSS: b_p·t² <= 1 for every pose p,   lower <= t <= upper.

With convex costs (exponential, power, reciprocal... on the bounds) this is a convex program.
It is solved by cutting planes: SLSQP on the current working rows (:mod:`evotol.measures.constraints`),
then an exact evaluation adds the rows it misses, until none is missing.

Certificate. Multipliers λ >= 0 of the (nearly) active rows are estimated by NNLS on the
stationarity condition ∇c(t*) + Σ λ_r ∇g_r(t*) = 0 over the free tolerances strictly inside their
bounds; the relative residual is the **KKT residual** (with no active row -- a cost with a
quality-loss term can have its optimum inside the requirement -- it is ``|∇c|·|t| / c`` over those
tolerances, the relative cost change of a unit relative change of t). For any λ >= 0 the Lagrange dual::

    q(λ) = Σ_j min_{lo_j <= t <= hi_j} [c_j(t) + w_j t + v_j t²] − Σ λ + (locked terms),
    w = Aᵀλ, v = Bᵀμ,

is a proven **lower bound** on the optimum (rows are true constraints, so dropping the others
only lowers it); each inner problem is one-dimensional and convex (solved by bisection on its
derivative). **gap** = (cost(t*) − q(λ)) / cost(t*).

Best accuracy at a fixed budget B (``budget=``): min s s.t. a_r·t <= s, b_p·t² <= s², Σ c_j(t_j) <= B.

Shared tolerances and asymmetric intervals: the program is solved over the free *variables* x
(t = full(x); a shared variable collects its members' row coefficients and costs), and the
worst-case rows are affine, a_r·t + a0_r <= 1 (offsets); the dual bound keeps the constants:
q(λ) = min_x [c(x) + Σ λ_r (a_r·t(x) + a0_r − 1)] (+ μ terms), still a proven lower bound.
"""
from __future__ import annotations

import time
import warnings

import numpy as np
from scipy.optimize import minimize, nnls

from evotol.allocators.sensitivity import sensitivity_design
from evotol.allocators.budget import check_budget
from evotol.allocators.monotone import allocate_monotone
from evotol.allocators.stack_dual import StackRows, dual_search, stack_rows
from evotol.allocators.workspace_refinement import allocate_on_workspace, check_refinable
from evotol.measures.constraints import ConstraintRows
from evotol.measures import feasibility
from evotol.errors import ConvergenceError, ValidationError
from evotol.core.problem import ToleranceProblem
from evotol.core.plausibility import issue
from evotol.core.result import AllocationResult, make_result
from evotol._runtime.blas_threads import single_threaded_blas


def _check_convex(problem: ToleranceProblem) -> None:
    seen = set()        # one check per (model, range): a stack of 5 000 dimensions shares one (1.8 s -> 0)
    for j in np.flatnonzero(~problem.locked & (problem.cost_weight > 0)):
        n = problem.names[j]
        tol = problem.tolerances[n]
        cm, w = tol.cost, tol.width_factor
        key = (id(cm), w * problem.lower[j], w * problem.upper[j])
        if key in seen:
            continue
        seen.add(key)
        if not cm.is_convex(w * problem.lower[j], w * problem.upper[j]):
            raise ValidationError(f"tolerances[{n!r}].cost", cm, f"a cost model convex on [{problem.lower[j]:.3g}, "
                                  f"{problem.upper[j]:.3g}] for the certified optimum (use allocate_ga instead)")


def _locked_part(problem: ToleranceProblem, M: np.ndarray, power: int) -> np.ndarray:
    """Row values of the locked tolerances: M[:, locked] @ t_locked**power (zeros if none)."""
    return problem.locked_part(M, power)


def _select(values: np.ndarray, k: int) -> np.ndarray:
    if values.size <= k:
        return np.arange(values.size)
    return np.argpartition(-values, k)[:k]


def _grow(kept: np.ndarray | None, values: np.ndarray, k: int) -> np.ndarray:
    """The working rows a solve hands SLSQP: the ``k`` largest ``values`` at the current design and every row
    ``kept`` from its earlier passes (the first pass: the ``k`` largest alone). Re-selecting alone can cycle:
    with two binding components one's rows crowd out the other's, whose variables then run to their upper
    bounds, and back; a growing set cannot. Rows are only appended to the working set during a solve, so the
    indices stay valid."""
    new = _select(values, k)
    return new if kept is None else np.union1d(kept, new)


def _min_1d(problem: ToleranceProblem, w: np.ndarray, v: np.ndarray) -> np.ndarray:
    """argmin over [lo, hi] of c_v(x) + w_v x + v_v x² for every free variable (bisection on the
    derivative); w, v are per source and are collected per variable."""
    f = np.flatnonzero(problem.free)
    lo, hi = problem.lower[f].copy(), problem.upper[f].copy()
    wv, vv = problem.to_variables(w), problem.to_variables(v)

    def deriv(t):
        return problem.variable_dcost(problem.full(t[None])[0]) + wv + 2 * vv * t

    d_lo, d_hi = deriv(lo), deriv(hi)
    a, b = lo.copy(), hi.copy()
    for _ in range(80):
        mid = 0.5 * (a + b)
        d = deriv(mid)
        a = np.where(d < 0, mid, a)
        b = np.where(d < 0, b, mid)
    t = 0.5 * (a + b)
    t = np.where(d_lo >= 0, lo, t)
    t = np.where(d_hi <= 0, hi, t)
    return t


def dual_bound(problem: ToleranceProblem, rows: ConstraintRows, lam: np.ndarray, mu: np.ndarray) -> float:
    """Lagrange dual value q(λ, μ) for linear rows A (λ) and quadratic rows B (μ): a lower bound.

    Parameters
    ----------
    problem : ToleranceProblem
        The problem (cost models and bounds).
    rows : ConstraintRows
        The working rows (``A``, ``A0``, ``B``).
    lam : numpy.ndarray, (n_linear_rows,)
        Multipliers λ >= 0 of the linear rows (cost units).
    mu : numpy.ndarray, (n_quadratic_rows,)
        Multipliers μ >= 0 of the quadratic rows (cost units).

    Returns
    -------
    float
        q(λ, μ) (cost units), a proven lower bound on the minimum cost subject to the rows.
    """
    f = problem.free
    w = rows.A.T @ lam if lam.size else np.zeros(problem.n_sources)
    v = rows.B.T @ mu if mu.size else np.zeros(problem.n_sources)
    tf = _min_1d(problem, w, v)
    t = problem.full(tf[None])[0]
    lag = problem.cost(t) - lam.sum() - mu.sum()
    if lam.size:
        lag += float(lam @ (rows.A @ t + rows.A0))
    if mu.size:
        lag += float(mu @ (rows.B @ t ** 2))
    return float(lag)


def certificate(problem: ToleranceProblem, rows: ConstraintRows, t: np.ndarray, active_tol: float = 1e-6) -> dict:
    """KKT residual and duality gap of design t on the working rows (see module docstring).

    Parameters
    ----------
    rows : ConstraintRows
        The working rows.
    active_tol : float
        A row counts as active when its value is >= 1 − active_tol (quadratic rows:
        1 − 2·active_tol) (dimensionless).

    Returns
    -------
    dict
        ``lower_bound`` (the dual bound, cost units), ``gap`` (relative duality gap),
        ``kkt_residual`` (relative), ``active_rows`` and ``working_rows`` (counts).
    """
    f = problem.free
    grad = problem.variable_dcost(t)
    ga = rows.A @ t + rows.A0 if rows.A.shape[0] else np.zeros(0)
    gb = rows.B @ t ** 2 if rows.B.shape[0] else np.zeros(0)
    act_a = np.flatnonzero(ga >= 1 - active_tol)
    act_b = np.flatnonzero(gb >= 1 - 2 * active_tol)
    tf = t[f]
    interior = (tf > problem.lower[f] * (1 + 1e-9)) & (tf < problem.upper[f] * (1 - 1e-9))
    M = np.concatenate([problem.to_variables(rows.A[act_a]).T,
                        problem.to_variables(2 * rows.B[act_b] * t).T], axis=1)[interior]
    rhs = -grad[interior]
    if M.shape[1] and M.shape[0]:
        coef, res = nnls(M, rhs, maxiter=50 * M.shape[1])
    else:
        coef, res = np.zeros(M.shape[1]), float(np.linalg.norm(rhs))
    lam = np.zeros(rows.A.shape[0])
    mu = np.zeros(rows.B.shape[0])
    lam[act_a] = coef[:act_a.size]
    mu[act_b] = coef[act_a.size:]
    cost = float(problem.cost(t))
    lb = dual_bound(problem, rows, lam, mu)
    if M.shape[1]:
        kkt = float(res / max(np.linalg.norm(rhs), 1e-300))
    else:   # no active row (a cost with a loss term can have its optimum inside): |∇c|·|t| / c
        kkt = float(res * np.linalg.norm(tf[interior]) / max(abs(cost), 1e-300))
    return {"lower_bound": lb, "gap": (cost - lb) / cost, "kkt_residual": kkt,
            "active_rows": int(act_a.size + act_b.size), "working_rows": int(rows.n_rows)}


def _solve_min_cost(problem, rows, t_start, max_rows, tol):
    f = np.flatnonzero(problem.free)
    hi = problem.upper[f]
    lo = problem.lower[f]
    c0 = max(float(problem.cost(t_start)), 1e-300)

    def T(y):
        return problem.full((y * hi)[None])[0]

    def obj(y):
        return problem.free_cost(T(y)) / c0

    def jac(y):
        return problem.variable_dcost(T(y)) * hi / c0

    t_cur = t_start.copy()
    sel_a = sel_b = None
    for _ in range(20):
        cons = []
        if rows.A.shape[0]:
            sel = sel_a = _grow(sel_a, rows.A @ t_cur + rows.A0, max_rows)
            A = rows.A[sel]
            Af, off = problem.to_variables(A) * hi, 1 - _locked_part(problem, A, 1) - rows.A0[sel]
            cons.append({"type": "ineq", "fun": lambda y, Af=Af, off=off: off - Af @ y, "jac": lambda y, Af=Af: -Af})
        if rows.B.shape[0]:
            sel = sel_b = _grow(sel_b, rows.B @ t_cur ** 2, max_rows)
            B = rows.B[sel]
            Bf = problem.to_variables(B) * hi ** 2
            off = 1 - _locked_part(problem, B, 2)
            cons.append({"type": "ineq", "fun": lambda y, Bf=Bf, off=off: off - Bf @ y ** 2,
                         "jac": lambda y, Bf=Bf: -2 * Bf * y})
        y0 = np.clip(t_cur[f] / hi, lo / hi, 1.0)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = minimize(obj, y0, jac=jac, bounds=list(zip(lo / hi, np.ones(len(f)))), constraints=cons,
                           method="SLSQP", options={"ftol": 1e-15, "maxiter": 1000})
        t_new = T(np.clip(res.x, lo / hi, 1.0))
        # rows outside the selection may now be violated: re-select and repeat
        if rows.violation(t_new[None])[0] <= tol:
            return t_new, res
        t_cur = t_new
    return t_new, res


@single_threaded_blas
def check_optimum(problem: ToleranceProblem, *, budget: float | None = None, refine: bool | dict = False) -> None:
    """The refusals of :func:`allocate_optimum` that need no solve, so that a study checks every
    method against its problem before the first one runs (issue 34 item 6).

    Parameters
    ----------
    budget : float or None
        The method's budget (cost units).
    refine : bool or dict
        The method's workspace refinement option.

    Raises
    ------
    evotol.errors.ValidationError
        ``budget`` or ``refine`` with clearance sources; ``refine`` on a calibrated problem; a measure
        other than ``worst_case``/``rss``; ``rss`` with asymmetric intervals; a cost model that is not
        convex on its range.
    """
    if problem.clearances is not None:      # not convex: the monotone bracket, on the problem's poses
        if budget is not None:
            raise ValidationError("budget", budget,
                                  "None with clearance sources (the optimum bracket minimises cost at the requirement)")
        if refine:
            raise ValidationError("refine", refine, "false with clearance sources (the optimum bracket minimises cost "
                                  "on the problem's poses; the GA's refine holds a design over the workspace)")
        return
    if refine:
        check_refinable(problem)
    if problem.requirement.measure not in ("worst_case", "rss"):
        raise ValidationError("requirement.measure", problem.requirement.measure,
                              "'worst_case' or 'rss' for the exact optimum (mc_quantile and yield have no convex rows: use allocate_ga)")
    if problem.requirement.measure == "rss" and problem.asymmetric:
        raise ValidationError("requirement.measure", "rss", "'worst_case' for the exact optimum of asymmetric "
                              "intervals (|shift| + RSS rows are not quadratic: use allocate_ga)")
    _check_convex(problem)


def allocate_optimum(problem: ToleranceProblem, *, budget: float | None = None, tol: float = 1e-9,
                     max_rounds: int = 60, max_rows: int = 400, refine: bool | dict = False) -> AllocationResult:
    """Certified optimum (min cost at the requirement, or best accuracy at ``budget``).

    SLSQP on the convex problem with cutting planes (the worst-case rows of
    :mod:`evotol.measures.constraints`), certified by its KKT residual and duality gap.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem (tolerances in SI: m or rad).
    budget : float or None
        If given (cost models' unit), best accuracy at this cost instead of least cost at the
        requirement.
    tol : float
        Largest normalised violation accepted before the design is scaled onto the boundary
        (1, dimensionless).
    max_rounds : int
        Cutting-plane rounds before :class:`evotol.errors.ConvergenceError`.
    max_rows : int
        Largest working set of constraint rows.
    refine : bool or dict
        The whole workspace (:mod:`evotol.allocators.workspace_refinement`): ``True`` or a dict of
        :func:`evotol.allocators.workspace_refinement.refine_poses` options (``grid``, ``candidates``, ``local``,
        ``add``, ``max_rounds``): after each solve, the workspace is searched for the pose of
        largest normalised error, which is added before solving again, until the requirement
        holds there. ``result.info["refinement"]`` reports the worst pose, its error and the
        number of rounds.

    Returns
    -------
    evotol.core.result.AllocationResult
        The optimal design (tolerances in SI: m or rad), its cost (cost models' unit), its
        errors (m, rad) and ``certificate`` (lower bound, relative gap, KKT residual, rows). With clearance
        sources (``problem.clearances``) the worst case is not convex: the result is
        :func:`evotol.allocators.monotone.allocate_monotone`'s best design with a proven lower
        bound (a bracket, reported "not certified" unless it closes).

    Raises
    ------
    evotol.errors.ValidationError
        A measure other than ``worst_case``/``rss`` (or ``rss`` with asymmetric intervals), a
        cost model that is not convex on its range, a bad ``budget``, or ``budget``/``refine``
        with clearance sources.
    evotol.errors.InfeasibleError
        Even every free tolerance at its lower bound misses the requirement.
    evotol.errors.ConvergenceError
        The cutting planes did not converge in ``max_rounds``.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import allocate_optimum
    >>> opt = allocate_optimum(problem)
    >>> opt.feasible, round(opt.cost, 3)
    (True, 97.426)
    >>> import math                                             # Lagrange: t_j ~ 1/sqrt(a_j)
    >>> math.isclose(opt.cost, 10 * (1 + math.sqrt(2) + math.sqrt(0.5)) ** 2, rel_tol=1e-9)
    True
    """
    check_optimum(problem, budget=budget, refine=refine)
    if problem.clearances is not None:   # not convex: the monotone polyblock bracket instead
        return allocate_monotone(problem)
    if refine:      # the whole workspace: this optimum, on a growing pose set (a wrapper, not a call back)
        return allocate_on_workspace(_allocate_optimum_at_poses, problem, refine, budget=budget, tol=tol,
                                     max_rounds=max_rounds, max_rows=max_rows)
    return _allocate_optimum_at_poses(problem, budget=budget, tol=tol, max_rounds=max_rounds, max_rows=max_rows)


def _allocate_optimum_at_poses(problem: ToleranceProblem, *, budget: float | None, tol: float, max_rounds: int,
                               max_rows: int):
    """:func:`allocate_optimum` on the problem's poses (no clearances, no refinement)."""
    t0 = time.perf_counter()
    stack = stack_rows(problem) if budget is None else None
    if stack is not None:       # one error direction at one pose: the dual search (evotol/allocators/stack_dual.py)
        if np.any(stack.value(problem.lower[stack.index]) > 1 + 1e-9):
            problem.check_feasible()                # its exact rows say infeasible: the problem's own refusal
        return _stack_optimum(problem, stack, t0)
    problem.check_feasible()
    rows = ConstraintRows(problem)
    if budget is not None:
        return _best_accuracy(problem, rows, check_budget(problem, budget), t0, tol, max_rounds, max_rows)
    t = sensitivity_design(problem)
    rounds, res = 0, None
    for _proven in range(6):
        for rounds in range(1, max_rounds + 1):
            t, res = _solve_min_cost(problem, rows, t, max_rows, tol)
            viol, added = rows.check(t[None])
            # stop when the exact error is within 1e-7 of the bound, or when the exact check finds no
            # row the working set lacks (what is left is solver tolerance, removed by scaling below)
            if viol[0] <= max(tol, 1e-7) or (added == 0 and viol[0] <= 1e-3):
                break
        else:
            raise ConvergenceError(f"cutting planes did not converge in {max_rounds} rounds (violation {viol[0]:.3g})")
        # make the design exactly feasible (the working-row solution may sit a hair outside)
        for _ in range(5):
            if viol[0] <= tol:
                break
            t = rows.scale_to_boundary(t[None])[0]
            viol, _ = rows.check(t[None])
        # the ascent from the direction grid can stop at a local maximum of the support function:
        # the certified search finds the directions it missed; their rows go in and we re-solve
        added, proven = feasibility.proven_cuts(problem, rows, t, return_evaluation=True)
        if not added:
            break
    cert = certificate(problem, rows, t)
    cert["rounds"] = rounds
    cert["solver"] = "SLSQP + cutting planes"
    # the working rows' hair outside; `proven` is t's evaluation with the certified search's bounds
    # (the rows it added do not change it)
    t, ev, repair = feasibility.hold_to_rule(problem, t, max_miss=np.inf, evaluation=proven)
    result = issue(make_result(problem, "optimum", t, evaluation=ev, certificate=cert, seconds=time.perf_counter() - t0,
                               info={"solver_message": str(getattr(res, "message", "")), **repair}))
    if problem.requirement.measure == "worst_case":
        # the proven bound of the design (tightened: evotol.measures.feasibility), over the requirement, as
        # make_result's one proven evaluation found it
        cert["proven_bound_over_requirement"] = result.info["bound_ratio"]
    return result


def _stack_optimum(problem: ToleranceProblem, stack: StackRows, t0: float) -> AllocationResult:
    """:func:`allocate_optimum` of a stack: the dual search, certified by its own dual bound."""
    found = dual_search(problem, stack)
    t = problem.full(found["t"][None])[0]
    locked_cost = sum(float(problem.tolerances[problem.names[j]].cost_of(t[j])) * problem.cost_weight[j]
                      for j in np.flatnonzero(problem.locked))
    cert = {"lower_bound": found["lower_bound"] + locked_cost, "kkt_residual": found["kkt_residual"],
            "active_rows": found["active_rows"], "working_rows": int(stack.rows.shape[0]), "rounds": 1,
            "solver": "dual search (one direction, evotol.allocators.stack_dual)",
            "multipliers": found["lam"].tolist()}
    t, ev, repair = feasibility.hold_to_rule(problem, t, max_miss=np.inf)     # the search's last bits outside
    result = issue(make_result(problem, "optimum", t, evaluation=ev, certificate=cert, seconds=time.perf_counter() - t0,
                               info={"solver_message": "dual search converged", **repair}))
    cert["gap"] = (result.cost - cert["lower_bound"]) / result.cost
    if problem.requirement.measure == "worst_case":
        cert["proven_bound_over_requirement"] = result.info["bound_ratio"]
    return result


def _best_accuracy(problem, rows, budget, t0, tol, max_rounds, max_rows):
    f = np.flatnonzero(problem.free)
    lo, hi = problem.lower[f], problem.upper[f]
    min_cost = float(problem.cost(problem.full(hi[None])[0]))
    if budget < min_cost:
        raise ValidationError("budget", budget, f">= {min_cost:.6g}, the cost with every free tolerance at its upper bound")

    def T(y):
        return problem.full((y * hi)[None])[0]

    y = np.clip(sensitivity_design(problem)[f] / hi, lo / hi, 1)
    s0 = float(rows.normalised_error(T(y)[None])[0])
    z = np.concatenate([y, [s0]])
    sel_a = sel_b = None
    for rounds in range(1, max_rounds + 1):
        cons = [{"type": "ineq", "fun": lambda z: (budget - float(problem.cost(T(z[:-1])))) / budget,
                 "jac": lambda z: np.concatenate([-problem.variable_dcost(T(z[:-1])) * hi, [0.0]]) / budget}]
        tz = T(z[:-1])
        if rows.A.shape[0]:
            sel = sel_a = _grow(sel_a, rows.A @ tz + rows.A0, max_rows)
            A = rows.A[sel]
            Af, off = problem.to_variables(A) * hi, _locked_part(problem, A, 1) + rows.A0[sel]
            cons.append({"type": "ineq", "fun": lambda z, Af=Af, off=off: z[-1] - off - Af @ z[:-1],
                         "jac": lambda z, Af=Af: np.hstack([-Af, np.ones((Af.shape[0], 1))])})
        if rows.B.shape[0]:
            sel = sel_b = _grow(sel_b, rows.B @ tz ** 2, max_rows)
            B = rows.B[sel]
            Bf = problem.to_variables(B) * hi ** 2
            off = _locked_part(problem, B, 2)
            cons.append({"type": "ineq", "fun": lambda z, Bf=Bf, off=off: z[-1] ** 2 - off - Bf @ z[:-1] ** 2,
                         "jac": lambda z, Bf=Bf: np.hstack([-2 * Bf * z[:-1], 2 * z[-1] * np.ones((Bf.shape[0], 1))])})
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = minimize(lambda z: z[-1], z, jac=lambda z: np.eye(len(z))[-1], method="SLSQP", constraints=cons,
                           bounds=list(zip(lo / hi, np.ones(len(f)))) + [(0, None)], options={"ftol": 1e-15, "maxiter": 1000})
        z = res.x
        viol, added = rows.check(T(z[:-1])[None])
        if added == 0 and rows.violation(T(z[:-1])[None])[0] <= z[-1] - 1 + tol:
            break
    else:       # the design of the last round is not the best accuracy the working rows prove: say so
        raise ConvergenceError(f"cutting planes (best accuracy at budget) did not converge in {max_rounds} rounds "
                               f"(normalised error {float(rows.normalised_error(T(z[:-1])[None])[0]):.3g} against "
                               f"{z[-1]:.3g} on the working rows)")
    t = T(np.clip(z[:-1], lo / hi, 1))
    return issue(make_result(problem, "optimum (best accuracy at budget)", t, seconds=time.perf_counter() - t0,
                             budget=budget, certificate={"rounds": rounds, "budget": budget, "solver": "SLSQP + cutting planes"},
                             info={"budget": budget, "normalised_error": float(rows.normalised_error(t[None])[0])}))

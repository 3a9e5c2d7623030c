"""Allocation that holds an assembly's **nonlinear** worst-case limit, by re-linearisation.

The linear (first-order) worst case ``Σ_j |∂f_k/∂x_j(x0)| t_j <= L_k`` is not the real limit when
``f_k`` is curved over the tolerance box (the one-way clutch: the arccos near 7° makes the real
worst case of the linear optimum 1.21 × the limit). This option repeats:

1. allocate on the current linear rows (any allocator: ``allocate_optimum``,
   ``allocate_process_optimum``...);
2. compute the proven nonlinear worst case of the design (:func:`evotol.measures.nonlinear.worst_case.nonlinear_worst_case`);
3. **re-linearise every response at its worst point** ``x0 + δ*``: its row becomes the secant
   sensitivities ``s̄_j = ∫_0^1 ∂f_k/∂x_j(x0 + τ δ*) dτ`` (8-point Gauss–Legendre), for which
   ``Σ_j s̄_j δ*_j = f_k(x0 + δ*) − f_k(x0)``: the row predicts the real deviation at that point;

until the proven nonlinear worst case is on the limit (within ``[1 − tight, 1 + rtol]``), keeping
the cheapest design that held it. The result is a design that **holds** the nonlinear limit (proven
by the worst-case bound), found by a fixed-point iteration: it is not certified optimal for the
nonlinear problem (the rows are re-linearisations, not bounds). Worst-case measure only (a statistical
limit has no box; use the nonlinear Monte Carlo of the studies).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evotol.allocators.process.branch_and_bound import allocate_process_optimum
from evotol.allocators.process.problem import ProcessProblem
from evotol.errors import ValidationError
from evotol.measures.nonlinear.worst_case import nonlinear_worst_case
from evotol.core.problem import ToleranceProblem
from evotol.robots.assembly import AssemblyFunction, LinearStack

_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)


@dataclass
class NonlinearLimitResult:
    """The linear optimum and the allocation holding the nonlinear limit, side by side.

    Parameters
    ----------
    linear : object
        Result of ``allocate`` on the first-order problem (an ``AllocationResult`` or
        ``ProcessResult``).
    result : object
        The cheapest allocation whose proven nonlinear worst case held the limit (if none did:
        the last one).
    linear_worst_case : dict
        Proven nonlinear worst case of ``linear``
        (:func:`evotol.measures.nonlinear.worst_case.nonlinear_worst_case`).
    worst_case : dict
        Proven nonlinear worst case of ``result``.
    iterations : int
        Number of re-linearisations done.
    converged : bool
        True if some allocation held the nonlinear limit (``result`` is then that one).
    history : list of dict
        Per iteration: ``iteration``, ``cost`` (cost units), ``nonlinear_over_limit``
        (dimensionless).
    """

    linear: object
    result: object
    linear_worst_case: dict
    worst_case: dict
    iterations: int
    converged: bool
    history: list = field(default_factory=list)

    @property
    def cost_difference(self) -> float:
        """Cost of holding the nonlinear limit minus the linear optimum's (cost units)."""
        return float(self.result.cost - self.linear.cost)

    def to_dict(self) -> dict:
        """JSON-ready summary of both results, their nonlinear worst cases and the cost difference.

        Returns
        -------
        dict
            ``linear``, ``nonlinear`` (the results' ``to_dict()``), ``linear_nonlinear_worst_case``,
            ``nonlinear_worst_case``, ``cost_difference`` (cost units),
            ``cost_difference_over_linear`` (dimensionless), ``iterations``, ``converged``,
            ``history``.
        """
        return {"linear": self.linear.to_dict(), "nonlinear": self.result.to_dict(),
                "linear_nonlinear_worst_case": self.linear_worst_case, "nonlinear_worst_case": self.worst_case,
                "cost_difference": self.cost_difference, "cost_difference_over_linear": self.cost_difference / self.linear.cost,
                "iterations": self.iterations, "converged": self.converged, "history": self.history}


def _tolerances(problem, res) -> np.ndarray:
    if isinstance(res.tolerances, dict):
        return np.array([res.tolerances[n] for n in problem.names], dtype=float)
    return np.asarray(res.t, dtype=float)


def secant_sensitivities(asm, k: int, offsets) -> np.ndarray:
    """``∫_0^1 ∇f_k(x0 + τ δ) dτ`` (8-point Gauss–Legendre) for offsets δ (SI): the row whose linear
    prediction equals the real deviation ``f_k(x0 + δ) − f_k(x0)`` (to quadrature accuracy).

    Parameters
    ----------
    asm : evotol.robots.assembly.AssemblyFunction
        The assembly (``x0`` and ``jacobian``).
    k : int
        Index of the response.
    offsets : array_like, (n_dims,)
        Offsets δ of the dimensions from nominal (SI: m or rad).

    Returns
    -------
    numpy.ndarray
        (n_dims,) secant sensitivities, in the response's unit per SI unit of each dimension.
    """
    d = np.asarray(offsets, dtype=float)
    tau = 0.5 * (_GL_X + 1.0)
    J = asm.jacobian(asm.x0 + tau[:, None] * d)[:, k, :]          # (8, n)
    return 0.5 * _GL_W @ J


def _rebuild(problem, stack: LinearStack):
    if isinstance(problem, ProcessProblem):
        out = ProcessProblem(stack, problem.processes, problem.requirement, stack.response_poses, check_dominance=False)
        out.loss_coefficients, out.quality_loss_A = problem.loss_coefficients, problem.quality_loss_A
        return out
    return ToleranceProblem(stack, problem.tolerances, problem.requirement, stack.response_poses)


def allocate_nonlinear_limit(problem, allocate, *, max_iter: int = 12, rtol: float = 1e-9, tight: float = 1e-6,
                             wc_rtol: float = 1e-7) -> NonlinearLimitResult:
    """Allocate with ``allocate`` so that the **nonlinear** worst case holds (module docstring).

    Parameters
    ----------
    problem : ToleranceProblem or ProcessProblem
        On an assembly function (:class:`evotol.robots.assembly.AssemblyFunction`), worst-case measure,
        no shared or locked sources.
    allocate : callable
        ``allocate(problem) -> result`` (e.g. ``allocate_optimum`` or ``allocate_process_optimum``).
    max_iter : int
        Re-linearisations at most.
    rtol : float
        The nonlinear worst case may exceed the limit by this fraction.
    tight : float
        Iterations stop when the nonlinear worst case is within ``[1 − tight, 1 + rtol]`` × limit;
        otherwise after ``max_iter``, with the cheapest design that held the limit.
    wc_rtol : float
        Tolerance of the branch-and-bound worst case (when the response is not proven monotone).

    Returns
    -------
    NonlinearLimitResult
        ``linear`` (the first-order optimum), ``result`` (the allocation holding the nonlinear
        limit), both proven nonlinear worst cases, iterations, ``cost_difference``.

    Raises
    ------
    ValidationError
        Not an assembly, not the worst-case measure, shared/locked sources.
    """
    asm = problem.model
    if not isinstance(asm, AssemblyFunction):
        raise ValidationError("robot", getattr(asm, "name", asm), "an assembly function (evotol.robots.assembly.AssemblyFunction)")
    if problem.requirement.measure != "worst_case":
        raise ValidationError("requirement.measure", problem.requirement.measure,
                              "'worst_case' (the nonlinear limit is a worst case over the tolerance box)")
    base = problem.base if isinstance(problem, ProcessProblem) else problem
    if base.follower.any() or base.locked.any():
        raise ValidationError("tolerances", "shared or locked sources", "independent free sources for the nonlinear limit")
    dims = list(asm.dimension_names)
    rows = {n: dict(zip(dims, asm.gradient[k].tolist())) for k, n in enumerate(asm.response_names)}
    limits = {n: float(asm.limits[k]) for k, n in enumerate(asm.response_names)}
    nominal = dict(zip(dims, asm.x0.tolist()))
    linear = res = allocate(problem)
    first = wc = nonlinear_worst_case(asm, _tolerances(problem, res), rtol=wc_rtol)
    history = [{"iteration": 0, "cost": float(res.cost), "nonlinear_over_limit": wc["max_over_limit"]}]
    best = (res, wc) if wc["max_over_limit"] <= 1 + rtol else None
    it = 0
    while it < max_iter and not (1 - tight <= wc["max_over_limit"] <= 1 + rtol):
        it += 1
        for k, r in enumerate(wc["responses"]):     # re-linearise every response at its worst point
            rows[r["name"]] = dict(zip(dims, secant_sensitivities(asm, k, r["worst_point_offsets"]).tolist()))
        stack = LinearStack(rows, limits, nominal=nominal, name=f"{asm.name}, re-linearised ({it})")
        res = allocate(_rebuild(problem, stack))
        wc = nonlinear_worst_case(asm, _tolerances(problem, res), rtol=wc_rtol)
        history.append({"iteration": it, "cost": float(res.cost), "nonlinear_over_limit": wc["max_over_limit"]})
        if wc["max_over_limit"] <= 1 + rtol and (best is None or res.cost < best[0].cost):
            best = (res, wc)
    if best is None:
        return NonlinearLimitResult(linear, res, first, wc, it, False, history)
    return NonlinearLimitResult(linear, best[0], first, best[1], it, True, history)


def allocate_process_nonlinear_limit(pp: ProcessProblem, *, max_iter: int = 12, rtol: float = 1e-9) -> NonlinearLimitResult:
    """The exact process optimum (:func:`evotol.allocators.process.allocate_process_optimum`)
    re-linearised until the assembly's nonlinear worst case holds (:func:`allocate_nonlinear_limit`;
    worst-case measure). The ``nonlinear_limit`` method of a process-selection study file.

    Parameters
    ----------
    pp : ProcessProblem
        The process-selection problem, on an assembly function.
    max_iter : int, optional
        Re-linearisations at most (default 12).
    rtol : float, optional
        Relative amount (dimensionless) by which the nonlinear worst case may exceed the limit
        (default 1e-9).

    Returns
    -------
    NonlinearLimitResult
        The re-linearised design (``result``), the first-order optimum's nonlinear worst case and
        the cost difference.

    Raises
    ------
    evotol.errors.ValidationError
        What :func:`allocate_nonlinear_limit` refuses (not an assembly, not the worst-case measure,
        bad ``max_iter``/``rtol``).
    """
    return allocate_nonlinear_limit(pp, allocate_process_optimum, max_iter=max_iter, rtol=rtol)

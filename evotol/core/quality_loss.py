"""Taguchi quadratic quality loss as a cost term of any tolerance problem.

Convention (docs/process_selection.md, "Quality loss"; Taguchi; Choi, Park & Salisbury 2000).
A response ``Y_k`` with limit ``±L_k`` and loss coefficient ``A_k`` (the loss, in cost units, of an
assembly whose response sits exactly at its limit) loses ``K_k (Y_k − Y0_k)²`` with
``K_k = A_k / L_k²``. Its expected value under the first-order model, zero-mean independent
dimensions with ``σ_j = t_j / 3`` and the target at the nominal response ``Y0_k = Y_k(x0)``, is

    E[QL_k] = K_k Σ_j (∂Y_k/∂x_j)² t_j² / 9.

The sum over responses is separable in the tolerances, ``QL(t) = Σ_j q_j t_j²`` with

    q_j = Σ_k w_k (A_k / 9) (∂Y_k/∂x_j / L_k)²,

so the loss is added to every source's cost model (:class:`evotol.cost_models.quality_loss.QualityLossCost`)
and every allocator that minimises cost (``allocate_optimum``, ``allocate_ga``, ``allocate_nsga2``,
and the process-selection allocators) minimises machining cost + expected loss.

:func:`with_quality_loss` is the one entry point, for a
:class:`~evotol.core.problem.ToleranceProblem` and for a process-selection problem
(:class:`~evotol.allocators.process.ProcessProblem`, whose implementation the process package
registers; ``pp.with_quality_loss(A)`` is the same call). :func:`loss_coefficients` holds the
equation above; :class:`~evotol.cost_models.quality_loss.QualityLossCost` is the cost term it builds.

A nominal off target (``Y_k(x0) ≠ Y0_k``) adds the constant ``K_k (Y_k(x0) − Y0_k)²``, which
changes no allocation and is left out.

Responses and weights ``w_k``:

* an assembly function (:mod:`evotol.robots.assembly`): each response is its own quality
  characteristic, ``w_k = 1``; ``A`` is one number or ``{response name: A_k}``;
* a robot: the responses are the error components (x, y, z of ``position``; those of
  ``orientation``) at the problem's poses, with ``L`` the requirement of that component and
  ``w = 1 / n_poses`` (the mean loss over the workspace); ``A`` is one number or
  ``{"position": A, "orientation": A}``.
"""
from __future__ import annotations

from functools import singledispatch
from typing import Mapping

import numpy as np

from evotol.cost_models.quality_loss import QualityLossCost
from evotol.robots.assembly import AssemblyFunction
from evotol.errors import ValidationError
from evotol.core.problem import Tolerance, ToleranceProblem

#: tolerance = KSIGMA standard deviations (Choi 2000's code: KSIGMA = 3)
KSIGMA = 3.0


def _coefficient(field: str, v) -> float:
    try:
        a = float(v)
    except (TypeError, ValueError):
        raise ValidationError(field, v, "a finite loss coefficient A >= 0 (cost units at the limit)") from None
    if not (np.isfinite(a) and a >= 0):
        raise ValidationError(field, v, "a finite loss coefficient A >= 0 (cost units at the limit)")
    return a


def _per_key(A, keys: tuple[str, ...], what: str) -> dict[str, float]:
    if isinstance(A, Mapping):
        unknown = [k for k in A if k not in keys]
        if unknown:
            raise ValidationError(f"quality_loss[{unknown[0]!r}]", A[unknown[0]], f"a {what} among {list(keys)}")
        return {k: _coefficient(f"quality_loss[{k!r}]", A.get(k, 0.0)) for k in keys}
    a = _coefficient("quality_loss", A)
    return {k: a for k in keys}


def loss_coefficients(problem: ToleranceProblem, A) -> np.ndarray:
    """Per-source coefficients ``q_j`` of the expected loss ``Σ_j q_j t_j²`` (module docstring).

    Parameters
    ----------
    problem : ToleranceProblem
        Any problem; its sensitivities at its poses are used (first-order model).
    A : float or mapping
        Loss at the limit (cost units): one number, or per response name (assembly) / per
        component ``"position"``, ``"orientation"`` (robot).

    Returns
    -------
    numpy.ndarray
        ``q`` (n_sources,), cost units per SI unit² of tolerance.

    Raises
    ------
    ValidationError
        A negative or non-finite coefficient, or a key that is no response/component.
    """
    robot = problem.error_model
    q = np.zeros(problem.n_sources)
    if isinstance(robot, AssemblyFunction):       # an assembly: per response, its gradient at the nominal
        a = _per_key(A, robot.response_names, "response name")
        w = np.array([a[n] for n in robot.response_names])
        # gradient (K, n_dims) in the response's unit per SI; limits (K,)
        S = robot.gradient / robot.limits[:, None]
        return (w[:, None] * S ** 2).sum(axis=0) / KSIGMA ** 2
    comps = dict(problem.components)
    a = _per_key(A, tuple(comps), "requirement component")
    for comp, L in comps.items():
        for j, B in enumerate(problem.blocks[comp]):          # (n_poses, 3, dim_j)
            q[j] += a[comp] / L ** 2 * float(np.mean(np.sum(B ** 2, axis=(1, 2)))) / KSIGMA ** 2
    return q


def expected_loss(problem: ToleranceProblem, A, T) -> np.ndarray:
    """Expected quality loss ``Σ_j q_j t_j²`` of designs ``T`` (n, n_sources) SI -> (n,) cost units.

    Parameters
    ----------
    problem : ToleranceProblem
        The problem (first-order sensitivities at its poses).
    A : float or mapping
        Loss at the limit (cost units); see :func:`loss_coefficients`.
    T : array_like, (n, n_sources) or (n_sources,)
        Tolerance designs (m or rad per source); one design may be given as a vector.

    Returns
    -------
    numpy.ndarray
        Expected loss of each design, (n,), cost units.

    Raises
    ------
    ValidationError
        As :func:`loss_coefficients`.
    """
    T = np.atleast_2d(np.asarray(T, dtype=float))
    return T ** 2 @ loss_coefficients(problem, A)


@singledispatch
def with_quality_loss(problem, A):
    """The same problem whose cost is machining cost + expected quality loss (the one entry point).

    Parameters
    ----------
    problem : ToleranceProblem or evotol.allocators.process.ProcessProblem
        The problem (its cost models, or its processes' cost models, are the machining costs).
    A : float or mapping
        Loss coefficients (see :func:`loss_coefficients`).

    Returns
    -------
    ToleranceProblem or evotol.allocators.process.ProcessProblem
        A problem of the same kind: every source's cost model (a process problem: every
        process's) wrapped in :class:`QualityLossCost`; geometry shared. A process problem's
        ``loss_coefficients`` hold the ``q_j`` and ``quality_loss_A`` the ``A`` given.

    Raises
    ------
    ValidationError
        As :func:`loss_coefficients`; a ``problem`` of another kind; a process problem that
        already carries a loss.
    """
    raise ValidationError("problem", type(problem).__name__,
                          "a ToleranceProblem or a ProcessProblem to add the quality loss to")


@with_quality_loss.register
def _tolerance_problem_with_quality_loss(problem: ToleranceProblem, A) -> ToleranceProblem:
    import copy

    q = loss_coefficients(problem, A)
    out = copy.copy(problem)
    out.tolerances = {n: _wrap(t, qj) for (n, t), qj in zip(problem.tolerances.items(), q)}
    out._mc_cache = None
    return out


def _wrap(tol: Tolerance, q: float) -> Tolerance:
    from dataclasses import replace

    return tol if tol.cost is None else replace(tol, cost=QualityLossCost(tol.cost, q))


def has_quality_loss(problem: ToleranceProblem) -> bool:
    """Whether some source's cost carries a positive loss term (then the cost is not monotone in t:
    the GA's boundary repair only pulls infeasible designs onto the limit).

    Parameters
    ----------
    problem : ToleranceProblem
        The problem (e.g. one made by :func:`with_quality_loss`).

    Returns
    -------
    bool
        True if some cost model is a :class:`QualityLossCost` with ``q > 0``.
    """
    return any(isinstance(t.cost, QualityLossCost) and t.cost.q > 0 for t in problem.tolerances.values())

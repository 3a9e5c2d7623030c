"""Tolerance allocation on a stack (:class:`evotol.measures.stack_model.Stack`): the half-widths of
its dimensions chosen by cost so that the gap stays within its limits [LSL, USL].

Mapping onto a :class:`evotol.core.problem.ToleranceProblem` (SI, m):

* the robot is the stack's :class:`evotol.robots.assembly.LinearStack` (:meth:`Stack.linear_stack`)
  ``gap = Σ a_i x_i`` whose limit is the half
  width of the specification ``L = (USL − LSL)/2``;
* dimension ``i`` keeps the **shape of its drawing zone**: with the drawn half-width ``h_i`` and
  deviations ``l_i <= u_i``, its tolerance is the half-width ``t_i`` and its interval
  ``[−minus_i t_i, plus_i t_i]`` with ``minus_i = −l_i/h_i``, ``plus_i = u_i/h_i`` -- a one-sided
  ``+0/−0.031`` stays one-sided (``minus = 2, plus = 0``) at every ``t``;
* the gap's limits need not be centred on the nominal gap: a **fixed source**
  ``"limits' centre"`` (sensitivity 1, offset ``g_0 − (LSL + USL)/2``, no cost, zero width) carries
  the difference, so ``|error| <= L`` is exactly ``LSL <= gap <= USL``; it appears only when the
  offset is not zero;
* the measure is the problem's: ``worst_case`` (the stack's worst-case limits within the
  specification) or ``rss`` (every tolerance ``3σ`` of a normal: the RSS limits within it).

:func:`allocated_stack` turns an allocation back into a :class:`Stack` whose deviations are the
allocated zones, so the allocated design is reported with the handbook's figures.
"""
from __future__ import annotations

import numpy as np

from evotol.cost_models.base import CostModel
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from evotol.errors import ValidationError
from evotol.measures.stack_model import Stack, StackDimension

#: name of the fixed source that carries the offset of the limits' centre from the nominal gap
CENTRE = "limits' centre"


def stack_problem(stack: Stack, costs: dict, lower: dict, upper: dict, *, measure: str = "worst_case",
                  fixed: tuple = ()) -> ToleranceProblem:
    """The allocation problem of a stack (module docstring).

    Parameters
    ----------
    stack : Stack
        The stack (SI: m), with both limits.
    costs : dict of str to evotol.cost_models.CostModel
        Dimension name -> cost model of its half-width (m); every free dimension needs one.
    lower, upper : dict of str to float
        Dimension name -> smallest and largest half-width allowed (m).
    measure : {"worst_case", "rss"}
        How the gap is judged.
    fixed : tuple of str
        Dimensions whose drawn zone is kept (bought-in parts): no cost, not optimised.

    Returns
    -------
    ToleranceProblem
        One pose (the gap), requirement ``position = 1`` (the normalised gap error).

    Raises
    ------
    evotol.errors.ValidationError
        A stack without both limits, a dimension without a zone (zero half-width) that is not
        fixed, a missing cost or bound, or what the problem itself refuses.
    """
    if stack.lower_limit is None or stack.upper_limit is None:
        raise ValidationError("stack.upper_limit" if stack.lower_limit is not None else "stack.lower_limit", None,
                              "both limits of the gap to allocate its tolerances")
    if measure not in ("worst_case", "rss"):
        raise ValidationError("allocation.measure", measure, "'worst_case' or 'rss' for a stack")
    half = 0.5 * (stack.upper_limit - stack.lower_limit)
    a, n, _, h = stack.arrays()
    centre = float(a @ n) - 0.5 * (stack.lower_limit + stack.upper_limit)
    tols = {}
    for d, hi in zip(stack.dimensions, h):
        f = f"dimensions.{d.name}"
        if hi <= 0:
            raise ValidationError(f"{f}.upper", d.upper, "a zone (upper > lower) whose shape the allocation keeps")
        shape = {"minus": -d.lower / hi, "plus": d.upper / hi, "distribution": "normal" if d.distribution == "normal"
                 else "uniform" if d.distribution == "uniform" else "normal"}
        if d.name in fixed:
            tols[d.name] = Tolerance.fixed(float(hi), **shape)
            continue
        for k, table in (("cost", costs), ("lower", lower), ("upper", upper)):
            if d.name not in table:
                raise ValidationError(f"{f}.{k}", None, "a cost model and half-width bounds for every free dimension")
        if not isinstance(costs[d.name], CostModel):
            raise ValidationError(f"{f}.cost", costs[d.name], "a evotol.cost_models.CostModel")
        tols[d.name] = Tolerance(costs[d.name], float(lower[d.name]), float(upper[d.name]), **shape)
    if centre != 0:
        tols[CENTRE] = Tolerance.fixed(half * 1e-12, offset=centre)
    robot = stack.linear_stack(half, extra={CENTRE: 1.0} if centre != 0 else None)
    return ToleranceProblem(robot, tols, Requirement(position=1.0, measure=measure), np.zeros((1, 1)))


def allocated_stack(stack: Stack, problem: ToleranceProblem, t) -> Stack:
    """The stack with the allocated zones as its deviations (same nominals, directions, limits).

    Parameters
    ----------
    stack : Stack
        The stack the problem was built from (:func:`stack_problem`).
    problem : ToleranceProblem
        Its allocation problem.
    t : array_like, shape (n_sources,)
        An allocation (half-widths, m), in the problem's source order.

    Returns
    -------
    Stack
        The allocated stack (m).
    """
    tv = dict(zip(problem.names, np.asarray(t, dtype=float)))
    dims = []
    for d in stack.dimensions:
        tol = problem.tolerances[d.name]
        dims.append(StackDimension(d.name, d.nominal, tol.plus * tv[d.name], -tol.minus * tv[d.name], d.sensitivity,
                                   d.distribution, d.same_part_as))
    return Stack(tuple(dims), stack.gap, stack.lower_limit, stack.upper_limit, stack.unit)

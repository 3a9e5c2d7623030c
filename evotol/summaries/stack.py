"""What a stack analysis writes: the JSON summary its page is drawn from (SI: m; the display unit
and drawing precision stated beside the values).

:func:`stack_summary` turns a :class:`evotol.measures.stack_analysis.Stack` and its statistical
models into plain data; :func:`evotol.reporting.stack_report.render_stack` draws the page from it alone.
"""
from __future__ import annotations

from evotol.allocators.stack_allocation import allocated_stack
from evotol.measures.stack_analysis import Stack, analyse_stack
from evotol.summaries.drawing import rounded_design
from evotol.units.display import DisplayUnits
from evotol.units import COUNT, RELATIVE, make_units_block

_FRACTION_OR_M = "m (contributions: deviation of the gap from its nominal) or 1 (models.*.outside: fraction of assemblies)"
#: units of the keys of a stack summary (docs/units.md)
KEYS = {"nominal": "m", "mean": "m", "upper": "m", "lower": "m", "limits": "m", "half_width": "m", "sigma": "m",
        "shift": "m", "below": _FRACTION_OR_M, "above": _FRACTION_OR_M,
        "sensitivity": RELATIVE + ": ∂gap/∂dimension", "factor": RELATIVE + ": MRSS correction factor C_f",
        "n": COUNT, "cp": RELATIVE, "cpk": RELATIVE, "cpl": RELATIVE, "cpu": RELATIVE,
        "cp_input": RELATIVE + ": every dimension's capability (half-width = 3·Cp·σ)",
        "k": RELATIVE + ": mean shift / half-width", "variance_share": RELATIVE,
        "below_percent": "%", "above_percent": "%", "below_interval": "1: Clopper-Pearson interval of the fraction",
        "above_interval": "1: Clopper-Pearson interval of the fraction", "precision": "the display unit (display.unit)",
        "computed": "m", "n_samples": COUNT, "cost": "cost-model unit", "normalised_error": RELATIVE + ": max error / requirement",
        "drawing_lower": "display unit (display.unit)", "drawing_upper": "display unit (display.unit)",
        "tolerances": "m: allocated half-widths", "cost_share_percent": "%", "confidence": "1: confidence level", "seed": COUNT, "seconds": "s"}


def stack_units_block(extra: dict | None = None) -> dict:
    """The ``units`` block of a stack summary.

    Parameters
    ----------
    extra : dict, optional
        Further key -> unit entries (a study's own keys).

    Returns
    -------
    dict
        :func:`evotol.units.make_units_block` with :data:`KEYS` (and ``extra``).
    """
    return make_units_block(keys={**KEYS, **(extra or {})})


def stack_summary(name: str, stack: Stack, models: dict, display: dict, *, seed: int = 0) -> dict:
    """The JSON summary of a stack analysis.

    Parameters
    ----------
    name : str
        The study's name.
    stack : Stack
        The stack (SI: m).
    models : dict of str to StackModel
        The named statistical models.
    display : dict
        ``unit`` (``"mm"``, ``"µm"`` or ``"in"``), ``precision`` (drawing precision in that unit),
        ``n_samples`` and ``confidence`` (Monte Carlo of non-normal dimensions).
    seed : int
        Seed of the Monte Carlo.

    Returns
    -------
    dict
        ``name``, ``stack`` (:func:`evotol.measures.stack_analysis.analyse_stack`, SI), ``display``
        (``unit``, ``precision``), ``seed`` and ``units``.

    Raises
    ------
    evotol.errors.ValidationError
        A model the stack does not support, before any computation (:func:`analyse_stack`).
    """
    a = analyse_stack(stack, models, n_samples=display.get("n_samples", 200_000), seed=seed,
                      confidence=display.get("confidence", 0.95))
    return {"name": name, "stack": a.to_dict(), "seed": seed,
            "display": {"unit": display["unit"], "precision": display["precision"]}, "units": stack_units_block()}


def allocation_summary(stack: Stack, problem, results: dict, models: dict, display: dict, *, seed: int = 0) -> dict:
    """Each allocation of a stack, reported as a stack: the allocated half-widths, cost and verdict,
    the handbook's figures of the allocated design (:func:`analyse_stack`) and its zones rounded to the
    drawing precision and re-checked (:func:`evotol.summaries.drawing.rounded_design`).

    Parameters
    ----------
    stack : Stack
        The stack (SI).
    problem : evotol.core.problem.ToleranceProblem
        Its allocation problem (:func:`evotol.allocators.stack_allocation.stack_problem`).
    results : dict
        Method -> :class:`evotol.core.result.AllocationResult`.
    models : dict of str to StackModel
        The statistical models the figures are given under.
    display : dict
        ``unit``, ``precision`` (drawing precision in that unit), ``n_samples``, ``confidence``.
    seed : int
        Seed of the Monte Carlo (non-normal dimensions).

    Returns
    -------
    dict
        ``measure`` and per method (``methods``): ``cost``, ``feasible``, ``status``, ``verdict``,
        ``normalised_error``, ``tolerances`` (m, the free dimensions'), ``cost_share_percent``, ``stack`` (the figures of
        the allocated stack) and ``drawing``.
    """
    out = {"measure": problem.requirement.measure, "methods": {}}
    units = DisplayUnits(display["unit"])
    dims = set(stack.names)         # once: Stack.names builds a list (2.3 s at 5 000 dimensions when asked per name)
    for m, r in results.items():
        costs = problem.source_costs(r.t)
        total = float(costs.sum())
        st = allocated_stack(stack, problem, r.t)
        fig = analyse_stack(st, models, n_samples=display.get("n_samples", 200_000), seed=seed,
                            confidence=display.get("confidence", 0.95)).to_dict()
        out["methods"][m] = {
            "cost": float(r.cost), "feasible": bool(r.feasible), "status": r.status(), "verdict": r.verdict,
            "normalised_error": float(r.errors.violation[0] + 1),
            "tolerances": {n: float(v) for n, v in zip(problem.names, r.t)       # the allocated (free) half-widths
                           if n in dims and not problem.tolerances[n].is_fixed},
            "cost_share_percent": {n: 100 * float(c) / total if total else 0.0
                                   for n, c in zip(problem.names, costs) if n in dims},
            "stack": fig, "drawing": rounded_design(problem, r.t, units, {display["unit"]: display["precision"]})}
    return out

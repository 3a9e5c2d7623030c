"""What a stack analysis writes: the JSON summary its page is drawn from (SI: m; the display unit
and drawing precision stated beside the values).

:func:`stack_summary` turns a :class:`evotol.measures.stack_analysis.Stack` and its statistical
models into plain data; :func:`evotol.reporting.stack_report.render_stack` draws the page from it alone.
"""
from __future__ import annotations

from evotol.measures.stack_analysis import Stack, analyse_stack
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
        "computed": "m", "n_samples": COUNT, "confidence": "1: confidence level", "seed": COUNT, "seconds": "s"}


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

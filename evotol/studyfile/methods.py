"""``[methods]``: the allocators a study file runs, their keyword tables, and the checks made on
them before the first one runs (an unknown method or keyword, a bad budget, an option a method
cannot honour for this problem).
"""
from __future__ import annotations

from evotol._runtime.keyword_checks import check_keywords, unknown_key_message
from evotol.allocators import (allocate_equal, allocate_ga, allocate_lagrange, allocate_monotone, allocate_nsga2,
                               allocate_optimum, allocate_sensitivity)
from evotol.allocators.budget import check_budget
from evotol.allocators.monotone import check_monotone_options
from evotol.allocators.optimum import check_optimum
from evotol.allocators.preflight import check_methods as check_refusals
from evotol.core.problem import ToleranceProblem
from evotol.errors import ValidationError
from evotol.studyfile.poses import refine_option

METHODS = {"sensitivity": allocate_sensitivity, "optimum": allocate_optimum, "ga": allocate_ga,
           "equal": allocate_equal, "lagrange": allocate_lagrange, "monotone": allocate_monotone}
#: methods that take the whole-workspace refinement option
REFINING_METHODS = ("optimum", "ga")


def study_methods(spec: dict, problem: ToleranceProblem) -> dict:
    """The ``[methods]`` table, or the default: sensitivity, optimum and GA; with clearance
    sources (no sensitivity rule) the GA and the optimum bracket.

    Returns
    -------
    dict
        Method name -> its keyword table, in the order they run.
    """
    return spec.get("methods", {"ga": {}, "monotone": {}} if problem.clearances is not None
                    else {"sensitivity": {}, "optimum": {}, "ga": {}})


def method_options(spec: dict, method: str, kw: dict) -> dict:
    """A method's keywords as the study passes them: its table, plus the ``[poses] refine`` option
    for the methods that take it (:data:`REFINING_METHODS`) unless the table sets its own.

    Parameters
    ----------
    method : str
        The method's name in ``[methods]``.
    kw : dict
        Its keyword table.

    Returns
    -------
    dict
        A copy of ``kw``, with ``refine`` set from ``[poses] refine`` where it applies.
    """
    kw = dict(kw)
    if method in REFINING_METHODS and refine_option(spec):
        kw.setdefault("refine", refine_option(spec))
    return kw


def check_methods(spec: dict, problem: ToleranceProblem, methods: dict) -> None:
    """Check every method table before the first method runs.

    Parameters
    ----------
    spec : dict
        The parsed study file (its ``[poses] refine`` option is checked with the methods).
    methods : dict
        Method name -> keyword table (:func:`study_methods`).

    Raises
    ------
    ValidationError
        An unknown method, a keyword the method does not take, a bad budget, or ``refine``/
        ``budget`` for the optimum of a problem with clearance sources
        (:func:`evotol.allocators.optimum.check_optimum`).
    """
    for m, kw in methods.items():
        if m != "nsga2" and m not in METHODS:
            raise ValidationError(f"methods.{m}", m, unknown_key_message(m, sorted(METHODS) + ["nsga2"]))
        check_keywords(allocate_nsga2 if m == "nsga2" else METHODS[m], kw, f"methods.{m}", exclude=("problem",))
        if "budget" in kw:
            check_budget(problem, kw["budget"], field=f"methods.{m}.budget")
        if m == "optimum":
            opts = method_options(spec, m, kw)
            try:
                check_optimum(problem, budget=opts.get("budget"), refine=opts.get("refine", False))
            except ValidationError as exc:
                if exc.field not in ("budget", "refine"):
                    raise ValidationError(f"methods.optimum: {exc.field}", exc.value, exc.expected) from None
                field = f"methods.optimum.{exc.field}" if exc.field in kw else f"poses.{exc.field}"
                raise ValidationError(field, exc.value, exc.expected) from None
    # every other method's own refusals, before the first one runs (issue 34); the optimum's are checked above
    check_refusals(problem, {m: kw for m, kw in methods.items() if m != "optimum"})


#: the settings of ``[methods] monotone`` every polyblock bracket takes: the ordinary run's, the calibrated one's and
#: the ISO one's (:func:`evotol.allocators.monotone.allocate_monotone`'s other keys, ``budget`` and ``incumbent``,
#: are the ordinary run's alone)
MONOTONE_KEYS = ("max_evaluations", "rel_gap", "batch")


def monotone_options(methods: dict) -> dict:
    """The settings of ``[methods] monotone`` a polyblock bracket on the random sources takes too (:data:`MONOTONE_KEYS`).

    Parameters
    ----------
    methods : dict
        The study's methods and their settings.

    Returns
    -------
    dict
        ``max_evaluations`` (int), ``rel_gap`` (float), ``batch`` (int): the ones the study gives.

    Raises
    ------
    evotol.errors.ValidationError
        One line, ``methods.monotone.<key>``: a setting out of range
        (:func:`evotol.allocators.monotone.check_monotone_options`).
    """
    given = {k: v for k, v in (methods.get("monotone") or {}).items() if k in MONOTONE_KEYS}
    try:
        check_monotone_options(**given)
    except ValidationError as exc:
        raise ValidationError(f"methods.monotone.{exc.field}", exc.value, exc.expected) from None
    return given

"""A tolerance stack written in a study file: the ``[stack]`` table (no Python needed).

::

    name = "motor_end_play"
    [stack]
    gap = "end play"          # the gap's name
    unit = "in"               # unit of every length in [stack]: "mm", "um" (µm), "in" or "m"
    lower_limit = 0.0         # the gap's limits (one of them may be left out)
    upper_limit = 0.12
    distribution = "normal"   # default of the dimensions: normal (±h = 3·Cp·σ), uniform, triangular
    precision = 0.0001        # drawing precision of the page, in `unit` (default: 0.0001 in, 0.001 mm, 0.1 µm)
    [stack.models]            # named statistical models (default: rss = {} -- t = 3σ normal, no shift)
    rss = {}
    six_sigma = { cp = 2.0, k = 0.25, shift_model = "dynamic" }

    [stack.dimensions.A]      # one table per dimension, in loop order
    nominal = 0.375
    upper = 0.0               # signed deviations as on the drawing: +0 / -0.031
    lower = -0.031
    direction = -1            # or sensitivity = -0.5 (∂gap/∂dimension)
    [stack.dimensions.B]
    nominal = 0.032
    tolerance = 0.002         # ± symmetric, instead of upper/lower

An optional ``[stack.allocation]`` table allocates the half-widths by cost
(:func:`allocation_from_table`, :mod:`evotol.allocators.stack_allocation`).

The figures and their conventions: :mod:`evotol.measures.stack_analysis`; the page:
:mod:`evotol.reporting.stack_report`. ``evotol run`` writes ``NAME.json`` (SI, m) and ``NAME.html``.
"""
from __future__ import annotations

import logging

import evotol.cost_models
from evotol._runtime.keyword_checks import check_keywords, check_table_keys, unknown_key_message
from evotol.allocators import allocate_equal, allocate_ga, allocate_lagrange, allocate_optimum, allocate_sensitivity
from evotol.allocators.preflight import check_methods
from evotol.allocators.stack_allocation import stack_problem
from evotol.errors import ValidationError
from evotol.measures.stack_analysis import DISTRIBUTIONS, Stack, StackDimension, StackModel, analyse_stack
from evotol.reporting.stack_report import DEFAULT_PRECISION, render_stack
from evotol.studyfile.kinds import Outcome
from evotol.summaries.stack import allocation_summary, stack_summary
from evotol.units.display import ALIASES, LENGTHS
from evotol.studyfile.steps import run_steps

logger = logging.getLogger(__name__)

STACK_KEYS = ("gap", "unit", "lower_limit", "upper_limit", "distribution", "precision", "models", "dimensions", "allocation",
              "n_samples", "confidence")
DIMENSION_KEYS = ("nominal", "upper", "lower", "tolerance", "direction", "sensitivity", "distribution", "same_part_as",
                  "cost")
ALLOCATION_KEYS = ("measure", "lower", "upper", "cost", "methods", "fixed")
#: allocators a stack takes (their keyword tables as in [methods])
STACK_METHODS = {"optimum": allocate_optimum, "sensitivity": allocate_sensitivity, "ga": allocate_ga,
                 "equal": allocate_equal, "lagrange": allocate_lagrange}
MODEL_KEYS = ("cp", "k", "shift_model")
#: study-file top-level keys beside [stack]
TOP_KEYS = ("name", "seed", "stack", "report")
#: length units a [stack] may be written in -> metres
INPUT_UNITS = {"m": 1.0, **LENGTHS}
def _num(field: str, v) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValidationError(field, v, "a number")
    return float(v)


def _dimension(name: str, t: dict, scale: float, default_dist: str) -> StackDimension:
    f = f"stack.dimensions.{name}"
    check_table_keys(t, DIMENSION_KEYS, f)
    if "nominal" not in t:
        raise ValidationError(f"{f}.nominal", None, "the dimension's nominal value (stack.unit)")
    if "tolerance" in t:
        if "upper" in t or "lower" in t:
            raise ValidationError(f"{f}.tolerance", t["tolerance"], "either tolerance (±) or upper/lower, not both")
        tol = _num(f"{f}.tolerance", t["tolerance"])
        if tol < 0:
            raise ValidationError(f"{f}.tolerance", tol, "a ± tolerance >= 0")
        upper, lower = tol, -tol
    elif "upper" in t and "lower" in t:
        upper, lower = _num(f"{f}.upper", t["upper"]), _num(f"{f}.lower", t["lower"])
    else:
        missing = "upper" if "upper" not in t else "lower"
        raise ValidationError(f"{f}.{missing}", None, "signed upper and lower deviations (e.g. upper = 0.010, "
                              "lower = -0.004), or tolerance = ± value")
    if "direction" in t and "sensitivity" in t:
        raise ValidationError(f"{f}.sensitivity", t["sensitivity"], "either direction (+1/-1) or sensitivity, not both")
    if "direction" in t and t["direction"] not in (1, -1):
        raise ValidationError(f"{f}.direction", t["direction"], "+1 or -1 (use sensitivity = value for another ∂gap/∂dimension)")
    a = _num(f"{f}.sensitivity", t.get("sensitivity", t.get("direction", 1)))
    if lower > upper:       # checked here, in the file's unit (the values below are SI)
        raise ValidationError(f"{f}.lower", lower, f"<= upper ({upper}): signed deviations, e.g. upper = 0.010, "
                              "lower = -0.004 for +0.010/-0.004")
    try:
        return StackDimension(str(name), _num(f"{f}.nominal", t["nominal"]) * scale, upper * scale, lower * scale, a,
                              t.get("distribution", default_dist), t.get("same_part_as"))
    except ValidationError as exc:      # name the field where the file has it
        raise ValidationError(f"stack.{exc.field}", exc.value, exc.expected) from None


def stack_from_table(table) -> tuple[Stack, dict, dict]:
    """The stack, its models and its display settings from a ``[stack]`` table (module docstring).

    Parameters
    ----------
    table : mapping
        The ``[stack]`` table.

    Returns
    -------
    stack : Stack
        The stack in SI (m).
    models : dict of str to StackModel
        The named statistical models.
    display : dict
        ``unit`` (canonical display unit), ``precision`` (in that unit), ``n_samples``, ``confidence``.

    Raises
    ------
    evotol.errors.ValidationError
        An unknown key, a missing ``unit`` or ``dimensions``, a unit evotol does not know, bad
        values (:class:`StackDimension`, :class:`Stack`, :class:`StackModel`).
    """
    check_table_keys(table, STACK_KEYS, "stack")
    if "unit" not in table:
        raise ValidationError("stack.unit", None, f"the length unit of the stack's values, one of {sorted(INPUT_UNITS)}")
    unit = ALIASES.get(table["unit"], table["unit"]) if isinstance(table["unit"], str) else table["unit"]
    if unit not in INPUT_UNITS:
        raise ValidationError("stack.unit", table["unit"], f"one of {sorted(INPUT_UNITS)} (or um, inch)")
    scale = INPUT_UNITS[unit]
    dist = table.get("distribution", "normal")
    if dist not in DISTRIBUTIONS:
        raise ValidationError("stack.distribution", dist, f"one of {DISTRIBUTIONS}")
    dims_t = table.get("dimensions")
    if isinstance(dims_t, list):
        for i, t in enumerate(dims_t):
            if not isinstance(t, dict) or "name" not in t:
                raise ValidationError(f"stack.dimensions[{i}].name", None, "a dimension name")
        dims_t = {t["name"]: {k: v for k, v in t.items() if k != "name"} for t in dims_t}
    if not isinstance(dims_t, dict) or not dims_t:
        raise ValidationError("stack.dimensions", dims_t, "one table per dimension: [stack.dimensions.A] nominal = ...")
    dims = tuple(_dimension(n, t, scale, dist) for n, t in dims_t.items())
    lim = {k: None if k not in table else _num(f"stack.{k}", table[k]) * scale for k in ("lower_limit", "upper_limit")}
    if None not in lim.values() and lim["lower_limit"] >= lim["upper_limit"]:
        raise ValidationError("stack.lower_limit", table["lower_limit"], f"< upper_limit ({table['upper_limit']})")
    try:
        stack = Stack(dims, str(table.get("gap", "gap")), lim["lower_limit"], lim["upper_limit"], "m")
    except ValidationError as exc:
        raise ValidationError(f"stack.{exc.field}", exc.value, exc.expected) from None
    models = {}
    for name, m in (table.get("models") or {"rss": {}}).items():
        check_table_keys(m, MODEL_KEYS, f"stack.models.{name}")
        try:
            models[name] = StackModel(**m)
        except ValidationError as exc:
            raise ValidationError(f"stack.models.{name}.{exc.field.split('.')[-1]}", exc.value, exc.expected) from None
    display_unit = unit if unit in LENGTHS else "mm"
    prec = _num("stack.precision", table.get("precision", DEFAULT_PRECISION[display_unit]))
    if prec <= 0:
        raise ValidationError("stack.precision", prec, f"a positive drawing precision in {display_unit}")
    return stack, models, {"unit": display_unit, "precision": prec, "n_samples": table.get("n_samples", 200_000),
                           "confidence": table.get("confidence", 0.95), "scale": scale}


def allocation_from_table(table: dict, stack: Stack, scale: float):
    """The allocation problem and methods of a ``[stack.allocation]`` table.

    ``measure`` (``"worst_case"`` or ``"rss"``), ``lower``/``upper`` (the half-widths allowed, in
    ``stack.unit``), ``cost`` (a cost-model table: its ``scale`` is SI, as everywhere; a dimension's
    own ``cost`` overrides it), ``fixed`` (dimensions whose drawn zone is kept), ``methods``
    (method -> keyword table; default ``{optimum = {}, sensitivity = {}}``, GA for ``rss``: the
    exact optimum takes no asymmetric RSS).

    Parameters
    ----------
    table : dict
        The ``[stack]`` table (its ``allocation`` and the dimensions' ``cost``).
    stack : Stack
        The stack (SI).
    scale : float
        Metres per unit of ``stack.unit``.

    Returns
    -------
    problem : ToleranceProblem
        :func:`evotol.allocators.stack_allocation.stack_problem`.
    methods : dict
        Method -> keyword arguments, checked against the problem.

    Raises
    ------
    evotol.errors.ValidationError
        An unknown key or method, a bad bound or cost model, a method option the problem refuses
        (all before any allocation runs).
    """
    al = table["allocation"]
    check_table_keys(al, ALLOCATION_KEYS, "stack.allocation")
    measure = al.get("measure", "worst_case")
    fixed = tuple(al.get("fixed", ()))
    for n in fixed:
        if n not in stack.names:
            raise ValidationError("stack.allocation.fixed", n, unknown_key_message(n, stack.names))
    methods = al.get("methods", {"optimum": {}, "sensitivity": {}} if measure == "worst_case" else {"ga": {}, "sensitivity": {}})
    if measure == "rss" and "optimum" in methods and _asymmetric(stack):
        # the optimum's own refusal (evotol.allocators.optimum.check_optimum), read off the drawing before
        # thousands of tolerances are set up (issue 43: 15 s and 2 GB for 5 000 dimensions)
        raise ValidationError("methods.optimum: requirement.measure", "rss",
                              "'worst_case' for the exact optimum of asymmetric zones or limits not centred on the "
                              "nominal gap (|shift| + RSS rows are not quadratic: use ga)")
    dims_t = table["dimensions"]
    dims_t = {t["name"]: t for t in dims_t} if isinstance(dims_t, list) else dims_t
    costs, lo, up = {}, {}, {}
    built = {}        # one cost model per distinct table: from_dict reads the entry points (23 ms a call)
    for d in stack.dimensions:
        if d.name in fixed:
            continue
        cspec = dims_t[d.name].get("cost", al.get("cost"))
        if cspec is None:
            raise ValidationError(f"stack.dimensions.{d.name}.cost", None, "a cost-model table (or stack.allocation.cost)")
        key = repr(cspec)
        try:
            if key not in built:
                built[key] = evotol.cost_models.from_dict(cspec)
        except ValidationError as exc:
            raise ValidationError(f"stack.dimensions.{d.name}.cost: {exc.field}", exc.value, exc.expected) from None
        costs[d.name] = built[key]
        for k, tab in (("lower", lo), ("upper", up)):
            if k not in al:
                raise ValidationError(f"stack.allocation.{k}", None, "the smallest/largest half-width allowed (stack.unit)")
            tab[d.name] = _num(f"stack.allocation.{k}", al[k]) * scale
    try:
        problem = stack_problem(stack, costs, lo, up, measure=measure, fixed=fixed)
    except ValidationError as exc:
        raise ValidationError(f"stack.{exc.field}" if not exc.field.startswith("stack") else exc.field,
                              exc.value, exc.expected) from None
    for m, kw in methods.items():
        if m not in STACK_METHODS:
            raise ValidationError(f"stack.allocation.methods.{m}", m, unknown_key_message(m, sorted(STACK_METHODS)))
        check_keywords(STACK_METHODS[m], kw, f"stack.allocation.methods.{m}", exclude=("problem",))
    check_methods(problem, methods)
    return problem, methods


def _asymmetric(stack: Stack) -> bool:
    """Whether :func:`evotol.allocators.stack_allocation.stack_problem` gives an asymmetric problem:
    a zone not centred on its nominal (``upper != -lower``) or limits whose centre is not the nominal gap."""
    if stack.lower_limit is None or stack.upper_limit is None:
        return False                                   # stack_problem refuses it, naming the limit
    a, n, _, _ = stack.arrays()
    centre = float(a @ n) - 0.5 * (stack.lower_limit + stack.upper_limit)
    return centre != 0 or any(d.upper != -d.lower for d in stack.dimensions)


def stack_study(study) -> Outcome:
    """``evotol run`` of a study file with a ``[stack]`` table: its analysis and, with
    ``[stack.allocation]``, its allocation methods as steps (:mod:`evotol.studyfile.kinds`).

    Parameters
    ----------
    study : evotol.studyfile.kinds.Study
        The run (its file, seed, Ctrl-C and step log).

    Returns
    -------
    evotol.studyfile.kinds.Outcome
        The summary (with ``seconds``) and its page.

    Raises
    ------
    evotol.errors.ValidationError
        A top-level key other than ``name``, ``seed``, ``stack``, ``report``, or a bad ``[stack]``
        table (:func:`stack_from_table`, :func:`allocation_from_table`), before any computation.
    evotol.errors.InfeasibleError
        No allowed half-widths hold the gap within its limits.
    """
    spec, seed = study.spec, study.seed
    check_table_keys(spec, TOP_KEYS, "")
    stack, models, display = stack_from_table(spec["stack"])
    units = (spec.get("report") or {}).get("units")
    if units is not None:
        u = ALIASES.get(units, units) if isinstance(units, str) else units
        if u not in LENGTHS:
            raise ValidationError("report.units", units, f"a length unit among {sorted(LENGTHS)} for a stack")
        display = {**display, "unit": u, "precision": DEFAULT_PRECISION[u] if "precision" not in spec["stack"]
                   else display["precision"]}
    alloc = allocation_from_table(spec["stack"], stack, display["scale"]) if "allocation" in spec["stack"] else None
    summary = stack_summary(study.name, stack, models, display, seed=seed)
    if alloc is not None:
        problem, methods = alloc
        results = run_steps({m: (lambda m=m, kw=kw: STACK_METHODS[m](problem, **{
            **({"seed": seed, "progress": False} if m == "ga" else {}), **kw})) for m, kw in methods.items()},
            study.ctrl_c, study.log)     # the one step loop of every study (evotol/studyfile/steps.py)
        if results:
            summary["allocation"] = allocation_summary(stack, problem, results, models, display, seed=seed)
    summary["seconds"] = study.seconds()
    return Outcome(summary, render_stack)

"""Process selection from a study file: ``[processes.<dimension>]`` tables (docs/process_selection.md).

A study file with a ``processes`` table is a process-selection study: every source (dimension)
lists its candidate processes, each with a ``name``, a ``cost`` model (as in ``[cost.*]``: a table
with ``model`` and its coefficients), a tolerance range ``lower``/``upper`` (SI) and an optional
``fixed_cost`` (set-up cost, cost units). Two spellings, both TOML::

    [[processes.X1]]                       # an array of tables, each with its name
    name = "turn"
    cost = { model = "power", a0 = 0.5, a1 = 1.0, scale = 1e-3 }
    lower = 6e-5
    upper = 1.5e-4
    fixed_cost = 5.0

    [processes.X2.grind]                   # or a table per process, named by its key
    cost = { model = "power", a0 = 0.25, a1 = 1.0, scale = 1e-3 }
    lower = 2e-5
    upper = 1.5e-4

The robot (an assembly function or any robot), the poses and the requirement are read as for an
ordinary study (:func:`evotol.studyfile.load_problem`); ``quality_loss`` adds the Taguchi loss
(``docs/process_selection.md``, "Quality loss"). ``[methods]`` takes ``optimum`` (branch and
bound, :func:`allocate_process_optimum`; ``method = "enumerate"`` for all combinations), ``ga``,
``baselines``, ``nsga2`` (:func:`process_front`) and ``nonlinear_limit`` (worst case: the optimum
re-linearised until the nonlinear worst case holds), with the keyword arguments of those functions;
the outputs are the same JSON/HTML pair as every study (:mod:`evotol.studyfile.process_run`).
"""
from __future__ import annotations

import evotol.cost_models
from evotol.allocators.nonlinear_limit import allocate_process_nonlinear_limit
from evotol.allocators.process import (Process, ProcessProblem, allocate_process_baselines, allocate_process_ga,
                                       allocate_process_optimum, process_front)
from evotol.errors import ValidationError
from evotol._runtime.keyword_checks import check_table_keys, unknown_key_message
from evotol.studyfile.problem import load_problem

PROCESS_KEYS = ("name", "cost", "lower", "upper", "fixed_cost")
#: the ``[methods]`` of a process-selection study (run by :mod:`evotol.studyfile.process_run`)
METHODS = {"optimum": allocate_process_optimum, "ga": allocate_process_ga, "baselines": allocate_process_baselines,
           "nsga2": process_front, "nonlinear_limit": allocate_process_nonlinear_limit}
DEFAULT_METHODS = {"optimum": {}, "ga": {}, "baselines": {}}


def _number(field: str, v, what: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValidationError(field, v, what)
    return float(v)


def parse_process(field: str, name: str, table) -> Process:
    """One process from its table (``field`` names it in errors: ``processes.X1.turn``).

    Parameters
    ----------
    field : str
        The table's place in the study file, named in errors.
    name : str
        The process's name.
    table : mapping
        Its keys: ``cost`` (a cost-model table), ``lower``, ``upper`` (SI tolerances, m or rad),
        optional ``fixed_cost`` (cost units, default 0) and ``name``.

    Returns
    -------
    evotol.allocators.process.Process
        The process.

    Raises
    ------
    ValidationError
        An unknown or missing key, a ``cost`` that is not a valid cost-model table, or a bound or
        fixed cost that is not a number.
    """
    check_table_keys(table, PROCESS_KEYS, field)
    for k in ("cost", "lower", "upper"):
        if k not in table:
            raise ValidationError(f"{field}.{k}", None, "a value (cost: a cost-model table; lower/upper: SI tolerances)")
    if not isinstance(table["cost"], dict):
        raise ValidationError(f"{field}.cost", table["cost"], "a cost-model table, e.g. { model = \"power\", a0 = 0.5, a1 = 1 }")
    try:
        cost = evotol.cost_models.from_dict(table["cost"])
    except ValidationError as exc:
        raise ValidationError(f"{field}.cost: {exc.field}", exc.value, exc.expected) from None
    return Process(str(name), cost, _number(f"{field}.lower", table["lower"], "a positive tolerance (SI)"),
                   _number(f"{field}.upper", table["upper"], "a positive tolerance (SI)"),
                   _number(f"{field}.fixed_cost", table.get("fixed_cost", 0.0), "a cost >= 0"))


def parse_processes(table, source_names) -> dict[str, list[Process]]:
    """``[processes]``: source name -> list of :class:`Process` (both spellings of the module docstring).

    Parameters
    ----------
    table : mapping
        The ``[processes]`` table of the study file.
    source_names : collection of str
        The sources of the problem (an assembly's ``nominal`` dimensions or the robot's sources).

    Returns
    -------
    dict of str to list of Process
        Source name -> its candidate processes, in file order.

    Raises
    ------
    ValidationError
        ``table`` is not a table, names an unknown source, an array entry has no ``name``, or a
        process table is bad (:func:`parse_process`).
    """
    if not isinstance(table, dict):
        raise ValidationError("processes", table, "a table [processes.<dimension>] per source")
    out = {}
    for src, entry in table.items():
        if src not in source_names:
            raise ValidationError(f"processes.{src}", src, unknown_key_message(src, list(source_names)))
        if isinstance(entry, list):
            procs = []
            for i, p in enumerate(entry):
                if not isinstance(p, dict) or "name" not in p:
                    raise ValidationError(f"processes.{src}[{i}].name", None, "a process name")
                procs.append(parse_process(f"processes.{src}[{i}]", p["name"], p))
        elif isinstance(entry, dict):
            procs = [parse_process(f"processes.{src}.{n}", p.get("name", n) if isinstance(p, dict) else n, p)
                     for n, p in entry.items()]
        else:
            raise ValidationError(f"processes.{src}", entry, "[[processes.NAME]] tables or [processes.NAME.PROCESS] tables")
        out[src] = procs
    return out


def load_process_problem(spec: dict, base_dir=None) -> ProcessProblem:
    """The :class:`ProcessProblem` of a study file with a ``processes`` table.

    The geometry (robot, poses, requirement) is read as for every study
    (:func:`evotol.studyfile.problem.load_problem`) with the processes' ranges as bounds and a
    placeholder cost (never used: every process brings its own cost).

    Parameters
    ----------
    spec : dict
        The parsed study file, with a ``processes`` table.
    base_dir : str or Path, optional
        Where relative files named in the study file are looked up.

    Returns
    -------
    ProcessProblem
        The problem, with the quality loss when ``quality_loss`` is given.

    Raises
    ------
    ValidationError
        A bad ``processes`` table (naming ``processes.SOURCE...``), ``cost``/``bounds`` given
        beside ``processes``, or anything :func:`load_problem` refuses.
    """
    for k in ("cost", "bounds"):
        if k in spec:
            raise ValidationError(k, spec[k], "nothing in a process-selection study (costs and ranges come from [processes.*])")
    rs = spec.get("robot", {})
    names = list(rs.get("nominal", {})) if "assembly" in rs else None
    procs_raw = spec["processes"]
    if names is not None:
        procs = parse_processes(procs_raw, names)
    else:
        procs = None
    geo = {k: v for k, v in spec.items() if k not in ("processes", "quality_loss", "methods")}
    geo["cost"] = {"default": {"model": "power", "a0": 1.0, "a1": 1.0, "scale": 1.0}}
    if procs is not None:
        geo["sources"] = {n: {"lower": min(p.lower for p in ps), "upper": max(p.upper for p in ps)}
                          for n, ps in procs.items() if ps}
    base = load_problem(geo, base_dir)
    if procs is None:
        procs = parse_processes(procs_raw, base.names)
    pp = ProcessProblem(base.model, procs, base.requirement, base.poses)
    if "quality_loss" in spec:
        pp = pp.with_quality_loss(spec["quality_loss"])
    return pp

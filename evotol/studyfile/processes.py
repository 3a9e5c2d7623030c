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
the outputs are the same JSON/HTML pair as every study.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

import cost_models
from evotol.allocators.nonlinear_limit import allocate_nonlinear_limit
from evotol.allocators.process import (Process, ProcessProblem, allocate_process_baselines, allocate_process_ga,
                                       allocate_process_optimum, process_front)
from evotol.errors import ValidationError
from evotol._runtime.keyword_checks import check_keywords, check_table_keys, unknown_key_message
from evotol.reporting import Report
from evotol.studies import StudyResult, write_outputs
from evotol.units import COST, COUNT, RELATIVE, units_block

PROCESS_KEYS = ("name", "cost", "lower", "upper", "fixed_cost")
def allocate_process_nonlinear_limit(pp: ProcessProblem, *, max_iter: int = 12, rtol: float = 1e-9):
    """The exact optimum re-linearised until the assembly's nonlinear worst case holds
    (:func:`evotol.allocators.nonlinear_limit.allocate_nonlinear_limit`; worst-case measure).

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
    evotol.allocators.nonlinear_limit.NonlinearLimitResult
        The re-linearised design (``result``), the first-order optimum's nonlinear worst case and
        the cost difference.
    """
    return allocate_nonlinear_limit(pp, allocate_process_optimum, max_iter=max_iter, rtol=rtol)


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
        cost = cost_models.from_dict(table["cost"])
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


def load_process_problem(spec: dict, load_problem, base_dir=None) -> ProcessProblem:
    """The :class:`ProcessProblem` of a study file with a ``processes`` table.

    The geometry (robot, poses, requirement) comes from ``load_problem`` (the study-file reader,
    :func:`evotol.studyfile.load_problem`, passed in by its caller) with the processes' ranges as
    bounds and a placeholder cost (never used: every process brings its own cost).

    Parameters
    ----------
    spec : dict
        The parsed study file, with a ``processes`` table.
    load_problem : callable
        ``load_problem(spec, base_dir) -> ToleranceProblem``, the study-file reader of the
        geometry.
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
    pp = ProcessProblem(base.robot, procs, base.requirement, base.poses)
    if "quality_loss" in spec:
        pp = pp.with_quality_loss(spec["quality_loss"])
    return pp


def _result_dict(pp: ProcessProblem, r) -> dict:
    d = r.to_dict()
    t = np.array([r.tolerances[n] for n in pp.names])
    d["quality_loss"] = float(pp.quality_loss(t)[0])
    d["machining_cost"] = r.cost - d["quality_loss"]
    return d


def run_process_study(spec: dict, path: Path, out, seed: int, load_problem) -> dict:
    """Run the methods of a process-selection study file and write ``NAME.json`` / ``NAME.html``
    (``load_problem``: the study-file reader of the geometry, see :func:`load_process_problem`).

    Parameters
    ----------
    spec : dict
        The parsed study file, with a ``processes`` table.
    path : Path
        The study file (its stem is the default name, its folder the base of relative files).
    out : str or Path
        The output folder.
    seed : int
        Seed of the GA and NSGA-II (unless their tables set one).
    load_problem : callable
        The study-file reader of the geometry (:func:`evotol.studyfile.load_problem`).

    Returns
    -------
    dict
        The JSON summary written (SI, cost units, with its ``units`` block), plus the ``html``
        and ``json`` paths written.

    Raises
    ------
    ValidationError
        An unknown method or keyword in ``[methods]``, or a bad study file
        (:func:`load_process_problem`).
    """
    t0 = time.perf_counter()
    name = spec.get("name", path.stem)
    pp = load_process_problem(spec, load_problem, base_dir=path.parent)
    methods = spec.get("methods", DEFAULT_METHODS)
    for m, kw in methods.items():
        if m not in METHODS:
            raise ValidationError(f"methods.{m}", m, unknown_key_message(m, sorted(METHODS)))
        check_keywords(METHODS[m], kw, f"methods.{m}", exclude=("problem", "pp", "budget"))
    results, front, nonlinear = {}, None, None
    for m, kw in methods.items():
        print(f"[evotol] {m} ...", flush=True)
        kw = dict(kw)
        if m in ("ga", "nsga2"):
            kw.setdefault("seed", seed)
        if m == "baselines":
            results.update({f"baseline {k}": r for k, r in allocate_process_baselines(pp, **kw).items()})
        elif m == "nsga2":
            front = process_front(pp, **kw)
        elif m == "nonlinear_limit":
            nl = allocate_process_nonlinear_limit(pp, **kw)
            results["nonlinear limit"] = nl.result
            nonlinear = {"linear_optimum_nonlinear_worst_case_over_limit": nl.linear_worst_case["max_over_limit"],
                         "nonlinear_worst_case_over_limit": nl.worst_case["max_over_limit"],
                         "method": nl.worst_case["responses"][0]["method"], "cost_difference": nl.cost_difference,
                         "n_iterations": nl.iterations, "converged": nl.converged}
        else:
            results[m] = METHODS[m](pp, **kw)
    summary = {"name": name, "study_file": str(Path(path).resolve()), "problem": pp.describe(), "seed": seed,
               "results": {m: _result_dict(pp, r) for m, r in results.items()},
               "seconds": time.perf_counter() - t0, "units": units_block(pp.base)}
    summary["units"]["keys"].update(quality_loss=COST + " (expected Taguchi loss)", n_nodes=COUNT, n_convex_solves=COUNT,
                                    n_combinations=COUNT, incumbent=COST, smallest_pruned_bound=COST,
                                    leaf_gap=RELATIVE, leaf_kkt_residual=RELATIVE, rtol=RELATIVE)
    summary["units"]["keys"].update({f"{n}_t": u for n, u in zip(pp.names, pp.base.units())})   # front columns
    if front is not None:
        summary["pareto_front"] = front.table.to_dict(orient="list")
    if nonlinear is not None:
        summary["nonlinear_limit"] = nonlinear
    rep = Report(f"evotol process-selection study: {name}",
                 f"{pp.robot.name}, {pp.n_sources} sources, {pp.n_combinations} process combinations, "
                 f"measure {pp.requirement.measure}" + (f", quality loss A = {pp.quality_loss_A}" if pp.quality_loss_A else ""))
    rep.heading("Allocations")
    rows = [[f"{n} (process)"] + [r.processes[n] for r in results.values()] for n in pp.names]
    rows += [[f"{n} (t, SI)"] + [r.tolerances[n] for r in results.values()] for n in pp.names]
    for key in ("machining_cost", "quality_loss"):
        rows.append([key.replace("_", " ")] + [summary["results"][m][key] for m in results])
    rows.append(["total cost"] + [r.cost for r in results.values()])
    rows.append(["max error / limit"] + [r.normalised_error for r in results.values()])
    rows.append(["feasible"] + [r.feasible for r in results.values()])
    rep.table(rows, ["", *results])
    if "optimum" in results and results["optimum"].certificate:
        c = results["optimum"].certificate
        rep.text(f"Certificate: {c['proof']}; incumbent {c['incumbent']:.6g}, leaf duality gap {c['leaf_gap']:.2e}.", note=True)
    if nonlinear is not None:
        rep.text(f"Nonlinear worst case over the tolerance box ({nonlinear['method']}): the first-order optimum reaches "
                 f"{nonlinear['linear_optimum_nonlinear_worst_case_over_limit']:.4f} × the limit; 'nonlinear limit' holds "
                 f"it ({nonlinear['nonlinear_worst_case_over_limit']:.6f}) for {nonlinear['cost_difference']:+.4g} "
                 f"after {nonlinear['n_iterations']} re-linearisations.", note=True)
    if front is not None:
        front_figure(rep, front)
    paths = write_outputs(name, out, StudyResult(summary), rep)
    summary.update({"html": str(paths["html"]), "json": str(paths["json"])})
    return summary


def front_figure(rep: Report, front) -> None:
    """Add the cost vs. normalised error scatter of a :class:`evotol.core.pareto.ParetoFront` to a study report.

    Parameters
    ----------
    rep : evotol.reporting.Report
        The report the figure is added to.
    front : evotol.core.pareto.ParetoFront
        The front: ``cost`` (cost units) against ``error`` (dimensionless, largest error /
        requirement).
    """
    import plotly.graph_objects as go

    fig = go.Figure(go.Scatter(x=front.error, y=front.cost, mode="markers", name="NSGA-II"))
    fig.update_layout(title="Cost vs. normalised error", xaxis_title="max error / requirement", yaxis_title="cost")
    rep.figure(fig)

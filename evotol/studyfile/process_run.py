"""``evotol run`` on a process-selection study file (``[processes.<dimension>]``, read by
:mod:`evotol.studyfile.processes`): the methods of ``[methods]`` -- ``optimum``, ``ga``,
``baselines``, ``nsga2``, ``nonlinear_limit`` -- and the JSON/HTML pair every study writes
(docs/process_selection.md).
"""
from __future__ import annotations

import logging
import time
from pathlib import Path

import numpy as np

from evotol._runtime.keyword_checks import check_keywords, unknown_key_message
from evotol.allocators.nonlinear_limit import allocate_process_nonlinear_limit
from evotol.allocators.process import ProcessProblem, allocate_process_baselines, process_front
from evotol.errors import ValidationError
from evotol.reporting import Report
from evotol.studyfile.kinds import Outcome, run_kind
from evotol.studyfile.steps import run_steps
from evotol.studyfile.processes import DEFAULT_METHODS, METHODS, load_process_problem
from evotol.units import COST, COUNT, RELATIVE, units_block

logger = logging.getLogger(__name__)

def _result_dict(pp: ProcessProblem, r) -> dict:
    d = r.to_dict()
    t = np.array([r.tolerances[n] for n in pp.names])
    d["quality_loss"] = float(pp.quality_loss(t)[0])
    d["machining_cost"] = r.cost - d["quality_loss"]
    return d


def run_process_study(spec: dict, path: Path, out, seed: int, keep_going: bool = False) -> dict:
    """Run the methods of a process-selection study file and write ``NAME.json`` / ``NAME.html``
    through the one pipeline of every study (:func:`evotol.studyfile.kinds.run_kind`; ``evotol run``
    claims the output set first).

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
    keep_going : bool, optional
        After a Ctrl-C, still run the remaining methods.

    Returns
    -------
    dict
        The JSON summary written (SI, cost units, with its ``units`` block), plus the ``html``
        and ``json`` paths written.

    Raises
    ------
    ValidationError
        An unknown method or keyword in ``[methods]``, or a bad study file
        (:func:`evotol.studyfile.processes.load_process_problem`).
    """
    return run_kind(process_study, spec, path, out, spec.get("name", Path(path).stem), seed, keep_going=keep_going)


def process_study(study) -> Outcome:
    """A process-selection study's methods as steps (module docstring), its summary and page.

    Parameters
    ----------
    study : evotol.studyfile.kinds.Study
        The run.

    Returns
    -------
    evotol.studyfile.kinds.Outcome
        The summary and its page.

    Raises
    ------
    ValidationError
        As :func:`run_process_study`, before any method runs.
    """
    spec, path, seed, name = study.spec, study.path, study.seed, study.name
    pp = load_process_problem(spec, base_dir=path.parent)
    methods = spec.get("methods", DEFAULT_METHODS)
    for m, kw in methods.items():
        if m not in METHODS:
            raise ValidationError(f"methods.{m}", m, unknown_key_message(m, sorted(METHODS)))
        check_keywords(METHODS[m], kw, f"methods.{m}", exclude=("problem", "pp", "budget"))

    def method(m, kw):
        kw = {**({"seed": seed} if m in ("ga", "nsga2") else {}), **kw}
        special = {"baselines": allocate_process_baselines, "nsga2": process_front,
                   "nonlinear_limit": allocate_process_nonlinear_limit}
        return lambda: special.get(m, METHODS[m])(pp, **kw)

    done = run_steps({m: method(m, kw) for m, kw in methods.items()}, study.ctrl_c, study.log)
    results, front, nonlinear = {}, done.get("nsga2"), None
    for m, value in done.items():       # in the order of [methods]
        if m == "baselines":
            results.update({f"baseline {k}": r for k, r in value.items()})
        elif m == "nonlinear_limit":
            results["nonlinear limit"] = value.result
            nonlinear = {"linear_optimum_nonlinear_worst_case_over_limit": value.linear_worst_case["max_over_limit"],
                         "nonlinear_worst_case_over_limit": value.worst_case["max_over_limit"],
                         "method": value.worst_case["responses"][0]["method"], "cost_difference": value.cost_difference,
                         "n_iterations": value.iterations, "converged": value.converged}
        elif m != "nsga2":
            results[m] = value
    t0 = study.t0
    summary = {"name": name, "problem": pp.describe(), "seed": seed,
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
    return Outcome(summary, lambda summary: _page(summary, pp, results, front, nonlinear))


def _page(summary: dict, pp: ProcessProblem, results: dict, front, nonlinear) -> Report:
    """The process study's page from its summary and results."""
    name = summary["name"]
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
    return rep


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

"""``evotol run STUDY.toml``: read the file, run its methods and Monte Carlo checks, write the JSON,
the page and the drawing table (``docs/user_reports.md``). A file with ``[processes]`` is run by
:func:`evotol.studyfile.process_run.run_process_study`.
"""
from __future__ import annotations

import time
import tomllib
from contextlib import nullcontext
from pathlib import Path

from evotol._runtime.interrupt import CtrlC
from evotol._runtime.keyword_checks import check_keywords
from evotol._runtime.output_paths import check_not_overwriting
from evotol._runtime.progress import Heartbeat
from evotol._runtime.toml_kinds import check_kind
from evotol.allocators import allocate_nsga2
from evotol.calibration.summary import add_to_study as add_calibration
from evotol.core.problem import ToleranceProblem
from evotol.errors import ValidationError
from evotol.measures.statistical.distributions import Distribution, as_distribution
from evotol.reporting.export import FORMATS as EXPORT_FORMATS
from evotol.reporting.callout_drawing import write_callout_exports
from evotol.reporting.export import write_tolerance_table
from evotol.reporting.user_study import render_user_study
from evotol.studies import StudyResult, write_outputs
from evotol.studyfile.methods import METHODS, check_methods, method_options, study_methods
from evotol.studyfile.callouts import callout_summary, callout_warnings
from evotol.studyfile.poses import refine_option
from evotol.studyfile.given_tolerances import run_given_tolerances
from evotol.studyfile.problem import load_problem
from evotol.studyfile.stack_table import run_stack_study
from evotol.summaries.drawing import drawing_precision, precision_warnings
from evotol.studyfile.process_run import run_process_study
from evotol.core.shop import apply_shop
from evotol.core.plausibility import study_warnings, warn as warn_plausibility
from evotol.summaries.user_study import study_summary
from evotol.units.display import DisplayUnits, parse_units, problem_units
from evotol.verification.montecarlo import verify


def report_units(spec: dict, problem: ToleranceProblem) -> DisplayUnits:
    """The study's display units: ``[report] units``, else the mechanism's ``display`` (evotol.units.display).

    Parameters
    ----------
    spec : dict
        The parsed study file.
    problem : ToleranceProblem
        The study's problem (its robot's workspace gives the defaults).

    Returns
    -------
    DisplayUnits
        The units of the report, the terminal and the drawing export.

    Raises
    ------
    ValidationError
        A bad ``[report] units`` (:func:`evotol.units.display.parse_units`).
    """
    return parse_units(spec.get("report", {}).get("units"), problem_units(problem))


def verification_model(spec: dict, problem: ToleranceProblem, vspec: dict) -> Distribution | None:
    """The one distribution the study's Monte Carlo samples every source from, or None for each
    source's own (issue 34: every verdict on one stated model).

    An ``rss`` requirement takes every tolerance as 3σ of a normal about its zone's centre; its
    Monte Carlo samples that model -- normal with σ = half-width / 3, or with the file's top-level
    ``sigma_k`` -- unless the file states the sources' distributions (a top-level or ``[bounds]``
    ``distribution``, or ``distribution``/``sigma_k``/``mean_shift`` in a ``[sources.NAME]``
    table) or ``[verify]`` chooses (its ``distribution``, or ``model = "nonlinear"``).

    Parameters
    ----------
    spec : dict
        The parsed study file (its ``distribution`` keys).
    problem : ToleranceProblem
        The study's problem (its requirement's measure).
    vspec : dict
        The ``[verify]`` table.

    Returns
    -------
    Distribution or None
        ``Distribution("normal", sigma_k)`` for an ``rss`` requirement whose sources' distributions
        the file does not state; None otherwise.
    """
    if problem.requirement.measure != "rss" or "distribution" in vspec or vspec.get("model") == "nonlinear":
        return None
    per_source = any(k in o for o in spec.get("sources", {}).values() if isinstance(o, dict)
                     for k in ("distribution", "sigma_k", "mean_shift"))
    if per_source or "distribution" in spec or "distribution" in spec.get("bounds", {}):
        return None
    return Distribution("normal", float(spec.get("sigma_k", 3.0)))


def read_study_file(path: Path) -> dict:
    """The parsed study file at ``path``.

    Parameters
    ----------
    path : Path
        The study file (TOML).

    Returns
    -------
    dict
        The parsed TOML.

    Raises
    ------
    ValidationError
        The file does not exist, is not valid TOML, or is a mechanism description.
    """
    if not path.exists():
        raise ValidationError("study file", str(path), "an existing TOML file")
    try:
        spec = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ValidationError("study file", str(path), f"valid TOML ({exc})") from None
    check_kind(spec, "study", path)          # a mechanism description given as a study file (issue 27)
    return spec


def run_study_file(path, out=None, seed=None, keep_going: bool = False, force: bool = False) -> dict:
    """Run the study; Ctrl-C stops the running method (GA/NSGA-II keep their best so far), skips the
    remaining ones unless ``keep_going``, and the partial results are still written, marked
    ``"interrupted": true`` in the JSON and in the report's header (issue 15).

    A study file with ``[processes]`` is run by
    :func:`evotol.studyfile.process_run.run_process_study`.

    Parameters
    ----------
    path : str or Path
        The study file (TOML).
    out : str or Path, optional
        The output folder (default: the study file's folder).
    seed : int, optional
        Overrides the file's ``seed`` (default: the file's, else 0).
    keep_going : bool, optional
        After a Ctrl-C, still run the remaining methods and Monte Carlo checks.
    force : bool, optional
        Overwrite another study's files of the same name in ``out``.

    Returns
    -------
    dict
        The JSON summary written (:func:`evotol.summaries.user_study.study_summary`, SI), with
        ``study_file``, ``warnings``, ``notes``, ``interrupted`` and the ``html`` and ``json``
        paths written.

    Raises
    ------
    ValidationError
        The file does not exist, is not valid TOML, is a mechanism description, would overwrite
        another study's files, or has a bad key or value (:func:`load_problem`, an unknown
        method, a keyword a method or ``verify`` does not take, a ``[verify] distribution``
        that does not suit a source, a bad budget, an option a method cannot honour for the
        problem).
    evotol.errors.InfeasibleError
        No allowed design meets the requirement (checked before the first method).
    """
    path = Path(path)
    spec = read_study_file(path)
    t0 = time.perf_counter()
    seed = spec.get("seed", 0) if seed is None else seed
    name = spec.get("name", path.stem)
    out = Path(out) if out else path.parent
    check_not_overwriting(out, name, path, force)     # another study's files (issue 27); before any work
    if "processes" in spec:     # process selection: [processes.<dimension>] (evotol/studyfile/processes.py)
        return run_process_study(spec, path, out, seed)
    if "stack" in spec:         # a tolerance stack written in the file: [stack] (evotol/studyfile/stack_table.py)
        return run_stack_study(spec, path, out, seed)
    problem = apply_shop(spec, load_problem(spec, base_dir=path.parent))    # [shop] floors, measurable (issue 41)
    units = report_units(spec, problem)
    if not problem.free.any():     # every tolerance given: nothing to allocate, analyse them (issue 33)
        return run_given_tolerances(spec, path, out, name, problem, units, seed, t0)
    precision = drawing_precision(spec.get("report", {}).get("precision"), units)   # [report] precision (issue 34)
    coarse = precision_warnings(problem, units, precision)      # a step coarser than the zones (issue 41)
    problem.warnings = [*problem.warnings, *coarse]
    warn_plausibility(coarse)
    methods = study_methods(spec, problem)
    vspec = spec.get("verify", {"n_samples": 1000})
    check_methods(spec, problem, methods)           # every table checked before the first method runs
    check_keywords(verify, vspec, "verify", exclude=("problem", "tolerances", "seed", "progress"))
    if "distribution" in vspec:     # [verify] distribution: checked against every source before any work
        for src in problem.error_model.sources:
            as_distribution(vspec["distribution"], "verify.distribution", src.dim)
    vmodel = verification_model(spec, problem, vspec)     # an rss requirement: checked on its own model (issue 34)
    if vmodel is not None:
        vspec = {**vspec, "distribution": vmodel}
    if any("budget" not in kw for m, kw in methods.items() if m != "nsga2"):
        problem.check_feasible()            # a requirement no design meets: say so before the first method
    results, front, stopped, skipped = {}, None, [], []
    with CtrlC() as ctrl_c:
        for m, kw in methods.items():
            if ctrl_c.count and not keep_going:
                skipped.append(m)
                continue
            print(f"[evotol] {m} ...", flush=True)
            before = ctrl_c.count
            try:
                if m == "nsga2":
                    front = allocate_nsga2(problem, seed=seed, **{"progress": True, **kw})   # a bar, or lines in a log
                    continue
                kw = method_options(spec, m, kw)
                if m == "ga":
                    kw.setdefault("seed", seed)
                    kw.setdefault("progress", True)       # a bar on a terminal, lines in a log (issue 27)
                if m == "monotone" and "ga" in results and results["ga"].feasible:   # the GA's design as incumbent
                    kw.setdefault("incumbent", results["ga"].t)
                with Heartbeat(m, bar=True) if m != "ga" else nullcontext():   # a line every 10 s or a bar (a GA: its own)
                    results[m] = METHODS[m](problem, **kw)
            except KeyboardInterrupt:
                ctrl_c.count = max(ctrl_c.count, before + 1)
            finally:
                if ctrl_c.count > before:
                    stopped.append(m)
        checks = {}
        for m, r in results.items():
            if ctrl_c.count and not keep_going:     # the user asked to stop: no Monte Carlo
                skipped.append(f"verify {m}")
                continue
            before = ctrl_c.count
            try:
                checks[m] = verify(problem, r.t, seed=seed, progress=True, **vspec).to_dict()
            except KeyboardInterrupt:
                ctrl_c.count = max(ctrl_c.count, before + 1)
            if ctrl_c.count > before:
                stopped.append(f"verify {m}")
    summary = study_summary(name, problem, results, front, checks, seed=seed, units=units,
                            seconds=time.perf_counter() - t0, precision=precision)
    summary["study_file"] = str(path.resolve())
    summary["warnings"] = study_warnings(problem, results.values())   # unit slips (issue 27)
    summary["notes"] = list(getattr(problem.robot, "notes", list)())      # e.g. a redundant arm's posture (issue 23)
    if getattr(problem, "calibration", None) is not None and results:   # what calibration buys (docs/calibration.md)
        add_calibration(summary, problem, results, seed)
    summary["interrupted"] = bool(stopped)
    if hasattr(problem.robot, "describe_callouts") and results and not stopped:   # exact zones vs boxes (issue 35)
        refine = refine_option(spec)
        opts = {"refine": refine} if refine else {}
        # the study's own optimum is the exact zones' side of the comparison when it ran with these options
        same = "optimum" in results and method_options(spec, "optimum", methods.get("optimum", {})) == opts
        summary["callouts"] = callout_summary(problem, results["optimum"] if same else None, **opts)
        summary["warnings"] = [*summary["warnings"], *callout_warnings(problem)]
    if stopped:
        summary["interruption"] = {"stopped": stopped, "skipped": skipped, "keep_going": keep_going}
    if results:     # the drawing table, linked from the page (evotol/reporting/export.py)
        summary["exports"] = {k: f"{name}_tolerances.{k}" for k in EXPORT_FORMATS}
    rep = render_user_study(summary)
    paths = write_outputs(name, out, StudyResult(summary), rep)
    for f in summary.get("exports", {}).values():
        write_tolerance_table(summary, out / f)
    if summary.get("callouts"):     # the drawing callouts: a CSV, and two sheets of the workbook
        summary["exports"]["drawing"] = f"{name}_drawing.csv"
        write_callout_exports(summary, out / f"{name}_drawing.csv", out / summary["exports"]["xlsx"])
    summary.update({"html": str(paths["html"]), "json": str(paths["json"])})
    return summary

"""``evotol run STUDY.toml``: read the file, run its methods and Monte Carlo checks, write the JSON,
the page and the drawing table (``docs/user_reports.md``). A file with ``[processes]`` is run by
:func:`evotol.studyfile.process_run.run_process_study`.
"""
from __future__ import annotations

import logging
import time
import tomllib
from contextlib import nullcontext
from pathlib import Path

from evotol._runtime.keyword_checks import check_keywords
from evotol._runtime.output_paths import path_inside
from evotol._runtime.output_set import claim_outputs
from evotol._runtime.progress import Heartbeat
from evotol._runtime.toml_kinds import check_kind
from evotol.allocators import allocate_nsga2
from evotol.core.problem import ToleranceProblem
from evotol.errors import ValidationError
from evotol.measures.statistical.distributions import Distribution, as_distribution
from evotol.reporting.export import FORMATS as EXPORT_FORMATS
from evotol.reporting.export import write_tolerance_table
from evotol.reporting.user_study import render_user_study

logger = logging.getLogger(__name__)
from evotol.studyfile.methods import METHODS, check_methods, method_options, study_methods
from evotol.studyfile.sections import SECTIONS, StudyRun
from evotol.studyfile.comparisons import comparison_runs, run_comparison
from evotol.studyfile.steps import run_steps
from evotol.studyfile.given_tolerances import given_tolerances_outcome
from evotol.studyfile.kinds import Outcome, Study, StudyKind, run_kind
from evotol.studyfile.iso9283 import read_iso9283
from evotol.studyfile.problem import load_problem
from evotol.studyfile.stack_table import stack_study
from evotol.summaries.drawing import drawing_precision, precision_warnings
from evotol.studyfile.process_run import process_study
from evotol.core.memory import check_memory
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
        spec = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValidationError("study file", str(path), f"valid TOML in UTF-8 ({exc})") from None
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
    # the name checked, one writer, another study's files refused (issues 27, 42); before any work
    with claim_outputs(out, name, f"study file {path.resolve()}", force=force, study_file=path):
        return _run_claimed(spec, path, out, name, seed, t0, keep_going)


def _run_claimed(spec: dict, path: Path, out: Path, name: str, seed: int, t0: float, keep_going: bool) -> dict:
    """The body of :func:`run_study_file`, run while it holds the output set (its Returns): the file's
    kind (:data:`KINDS`, the first whose ``present`` holds) run through the one pipeline
    (:func:`evotol.studyfile.kinds.run_kind`)."""
    kind = next(k for k in KINDS if k.present(spec))
    return run_kind(kind.run, spec, path, out, name, seed, t0, keep_going)


def robot_study(study: Study) -> Outcome:
    """A robot or mechanism study: its methods, comparisons and Monte Carlo checks as steps, then
    its summary with each present section's block (or, every tolerance given, their analysis).

    Parameters
    ----------
    study : evotol.studyfile.kinds.Study
        The run.

    Returns
    -------
    evotol.studyfile.kinds.Outcome
        The summary, its page and the drawing table's and sections' files.
    """
    spec, path, seed, log = study.spec, study.path, study.seed, study.log
    problem = apply_shop(spec, load_problem(spec, base_dir=path.parent))    # [shop] floors, measurable (issue 41)
    iso = read_iso9283(spec, problem)       # ISO 9283 AP/RP and random sources, checked before work (issue 44)
    units = report_units(spec, problem)
    if not problem.free.any():     # every tolerance given: nothing to allocate, analyse them (issue 33)
        return given_tolerances_outcome(study, problem, units, iso)
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
    check_memory(problem)           # more poses than the machine's memory holds: said with the estimate (issue 43)
    if any("budget" not in kw for m, kw in methods.items() if m != "nsga2"):
        problem.check_feasible()            # a requirement no design meets: say so before the first method
    results = {}

    def method(m, kw):
        def step():
            if m == "nsga2":        # a front, not a design: taken out of the results below
                return allocate_nsga2(problem, **{"seed": seed, "progress": True, **kw})   # its own seed if set   # a bar, or log lines
            opts = method_options(spec, m, kw)
            if m == "ga":
                opts.setdefault("seed", seed)
                opts.setdefault("progress", True)       # a bar on a terminal, lines in a log (issue 27)
            if m == "monotone" and "ga" in results and results["ga"].feasible:   # the GA's design as incumbent
                opts.setdefault("incumbent", results["ga"].t)
            with Heartbeat(m, bar=True) if m != "ga" else nullcontext():   # a line every 10 s or a bar (a GA: its own)
                return METHODS[m](problem, **opts)
        return step

    def comparison(c, run):
        def step():
            with Heartbeat(c, bar=True):
                return run_comparison(run)
        return step

    ctrl_c = study.ctrl_c
    run_steps({m: method(m, kw) for m, kw in methods.items()}, ctrl_c, log, results)
    front = results.pop("nsga2", None)
    # what the sections compare with: ordinary runs under the same Ctrl-C (issue 39)
    compared = run_steps({c: comparison(c, run) for c, run in
                          (comparison_runs(spec, problem, methods) if results else {}).items()}, ctrl_c, log)
    checks = run_steps({m: (lambda r=r: verify(problem, r.t, seed=seed, progress=True, **vspec).to_dict())
                        for m, r in results.items()}, ctrl_c, log, label="verify ", say=False)
    summary = study_summary(study.name, problem, results, front, checks, seed=seed, units=units,
                            seconds=study.seconds(), precision=precision)
    summary["warnings"] = study_warnings(problem, results.values())   # unit slips (issue 27)
    summary["notes"] = list(problem.model.notes())      # e.g. a redundant arm's posture (issue 23)
    run = StudyRun(problem, results, compared, seed, bool(log.stopped), iso)
    present = [s for s in SECTIONS if s.present(run)]      # callouts, calibration, ISO 9283 (sections.py)
    for section in present:
        section.summarise(summary, run)
    exports = []
    if results:     # the drawing table, linked from the page (evotol/reporting/export.py)
        summary["exports"] = {k: f"{study.name}_tolerances.{k}" for k in EXPORT_FORMATS}
        exports.append(lambda summary, out, name: [write_tolerance_table(summary, path_inside(out, f))
                                                   for f in summary["exports"].values()])
    exports += [section.export for section in present if section.export is not None]
    return Outcome(summary, render_user_study, exports)


#: the kinds of study file, tried in order (evotol/studyfile/kinds.py): the first whose ``present`` holds runs
KINDS = (StudyKind("processes", lambda spec: "processes" in spec, process_study),   # [processes.<dimension>]
         StudyKind("stack", lambda spec: "stack" in spec, stack_study),               # [stack] (stack_table.py)
         StudyKind("robot", lambda spec: True, robot_study))                          # a robot or mechanism

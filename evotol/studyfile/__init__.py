"""``evotol run STUDY.toml``: a user's own allocation study, with the same outputs as the seeds.

See ``reports/studies/ucr3_example.toml`` for every field. Units are SI (m, rad); a cost model's
``scale`` is the unit its coefficients were fitted in. Tolerance specifications
(``docs/tolerances.md``): per source ``offset``/``minus``/``plus``, ``cost_width``,
``contains_nominal``, ``fixed = t``, ``distribution`` (+ ``sigma_k``, ``mean_shift``); a
``[shared]`` table (``legs = ["l1", "l2", "l3"]``) with ``shared_cost = "part" | "variable"``;
``[poses] refine = true`` (or a table of refinement options) for the whole workspace;
``[clearances]`` joint-clearance classes allocated with the geometric sources
(``docs/clearance_allocation.md``); ``[report] units = "mm"`` (or ``"um, arcsec"``...): the units
the report, the terminal and the drawing export show (``docs/units.md``; the JSON stays SI).
The outputs and the page: ``docs/user_reports.md``.
Every key is checked: an unknown one is an error naming it and the nearest valid key.
"""
from __future__ import annotations

import dataclasses
import time
import tomllib
from contextlib import nullcontext
from pathlib import Path

import numpy as np

import cost_models
from evotol.measures import clearances
from evotol.core import plausibility
from evotol.allocators import (allocate_equal, allocate_ga, allocate_lagrange, allocate_monotone, allocate_nsga2,
                               allocate_optimum, allocate_sensitivity)
from evotol.allocators.budget import check_budget
from evotol.units.display import DisplayUnits, parse_units, problem_units
from evotol.core.distributions import Distribution
from evotol.errors import ValidationError
from evotol._runtime.toml_kinds import check_kind
from evotol._runtime.interrupt import CtrlC
from evotol._runtime.keyword_checks import check_keywords, check_table_keys, unknown_key_message
from evotol.verification.montecarlo import verify
from evotol._runtime.output_paths import check_not_overwriting
from evotol._runtime.progress import Heartbeat
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from evotol.studyfile.processes import run_process_study
from evotol.core.quality_loss import with_quality_loss
from evotol.reporting.export import FORMATS as EXPORT_FORMATS
from evotol.reporting.export import write_tolerance_table
from evotol.reporting.user_study import render_user_study
from evotol.studies import StudyResult, write_outputs
from evotol.summaries.user_study import study_summary
from robots import registry
from robots.assembly import assembly_from_spec
from robots.mechanism.model import model_from_table
from evotol.core.axis_limits import AXIS_KEYS, axis_requirement
from evotol.studyfile.given_tolerances import run_given_tolerances
from evotol.studyfile.joint_poses import drop_unreachable, joint_poses

METHODS = {"sensitivity": allocate_sensitivity, "optimum": allocate_optimum, "ga": allocate_ga,
           "equal": allocate_equal, "lagrange": allocate_lagrange, "monotone": allocate_monotone}
TOP_KEYS = ("name", "seed", "robot", "poses", "requirement", "bounds", "cost", "sources", "shared", "shared_cost",
            "methods", "verify", "distribution", "sigma_k", "clearances", "quality_loss", "processes", "report")
REPORT_KEYS = ("units",)
POSE_KEYS = ("grid", "latin_hypercube", "list", "refine", "joints", "drop_unreachable")
REFINE_KEYS = ("grid", "local", "add", "max_rounds", "tol", "n_final", "n_local")
BOUND_KEYS = ("lower", "upper", "cost_width", "distribution", "contains_nominal")
SOURCE_KEYS = ("lower", "upper", "locked", "fixed", "cost", "distribution", "sigma_k", "mean_shift", "offset", "minus",
               "plus", "cost_width", "contains_nominal")
REQUIREMENT_KEYS = tuple(f.name for f in dataclasses.fields(Requirement)) + AXIS_KEYS
#: methods that take the whole-workspace refinement option
REFINING_METHODS = ("optimum", "ga")


def check_study_keys(spec: dict) -> None:
    """Check every table of a study file whose keys evotol defines (typos like ``lowr`` or
    ``[requirment]`` are errors, not silently ignored).

    Parameters
    ----------
    spec : dict
        The parsed study file.

    Raises
    ------
    ValidationError
        An unknown key in the top level, ``[poses]``, ``[poses.refine]``, ``[requirement]``,
        ``[report]``, ``[bounds]`` or a ``[sources.NAME]`` table; a ``refine`` that is neither a
        bool nor a table; a ``seed`` that is not a non-negative integer.
    """
    check_table_keys(spec, TOP_KEYS, "")
    check_table_keys(spec.get("poses", {}), POSE_KEYS, "poses")
    ref = spec.get("poses", {}).get("refine")
    if isinstance(ref, dict):
        check_table_keys(ref, REFINE_KEYS, "poses.refine")
    elif ref is not None and not isinstance(ref, bool):
        raise ValidationError("poses.refine", ref, "true, false or a table of refinement options")
    check_table_keys(spec.get("requirement", {}), REQUIREMENT_KEYS, "requirement")
    check_table_keys(spec.get("report", {}), REPORT_KEYS, "report")
    bounds = spec.get("bounds", {})   # sub-tables [bounds.GROUP] are checked once the robot is known
    check_table_keys({k: v for k, v in bounds.items() if not isinstance(v, dict)} if isinstance(bounds, dict) else bounds,
                     BOUND_KEYS, "bounds")
    for n, o in spec.get("sources", {}).items():
        check_table_keys(o, SOURCE_KEYS, f"sources.{n}")
    seed = spec.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValidationError("seed", seed, "a non-negative integer")


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


def refine_option(spec: dict):
    """The ``[poses] refine`` setting as allocator keyword: False, True or a dict of options.

    Parameters
    ----------
    spec : dict
        The parsed study file.

    Returns
    -------
    bool or dict
        False when absent; the options table as a dict; else ``bool(refine)``.
    """
    ref = spec.get("poses", {}).get("refine", False)
    return dict(ref) if isinstance(ref, dict) else bool(ref)


def _tolerance(s, o: dict, bounds: dict, costs: dict, spec: dict) -> Tolerance:
    """One source's :class:`Tolerance` from its ``[sources.NAME]`` table and the defaults."""
    shape = {k: o.get(k, bounds.get(k)) for k in ("cost_width", "contains_nominal") if k in o or k in bounds}
    shape.update({k: float(o[k]) if isinstance(o[k], (int, float)) and not isinstance(o[k], bool) else o[k]
                  for k in ("offset", "minus", "plus") if k in o})
    # distribution, sigma_k (t = k·σ) and mean_shift (fraction of t): per source, else top level
    dist = o.get("distribution", bounds.get("distribution", spec.get("distribution", "uniform")))
    if isinstance(dist, dict):
        dist = {"sigma_k": spec.get("sigma_k", 3.0), **dist}
    else:
        dist = Distribution(dist, o.get("sigma_k", spec.get("sigma_k", 3.0)), o.get("mean_shift", 0.0))
    if "fixed" in o:
        extra = sorted(set(o) & {"lower", "upper", "locked", "cost"})
        if extra:
            raise ValidationError(f"sources.{s.name}.{extra[0]}", o[extra[0]], "nothing: a fixed source has no range, lock or cost")
        return Tolerance.fixed(o["fixed"], distribution=dist, **shape)
    cspec = o.get("cost", costs.get(s.name, costs.get(s.group, costs.get("default"))))
    if cspec is None:
        raise ValidationError(f"cost.{s.group}", None, f"a cost model for source {s.name} (by name, group or 'default')")
    return Tolerance(cost=cost_models.from_dict(cspec), lower=_bound(o, bounds, s, "lower", 1e-6),
                     upper=_bound(o, bounds, s, "upper", 1e-3), locked=o.get("locked"),
                     distribution=dist, **shape)


GROUP_BOUND_KEYS = ("lower", "upper")     # keys of [bounds.GROUP] / [bounds.SOURCE]


def _check_bounds_table(bounds, robot) -> None:
    """``[bounds]``: ``lower``/``upper`` for every source, and sub-tables by group or source name
    (``[bounds."U joint"]``, ``[bounds.l1]``) -- sources in m and in rad need their own ranges."""
    if not isinstance(bounds, dict):
        raise ValidationError("bounds", bounds, "a table with lower/upper and optional group or source sub-tables")
    names = {*robot.source_names, *(s.group for s in robot.sources)}
    for key, value in bounds.items():
        if key in BOUND_KEYS:
            continue
        if key not in names or not isinstance(value, dict):
            raise ValidationError(f"bounds.{key}", value, unknown_key_message(key, [*BOUND_KEYS, *sorted(names)])
                                  + " (a group or source name takes a table: [bounds.GROUP] lower = ..., upper = ...)")
        for k, v in value.items():
            if k not in GROUP_BOUND_KEYS:
                raise ValidationError(f"bounds.{key}.{k}", v, unknown_key_message(k, GROUP_BOUND_KEYS))


def _bound(override: dict, bounds: dict, source, which: str, default: float) -> float:
    """lower/upper of one source: [sources.NAME] > [bounds.NAME] > [bounds.GROUP] > [bounds] > default."""
    for field, table in ((f"sources.{source.name}", override), (f"bounds.{source.name}", bounds.get(source.name, {})),
                         (f"bounds.{source.group}", bounds.get(source.group, {})), ("bounds", bounds)):
        if which in table:
            v = table[which]
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ValidationError(f"{field}.{which}", v, "a positive tolerance in SI units (m or rad)")
            return float(v)
    return default


def load_problem(spec: dict, base_dir=None) -> ToleranceProblem:
    """Build the problem from a parsed study file (dict); ``base_dir``: where relative files
    (``[robot] mechanism = "my_robot.toml"``) are looked up.

    Parameters
    ----------
    spec : dict
        The parsed study file (keys checked by :func:`check_study_keys`).
    base_dir : str or Path, optional
        Where relative files are looked up (default: the current folder).

    Returns
    -------
    ToleranceProblem
        The problem (with the Taguchi loss when ``quality_loss`` is given); tolerances and
        requirement in SI (m, rad).

    Raises
    ------
    ValidationError
        An unknown key or bad value anywhere in the file: a ``[processes]`` table (read by
        :func:`evotol.studyfile.processes.load_process_problem` instead), no robot model, robot
        parameters the model does not take, a bad ``[poses]`` table, an unknown source in
        ``[sources]``, a bad ``[bounds]`` table or bound, a fixed source with a range, lock or
        cost, a source without a cost model; and what the problem's own checks refuse.
    """
    check_study_keys(spec)
    if "processes" in spec:
        raise ValidationError("processes", sorted(spec["processes"]), "no [processes.*] here: a process-selection study "
                              "is read by evotol.studyfile.processes.load_process_problem (evotol run does so)")
    rs = dict(spec.get("robot", {}))
    if "mechanism" in rs or "urdf" in rs:       # a description (robots/mechanism, docs/mechanisms.md); its
        robot = model_from_table(rs, base_dir)  # [robot.assembly] table is the assembly configuration
    elif "assembly" in rs:  # an assembly function (docs/process_selection.md): one pose per response
        robot = assembly_from_spec(rs)
        spec = {**spec, "poses": spec.get("poses", {"list": robot.response_poses.tolist()}),
                "requirement": {"position": 1.0, **spec.get("requirement", {})}}
    elif "model" not in rs:
        raise ValidationError("robot.model", None, "a robot name, e.g. 'ucr3', mechanism = 'my_robot.toml' "
                              "or assembly = 'module:function'")
    else:
        cls = registry.get(rs.pop("model"))
        try:
            robot = cls(**rs)
        except TypeError as exc:
            raise ValidationError("robot", rs, f"parameters accepted by {cls.__name__} ({exc})") from None
    ps = spec.get("poses", {"grid": 5})
    if "joints" in ps:      # joint configurations of a serial arm, held exactly (issue 33)
        robot, poses = joint_poses(robot, ps)
    elif "grid" in ps:
        poses = robot.workspace.grid(ps["grid"])
    elif "latin_hypercube" in ps:
        poses = robot.workspace.latin_hypercube(ps["latin_hypercube"], seed=spec.get("seed", 0))
    elif "list" in ps:
        poses = np.asarray(ps["list"], dtype=float)
    else:
        raise ValidationError("poses", ps, "one of grid = [n, ...], latin_hypercube = n, list = [[...], ...]")
    poses = drop_unreachable(robot, poses, ps)      # unreachable poses together, or dropped (issue 33)
    # [clearances]: joint-clearance classes allocated with (or, geometric = false, instead of) the
    # robot's sources (docs/clearance_allocation.md)
    cl = clearances.from_table(spec["clearances"], robot) if "clearances" in spec else None
    sourced = clearances.WithClearances(robot, cl, spec["clearances"].get("geometric", True)) if cl else robot
    bounds = spec.get("bounds", {})
    _check_bounds_table(bounds, sourced)
    costs = spec.get("cost", {})
    overrides = spec.get("sources", {})
    unknown = set(overrides) - set(sourced.source_names)
    if unknown:
        u = sorted(unknown)[0]
        raise ValidationError(f"sources.{u}", u, f"a source of {sourced.name}: " + unknown_key_message(u, sourced.source_names))
    tol = {s.name: _tolerance(s, overrides.get(s.name, {}), bounds, costs, spec) for s in sourced.sources}
    # position = { x = "0.5*mm", ... }: per-axis limits (evotol/core/axis_limits.py, issue 33)
    robot, poses, req_table = axis_requirement(robot, poses, spec.get("requirement", {}), clearances=cl)
    req = Requirement(**req_table)
    shared = spec.get("shared")
    problem = ToleranceProblem(robot, tol, req, poses, shared=shared, shared_cost=spec.get("shared_cost", "part"),
                               clearances=cl, all_given=True)     # every tolerance given: analysed (issue 33)
    # quality_loss = A (or {response = A}): machining cost + Taguchi loss (docs/process_selection.md)
    return with_quality_loss(problem, spec["quality_loss"]) if "quality_loss" in spec else problem


def run_study_file(path, out=None, seed=None, keep_going: bool = False, force: bool = False) -> dict:
    """Run the study; Ctrl-C stops the running method (GA/NSGA-II keep their best so far), skips the
    remaining ones unless ``keep_going``, and the partial results are still written, marked
    ``"interrupted": true`` in the JSON and in the report's header (issue 15).

    A study file with ``[processes]`` is run by
    :func:`evotol.studyfile.processes.run_process_study`.

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
        method, a keyword a method or ``verify`` does not take, a bad budget).
    evotol.errors.InfeasibleError
        No allowed design meets the requirement (checked before the first method).
    """
    path = Path(path)
    if not path.exists():
        raise ValidationError("study file", str(path), "an existing TOML file")
    try:
        spec = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ValidationError("study file", str(path), f"valid TOML ({exc})") from None
    check_kind(spec, "study", path)          # a mechanism description given as a study file (issue 27)
    t0 = time.perf_counter()
    seed = spec.get("seed", 0) if seed is None else seed
    name = spec.get("name", path.stem)
    out = Path(out) if out else path.parent
    check_not_overwriting(out, name, path, force)     # another study's files (issue 27); before any work
    if "processes" in spec:     # process selection: [processes.<dimension>] (evotol/studyfile/processes.py)
        return run_process_study(spec, path, out, seed, load_problem)
    problem = load_problem(spec, base_dir=path.parent)
    units = report_units(spec, problem)
    if not problem.free.any():     # every tolerance given: nothing to allocate, analyse them (issue 33)
        return run_given_tolerances(spec, path, out, name, problem, units, seed, t0)
    methods = spec.get("methods", {"ga": {}, "monotone": {}} if problem.clearances is not None   # no sensitivity rule
                       else {"sensitivity": {}, "optimum": {}, "ga": {}})
    vspec = spec.get("verify", {"n_samples": 1000})
    for m, kw in methods.items():           # every table checked before the first method runs
        if m != "nsga2" and m not in METHODS:
            raise ValidationError(f"methods.{m}", m, unknown_key_message(m, sorted(METHODS) + ["nsga2"]))
        check_keywords(allocate_nsga2 if m == "nsga2" else METHODS[m], kw, f"methods.{m}", exclude=("problem",))
        if "budget" in kw:
            check_budget(problem, kw["budget"], field=f"methods.{m}.budget")
    check_keywords(verify, vspec, "verify", exclude=("problem", "tolerances", "seed", "progress"))
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
                kw = dict(kw)
                if m == "ga":
                    kw.setdefault("seed", seed)
                    kw.setdefault("progress", True)       # a bar on a terminal, lines in a log (issue 27)
                if m == "monotone" and "ga" in results and results["ga"].feasible:   # the GA's design as incumbent
                    kw.setdefault("incumbent", results["ga"].t)
                if m in REFINING_METHODS and refine_option(spec):
                    kw.setdefault("refine", refine_option(spec))
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
                            seconds=time.perf_counter() - t0)
    summary["study_file"] = str(path.resolve())
    summary["warnings"] = plausibility.study_warnings(problem, results.values())   # unit slips (issue 27)
    summary["notes"] = list(getattr(problem.robot, "notes", list)())      # e.g. a redundant arm's posture (issue 23)
    summary["interrupted"] = bool(stopped)
    if stopped:
        summary["interruption"] = {"stopped": stopped, "skipped": skipped, "keep_going": keep_going}
    if results:     # the drawing table, linked from the page (evotol/reporting/export.py)
        summary["exports"] = {k: f"{name}_tolerances.{k}" for k in EXPORT_FORMATS}
    rep = render_user_study(summary)
    paths = write_outputs(name, out, StudyResult(summary), rep)
    for f in summary.get("exports", {}).values():
        write_tolerance_table(summary, out / f)
    summary.update({"html": str(paths["html"]), "json": str(paths["json"])})
    return summary

"""What ``evotol run`` writes about a user study: the JSON summary its report is drawn from.

:func:`study_summary` turns a problem, its allocations, the NSGA-II front and the Monte Carlo
checks into plain data (SI, with the ``units`` block of docs/units.md): per method the worst pose
and its coordinates, the errors at every pose, the contributions at the worst pose, the normalised
error (where the method sits next to the front); the error maps over workspace slices
(:mod:`evotol.summaries.workspace_map`); the NSGA-II front's cheapest feasible point and knee, and how far
the cheapest is above the certified optimum; the explorer's data (:mod:`evotol.summaries.explorer_data`).
:func:`evotol.reporting.user_study.render_user_study` draws the page from it alone.
"""
from __future__ import annotations

import numpy as np

from evotol.units.display import DisplayUnits, error_unit
from evotol.summaries.explorer_data import explorer_data
from evotol.measures.statistical.distributions import as_distribution
from evotol.summaries.pose_joints import pose_joints
from evotol.summaries.yield_quantile import largest_quantile
from evotol.core.problem import ToleranceProblem
from evotol.core.shop import at_floors
from evotol.summaries.drawing import KEYS as DRAWING_KEYS
from evotol.summaries.drawing import nonlinear_check, rounded_design, tolerance_zone
from evotol.summaries.nominals import nominal_notes, nominals_with_notes, source_nominals  # noqa: F401 (re-exported)
from evotol.units import COST, COUNT, RELATIVE, make_units_block
from evotol.summaries.workspace_map import DEFAULT_N, error_map_slices
from evotol.robots.assembly import AssemblyFunction
from evotol.robots.mechanism.callouts.model import zone_per_t

_PER_SOURCE = "m or rad (the source's unit, see units.tolerances)"
_COORD = "workspace coordinate, SI (see workspace.units)"
#: units of the keys this module adds to a user study's JSON (docs/units.md)
KEYS = {
    "low": _COORD, "high": _COORD, "display_scale": "display unit per SI unit (see workspace.display_units)",
    "poses": _COORD, "x": _COORD, "y": _COORD, "fixed": _COORD, "worst_pose_coordinates": _COORD,
    "unreachable": COUNT, "dim": COUNT, "row": "index", "members": "index", "owner": "index",
    "rho": RELATIVE + ": half-width per unit t", "kappa": RELATIVE + ": centre shift per unit t",
    "width": RELATIVE + ": width the cost model sees per unit t", "cost_weight": RELATIVE,
    "offset": _PER_SOURCE, "nominal": _PER_SOURCE, "nominal_note": "text: what the nominal is",
    "minus": RELATIVE + ": lower deviation per unit t", "zone_per_t": RELATIVE + ": a callout member's zone per unit of its t",
    "plus": RELATIVE + ": upper deviation per unit t", "locked": _PER_SOURCE, "lower": _PER_SOURCE, "upper": _PER_SOURCE, "starts": _PER_SOURCE,
    "params": "cost-model coefficients (t in units of scale)", "scale": _PER_SOURCE + ": the cost model's unit of t",
    "limit": "m or rad (the component's unit)", "directions": "1: unit direction vector", "covering_angle": "rad",
    "blocks": "m or rad per unit source error (first-order sensitivity B_j)",
    "sensitivity": "m or rad per unit source error (spectral norm of B_j)",
    "guaranteed": RELATIVE + ": 1 - cos(covering angle), the page's largest possible shortfall",
    "measured": RELATIVE + ": largest 1 - sampled / certified worst case (largest error of a design)",
    "measured_any_pose": RELATIVE + ": largest 1 - sampled / certified worst case (any pose)",
    "worst_pose_agrees": "1: fraction of designs whose sampled worst pose is the certified one",
    "yield_at_worst_pose": "1: first-order yield (lower bound) at the worst pose",
    "required_yield": "1: required probability", "source_costs": COST,
    "half_width": _PER_SOURCE + ": (minus + plus)/2·t", "sigma_k": RELATIVE + ": t = sigma_k·σ",
    "mean_shift": RELATIVE + ": process mean shift / t",
    "limits": "the response's own unit: an assembly's allowed deviation from its nominal response",
    "best_fitness": "fitness (cost + penalty, or normalised error in budget mode)",
    "mean_fitness": "fitness (cost + penalty, or normalised error in budget mode)",
}


def _axis_labels(robot) -> dict:
    """The labels of a per-axis requirement's slots (:attr:`AxisErrorModel.coordinate_labels
    <evotol.core.axis_limits.AxisErrorModel.coordinate_labels>`), or {} without per-axis limits."""
    axis = robot.part_of("axis_limits")
    return axis.coordinate_labels if axis is not None else {}


def study_units_block(problem: ToleranceProblem) -> dict:
    """The ``units`` block of a user study's JSON.

    Parameters
    ----------
    problem : ToleranceProblem
        Its sources' SI units (m or rad) fill ``tolerances``.

    Returns
    -------
    dict
        :func:`evotol.units.make_units_block` with this module's ``KEYS`` added.
    """
    return make_units_block(keys={**KEYS, **DRAWING_KEYS}, tolerances=dict(zip(problem.names, problem.units())))


def source_table(problem: ToleranceProblem) -> list[dict]:
    """Per source: name, group, SI unit, dimension, nominal (SI, where known), the interval
    [offset − minus·t, offset + plus·t], and whether it is fixed (no cost) or locked.

    Returns
    -------
    list of dict
        One row per source, in source order: ``name``, ``group``, ``unit`` (``"m"`` or
        ``"rad"``), ``dim``, ``offset`` (m or rad), ``minus``, ``plus`` (dimensionless, per unit
        t), ``fixed`` (bool), ``locked`` (m or rad, or None), ``distribution`` (``kind``,
        ``sigma_k``, ``mean_shift``: what the Monte Carlo samples), where known ``nominal`` (m or
        rad) and ``nominal_note`` (what the nominal is: :func:`evotol.summaries.nominals.nominal_notes`),
        and ``no_effect = True`` for a source that cannot move the constrained errors
        (:func:`sources_without_effect`).
    """
    nominal, notes = nominals_with_notes(problem.model, problem.names)
    per_t = zone_per_t(problem.model)
    no_effect = sources_without_effect(problem)
    out = []
    for j, (n, s) in enumerate(zip(problem.names, problem.error_model.sources)):
        tol = problem.tolerances[n]
        row = {"name": n, "group": s.group, "unit": s.unit, "dim": s.dim, "offset": float(tol.offset),
               "minus": float(tol.minus), "plus": float(tol.plus), "fixed": bool(tol.is_fixed),
               "locked": None if tol.locked is None else float(tol.locked)}
        dist = as_distribution(tol.distribution)
        row["distribution"] = {"kind": dist.kind, "sigma_k": float(dist.sigma_k), "mean_shift": float(dist.mean_shift)}
        if n in per_t:      # a callout member: its zone per unit of the drawing's value (docs/callouts.md)
            row["zone_per_t"] = per_t[n]
        if n in nominal:
            row["nominal"] = nominal[n]
        if no_effect[j]:
            row["no_effect"] = True
        if n in notes:
            row["nominal_note"] = notes[n]
        out.append(row)
    return out


#: a source moves the constrained errors by less than this fraction of the requirement at its upper bound: no effect
NO_EFFECT_FRACTION = 1e-9


def sources_without_effect(problem: ToleranceProblem) -> np.ndarray:
    """Which sources cannot move any constrained error component (issue 33: they were shown at their
    upper bound with no mark).

    Parameters
    ----------
    problem : ToleranceProblem
        The study's problem (its per-source spectral norms ``sensitivities`` over the poses).

    Returns
    -------
    (n_sources,) ndarray of bool
        True where ``max over poses ||B_j|| x upper_j < NO_EFFECT_FRACTION x limit`` for every
        constrained component; never for a joint clearance class, whose effect the certified
        clearance measure computes outside the first-order map (its columns there are 0), nor for
        a source the calibration part lists in ``effect_beyond_first_order``.
    """
    out = np.ones(problem.n_sources, bool)
    for comp, lim in problem.components:
        s = np.asarray(problem.sensitivities[comp], float).max(axis=0)          # (n_poses, n_sources) -> per source
        out &= s * np.asarray(problem.upper, float) < NO_EFFECT_FRACTION * lim
    if problem.clearances is not None:
        out &= ~np.isin(list(problem.names), list(problem.clearances.names))
    calibrated = problem.error_model.part_of("calibration")
    if calibrated is not None:
        out &= ~np.isin(list(problem.names), list(calibrated.effect_beyond_first_order))
    return out


def result_details(problem: ToleranceProblem, r) -> dict:
    """Per-method additions to ``AllocationResult.to_dict``: normalised error, worst pose (index
    and SI coordinates) and errors at every pose per component, contributions at the worst pose,
    the yield at the worst pose for a yield design.

    Parameters
    ----------
    problem : ToleranceProblem
        The problem ``r`` solves.
    r : evotol.core.result.AllocationResult
        One method's result.

    Returns
    -------
    dict
        ``normalised_error`` (dimensionless: largest error / requirement), ``worst_pose`` (index
        per component), ``worst_pose_coordinates`` (SI), ``errors_per_pose`` (m or rad),
        ``contributions`` (``source``, ``percent``), ``source_costs`` (cost units), ``zones``
        (per source, :func:`tolerance_zone`); a GA's ``history`` and, for a yield design, ``yield_at_worst_pose`` and ``required_yield``
        (probabilities); with ``[shop]`` floors, ``at_floor``, the sources the design holds at
        their floor (:func:`evotol.core.shop.at_floors`).
    """
    d = {"normalised_error": float(r.errors.violation[0] + 1), "worst_pose": {}, "worst_pose_coordinates": {},
         "errors_per_pose": {}, "contributions": {},
         "source_costs": dict(zip(problem.names, problem.source_costs(r.t).tolist())),
         "zones": {row["name"]: tolerance_zone(row, t) for row, t in zip(source_table(problem), r.t)}}
    for comp, _ in problem.components:
        p = r.worst_pose(comp)
        d["worst_pose"][comp] = p
        d["worst_pose_coordinates"][comp] = problem.poses[p].tolist()
        d["errors_per_pose"][comp] = getattr(r.errors, comp)[0].tolist()
        if getattr(r.errors, f"{comp}_contrib") is not None:
            c = r.contributions(comp)
            d["contributions"][comp] = {"source": c["source"].tolist(), "percent": c["percent"].tolist()}
    if problem.shop_floors:      # feasible, and held by the shop's floors (issue 41)
        d["at_floor"] = at_floors(problem, r.t)
    if r.history is not None and len(r.history) and {"best_fitness", "mean_fitness"} <= set(r.history):
        d["history"] = {k: r.history[k].tolist() for k in ("generation", "best_fitness", "mean_fitness")}
    if r.errors.probability is not None:
        d["yield_at_worst_pose"] = float(np.min(r.errors.probability[0]))
        d["required_yield"] = problem.requirement.required_yield
        # the error at the required yield, a quantile of the stated model (the measure's value is E·k_req/k; issue 33)
        d["error_at_required_yield"] = largest_quantile(problem, r.t, problem.requirement.required_yield,
                                                        seed=problem.requirement.seed)
    return d


def front_summary(problem: ToleranceProblem, front, results: dict) -> dict:
    """The NSGA-II front's cheapest feasible point and knee (row, cost, normalised error, largest
    errors, tolerances), and the cheapest's cost over the certified optimum's when there is one.

    Parameters
    ----------
    problem : ToleranceProblem
        The problem the front was computed for.
    front : evotol.core.pareto.ParetoFront
        The NSGA-II front (its ``table`` has ``cost``, ``normalised_error``, ``COMP_error`` and
        one column per source).
    results : dict
        Method -> :class:`evotol.core.result.AllocationResult`; ``"optimum"``, if certified optimal,
        gives the reference cost.

    Returns
    -------
    dict
        ``knee`` and, when a front point meets the requirement, ``cheapest_feasible``: each with
        ``row``, ``cost`` (cost units), ``normalised_error``, ``max_COMP_error`` (m or rad),
        ``worst_pose``, ``worst_pose_coordinates`` (SI) and ``tolerances`` (SI);
        ``cheapest_feasible_over_optimum`` (dimensionless, cost / optimum cost - 1) when there is
        a certified optimum.
    """
    table = front.table
    out = {}
    rows = {"knee": int(front.knee())}
    feasible = table.index[table["normalised_error"] <= 1 + 1e-9]
    if len(feasible):
        rows["cheapest_feasible"] = int(table.loc[feasible, "cost"].idxmin())
    for key, i in rows.items():
        row = table.iloc[i]
        t = np.array([float(row[n]) for n in problem.names])
        ev = problem.evaluate(t[None])          # where its largest error is (the front keeps only the value)
        worst = {c: int(np.argmax(getattr(ev, c)[0])) for c, _ in problem.components}
        out[key] = {"row": i, "cost": float(row["cost"]), "normalised_error": float(row["normalised_error"]),
                    **{f"max_{c}_error": float(row[f"{c}_error"]) for c, _ in problem.components},
                    "worst_pose": worst, "worst_pose_coordinates": {c: problem.poses[p].tolist() for c, p in worst.items()},
                    "tolerances": dict(zip(problem.names, t.tolist()))}
    opt = results.get("optimum")
    if "cheapest_feasible" in out and opt is not None and opt.verdict and opt.verdict.startswith("certified optimal"):
        out["cheapest_feasible_over_optimum"] = out["cheapest_feasible"]["cost"] / opt.cost - 1
    return out


def study_summary(name: str, problem: ToleranceProblem, results: dict, front, checks: dict, *, seed: int,
                  units: DisplayUnits, seconds: float, maps: bool = True, precision: dict | None = None) -> dict:
    """The JSON-ready summary of a user study (see the module docstring).

    Parameters
    ----------
    name : str
        The study's name.
    results : dict
        Method -> :class:`evotol.core.result.AllocationResult`.
    front : evotol.core.pareto.ParetoFront or None
        The NSGA-II front, if NSGA-II ran.
    checks : dict
        Method -> ``MonteCarloResult.to_dict()``.
    seed : int
        The study's seed (stored; also seeds the explorer's tightness sample).
    units : DisplayUnits
        The study's display units (stored; values stay SI).
    seconds : float
        Wall time of the study, s.
    maps : bool
        Compute the error maps over workspace slices (default True; not for a workspace that is
        a list of responses).
    precision : dict, optional
        Display unit -> drawing step (:func:`evotol.summaries.drawing.drawing_precision`); the
        defaults of :data:`evotol.summaries.drawing.DEFAULT_PRECISION` otherwise.

    Returns
    -------
    dict
        JSON-ready, SI: the problem, requirement, workspace, sources, per-method results with
        :func:`result_details`, the Monte Carlo checks, the NSGA-II front and
        :func:`front_summary`, ``figures`` (error maps), ``explorer`` and the ``units`` block.
    """
    ws = problem.model.workspace
    summary = {"name": name, "problem": problem.describe(), "seed": seed, "measure": problem.requirement.measure,
               "requirement": {c: lim for c, lim in problem.components},
               "error_units": {c: error_unit(problem, c) for c, _ in problem.components},
               "display_units": units.to_dict(),
               "workspace": {"names": list(ws.names), "units": list(ws.units), "display_units": list(ws.display_units),
                             "display_scale": list(ws.display_scale), "low": list(ws.low), "high": list(ws.high),
                             "labels": _axis_labels(problem.model)},     # per-axis slots (issue 33)
               "robot": problem.error_model.name, "n_poses": problem.n_poses, "poses": problem.poses.tolist(),
               "sources": source_table(problem),
               "results": {m: {**r.to_dict(), **result_details(r.problem, r)} for m, r in results.items()},
               "monte_carlo": checks, "seconds": seconds, "figures": {}}
    inner = problem.robot
    if isinstance(inner, AssemblyFunction):   # an assembly: responses, not poses
        summary["assembly"] = {"responses": list(inner.response_names), "limits": [float(v) for v in inner.limits]}
    if front is not None:
        summary["pareto_front"] = front.table.to_dict(orient="list")
        summary["nsga2"] = front_summary(problem, front, results)
    continuous = tuple(ws.units) != ("1",) and any(h > lo for lo, h in zip(ws.low, ws.high))
    if maps and results and continuous and _axis_labels(problem.model):
        maps = False        # a per-axis requirement: the axis is a label, not a coordinate to map (issue 33)
        summary["figures"]["error_maps_note"] = ("no error map: with a per-axis requirement each pose is a configuration "
                                                 "and an axis; the per-pose values are in the tables")
    if maps and results and not continuous:
        summary["figures"]["error_maps_note"] = ("no error map: the workspace is a list of responses "
                                                 "(an assembly), not a continuous range")
    if maps and results and continuous:
        names = list(results)
        T = np.array([results[m].t for m in names])
        first = results[names[0]]
        # the result's own poses: a refined result's problem has the poses the refinement added
        anchor = first.problem.poses[first.worst_pose(problem.components[0][0])]
        n = 11 if problem.clearances is not None else DEFAULT_N    # the certified engine is slower per pose
        slices = error_map_slices(problem, T, anchor, n)
        summary["figures"]["error_maps"] = {
            m: [{**{k: v for k, v in s.items() if k != "values"},
                 "values": {c: s["values"][c][i] for c in s["values"]}} for s in slices]
            for i, m in enumerate(names)}
    starts = {m: r.t for m, r in results.items()}
    for key, p in summary.get("nsga2", {}).items():     # the front's cheapest feasible point and knee too
        if isinstance(p, dict) and "tolerances" in p:
            starts[f"nsga2 {key.replace('_', ' ')}"] = problem.as_array(p["tolerances"])
    summary["explorer"] = explorer_data(problem, starts, seed)
    # the drawing: every method's zones rounded to the drawing precision, the drawn design re-checked
    summary["drawing"] = {m: rounded_design(problem, r.t, units, precision) for m, r in results.items()}
    for m, r in results.items():    # each allocation on the nonlinear model too: a verdict names its model (issue 41)
        check = nonlinear_check(problem, r.t)
        if check and m in summary.get("results", {}):
            summary["results"][m]["nonlinear_check"] = check
    summary["joints"] = pose_joints(problem)        # the posture used at every pose (issue 33)
    summary["units"] = study_units_block(problem)
    if summary["joints"]:       # joints/values/<joint>/i: each joint variable in its own unit (rad or m)
        j = summary["joints"]
        summary["units"].setdefault("tables", {})["values"] = dict(zip(j["variables"], j["units"]))
    return summary

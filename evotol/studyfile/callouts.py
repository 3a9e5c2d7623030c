"""What a study does with drawing callouts (issue 35): exact zones against independent boxes, and
the warnings about refinements.

For a problem whose robot is a :class:`evotol.robots.mechanism.callouts.model.CalloutModel`, the twin
problem takes the same callouts, tolerances, requirement and poses under the independent-box rule
(``zones = "boxes"``: each position callout's translations ±t/2 and tilts ±t/L as independent
intervals sharing its value). Both are allocated by the certified optimum and checked on the
nonlinear model at each pose's worst-case vertex (:func:`evotol.verification.nonlinear.worst_vertex_errors`).
The box rule's zone contains the exact one, so its callouts also hold under the exact zones, with
a margin that is the money the box rule spends; the comparison reports both costs, every callout
under both, the saving ``1 - cost_exact / cost_boxes``, and the worst error each design holds:
under its own zone model and (for the box design) under the exact zones its drawing really gives.

The parameters several definitions of this module share are described once, here.

Parameters
----------
problem : ToleranceProblem
    A problem whose robot is a ``CalloutModel``.
"""
from __future__ import annotations

import copy

import numpy as np

from evotol.allocators import allocate_optimum
from evotol.core.problem import ToleranceProblem
from evotol.errors import ValidationError
from evotol.verification.nonlinear import worst_vertex_errors
from evotol.robots.mechanism.callouts.table import datum_features, refinement_warnings

#: a position or orientation callout's feature length below this (m) is probably a unit slip
MIN_FEATURE_LENGTH = 1e-3


def variable_values(problem: ToleranceProblem, t) -> dict:
    """One design as ``{variable name: value}`` (a callout's value, a raw source's tolerance).

    Parameters
    ----------
    problem : ToleranceProblem
        The problem.
    t : array_like, shape (n_sources,)
        A design (SI: m or rad).

    Returns
    -------
    dict of str to float
        Free variable name -> its value (SI).
    """
    t = problem.as_array(t)
    return dict(zip(problem.variables, (float(v) for v in t[problem.free])))


def twin_problem(problem: ToleranceProblem, zones: str) -> ToleranceProblem:
    """The same study with the callouts under another zone model.

    Parameters
    ----------
    zones : {"exact", "boxes"}
        The twin's zone model.

    Returns
    -------
    ToleranceProblem
        Same requirement, poses, tolerances (each member of a callout takes the callout's),
        shared groups and cost counting.

    Raises
    ------
    evotol.errors.ValidationError
        The robot has no callouts.
    """
    robot = problem.model
    callouts = robot.part_of("callouts")
    if callouts is None:
        raise ValidationError("robot", robot.name, "a model with drawing callouts ([[robot.callouts]], docs/callouts.md)")
    twin = robot.with_part("callouts", lambda m: m.with_zones(zones))   # the outer parts (joint space, ...) kept
    tols = {}
    for s in twin.sources:
        c = callouts.callout_of(s.name)
        src = robot.tied_sources.get(c.name, (c.name,))[0] if c is not None else s.name
        tols[s.name] = copy.copy(problem.tolerances[src])
    return ToleranceProblem(twin, tols, problem.requirement, problem.poses, n_directions=problem.n_directions,
                            shared=problem.shared or None, shared_cost=problem.shared_cost)


def _worst(problem: ToleranceProblem, t) -> dict:
    """Largest linear worst case and nonlinear worst-vertex error per constrained component (SI)."""
    lin = problem.max_errors(np.asarray(t)[None], "worst_case")
    nl = worst_vertex_errors(problem, t)
    return {c: {"linear": float(lin[c][0]), "nonlinear": float(np.max(nl[c]))} for c, _ in problem.components}


def zone_comparison(problem: ToleranceProblem, exact_result=None, boxes_result=None, **optimum) -> dict:
    """Certified optimum under exact zones and under independent boxes (module docstring).

    Parameters
    ----------
    problem : ToleranceProblem
        A problem whose robot is a ``CalloutModel`` (its zones exact or boxes).
    exact_result : AllocationResult, optional
        ``allocate_optimum(problem, **optimum)`` when the caller already has it (a study's own
        optimum, same problem and options): used for the exact zones instead of solving again.
    boxes_result : AllocationResult, optional
        The certified optimum of :func:`twin_problem` ``(problem, "boxes")`` when the caller already has it
        (a study runs it in its method loop, :mod:`evotol.studyfile.comparisons`).
    **optimum
        Keywords of :func:`evotol.allocators.allocate_optimum` (``refine``...).

    Returns
    -------
    dict
        JSON-ready (SI): ``exact`` and ``boxes`` each with ``cost``, ``feasible``, ``values``
        (variable -> value) and ``worst`` (component -> ``linear``/``nonlinear`` largest error
        over the poses under its own zone model); ``boxes.worst_in_exact_zones`` (the box design's
        callouts under the exact zones); ``saving`` (fraction of the box rule's cost);
        ``callouts`` (names of the callout variables).

    Raises
    ------
    evotol.errors.ValidationError
        The robot has no callouts.
    evotol.errors.InfeasibleError
        No design meets the requirement.
    """
    callouts = problem.model.part_of("callouts")
    if callouts is None:
        raise ValidationError("robot", problem.model.name, "a model with drawing callouts ([[robot.callouts]])")
    exact = problem if callouts.zones == "exact" else twin_problem(problem, "exact")
    boxes = twin_problem(exact, "boxes")
    out = {}
    for key, p in (("exact", exact), ("boxes", boxes)):
        given = {"exact": exact_result, "boxes": boxes_result}[key]
        r = given if given is not None else allocate_optimum(p, **optimum)
        t = np.array([r.tolerances[n] for n in p.names])
        out[key] = {"cost": float(r.cost), "feasible": bool(r.feasible), "values": variable_values(p, t),
                    "worst": _worst(p, t)}
        if key == "boxes":
            vals = out[key]["values"]
            te = exact.full(np.array([vals[v] for v in exact.variables])[None])[0]
            out[key]["worst_in_exact_zones"] = _worst(exact, te)
    out["saving"] = 1.0 - out["exact"]["cost"] / out["boxes"]["cost"]
    out["callouts"] = [c.name for c in callouts.callouts]
    return out


def callout_summary(problem: ToleranceProblem, exact_result=None, boxes_result=None, **optimum) -> dict:
    """What a study's summary carries about its callouts: the features and the comparison.

    Parameters
    ----------
    exact_result, boxes_result : AllocationResult, optional
        The optima under exact zones and under boxes when the caller has them (:func:`zone_comparison`).
    **optimum
        Keywords of :func:`evotol.allocators.allocate_optimum` for the comparison.

    Returns
    -------
    dict
        ``features`` (:meth:`CalloutModel.describe_callouts`, SI) and ``comparison``
        (:func:`zone_comparison`).

    Raises
    ------
    evotol.errors.ValidationError
        The robot has no callouts.
    evotol.errors.InfeasibleError
        No design meets the requirement.
    """
    callouts = problem.model.part_of("callouts")
    if callouts is None:
        raise ValidationError("robot", problem.model.name, "a model with drawing callouts ([[robot.callouts]])")
    features = callouts.describe_callouts()
    mech = problem.robot.mechanism
    for f in features:                  # what the datum letters name on the part's drawing (issue 41)
        f["datum_features"] = datum_features(mech, f["part"], f["datums"])
    return {"features": features, "zones": callouts.zones,
            "comparison": zone_comparison(problem, exact_result, boxes_result, **optimum)}


def callout_warnings(problem: ToleranceProblem) -> list[str]:
    """One line per position or orientation callout over a feature shorter than
    :data:`MIN_FEATURE_LENGTH` (1 mm: ``"50 um"`` meant ``"50 mm"``), and per seat whose orientation
    callout is always tighter than the position callout it refines (it binds the tilt; the pair is
    modelled by its safe outer set, ``docs/callouts.md``).

    Parameters
    ----------
    problem : ToleranceProblem
        Any problem; only a ``CalloutModel``'s callouts are read.

    Returns
    -------
    list of str
        Warning lines (empty without callouts or refinements).
    """
    robot = problem.model.part_of("callouts")
    if robot is None:
        return []
    lower, upper = {}, {}
    for c in robot.callouts:
        j = problem.names.index(robot.tied_sources.get(c.name, (c.name,))[0])
        locked = problem.locked_values[j]
        lower[c.name], upper[c.name] = (locked, locked) if np.isfinite(locked) else (problem.lower[j], problem.upper[j])
    short = [f"robot.callouts {c.name}: length = {c.length * 1e3:g} mm is shorter than a bearing seat or a guide is "
             f"(under {MIN_FEATURE_LENGTH * 1e3:g} mm); a zone ⌀t over it tilts the axis by up to t/L (the smallest "
             f"⌀{lower[c.name] * 1e6:g} µm: {lower[c.name] / c.length:.3g} rad), so the requirement may be out of "
             f"reach; if '{c.length * 1e6:g} um' was meant in mm, write '{c.length * 1e6:g} mm'"
             for c in robot.callouts if c.kind != "axial" and 0 < c.length < MIN_FEATURE_LENGTH]
    return short + refinement_warnings(robot.callouts, lower, upper)

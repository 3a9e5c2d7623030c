"""The error sources of a study file and their tolerance specifications: ``[clearances]`` (joint
clearance classes, docs/clearance_allocation.md), ``[bounds]`` (with ``[bounds.GROUP]`` /
``[bounds.SOURCE]`` sub-tables), ``[cost.*]``, ``[sources.NAME]`` (``offset``/``minus``/``plus``,
``cost_width``, ``contains_nominal``, ``fixed``, ``locked``, ``distribution``, ``sigma_k``,
``mean_shift``; docs/tolerances.md; NAME may be an fnmatch pattern such as ``"l?"``) and the top-level ``distribution``/``sigma_k`` defaults.
"""
from __future__ import annotations

import evotol.cost_models
from evotol._runtime.keyword_checks import expand_patterns, unknown_key_message
from evotol.measures.statistical.distributions import Distribution
from evotol.core.tolerance import Tolerance
from evotol.errors import ValidationError
from evotol.units.quantity import parse_quantity
from evotol.core.shop import floors_of
from evotol.measures import clearances
from evotol.studyfile.keys import BOUND_KEYS, GROUP_BOUND_KEYS
from evotol.robots.base import RobotErrorModel


def read_clearances(spec: dict, robot: RobotErrorModel) -> tuple["clearances.ClearanceSources | None", tuple]:
    """``[clearances]``: the joint-clearance classes allocated with (or, ``geometric = false``,
    instead of) the robot's sources, and the problem's sources in order.

    Returns
    -------
    classes : evotol.measures.clearances.ClearanceSources or None
        The clearance classes; None without a ``[clearances]`` table.
    sources : tuple of evotol.robots.base.SourceSpec
        The sources the problem will have (:func:`evotol.measures.clearances.error_sources`):
        the robot's, then the classes.

    Raises
    ------
    ValidationError
        A bad ``[clearances]`` table (:func:`evotol.measures.clearances.from_table`), or classes
        that cannot stand beside the robot's sources.
    """
    if "clearances" not in spec:
        return None, tuple(robot.sources)
    cl = clearances.from_table(spec["clearances"], robot)
    return cl, clearances.error_sources(robot, cl, spec["clearances"].get("geometric", True))


def read_tolerances(spec: dict, sources, owner: str) -> dict[str, Tolerance]:
    """One :class:`Tolerance` per source, from ``[sources.NAME]``, ``[bounds]``, ``[cost.*]`` and the
    top-level defaults.

    Parameters
    ----------
    sources : sequence of evotol.robots.base.SourceSpec
        The problem's sources (:func:`read_clearances`).
    owner : str
        What the sources belong to, as errors name it (the robot's name, and its clearance classes).

    Returns
    -------
    dict of str to Tolerance
        Source name -> its tolerance (bounds in SI: m or rad), in source order.

    Raises
    ------
    ValidationError
        An unknown source in ``[sources]``, a bad ``[bounds]`` table or bound, a fixed source with
        a range, lock or cost, a source without a cost model.
    """
    bounds = spec.get("bounds", {})
    names = [s.name for s in sources]
    _check_bounds_table(bounds, sources)
    costs = spec.get("cost", {})
    overrides = expand_patterns(spec.get("sources", {}), names, "sources", "source")     # [sources."l?"] (issue 41)
    unknown = set(overrides) - set(names)
    if unknown:
        u = sorted(unknown)[0]
        raise ValidationError(f"sources.{u}", u, f"a source of {owner}: " + unknown_key_message(u, names))
    floors = floors_of(sources, spec["shop"]["floors"]) if "floors" in spec.get("shop", {}) else {}   # issue 41
    return {s.name: _tolerance(s, overrides.get(s.name, {}), bounds, costs, spec, floors.get(s.name, (0.0,))[0])
            for s in sources}


def _tolerance(s, o: dict, bounds: dict, costs: dict, spec: dict, floor: float = 0.0) -> Tolerance:
    """One source's :class:`Tolerance` from its ``[sources.NAME]`` table and the defaults; ``floor``
    (m or rad, ``[shop] floors``) raises its lower bound."""
    kind = "angle" if s.unit == "rad" else "length"
    o = {k: parse_quantity(v, f"sources.{s.name}.{k}", kind) if k in ("fixed", "locked", "lower", "upper", "offset")
         and isinstance(v, str) else v for k, v in o.items()}        # "50 um", "0.05*mm": docs/units.md
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
    return Tolerance(cost=evotol.cost_models.from_dict(cspec), lower=max(_bound(o, bounds, s, "lower", 1e-6), floor),
                     upper=_bound(o, bounds, s, "upper", 1e-3), locked=o.get("locked"),
                     distribution=dist, **shape)


def _check_bounds_table(bounds, sources) -> None:
    """``[bounds]``: ``lower``/``upper`` for every source, and sub-tables by group or source name
    (``[bounds."U joint"]``, ``[bounds.l1]``) -- sources in m and in rad need their own ranges."""
    if not isinstance(bounds, dict):
        raise ValidationError("bounds", bounds, "a table with lower/upper and optional group or source sub-tables")
    names = {*(s.name for s in sources), *(s.group for s in sources)}
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
            if isinstance(v, str):
                v = parse_quantity(v, f"{field}.{which}", "angle" if source.unit == "rad" else "length")
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ValidationError(f"{field}.{which}", v, "a positive tolerance in SI units (m or rad) or with its unit, e.g. '20 um'")
            return float(v)
    return default

"""What the shop can hold (issue 41 item 1): per feature kind or source group the smallest zone a
process holds (a **floor**), taken as a lower bound of the allocation; when the requirement cannot
be met with every source at or above its floor, which sources sit there and what would make the
study feasible; and zones narrower than what can be measured.

A study file writes::

    [shop]
    floors = { "bore position" = "10 um", axial = "20 um", actuator = "5 arcsec" }
    measurable = "2 um"          # optional: the smallest zone a CMM checks (default MEASURABLE)

A key of ``floors`` is a source name, a drawing callout's name (``"elbow_joint.position"``), a
source group (a callout's kind is its group: ``position``, ``axial``...) or one of the feature names
of :data:`FEATURES` (``"bore position"`` is the position of a bore's axis). A value is a zone with
its unit (``docs/units.md``) in the source's own measure: the callout's value ⌀t, or an interval's
tolerance t. From Python, :func:`floors_of` gives the floors per source and
:func:`with_floors` the problem with them as lower bounds.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from evotol.errors import InfeasibleError, ValidationError
from evotol.units.quantity import parse_quantity

#: feature names a shop uses -> the callout kind or source group they stand for
FEATURES = {"bore position": "position", "bore axis": "position", "guide parallelism": "parallelism",
            "bore perpendicularity": "perpendicularity", "shoulder face": "axial", "face": "axial"}
#: the smallest zone evotol takes as measurable by default (m for lengths, rad for angles): a
#: 2 µm zone is the order of a good coordinate measuring machine's uncertainty, 1 arcsec an autocollimator's
MEASURABLE = {"m": 2e-6, "rad": 4.85e-6}


def _callout(name: str) -> str:
    """The callout a zone member belongs to (``elbow_joint.position.end1`` -> ``elbow_joint.position``)."""
    head, _, last = name.rpartition(".")
    return head if last in ("end1", "end2", "centre", "shift_e1", "shift_e2", "tilt_e1", "tilt_e2") else name


def floors_of(sources, floors: dict, field: str = "shop.floors") -> dict:
    """The floor of each source a ``floors`` table reaches (module docstring), in SI.

    Parameters
    ----------
    sources : sequence of evotol.robots.base.SourceSpec
        The model's sources (name, group, unit).
    floors : dict
        Key (source, callout, group or feature name) -> the smallest zone (a number in SI or a
        string with its unit).
    field : str
        The table's name in errors.

    Returns
    -------
    dict of str to (float, str)
        Source name -> (floor in m or rad, the key that set it); the most specific key wins
        (source, then callout, then group or feature).

    Raises
    ------
    evotol.errors.ValidationError
        Not a table, a key that reaches no source, a value that is not a positive zone of the
        source's kind.
    """
    if not isinstance(floors, dict):
        raise ValidationError(field, floors, "a table: feature kind, source group or name -> the smallest zone, e.g. "
                                             "{ \"bore position\" = \"10 um\" }")
    out, used = {}, set()
    for s in sources:
        kind = "angle" if s.unit == "rad" else "length"
        for key in (s.name, _callout(s.name), s.group, *(f for f, g in FEATURES.items() if g == s.group)):
            if key in floors:
                v = parse_quantity(floors[key], f"{field}.{key}", kind)
                if not v > 0:
                    raise ValidationError(f"{field}.{key}", floors[key], "a positive zone")
                out[s.name] = (v, key)
                used.add(key)
                break
    unknown = sorted(set(floors) - used)
    if unknown:
        names = sorted({s.group for s in sources} | set(FEATURES))
        raise ValidationError(f"{field}.{unknown[0]}", floors[unknown[0]], f"a source, callout, group or feature "
                              f"among {names} (or a source's name)")
    return out


def with_floors(problem, floors: dict):
    """The problem with each floor as its source's lower bound (``max(lower, floor)``).

    Parameters
    ----------
    problem : ToleranceProblem
        The problem.
    floors : dict
        As for :func:`floors_of`.

    Returns
    -------
    ToleranceProblem
        The problem with raised lower bounds, ``shop_floors`` (source -> (floor, key)) set.

    Raises
    ------
    evotol.errors.ValidationError
        A bad table (:func:`floors_of`), or a floor above a source's upper bound.

    Examples
    --------
    >>> import numpy as np, cost_models as cm
    >>> from evotol import Requirement, Tolerance, ToleranceProblem
    >>> from evotol.core.shop import with_floors
    >>> from tests.toy_robot import ToyRobot
    >>> robot = ToyRobot(dims=(1, 1))
    >>> tol = {s.name: Tolerance(cm.ReciprocalCost(0.0, 1.0, scale=1e-5), 1e-6, 1e-3) for s in robot.sources}
    >>> p = ToleranceProblem(robot, tol, Requirement(position=1e-4), np.array([[0.0], [1.0]]))
    >>> [round(float(v), 9) for v in with_floors(p, {"s0": "10 um"}).lower]
    [1e-05, 1e-06]
    """
    table = floors_of(problem.error_model.sources, floors)
    tols = dict(problem.tolerances)
    for n, (v, key) in table.items():
        t = tols[n]
        if t.cost is None or t.locked is not None:
            continue            # a given tolerance is what it is
        if v > t.upper:
            raise ValidationError(f"shop.floors.{key}", v, f"a floor at most the upper bound of {n} ({t.upper:g})")
        tols[n] = dataclasses.replace(t, lower=max(float(t.lower), v))
    new = type(problem)(problem.model, tols, problem.requirement, problem.poses, n_directions=problem.n_directions,
                        shared=problem.shared or None, shared_cost=problem.shared_cost)
    new.shop_floors = {n: fv for n, fv in table.items() if n in tols and tols[n].cost is not None}
    return new


def check_floors_feasible(problem) -> None:
    """When the requirement cannot be met with every free source at its floor (or lower bound): say
    which sources sit at their floor, the error there, and what would make the study feasible.

    Parameters
    ----------
    problem : ToleranceProblem
        A problem built by :func:`with_floors` (other problems: nothing is checked here).

    Raises
    ------
    evotol.errors.InfeasibleError
        Naming the floored sources, the error at the floors and the remedies.
    """
    floors = problem.shop_floors
    if not floors:
        return
    try:
        problem.check_feasible()
    except InfeasibleError as e:
        floored = [n for n, (v, key) in floors.items() if problem.free[problem.names.index(n)]]
        keys = sorted({floors[n][1] for n in floored})
        unit = "m" if e.requirement.split()[1] == "position" else "rad"
        raise InfeasibleError(
            f"{e.requirement} with the shop's floors ({', '.join(f'{k} >= {floors_key_value(floors, k)}' for k in keys)})",
            e.smallest_error, e.pose,
            f"{e.detail + '; ' if e.detail else ''}sources at a floor: {', '.join(sorted({_callout(n) for n in floored}))}; "
            f"feasible with a requirement of at least {e.smallest_error:.6g} {unit}, with calibration ([calibration], "
            "docs/calibration.md), or with processes that hold smaller zones (lower [shop] floors)") from None


def at_floors(problem, t, rtol: float = 1e-6) -> list[dict]:
    """The free sources a design holds at their ``[shop]`` floor (one per callout), for a feasible
    design as :func:`check_floors_feasible` names them for an infeasible one.

    Parameters
    ----------
    problem : ToleranceProblem
        A problem with ``shop_floors`` (:func:`apply_shop`, :func:`with_floors`); others: none.
    t : array_like, shape (n_sources,)
        A design (SI).
    rtol : float, optional
        A tolerance within ``rtol`` of its floor sits there (the allocators stop at the bound
        to round-off).

    Returns
    -------
    list of dict
        ``{"source": source or callout name, "floor": m or rad, "key": the [shop] floors key}``,
        in source order.
    """
    floors = problem.shop_floors or {}
    t = problem.as_array(t)
    out, seen = [], set()
    for n, (v, key) in floors.items():
        j = problem.names.index(n)
        name = _callout(n)
        if not problem.free[j] or name in seen or t[j] > v * (1 + rtol):
            continue
        seen.add(name)
        out.append({"source": name, "floor": float(v), "key": key})
    return out


def floors_key_value(floors: dict, key: str) -> str:
    """A floor as the table stated it, in µm or arcsec (``"10 µm"``).

    Parameters
    ----------
    floors : dict
        ``shop_floors`` of :func:`with_floors`.
    key : str
        A key of the ``[shop] floors`` table.

    Returns
    -------
    str
        The floor's value.
    """
    v = next(v for v, k in floors.values() if k == key)
    return f"{v * 1e6:g} µm" if v < 1 else f"{v:g}"


def apply_shop(spec: dict, problem):
    """A study file's ``[shop]`` table on its problem: the floors (already its lower bounds, set where
    the study file's bounds are read, :mod:`evotol.studyfile.sources`) named on the problem
    (``problem.shop_floors``) and checked for feasibility at once (:func:`check_floors_feasible`),
    and the measurability limits the results' warnings use (``problem.measurable``;
    :data:`MEASURABLE` when not stated).

    Parameters
    ----------
    spec : dict
        The parsed study file.
    problem : ToleranceProblem
        Its problem.

    Returns
    -------
    ToleranceProblem
        The same problem, with ``shop_floors`` and ``measurable`` set.

    Raises
    ------
    evotol.errors.ValidationError
        An unknown key of ``[shop]``, a bad floor or measurable limit.
    evotol.errors.InfeasibleError
        The requirement cannot be met at the floors.
    """
    shop = spec.get("shop", {})
    if not isinstance(shop, dict):
        raise ValidationError("shop", shop, "a table with floors and/or measurable")
    bad = sorted(set(shop) - {"floors", "measurable"})
    if bad:
        raise ValidationError(f"shop.{bad[0]}", shop[bad[0]], "floors or measurable")
    if "floors" in shop:      # the floors are already the lower bounds (evotol.studyfile.sources); named here
        table = floors_of(problem.error_model.sources, shop["floors"])
        problem.shop_floors = {n: fv for n, fv in table.items() if problem.tolerances[n].cost is not None
                               and problem.tolerances[n].locked is None}
    m = shop.get("measurable", {})
    m = m if isinstance(m, dict) else {"length": m}
    limits = {}
    for k, v in m.items():
        if k not in ("length", "angle"):
            raise ValidationError(f"shop.measurable.{k}", v, "length and/or angle: the smallest zone that can be measured")
        limits["m" if k == "length" else "rad"] = parse_quantity(v, f"shop.measurable.{k}" if len(m) > 1 or k != "length"
                                                                 else "shop.measurable", k)
    problem.measurable = {**MEASURABLE, **limits}
    check_floors_feasible(problem)
    return problem


def unmeasurable(problem, t, limits: dict | None = None) -> list[str]:
    """Sources whose allocated zone is narrower than what can be measured (one line each).

    Parameters
    ----------
    problem : ToleranceProblem
        The problem.
    t : array_like, shape (n_sources,)
        A design (SI).
    limits : dict, optional
        SI unit (``"m"``, ``"rad"``) -> the smallest measurable zone (default :data:`MEASURABLE`).

    Returns
    -------
    list of str
        One line per free source (one per callout) whose tolerance is below its limit.
    """
    limits = {**MEASURABLE, **(limits or {})}
    t = problem.as_array(t)
    out, seen = [], set()
    for j, (n, u) in enumerate(zip(problem.names, problem.units())):
        name = _callout(n)
        if not problem.free[j] or name in seen or u not in limits or t[j] >= limits[u] * (1 - 1e-9):
            continue
        seen.add(name)
        show = (lambda v: f"{v * 1e6:.3g} µm") if u == "m" else (lambda v: f"{np.degrees(v) * 3600:.3g} arcsec")
        out.append(f"{name}: a tolerance of {show(t[j])} is below what can be measured ({show(limits[u])}, [shop] "
                   f"measurable): state a floor ([shop] floors) or a capable measurement")
    return out

"""The allocated design as a drawing carries it: zones rounded to a stated drawing precision, and the
rounded design re-checked against the requirement (issue 34 item 5).

A free tolerance's zone ``[lower, upper]`` (deviations from the nominal, display unit) is rounded
**inward** to the precision -- ``lower`` up, ``upper`` down -- so the drawing never allows more than
the allocation. A fixed or locked source is a given, not a choice: its zone is rounded **outward**
(the drawing states at least what it is) and re-checked as it is given. The re-check is made on exactly the drawn zones: the
problem's intervals are re-shaped (:meth:`ToleranceProblem.with_tolerances`: ``minus``/``plus``
such that ``[offset − minus·t, offset + plus·t]`` is the rounded zone at the same ``t``; a disk or
ball source takes the rounded radius as its ``t``), evaluated with the problem's own measure, and
its normalised error (largest error / requirement) reported: at most 1 means the drawing still
meets the requirement. The cost is that of the drawn zones (the cost model sees their widths).
"""
from __future__ import annotations

import math

import numpy as np

from evotol.core.problem import ToleranceProblem
from evotol.errors import ValidationError, is_real
from evotol.units.display import ROUND_OFF, DisplayUnits, number
from evotol.verification.nonlinear import worst_vertex_errors
from evotol.robots.mechanism.callouts.model import zone_per_t

#: units of the keys this module adds to a study's JSON (docs/units.md)
KEYS = {"drawing_lower": "the source's display unit (display_units), rounded to the drawing precision",
        "drawing_upper": "the source's display unit (display_units), rounded to the drawing precision",
        "precision": "the display unit it is keyed by", "meets": "bool", "vanished": "source names",
        "drawing_value": "the source's display unit (display_units): a callout's drawn value (its ⌀ or face width)",
        "meets_nonlinear": "bool"}
#: default drawing precision per display unit (a 0.1 µm step in every length unit, 0.1 arcsec in angles)
DEFAULT_PRECISION = {"µm": 0.1, "mm": 1e-4, "in": 1e-5, "arcsec": 0.1, "mrad": 1e-4, "deg": 1e-5}


def tolerance_zone(source: dict, t: float) -> dict:
    """The zone a drawing states for one source at tolerance t: the deviations from the nominal
    ``lower = offset − minus·t`` and ``upper = offset + plus·t`` and the half-width
    ``(minus + plus)/2·t`` (``docs/tolerances.md``). Every view of a tolerance (the JSON's
    ``zones``, the page's tolerance table, the CSV and the workbook) takes its zone from here.

    Parameters
    ----------
    source : dict
        A row of :func:`evotol.summaries.user_study.source_table` (``offset`` in m or rad, ``minus``, ``plus`` per unit t).
    t : float
        The tolerance (m or rad, the source's unit).

    Returns
    -------
    dict
        ``lower``, ``upper`` (signed deviations, m or rad) and ``half_width`` (m or rad); for a
        callout member (``zone_per_t`` in the row, :attr:`CalloutModel.zone_per_t`) the zone of the
        member itself, e.g. the disc of radius t/2 at a bore's end for a position ⌀t.
    """
    t = float(t) * source.get("zone_per_t", 1.0)     # a callout member's zone is t/2 per unit of the callout's t
    return {"lower": source["offset"] - source["minus"] * t, "upper": source["offset"] + source["plus"] * t,
            "half_width": 0.5 * (source["minus"] + source["plus"]) * t}


def _source_rows(problem: ToleranceProblem) -> list[dict]:
    """The rows :func:`tolerance_zone` reads, per source (SI): name, unit, dim, offset, minus, plus, fixed, locked."""
    rows = []
    callouts = problem.model.part_of("callouts")
    per_t = zone_per_t(problem.model)
    for n, s in zip(problem.names, problem.model.sources):
        tol = problem.tolerances[n]
        rows.append({"name": n, "unit": s.unit, "dim": s.dim, "offset": float(tol.offset), "minus": float(tol.minus),
                     "plus": float(tol.plus), "fixed": bool(tol.is_fixed), "locked": tol.locked,
                     "zone_per_t": per_t.get(n, 1.0),
                     "callout": callouts is not None and callouts.callout_of(n) is not None})
    return rows


def clean(value: float, digits: int = 13) -> float:
    """``value`` rounded to ``digits`` significant digits: no float noise (9524.999999999998 -> 9525.0);
    a value in a display unit below ``ROUND_OFF`` (1e-9, :mod:`evotol.units.display`) is 0.

    Parameters
    ----------
    value : float
        Any number.
    digits : int
        Significant digits kept (default 13, far below a drawing's precision and far above
        round-off).

    Returns
    -------
    float
        The rounded number; 0 (never -0.0) below ``ROUND_OFF`` in magnitude; inf and NaN unchanged.
    """
    v = float(value)
    if abs(v) < ROUND_OFF:
        return 0.0              # round-off, never "-0.0"
    if not math.isfinite(v):
        return v
    return round(v, digits - 1 - int(math.floor(math.log10(abs(v))))) + 0.0


def precision_warnings(problem: ToleranceProblem, units: DisplayUnits, precision: dict,
                       field: str = "report.precision") -> list[str]:
    """A stated drawing step coarser than the zones the allocation may give: a free source whose
    zone at its lower bound is narrower than the step could be drawn as ``0 / 0`` (one line per
    display unit, naming the key, before any work).

    Parameters
    ----------
    problem : ToleranceProblem
        The study's problem (free sources, their lower bounds).
    units : DisplayUnits
        The study's display units.
    precision : dict
        Display unit -> step, as :func:`drawing_precision` gives it (only the stated steps).
    field : str
        The setting's name in the line.

    Returns
    -------
    list of str
        One line per display unit whose step exceeds the half-width of some free source's zone
        at its lower bound; empty otherwise.
    """
    smallest = {}
    for j, row in enumerate(_source_rows(problem)):
        du = units.unit_for(row["unit"])
        if not problem.free[j] or du not in precision:
            continue
        hw = tolerance_zone(row, problem.lower[j])["half_width"] * units.factor(row["unit"])
        if hw < precision[du] and hw < smallest.get(du, (math.inf,))[0]:
            smallest[du] = (hw, row["name"])
    return [f"{field} = {precision[du]:g} {du} is coarser than the zones it rounds: {name}'s zone at its lower bound "
            f"is ±{number(hw)} {du}, which the drawing would show as 0; state a step of at most {number(hw / 10)} {du}"
            for du, (hw, name) in smallest.items()]


def drawing_precision(spec, units: DisplayUnits, field: str = "report.precision") -> dict:
    """The drawing precision a study states (``[report] precision``), keyed by display unit.

    Parameters
    ----------
    spec : float, dict or None
        A number (the step of the length display unit), ``{length = step, angle = step}``, or
        None for :data:`DEFAULT_PRECISION`.
    units : DisplayUnits
        The study's display units (the steps are in them).
    field : str
        The setting's name in error messages.

    Returns
    -------
    dict
        Display unit -> step (only the units the study states; the rest take the defaults).

    Raises
    ------
    evotol.errors.ValidationError
        A step that is not a positive number, or a table with keys other than ``length``/``angle``.
    """
    if spec is None:
        return {}
    table = {"length": spec} if not isinstance(spec, dict) else dict(spec)
    out = {}
    for k, v in table.items():
        if k not in ("length", "angle"):
            raise ValidationError(f"{field}.{k}", v, "length and/or angle: the drawing step in the display unit")
        if not is_real(v) or not math.isfinite(v) or v <= 0:
            raise ValidationError(f"{field}.{k}" if isinstance(spec, dict) else field, v,
                                  f"a positive drawing step in {units.length if k == 'length' else units.angle}")
        out[units.length if k == "length" else units.angle] = float(v)
    return out


def _decimals(step: float) -> int:
    return max(0, -int(math.floor(math.log10(step) + 1e-9)))


def rounded_design(problem: ToleranceProblem, t, units: DisplayUnits, precision: dict | None = None) -> dict:
    """Round a design's zones to the drawing precision and re-check the drawn zones (module docstring).

    Parameters
    ----------
    t : array_like, shape (n_sources,)
        The allocated tolerances (SI: m or rad).
    units : DisplayUnits
        The study's display units (the precision is stated in them).
    precision : dict, optional
        Display unit -> drawing step (default :data:`DEFAULT_PRECISION`).

    Returns
    -------
    dict
        ``precision`` (display unit -> step used), ``zones`` (source -> ``drawing_lower``,
        ``drawing_upper``: the rounded deviations in the source's display unit), ``normalised_error`` (1: largest error / requirement of the drawn
        zones; None when a zone vanishes), ``meets`` (bool), ``cost`` (cost units, of the drawn
        zones; None when a zone vanishes) and ``vanished`` (sources whose zone rounds to nothing:
        the precision is too coarse for them).
    """
    steps = {**DEFAULT_PRECISION, **(precision or {})}
    t = np.asarray(t, dtype=float)
    T = t.copy()
    sh = problem.shape
    minus = sh.rho - sh.kappa
    plus = sh.rho + sh.kappa
    zones, used, vanished = {}, {}, []
    for j, row in enumerate(_source_rows(problem)):
        du = units.unit_for(row["unit"])
        k, p = units.factor(row["unit"]), steps.get(du, 0.0)
        z = tolerance_zone(row, t[j])
        if p <= 0:
            zones[row["name"]] = {"drawing_lower": clean(z["lower"] * k), "drawing_upper": clean(z["upper"] * k)}
            continue
        used[du] = p
        if row["callout"] and not (row["fixed"] or row["locked"] is not None):
            # a drawing callout states its value t (the ⌀ or the face's width): that value is what is
            # rounded inward, and every member of the callout takes it (they share one variable)
            c_r = round(math.floor(t[j] * k / p + 1e-9) * p, _decimals(p)) + 0.0
            T[j] = c_r / k
            zd = tolerance_zone(row, T[j])
            zones[row["name"]] = {"drawing_lower": clean(zd["lower"] * k), "drawing_upper": clean(zd["upper"] * k),
                                  "drawing_value": c_r}
            if c_r <= 0:
                vanished.append(row["name"])
            continue
        lo_q, up_q = z["lower"] * k / p, z["upper"] * k / p
        given = row["fixed"] or row["locked"] is not None
        if given:       # outward: the drawing states at least the given zone (re-checked as given)
            lo_r, up_r = math.floor(lo_q + 1e-9) * p, math.ceil(up_q - 1e-9) * p
        else:           # inward: never more than the allocation
            lo_r, up_r = math.ceil(lo_q - 1e-9) * p, math.floor(up_q + 1e-9) * p
        d = _decimals(p)
        lo_r, up_r = round(lo_r, d) + 0.0, round(up_r, d) + 0.0
        zones[row["name"]] = {"drawing_lower": lo_r, "drawing_upper": up_r}
        if given:
            continue
        f = row["zone_per_t"]      # back from the member's zone to the callout's value
        if row["dim"] > 1 or (row["offset"] == 0 and minus[j] == plus[j] == 1 and lo_r == -up_r):
            T[j] = up_r / k / f     # a centred ±t stays centred (the clearance measure takes only ±t)
        else:
            minus[j] = max(row["offset"] - lo_r / k, 0.0) / (t[j] * f)
            plus[j] = max(up_r / k - row["offset"], 0.0) / (t[j] * f)
        if up_r <= lo_r or T[j] <= 0:
            vanished.append(row["name"])
    out = {"precision": used, "zones": zones, "vanished": vanished, "normalised_error": None, "meets": False, "cost": None}
    if vanished:
        return out
    drawn = problem.with_tolerances(minus=minus, plus=plus)
    err = float(drawn.evaluate(T[None]).violation[0] + 1)
    out.update(normalised_error=err, meets=bool(err <= 1 + 1e-9), cost=float(drawn.cost(T[None])[0]))
    out.update(nonlinear_check(drawn, T))
    return out


def nonlinear_check(problem: ToleranceProblem, t) -> dict:
    """The drawn design on the robot's nonlinear model: the error at each pose's worst-case vertex
    (:func:`evotol.verification.nonlinear.worst_vertex_errors`) against the requirement.

    Made for a worst-case requirement on a robot with a nonlinear model (the nonlinear counterpart
    of the worst case); nothing otherwise.

    Parameters
    ----------
    problem : ToleranceProblem
        The problem of the drawn zones.
    t : array_like, shape (n_sources,)
        The drawn design (SI: m or rad).

    Returns
    -------
    dict
        ``normalised_error_nonlinear`` (1: max over components of the largest nonlinear error /
        requirement), ``meets_nonlinear`` (bool) and ``over_nonlinear`` (component -> the error
        beyond the requirement, SI, negative when within it); empty when not made.
    """
    comps = problem.components
    if (problem.requirement.measure != "worst_case" or not comps
            or not problem.error_model.has_nonlinear_model):
        return {}
    nl = worst_vertex_errors(problem, t)
    worst = {c: float(np.max(nl[c])) for c, _ in comps if c in nl}
    if not worst:
        return {}
    err = max(worst[c] / lim for c, lim in comps if c in worst)
    return {"normalised_error_nonlinear": err, "meets_nonlinear": bool(err <= 1 + 1e-9),
            "over_nonlinear": {c: worst[c] - lim for c, lim in comps if c in worst}}

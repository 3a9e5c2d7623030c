"""Requirements and tolerance bounds that are probably unit slips, and requirements that do not act
(issue 27 item 3).

A study that runs to a "certified optimal" answer can still answer the wrong question:
``position = 0.05`` meant 0.05 mm but reads 50 mm, so every tolerance sits at its upper bound and
the requirement never binds. These checks never stop a run; each gives **one line** with the
numbers and a units hint:

* **outside the usual range** (:data:`USUAL_RANGE`, SI): a position requirement (or a per-axis
  limit, named by its axis: ``requirement.position.y``) above 10 mm or below 10 nm, an orientation
  requirement above 0.1 rad (5.7°) or below 1e-8 rad; a tolerance bound (lower or upper) or a given
  tolerance (``fixed``, ``locked``) above 10 mm or 0.1 rad (a tiny lower bound only allows more). An
  assembly function's requirement is a ratio of its limits (``position = 1``) and is not checked;
* **inactive requirement**: every free tolerance at its upper bound while the largest error is at
  least :data:`INACTIVE_FACTOR` (10) times below the requirement -- the bounds decide the design,
  not the requirement (worst-case, RSS and quantile measures; not in budget mode).

:func:`problem_warnings` runs once, when the problem is built (kept as ``problem.warnings`` and
issued then), :func:`result_warnings` once per allocator's result (:func:`evotol.core.result.make_result`
keeps the lines in ``info["warnings"]``; the allocator issues them with :func:`issue`);
:func:`study_warnings` lists what was computed, in that order.
"""
from __future__ import annotations

import logging
import math
import warnings
from contextlib import contextmanager

import numpy as np

from evotol.core.shop import unmeasurable

#: usual range of requirements and tolerance bounds per unit (SI): (smallest, largest)
USUAL_RANGE = {"m": (1e-8, 1e-2), "rad": (1e-8, 0.1)}
#: an error this many times below the requirement, with every tolerance at its upper bound: inactive
INACTIVE_FACTOR = 10.0
_COMPONENT_UNIT = {"position": "m", "orientation": "rad"}
_RANGE_TEXT = {"m": "10 nm to 10 mm", "rad": "1e-8 to 0.1 rad (5.7 deg)"}


class PlausibilityWarning(UserWarning):
    """A value that is probably a unit slip, or a requirement that does not act."""


def shown(value: float, unit: str) -> str:
    """``0.05 m`` -> ``'0.05 m (50 mm)'``; ``0.5 rad`` -> ``'0.5 rad (28.6 deg)'``.

    Parameters
    ----------
    value : float
        The value in ``unit``.
    unit : str
        ``"m"``, ``"rad"`` or another unit (then shown without a conversion).

    Returns
    -------
    str
        The value (6 significant digits) with its unit, and in mm or deg for m or rad.
    """
    if unit == "m":
        return f"{value:.6g} m ({value * 1e3:.6g} mm)"
    if unit == "rad":
        return f"{value:.6g} rad ({math.degrees(value):.6g} deg)"
    return f"{value:.6g} {unit}"


def units_hint(value: float, unit: str) -> str:
    """What the number would be if it was written in mm or deg: ``'if 0.05 was meant in mm, write 5e-05'``.

    Parameters
    ----------
    value : float
        The number as written in the study file (read as SI).
    unit : str
        Its SI unit, ``"m"`` or ``"rad"``.

    Returns
    -------
    str
        The hint, with ``value`` read as mm (times 1e-3) or deg (in rad); ``""`` for another unit.
    """
    if unit == "m":
        return f"if {value:g} was meant in mm, write {value * 1e-3:.6g} or '{value:g} mm'"
    if unit == "rad":
        return f"if {value:g} was meant in deg, write {math.radians(value):.6g} or '{value:g} deg'"
    return ""


def _out_of_range(field: str, value: float, unit: str, what: str) -> str | None:
    lo, hi = USUAL_RANGE[unit]
    if lo <= value <= hi:
        return None
    if value > hi:
        return (f"{field} = {shown(value, unit)} is above the usual range of {what} ({_RANGE_TEXT[unit]}); values are "
                f"SI (m, rad): {units_hint(value, unit)}")
    return f"{field} = {shown(value, unit)} is below the usual range of {what} ({_RANGE_TEXT[unit]}); values are SI (m, rad)"


def _normalised_requirement(problem) -> bool:
    """An assembly function's requirement is a ratio of its limits (robots/assembly/)."""
    from evotol.robots.assembly import AssemblyFunction

    return isinstance(problem.model, AssemblyFunction)


def problem_warnings(problem) -> list[str]:
    """Requirement and tolerance bounds outside their usual range (one line each).

    Parameters
    ----------
    problem : ToleranceProblem
        The problem as built (requirement, tolerances with their units).

    Returns
    -------
    list of str
        One line per finding; empty when every value is in its usual range.
    """
    out = []
    axis = problem.model.part_of("axis_limits")
    per_axis = {c: getattr(axis.limits, c) for c in ("position", "orientation")} if axis is not None else {}
    if not _normalised_requirement(problem):
        for comp, bound in problem.components:
            if per_axis.get(comp):          # per-axis limits: each limit is checked under its own key
                for ax, v in per_axis[comp].items():
                    line = _out_of_range(f"requirement.{comp}.{ax}", float(v), _COMPONENT_UNIT[comp],
                                         f"a per-axis {comp} limit")
                    out += [line] if line else []
                continue
            line = _out_of_range(f"requirement.{comp}", bound, _COMPONENT_UNIT[comp], f"a {comp} requirement")
            if line:
                out.append(line)
    units = problem.units()
    for name, unit, free in zip(problem.names, units, problem.free):
        tol = problem.tolerances[name]
        given = tol.locked if tol.locked is not None else (tol.upper if tol.is_fixed else None)
        if not free and given is not None and unit in USUAL_RANGE and float(given) > USUAL_RANGE[unit][1]:
            key = "fixed" if tol.is_fixed else "locked"
            out.append(_out_of_range(f"sources.{name}.{key}", float(given), unit, f"a tolerance in {unit}"))
    for which, values in (("upper", problem.upper), ("lower", problem.lower)):
        by_value = {}
        for name, unit, v, free in zip(problem.names, units, values, problem.free):
            if free and unit in USUAL_RANGE and v > USUAL_RANGE[unit][1]:      # a tiny bound only allows more
                by_value.setdefault((unit, float(v)), []).append(name)
        for (unit, v), names in by_value.items():
            who = names[0] if len(names) == 1 else f"{len(names)} sources ({', '.join(names[:3])}{', ...' if len(names) > 3 else ''})"
            out.append(_out_of_range(f"tolerance {which} bound of {who}", v, unit, f"a tolerance in {unit}"))
    return out


def result_warnings(problem, result) -> list[str]:
    """Whether the requirement acted on ``result`` (one line per inactive component).

    Parameters
    ----------
    problem : ToleranceProblem
        The problem ``result`` solves (requirement, bounds, free sources).
    result : AllocationResult
        An allocator's result (tolerances, errors, info).

    Returns
    -------
    list of str
        One line per component whose largest error is at least ``INACTIVE_FACTOR`` times below
        its requirement while every free tolerance is at its upper bound (never for the yield
        measure or in budget mode); and, for a problem with ``measurable`` limits (a study file's
        ``[shop]``, :func:`evotol.core.shop.apply_shop`), one line per source whose zone is below
        them (:func:`evotol.core.shop.unmeasurable`).
    """
    out = []
    if problem.measurable is not None:     # a study file's [shop] (issue 41): zones below it
        out += unmeasurable(problem, result.t, problem.measurable)
    if problem.requirement.measure == "yield" or "budget" in (result.info or {}):
        return out
    if problem.calibration is not None:   # calibration removes the first-order error: the
        return out                                          # linear-range bounds decide (docs/calibration.md)
    t = result.t
    f = problem.free
    if not np.all(t[f] >= problem.upper[f] * (1 - 1e-6)):
        return out
    for comp, bound in problem.components:
        err = result.max_error(comp)
        if np.isfinite(err) and err * INACTIVE_FACTOR <= bound:
            unit = _COMPONENT_UNIT[comp]
            ratio = _normalised_requirement(problem)        # an assembly's requirement: a ratio of its limits
            show = (lambda v: f"{v:.6g} (ratio of the limits)") if ratio else (lambda v: shown(v, unit))
            out.append(f"requirement.{comp} = {show(bound)} is inactive for {result.method}: every free tolerance "
                       f"sits at its upper bound and the largest {comp} error is {show(err)}, "
                       f"{bound / max(err, 1e-300):.3g}x below it" + ("" if ratio else f"; {units_hint(bound, unit)}"))
    return out


def study_warnings(problem, results) -> list[str]:
    """Every line of a study: the problem's (``problem.warnings``), then each result's
    ``info["warnings"]`` -- each computed once, where it arose.

    Parameters
    ----------
    problem : ToleranceProblem
        The study's problem (its ``warnings``, :func:`problem_warnings` at construction).
    results : iterable of AllocationResult
        The methods' results; their ``info["warnings"]`` are read.

    Returns
    -------
    list of str
        The lines, in that order.
    """
    return [*problem.warnings, *(w for r in results for w in (r.info or {}).get("warnings", ()))]


def issue(result):
    """Issue a result's plausibility lines (``result.info["warnings"]``) as :class:`PlausibilityWarning`,
    the allocators' last step.

    Parameters
    ----------
    result : AllocationResult
        An allocator's result.

    Returns
    -------
    AllocationResult
        ``result`` itself.
    """
    warn((result.info or {}).get("warnings", ()), stacklevel=4)
    return result


@contextmanager
def reported(stream=None):
    """Within the block, each :class:`PlausibilityWarning` is shown once as one line instead of
    Python's two-line format: logged at WARNING level on the ``evotol`` log (which the command shows
    as ``evotol: warning: ...`` on standard error), or printed on ``stream``; other warnings are
    shown as usual. Yields the list of lines shown.

    Parameters
    ----------
    stream : file, optional
        Where the lines go (default: the log).

    Yields
    ------
    list of str
        The distinct warning lines printed so far; it grows while the block runs.
    """
    lines = []
    with warnings.catch_warnings():
        warnings.simplefilter("always", PlausibilityWarning)
        show = warnings.showwarning

        def one_line(message, category, filename, lineno, file=None, line=None):
            if not issubclass(category, PlausibilityWarning):
                return show(message, category, filename, lineno, file, line)
            if str(message) not in lines:
                lines.append(str(message))
                if stream is None:
                    logging.getLogger(__name__).warning("%s", message)
                else:
                    print(f"evotol: warning: {message}", file=stream, flush=True)

        warnings.showwarning = one_line
        yield lines


def warn(lines, stacklevel: int = 3) -> None:
    """Issue each line as a :class:`PlausibilityWarning` (Python shows each distinct line once).

    Parameters
    ----------
    lines : iterable of str
        The warning lines (from :func:`problem_warnings` or :func:`result_warnings`).
    stacklevel : int, optional
        Passed to :func:`warnings.warn` (default 3: the caller of the function that calls this).
    """
    for line in lines:
        warnings.warn(line, PlausibilityWarning, stacklevel=stacklevel)

"""One unit grammar for every length and angle a study file or a mechanism description takes
(issue 41 item 5, ``docs/units.md`` "Writing a value with its unit").

A value is a number followed by a unit, with a space or a ``*`` between them or nothing:
``"0.5 mm"``, ``"0.5*mm"``, ``"0.5mm"``, ``"20 um"``, ``"20*µm"``, ``"0.1 mrad"``, ``"30 deg"``,
``"0.002 in"``. The units and their size in SI are the one table :data:`UNITS` (lengths in m,
angles in rad); every reader (requirement bounds, per-axis limits, bounds and given tolerances,
callout lengths, the calibration's noise, the safe expressions of a description) takes its units
from here, so a spelling accepted in one place is accepted in all. pint was considered: it would
add a dependency and a registry of several thousand units for the dozen a tolerance file needs, and
its parser accepts expressions (``"2 mm / 3"``) that our safe expressions already cover.
"""
from __future__ import annotations

import math
import re

from evotol.errors import ValidationError, is_real

#: unit -> (kind, size in SI: m for a length, rad for an angle)
UNITS = {
    "m": ("length", 1.0), "mm": ("length", 1e-3), "um": ("length", 1e-6), "µm": ("length", 1e-6),
    "μm": ("length", 1e-6), "micron": ("length", 1e-6), "nm": ("length", 1e-9), "in": ("length", 0.0254),
    "inch": ("length", 0.0254),
    "rad": ("angle", 1.0), "mrad": ("angle", 1e-3), "urad": ("angle", 1e-6), "µrad": ("angle", 1e-6),
    "μrad": ("angle", 1e-6), "deg": ("angle", math.pi / 180), "°": ("angle", math.pi / 180),
    "arcmin": ("angle", math.pi / (180 * 60)), "arcsec": ("angle", math.pi / (180 * 3600)),
}
#: the SI unit of each kind
SI = {"length": "m", "angle": "rad"}
_VALUE = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*\*?\s*([^\s\d*+\-/.][^\s*]*)\s*$")


def units_of(kind: str | None) -> dict:
    """The units of one kind (``"length"``, ``"angle"``; None: all) and their size in SI.

    Parameters
    ----------
    kind : {"length", "angle"} or None
        The kind.

    Returns
    -------
    dict of str to float
        Unit -> size (m or rad).
    """
    return {u: f for u, (k, f) in UNITS.items() if kind is None or k == kind}


def is_quantity_text(value) -> bool:
    """True when ``value`` is a string of the grammar (a number and a unit of :data:`UNITS`).

    Parameters
    ----------
    value : object
        Anything.

    Returns
    -------
    bool
        Whether :func:`parse_quantity` reads it.
    """
    m = _VALUE.match(value) if isinstance(value, str) else None
    return bool(m) and m.group(2) in UNITS


def parse_quantity(value, field: str, kind: str | None = None, require_unit: bool = False) -> float:
    """A value written with its unit (module docstring), in SI.

    Parameters
    ----------
    value : str or int or float
        ``"0.5 mm"``, ``"20*um"``, ``"30 deg"``..., or a number (taken as SI unless ``require_unit``).
    field : str
        The key named in an error.
    kind : {"length", "angle"} or None
        The kind the field takes (None: either).
    require_unit : bool
        Refuse a bare number other than 0 (a drawing length, a noise: the unit slip this exists for).

    Returns
    -------
    float
        The value in m (length) or rad (angle).

    Raises
    ------
    evotol.errors.ValidationError
        Not a number or a number with a unit, an unknown unit, a unit of the other kind, a
        non-finite number, or a bare number where a unit is required.

    Examples
    --------
    >>> from evotol.units.quantity import parse_quantity
    >>> [round(parse_quantity(v, "x"), 12) for v in ("0.5 mm", "0.5*mm", "20 um", "20*um", "0.002 in")]
    [0.0005, 0.0005, 2e-05, 2e-05, 5.08e-05]
    >>> round(parse_quantity("30 deg", "x", "angle"), 6), parse_quantity("0.1 mrad", "x", "angle")
    (0.523599, 0.0001)
    """
    units = units_of(kind)
    example = {"length": "'0.5 mm'", "angle": "'30 deg'", None: "'0.5 mm' or '30 deg'"}[kind]
    expected = f"{'an angle' if kind == 'angle' else 'a ' + (kind or 'length or angle')} with its unit, e.g. {example} (units {', '.join(units)})"
    if is_real(value):
        if require_unit and value != 0:
            raise ValidationError(field, value, expected + "; a bare number has none")
        if not math.isfinite(value):
            raise ValidationError(field, value, "a finite value")
        return float(value)
    m = _VALUE.match(value) if isinstance(value, str) else None
    if m is None:
        raise ValidationError(field, value, expected)
    unit = m.group(2)
    if unit not in units:
        other = UNITS.get(unit, (None,))[0]
        raise ValidationError(field, value, expected + (f" ({unit!r} is a unit of {other})" if other else ""))
    v = float(m.group(1)) * units[unit]
    if not math.isfinite(v):
        raise ValidationError(field, value, "a finite value")
    return v

"""Plausibility checks of a mechanism description: values that parse but do not mean what was
written (issue 27 item 2). A careful CAD or robot-description tool checks a model before it
computes with it; these checks make the commonest slips errors that name the field, the value
and the fix:

* a **length beyond** :data:`MAX_LENGTH` (10 m; ``[checks] max_length`` raises it for a large
  machine): ``Rb = 250`` meant 250 mm -- "did you mean '250*mm'?";
* an **angle beyond 2π written as a plain number** (``gamma = 90`` is 90 rad): "did you mean
  '90*deg'?" -- an angle written with a unit or with ``pi`` (``"720*deg"``, ``"4*pi"``) is taken
  as meant (also in ``[assembly] joints`` and ``[limits]``, by the joint's kind);
* a **negative design length** in ``[lengths]`` (a mirrored mechanism), unless listed in ``[checks]
  negative_lengths``: signs belong in the frame entries (``d = "-rp"``);
* a **workspace coordinate that moves nothing**: an ``angle`` coordinate named in no
  ``end_effector.orientation`` entry, two coordinates on one axis, a ``z`` coordinate or an
  out-of-plane orientation in a planar mechanism.

The written values (``spec``, the parsed TOML) are checked, not only the SI numbers, so the
message can quote what was typed. Whether the workspace stays within the joint and stroke limits
is the inverse geometry's check (issue 23).
"""
from __future__ import annotations

import math
from typing import Mapping

from evotol.errors import ValidationError
from evotol._runtime.keyword_checks import check_table_keys
from evotol.robots.mechanism.description.expressions import Expression

#: largest plausible length of a description (m), unless ``[checks] max_length`` says otherwise
MAX_LENGTH = 10.0
CHECK_KEYS = ("max_length", "negative_lengths")
_LENGTH_FIELDS, _ANGLE_FIELDS = ("b", "d", "r"), ("gamma", "alpha", "theta")


def _constant(raw, where: str) -> float | None:
    """The value of a constant entry (number or constant expression), else None."""
    if isinstance(raw, bool) or not isinstance(raw, (int, float, str)):
        return None
    e = Expression.parse(raw, where)
    return float(e({})) if e.is_constant else None


def _check_length(where: str, raw, value: float | None, max_length: float) -> None:
    if value is None or abs(value) <= max_length:
        return
    hint = f"; did you mean '{raw}*mm'?" if not isinstance(raw, str) else ""
    raise ValidationError(where, raw, f"a length in metres below {max_length:g} m{hint} (a larger machine: "
                                      "raise [checks] max_length)")


def _check_angle(where: str, raw) -> None:
    if isinstance(raw, bool) or not isinstance(raw, (int, float)) or abs(raw) <= 2 * math.pi:
        return
    raise ValidationError(where, raw, f"an angle in radians within ±2π, or written with its unit: did you mean '{raw}*deg'?")


def check_options(spec: Mapping) -> tuple[float, frozenset]:
    """``[checks]``: ``max_length`` (m) and ``negative_lengths`` (names of ``[lengths]``).

    Parameters
    ----------
    spec : mapping
        The description as parsed from TOML; its ``[checks]`` table (optional) is read.

    Returns
    -------
    max_length : float
        Largest plausible length (m); :data:`MAX_LENGTH` (10 m) unless ``[checks]`` sets it.
    negative_lengths : frozenset of str
        Names of ``[lengths]`` allowed to be negative.

    Raises
    ------
    evotol.errors.ValidationError
        An unknown ``[checks]`` key, a ``max_length`` that is not a positive constant, or a
        ``negative_lengths`` that is not a list of names of ``[lengths]``.
    """
    opts = spec.get("checks", {})
    check_table_keys(opts, CHECK_KEYS, "checks")
    max_length = _constant(opts.get("max_length", MAX_LENGTH), "checks.max_length")
    if max_length is None or not max_length > 0:
        raise ValidationError("checks.max_length", opts.get("max_length"), "a positive length in metres")
    neg = opts.get("negative_lengths", [])
    lengths = dict(spec.get("lengths", {}))
    if not isinstance(neg, list) or any(n not in lengths for n in neg):
        raise ValidationError("checks.negative_lengths", neg, f"a list of names of [lengths]: {sorted(lengths)}")
    return max_length, frozenset(neg)


def check_written_values(spec: Mapping, variables: Mapping[str, str]) -> None:
    """Lengths, angles and assembly joints as written in ``spec`` (the parsed TOML).

    Parameters
    ----------
    spec : mapping
        The description as parsed from TOML (written values: numbers or expression strings).
    variables : mapping
        Joint variable -> ``"m"`` (prismatic) or ``"rad"`` (revolute), for ``[assembly] joints``.

    Raises
    ------
    ValidationError
        Naming the field, the value as written and the fix (see the module docstring).
    """
    max_length, negative_ok = check_options(spec)
    for k, raw in dict(spec.get("lengths", {})).items():
        v = _constant(raw, f"lengths.{k}")
        _check_length(f"lengths.{k}", raw, v, max_length)
        if v is not None and v < 0 and k not in negative_ok:
            raise ValidationError(f"lengths.{k}", raw, "a non-negative length (a negative one mirrors the mechanism): put the "
                                                       f"sign in the frame entries ('-{k}'), or list {k!r} in [checks] "
                                                       "negative_lengths if it is intended")
    for k, raw in dict(spec.get("angles", {})).items():
        _check_angle(f"angles.{k}", raw)
    for i, fr in enumerate(spec.get("frame", []) if isinstance(spec.get("frame"), list) else []):
        name = fr.get("name", i) if isinstance(fr, Mapping) else i
        for k in _LENGTH_FIELDS:
            if isinstance(fr, Mapping) and k in fr:
                _check_length(f"frame {name!r}.{k}", fr[k], _constant(fr[k], f"frame {name!r}.{k}"), max_length)
        for k in _ANGLE_FIELDS:
            if isinstance(fr, Mapping) and k in fr:
                _check_angle(f"frame {name!r}.{k}", fr[k])
    ee = spec.get("end_effector", {}) if isinstance(spec.get("end_effector"), Mapping) else {}
    coords = [c for c in ee.get("coordinates", []) if isinstance(c, Mapping)]
    for c in coords:
        for side in ("low", "high"):
            if side in c:
                where = f"coordinate {c.get('name')}.{side}"
                if c.get("axis", c.get("name")) == "angle":
                    _check_angle(where, c[side])
                else:
                    _check_length(where, c[side], _constant(c[side], where), max_length)
    for i, o in enumerate(ee.get("orientation", [])):
        if isinstance(o, list) and len(o) == 2:
            _check_angle(f"end_effector.orientation[{i}]", o[1])
    asm = spec.get("assembly", {}) if isinstance(spec.get("assembly"), Mapping) else {}
    for c, raw in zip(coords, asm.get("pose", ())):
        where = f"assembly.pose ({c.get('name')})"
        if c.get("axis", c.get("name")) == "angle":
            _check_angle(where, raw)
        else:
            _check_length(where, raw, _constant(raw, where), max_length)
    joint_values = [(f"assembly.joints.{x}", x, raw) for x, raw in dict(asm.get("joints", {})).items()]
    limits = spec.get("limits", {}) if isinstance(spec.get("limits"), Mapping) else {}
    joint_values += [(f"limits.{x}", x, raw) for x, pair in limits.items() if isinstance(pair, list) for raw in pair]
    for where, x, raw in joint_values:
        unit = variables.get(x)
        if unit == "m":
            _check_length(where, raw, _constant(raw, where), max_length)
        elif unit == "rad":
            _check_angle(where, raw)


def check_workspace(coordinates, orientation, planar: bool) -> None:
    """Every workspace coordinate moves the end-effector (see the module docstring).

    Parameters
    ----------
    coordinates : sequence of Coordinate
        The description's pose coordinates (``name``, ``axis``).
    orientation : sequence of (axis, expression text)
        The end-effector's target orientation.
    planar : bool
        A planar mechanism moves in the base x-y plane.

    Raises
    ------
    ValidationError
        Naming the coordinate that moves nothing.
    """
    used = set()
    for ax, text in orientation:
        used |= Expression.parse(text, "end_effector.orientation").names
        if planar and ax != "z":
            raise ValidationError("end_effector.orientation", [ax, text], "rotations about z only in a planar mechanism")
    seen = {}
    for c in coordinates:
        if c.axis == "angle":
            if c.name not in used:
                raise ValidationError(f"coordinate {c.name!r}", c.name, "an angle named in end_effector.orientation "
                                                                        f"(e.g. orientation = [['z', '{c.name}']]): otherwise "
                                                                        "it moves nothing and every pose repeats the same joints")
            continue
        if c.axis in seen:
            raise ValidationError(f"coordinate {c.name!r}.axis", c.axis, f"an axis no other coordinate uses "
                                                                         f"({seen[c.axis]!r} is already {c.axis})")
        seen[c.axis] = c.name
        if planar and c.axis == "z":
            raise ValidationError(f"coordinate {c.name!r}.axis", "z", "x, y or angle in a planar mechanism (it moves in "
                                                                      "the base x-y plane; z moves nothing)")

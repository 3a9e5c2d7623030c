"""Reading drawing callouts from a study file's ``[robot]`` table or a description (issue 35).

A callout is one ``[[robot.callouts]]`` table (``[[callouts]]`` in a mechanism description)::

    [[robot.callouts]]
    joint = "elbow_joint"        # the joint whose seat (bore) carries it
    kind = "position"            # position | perpendicularity | parallelism | axial
    length = "50 mm"             # feature length L, with its unit (m, mm, um, in); "stroke" for a guide
    offset = "0 mm"              # centre of the feature along the axis from the joint origin
    datums = "A|B"               # as the drawing writes them (shown, not interpreted)

The zones and the datum convention: :mod:`evotol.robots.mechanism.callouts` and ``docs/callouts.md``.
Every mistake is a one-line :class:`evotol.errors.ValidationError` before any model is built: an
unknown key or kind, a length without unit or not positive, an unknown joint or one without an
axis, two callouts of the same kind (or two orientation callouts) on one joint, ``"stroke"`` on a
joint without a stroke.
"""
from __future__ import annotations

import re

import numpy as np

from evotol._runtime.keyword_checks import check_table_keys, did_you_mean
from evotol.errors import ValidationError
from evotol.robots.mechanism.callouts import KINDS, ORIENTATION_KINDS, Callout
from evotol.robots.mechanism.expressions import Expression

#: keys of one callout table
CALLOUT_KEYS = ("joint", "kind", "length", "offset", "datums")
#: length units a callout may be written in -> metres
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "in": 0.0254}
_LENGTH = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*\*?\s*([a-zµ]+)\s*$")


def parse_length(value, field: str) -> float:
    """A length written with its unit (``"50 mm"``, ``"50*mm"``, ``"0.05 m"``) in metres.

    A bare 0 is accepted (no unit needed); any other bare number is refused: a drawing length
    without unit is the slip this check exists for.

    Parameters
    ----------
    value : str or int or float
        The value as written.
    field : str
        The field named in the error.

    Returns
    -------
    float
        The length (m).

    Raises
    ------
    evotol.errors.ValidationError
        A number without unit, an unknown unit, or not a length at all.
    """
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        if value == 0:
            return 0.0
        raise ValidationError(field, value, f"a length with its unit, e.g. '{value} mm' (units {sorted(LENGTH_UNITS)})")
    m = _LENGTH.match(value) if isinstance(value, str) else None
    if m is None or m.group(2) not in LENGTH_UNITS:
        raise ValidationError(field, value, f"a length with its unit, e.g. '50 mm' (units {sorted(LENGTH_UNITS)})")
    return float(m.group(1)) * LENGTH_UNITS[m.group(2)]


def callouts_from_tables(entries, mech, field: str = "robot.callouts") -> list[Callout]:
    """The callouts of a ``[[robot.callouts]]`` array, checked against the description.

    Parameters
    ----------
    entries : list of dict
        The parsed tables (module docstring).
    mech : evotol.robots.mechanism.mechanism.Mechanism
        The description the joints belong to.
    field : str
        The array's name in error messages.

    Returns
    -------
    list of Callout
        In the order written.

    Raises
    ------
    evotol.errors.ValidationError
        See the module docstring.
    """
    if not isinstance(entries, list) or not entries or not all(isinstance(e, dict) for e in entries):
        raise ValidationError(field, entries, "a non-empty array of tables [[robot.callouts]] joint = ..., kind = ..., length = ...")
    out, seen = [], {}
    for i, e in enumerate(entries):
        where = f"{field}[{i}]"
        check_table_keys(e, CALLOUT_KEYS, where)
        for k in ("joint", "kind", "length"):
            if k not in e:
                raise ValidationError(f"{where}.{k}", None, {"joint": "the joint whose seat carries the callout",
                                                            "kind": f"one of {KINDS}",
                                                            "length": "the feature length with its unit, e.g. '50 mm'"}[k])
        joint, kind = str(e["joint"]), e["kind"]
        if kind not in KINDS:
            raise ValidationError(f"{where}.kind", kind, f"one of {KINDS}" + (" (a guide's straightness is a form "
                                  "error along the stroke, not a placement: use parallelism over the stroke)"
                                  if kind == "straightness" else ""))
        seat = joint_seat(mech, joint)
        if e["length"] == "stroke":
            lim = mech.limits.get(seat["variable"])
            if seat["joint"] != "prismatic" or lim is None:
                raise ValidationError(f"{where}.length", "stroke", f"a length with its unit ({joint} has no prismatic "
                                      "stroke in the description's limits)")
            length = float(lim[1] - lim[0])
        else:
            length = parse_length(e["length"], f"{where}.length")
        if length <= 0:
            raise ValidationError(f"{where}.length", e["length"], "a positive feature length")
        offset = parse_length(e.get("offset", 0), f"{where}.offset")
        key = (joint, "orientation" if kind in ORIENTATION_KINDS else kind)
        if key in seen:
            raise ValidationError(f"{where}.kind", kind, f"one {key[1]} callout per joint ({joint} has one already: "
                                  f"{field}[{seen[key]}])")
        seen[key] = i
        out.append(Callout(joint, kind, length, offset, str(e.get("datums", "A|B"))))
    return out


def joint_seat(mech, joint: str) -> dict:
    """Where a joint's callouts act: its placement frame, axis, type and the part carrying the seat.

    A URDF joint ``J`` has the fixed frame ``J`` (its ``<origin>``) followed by the joint row
    ``J__q`` turning about ``Rot(z, gamma) Rot(x, alpha) e_z``; a ``[[frame]]`` joint row's axis is
    the z of its placement. The part is the URDF parent link, else the antecedent frame.

    Parameters
    ----------
    mech : evotol.robots.mechanism.mechanism.Mechanism
        The description (only its frames, parameters and URDF are read).
    joint : str
        The joint's name (the placement frame's).

    Returns
    -------
    dict
        ``frame`` (placement frame name), ``axis`` ((3,) unit vector in the placement frame),
        ``joint`` (``"revolute"`` or ``"prismatic"``), ``part`` (str), ``variable`` (joint variable
        name or None).

    Raises
    ------
    evotol.errors.ValidationError
        An unknown joint (names the nearest), a fixed frame (no axis to tolerance), or a planar
        mechanism.
    """
    if mech.planar:
        raise ValidationError(f"callout {joint}", mech.name, "a joint of a spatial mechanism (a callout's zone moves "
                              "the axis out of the plane; in a planar mechanism tolerance gamma, d, theta)")
    frames = {f.name: f for f in mech.frames}
    q = frames.get(f"{joint}__q")
    if q is not None and q.antecedent == joint and q.joint != "fixed":
        vals = dict(mech.parameters)
        g, al = (float(Expression.parse(getattr(q, k), f"frame {q.name}.{k}")(vals)) for k in ("gamma", "alpha"))
        axis = np.array([np.sin(al) * np.sin(g), -np.sin(al) * np.cos(g), np.cos(al)])
        return {"frame": joint, "axis": axis, "joint": q.joint, "part": _urdf_parent(mech, joint) or frames[joint].antecedent,
                "variable": str(getattr(q, q.joint_field)).split()[0]}
    f = frames.get(joint)
    if f is None:
        joints = sorted(n for n, fr in frames.items() if fr.joint != "fixed" and not n.endswith("__q")) + \
            sorted(n[:-3] for n in frames if n.endswith("__q"))
        raise ValidationError("callout joint", joint, f"a joint of {mech.name}: {joints}" + did_you_mean(joint, joints))
    if f.joint == "fixed":
        raise ValidationError(f"callout {joint}", "fixed frame", f"a revolute or prismatic joint: {mech.name} has no axis at {joint}")
    return {"frame": joint, "axis": np.array([0.0, 0.0, 1.0]), "joint": f.joint, "part": f.antecedent,
            "variable": str(getattr(f, f.joint_field))}


def _urdf_parent(mech, joint: str) -> str | None:
    """The URDF parent link of ``joint`` (None without a URDF or that joint)."""
    if not mech.urdf:
        return None
    import xml.etree.ElementTree as ET

    for j in ET.parse(mech.urdf[0]).getroot().iter("joint"):
        if j.get("name") == joint and j.find("parent") is not None:
            return j.find("parent").get("link")
    return None


def expand_callout_overrides(overrides: dict, robot) -> dict:
    """``[sources."elbow_joint.position"]`` applies to each member source of that callout.

    Parameters
    ----------
    overrides : dict
        The study file's ``[sources]`` table.
    robot : evotol.robots.base.RobotErrorModel
        The model; its ``tied_sources`` (callout name -> member sources), if any.

    Returns
    -------
    dict
        The table with each callout name replaced by its members (the same settings each).
    """
    tied = getattr(robot, "tied_sources", None) or {}
    out = {}
    for k, v in overrides.items():
        for m in tied.get(k, (k,)):
            out[m] = v
    return out


def refinement_warnings(callouts, lower: dict, upper: dict) -> list[str]:
    """Warnings for an orientation callout tighter than the position callout it refines.

    Parameters
    ----------
    callouts : sequence of Callout
        The callouts.
    lower, upper : dict of str to float
        Callout name -> the smallest and largest allowed value (m; a locked callout: both its value).

    Returns
    -------
    list of str
        One line per joint whose orientation callout is always tighter than its position callout.
    """
    by = {(c.joint, c.kind in ORIENTATION_KINDS): c for c in callouts if c.kind != "axial"}
    out = []
    for (joint, orient), o in by.items():
        p = by.get((joint, False))
        if not orient or p is None:
            continue
        if upper[o.name] < lower[p.name]:
            out.append(f"{o.name}: orientation ⌀ <= {upper[o.name] * 1e6:g} um is tighter than the position ⌀ >= "
                       f"{lower[p.name] * 1e6:g} um it refines, so it is the one that binds the tilt of {joint}; the pair "
                       "is modelled by its safe outer set (centre disc ⌀t_pos + tilt ⌀t_or/L, docs/callouts.md)")
    return out

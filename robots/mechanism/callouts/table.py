"""Reading drawing callouts from a study file's ``[robot]`` table or a description (issue 35).

A callout is one ``[[robot.callouts]]`` table (``[[callouts]]`` in a mechanism description)::

    [[robot.callouts]]
    joint = "elbow_joint"        # the joint whose seat (bore) carries it
    kind = "position"            # position | perpendicularity | parallelism | axial
    length = "50 mm"             # feature length L, with its unit (m, mm, um, in); "stroke" for a guide
    offset = "0 mm"              # centre of the feature along the axis from the joint origin
    datums = "A|B"               # as the drawing writes them (shown, not interpreted)

The zones and the datum convention: :mod:`evotol.robots.mechanism.callouts.zones` and ``docs/callouts.md``.
Every mistake is a one-line :class:`evotol.errors.ValidationError` before any model is built: an
unknown key or kind, a length without unit or not positive, an unknown joint or one without an
axis, two callouts of the same kind (or two orientation callouts) on one joint, ``"stroke"`` on a
joint without a stroke.
"""
from __future__ import annotations


import numpy as np

from evotol._runtime.keyword_checks import check_table_keys, did_you_mean
from evotol.errors import ValidationError
from evotol.units.quantity import parse_quantity, units_of
from evotol.robots.mechanism.callouts.zones import KINDS, ORIENTATION_KINDS, Callout
from evotol.robots.mechanism.description.expressions import Expression

#: keys of one callout table
CALLOUT_KEYS = ("joint", "kind", "length", "offset", "datums")
#: length units a callout may be written in -> metres
LENGTH_UNITS = units_of("length")


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
    return parse_quantity(value, field, "length", require_unit=True)


def callouts_from_tables(entries, mech, field: str = "robot.callouts") -> list[Callout]:
    """The callouts of a ``[[robot.callouts]]`` array, checked against the description.

    Parameters
    ----------
    entries : list of dict
        The parsed tables (module docstring).
    mech : evotol.robots.mechanism.description.mechanism.Mechanism
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
    mech : evotol.robots.mechanism.description.mechanism.Mechanism
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


def dh_placement_fields(mech, uses, joint: str) -> dict:
    """The DH sources that move one placement direction of a ``[[frame]]`` joint's seat exactly.

    A joint row ``J`` turns on the z axis of its placement ``P_J = T_a Rot(z, gamma) Trans(z, b)
    Rot(x, alpha) Trans(x, d)`` (:mod:`evotol.robots.mechanism.kinematics.placement`), then moves by ``Rot(z, theta)
    Trans(z, r)``. Rotations and translations along one axis commute, so an error ``e`` of ``J``'s
    ``d``, ``alpha``, ``r`` or ``theta`` is exactly ``P_J exp(e·[x; 0])``, ``exp(e·[0; x])``,
    ``exp(e·[z; 0])``, ``exp(e·[0; z])``: the placement errors ``shift_x``, ``tilt_x``, ``shift_z``,
    ``tilt_z``. When ``J``'s ``gamma, b, alpha, d`` are nominally 0 and its antecedent is a fixed
    frame ending on ``Trans(x, d)`` (its ``theta``, ``r`` nominally 0), that frame's ``d`` and
    ``alpha`` are ``J``'s ``shift_x`` and ``tilt_x`` too. For a standard-DH row ``i`` (joint frame
    ``J<i>`` after distal frame ``i-1``, :mod:`evotol.robots.mechanism.description.standard_dh`) this says
    ``a_(i-1) = shift_x``, ``alpha_(i-1) = tilt_x``, ``d_i = shift_z``, ``theta_i = tilt_z`` (row 1:
    ``base.a``, ``base.alpha``).

    Parameters
    ----------
    mech : evotol.robots.mechanism.description.mechanism.Mechanism
        The description.
    uses : dict of str to list of (str, str)
        Name -> the DH entries ``(frame, field)`` whose expressions use it (``Kinematics.uses``).
    joint : str
        The joint row (the callout's seat frame).

    Returns
    -------
    dict of str to str
        Source name (an entry ``"<frame>.<field>"``, a design parameter used by that entry alone
        with slope 1, or its standard-DH alias such as ``"base.a"``) -> placement field. Empty for
        a fixed frame (a URDF joint's origin: its placement errors are the sources themselves).
    """
    frames = {f.name: f for f in mech.frames}
    J = frames.get(joint)
    if J is None or J.joint == "fixed":
        return {}
    vals = {**{n: 0.0 for n in uses}, **dict(mech.parameters)}          # joint variables at 0 (not read)

    def value(f, k, extra=None):
        return float(Expression.parse(getattr(f, k), f"frame {f.name}.{k}")({**vals, **(extra or {})}))

    entries = {(joint, "d"): "shift_x", (joint, "alpha"): "tilt_x", (joint, "r"): "shift_z", (joint, "theta"): "tilt_z"}
    P = frames.get(J.antecedent)
    if (P is not None and P.joint == "fixed" and all(abs(value(J, k)) < 1e-15 for k in ("gamma", "b", "alpha", "d"))
            and all(abs(value(P, k)) < 1e-15 for k in ("theta", "r"))):
        entries.update({(P.name, "d"): "shift_x", (P.name, "alpha"): "tilt_x"})
    out = {f"{fr}.{k}": f for (fr, k), f in entries.items()}
    alias = {v: k for k, v in mech.aliases.items()}
    for p, where in uses.items():
        if p in mech.parameters and len(where) == 1 and where[0] in entries:
            fr, k = where[0]
            if abs(value(frames[fr], k, {p: vals[p] + 1.0}) - value(frames[fr], k) - 1.0) < 1e-12:    # slope 1
                out[alias.get(p, p)] = entries[where[0]]
    return out


def datum_features(mech, part: str, datums: str) -> str:
    """The features a callout's datum letters stand for on its part's drawing (``docs/callouts.md``,
    "Datum convention"): the part's own seat on the joint that carries it -- datum A its bore axis,
    datum B its shoulder face -- or, for the base, its mounting face and locating bore. Letters a user
    wrote other than ``A|B`` are kept as their own (evotol cannot know what they name).

    Parameters
    ----------
    mech : evotol.robots.mechanism.description.mechanism.Mechanism
        The description (its URDF, else its frames).
    part : str
        The part (link) that carries the seat.
    datums : str
        The datum letters as the drawing writes them.

    Returns
    -------
    str
        E.g. ``"A = axis of shoulder_link's bore on shoulder_pan_joint, B = its shoulder face"``.
    """
    if datums.replace(" ", "") != "A|B":
        return f"{datums} as the drawing defines them (the joint's nominal placement in {part})"
    carrier = _carrier(mech, part)
    if carrier is None:
        return f"A = {part}'s mounting face, B = its locating bore (the base frame)"
    return f"A = axis of {part}'s bore on {carrier}, B = its shoulder face on {carrier}"


def _carrier(mech, part: str) -> str | None:
    """The moving joint that carries ``part`` (through fixed joints), or None at the base."""
    if mech.urdf:
        import xml.etree.ElementTree as ET

        joints = {j.find("child").get("link"): j for j in ET.parse(mech.urdf[0]).getroot().iter("joint")
                  if j.find("child") is not None and j.find("parent") is not None}
        link, seen = part, set()
        while link in joints and link not in seen:
            seen.add(link)
            j = joints[link]
            if j.get("type") != "fixed":
                return j.get("name")
            link = j.find("parent").get("link")
        return None
    frames = {f.name: f for f in mech.frames}
    f = frames.get(part)
    while f is not None and f.joint == "fixed":
        f = frames.get(f.antecedent)
    return None if f is None else f.name.removesuffix("__q")


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
    tied = robot.tied_sources
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

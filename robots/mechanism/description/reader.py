"""Reading a mechanism description: a TOML file, or its parsed dict, into a :class:`Mechanism`.

:func:`load_mechanism` reads a file, :func:`mechanism_from_dict` a parsed document; errors name the
field (``docs/mechanisms.md`` is the reference and the tutorial). Every number is SI (m, rad); an
entry may also be an expression (:mod:`evotol.robots.mechanism.description.expressions`) such as ``"-L0/2"``,
``"100*mm"``, ``"q1 - pi"``. A description may take its frames from a URDF (``urdf`` + ``tip``,
:mod:`evotol.robots.mechanism.urdf.reader`). Written values are checked for plausibility
(:mod:`evotol.robots.mechanism.description.plausibility`).

The description itself is :class:`evotol.robots.mechanism.description.mechanism.Mechanism` and its parts
(:mod:`evotol.robots.mechanism.description.parts`: frames, loops, points, coordinates, clearances); they are
importable from here too.
"""
from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path
from typing import Mapping

from evotol.errors import ValidationError
from evotol._runtime.toml_kinds import check_kind
from evotol._runtime.keyword_checks import check_table_keys, expand_patterns
from evotol.robots.clearance.kinematics import DH_FIELDS
from evotol.robots.clearance.parts import BOUND_NAMES, ClearanceBounds
from evotol.robots.mechanism.callouts.table import callouts_from_tables
from evotol.robots.mechanism.description.expressions import Expression
from evotol.robots.mechanism.description.mechanism import Mechanism
from evotol.robots.mechanism.description.parts import AXES, ClearanceChain, ClearanceSpec, Coordinate, Frame, Loop, Point, joint_units
from evotol.robots.mechanism.description.parts import ANGLE_FIELDS, JOINT_TYPES, LENGTH_FIELDS, LOOP_COMPONENTS, UNIT_SCALE  # noqa: F401  (re-exported)
from evotol.robots.mechanism.description.plausibility import check_written_values
from evotol.robots.mechanism.description.reach import reach_coordinates
from evotol.robots.mechanism.description.standard_dh import STANDARD_TOP_KEYS, convention_of, standard_to_modified
from evotol.robots.mechanism.urdf.reader import resolve_urdf, urdf_frames

TOP_KEYS = ("name", "description", "planar", "lengths", "angles", "frame", "point", "loop", "end_effector", "assembly",
            "tolerances", "clearance", "urdf", "tip", "checks", "limits", "callouts") + STANDARD_TOP_KEYS


def _number(v, where: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, str)):
        raise ValidationError(where, v, "a number (SI) or a constant expression such as '100*mm'")
    e = Expression.parse(v, where)
    if not e.is_constant:
        raise ValidationError(where, v, f"a constant (names {sorted(e.names)} are not known here)")
    return float(e({}))


def mechanism_from_dict(spec: Mapping, path: str = "") -> Mechanism:
    """Build a :class:`Mechanism` from a parsed TOML document (dict); errors name the field.

    With ``convention = "standard"`` the rows are a textbook's standard-DH table, rewritten
    exactly in the modified convention (:mod:`evotol.robots.mechanism.description.standard_dh`).

    With a ``urdf`` key the frames, lengths, angles, default sources and joint limits come from
    the URDF chain to ``tip`` (:func:`evotol.robots.mechanism.urdf.reader.urdf_frames`); the table's own
    ``[lengths]``, ``[angles]``, ``[limits]`` override them. Written values are checked for
    plausibility (:mod:`evotol.robots.mechanism.description.plausibility`).

    Parameters
    ----------
    spec : Mapping
        The parsed description (``docs/mechanisms.md``): numbers in SI (m, rad) or expression
        strings.
    path : str, optional
        File the document was read from: names the default mechanism (its stem), resolves a
        relative ``urdf`` path, and checks that the file is a mechanism description and not a
        study; empty (default): built in code.

    Returns
    -------
    Mechanism
        The description.

    Raises
    ------
    evotol.errors.ValidationError
        An unknown key, a missing or malformed table or entry (frames, points, loops,
        end-effector, coordinates, orientation, assembly, limits, clearance), a non-constant
        number where a constant is needed, ``[[frame]]`` rows next to ``urdf`` or a ``urdf``
        without ``tip``, an implausible value (a length beyond ``max_length``, an angle in
        degrees written as radians...), or any check of :class:`Mechanism` and its parts; the
        message names the field.
    """
    if path:
        check_kind(spec, "mechanism", path)     # a study file given as a description (issue 27)
    check_table_keys(spec, TOP_KEYS, "mechanism")
    aliases = {}
    if convention_of(spec) == "standard":       # a textbook's a, alpha, d, theta table (issue 33)
        spec, aliases = standard_to_modified(spec)
    name = spec.get("name") or (Path(path).stem if path else "mechanism")
    lengths = {k: _number(v, f"lengths.{k}") for k, v in dict(spec.get("lengths", {})).items()}
    angles = {k: _number(v, f"angles.{k}") for k, v in dict(spec.get("angles", {})).items()}
    frames = []
    raw_frames = spec.get("frame", [])
    ee_default, sources_default, limits, urdf = None, (), {}, ()
    if "urdf" in spec:                          # a serial arm from URDF (robots/mechanism/urdf/reader.py)
        if raw_frames:
            raise ValidationError("frame", raw_frames, "no [[frame]] rows next to urdf (the URDF gives them)")
        if "tip" not in spec:
            raise ValidationError("tip", None, "the URDF link or frame that is the end-effector, e.g. 'tool0'")
        urdf = (str(resolve_urdf(str(spec["urdf"]), Path(path).parent if path else None)), str(spec["tip"]))
        rows, ul, ua, info = urdf_frames(*urdf)
        raw_frames = rows
        lengths, angles = {**ul, **lengths}, {**ua, **angles}
        ee_default, sources_default, limits = info["tip"], tuple(info["default_sources"]), dict(info["limits"])
    if not isinstance(raw_frames, list) or not raw_frames:
        raise ValidationError("frame", raw_frames, "a list of [[frame]] tables (the modified-DH rows)")
    fkeys = ("name", "antecedent", "joint", "actuated", "description") + DH_FIELDS
    for i, fr in enumerate(raw_frames):
        check_table_keys(fr, fkeys, f"frame[{i}]")
        for k in ("name", "antecedent"):
            if k not in fr:
                raise ValidationError(f"frame[{i}].{k}", None, "a frame name (antecedent '0' is the base)")
        kw = {k: fr[k] for k in DH_FIELDS if k in fr}
        for k, v in kw.items():
            Expression.parse(v, f"frame {fr['name']!r}.{k}")
        frames.append(Frame(str(fr["name"]), str(fr["antecedent"]), fr.get("joint", "fixed"), bool(fr.get("actuated", False)),
                            description=fr.get("description", ""), **kw))
    points = []
    for i, pt in enumerate(spec.get("point", [])):
        check_table_keys(pt, ("name", "mean_of", "description"), f"point[{i}]")
        if "name" not in pt or not isinstance(pt.get("mean_of"), list):
            raise ValidationError(f"point[{i}]", pt, "name and mean_of (a list of frame names)")
        points.append(Point(str(pt["name"]), tuple(map(str, pt["mean_of"])), str(pt.get("description", ""))))
    loops = []
    for i, lp in enumerate(spec.get("loop", [])):
        check_table_keys(lp, ("frames", "components"), f"loop[{i}]")
        fr = lp.get("frames")
        if not isinstance(fr, list) or len(fr) != 2:
            raise ValidationError(f"loop[{i}].frames", fr, "two frame names that coincide (the cut joint)")
        loops.append(Loop(str(fr[0]), str(fr[1]), lp.get("components", "all")))
    ee = spec.get("end_effector", {})
    if not isinstance(ee, Mapping):
        raise ValidationError("end_effector", ee, "a table with frame and coordinates")
    check_table_keys(ee, ("frame", "coordinates", "orientation"), "end_effector")
    coords = []
    for i, c in enumerate(ee.get("coordinates", [])):
        check_table_keys(c, ("name", "axis", "low", "high", "display"), f"end_effector.coordinates[{i}]")
        if "name" not in c or "low" not in c or "high" not in c:
            raise ValidationError(f"end_effector.coordinates[{i}]", c, "name, axis, low and high")
        coords.append(Coordinate(str(c["name"]), c.get("axis", c["name"]), _number(c["low"], f"coordinate {c['name']}.low"),
                                 _number(c["high"], f"coordinate {c['name']}.high"), c.get("display", "")))
    orient = []
    for i, o in enumerate(ee.get("orientation", [])):
        if not (isinstance(o, list) and len(o) == 2 and o[0] in AXES):
            raise ValidationError(f"end_effector.orientation[{i}]", o, "a pair [axis x|y|z, angle expression]")
        Expression.parse(o[1], f"end_effector.orientation[{i}]")
        orient.append((o[0], str(o[1])))
    asm = spec.get("assembly", {})
    check_table_keys(asm, ("pose", "joints"), "assembly")
    if isinstance(asm.get("joints"), Mapping):      # "l?" = "650*mm": a rough guess by pattern (issue 41)
        asm = {**asm, "joints": expand_patterns(asm["joints"], joint_units(frames, set(lengths) | set(angles)),
                                                "assembly.joints", "joint variable")}
        spec = {**spec, "assembly": asm}
    pose = tuple(_number(v, "assembly.pose") for v in asm.get("pose", ()))
    joints = {k: _number(v, f"assembly.joints.{k}") for k, v in dict(asm.get("joints", {})).items()}
    tol = spec.get("tolerances", {})
    check_table_keys(tol, ("sources",), "tolerances")
    clearance = _clearance_from_dict(spec["clearance"]) if "clearance" in spec else None
    check_written_values(spec, joint_units(frames, set(lengths) | set(angles)))    # issue 27: units as written
    limits = {**limits, **_limits(spec.get("limits", {}))}
    task_box = bool(coords)
    if not coords:      # a serial arm posed by its joints: x, y, z over its reach (issue 39 item 4)
        if loops:
            raise ValidationError("end_effector.coordinates", [], "the task coordinates of a closed-loop mechanism "
                                  "(its poses are task poses: [end_effector] coordinates = [...])")
        coords = list(reach_coordinates(frames, {**lengths, **angles}, limits))
    mech = Mechanism(name=str(name), frames=tuple(frames), end_effector=str(ee.get("frame", ee_default or "")), coordinates=tuple(coords),
                     loops=tuple(loops), lengths=lengths, angles=angles, orientation=tuple(orient),
                     planar=bool(spec.get("planar", False)), assembly_pose=pose, assembly_joints=joints,
                     sources=tuple(tol.get("sources", sources_default)), clearance=clearance, description=spec.get("description", ""),
                     path=str(path), points=tuple(points), limits=limits, urdf=urdf,
                     aliases=aliases, task_box=task_box)
    if "callouts" in spec:          # [[callouts]] on joint seats (docs/callouts.md, issue 35)
        mech = dataclasses.replace(mech, callouts=tuple(callouts_from_tables(spec["callouts"], mech, "callouts")))
    return mech


def _limits(table) -> dict:
    """``[limits] q1 = [-pi, pi]``: joint variable -> (lower, upper) in SI (rad, m); issue 23."""
    out = {}
    for k, v in dict(table).items():
        if not (isinstance(v, list) and len(v) == 2):
            raise ValidationError(f"limits.{k}", v, "[lower, upper] of the joint variable (rad or m, e.g. ['-170*deg', '170*deg'])")
        lo, hi = (_number(x, f"limits.{k}") for x in v)
        if not lo <= hi:
            raise ValidationError(f"limits.{k}", v, "lower <= upper")
        out[str(k)] = (lo, hi)
    return out


def _bounds(b, where: str) -> ClearanceBounds:
    check_table_keys(b, BOUND_NAMES, where)
    missing = [k for k in BOUND_NAMES if k not in b]
    if missing:
        raise ValidationError(f"{where}.{missing[0]}", None, f"all of {BOUND_NAMES} (rad, rad, m, m)")
    return ClearanceBounds(*(_number(b[k], f"{where}.{k}") for k in BOUND_NAMES))


def _clearance_from_dict(c: Mapping) -> ClearanceSpec:
    check_table_keys(c, ("bodies", "chain", "end_effector", "bounds"), "clearance")
    chains = []
    for i, ch in enumerate(c.get("chain", [])):
        check_table_keys(ch, ("name", "start", "end", "joints", "path_end"), f"clearance.chain[{i}]")
        for k in ("name", "start", "end", "joints"):
            if k not in ch:
                raise ValidationError(f"clearance.chain[{i}].{k}", None, "name, start and end bodies, joints (frame names)")
        chains.append(ClearanceChain(str(ch["name"]), str(ch["start"]), str(ch["end"]), tuple(map(str, ch["joints"])),
                                     ch.get("path_end")))
    if not chains:
        raise ValidationError("clearance.chain", [], "at least one [[clearance.chain]]")
    bounds = {k: _bounds(v, f"clearance.bounds.{k}") for k, v in dict(c.get("bounds", {})).items()}
    bodies = {str(k): str(v) for k, v in dict(c.get("bodies", {})).items()}
    return ClearanceSpec(bodies=bodies, chains=tuple(chains), end_effector=str(c.get("end_effector", next(iter(bodies), ""))),
                         bounds=bounds)


def load_mechanism(path) -> Mechanism:
    """Read a mechanism description file (TOML); errors name the file and the field.

    Parameters
    ----------
    path : str or Path
        The TOML file.

    Returns
    -------
    Mechanism
        The description (:func:`mechanism_from_dict`), with ``path`` set.

    Raises
    ------
    evotol.errors.ValidationError
        No such file, invalid TOML, or a mistake in the description (names the field).
    """
    p = Path(path)
    if not p.is_file():
        raise ValidationError("mechanism file", str(p), "an existing TOML file")
    try:
        spec = tomllib.loads(p.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ValidationError("mechanism file", str(p), f"valid TOML ({exc})") from None
    return mechanism_from_dict(spec, path=str(p))

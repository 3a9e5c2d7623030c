"""A mechanism described as data: modified-DH frames, loops, end-effector, tolerances, clearances.

The description is plain frozen dataclasses (:class:`Mechanism` and its parts); a TOML file with
the same fields is read by :func:`load_mechanism` (``docs/mechanisms.md`` is the reference and the
tutorial). Every number is SI (m, rad); an entry may also be an expression
(:mod:`robots.mechanism.expressions`) such as ``"-L0/2"``, ``"100*mm"``, ``"q1 - pi"``.

Frames follow Khalil & Kleinfinger (1986), the convention of Deng 2012 Tabs. II.1, IV.1 and of
Brahmia 2023 Tab. 1: frame ``j`` with antecedent ``a(j)`` is placed by
``Rot(z, gamma) Trans(z, b) Rot(x, alpha) Trans(x, d) Rot(z, theta) Trans(z, r)``; a revolute
joint turns about its ``z`` axis (``theta`` holds its variable), a prismatic joint slides along it
(``r`` holds its variable), a ``fixed`` frame is a rigid offset. Universal and spherical joints
are two or three revolute frames with concurrent axes (``d = r = 0``).

A closed mechanism is a tree of frames plus **loops**: pairs of frames that must coincide (the cut
joints). The **end-effector** is a frame; its pose coordinates (a subset of ``x, y, z`` of its
origin in the base frame, optionally a target orientation) define the workspace box.

A **point** is the mean of several frames' origins (``[[point]] name = "P1", mean_of = ["E1",
"E1b"]``), with the orientation of its first frame. It stands where a frame may stand in a
position loop or as a position-only end-effector: the least-squares closure of an
over-constrained sub-chain, e.g. Brahmia 2023's Delta, whose leg ends at the midpoint of its two
parallelogram rods.
"""
from __future__ import annotations

import fnmatch
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from evotol.errors import ValidationError
from evotol.filekinds import check_kind
from evotol.keywords import check_table_keys
from robots.clearance.kinematics import DH_FIELDS
from robots.clearance.parts import BOUND_NAMES, Chain, ClearanceBounds
from robots.mechanism.expressions import CONSTANTS, FUNCTIONS, Expression
from robots.mechanism.placement import PLACEMENT_FIELDS
from robots.mechanism.plausibility import check_workspace, check_written_values
from robots.mechanism.urdf import resolve_urdf, urdf_frames

JOINT_TYPES = ("revolute", "prismatic", "fixed")
LENGTH_FIELDS = ("b", "d", "r")
ANGLE_FIELDS = ("gamma", "alpha", "theta")
AXES = ("x", "y", "z")
LOOP_COMPONENTS = ("all", "position")
UNIT_SCALE = {"m": 1.0, "mm": 1e-3, "rad": 1.0, "deg": np.pi / 180}


@dataclass(frozen=True)
class Frame:
    """One row of the modified-DH (Khalil-Kleinfinger) table. Entries: numbers (m, rad) or
    expression strings. ``joint``: revolute / prismatic / fixed; ``actuated``: a motor drives it.

    Parameters
    ----------
    name : str
        Frame name: non-empty, without ``.``, not ``"0"`` (the base).
    antecedent : str
        Name of the frame ``a(j)`` it is placed from (``"0"``: the base).
    joint : {"fixed", "revolute", "prismatic"}, optional
        Joint between the antecedent and this frame (default ``"fixed"``, a rigid offset).
    actuated : bool, optional
        A motor drives the joint (its variable is held in the inverse geometry); not for a fixed
        frame.
    gamma, b, alpha, d, theta, r : float or str, optional
        The modified-DH entries of ``Rot(z, gamma) Trans(z, b) Rot(x, alpha) Trans(x, d)
        Rot(z, theta) Trans(z, r)``: ``gamma``, ``alpha``, ``theta`` in rad, ``b``, ``d``, ``r`` in m;
        numbers or expression strings (``"-L0/2"``, ``"q1 - pi"``); default 0. ``theta`` holds a
        revolute joint's variable, ``r`` a prismatic one's.
    description : str, optional
        One line for reports.

    Raises
    ------
    evotol.errors.ValidationError
        An empty name or one with ``.``, an unknown joint type, or an actuated fixed frame.
    """

    name: str
    antecedent: str
    joint: str = "fixed"
    actuated: bool = False
    gamma: float | str = 0.0
    b: float | str = 0.0
    alpha: float | str = 0.0
    d: float | str = 0.0
    theta: float | str = 0.0
    r: float | str = 0.0
    description: str = ""

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name or "." in self.name:
            raise ValidationError("frame.name", self.name, "a non-empty name without '.'")
        if self.joint not in JOINT_TYPES:
            raise ValidationError(f"frame {self.name!r}.joint", self.joint, f"one of {JOINT_TYPES}")
        if self.actuated and self.joint == "fixed":
            raise ValidationError(f"frame {self.name!r}.actuated", True, "false for a fixed frame (only joints are actuated)")

    @property
    def joint_field(self) -> str | None:
        """DH entry holding the joint variable: ``"theta"`` (revolute), ``"r"`` (prismatic), None (fixed)."""
        return {"revolute": "theta", "prismatic": "r"}.get(self.joint)

    @property
    def sigma(self) -> int:
        """Joint type index (Khalil-Kleinfinger sigma): 0 revolute, 1 prismatic, 2 fixed."""
        return JOINT_TYPES.index(self.joint)


@dataclass(frozen=True)
class Loop:
    """A cut joint: frames ``a`` and ``b`` coincide (``components="all"``: pose, 6 equations; or
    ``"position"``: only their origins, 3 equations -- a spherical cut joint). In a planar
    mechanism only the in-plane components (x, y, rotation about z) are used.

    Parameters
    ----------
    a, b : str
        Names of the two frames (or, for ``"position"``, points) that coincide.
    components : {"all", "position"}, optional
        ``"all"`` (default): the whole pose; ``"position"``: only the origins.

    Raises
    ------
    evotol.errors.ValidationError
        Another ``components``.
    """

    a: str
    b: str
    components: str = "all"

    def __post_init__(self):
        if self.components not in LOOP_COMPONENTS:
            raise ValidationError(f"loop {self.a}-{self.b}.components", self.components, f"one of {LOOP_COMPONENTS}")


@dataclass(frozen=True)
class Point:
    """The mean of the origins of ``frames`` (m), oriented like ``frames[0]``: usable in position
    loops and as a position-only end-effector (see the module docstring).

    Parameters
    ----------
    name : str
        Point name: non-empty, without ``.``.
    frames : tuple of str
        Two or more different frame names whose origins are averaged (``mean_of`` in TOML).
    description : str, optional
        One line for reports.

    Raises
    ------
    evotol.errors.ValidationError
        An empty name or one with ``.``, or fewer than two different frames.
    """

    name: str
    frames: tuple[str, ...]
    description: str = ""

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name or "." in self.name:
            raise ValidationError("point.name", self.name, "a non-empty name without '.'")
        if len(self.frames) < 2 or len(set(self.frames)) != len(self.frames):
            raise ValidationError(f"point {self.name!r}.mean_of", list(self.frames), "two or more different frame names")


@dataclass(frozen=True)
class Coordinate:
    """A pose coordinate: ``axis`` x/y/z of the end-effector origin in the base frame (m), or
    ``"angle"`` (rad; used only in the end-effector's target ``orientation``). ``low, high``: the
    workspace box in SI; ``display``: the unit shown in reports (mm, deg).

    Parameters
    ----------
    name : str
        Coordinate name (e.g. ``"x"``, ``"phi"``).
    axis : {"x", "y", "z", "angle"}
        Base axis of the end-effector origin's coordinate (m), or ``"angle"`` (rad).
    low, high : float
        Workspace range, SI (m, or rad for an angle); finite, ``low <= high``.
    display : {"", "m", "mm", "rad", "deg"}, optional
        Unit shown in reports; empty (default): the SI unit.

    Raises
    ------
    evotol.errors.ValidationError
        An unknown axis or display unit, or a range that is not finite with ``low <= high``.
    """

    name: str
    axis: str
    low: float
    high: float
    display: str = ""

    def __post_init__(self):
        if self.axis not in AXES + ("angle",):
            raise ValidationError(f"coordinate {self.name!r}.axis", self.axis, "x, y, z or angle")
        if not (np.isfinite(self.low) and np.isfinite(self.high) and self.low <= self.high):
            raise ValidationError(f"coordinate {self.name!r} range", (self.low, self.high), "finite low <= high (SI units)")
        if self.display and self.display not in UNIT_SCALE:
            raise ValidationError(f"coordinate {self.name!r}.display", self.display, f"one of {sorted(UNIT_SCALE)}")

    @property
    def unit(self) -> str:
        """SI unit of the coordinate: ``"rad"`` for an angle, else ``"m"``."""
        return "rad" if self.axis == "angle" else "m"


#: a serial chain of joints with clearance between two bodies (Deng 2012 Ch. III, V): the engine's
#: own :class:`robots.clearance.parts.Chain`, built directly from the description
ClearanceChain = Chain


@dataclass(frozen=True)
class ClearanceSpec:
    """Joint clearances: bodies (name -> frame), chains, and the bounds of each joint (by joint frame
    name; ``default`` / ``actuated`` / ``passive`` apply to the rest).

    Parameters
    ----------
    bodies : Mapping[str, str]
        Body name -> the DH frame it is attached to.
    chains : tuple of robots.clearance.parts.Chain
        Serial chains of joints with clearance between bodies (Deng 2012 Ch. III, V).
    end_effector : str
        Name of the end-effector body.
    bounds : Mapping[str, robots.clearance.parts.ClearanceBounds]
        Joint frame name, or ``default`` / ``actuated`` / ``passive`` -> clearance bounds
        (``beta_xy``, ``beta_z`` in rad; ``b_xy``, ``b_z`` in m).
    """

    bodies: Mapping[str, str]
    chains: tuple[ClearanceChain, ...]
    end_effector: str
    bounds: Mapping[str, ClearanceBounds]


@dataclass(frozen=True)
class Mechanism:
    """A whole description (see the module docstring).

    Parameters
    ----------
    name : str
        Mechanism name (reports, messages).
    frames : tuple of Frame
        The modified-DH rows; unique names, each antecedent ``"0"`` or one of them.
    end_effector : str
        Name of the end-effector frame or point.
    coordinates : tuple of Coordinate
        Pose coordinates of the workspace box; at least one of axis x, y, z.
    loops : tuple of Loop, optional
        Cut joints closing the tree (default: none, an open chain).
    lengths : Mapping[str, float], optional
        Design lengths by name (m).
    angles : Mapping[str, float], optional
        Design angles by name (rad); names distinct from ``lengths`` and from the expression
        functions and constants.
    orientation : tuple of (str, str), optional
        Target orientation of the end-effector: ``(axis, angle expression)`` pairs, a product
        of rotations about base axes (e.g. ``(("z", "phi"),)``); empty: the mechanism decides it.
    planar : bool, optional
        Planar mechanism: only in-plane components (x, y, rotation about z) are used.
    assembly_pose : tuple of float, optional
        Pose (SI, one value per coordinate) of the assembly configuration; empty: the middle of
        the box.
    assembly_joints : Mapping[str, float], optional
        Joint variable -> its value (rad or m) at the assembly pose, Newton's starting point.
    sources : tuple of str, optional
        Source names or fnmatch patterns of ``[tolerances]`` (see :meth:`select_sources`).
    clearance : ClearanceSpec or None, optional
        Joint clearances, if the description has a ``[clearance]`` table.
    description : str, optional
        Free text.
    path : str, optional
        The file the description was read from (empty if built in code).
    points : tuple of Point, optional
        Mean points of frames' origins, usable in position loops and as end-effector.
    limits : Mapping[str, tuple of (float, float)], optional
        Joint variable -> (lower, upper), SI (rad or m).
    urdf : tuple of str, optional
        ``(resolved URDF path, tip frame)`` of a description read from a URDF; empty otherwise.

    Raises
    ------
    evotol.errors.ValidationError
        Duplicate frame names or a frame named ``"0"``, an unknown antecedent, a bad point or
        loop (unknown frame, a point in a loop that is not ``"position"``), an unknown
        end-effector or an orientation for a point end-effector, no x/y/z coordinate, a
        parameter name that clashes with a constant, a function or the other table, an
        ``assembly_pose`` of the wrong length, or a workspace coordinate that moves nothing
        (:func:`robots.mechanism.plausibility.check_workspace`).
    """

    name: str
    frames: tuple[Frame, ...]
    end_effector: str
    coordinates: tuple[Coordinate, ...]
    loops: tuple[Loop, ...] = ()
    lengths: Mapping[str, float] = field(default_factory=dict)
    angles: Mapping[str, float] = field(default_factory=dict)
    orientation: tuple[tuple[str, str], ...] = ()
    planar: bool = False
    assembly_pose: tuple[float, ...] = ()
    assembly_joints: Mapping[str, float] = field(default_factory=dict)
    sources: tuple[str, ...] = ()
    clearance: ClearanceSpec | None = None
    description: str = ""
    path: str = ""
    points: tuple[Point, ...] = ()
    limits: Mapping[str, tuple[float, float]] = field(default_factory=dict)   # joint variable -> (lower, upper), SI
    urdf: tuple[str, ...] = ()        # (resolved URDF path, tip frame) of a description read from a URDF

    def __post_init__(self):
        names = [f.name for f in self.frames]
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise ValidationError("frame.name", dup[0], "unique frame names")
        if "0" in names:
            raise ValidationError("frame.name", "0", "a name other than '0' (the base frame)")
        known = set(names) | {"0"}
        for f in self.frames:
            if f.antecedent not in known:
                raise ValidationError(f"frame {f.name!r}.antecedent", f.antecedent, f"'0' (the base) or a frame of the table: {names}")
        points = [p.name for p in self.points]
        for p in self.points:
            if p.name in known or points.count(p.name) > 1:
                raise ValidationError("point.name", p.name, "a name used by no frame and no other point")
            for x in p.frames:
                if x not in names:
                    raise ValidationError(f"point {p.name!r}.mean_of", x, f"a frame of the table: {names}")
        for lp in self.loops:
            for x in (lp.a, lp.b):
                if x not in known and x not in points:
                    raise ValidationError(f"loop {lp.a}-{lp.b}", x, f"a frame of the table: {names}" + (f" or a point {points}" if points else ""))
                if x in points and lp.components != "position":
                    raise ValidationError(f"loop {lp.a}-{lp.b}.components", lp.components, f"'position' (point {x!r} has no orientation of its own)")
        if self.end_effector not in names and self.end_effector not in points:
            raise ValidationError("end_effector.frame", self.end_effector, f"a frame of the table: {names}" + (f" or a point {points}" if points else ""))
        if self.end_effector in points and self.orientation:
            raise ValidationError("end_effector.orientation", self.orientation, f"none for the point {self.end_effector!r} (position only)")
        if not self.coordinates or not any(c.axis in AXES for c in self.coordinates):
            raise ValidationError("end_effector.coordinates", self.coordinates, "at least one of x, y, z")
        params = set(self.lengths) | set(self.angles)
        clash = params & (set(CONSTANTS) | set(FUNCTIONS))
        if clash:
            raise ValidationError("parameter name", sorted(clash)[0], f"a name other than {sorted(CONSTANTS) + sorted(FUNCTIONS)}")
        if set(self.lengths) & set(self.angles):
            raise ValidationError("parameter name", sorted(set(self.lengths) & set(self.angles))[0], "in [lengths] or [angles], not both")
        if self.assembly_pose and len(self.assembly_pose) != len(self.coordinates):
            raise ValidationError("assembly.pose", self.assembly_pose, f"{len(self.coordinates)} numbers, one per coordinate")
        check_workspace(self.coordinates, self.orientation, self.planar)       # issue 27: a coordinate moves something

    # ------------------------------------------------------------------ names
    @property
    def parameters(self) -> dict[str, float]:
        """Every design parameter by name: ``lengths`` (m) then ``angles`` (rad)."""
        return {**self.lengths, **self.angles}

    @property
    def frame(self) -> dict[str, Frame]:
        """The frames by name."""
        return {f.name: f for f in self.frames}

    def entry_names(self) -> list[str]:
        """Every DH entry as ``"<frame>.<entry>"`` (e.g. ``"A.theta"``, ``"C.d"``), then every
        placement error ``"<frame>.shift_x"`` ... ``"<frame>.tilt_z"`` (:mod:`robots.mechanism.placement`).

        Returns
        -------
        list of str
            Per frame in table order: its six DH entries (``gamma b alpha d theta r``), then its
            six placement errors.
        """
        return [f"{f.name}.{k}" for f in self.frames for k in DH_FIELDS + PLACEMENT_FIELDS]

    def candidate_sources(self, actuated: Sequence[str] = ()) -> list[str]:
        """Names a tolerance may be put on: design parameters, actuated joint variables (actuator
        offsets), then every DH entry.

        Parameters
        ----------
        actuated : sequence of str, optional
            The actuated joint variables (their names are actuator-offset sources).

        Returns
        -------
        list of str
            ``lengths``, ``angles``, ``actuated``, then :meth:`entry_names` (with the placement
            errors), in that order.
        """
        return list(self.lengths) + list(self.angles) + list(actuated) + self.entry_names()

    def select_sources(self, patterns: Sequence[str] | None = None, actuated: Sequence[str] = ()) -> list[str]:
        """Source names matching ``patterns`` (fnmatch: ``"*.d"``, ``"A*.theta"``, ``"L?"``), in
        candidate order. A pattern that matches nothing is an error (a typo would silently drop a
        tolerance otherwise).

        Parameters
        ----------
        patterns : sequence of str or None, optional
            Names or fnmatch patterns; None (default): the description's ``sources``.
        actuated : sequence of str, optional
            The actuated joint variables (candidates too, see :meth:`candidate_sources`).

        Returns
        -------
        list of str
            The matching candidates without repeats, pattern by pattern, each pattern's matches
            in candidate order.

        Raises
        ------
        evotol.errors.ValidationError
            A pattern that is not a string, or that matches no candidate (the message lists the
            kinds of valid names).
        """
        patterns = list(self.sources if patterns is None else patterns)
        cands = self.candidate_sources(actuated)
        out = []
        for p in patterns:
            if not isinstance(p, str):
                raise ValidationError("tolerances.sources", p, "a name or pattern string")
            hit = [c for c in cands if fnmatch.fnmatchcase(c, p)]
            if not hit:
                raise ValidationError("tolerances.sources", p, f"a parameter ({sorted(self.parameters)}), an actuated joint variable {list(actuated)}, a DH entry "
                                                                f"'<frame>.<gamma|b|alpha|d|theta|r>' or a placement error '<frame>.<shift|tilt>_<x|y|z>' "
                                                                f"of frames {[f.name for f in self.frames]}")
            out += [h for h in hit if h not in out]
        return out


# ---------------------------------------------------------------------------------------- TOML
TOP_KEYS = ("name", "description", "planar", "lengths", "angles", "frame", "point", "loop", "end_effector", "assembly",
            "tolerances", "clearance", "urdf", "tip", "checks", "limits")


def _number(v, where: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, str)):
        raise ValidationError(where, v, "a number (SI) or a constant expression such as '100*mm'")
    e = Expression.parse(v, where)
    if not e.is_constant:
        raise ValidationError(where, v, f"a constant (names {sorted(e.names)} are not known here)")
    return float(e({}))


def mechanism_from_dict(spec: Mapping, path: str = "") -> Mechanism:
    """Build a :class:`Mechanism` from a parsed TOML document (dict); errors name the field.

    With a ``urdf`` key the frames, lengths, angles, default sources and joint limits come from
    the URDF chain to ``tip`` (:func:`robots.mechanism.urdf.urdf_frames`); the table's own
    ``[lengths]``, ``[angles]``, ``[limits]`` override them. Written values are checked for
    plausibility (:mod:`robots.mechanism.plausibility`).

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
    name = spec.get("name") or (Path(path).stem if path else "mechanism")
    lengths = {k: _number(v, f"lengths.{k}") for k, v in dict(spec.get("lengths", {})).items()}
    angles = {k: _number(v, f"angles.{k}") for k, v in dict(spec.get("angles", {})).items()}
    frames = []
    raw_frames = spec.get("frame", [])
    ee_default, sources_default, limits, urdf = None, (), {}, ()
    if "urdf" in spec:                          # a serial arm from URDF (robots/mechanism/urdf.py)
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
    ee = spec.get("end_effector")
    if ee is None:
        raise ValidationError("end_effector", None, "a table with frame and coordinates")
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
    pose = tuple(_number(v, "assembly.pose") for v in asm.get("pose", ()))
    joints = {k: _number(v, f"assembly.joints.{k}") for k, v in dict(asm.get("joints", {})).items()}
    tol = spec.get("tolerances", {})
    check_table_keys(tol, ("sources",), "tolerances")
    clearance = _clearance_from_dict(spec["clearance"]) if "clearance" in spec else None
    check_written_values(spec, joint_units(frames, set(lengths) | set(angles)))    # issue 27: units as written
    mech = Mechanism(name=str(name), frames=tuple(frames), end_effector=str(ee.get("frame", ee_default or "")), coordinates=tuple(coords),
                     loops=tuple(loops), lengths=lengths, angles=angles, orientation=tuple(orient),
                     planar=bool(spec.get("planar", False)), assembly_pose=pose, assembly_joints=joints,
                     sources=tuple(tol.get("sources", sources_default)), clearance=clearance, description=spec.get("description", ""),
                     path=str(path), points=tuple(points), limits={**limits, **_limits(spec.get("limits", {}))}, urdf=urdf)
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


def joint_units(frames, params) -> dict[str, str]:
    """Joint variable -> "m" (in the r of a prismatic frame) or "rad" (in the theta of a revolute one).

    Parameters
    ----------
    frames : iterable of Frame
        The DH rows.
    params : set of str
        Design parameter names (not joint variables, even when they appear in ``theta``/``r``).

    Returns
    -------
    dict of str to str
        Every name in a joint entry that is not a parameter -> its unit; the first frame using a
        name decides.

    Raises
    ------
    evotol.errors.ValidationError
        A joint entry that does not parse (:meth:`Expression.parse
        <robots.mechanism.expressions.Expression.parse>`).
    """
    out = {}
    for f in frames:
        if f.joint_field:
            for x in Expression.parse(getattr(f, f.joint_field), f"frame {f.name!r}.{f.joint_field}").names - params:
                out.setdefault(x, "m" if f.joint == "prismatic" else "rad")
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

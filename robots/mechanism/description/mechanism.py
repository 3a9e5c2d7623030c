"""A whole mechanism description: the tree of frames, its loops, end-effector, parameters and sources.

:class:`Mechanism` holds the parts (:mod:`evotol.robots.mechanism.description.parts`) and checks that they fit
together. A closed mechanism is a tree of frames plus **loops**: pairs of frames that must coincide
(the cut joints). The **end-effector** is a frame or a point; its pose coordinates (a subset of
``x, y, z`` of its origin in the base frame, optionally a target orientation) define the workspace
box. The names a tolerance may be put on (design parameters, actuator offsets, DH entries,
placement errors) are listed and selected here (:meth:`Mechanism.select_sources`).
A TOML file with the same fields is read by :func:`evotol.robots.mechanism.description.reader.load_mechanism`
(``docs/mechanisms.md`` is the reference and the tutorial); every number is SI (m, rad).
"""
from __future__ import annotations

import fnmatch
from dataclasses import dataclass, field
from typing import Mapping, Sequence

from evotol.errors import ValidationError
from evotol.robots.clearance.kinematics import DH_FIELDS
from evotol.robots.mechanism.description.expressions import CONSTANTS, FUNCTIONS
from evotol.robots.mechanism.description.parts import AXES, ClearanceSpec, Coordinate, Frame, Loop, Point
from evotol.robots.mechanism.kinematics.placement import PLACEMENT_FIELDS
from evotol.robots.mechanism.description.plausibility import check_workspace


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
    callouts : tuple of evotol.robots.mechanism.callouts.zones.Callout, optional
        Drawing callouts on joint seats (``[[callouts]]``, ``docs/callouts.md``); the error model
        with them is :class:`evotol.robots.mechanism.callouts.model.CalloutModel`.
    aliases : Mapping[str, str], optional
        Source name -> design parameter it tolerances, for names a parameter cannot have (a
        standard-DH description's ``base.d`` -> ``base_d``, :mod:`evotol.robots.mechanism.description.standard_dh`);
        the parameter is then listed under its alias only.
    task_box : bool, optional
        True (default) when ``coordinates`` are a task box the file states; False for a serial arm
        described without one (x, y, z over its reach,
        :mod:`evotol.robots.mechanism.description.reach`).

    Raises
    ------
    evotol.errors.ValidationError
        Duplicate frame names or a frame named ``"0"``, an unknown antecedent, a bad point or
        loop (unknown frame, a point in a loop that is not ``"position"``), an unknown
        end-effector or an orientation for a point end-effector, no x/y/z coordinate, a
        parameter name that clashes with a constant, a function or the other table, an
        ``assembly_pose`` of the wrong length, or a workspace coordinate that moves nothing
        (:func:`evotol.robots.mechanism.description.plausibility.check_workspace`).
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
    callouts: tuple = ()              # drawing callouts on joint seats (evotol.robots.mechanism.callouts.zones, issue 35)
    aliases: Mapping[str, str] = field(default_factory=dict)    # source name -> parameter (standard DH: base.d)
    task_box: bool = True             # False: no [end_effector] coordinates; x, y, z over the reach (description/reach.py)

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
        placement error ``"<frame>.shift_x"`` ... ``"<frame>.tilt_z"`` (:mod:`evotol.robots.mechanism.kinematics.placement`).

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
        hidden = set(self.aliases.values())
        params = [p for p in (*self.lengths, *self.angles) if p not in hidden]
        # a standard-DH [base]/[tool] is named by its textbook entries (base.d = d_B); the modified
        # entries of its frame (base.d there would be a_B) are hidden, its placement errors kept
        aliased = {a.split(".")[0] for a in self.aliases}
        entries = [e for e in self.entry_names() if not (e.split(".")[0] in aliased and e.split(".")[1] in DH_FIELDS)]
        return params + list(self.aliases) + list(actuated) + entries

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
            out += [h for h in dict.fromkeys(hit) if h not in out]
        return out

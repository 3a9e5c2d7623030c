"""The parts of a mechanism description: modified-DH frame rows, loops, points, pose coordinates,
clearances.

Plain frozen dataclasses that check themselves; the whole description that holds them is
:class:`evotol.robots.mechanism.description.mechanism.Mechanism`, read from TOML by :mod:`evotol.robots.mechanism.description.reader`
(``docs/mechanisms.md`` is the reference). Every number is SI (m, rad); an entry may also be an
expression (:mod:`evotol.robots.mechanism.description.expressions`) such as ``"-L0/2"``, ``"100*mm"``, ``"q1 - pi"``.

Frames follow Khalil & Kleinfinger (1986), the convention of Deng 2012 Tabs. II.1, IV.1 and of
Brahmia 2023 Tab. 1: frame ``j`` with antecedent ``a(j)`` is placed by
``Rot(z, gamma) Trans(z, b) Rot(x, alpha) Trans(x, d) Rot(z, theta) Trans(z, r)``; a revolute
joint turns about its ``z`` axis (``theta`` holds its variable), a prismatic joint slides along it
(``r`` holds its variable), a ``fixed`` frame is a rigid offset. Universal and spherical joints
are two or three revolute frames with concurrent axes (``d = r = 0``).

A **loop** is a pair of frames that must coincide (a cut joint). A **point** is the mean of
several frames' origins (``[[point]] name = "P1", mean_of = ["E1", "E1b"]``), with the
orientation of its first frame. It stands where a frame may stand in a position loop or as a
position-only end-effector: the least-squares closure of an over-constrained sub-chain, e.g.
Brahmia 2023's Delta, whose leg ends at the midpoint of its two parallelogram rods. A
**coordinate** is one axis of the end-effector pose and its workspace range.

The parameters several definitions of this module share are described once, here.

Parameters
----------
description : str, optional
    One line for reports.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.clearance.parts import Chain, ClearanceBounds
from evotol.robots.mechanism.description.expressions import Expression

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
#: own :class:`evotol.robots.clearance.parts.Chain`, built directly from the description
ClearanceChain = Chain


@dataclass(frozen=True)
class ClearanceSpec:
    """Joint clearances: bodies (name -> frame), chains, and the bounds of each joint (by joint frame
    name; ``default`` / ``actuated`` / ``passive`` apply to the rest).

    Parameters
    ----------
    bodies : Mapping[str, str]
        Body name -> the DH frame it is attached to.
    chains : tuple of evotol.robots.clearance.parts.Chain
        Serial chains of joints with clearance between bodies (Deng 2012 Ch. III, V).
    end_effector : str
        Name of the end-effector body.
    bounds : Mapping[str, evotol.robots.clearance.parts.ClearanceBounds]
        Joint frame name, or ``default`` / ``actuated`` / ``passive`` -> clearance bounds
        (``beta_xy``, ``beta_z`` in rad; ``b_xy``, ``b_z`` in m).
    """

    bodies: Mapping[str, str]
    chains: tuple[ClearanceChain, ...]
    end_effector: str
    bounds: Mapping[str, ClearanceBounds]


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
        <evotol.robots.mechanism.description.expressions.Expression.parse>`).
    """
    out = {}
    for f in frames:
        if f.joint_field:
            for x in Expression.parse(getattr(f, f.joint_field), f"frame {f.name!r}.{f.joint_field}").names - params:
                out.setdefault(x, "m" if f.joint == "prismatic" else "rad")
    return out

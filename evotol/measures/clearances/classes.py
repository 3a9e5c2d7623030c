"""Clearance classes: the joint clearances allocated as tolerances (Deng 2012 Sec. VII.1 stated as an
optimisation; issue 12 item 5), their set on a mechanism, and the ``[clearances]`` table of a study
file. The certified worst case of clearances and geometric sources together is in
:mod:`evotol.measures.clearances.certified`.

A **clearance class** is one tolerance t (SI) that sets some clearance bounds of some joints,
each as ``factor * t``: the thesis's radial clearance of joint A, ``Δb_xy = t`` with its tilt
``Δβ_xy = t / h`` (eq. III.2), is ``ClearanceClass("bxy_A", ("A",), {"b_xy": 1, "beta_xy": 1/h})``;
one class may cover several joints (one fit for all passive joints). Bounds no class covers keep
the mechanism's own values (e.g. the passive joints' idle rotation Δβ_z = 0.2 rad).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from evotol.errors import ValidationError
from evotol._runtime.keyword_checks import check_table_keys
from evotol.robots.base import SourceSpec
from evotol.robots.clearance.model import ClearanceMechanism

#: clearance bound components, in the engine's column order (Deng 2012 eqs. III.3-III.6)
COMPONENTS = ("beta_xy", "beta_z", "b_xy", "b_z")


@dataclass(frozen=True)
class ClearanceClass:
    """One allocated clearance tolerance (see the module docstring).

    Parameters
    ----------
    name : str
        The tolerance's name (a source name of the problem).
    joints : str or sequence of str
        Names of the clearance mechanism's joints it sets.
    bounds : Mapping[str, float]
        Component (``beta_xy``, ``beta_z``, ``b_xy``, ``b_z``) -> factor; the bound is
        ``factor * t`` (rad for ``beta_*``, m for ``b_*``).
    unit : {"m", "rad"} or None
        Unit of t (default: m if a ``b_*`` component has factor 1, else rad).
    group : str
        The cost-model group (default ``"clearance"``).
    description : str
        One line for reports (default: the bounds and joints).

    Raises
    ------
    evotol.errors.ValidationError
        No joint, empty bounds, an unknown component, a factor that is not positive, or a
        ``unit`` other than ``"m"``, ``"rad"``.

    Examples
    --------
    >>> from evotol import ClearanceClass
    >>> radial = ClearanceClass("radial", ("A", "C"), {"b_xy": 1.0})   # one radial play for joints A, C
    >>> radial.name, radial.joints
    ('radial', ('A', 'C'))
    """

    name: str
    joints: tuple[str, ...]
    bounds: Mapping[str, float]
    unit: str | None = None
    group: str = "clearance"
    description: str = ""

    def __post_init__(self):
        if isinstance(self.joints, str):
            object.__setattr__(self, "joints", (self.joints,))
        object.__setattr__(self, "joints", tuple(self.joints))
        f0 = f"clearance class {self.name!r}"
        if not self.joints:
            raise ValidationError(f"{f0}.joints", self.joints, "at least one joint name")
        if not isinstance(self.bounds, Mapping) or not self.bounds:
            raise ValidationError(f"{f0}.bounds", self.bounds, f"a mapping component -> factor, components {COMPONENTS}")
        for k, v in self.bounds.items():
            if k not in COMPONENTS:
                raise ValidationError(f"{f0}.bounds.{k}", k, f"one of {COMPONENTS}")
            if not isinstance(v, (int, float, np.floating)) or not np.isfinite(v) or v <= 0:
                raise ValidationError(f"{f0}.bounds.{k}", v, "a positive factor (bound = factor * tolerance)")
        if self.unit is None:
            unit = "m" if any(k.startswith("b_") and float(v) == 1.0 for k, v in self.bounds.items()) else "rad"
            object.__setattr__(self, "unit", unit)
        if self.unit not in ("m", "rad"):
            raise ValidationError(f"{f0}.unit", self.unit, "'m' or 'rad'")

    @property
    def source(self) -> SourceSpec:
        """The class as a one-dimensional source of the problem (name, unit m or rad, group, description)."""
        d = self.description or (", ".join(f"{k} = {v:g} t" for k, v in self.bounds.items())
                                 + f" of joint{'s' if len(self.joints) > 1 else ''} {', '.join(self.joints)}")
        return SourceSpec(self.name, 1, self.unit, self.group, d)


def thesis_classes(joints: Sequence[str], h: float, axial: bool = True) -> list[ClearanceClass]:
    """Deng 2012 Sec. VII.1.1: per joint a radial class ``bxy_<J>`` (Δb_xy = t, Δβ_xy = t / h,
    eq. III.2; h: joint length, m) and, with ``axial``, an axial class ``bz_<J>`` (Δb_z = t).

    Parameters
    ----------
    joints : sequence of str
        Names of the joints with clearance.
    h : float
        Joint length (m): the radial tilt bound is Δβ_xy = t / h (rad).
    axial : bool
        Whether to add an axial class per joint.

    Returns
    -------
    list of ClearanceClass
        The radial classes (one per joint, unit m), then the axial ones.

    Raises
    ------
    evotol.errors.ValidationError
        If ``h`` is not a positive number (or a class is invalid, e.g. no joints).
    """
    if not (isinstance(h, (int, float, np.floating)) and h > 0):
        raise ValidationError("h", h, "a positive joint length (m)")
    out = [ClearanceClass(f"bxy_{j}", (j,), {"b_xy": 1.0, "beta_xy": 1.0 / h}, "m",
                          description=f"radial clearance of joint {j} (Δb_xy = t, Δβ_xy = t/h, h = {h:g} m)")
           for j in joints]
    if axial:
        out += [ClearanceClass(f"bz_{j}", (j,), {"b_z": 1.0}, "m", description=f"axial clearance of joint {j} (Δb_z = t)")
                for j in joints]
    return out


@dataclass
class ClearanceSources:
    """Clearance classes of a clearance mechanism (:class:`evotol.robots.clearance.ClearanceMechanism`).

    Parameters
    ----------
    mechanism : evotol.robots.clearance.ClearanceMechanism
        The engine's mechanism (e.g. ``MechanismModel(...).clearance_mechanism()``, whose pose
        coordinates are the robot's).
    classes : sequence of ClearanceClass
        The allocated clearances.
    base_bounds : ndarray, shape (n_joints, 4), or None
        The bounds (``beta_xy``, ``beta_z`` in rad; ``b_xy``, ``b_z`` in m) of everything no
        class sets (default: the joints' own bounds).
    tol : float
        Relative certificate gap of the engine (1, dimensionless).
    _maps : dict
        Internal cache of the engine's pose maps (keyed by the poses); leave the default.

    Raises
    ------
    evotol.errors.ValidationError
        Not a clearance mechanism, no class, a class that is not a :class:`ClearanceClass`, a
        joint without clearance, a bound set by two classes, duplicate class names, or
        ``base_bounds`` of the wrong shape or negative.

    Examples
    --------
    >>> from evotol import ClearanceClass, ClearanceSources, MechanismModel
    >>> from evotol.robots.mechanism.model.error_model import resolve_description
    >>> robot = MechanismModel(resolve_description("fivebar"))
    >>> mech = robot.clearance_mechanism()
    >>> [j.name for j in mech.joints]
    ['A', 'C', 'B', 'D', 'E']
    >>> cl = ClearanceSources(mech, [ClearanceClass("radial", ("A", "C"), {"b_xy": 1.0})])
    >>> cl.names
    ('radial',)
    """

    mechanism: object
    classes: Sequence[ClearanceClass]
    base_bounds: np.ndarray | None = None
    tol: float = 1e-3
    _maps: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        mech = self.mechanism
        if not isinstance(mech, ClearanceMechanism):
            raise ValidationError("clearances.mechanism", mech, "a evotol.robots.clearance.ClearanceMechanism")
        self.classes = tuple(self.classes)
        if not self.classes:
            raise ValidationError("clearances.classes", [], "at least one clearance class")
        names = [j.name for j in mech.joints]
        seen: dict = {}
        self.index = []          # per class: (joint indices, component indices, factors)
        for c in self.classes:
            if not isinstance(c, ClearanceClass):
                raise ValidationError("clearances.classes", c, "evotol.measures.clearances.ClearanceClass values")
            ji = []
            for j in c.joints:
                if j not in names:
                    raise ValidationError(f"clearance class {c.name!r}.joints", j, f"a joint with clearance: {names}")
                ji.append(names.index(j))
            for j in ji:
                for k in c.bounds:
                    key = (j, COMPONENTS.index(k))
                    if key in seen:
                        raise ValidationError(f"clearance class {c.name!r}.bounds.{k}", names[j],
                                              f"a bound set by one class only (already set by {seen[key]!r})")
                    seen[key] = c.name
            self.index.append((np.array(ji), np.array([COMPONENTS.index(k) for k in c.bounds]),
                               np.array([float(v) for v in c.bounds.values()])))
        if len({c.name for c in self.classes}) != len(self.classes):
            raise ValidationError("clearances.classes", [c.name for c in self.classes], "unique class names")
        base = mech.default_bounds() if self.base_bounds is None else np.asarray(self.base_bounds, float)
        if base.shape != (mech.n_joints, 4) or not np.all(np.isfinite(base)) or np.any(base < 0):
            raise ValidationError("clearances.base_bounds", np.shape(base), f"finite bounds >= 0 of shape ({mech.n_joints}, 4)")
        base = base.copy()
        for ji, ki, _ in self.index:
            base[np.ix_(ji, ki)] = 0.0
        self.base_bounds = base
        # bound entry (joint, component) -> class index, -1 for a fixed bound
        self.owner = -np.ones((mech.n_joints, 4), int)
        for i, (ji, ki, _) in enumerate(self.index):
            self.owner[np.ix_(ji, ki)] = i

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the clearance classes (source names), in order."""
        return tuple(c.name for c in self.classes)

    @property
    def sources(self) -> tuple[SourceSpec, ...]:
        """The classes as one-dimensional sources (:attr:`ClearanceClass.source`), in order."""
        return tuple(c.source for c in self.classes)

    @property
    def homogeneous(self) -> bool:
        """True when every bound is set by a class (no fixed part): W is then positively
        homogeneous of degree 1 in (t, c)."""
        return not np.any(self.base_bounds > 0)

    def bounds(self, C) -> np.ndarray:
        """Engine bounds (n, n_joints, 4) [beta_xy, beta_z, b_xy, b_z] (rad, m) of class tolerances C (n, n_classes).

        Parameters
        ----------
        C : array_like, (n, n_classes) or (n_classes,)
            Tolerances of the clearance classes (each in its class's unit, m or rad).

        Returns
        -------
        numpy.ndarray
            (n, n_joints, 4) bounds: ``factor * t`` where a class sets the bound, the fixed
            ``base_bounds`` elsewhere (rad for ``beta_*``, m for ``b_*``).

        Raises
        ------
        evotol.errors.ValidationError
            If the last axis of ``C`` is not ``n_classes`` long.
        """
        C = np.atleast_2d(np.asarray(C, float))
        if C.shape[-1] != len(self.classes):
            raise ValidationError("clearance tolerances shape", C.shape, f"(n, {len(self.classes)})")
        out = np.broadcast_to(self.base_bounds, (C.shape[0],) + self.base_bounds.shape).copy()
        for i, (ji, ki, fac) in enumerate(self.index):
            out[:, ji[:, None], ki[None, :]] = C[:, i, None, None] * fac[None, None, :]
        return out

    def maps(self, poses: np.ndarray):
        """The engine's per-pose maps at ``poses`` (cached by the poses' bytes).

        Only the last poses asked for are cached.

        Parameters
        ----------
        poses : numpy.ndarray, (n_poses, d) or (d,)
            Poses in the mechanism's (the robot's) pose coordinates (m or rad).

        Returns
        -------
        list of evotol.robots.clearance.PoseMaps
            One per decoupled block (:meth:`evotol.robots.clearance.ClearanceMechanism.pose_maps`).
        """
        key = np.ascontiguousarray(poses, float).tobytes()
        if key not in self._maps:
            self._maps.clear()
            self._maps[key] = self.mechanism.pose_maps(np.atleast_2d(poses))
        return self._maps[key]


CLASS_KEYS = ("name", "joints", "bounds", "unit", "group", "description")
TABLE_KEYS = ("h", "joints", "axial", "class", "geometric", "tol")


def from_table(table: dict, robot) -> ClearanceSources:
    """The ``[clearances]`` table of a study file: the thesis's classes (``h`` = joint length, m;
    optional ``joints`` (default: every joint with clearance), ``axial = false`` for radial only)
    and/or explicit ``[[clearances.class]]`` tables (``name``, ``joints``, ``bounds = {b_xy = 1.0,
    beta_xy = 100.0}``, optional ``unit``, ``group``). ``robot.clearance_mechanism()`` gives the
    joints and the fixed bounds (the description's ``[clearance]``).

    Parameters
    ----------
    table : dict
        The ``[clearances]`` table (keys ``h``, ``joints``, ``axial``, ``class``, ``tol``,
        ``geometric``; ``tol`` is the engine's relative gap, default 1e-3).
    robot : RobotErrorModel
        The robot; it must have ``clearance_mechanism()``.

    Returns
    -------
    ClearanceSources
        The classes on the robot's clearance mechanism.

    Raises
    ------
    evotol.errors.ValidationError
        An unknown key, a robot without joint clearances, ``joints`` or ``axial`` without ``h``,
        a class table without ``name``, ``joints`` or ``bounds``, or an invalid class or
        class set (:class:`ClearanceClass`, :class:`ClearanceSources`).
    """
    check_table_keys(table, TABLE_KEYS, "clearances")
    mech = robot.clearance_mechanism()         # refused in one line by a robot without joint clearances
    classes = []
    if "h" in table:
        joints = table.get("joints", [j.name for j in mech.joints])
        classes += thesis_classes(joints, table["h"], bool(table.get("axial", True)))
    elif "joints" in table or "axial" in table:
        raise ValidationError("clearances.h", None, "the joint length h (m) of eq. III.2 for the thesis's classes")
    for i, c in enumerate(table.get("class", [])):
        check_table_keys(c, CLASS_KEYS, f"clearances.class[{i}]")
        if "name" not in c or "joints" not in c or "bounds" not in c:
            raise ValidationError(f"clearances.class[{i}]", sorted(c), "name, joints and bounds")
        classes.append(ClearanceClass(**{**c, "joints": tuple(np.atleast_1d(c["joints"]).tolist())}))
    return ClearanceSources(mech, classes, tol=float(table.get("tol", 1e-3)))

"""Joint clearances as allocated tolerances: the certified worst case of geometric tolerances and
clearance bounds together (Deng 2012 Sec. VII.1 stated as an optimisation; issue 12 item 5).

A **clearance class** is one tolerance t (SI) that sets some clearance bounds of some joints,
each as ``factor * t``: the thesis's radial clearance of joint A, ``Δb_xy = t`` with its tilt
``Δβ_xy = t / h`` (eq. III.2), is ``ClearanceClass("bxy_A", ("A",), {"b_xy": 1, "beta_xy": 1/h})``;
one class may cover several joints (one fit for all passive joints). Bounds no class covers keep
the mechanism's own values (e.g. the passive joints' idle rotation Δβ_z = 0.2 rad).

Measure. At pose p, the geometric sources (intervals ``|δ_j| <= t_j`` through the first-order map J_g)
and the clearance screws s (each joint's s_k in its set C_k(c), consistent with the loops,
``B^T s = 0``) move the end-effector by ``J_g δ + C s``. The reachable set is the Minkowski sum
``P_g(t) + P_c(c)``, and the worst case ``W(t, c) = max |J_g δ + C s|`` is computed by the
certified engine of :mod:`robots.clearance` (``evaluate_cases(..., extra=(J_g, t))``): a value
**attained** by explicit screws and source errors, and a **proven upper bound** (relative gap
<= ``tol``, default 1e-3).

Structure (proved in ``docs/clearance_allocation.md``, checked numerically in the tests):
  * W is nondecreasing in every t_j and c_k (C_k(c) = c·B_k grows with c, B_k convex and
    containing 0), and positively homogeneous of degree 1 in (t, c) when no fixed bound is
    nonzero;
  * for a fixed direction u the clearance support function h_c(u; c) is *concave* in c (a
    mixture of two feasible screw sets is feasible for the mixed bounds) -- with loops, W is
    **not convex** in (t, c): along random segments of the 5-bar's thesis problem it exceeds
    its chord by up to 150-400 %, and two parallel chains give W = min(c_1, c_2) exactly.

So the certified optimum's cutting planes do not apply; :mod:`evotol.allocators.monotone` uses
the monotonicity instead (polyblock outer approximation: a proven lower bound on the cost).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from evotol.errors import ValidationError
from evotol.keywords import check_table_keys
from robots.base import RobotErrorModel, SourceSpec

#: clearance bound components, in the engine's column order (Deng 2012 eqs. III.3-III.6)
COMPONENTS = ("beta_xy", "beta_z", "b_xy", "b_z")
#: screw component (row of a joint's [dr; dt] in its frame) -> bound component index
_SCREW_KIND = (0, 0, 1, 2, 2, 3)
#: twist order of the engine [dtheta; dp] -> evotol's [dp; dtheta]
_TO_ENGINE = [3, 4, 5, 0, 1, 2]


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
    """Clearance classes of a clearance mechanism (:class:`robots.clearance.ClearanceMechanism`).

    Parameters
    ----------
    mechanism : robots.clearance.ClearanceMechanism
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
    """

    mechanism: object
    classes: Sequence[ClearanceClass]
    base_bounds: np.ndarray | None = None
    tol: float = 1e-3
    _maps: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        mech = self.mechanism
        if not hasattr(mech, "pose_maps") or not hasattr(mech, "joints"):
            raise ValidationError("clearances.mechanism", mech, "a robots.clearance.ClearanceMechanism")
        self.classes = tuple(self.classes)
        if not self.classes:
            raise ValidationError("clearances.classes", [], "at least one clearance class")
        names = [j.name for j in mech.joints]
        seen: dict = {}
        self.index = []          # per class: (joint indices, component indices, factors)
        for c in self.classes:
            if not isinstance(c, ClearanceClass):
                raise ValidationError("clearances.classes", c, "evotol.clearances.ClearanceClass values")
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
        list of robots.clearance.PoseMaps
            One per decoupled block (:meth:`robots.clearance.ClearanceMechanism.pose_maps`).
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
    if not hasattr(robot, "clearance_mechanism"):
        raise ValidationError("clearances", robot.name, "a robot with joint clearances (clearance_mechanism())")
    mech = robot.clearance_mechanism()
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


class WithClearances(RobotErrorModel):
    """A robot's geometric sources followed by clearance classes, for :class:`ToleranceProblem`.

    The clearance classes have no linear column: ``sensitivity`` gives them zero columns, and the
    problem evaluates them only through the certified engine (:func:`worst_case`). Not a robot to
    use on its own (its first-order map omits the clearances).

    Parameters
    ----------
    robot : RobotErrorModel
        The robot whose geometric sources come first (interval sources only).
    clearances : ClearanceSources
        The clearance classes, appended as sources after the geometric ones.
    geometric : bool
        Whether the robot's geometric sources are included (False: clearances only).

    Raises
    ------
    evotol.errors.ValidationError
        A class named like a geometric source, or a geometric source that is not an interval
        (dim != 1).
    """

    def __init__(self, robot: RobotErrorModel, clearances: ClearanceSources, geometric: bool = True):
        self.base, self.clearances, self.geometric = robot, clearances, bool(geometric)
        self.name = f"{robot.name} + clearances" if geometric else f"{robot.name} (clearances)"
        self.workspace = robot.workspace
        own = tuple(robot.sources) if geometric else ()
        clash = {s.name for s in own} & set(clearances.names)
        if clash:
            raise ValidationError("clearances.classes", sorted(clash), f"names other than the sources of {robot.name}")
        for s in own:
            if s.dim != 1:
                raise ValidationError(f"{robot.name} source {s.name!r}", s.shape,
                                      "interval sources only next to clearances (the engine adds intervals)")
        self.sources = own + clearances.sources
        self.n_geometric = len(own)

    def sensitivity(self, poses) -> np.ndarray:
        """First-order map of the geometric sources, with zero columns for the clearance classes.

        Parameters
        ----------
        poses : array_like, (n_poses, d)
            Poses in the robot's pose coordinates (m or rad).

        Returns
        -------
        numpy.ndarray
            (n_poses, 6, n_sources) Jacobian of the twist ``[dp; dtheta]`` (m, rad) with respect
            to the sources (per SI unit of each source); the clearance columns are 0.
        """
        J = np.asarray(self.base.sensitivity(poses), float) if self.geometric else \
            np.zeros((len(self.check_poses(poses)), 6, 0))
        return np.concatenate([J, np.zeros(J.shape[:2] + (len(self.clearances.classes),))], axis=2)

    def pose_error(self, poses, errors) -> np.ndarray:   # pragma: no cover - guarded by has_nonlinear_model
        """Not available: clearances have no nonlinear model (:attr:`has_nonlinear_model` is False).

        Parameters
        ----------
        poses : array_like
            Poses (unused).
        errors : array_like
            Source errors (unused).

        Raises
        ------
        evotol.errors.ValidationError
            Always.
        """
        raise ValidationError("pose_error", self.name, "geometric sources only: clearances are first order")

    @property
    def has_nonlinear_model(self) -> bool:
        """False: clearances are evaluated first order only (certified engine)."""
        return False


@dataclass(frozen=True)
class ClearanceWorstCase:
    """Certified worst case at every pose of designs (n_designs, n_poses) per component
    (``"position"`` m, ``"orientation"`` rad): attained value, proven bound, worst direction (unit,
    base axes, (n, P, 3)) and each source's share of the error at that direction ((n, P, n_src);
    the shares miss what the fixed, unallocated clearance bounds contribute).

    Parameters
    ----------
    value : dict
        Component -> (n_designs, n_poses) attained worst-case error (m or rad).
    bound : dict
        Component -> (n_designs, n_poses) proven upper bound (m or rad).
    direction : dict
        Component -> (n_designs, n_poses, 3) unit direction of the worst error (base axes).
    contrib : dict
        Component -> (n_designs, n_poses, n_sources) each source's share of the attained error,
        as a fraction of it (dimensionless).
    n_solves : int
        Number of support problems the engine solved (its work).
    """

    value: dict
    bound: dict
    direction: dict
    contrib: dict
    n_solves: int


def _only(maps, comp: str):
    """The maps with the other target removed: the engine then skips it (position-only
    requirements do not pay for the rotational branch and bound)."""
    import dataclasses

    if comp == "position":
        return [dataclasses.replace(pm, C_rot=pm.C_rot[:, :0], rot_comps=()) for pm in maps]
    return [dataclasses.replace(pm, C_pos=pm.C_pos[:, :0], pos_comps=()) for pm in maps]


def worst_case(robot: WithClearances, poses: np.ndarray, jacobian: np.ndarray, T,
               components: Sequence[str] = ("position", "orientation")) -> ClearanceWorstCase:
    """Certified worst-case position (m) and orientation (rad) error of designs T (n, n_sources)
    at every pose: the geometric intervals through ``jacobian`` (n_poses, 6, n_sources; the
    clearance columns are ignored) plus the consistent clearance screws inside the classes' bounds
    (Minkowski sum; :func:`robots.clearance.evaluate_cases` with ``extra``). Only the listed
    ``components`` are computed.

    Parameters
    ----------
    robot : WithClearances
        The robot with its clearance classes.
    poses : numpy.ndarray, (n_poses, d)
        Poses (m or rad).
    jacobian : numpy.ndarray, (n_poses, 6, n_sources)
        First-order map of the twist ``[dp; dtheta]`` (:meth:`WithClearances.sensitivity`).
    T : array_like, (n, n_sources) or (n_sources,)
        Designs: geometric tolerances first, then the class tolerances (m or rad).
    components : sequence of {"position", "orientation"}
        Error components to compute.

    Returns
    -------
    ClearanceWorstCase
        Attained values, proven bounds, worst directions and shares per component.
    """
    from robots.clearance import evaluate_cases

    cl = robot.clearances
    T = np.atleast_2d(np.asarray(T, float))
    n, P, g = T.shape[0], len(poses), robot.n_geometric
    maps = cl.maps(poses)
    if len(components) == 1:
        maps = _only(maps, components[0])
    idx = np.tile(np.arange(P), n)                                   # case = (design, pose)
    bounds = np.repeat(cl.bounds(T[:, g:]), P, axis=0)
    extra = None
    if g:
        Jg = jacobian[:, _TO_ENGINE, :g]
        extra = (Jg, np.repeat(T[:, :g], P, axis=0))
    res = evaluate_cases(cl.mechanism, maps, idx, bounds, tol=cl.tol, extra=extra)
    out = ClearanceWorstCase({}, {}, {}, {}, res.n_solves)
    for comp in components:
        w, rows = ("p", slice(3, 6)) if comp == "position" else ("r", slice(0, 3))
        val = getattr(res, f"{w}_max")
        tw = getattr(res, f"{w}_twist")
        inv = 1.0 / np.where(val > 0, val, 1.0)
        u = tw[:, rows] * inv[:, None]
        contrib = np.zeros((n * P, T.shape[1]))
        if g:   # u·J_j δ_j for the geometric sources at the maximiser
            contrib[:, :g] = np.einsum("ck,ckj,cj->cj", u, Jg[idx][:, rows], getattr(res, f"{w}_extra"))
        S = getattr(res, f"{w}_screws").reshape(n * P, -1)
        for pm in maps:   # u·C_col s_col summed over the columns a class owns
            C, comps = (pm.C_pos, pm.pos_comps) if w == "p" else (pm.C_rot, pm.rot_comps)
            if not comps:
                continue
            part = np.einsum("ck,ckr,cr->cr", tw[:, list(comps)] * inv[:, None], C[idx], S[:, pm.cols])
            own = cl.owner[pm.cols // 6, np.array(_SCREW_KIND)[pm.cols % 6]]
            for r in np.flatnonzero(own >= 0):
                contrib[:, g + own[r]] += part[:, r]
        out.value[comp] = val.reshape(n, P)
        out.bound[comp] = getattr(res, f"{w}_upper").reshape(n, P)
        out.direction[comp] = u.reshape(n, P, 3)
        out.contrib[comp] = (contrib * inv[:, None]).reshape(n, P, -1)
    return out


def sample_twists(robot: WithClearances, poses: np.ndarray, c: np.ndarray, n_samples: int, rng,
                  mode: str = "uniform") -> np.ndarray:
    """End-effector twists ``[dp; dtheta]`` (n_poses, n_samples, 6) of random consistent clearance
    states for class tolerances c (n_classes,): every joint's screw drawn uniformly inside (or, with
    ``mode="boundary"``, on the boundary of) its disks and intervals, projected onto the loop
    equations ``B^T s = 0`` and scaled back into the set -- the sampling of
    :func:`robots.clearance.sample_max_errors`, per sample instead of its maximum.

    Parameters
    ----------
    robot : WithClearances
        The robot with its clearance classes.
    poses : numpy.ndarray, (n_poses, d)
        Poses (m or rad).
    c : array_like, (n_classes,)
        Class tolerances (m or rad).
    n_samples : int
        Samples per pose.
    rng : numpy.random.Generator
        Random generator.
    mode : {"uniform", "boundary"}
        Screws drawn inside their sets or on their boundaries.

    Returns
    -------
    numpy.ndarray
        (n_poses, n_samples, 6) twists ``[dp; dtheta]`` (m, rad).
    """
    cl = robot.clearances
    b = cl.bounds(np.asarray(c, float)[None])[0]
    maps = cl.maps(poses)
    out = np.zeros((len(poses), n_samples, 6))
    for p in range(len(poses)):
        for pm in maps:
            s = pm.sample_screws(p, b, n_samples, rng, mode)
            out[p][:, [_TO_ENGINE.index(k) for k in pm.pos_comps]] += s @ pm.C_pos[p].T
            out[p][:, [_TO_ENGINE.index(k) for k in pm.rot_comps]] += s @ pm.C_rot[p].T
    return out

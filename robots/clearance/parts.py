"""Plain values of the clearance model (Deng 2012 Ch. III): the four clearance bounds of a joint
(eqs. III.3-III.6), joints, serial chains between bodies, and the decoupled blocks of screw/twist
components. The mechanism that assembles them is :class:`evotol.robots.clearance.model.ClearanceMechanism`."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.errors import ValidationError

#: bound kinds, in the column order of a bounds array ``(..., n_joints, 4)``
BOUND_NAMES = ("beta_xy", "beta_z", "b_xy", "b_z")
#: units of those bound kinds (SI)
BOUND_UNITS = ("rad", "rad", "m", "m")
#: screw components each bound constrains (eqs. III.3-III.6): disk, interval, disk, interval
CONE_COMPONENTS = ((0, 1), (2,), (3, 4), (5,))
ROT, POS = (0, 1, 2), (3, 4, 5)


@dataclass(frozen=True)
class ClearanceBounds:
    """Clearance bounds of one joint (Deng 2012 Fig. III.1, eqs. III.3-III.6), SI units.

    beta_xy: tilt of the joint axis, rad (disk); beta_z: rotation about the axis, rad (interval;
    ~0 for an actuated joint, large for a passive one: idle motion); b_xy: radial play, m (disk);
    b_z: axial play, m (interval).

    Parameters
    ----------
    beta_xy : float
        Tilt of the joint axis, rad: bound on the norm of the rotation components ``(x, y)`` of the
        joint's error screw (a disk, eq. III.3).
    beta_z : float
        Rotation about the joint axis, rad: bound on ``|dr_z|`` (an interval, eq. III.4).
    b_xy : float
        Radial play, m: bound on the norm of the translation components ``(x, y)`` (a disk, eq. III.5).
    b_z : float
        Axial play, m: bound on ``|dt_z|`` (an interval, eq. III.6).

    Raises
    ------
    ValidationError
        A bound that is not a finite number >= 0 (a Python or NumPy float or int).
    """

    beta_xy: float
    beta_z: float
    b_xy: float
    b_z: float

    def __post_init__(self):
        for k in BOUND_NAMES:
            v = getattr(self, k)
            if not isinstance(v, (int, float, np.floating)) or not np.isfinite(v) or v < 0:
                raise ValidationError(f"ClearanceBounds.{k}", v, "a finite number >= 0 (SI units)")

    @classmethod
    def thesis(cls, active: bool, *, b_xy: float = 1e-4, b_z: float = 1e-4, beta_xy: float | None = 0.01,
               h: float | None = None, beta_z_passive: float = 0.2, beta_z_active: float = 0.0) -> "ClearanceBounds":
        """The thesis's convention (Sec. III.1.1, IV.3): ``beta_z`` = ``beta_z_active`` (locked,
        default 0) for an actuated joint, ``beta_z_passive`` (idle motion, default 0.2 rad) for a
        passive one; ``beta_xy = b_xy / h`` (eq. III.2) when a joint length ``h`` (m) is given.

        Parameters
        ----------
        active : bool
            True for an actuated joint (``beta_z = beta_z_active``), False for a passive one
            (``beta_z = beta_z_passive``).
        b_xy : float, optional
            Radial play, m (default 1e-4 m = 0.1 mm).
        b_z : float, optional
            Axial play, m (default 1e-4 m).
        beta_xy : float or None, optional
            Tilt of the joint axis, rad (default 0.01 rad); ignored when ``h`` is given.
        h : float or None, optional
            Joint length, m: when given, ``beta_xy = b_xy / h``.
        beta_z_passive : float, optional
            Rotation about the axis of a passive joint, rad (default 0.2 rad, idle motion).
        beta_z_active : float, optional
            Rotation about the axis of an actuated joint, rad (default 0: locked).

        Returns
        -------
        ClearanceBounds
            The joint's four bounds, SI units.

        Raises
        ------
        ValidationError
            ``h`` given but not > 0; ``beta_xy`` None and no ``h``; or a resulting bound that is
            not finite and >= 0.
        """
        if h is not None:
            if not h > 0:
                raise ValidationError("ClearanceBounds.thesis h", h, "a joint length > 0 (m)")
            beta_xy = b_xy / h
        if beta_xy is None:
            raise ValidationError("ClearanceBounds.thesis beta_xy", beta_xy, "a number, or give h")
        return cls(float(beta_xy), float(beta_z_active if active else beta_z_passive), float(b_xy), float(b_z))

    def as_array(self) -> np.ndarray:
        """The bounds as an array.

        Returns
        -------
        (4,) ndarray
            ``[beta_xy (rad), beta_z (rad), b_xy (m), b_z (m)]`` (the order of ``BOUND_NAMES``).
        """
        return np.array([self.beta_xy, self.beta_z, self.b_xy, self.b_z])

    def scaled(self, factor: float) -> "ClearanceBounds":
        """All four bounds multiplied by one factor.

        Parameters
        ----------
        factor : float
            Scale factor, dimensionless (>= 0).

        Returns
        -------
        ClearanceBounds
            ``factor`` times each bound.

        Raises
        ------
        ValidationError
            A negative or non-finite ``factor`` (a scaled bound not finite and >= 0).
        """
        return ClearanceBounds(*(factor * self.as_array()))


@dataclass(frozen=True)
class Joint:
    """A joint with clearance: ``frame`` is the DH frame whose ``z`` axis is the joint axis (the
    error screw is expressed in it); ``active``: actuated (locked for the analysis).

    Parameters
    ----------
    name : str
        Joint name (unique in the mechanism).
    frame : str
        Name of the DH frame whose ``z`` axis is the joint axis; the joint's error screw
        ``[dr; dt]`` (rad, m) is expressed in this frame.
    active : bool
        True for an actuated joint (locked for the analysis).
    bounds : ClearanceBounds
        The joint's clearance bounds (rad, m).
    """

    name: str
    frame: str
    active: bool
    bounds: ClearanceBounds


@dataclass(frozen=True)
class Chain:
    """A serial chain of joints from body ``start`` to body ``end`` (names of bodies; ``"base"`` is
    fixed). ``joints``: names of the chain's joints, base side first. ``path_end``: DH frame at
    the end of the chain's kinematic path (defaults to the end body's frame); the end body is
    reached from it by a constant offset (a cut joint of a closed loop, e.g. frame 5 = frame 6 of
    the 5-bar, Tab. IV.1).

    Parameters
    ----------
    name : str
        Chain name.
    start : str
        Name of the body at the base side (``"base"``: the fixed base).
    end : str
        Name of the body at the end of the chain.
    joints : tuple of str
        Names of the chain's joints, base side first.
    path_end : str or None, optional
        DH frame at the end of the chain's kinematic path; None (default): the end body's frame.
    """

    name: str
    start: str
    end: str
    joints: tuple[str, ...]
    path_end: str | None = None


@dataclass(frozen=True)
class Block:
    """A set of screw/twist components that decouples from the rest (planar in/out of plane).

    Parameters
    ----------
    name : str
        Block name (``"spatial"``, ``"in-plane"``, ``"out-of-plane"``).
    components : tuple of int
        Indices (0-5) of the twist and screw components ``[dr; dt]`` in the block (the same index
        sets for twists and screws).
    """

    name: str
    components: tuple[int, ...]  # twist and screw components (same index sets for the blocks used)


#: one spatial block: all six twist components solved together
FULL = (Block("spatial", (0, 1, 2, 3, 4, 5)),)
#: a planar mechanism's exact split: in-plane (x, y translations, z rotation) and out-of-plane blocks
PLANAR = (Block("in-plane", (2, 3, 4)), Block("out-of-plane", (0, 1, 5)))

"""Plain values of the clearance model (Deng 2012 Ch. III): the four clearance bounds of a joint
(eqs. III.3-III.6), joints, serial chains between bodies, and the decoupled blocks of screw/twist
components. The mechanism that assembles them is :class:`robots.clearance.model.ClearanceMechanism`."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.errors import ValidationError

#: bound kinds, in the column order of a bounds array ``(..., n_joints, 4)``
BOUND_NAMES = ("beta_xy", "beta_z", "b_xy", "b_z")
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
        passive one; ``beta_xy = b_xy / h`` (eq. III.2) when a joint length ``h`` (m) is given."""
        if h is not None:
            if not h > 0:
                raise ValidationError("ClearanceBounds.thesis h", h, "a joint length > 0 (m)")
            beta_xy = b_xy / h
        if beta_xy is None:
            raise ValidationError("ClearanceBounds.thesis beta_xy", beta_xy, "a number, or give h")
        return cls(float(beta_xy), float(beta_z_active if active else beta_z_passive), float(b_xy), float(b_z))

    def as_array(self) -> np.ndarray:
        return np.array([self.beta_xy, self.beta_z, self.b_xy, self.b_z])

    def scaled(self, factor: float) -> "ClearanceBounds":
        return ClearanceBounds(*(factor * self.as_array()))


@dataclass(frozen=True)
class Joint:
    """A joint with clearance: ``frame`` is the DH frame whose ``z`` axis is the joint axis (the
    error screw is expressed in it); ``active``: actuated (locked for the analysis)."""

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
    the 5-bar, Tab. IV.1)."""

    name: str
    start: str
    end: str
    joints: tuple[str, ...]
    path_end: str | None = None


@dataclass(frozen=True)
class Block:
    """A set of screw/twist components that decouples from the rest (planar in/out of plane)."""

    name: str
    components: tuple[int, ...]  # twist and screw components (same index sets for the blocks used)


FULL = (Block("spatial", (0, 1, 2, 3, 4, 5)),)
PLANAR = (Block("in-plane", (2, 3, 4)), Block("out-of-plane", (0, 1, 5)))

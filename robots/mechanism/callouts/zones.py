"""Drawing callouts on a joint seat and their exact zones as placement errors (issue 35).

A shop tolerances a bearing bore by a **callout** on the link's drawing, not by "tilt_z ± 41 µrad".
This module states the geometry of four callouts on the axis of a revolute or prismatic joint and
maps each zone exactly onto the placement errors ``[shift; tilt]`` of the joint's placement
(:mod:`evotol.robots.mechanism.kinematics.placement`, ``placement * exp(delta)``); ``docs/callouts.md`` derives it.

Datum convention. The datum reference frame of a callout (the drawing's ``A|B``) is the joint's
*nominal placement*: for a URDF arm the joint's ``<origin>`` in its parent link (the part that
carries the bore), its origin on the joint axis ``a`` (unit, placement axes). Errors of the parent
link itself are the callouts (or sources) of the joints upstream. A position along the axis is
``s`` (m) from that origin; a feature of length ``L`` centred at ``c`` spans ``s1 = c - L/2`` to
``s2 = c + L/2``. Lateral directions ``(e1, e2)`` are the placement's coordinate axes orthogonal to
``a`` taken cyclically (``a = z``: ``(x, y)``; ``a = y``: ``(z, x)``; ``a = x``: ``(y, z)``; any other
axis: the least aligned coordinate axis projected), ``e1 x e2 = a``. Only the independent-box
rule depends on this choice: a disc has no preferred direction.

Zones (the tolerance value ``t`` is the drawing's value, in m; the cost model sees it):

* **position** ``⌖ ⌀t`` over ``L`` at ``c``: the axis lies in a cylinder ⌀t, so its lateral
  displacement ``d1`` at ``s1`` and ``d2`` at ``s2`` each lie in a disc of radius t/2, and those two
  discs are the whole zone (a segment is in a convex cylinder iff its ends are). Two **disk
  sources** ``J.position.end1``/``end2`` with errors ``|e_k| <= t`` and ``d_k = e_k / 2``, sharing
  one tolerance (one cost). Linear map: ``g = (d2 - d1)/L`` (slope), lateral shift at the origin
  ``v = (s2 d1 - s1 d2)/L``, tilt ``w = a x g``; a point of the axis at ``s`` moves by ``v + s g``.
* **orientation** (``⊥`` perpendicularity, ``∥`` parallelism) ``⌀t`` over ``L``: the axis lies in a
  cylinder ⌀t of fixed direction and free location: ``|d2 - d1| <= t``. One disk source
  ``e = d2 - d1`` (``|e| <= t``): a tilt ``w = a x e / L`` about the feature centre ``p = c a``
  (``v = p x w``). For a prismatic joint's guide, ``∥`` over its stroke is the same with ``L`` the
  stroke.
* **axial** location of the shoulder face (position or profile of the face, ``t`` wide): an
  interval source ``|e| <= t``, shift ``e/2`` along ``a`` (the face within ±t/2).
* **position refined by orientation** on the same feature: the zone is the intersection
  ``|d1|, |d2| <= t_p/2, |d2 - d1| <= t_o``, which is not a sum of discs. evotol models it by the
  outer (safe) set: a disc of radius t_p/2 for the displacement of the feature centre
  (``J.position``, ``|e| <= t_p``, ``d_c = e/2``) plus the orientation disc above -- every axis of
  the true zone is in it (``d_c`` is the mean of ``d1``, ``d2``), exact as ``t_o -> 0``.

The **independent-box rule** of common tolerance tools (``zones = "boxes"``): translations of the
feature centre within ±t/2 along ``e1`` and ``e2`` and tilts within ±t/L about ``e1`` and ``e2``,
each an interval source sharing the callout's tolerance. It contains the exact zone, so it holds
whatever the exact zone holds, at a higher cost.

The parameters several definitions of this module share are described once, here.

Parameters
----------
axis : (3,) array_like
    The joint axis in the placement frame.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.errors import ValidationError

#: callout kind -> drawing symbol (ASME Y14.5 / ISO 1101)
SYMBOLS = {"position": "⌖ ⌀", "perpendicularity": "⊥ ⌀", "parallelism": "∥ ⌀", "axial": "⌖ face"}
#: kinds that hold only the axis direction
ORIENTATION_KINDS = ("perpendicularity", "parallelism")
KINDS = tuple(SYMBOLS)
#: how a zone is modelled: exactly, or by the independent-box rule
ZONE_MODELS = ("exact", "boxes")


@dataclass(frozen=True)
class Callout:
    """One drawing callout on a joint's axis (see the module docstring for the zones).

    Parameters
    ----------
    joint : str
        The joint whose seat carries it (the placement frame's name, e.g. ``"elbow_joint"``).
    kind : str
        One of :data:`KINDS`.
    length : float
        Feature length L (m): the bore or guide length over which the zone applies; for an
        ``axial`` callout the shoulder face's size (only shown on the drawing).
    offset : float
        Centre c of the feature along the joint axis from the placement origin (m).
    datums : str
        The drawing's datum letters (e.g. ``"A|B"``), shown as written.

    Raises
    ------
    evotol.errors.ValidationError
        An unknown kind, a length that is not positive and finite, an offset that is not finite.
    """

    joint: str
    kind: str
    length: float
    offset: float = 0.0
    datums: str = "A|B"

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValidationError(f"callout {self.joint}.kind", self.kind, f"one of {KINDS}")
        if not (isinstance(self.length, (int, float)) and np.isfinite(self.length) and self.length > 0):
            raise ValidationError(f"callout {self.name}.length", self.length, "a positive feature length (m)")
        if not (isinstance(self.offset, (int, float)) and np.isfinite(self.offset)):
            raise ValidationError(f"callout {self.name}.offset", self.offset, "a finite centre offset along the axis (m)")

    @property
    def name(self) -> str:
        """The tolerance's name, ``"<joint>.<kind>"``."""
        return f"{self.joint}.{self.kind}"

    @property
    def symbol(self) -> str:
        """The drawing symbol (``"⌖ ⌀"``, ``"⊥ ⌀"``, ``"∥ ⌀"``, ``"⌖ face"``)."""
        return SYMBOLS[self.kind]

    def text(self, value: str = "t") -> str:
        """The callout as a drawing writes it, e.g. ``"⌖ ⌀20 µm"`` or ``"⌖ face 60 µm"``.

        Parameters
        ----------
        value : str
            The value as text (default the letter ``t``).

        Returns
        -------
        str
            Symbol and value.
        """
        return f"{self.symbol}{value}" if self.symbol.endswith("⌀") else f"{self.symbol} {value}"

    @property
    def ends(self) -> tuple[float, float]:
        """(s1, s2): the feature's ends along the axis from the placement origin (m)."""
        return self.offset - self.length / 2, self.offset + self.length / 2


@dataclass(frozen=True)
class ZoneMember:
    """One source of a callout's zone: its name, shape and map to the placement twist.

    Parameters
    ----------
    name : str
        Source name (``"elbow_joint.position.end1"``...).
    dim : int
        1 (interval), 2 (disk).
    matrix : (6, dim) ndarray
        Placement twist ``[shift (m); tilt (rad)]`` per unit of the source's error (per m).
    """

    name: str
    dim: int
    matrix: np.ndarray


def lateral_basis(axis) -> tuple[np.ndarray, np.ndarray]:
    """(e1, e2): the lateral directions of a joint axis, ``e1 x e2 = a`` (module docstring).

    Parameters
    ----------
    axis : (3,) array_like
        The joint axis in the placement frame (normalised here).

    Returns
    -------
    e1, e2 : (3,) ndarray
        Unit vectors orthogonal to the axis and to each other.

    Raises
    ------
    evotol.errors.ValidationError
        A zero or non-finite axis.
    """
    a = np.asarray(axis, float)
    n = np.linalg.norm(a)
    if not np.isfinite(n) or n == 0:
        raise ValidationError("joint axis", a.tolist(), "a non-zero finite vector")
    a = a / n
    k = int(np.argmax(np.abs(a)))
    ref = np.eye(3)[(k + 1) % 3]          # cyclic: z -> x, y -> z, x -> y
    e1 = ref - (ref @ a) * a
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(a, e1)


def _twist(v, w) -> np.ndarray:
    return np.concatenate([v, w])


def zone_members(callout: Callout, axis, refined: bool = False, zones: str = "exact") -> list[ZoneMember]:
    """The sources that make a callout's zone, each with its map to the placement twist.

    Parameters
    ----------
    callout : Callout
        The callout.
    refined : bool
        For a ``position`` callout: an orientation callout refines it on the same feature (the
        feature centre's disc replaces the two end discs; module docstring).
    zones : {"exact", "boxes"}
        Exact zones, or the independent-box rule.

    Returns
    -------
    list of ZoneMember
        Member sources in order; their errors are bounded by the callout's value t (a disc
        ``|e| <= t`` or an interval ``|e| <= t``), with the zone's factors in the matrices.

    Raises
    ------
    evotol.errors.ValidationError
        An unknown ``zones`` model or a bad axis.
    """
    if zones not in ZONE_MODELS:
        raise ValidationError("zones", zones, f"one of {ZONE_MODELS}")
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    e1, e2 = lateral_basis(a)
    E = np.stack([e1, e2], axis=1)                    # (3, 2) lateral directions
    s1, s2 = callout.ends
    L, nm = callout.length, callout.name
    p = callout.offset * a                             # feature centre
    zero = np.zeros((3, 2))
    if callout.kind == "axial":
        return [ZoneMember(nm, 1, _twist(a / 2, np.zeros(3))[:, None])]
    tilt = np.cross(a[None, :], E.T).T / L             # w = a x e / L per unit e (3, 2)
    about_centre = np.vstack([np.cross(p[None, :], tilt.T).T, tilt])   # v = p x w
    if zones == "boxes":
        cols = [("shift_e1", np.r_[e1 / 2, np.zeros(3)]), ("shift_e2", np.r_[e2 / 2, np.zeros(3)])] \
            if callout.kind == "position" else []
        # tilt +-t/L about e1, e2 (through the feature centre): w = e_k / L per unit e
        for lab, ek in (("tilt_e1", e1), ("tilt_e2", e2)):
            w = ek / L
            cols.append((lab, np.r_[np.cross(p, w), w]))
        return [ZoneMember(f"{nm}.{lab}", 1, c[:, None]) for lab, c in cols]
    if callout.kind in ORIENTATION_KINDS:
        return [ZoneMember(nm, 2, about_centre)]
    if refined:
        return [ZoneMember(nm, 2, np.vstack([E / 2, zero]))]
    # position: d1 = e1/2 at s1, d2 = e2/2 at s2; g = (d2 - d1)/L, v = (s2 d1 - s1 d2)/L, w = a x g
    end1 = np.vstack([E * s2 / (2 * L), -tilt / 2])
    end2 = np.vstack([-E * s1 / (2 * L), tilt / 2])
    return [ZoneMember(f"{nm}.end1", 2, end1), ZoneMember(f"{nm}.end2", 2, end2)]


def replaced_fields(callouts, axis) -> np.ndarray:
    """The placement directions a joint's callouts take over from raw placement sources.

    Position: the two lateral shifts and tilts; orientation: the two lateral tilts; axial: the
    shift along the axis.

    Parameters
    ----------
    callouts : sequence of Callout
        The joint's callouts.

    Returns
    -------
    (6, k) ndarray
        Orthonormal columns spanning the replaced twist directions ``[shift; tilt]``.
    """
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    e1, e2 = lateral_basis(a)
    z = np.zeros(3)
    cols = []
    for c in callouts:
        if c.kind == "position":
            cols += [np.r_[e1, z], np.r_[e2, z], np.r_[z, e1], np.r_[z, e2]]
        elif c.kind in ORIENTATION_KINDS:
            cols += [np.r_[z, e1], np.r_[z, e2]]
        else:
            cols.append(np.r_[a, z])
    if not cols:
        return np.zeros((6, 0))
    U, s, _ = np.linalg.svd(np.stack(cols, axis=1), full_matrices=False)
    return U[:, s > 1e-9]


def axis_displacement(delta, axis, s) -> np.ndarray:
    """Lateral displacement (m) of the axis point at ``s`` under a placement twist (first order).

    Parameters
    ----------
    delta : (..., 6) array_like
        Placement twists ``[shift (m); tilt (rad)]``.
    s : float
        Position along the axis from the placement origin (m).

    Returns
    -------
    (..., 2) ndarray
        Displacement along ``(e1, e2)`` of :func:`lateral_basis` (m).
    """
    d = np.asarray(delta, float)
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    E = np.stack(lateral_basis(a), axis=1)
    move = d[..., :3] + np.cross(d[..., 3:], s * a)
    return move @ E


def worst_axis_displacement(t: float, length: float, s: float, zones: str = "exact") -> float:
    """Largest lateral displacement (m) of an axis point ``s`` from the feature centre under a
    position zone ⌀t over ``length`` (closed form).

    Exact zone: ``d(s) = (1/2 - s/L) d1 + (1/2 + s/L) d2`` with ``|d_k| <= t/2``, so the largest is
    ``t/2 max(1, 2|s|/L)``; independent boxes: ``sqrt(2) (t/2 + |s| t/L)``.

    Parameters
    ----------
    t : float
        Zone diameter (m).
    length : float
        Feature length L (m).
    s : float
        Distance of the point from the feature centre along the axis (m).

    Returns
    -------
    float
        The largest displacement (m).

    Raises
    ------
    evotol.errors.ValidationError
        An unknown zone model.
    """
    if zones == "exact":
        return t / 2 * max(1.0, 2 * abs(s) / length)
    if zones == "boxes":
        return float(np.sqrt(2.0) * (t / 2 + abs(s) * t / length))
    raise ValidationError("zones", zones, f"one of {ZONE_MODELS}")

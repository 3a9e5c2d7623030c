"""Random error sources of a described mechanism, serial or closed-loop: what changes from one cycle to the
next (issue 44).

A **systematic** source (a DH or placement error, an encoder offset) is fixed per robot; a **random**
source draws anew at every cycle. Each random source acts through columns the mechanism's error model
already has (:class:`evotol.robots.mechanism.model.error_model.MechanismModel`: the joint's encoder offset, the three
shifts of the joint's placement), so the first-order map and the nonlinear ``pose_error`` serve both
kinds. The kinds, each with its tolerance ``t`` (the catalogue's figure) and its distribution:

``backlash``      lost motion of joint J about its axis, ``t = b`` (rad, total). Taken up from one
                  side, the joint lags its motion by a **fixed offset** ``-s b/2`` for the approach
                  direction ``s = ±1`` of the joint (it feeds AP and the multi-directional vAP, not RP), plus a **cycle-to-cycle
                  variation** uniform within ``± variation·b/2`` (it feeds RP). ``variation`` is the
                  share of the lost motion that is not taken up the same way every cycle (0.1 default).
``encoder``       encoder resolution of joint J, ``t = q`` (rad, one count, at the joint): the joint error
                  is uniform within ``± q/2`` (quantisation). From a catalogue's bits:
                  :func:`encoder_count` ``= 2π / (2^bits · gear_ratio)``.
``radial_play``   radial bearing play of joint J, ``t = c`` (m, diametral): the axis is displaced
                  uniformly within a disc of radius ``c/2`` perpendicular to the axis.
``axial_play``    axial bearing play of joint J, ``t = a`` (m, total): the axis slides uniformly within
                  ``± a/2`` along itself.

Backlash and encoder need an actuator: their joint is an actuated joint variable. Bearing play may sit
on any joint, actuated or **passive** (on a parallel mechanism the passive joints' play is the main
random source): its joint is an actuated joint variable or the name of a joint's frame, and it acts
through the three shifts of that joint's placement (:func:`play_columns`). On a closed-loop mechanism
the first-order map and ``pose_error`` close the loops, so every source moves the end effector as the
whole mechanism does (docs/iso9283.md, "Closed-loop mechanisms": checked against a closed-form Delta).

The direction of the joint axis in the joint's placement frame is read from the model itself (the
rotation of the encoder column and the translations of the shift columns at one configuration) for an
actuated joint with shift columns of its own name, so a URDF arm whose axes are not ``z`` is handled the
same way; for a joint's frame it is the frame's seat axis
(:func:`evotol.robots.mechanism.callouts.table.joint_seat`: the placement's z for a ``[[frame]]`` row).

Parameters
----------
robot : evotol.robots.mechanism.model.error_model.MechanismModel
    The mechanism; backlash and encoder name an actuated joint and need its encoder column (``J``);
    bearing play needs the shifts of the joint's placement (``<frame>.shift_x|y|z``) among the model's
    sources.
sources : sequence of RandomSource
    The random sources.
loadings : list of (n_columns, dim) ndarray
    Per source its :func:`column_loading`.
tolerances : (n_sources,) array_like
    Per source its tolerance (SI), possibly other than its own (an allocation's).
draws : list of (n, dim) ndarray
    Per source its :func:`unit_draws`.
signs : dict of str to float
    Joint -> sign of its approach motion (+1, -1, or 0 for a joint that does not move).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.mechanism.callouts.table import joint_seat

KINDS = ("backlash", "encoder", "radial_play", "axial_play")
UNITS = {"backlash": "rad", "encoder": "rad", "radial_play": "m", "axial_play": "m"}


@dataclass(frozen=True)
class RandomSource:
    """One random source of a described mechanism (module docstring: kinds, distributions).

    Parameters
    ----------
    kind : {"backlash", "encoder", "radial_play", "axial_play"}
        What moves from one cycle to the next.
    joint : str
        The joint it belongs to: an actuated joint variable (backlash, encoder, bearing play), or for
        bearing play also a joint's frame name (a passive joint of a closed loop, e.g. ``"2_1"``).
    tolerance : float
        The catalogue figure ``t`` (rad for backlash and encoder, m for bearing play), > 0.
    variation : float
        Backlash only: share of the lost motion that varies from cycle to cycle, in [0, 1].

    Raises
    ------
    evotol.errors.ValidationError
        An unknown kind, a tolerance that is not positive and finite, a variation outside [0, 1].
    """

    kind: str
    joint: str
    tolerance: float
    variation: float = 0.1

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValidationError("random source kind", self.kind, f"one of {KINDS}")
        if not (np.isfinite(self.tolerance) and self.tolerance > 0):
            raise ValidationError(f"random source {self.name} tolerance", self.tolerance, "a positive number (SI)")
        if not 0.0 <= self.variation <= 1.0:
            raise ValidationError(f"random source {self.name} variation", self.variation, "a share in [0, 1]")

    @property
    def name(self) -> str:
        """``"<joint>.<kind>"``, e.g. ``"elbow_joint.backlash"``."""
        return f"{self.joint}.{self.kind}"

    @property
    def unit(self) -> str:
        """``"rad"`` or ``"m"``."""
        return UNITS[self.kind]

    @property
    def dim(self) -> int:
        """Number of unit draws per cycle: 2 for radial play (a disc), else 1."""
        return 2 if self.kind == "radial_play" else 1


def encoder_count(bits: float, gear_ratio: float = 1.0) -> float:
    """One encoder count at the joint (rad): ``2π / (2^bits · gear_ratio)``.

    Parameters
    ----------
    bits : float
        Encoder resolution in bits per revolution of the shaft it sits on (> 0).
    gear_ratio : float
        Reduction between that shaft and the joint (1: encoder on the joint).

    Returns
    -------
    float
        The count (rad at the joint).

    Raises
    ------
    evotol.errors.ValidationError
        Bits or gear ratio not positive.

    Examples
    --------
    >>> round(encoder_count(14) * 1e6, 2)     # 14-bit encoder on the joint: 383.5 µrad
    383.5
    """
    if not (bits > 0 and gear_ratio > 0):
        raise ValidationError("encoder bits / gear_ratio", (bits, gear_ratio), "positive numbers")
    return float(2 * np.pi / (2.0 ** bits * gear_ratio))


def _axis_in_placement(robot, joint: str) -> tuple[np.ndarray, list[int]]:
    """The joint's unit axis in its placement frame and the columns of the frame's three shifts."""
    names = list(robot.source_names)
    shifts = [f"{joint}.shift_{a}" for a in "xyz"]
    missing = [s for s in shifts + [joint] if s not in names]
    if missing:
        raise ValidationError("random source joint columns", missing[0],
                              f"the model's sources to include {joint!r} and {joint}.shift_x|y|z (bearing play and the "
                              "axis direction are read from them)")
    q = robot.kin.assembly()[1]
    S = robot.sensitivity_at_joints({k: np.atleast_1d(v) for k, v in q.items()})[0]
    R = S[:3, [names.index(s) for s in shifts]]          # world directions of the placement's x, y, z
    axis = R.T @ S[3:, names.index(joint)]                # rotation of the joint, in the placement frame
    return axis / np.linalg.norm(axis), [names.index(s) for s in shifts]


def joint_frames(robot) -> dict:
    """The joints a bearing play may name besides the actuated variables: frame name -> its joint variable.

    Returns
    -------
    dict of str to str
        Every revolute or prismatic ``[[frame]]`` row (a URDF joint's row ``J__q`` under its origin's name
        ``J``) -> the name in its joint field (an expression for a coupled joint).
    """
    out = {}
    for f in robot.kin.mech.frames:
        if f.joint != "fixed":
            out[f.name[:-3] if f.name.endswith("__q") else f.name] = str(getattr(f, f.joint_field))
    return out


def _one_branch_of_mean(mech, frame: str) -> str | None:
    """``"P1 = mean of (E1, Eb1)"`` when ``frame`` lies on some but not all branches of a mean point, else None."""
    frames = {f.name: f for f in mech.frames}

    def chain(n):
        out = set()
        while n in frames and n not in out:
            out.add(n)
            n = frames[n].antecedent
        return out
    for pt in mech.points:
        on = [frame in chain(m) for m in pt.frames]
        if any(on) and not all(on):
            return f"{pt.name} = mean of {tuple(pt.frames)}"
    return None


def play_columns(robot, joint: str) -> tuple[np.ndarray, list[int]]:
    """The axis (in the placement frame) and the three shift columns through which a joint's bearing play acts.

    ``joint`` is an actuated variable with columns ``J`` and ``J.shift_x|y|z`` (a URDF arm: axis read from
    the model), or a joint's frame name, or an actuated variable whose frame is named otherwise (the Delta's
    ``q1_1`` turns frame ``1_1``): columns ``<frame>.shift_x|y|z``, axis the frame's seat axis.

    Parameters
    ----------
    joint : str
        An actuated joint variable or a joint's frame name (a passive joint of a closed loop, e.g. ``"2_1"``).

    Returns
    -------
    axis : (3,) ndarray
        Unit axis in the placement frame.
    cols : list of int
        Columns of the placement's shifts along its x, y, z (m).

    Raises
    ------
    evotol.errors.ValidationError
        Not a joint of the mechanism; a joint on one branch of a point closed at the mean of its branches (a
        rod of the Delta's parallelogram: its play would tilt the platform, which the midpoint closure does
        not model; measured against Clavel's six-rod model, docs/iso9283.md); or its shift columns not among
        the model's sources.
    """
    names = list(robot.source_names)
    if joint in robot.kin.actuated and f"{joint}.shift_x" in names:
        return _axis_in_placement(robot, joint)
    frames = joint_frames(robot)
    frame = joint if joint in frames else next((f for f, v in frames.items() if v == joint), None)
    if frame is None:
        raise ValidationError("random source joint", joint, f"an actuated joint {tuple(robot.kin.actuated)} or a "
                              f"joint's frame {tuple(frames)}")
    branch = _one_branch_of_mean(robot.kin.mech, frame)
    if branch:
        raise ValidationError(f"random source {joint} bearing play", frame, f"a joint on every branch or none of a "
                              f"point closed at the mean of its branches: {branch}, an over-constrained loop (e.g. a "
                              "parallelogram); play of one branch tilts the platform, which that closure does not model "
                              "(docs/iso9283.md, Closed-loop mechanisms)")
    shifts = [f"{frame}.shift_{a}" for a in "xyz"]
    missing = [s for s in shifts if s not in names]
    if missing:
        raise ValidationError("random source joint columns", missing[0], f"the model's sources to include "
                              f"{frame}.shift_x|y|z (the bearing play of {joint!r} moves its placement), e.g. "
                              f"[robot] sources = [..., \"{frame}.shift_?\"]")
    return joint_seat(robot.kin.mech, frame)["axis"], [names.index(s) for s in shifts]


def column_loading(robot, sources) -> list[np.ndarray]:
    """Per source: the matrix ``G`` (n_columns, dim) taking its unit draws to the model's columns.

    Backlash and encoder load the joint's encoder column with 1 (rad per rad); radial play loads
    the shifts with two unit vectors perpendicular to the axis; axial play with the axis.

    Returns
    -------
    list of (n_columns, dim) ndarray
        One per source, in order (m or rad per unit of the draw).

    Raises
    ------
    evotol.errors.ValidationError
        Backlash or encoder on a joint that is not actuated (they need an actuator), or a model without
        the joint's columns.
    """
    names = list(robot.source_names)
    out = []
    for s in sources:
        G = np.zeros((len(names), s.dim))
        if s.kind in ("backlash", "encoder"):
            if s.joint not in robot.kin.actuated:
                raise ValidationError(f"random source {s.name} joint", s.joint, f"an actuated joint of "
                                      f"{tuple(robot.kin.actuated)}: {s.kind} needs an actuator (bearing play, "
                                      "radial_play and axial_play, may sit on a passive joint)")
            if s.joint not in names:
                raise ValidationError("random source joint columns", s.joint, f"the model's sources to include {s.joint!r}")
            G[names.index(s.joint), 0] = 1.0
        else:
            a, cols = play_columns(robot, s.joint)
            if s.kind == "axial_play":
                G[cols, 0] = a
            else:
                e1 = np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0])
                e1 /= np.linalg.norm(e1)
                G[cols, 0], G[cols, 1] = e1, np.cross(a, e1)
        out.append(G)
    return out


def unit_draws(sources, n: int, rng) -> list[np.ndarray]:
    """Standardised cycle-to-cycle draws: per source (n, dim), to be scaled by its tolerance.

    Backlash ``U(-variation/2, variation/2)``, encoder ``U(-1/2, 1/2)``, axial ``U(-1/2, 1/2)``,
    radial uniform in the disc of radius 1/2 (``ρ = √U / 2``, ``φ ~ U(0, 2π)``).

    Parameters
    ----------
    n : int
        Number of cycles.
    rng : numpy.random.Generator
        The random generator.

    Returns
    -------
    list of (n, dim) ndarray
        Draws per unit tolerance (dimensionless).
    """
    out = []
    for s in sources:
        if s.kind == "radial_play":
            r, phi = 0.5 * np.sqrt(rng.random(n)), rng.uniform(0, 2 * np.pi, n)
            out.append(np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1))
        else:
            w = s.variation if s.kind == "backlash" else 1.0
            out.append(rng.uniform(-0.5, 0.5, (n, 1)) * w)
    return out


def cycle_errors(loadings, tolerances, draws) -> np.ndarray:
    """Column errors of the random sources for unit draws and tolerances: ``Σ_k t_k d_k G_kᵀ``.

    Returns
    -------
    (n, n_columns) ndarray
        Column errors per cycle (m or rad).
    """
    return sum(t * d @ G.T for G, t, d in zip(loadings, tolerances, draws))


def backlash_offset(sources, loadings, tolerances, signs) -> np.ndarray:
    """Fixed column errors (n_columns,) of lost motion taken up from one side: the joint lags its
    motion, ``-s_J b_J/2`` on each backlash joint, ``signs`` a dict joint -> ±1 (the sign of the joint's
    approach motion); ``tolerances`` the lost motion of each source (rad; others ignored).

    Returns
    -------
    (n_columns,) ndarray
        The offsets (rad).
    """
    out = np.zeros(loadings[0].shape[0]) if loadings else np.zeros(0)
    for s, G, t in zip(sources, loadings, tolerances):
        if s.kind == "backlash":
            out = out + G[:, 0] * -signs.get(s.joint, 1.0) * t / 2
    return out

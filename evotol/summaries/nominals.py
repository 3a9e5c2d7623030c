"""The nominal of each error source, where evotol knows it, and what that nominal is (issue 34
item 5: drawing-ready tables).

* an assembly's dimension (``evotol.robots.assembly``): its nominal, when the assembly was given one;
* a mechanism description's design parameter (``[lengths]``/``[angles]``): its value (for an arm
  read from a URDF: its joint origins' ``xyz``/``rpy``, ``elbow_joint_z``);
* a DH entry ``"<frame>.<gamma|b|alpha|d|theta|r>"`` whose expression uses design parameters only:
  the entry's value in the description (e.g. ``P1.d = "rp"`` → 0.05 m); an entry holding a joint
  variable varies with the pose and has no single nominal;
* a placement error ``"<frame>.shift_x"`` ... ``"<frame>.tilt_z"`` (:mod:`evotol.robots.mechanism.kinematics.placement`):
  0 -- the deviation is a small shift along / tilt about an axis of the frame's placement as the
  description (for an arm read from a URDF: the URDF joint origin) gives it, so the nominal is the
  URDF's (description's) value and the tolerance zone is about it;
* an actuator offset (encoder error): none -- the joint's value is commanded and varies with the
  pose; the zone is about it.

Values are SI (m or rad, the source's unit).
"""
from __future__ import annotations

import numpy as np

from evotol.robots.assembly import AssemblyFunction
from evotol.robots.base import RobotErrorModel
from evotol.robots.mechanism.kinematics.placement import PLACEMENT_FIELDS, SHIFT_FIELDS


def _nominals(robot, names) -> tuple[dict, dict]:
    """(values, notes) by source name (module docstring); ``names`` None: the robot's sources."""
    inner = robot.described if isinstance(robot, RobotErrorModel) else robot     # the robot as described
    names = list(getattr(robot, "source_names", ())) if names is None else list(names)
    if isinstance(inner, AssemblyFunction):
        if not inner.nominal_given:
            return {}, {}
        values = {n: float(v) for n, v in zip(inner.dimension_names, np.ravel(inner.x0))}
        return values, {n: "the assembly's nominal dimension" for n in values}
    if not isinstance(inner, RobotErrorModel) or not inner.joint_maps:     # no description to read nominals from
        return {}, {}
    mech = inner.mechanism
    params = {n: float(v) for table in (mech.lengths, mech.angles)
              for n, v in table.items() if np.isscalar(v)}
    values, notes = dict(params), {n: f"design parameter {n} of the description" for n in params}
    kin = inner.kin
    urdf = bool(mech.urdf)
    origin = "URDF joint origin" if urdf else "description's placement"
    for n in params:            # a URDF arm's parameters are its joint origins' xyz/rpy (robots/mechanism/urdf/reader.py)
        joint, _, k = n.rpartition("_")
        if urdf and k in ("x", "y", "z", "roll", "pitch", "yaw"):
            notes[n] = f"the URDF joint origin's {'xyz' if len(k) == 1 else 'rpy'} {k} of {joint}"
    for n in names:
        frame, _, field = n.partition(".")
        if n in kin.actuated:
            notes[n] = "actuator offset: deviation of the joint's zero (its value varies with the pose)"
        elif field in PLACEMENT_FIELDS:
            values[n] = 0.0
            what = "shift along" if field in SHIFT_FIELDS else "tilt about"
            notes[n] = f"0 = the {origin} of {frame}; the deviation is a {what} its {field[-1]} axis"
        elif (frame, field) in kin.expr:
            e = kin.expr[(frame, field)]
            if e.names <= set(params):
                values[n] = float(e(params))
                notes[n] = f"{field} of frame {frame} in the description ({e.text})"
            else:
                notes[n] = f"{field} of frame {frame} ({e.text}): varies with the pose"
    return values, notes


def nominals_with_notes(robot, names=None) -> tuple[dict[str, float], dict[str, str]]:
    """:func:`source_nominals` and :func:`nominal_notes` in one pass over the model.

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        As for :func:`source_nominals`.
    names : sequence of str, optional
        The sources asked about (default: the robot's).

    Returns
    -------
    values : dict of str to float
        Source name -> nominal value, m or rad (:func:`source_nominals`).
    notes : dict of str to str
        Source name -> what the nominal is (:func:`nominal_notes`).
    """
    return _nominals(robot, names)


def source_nominals(robot, names=None) -> dict[str, float]:
    """Nominal values (SI) of the sources where the model knows them (module docstring).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The problem's robot (an assembly function with ``dimension_names`` and ``x0``, or a model
        with a ``mechanism`` description), or a wrapper with the model in ``base``
        (:class:`evotol.measures.clearances.WithClearances`, a callout model; the clearance
        classes and callout zones have no nominal).
    names : sequence of str, optional
        The sources asked about (default: the robot's); a mechanism's design parameters are
        always given.

    Returns
    -------
    dict of str to float
        Source name -> nominal value, m or rad; empty when the model knows none (a
        :class:`evotol.robots.assembly.LinearStack` built without its nominals: 0 would be a made-up value).
    """
    return _nominals(robot, names)[0]


def nominal_notes(robot, names=None) -> dict[str, str]:
    """What each source's nominal is, in words: the description's entry, the URDF joint origin the
    deviation is about, or why there is no single nominal (module docstring).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        As for :func:`source_nominals`.
    names : sequence of str, optional
        The sources asked about (default: the robot's).

    Returns
    -------
    dict of str to str
        Source name -> one phrase (e.g. ``"0 = the URDF joint origin of elbow_joint; the deviation
        is a shift along its x axis"``); sources the model says nothing about are absent.
    """
    return _nominals(robot, names)[1]

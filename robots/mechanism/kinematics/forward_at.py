"""The forward kinematics of a description at given joint values, and a URDF's candidate end links.

``evotol check-mechanism FILE --at "10*deg, 10*deg, ..."`` prints where the end-effector is at
those joints (issue 33: a designer had no way to get the tool position at given joint values), and
``evotol check-mechanism arm.urdf`` without ``--tip`` lists the links that can be one.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.mechanism.model.joint_space import joint_configurations


def forward_at(model, text: str) -> dict:
    """The end-effector pose of a serial description at joint values written as text.

    Parameters
    ----------
    model : evotol.robots.mechanism.model.error_model.MechanismModel
        A serial arm.
    text : str
        Comma-separated joint values in the mechanism's joint order, each a number (SI: rad or m)
        or an expression (``"30*deg"``, ``"250*mm"``).

    Returns
    -------
    dict
        ``joints`` (name -> value, SI), ``units`` (name -> ``"rad"`` or ``"m"``), ``frame`` (the
        end-effector), ``position`` (m, base frame), ``rotation`` (3x3) and ``zyx`` (yaw, pitch,
        roll of ``R = Rz(yaw) Ry(pitch) Rx(roll)``, rad).

    Raises
    ------
    evotol.errors.ValidationError
        The wrong number of values, a value that is not a constant or outside the joint limits,
        or a mechanism with closed loops (``--at``).
    """
    parts = [p.strip() for p in str(text).split(",")]
    vals = [float(p) if _is_number(p) else p for p in parts]
    jm, Q = joint_configurations(model, [vals], where="--at")
    T = jm.tool_pose(Q)[0]
    R = T[:3, :3]
    zyx = (float(np.arctan2(R[1, 0], R[0, 0])), float(np.arcsin(np.clip(-R[2, 0], -1, 1))), float(np.arctan2(R[2, 1], R[2, 2])))
    return {"joints": dict(zip(jm.variables, Q[0].tolist())), "units": dict(zip(jm.variables, jm.workspace.units)),
            "frame": model.mechanism.end_effector, "position": T[:3, 3].tolist(), "rotation": R.tolist(), "zyx": list(zyx)}


def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def urdf_end_links(path) -> list[str]:
    """The links of a URDF that are the child of some joint and the parent of none: the candidates
    for ``--tip`` (a tool flange, a gripper's fingers...).

    Returns
    -------
    list of str
        Link names in file order.

    Raises
    ------
    evotol.errors.ValidationError
        A file that is not valid URDF XML.
    """
    try:
        root = ET.parse(str(path)).getroot()
    except (ET.ParseError, OSError) as exc:
        raise ValidationError("urdf file", str(path), f"a readable URDF ({exc})") from None
    parents = {j.find("parent").get("link") for j in root.findall("joint") if j.find("parent") is not None}
    children = [j.find("child").get("link") for j in root.findall("joint") if j.find("child") is not None]
    return [c for c in children if c not in parents]

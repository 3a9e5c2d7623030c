"""Serial arms from URDF, read with Pinocchio (``pip install pin``), into a mechanism description.

Why Pinocchio: it is the maintained reference implementation for URDF kinematics (BSD; used by
``example-robot-data``, whose UR and Panda URDFs we study), it resolves fixed joints into frame
placements the way robot software does, and its own forward kinematics is the independent check
of ours (``tests/test_mechanism_urdf.py``: 1e-12).

Every joint ``J`` of the chain from the root to the ``tip`` frame becomes rows of the modified-DH
table: its origin (the placement of the joint in its parent joint's frame, fixed joints folded in)
as a translation ``Tz(J_z) Tx(J_x) Ty(J_y)`` and a rotation ``Rz(J_yaw) Ry(J_pitch) Rx(J_roll)``
(URDF's ``xyz``/``rpy``, design parameters in ``[lengths]``/``[angles]``) ending in a fixed frame
``J`` (the joint frame before its motion), then the joint about (along) its axis, any direction,
with the variable ``J``. The error sources by default are each origin's placement errors
``J.shift_x ... J.tilt_z`` (:mod:`robots.mechanism.placement`, Pinocchio's placement-regressor
convention) and the joint offsets ``J``; ``docs/mechanisms.md`` states the conventions.

In a description file: ``urdf = "arm.urdf"`` (relative to the file) or
``urdf = "example-robot-data:ur_description/urdf/ur5_robot.urdf"`` (a file shipped in a pip
package's ``cmeel.prefix/share/<package>/robots``), ``tip = "tool0"``, instead of ``[[frame]]``.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from evotol.errors import ValidationError
from robots.mechanism.placement import PLACEMENT_FIELDS

AXIS_NAMES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def _pin():
    try:
        import pinocchio
    except ImportError:
        raise ValidationError("urdf", "pinocchio", "the 'pin' package installed (a dependency of evotol: pip install evotol)") from None
    return pinocchio


#: URDFs shipped with evotol (``robots/urdf/``, copies from example-robot-data 6.0.0 with their licences)
SHIPPED_URDF_DIR = Path(__file__).resolve().parent.parent / "urdf"


def resolve_urdf(name: str, base_dir=None) -> Path:
    """The file a description's ``urdf = ...`` names.

    Parameters
    ----------
    name : str
        A path (relative paths are tried against ``base_dir`` first), or
        ``"<pip package>:<path under its robots folder>"`` such as
        ``"example-robot-data:ur_description/urdf/ur5_robot.urdf"``. For the ``example-robot-data``
        files evotol ships (``robots/urdf/``: the UR5 and the Panda, byte-identical to 6.0.0), the
        shipped copy is used, so a result does not depend on which version of that package is
        installed; any other file is taken from the installed package.
    base_dir : path-like, optional
        Folder of the description file.

    Returns
    -------
    pathlib.Path
        An existing file.

    Raises
    ------
    ValidationError
        ``urdf``: the package is not installed (and no shipped copy exists) or the file does not exist.
    """
    if ":" in name and not Path(name).exists():
        import importlib.metadata as md

        pkg, _, rel = name.partition(":")
        shipped = SHIPPED_URDF_DIR / rel if pkg == "example-robot-data" else None
        if shipped is not None and shipped.is_file():
            return shipped
        try:
            dist = md.distribution(pkg)
        except md.PackageNotFoundError:
            have = (f"; evotol ships {', '.join(sorted(str(p.relative_to(SHIPPED_URDF_DIR)) for p in SHIPPED_URDF_DIR.rglob('*.urdf')))}"
                    if shipped is not None else "")
            raise ValidationError("urdf", name, f"an installed package {pkg!r} (pip install {pkg}){have}") from None
        p = Path(dist.locate_file(f"cmeel.prefix/share/{pkg}/robots/{rel}"))
    else:
        p = Path(name)
        if base_dir and not p.is_absolute() and (Path(base_dir) / p).exists():
            p = Path(base_dir) / p
    if not p.is_file():
        raise ValidationError("urdf", name, "an existing URDF file")
    return p


def _ident(name: str) -> str:
    s = re.sub(r"\W", "_", name)
    return s if s and not s[0].isdigit() else f"j_{s}"


def _origin_rows(prefix: str, antecedent: str, M, lengths: dict, angles: dict, pin) -> list[dict]:
    """Rows Tz(z) Tx(x) Ty(y) Rz(yaw) Ry(pitch) Rx(roll) for a placement M (pinocchio SE3); the
    last row, a fixed frame named ``prefix``, is the placement itself (its errors:
    :mod:`robots.mechanism.placement`)."""
    x, y, z = (float(v) for v in M.translation)
    roll, pitch, yaw = (float(v) for v in pin.rpy.matrixToRpy(M.rotation))
    for k, v in zip("xyz", (x, y, z)):
        lengths[f"{prefix}_{k}"] = v
    for k, v in zip(("roll", "pitch", "yaw"), (roll, pitch, yaw)):
        angles[f"{prefix}_{k}"] = v
    return [
        {"name": f"{prefix}__t", "antecedent": antecedent, "b": f"{prefix}_z", "d": f"{prefix}_x", "theta": "pi/2"},
        {"name": f"{prefix}__ty", "antecedent": f"{prefix}__t", "d": f"{prefix}_y", "theta": "-pi/2"},
        {"name": f"{prefix}__rzy", "antecedent": f"{prefix}__ty", "gamma": f"{prefix}_yaw + pi/2", "alpha": f"{prefix}_pitch",
         "theta": "-pi/2"},
        {"name": prefix, "antecedent": f"{prefix}__rzy", "alpha": f"{prefix}_roll"},
    ]


def joint_axis(model, j: int) -> tuple[str, np.ndarray]:
    """('revolute' | 'prismatic', unit axis in the joint frame) of Pinocchio joint ``j``; continuous
    joints are revolute (one angle, Pinocchio's (cos, sin) pair)."""
    short = model.joints[j].shortname()
    m = re.fullmatch(r"JointModel(R|P)(?:UB)?([XYZ])", short)
    if m:
        kind, ax = m.groups()
        return ("revolute" if kind == "R" else "prismatic"), np.array(AXIS_NAMES[ax])
    m = re.fullmatch(r"JointModel(Revolute|Prismatic)(?:Unbounded)?Unaligned(?:Tpl)?", short)
    if m:
        a = np.asarray(model.joints[j].extract().axis, float)
        return m.group(1).lower(), a / np.linalg.norm(a)
    raise ValidationError(f"urdf joint {model.names[j]!r}", short,
                          "a revolute, continuous or prismatic joint (floating and planar joints are not a serial chain's)")


def axis_angles(a: np.ndarray) -> tuple[float, float]:
    """(gamma, alpha) with Rot(z, gamma) Rot(x, alpha) e_z = a (a unit vector)."""
    alpha = float(np.arccos(np.clip(a[2], -1.0, 1.0)))
    gamma = float(np.arctan2(a[0], -a[1])) if np.hypot(a[0], a[1]) > 1e-15 else 0.0
    return gamma, alpha


def _along_axis(kind: str, a: np.ndarray) -> str | None:
    """The placement error a joint offset duplicates, when the axis is a coordinate axis (else None)."""
    k = int(np.argmax(np.abs(a)))
    if abs(abs(a[k]) - 1.0) > 1e-12:
        return None
    return ("tilt_" if kind == "revolute" else "shift_") + "xyz"[k]


def urdf_frames(path, tip: str) -> tuple[list[dict], dict, dict, dict]:
    """(frame rows, lengths, angles, info) of the chain root -> ``tip`` of a URDF.

    Per joint ``J``: origin rows ending in the fixed frame ``J`` (the joint's origin, URDF
    ``<origin>``), the joint row ``J__q`` turning about (sliding along) the URDF axis with the
    variable ``J``, and for an axis other than +z a row ``J__back`` that restores the origin's axes.

    info: ``model`` (pinocchio Model), ``tip_frame_id``, ``joints`` (names in chain order),
    ``variables`` (joint variable names in the description), ``tip`` (the description frame that
    equals the URDF tip frame) and ``default_sources``: per joint the six placement errors of its
    origin and its joint offset, less the one placement error the offset duplicates (the rotation
    about a revolute joint's own axis, the translation along a prismatic joint's), when the axis
    is a coordinate axis of the origin -- the span of Pinocchio's joint placement regressor."""
    pin = _pin()
    try:
        model = pin.buildModelFromUrdf(str(path))
    except (RuntimeError, ValueError) as exc:
        raise ValidationError("urdf", str(path), f"a URDF Pinocchio can read ({exc})") from None
    if not model.existFrame(tip):
        raise ValidationError("tip", tip, f"a link or frame of {Path(path).name}: {[f.name for f in model.frames][:40]}")
    fid = model.getFrameId(tip)
    chain, j = [], model.frames[fid].parentJoint
    while j > 0:
        chain.append(j)
        j = model.parents[j]
    chain.reverse()
    rows, lengths, angles, names, variables, sources = [], {}, {}, [], [], []
    ant = "0"
    for j in chain:
        jname = _ident(model.names[j])
        kind, a = joint_axis(model, j)
        rows += _origin_rows(jname, ant, model.jointPlacements[j], lengths, angles, pin)
        gamma, alpha = axis_angles(a)
        joint_row = {"name": f"{jname}__q", "antecedent": jname, "joint": kind, "actuated": True,
                     ("theta" if kind == "revolute" else "r"): jname}
        if gamma or alpha:
            joint_row.update(gamma=gamma, alpha=alpha)
        rows.append(joint_row)
        ant = f"{jname}__q"
        if gamma or alpha:
            rows.append({"name": f"{jname}__back", "antecedent": ant, "alpha": -alpha, "theta": -gamma})
            ant = f"{jname}__back"
        dup = _along_axis(kind, a)
        sources += [f"{jname}.{k}" for k in PLACEMENT_FIELDS if k != dup] + [jname]
        names.append(model.names[j])
        variables.append(jname)
    tname = _ident(tip)
    rows += _origin_rows(tname, ant, model.frames[fid].placement, lengths, angles, pin)
    return rows, lengths, angles, {"model": model, "tip_frame_id": fid, "joints": names, "variables": variables, "tip": tname,
                                   "default_sources": sources}


def pinocchio_tip_pose(path, tip: str, q: np.ndarray) -> np.ndarray:
    """Pinocchio's own forward kinematics of the tip frame, (n, 4, 4), for joint values (n, nq)."""
    pin = _pin()
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    fid = model.getFrameId(tip)
    out = []
    for qi in np.atleast_2d(q):
        pin.framesForwardKinematics(model, data, np.asarray(qi, float))
        out.append(data.oMf[fid].homogeneous.copy())
    return np.array(out)

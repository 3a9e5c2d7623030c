"""Serial arms from URDF, read with Pinocchio (``pip install pin``), into a mechanism description.

Why Pinocchio: it is the maintained reference implementation for URDF kinematics (BSD; used by
``example-robot-data``, whose UR and Panda URDFs we study), it resolves fixed joints into frame
placements the way robot software does, and its own forward kinematics is the independent check
of ours (``tests/test_mechanism_urdf.py``: 1e-12).

Every joint ``J`` of the chain from the root to the ``tip`` frame becomes rows of the modified-DH
table: its origin (the placement of the joint in its parent joint's frame, fixed joints folded in)
as a translation ``Tz(J_z) Tx(J_x) Ty(J_y)`` and a rotation ``Rz(J_yaw) Ry(J_pitch) Rx(J_roll)``
(URDF's ``xyz``/``rpy``), then the joint about (along) its axis with the variable ``J``. The twelve
numbers ``J_x ... J_yaw`` are **design parameters** in ``[lengths]``/``[angles]`` -- the link-length
and link-angle errors -- and the joint variables are actuated (their sources are the joint
offsets / encoder errors). The tip's own placement gets parameters ``<tip>_x ...`` too.

In a description file: ``urdf = "arm.urdf"`` (relative to the file) or
``urdf = "example-robot-data:ur_description/urdf/ur5_robot.urdf"`` (a file shipped in a pip
package's ``cmeel.prefix/share/<package>/robots``), ``tip = "tool0"``, instead of ``[[frame]]``.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from evotol.errors import ValidationError

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


def _origin_rows(prefix: str, antecedent: str, M, lengths: dict, angles: dict, pin) -> tuple[list[dict], str]:
    """Rows Tz(z) Tx(x) Ty(y) Rz(yaw) Ry(pitch) Rx(roll) for a placement M (pinocchio SE3)."""
    x, y, z = (float(v) for v in M.translation)
    roll, pitch, yaw = (float(v) for v in pin.rpy.matrixToRpy(M.rotation))
    for k, v in zip("xyz", (x, y, z)):
        lengths[f"{prefix}_{k}"] = v
    for k, v in zip(("roll", "pitch", "yaw"), (roll, pitch, yaw)):
        angles[f"{prefix}_{k}"] = v
    rows = [
        {"name": f"{prefix}__t", "antecedent": antecedent, "b": f"{prefix}_z", "d": f"{prefix}_x", "theta": "pi/2"},
        {"name": f"{prefix}__ty", "antecedent": f"{prefix}__t", "d": f"{prefix}_y", "theta": "-pi/2"},
        {"name": f"{prefix}__rzy", "antecedent": f"{prefix}__ty", "gamma": f"{prefix}_yaw + pi/2", "alpha": f"{prefix}_pitch",
         "theta": "-pi/2"},
        {"name": f"{prefix}__rx", "antecedent": f"{prefix}__rzy", "alpha": f"{prefix}_roll"},
    ]
    return rows, f"{prefix}__rx"


def urdf_frames(path, tip: str) -> tuple[list[dict], dict, dict, dict]:
    """(frame rows, lengths, angles, info) of the chain root -> ``tip`` of a URDF.

    info: ``model`` (pinocchio Model), ``tip_frame_id``, ``joints`` (names in chain order),
    ``variables`` (joint variable names in the description) and ``tip`` (the description frame
    that equals the URDF tip frame)."""
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
    rows, lengths, angles, names, variables = [], {}, {}, [], []
    ant = "0"
    for j in chain:
        jname = _ident(model.names[j])
        short = model.joints[j].shortname()
        m = re.fullmatch(r"JointModel(R|P)(?:UB)?([XYZ])", short)
        if m is None:
            raise ValidationError(f"urdf joint {model.names[j]!r}", short, "a revolute, continuous or prismatic joint about x, y or z")
        kind, ax = m.groups()
        if model.nqs[j] != 1:
            raise ValidationError(f"urdf joint {model.names[j]!r}", short, "a joint with one configuration variable "
                                                                          "(continuous joints are read as revolute)")
        r, ant = _origin_rows(jname, ant, model.jointPlacements[j], lengths, angles, pin)
        rows += r
        pre = {"X": {"gamma": "pi/2", "alpha": "pi/2"}, "Y": {"alpha": "-pi/2"}, "Z": {}}[ax]
        post = {"X": {"alpha": "-pi/2", "theta": "-pi/2"}, "Y": {"alpha": "pi/2"}, "Z": None}[ax]
        if pre:
            rows.append({"name": f"{jname}__axis", "antecedent": ant, **pre})
            ant = f"{jname}__axis"
        joint_row = {"name": jname, "antecedent": ant, "joint": "revolute" if kind == "R" else "prismatic", "actuated": True,
                     ("theta" if kind == "R" else "r"): jname}
        rows.append(joint_row)
        ant = jname
        if post:
            rows.append({"name": f"{jname}__back", "antecedent": ant, **post})
            ant = f"{jname}__back"
        names.append(model.names[j])
        variables.append(jname)
    tname = _ident(tip)
    r, ant = _origin_rows(tname, ant, model.frames[fid].placement, lengths, angles, pin)
    rows += r
    rows.append({"name": tname, "antecedent": ant})
    return rows, lengths, angles, {"model": model, "tip_frame_id": fid, "joints": names, "variables": variables, "tip": tname}


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

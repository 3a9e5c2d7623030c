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
``J.shift_x ... J.tilt_z`` (:mod:`evotol.robots.mechanism.kinematics.placement`, Pinocchio's placement-regressor
convention) and the joint offsets ``J``; ``docs/mechanisms.md`` states the conventions.

In a description file: ``urdf = "arm.urdf"`` (relative to the file) or
``urdf = "example-robot-data:ur_description/urdf/ur5_robot.urdf"`` (a file shipped in a pip
package's ``cmeel.prefix/share/<package>/robots``), ``tip = "tool0"``, instead of ``[[frame]]``.

The parameters several definitions of this module share are described once, here.

Parameters
----------
model : pinocchio.Model
    The model built from the URDF.
"""
from __future__ import annotations

import difflib
import re
from pathlib import Path

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.mechanism.kinematics.placement import PLACEMENT_FIELDS

AXIS_NAMES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def _pin():
    try:
        import pinocchio
    except ImportError:
        raise ValidationError("urdf", "pinocchio", "the 'pin' package installed (a dependency of evotol: pip install evotol)") from None
    return pinocchio


#: URDFs shipped with evotol (``robots/urdf/``, copies from example-robot-data 6.0.0 with their licences)
SHIPPED_URDF_DIR = Path(__file__).resolve().parents[2] / "urdf"


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
            extra = ' (pip install "evotol[urdf]", or pip install example-robot-data)' if shipped is not None \
                else f" (pip install {pkg})"
            raise ValidationError("urdf", name, f"an installed package {pkg!r}{extra}{have}") from None
        share = dist.metadata["Name"] or pkg        # the package's own spelling (example_robot_data -> example-robot-data)
        root = Path(dist.locate_file(f"cmeel.prefix/share/{share}/robots"))
        p = root / rel
        if not p.is_file():
            files = [str(f.relative_to(root)) for f in root.rglob("*.urdf")] if root.is_dir() else []
            near = difflib.get_close_matches(rel, files, 3, 0.5)
            raise ValidationError("urdf", name, f"a URDF file of the installed package {share!r} "
                                  + (f"(nearest: {', '.join(near)})" if near else
                                     f"({len(files)} URDF files under {root})" if files else
                                     f"(it has no robots folder at {root}: is it the package that ships the file?)"))
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
    :mod:`evotol.robots.mechanism.kinematics.placement`)."""
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
    joints are revolute (one angle, Pinocchio's (cos, sin) pair).

    Parameters
    ----------
    j : int
        Pinocchio joint id (1 .. ``model.njoints - 1``).

    Returns
    -------
    kind : {"revolute", "prismatic"}
        The joint type.
    axis : (3,) ndarray
        Unit vector of the joint axis in the joint frame (dimensionless).

    Raises
    ------
    evotol.errors.ValidationError
        Any other joint model (floating, planar, spherical...): not a serial chain's joint.
    """
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
    """(gamma, alpha) with Rot(z, gamma) Rot(x, alpha) e_z = a (a unit vector).

    Parameters
    ----------
    a : (3,) ndarray
        Unit axis vector (dimensionless).

    Returns
    -------
    gamma : float
        Rotation about z (rad), in ``(-pi, pi]``; 0 when ``a`` is along z.
    alpha : float
        Rotation about the new x (rad), in ``[0, pi]``.
    """
    alpha = float(np.arccos(np.clip(a[2], -1.0, 1.0)))
    gamma = float(np.arctan2(a[0], -a[1])) if np.hypot(a[0], a[1]) > 1e-15 else 0.0
    return gamma, alpha


def _along_axis(kind: str, a: np.ndarray) -> str | None:
    """The placement error a joint offset duplicates, when the axis is a coordinate axis (else None)."""
    k = int(np.argmax(np.abs(a)))
    if abs(abs(a[k]) - 1.0) > 1e-12:
        return None
    return ("tilt_" if kind == "revolute" else "shift_") + "xyz"[k]


def urdf_joints(path) -> dict:
    """The URDF's joints as written: ``{name: {"type", "mimic": (leader, multiplier, offset) | None,
    "limit": (lower, upper) | None}}`` (``<limit>`` of revolute and prismatic joints; continuous
    joints have none; SI as in URDF).

    Returns
    -------
    dict of str to dict
        Joint name as written -> ``{"type": str, "mimic": (leader, multiplier, offset) or None,
        "limit": (lower, upper) or None}``: limits in rad (revolute) or m (prismatic), the
        multiplier dimensionless, the offset in the joint's unit. Joints without a name or type
        are skipped.

    Raises
    ------
    evotol.errors.ValidationError
        A file that is not well-formed XML.
    """
    import xml.etree.ElementTree as ET

    try:
        root = ET.parse(str(path)).getroot()
    except ET.ParseError as exc:
        raise ValidationError("urdf", str(path), f"well-formed XML ({exc})") from None
    out = {}
    for j in root.iter("joint"):
        name, typ = j.get("name"), j.get("type")
        if name is None or typ is None:
            continue
        mim = j.find("mimic")
        mimic = None if mim is None else (mim.get("joint"), float(mim.get("multiplier", 1.0)), float(mim.get("offset", 0.0)))
        lim = j.find("limit")
        limit = None
        if typ in ("revolute", "prismatic") and lim is not None and lim.get("lower") is not None and lim.get("upper") is not None:
            limit = (float(lim.get("lower")), float(lim.get("upper")))
        out[name] = {"type": typ, "mimic": mimic, "limit": limit}
    return out


def frame_id(model, name: str) -> int:
    """Pinocchio's id of frame ``name``: the link (BODY) when a link and a joint share the name.

    Frame types are tried in the order BODY, OP_FRAME, FIXED_JOINT, JOINT, then any.

    Parameters
    ----------
    name : str
        Name of a link, operational frame or joint.

    Returns
    -------
    int
        Index into ``model.frames`` (for an unknown name, whatever Pinocchio's
        ``getFrameId`` returns: callers check ``existFrame`` first).

    Raises
    ------
    evotol.errors.ValidationError
        Pinocchio (package ``pin``) is not installed.
    """
    pin = _pin()
    for kind in (pin.FrameType.BODY, pin.FrameType.OP_FRAME, pin.FrameType.FIXED_JOINT, pin.FrameType.JOINT):
        if model.existFrame(name, kind):
            return model.getFrameId(name, kind)
    return model.getFrameId(name)


def chain_joints(model, frame_id: int) -> list[int]:
    """Pinocchio joint ids from the root to the joint that carries frame ``frame_id``.

    Parameters
    ----------
    frame_id : int
        Index into ``model.frames``.

    Returns
    -------
    list of int
        Joint ids, root side first (the universe joint 0 excluded); empty for a frame fixed to
        the root.
    """
    chain, j = [], model.frames[frame_id].parentJoint
    while j > 0:
        chain.append(j)
        j = model.parents[j]
    return chain[::-1]


def urdf_frames(path, tip: str) -> tuple[list[dict], dict, dict, dict]:
    """(frame rows, lengths, angles, info) of the chain root -> ``tip`` of a URDF.

    Per joint ``J``: origin rows ending in the fixed frame ``J`` (the joint's origin, URDF
    ``<origin>``), the joint row ``J__q`` turning about (sliding along) the URDF axis, any
    direction, with the variable ``J``, and for an axis other than +z a row ``J__back`` that
    restores the origin's axes. A mimic joint ``J`` of ``L`` has no variable of its own: its row
    holds ``J_multiplier * L + J_offset`` (both design parameters, so their errors are sources).

    info: ``model`` (pinocchio Model), ``tip_frame_id``, ``joints`` (names in chain order),
    ``variables`` (joint variable names), ``mimic`` (``{joint: (leader variable, multiplier,
    offset)}``), ``limits`` (``{variable: (lower, upper)}`` from ``<limit>``, a mimic joint's range
    carried over to its leader), ``tip`` (the description frame that equals the URDF tip frame) and
    ``default_sources``: per joint the six placement errors of its origin and its joint offset (a
    mimic joint: its offset; its multiplier ``J_multiplier`` is a source on request), less the one placement error the offset duplicates
    (the rotation about a revolute joint's own axis, the translation along a prismatic joint's),
    when the axis is a coordinate axis of the origin -- the span of Pinocchio's joint placement
    regressor.

    Parameters
    ----------
    tip : str
        The end-effector link or frame (e.g. ``"tool0"``).

    Returns
    -------
    rows : list of dict
        The modified-DH rows as ``[[frame]]`` tables (numbers in m, rad, or expression strings).
    lengths : dict of str to float
        Design lengths (m): each origin's ``J_x``, ``J_y``, ``J_z`` (and a prismatic mimic
        joint's ``J_offset``).
    angles : dict of str to float
        Design angles (rad): each origin's ``J_roll``, ``J_pitch``, ``J_yaw``, a revolute mimic
        joint's ``J_offset`` and every mimic ``J_multiplier`` (dimensionless).
    info : dict
        As described above.

    Raises
    ------
    evotol.errors.ValidationError
        Pinocchio not installed, a file Pinocchio cannot read or that is not well-formed XML,
        an unknown tip or one no joint moves, or a joint on the chain that is not revolute,
        continuous or prismatic.
    """
    pin = _pin()
    try:
        model = pin.buildModelFromUrdf(str(path))
    except (RuntimeError, ValueError) as exc:
        raise ValidationError("urdf", str(path), f"a URDF Pinocchio can read ({exc})") from None
    if not model.existFrame(tip):
        raise ValidationError("tip", tip, f"a link or frame of {Path(path).name}: {[f.name for f in model.frames][:40]}")
    written = urdf_joints(path)
    fid = frame_id(model, tip)
    chain = chain_joints(model, fid)
    if not chain:
        raise ValidationError("tip", tip, f"a frame that a joint of {Path(path).name} moves (this one is fixed to the root)")
    rows, lengths, angles, names, variables, sources, mimic, limits = [], {}, {}, [], [], [], {}, {}
    ant = "0"
    for j in chain:
        jname = _ident(model.names[j])
        kind, a = joint_axis(model, j)
        rows += _origin_rows(jname, ant, model.jointPlacements[j], lengths, angles, pin)
        gamma, alpha = axis_angles(a)
        w = written.get(model.names[j], {})
        dup = _along_axis(kind, a)
        if w.get("mimic"):
            leader, mult, off = w["mimic"]
            var = _ident(leader)
            angles[f"{jname}_multiplier"] = mult
            (lengths if kind == "prismatic" else angles)[f"{jname}_offset"] = off
            value = f"{jname}_multiplier * {var} + {jname}_offset"
            mimic[jname] = (var, mult, off)
            own = [f"{jname}_offset"]           # the multiplier's error: a source on request (dimensionless)
            if w.get("limit") and mult != 0:
                lo, hi = sorted(((w["limit"][0] - off) / mult, (w["limit"][1] - off) / mult))
                plo, phi = limits.get(var, (-np.inf, np.inf))
                limits[var] = (max(lo, plo), min(hi, phi))
        else:
            var, value, own = jname, jname, [jname]
            if w.get("limit"):
                plo, phi = limits.get(var, (-np.inf, np.inf))
                limits[var] = (max(w["limit"][0], plo), min(w["limit"][1], phi))
        joint_row = {"name": f"{jname}__q", "antecedent": jname, "joint": kind, "actuated": True,
                     ("theta" if kind == "revolute" else "r"): value}
        if gamma or alpha:
            joint_row.update(gamma=gamma, alpha=alpha)
        rows.append(joint_row)
        ant = f"{jname}__q"
        if gamma or alpha:
            rows.append({"name": f"{jname}__back", "antecedent": ant, "alpha": -alpha, "theta": -gamma})
            ant = f"{jname}__back"
        sources += [f"{jname}.{k}" for k in PLACEMENT_FIELDS if k != dup] + own
        names.append(model.names[j])
        if var not in variables:
            variables.append(var)
    tname = _ident(tip)
    if any(r["name"] == tname for r in rows):
        tname = f"{tname}__tip"
    rows += _origin_rows(tname, ant, model.frames[fid].placement, lengths, angles, pin)
    return rows, lengths, angles, {"model": model, "tip_frame_id": fid, "joints": names, "variables": variables, "tip": tname,
                                   "default_sources": sources, "mimic": mimic, "limits": limits}


def pinocchio_configuration(model, chain_values: dict, mimic: dict | None = None) -> np.ndarray:
    """Pinocchio's ``q`` (n, model.nq) for joint values ``{joint name: (n,)}`` (rad, m; other joints
    at 0): a continuous joint's angle becomes its (cos, sin) pair, a mimic joint ``{name: (leader,
    multiplier, offset)}`` follows its leader.

    Parameters
    ----------
    chain_values : dict of str to (n,) array_like
        Joint variable (the description's identifier of the URDF joint name) -> values (rad or
        m); at least one entry, whose length sets ``n``.
    mimic : dict or None, optional
        Mimic joint identifier -> (leader variable, multiplier, offset), as ``info["mimic"]`` of
        :func:`urdf_frames`; None: no mimic joints.

    Returns
    -------
    (n, model.nq) ndarray
        Pinocchio configurations; joints without a value at 0 (a continuous joint at angle 0:
        ``(1, 0)``).
    """
    n = len(np.atleast_1d(next(iter(chain_values.values()))))
    vals = {k: np.broadcast_to(np.asarray(v, float), (n,)) for k, v in chain_values.items()}
    for jn, (leader, m, o) in (mimic or {}).items():
        if leader in vals:
            vals[jn] = m * vals[leader] + o
    Q = np.zeros((n, model.nq))
    for j in range(1, model.njoints):
        i, nq = model.idx_qs[j], model.nqs[j]
        v = vals.get(_ident(model.names[j]))
        if nq == 2:
            a = np.zeros(n) if v is None else v
            Q[:, i], Q[:, i + 1] = np.cos(a), np.sin(a)
        elif nq == 1 and v is not None:
            Q[:, i] = v
    return Q


def pinocchio_tip_pose(path, tip: str, q) -> np.ndarray:
    """Pinocchio's own forward kinematics of the tip frame, (n, 4, 4): ``q`` is an array (n, nq)
    of Pinocchio configurations, or a dict of the description's joint values (see
    :func:`pinocchio_configuration`; mimic joints follow their leaders).

    Parameters
    ----------
    tip : str
        The tip link or frame.
    q : (n, nq) array_like or dict of str to (n,) array_like
        Pinocchio configurations, or the description's joint values (rad or m).

    Returns
    -------
    (n, 4, 4) ndarray
        Homogeneous transforms of the tip frame in the root frame (position in m).

    Raises
    ------
    evotol.errors.ValidationError
        Pinocchio (package ``pin``) is not installed.
    """
    pin = _pin()
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    fid = frame_id(model, tip)
    if isinstance(q, dict):
        written = urdf_joints(path)
        mim = {_ident(n): (_ident(w["mimic"][0]), w["mimic"][1], w["mimic"][2]) for n, w in written.items() if w["mimic"]}
        q = pinocchio_configuration(model, q, mim)
    out = []
    for qi in np.atleast_2d(q):
        pin.framesForwardKinematics(model, data, np.asarray(qi, float))
        out.append(data.oMf[fid].homogeneous.copy())
    return np.array(out)


def pinocchio_placement_regressor(model, frame_id: int, Q: np.ndarray, with_tip: bool = False) -> np.ndarray:
    """Pinocchio's joint placement regressor of a frame, (n, 6, 6 (njoints - 1)) [+ 6 tip columns].

    Parameters
    ----------
    frame_id : int
        Index into ``model.frames`` of the frame.
    Q : ndarray (n, model.nq)
        Pinocchio configurations.
    with_tip : bool
        Append the frame's own placement twist (``[R 0; 0 R]`` in ``LOCAL_WORLD_ALIGNED``).

    Returns
    -------
    ndarray
        ``[v; omega]`` of the frame per unit twist of each joint placement (local, ``M exp(delta)``).
    """
    pin = _pin()
    data = model.createData()
    out = []
    for q in np.atleast_2d(Q):
        pin.framesForwardKinematics(model, data, q)
        R = pin.computeFrameKinematicRegressor(model, data, frame_id, pin.LOCAL_WORLD_ALIGNED)
        if with_tip:
            tip = np.zeros((6, 6))
            tip[:3, :3] = tip[3:, 3:] = data.oMf[frame_id].rotation
            R = np.hstack([R, tip])
        out.append(R)
    return np.array(out)

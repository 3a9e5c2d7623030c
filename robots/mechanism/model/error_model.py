"""The error model of a described mechanism: a :class:`evotol.robots.base.RobotErrorModel` built from data.

Sources (intervals) are generated from the description by name or pattern
(:mod:`evotol.robots.mechanism.model.sources`): design parameters, actuator offsets, DH entries and placement
errors.

Sensitivity (first order, loop constraints eliminated): with the actuated joints held, the loop
equations ``h(q_p, e) = 0`` give ``dq_p = -H_p^+ H_e de`` and the end-effector moves by
``J_e de + J_p dq_p``, so ``S = J_e - J_p H_p^+ H_e`` -- every matrix from
:meth:`Kinematics.frame_jacobian` (exact derivatives of the DH tree). Where the passive joints do
not determine the end-effector (a type-2 / parallel singularity) or a source would open a loop
that no passive joint can close (an over-constrained loop), a :class:`KinematicsError` names the
pose. ``pose_error`` re-solves the loops with the perturbed description (Newton on the passive
joints, actuated joints held), so :func:`evotol.robots.base.check_robot` compares the two.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.base import RobotErrorModel, Workspace
from evotol.robots.clearance.kinematics import rotation_vector
from evotol.robots.clearance.model import ClearanceMechanism
from evotol.robots.mechanism.model.clearances import clearance_mechanism
from evotol.robots.mechanism.description.reader import load_mechanism, mechanism_from_dict
from evotol.robots.mechanism.kinematics.tree import IN_PLANE, Kinematics
from evotol.robots.mechanism.description.mechanism import Mechanism
from evotol.robots.mechanism.description.parts import UNIT_SCALE
from evotol.robots.mechanism.kinematics.placement import PLACEMENT_FIELDS
from evotol.robots.mechanism.posture.held import check_posture, posture_notes
from evotol.robots.mechanism.kinematics.serial import SERIAL_COMPILED, SerialChain, serial_inverse_geometry
from evotol.robots.mechanism.description.shipped import resolve_description
from evotol.robots.mechanism.description.shipped import SHIPPED  # noqa: F401  (re-exported: evotol.robots.mechanism.model.error_model.SHIPPED)
from evotol.robots.mechanism.model.sources import OUT_OF_PLANE_FIELDS, source_columns  # noqa: F401  (OUT_OF_PLANE_FIELDS re-exported)


class MechanismModel(RobotErrorModel):
    """Geometric error model of a described mechanism (see the module docstring).

    Parameters
    ----------
    mechanism : Mechanism or str or Path
        A :class:`Mechanism` or the path of its TOML file (``docs/mechanisms.md``).
    sources : sequence of str or None
        Source names/patterns (default: the description's ``[tolerances] sources``, else every
        design parameter and every actuator offset).
    workspace : evotol.robots.base.Workspace or None
        Override of the description's box (SI: m, rad).

    Raises
    ------
    evotol.errors.ValidationError
        A description that does not load or check (names the entry), or no toleranced source.

    Examples
    --------
    >>> from evotol import MechanismModel
    >>> from evotol.robots.mechanism.model.error_model import resolve_description
    >>> robot = MechanismModel(resolve_description("planar3rpr"))   # a shipped description
    >>> robot.source_names
    ('Rb', 'rp', 'l1', 'l2', 'l3')
    >>> robot.sensitivity([[0.0, 0.0, 0.0]]).shape
    (1, 6, 5)
    """

    def __init__(self, mechanism: Mechanism | str | Path, sources=None, workspace: Workspace | None = None):
        mech = mechanism if isinstance(mechanism, Mechanism) else load_mechanism(mechanism)
        self.mechanism = mech
        self.name = mech.name
        self.kin = Kinematics(mech)
        cs = mech.coordinates
        self.workspace = workspace or Workspace(
            names=tuple(c.name for c in cs), low=tuple(c.low for c in cs), high=tuple(c.high for c in cs),
            units=tuple(c.unit for c in cs), display_units=tuple(c.display or c.unit for c in cs),
            display_scale=tuple(1.0 / UNIT_SCALE[c.display or c.unit] for c in cs), stated=mech.task_box)
        self.columns, specs = source_columns(mech, self.kin, sources)
        self.sources = tuple(specs)
        self._placement_frames = frozenset(c[0] for c in self.columns if isinstance(c, tuple) and c[1] in PLACEMENT_FIELDS)
        self._serial = SerialChain.build(self.kin, self.columns) if SERIAL_COMPILED else None   # robots/mechanism/kinematics/serial.py

    # ------------------------------------------------------------------ helpers
    joint_maps = True

    def joint_values(self, poses) -> dict:
        """All joint variables at poses (SI), from the continued Newton inverse geometry.

        Parameters
        ----------
        poses : (n, n_coordinates) or (n_coordinates,) array_like
            Workspace poses (SI: m, rad); not checked against the workspace box.

        Returns
        -------
        dict of str to (n,) ndarray
            Every joint variable (rad, or m for a prismatic joint) at the poses.

        Raises
        ------
        evotol.errors.KinematicsError
            A pose out of reach or singular, or a joint outside its limits
            (:meth:`Kinematics.inverse_geometry
            <evotol.robots.mechanism.posture.inverse_geometry.InverseGeometry.inverse_geometry>`).
        """
        return self._inverse_geometry(np.atleast_2d(np.asarray(poses, float)))

    @property
    def redundancy(self) -> dict | None:
        """For a redundant mechanism (more joint variables than loop and task equations, e.g. the
        7-joint Panda on a 6-D task): the counts and how the inverse geometry resolves the
        self-motion (:meth:`InverseGeometry._newton
        <evotol.robots.mechanism.posture.inverse_geometry.InverseGeometry._newton>`, ``docs/mechanisms.md`` "Redundant arms"); else None."""
        kin = self.kin
        n_eq = sum(len(kin.loop_rows(lp)) for lp in self.mechanism.loops) + len(kin.coord_axes) + (3 if kin.orientation else 0)
        n_var = len(kin.variables)
        if n_var <= n_eq:
            return None
        _, q0 = kin.assembly()
        return {"joint_variables": n_var, "task_equations": n_eq, "self_motions": n_var - n_eq,
                "resolution": "nearest to the assembly posture",
                "posture": {k: float(v) for k, v in q0.items()},
                "text": f"{self.name} is redundant: {n_var} joint variables for {n_eq} task equations ({n_var - n_eq} "
                        "self-motion). At every pose the inverse geometry takes the configuration nearest to the "
                        "assembly posture (Euclidean norm of the joint values, rad and m), continued from the assembly; "
                        "the tolerances hold for that posture (docs/mechanisms.md, Redundant arms)."}

    def notes(self) -> list[str]:
        """Statements a report should carry about how this model was evaluated (the redundancy resolution).

        Returns
        -------
        list of str
            The redundancy text of :attr:`redundancy` for a redundant mechanism, else empty.
        """
        r = self.redundancy
        return ([r["text"]] if r else []) + posture_notes(self)

    def _inverse_geometry(self, poses) -> dict:
        """:meth:`Kinematics.inverse_geometry`, compiled for a serial chain (same steps, per pose);
        a serial arm's posture is then held (:func:`evotol.robots.mechanism.posture.held.check_posture`).

        Poses that are rows of the largest pose set solved so far take its joint values (a study's Monte
        Carlo and vertex checks ask for its poses a chunk at a time: 10^5 poses were solved and checked
        three times over, issue 43 item 4). The continuation from the assembly of a chunk and of the whole
        set end at the same solution to round-off (converged at the pose, the posture checked)."""
        poses = np.atleast_2d(np.asarray(poses, float))
        known = self._known_joints(poses)
        if known is not None:
            return known
        if self._serial is None:
            q = self.kin.inverse_geometry(poses)
        else:
            q = serial_inverse_geometry(self.kin, self._serial, poses)
        check_posture(self, poses, q)
        seen = self.__dict__.get("_solved")
        if len(poses) > 1 and (seen is None or len(poses) > len(seen[0])):
            self._solved = (poses.copy(), q, None)             # rows indexed when first looked up
        return q

    def _known_joints(self, poses: np.ndarray) -> dict | None:
        """The joint values of ``poses`` when every row is a row of the largest solved set, else None."""
        seen = self.__dict__.get("_solved")
        if seen is None or len(poses) > len(seen[0]) or poses.shape[1:] != seen[0].shape[1:]:
            return None
        P, q, index = seen
        if index is None:
            index = {row.tobytes(): i for i, row in enumerate(P)}
            self._solved = (P, q, index)
        rows = [index.get(row.tobytes()) for row in poses]
        if any(i is None for i in rows):
            return None
        return {k: v[rows] for k, v in q.items()}

    def _param_names(self):
        return [c for c in self.columns if isinstance(c, str)]  # parameters and actuated variables

    def _maps(self, poses):
        q = self._inverse_geometry(poses)
        n = len(poses)
        st = self.kin.state(q, n, wrt=set(self.kin.passive) | set(self._param_names()), placement=self._placement_frames)
        return q, st

    def sensitivity(self, poses) -> np.ndarray:
        """First-order map (n, 6, n_sources): ``[dp (m); dphi (rad)]`` of the end-effector frame.

        ``S = J_e - J_p H_p^+ H_e`` (module docstring); the out-of-plane rows of a planar
        mechanism are zero.

        Raises
        ------
        evotol.errors.ValidationError
            Poses of the wrong shape or not finite.
        evotol.errors.KinematicsError
            A pose outside the workspace or out of reach, a joint outside its limits, a parallel
            (type-2) singularity, or a source that opens an over-constrained loop.
        """
        poses = self.check_poses(poses)
        if self._serial is not None:
            return self._serial.sensitivity(self._serial.joints_array(self._inverse_geometry(poses)))
        q, st = self._maps(poses)
        return self._sensitivity(st, poses)

    def sensitivity_at_joints(self, q) -> np.ndarray:
        """First-order map (n, 6, n_sources) at given joint values: a dict ``{variable: (n,)}`` or an
        array (n, n_variables) in the order of ``kin.variables`` (rad, m); no inverse geometry.

        Parameters
        ----------
        q : dict of str to (n,) array_like, or (n, n_variables) array_like
            Every joint variable's values (rad, or m for a prismatic joint); the actuated and
            passive ones must close the loops (not checked).

        Returns
        -------
        (n, 6, n_sources) ndarray
            End-effector error twist per unit of each source (m or rad per m or rad).

        Raises
        ------
        evotol.errors.ValidationError
            An array without one column per joint variable, or a dict missing one.
        evotol.errors.KinematicsError
            A parallel singularity or an over-constrained loop at a configuration (the pose
            reported is zeros: the poses are not known here).
        """
        if self._serial is not None and not isinstance(q, dict):
            Q = np.atleast_2d(np.asarray(q, float))
            if Q.ndim == 2 and Q.shape[1] == len(self.kin.variables):     # the chain's order: no dict round trip
                return self._serial.sensitivity(Q)
        q, n = self._joint_dict(q)
        if self._serial is not None:
            return self._serial.sensitivity(self._serial.joints_array(q))
        st = self.kin.state(q, n, wrt=set(self.kin.passive) | set(self._param_names()), placement=self._placement_frames)
        return self._sensitivity(st, np.zeros((n, len(self.workspace.names))))

    def _joint_dict(self, q) -> tuple[dict, int]:
        """Joint values as ``{variable: (n,)}`` from a dict or an array (n, n_variables); and n."""
        if not isinstance(q, dict):
            Q = np.atleast_2d(np.asarray(q, float))
            if Q.ndim != 2 or Q.shape[1] != len(self.kin.variables):
                raise ValidationError("joint values", Q.shape, f"(n, {len(self.kin.variables)}) columns {self.kin.variables}")
            q = {v: Q[:, i] for i, v in enumerate(self.kin.variables)}
        missing = [v for v in self.kin.variables if v not in q]
        if missing:
            raise ValidationError("joint values", missing[0], f"a value for every joint variable {self.kin.variables}")
        n = len(np.atleast_1d(q[self.kin.variables[0]])) if self.kin.variables else 1
        return {v: np.broadcast_to(np.asarray(q[v], float), (n,)) for v in self.kin.variables}, n

    def _sensitivity(self, st, poses) -> np.ndarray:
        kin = self.kin
        Je = kin.frame_jacobian(st, self.mechanism.end_effector, self.columns)
        if not (self.mechanism.loops and kin.passive):
            return self._planar(Je)
        Jp = kin.frame_jacobian(st, self.mechanism.end_effector, kin.passive)
        Hp = kin.loop_jacobian(st, kin.passive)
        He = kin.loop_jacobian(st, self.columns)
        w = np.where(kin.loop_row_is_length(), 1.0 / kin.length_scale, 1.0)
        Hp, He = Hp * w[:, None], He * w[:, None]
        U, s, Vt = np.linalg.svd(Hp, full_matrices=True)
        smax = np.maximum(s[:, :1], 1e-300)
        keep = s > 1e-10 * smax
        sinv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
        k = s.shape[1]
        pinv = np.einsum("nji,nj,nkj->nik", Vt[:, :k, :], sinv, U[:, :, :k])
        dq = -pinv @ He                                            # (n, n_p, n_s)
        out = Je + Jp @ dq
        # passive motions the loops leave free must not move the end-effector (type-2 singularity)
        null = np.ones(Vt.shape[:2], bool)
        null[:, :k] = ~keep
        if null.any():
            free = Vt * null[:, :, None]
            move = np.abs(Jp @ np.swapaxes(free, 1, 2)).max(axis=(1, 2))
            bad = move > 1e-8 * np.maximum(np.abs(Jp).max(axis=(1, 2)), 1e-300)
            if bad.any():
                i = int(np.nonzero(bad)[0][0])
                raise KinematicsError(f"{self.name}: the actuated joints do not determine the end-effector at pose "
                                      f"{poses[i].tolist()} (parallel singularity)", poses=poses[bad])
        leftover = np.abs(Hp @ dq + He).max(axis=(1, 2))
        bad = leftover > 1e-8 * np.maximum(np.abs(He).max(axis=(1, 2)), 1.0)
        if bad.any():
            i = int(np.nonzero(bad)[0][0])
            col = int(np.argmax(np.abs(Hp[i] @ dq[i] + He[i]).max(axis=0)))
            raise KinematicsError(f"{self.name}: source {self.source_names[col]} opens a loop that no passive joint can "
                                  f"close at pose {poses[i].tolist()} (over-constrained loop)", poses=poses[bad])
        return self._planar(out)

    def _planar(self, J):
        if self.mechanism.planar:
            J = J.copy()
            J[:, [r for r in range(6) if r not in IN_PLANE]] = 0.0
        return J

    def _perturbation(self, errors: np.ndarray):
        """Parameter overrides and DH-entry offsets for flat errors (N, n_sources)."""
        params, offsets = {}, {}
        for c, col in enumerate(self.columns):
            if col in self.kin.actuated:
                continue
            if isinstance(col, str):
                params[col] = self.mechanism.parameters[col] + errors[:, c]
            else:
                offsets[col] = offsets.get(col, 0.0) + errors[:, c]
        return params, offsets

    def pose_error(self, poses, errors) -> np.ndarray:
        """Nonlinear end-effector error (n, m, 6) for source errors (n, m, n_sources): the loops
        re-closed with the perturbed description, actuated joints held at their nominal values;
        ``[dp (m); rotation vector of R R0^T (rad)]`` relative to the nominal, out-of-plane rows
        zero for a planar mechanism.

        An actuator-offset source is added to its joint variable; parameter sources perturb the
        parameter wherever it is used; DH-entry and placement sources perturb that entry only.

        Raises
        ------
        evotol.errors.ValidationError
            Poses of the wrong shape or not finite, or ``errors`` not of shape
            ``(n, m, n_sources)``.
        evotol.errors.KinematicsError
            A pose outside the workspace or out of reach, or loops that do not close with the
            given errors (names the pose).
        """
        poses = self.check_poses(poses)
        errors = np.asarray(errors, float)
        n = len(poses)
        if errors.ndim != 3 or errors.shape[0] != n or errors.shape[2] != self.n_columns:
            raise ValidationError("errors shape", errors.shape, f"({n}, n_samples, {self.n_columns})")
        return self._pose_error(self._inverse_geometry(poses), n, errors, poses)

    def pose_error_at_joints(self, q, errors) -> np.ndarray:
        """:meth:`pose_error` at given joint values (a dict or (n, n_variables), rad and m) instead
        of poses: errors (n, m, n_sources) -> (n, m, 6); no inverse geometry.

        Parameters
        ----------
        q : dict of str to (n,) array_like, or (n, n_variables) array_like
            Every joint variable's nominal values (rad, or m for a prismatic joint).
        errors : (n, m, n_sources) array_like
            Source errors (m or rad), ``m`` samples per configuration.

        Returns
        -------
        (n, m, 6) ndarray
            ``[dp (m); rotation vector (rad)]`` of the end-effector frame relative to the
            nominal at ``q``.

        Raises
        ------
        evotol.errors.ValidationError
            Joint values without every variable, or ``errors`` not of shape
            ``(n, m, n_sources)``.
        evotol.errors.KinematicsError
            Loops that do not close with the given errors (the pose reported is zeros).
        """
        q, n = self._joint_dict(q)
        errors = np.asarray(errors, float)
        if errors.ndim != 3 or errors.shape[0] != n or errors.shape[2] != self.n_columns:
            raise ValidationError("errors shape", errors.shape, f"({n}, n_samples, {self.n_columns})")
        return self._pose_error(q, n, errors, np.zeros((n, len(self.workspace.names))))

    def _pose_error(self, q, n, errors, poses) -> np.ndarray:
        if self._serial is not None:
            return self._serial.pose_error(self._serial.joints_array(q), errors)
        m = errors.shape[1]
        T0 = self.kin.state(q, n, twists=False).world[self.mechanism.end_effector]
        qq = {k: np.repeat(v, m) for k, v in q.items()}
        flat = errors.reshape(n * m, -1)
        for c, col in enumerate(self.columns):
            if col in self.kin.actuated:
                qq[col] = qq[col] + flat[:, c]
        params, offsets = self._perturbation(flat)
        qq, st, res = self.kin.solve_passive(qq, n * m, params=params, offsets=offsets)
        bad = ~(res < 1e-9)
        if bad.any():
            i = int(np.nonzero(bad)[0][0]) // m
            raise KinematicsError(f"{self.name}: the loops do not close with the given errors at pose {poses[i].tolist()}",
                                  poses=poses[i:i + 1])
        T = st.world[self.mechanism.end_effector].reshape(n, m, 4, 4)
        out = np.concatenate([T[..., :3, 3] - T0[:, None, :3, 3],
                              rotation_vector(T[..., :3, :3] @ np.swapaxes(T0[:, None, :3, :3], -1, -2))], axis=-1)
        return self._planar(out.reshape(n * m, 6, 1)).reshape(n, m, 6) if self.mechanism.planar else out

    # ------------------------------------------------------------------ checks and clearances
    def closure_residual(self, poses=None) -> float:
        """Largest loop-closure and pose residual (m or rad) of the inverse geometry at poses.

        Parameters
        ----------
        poses : (n, n_coordinates) array_like or None, optional
            Workspace poses (SI); None (default): 20 Latin-hypercube poses of the workspace
            (seed 0).

        Returns
        -------
        float
            Largest absolute residual of the loop-closure, coordinate and orientation equations
            (unscaled: m for position rows, rad for rotation rows); 0.0 when there are none.

        Raises
        ------
        evotol.errors.ValidationError
            Poses of the wrong shape or not finite.
        evotol.errors.KinematicsError
            A pose outside the workspace or out of reach.
        """
        poses = self.workspace.latin_hypercube(20, seed=0) if poses is None else self.check_poses(poses)
        q = self._inverse_geometry(poses)
        Rt = self.kin._target_orientation(poses)
        F, _, _ = self.kin._ig_system(q, poses, Rt)
        return float(np.abs(F).max()) if F.size else 0.0

    def clearance_mechanism(self) -> ClearanceMechanism:
        """The description's joint clearances as a :class:`ClearanceMechanism` (Deng 2012 Ch. III-V)
        for the certified engine (``evotol.robots.clearance.max_pose_error``); joint values come from the
        Newton inverse geometry.

        DH entries that use a joint variable become named variables ``"<frame>.<field>"`` of the
        clearance tree; the others are evaluated with the nominal parameters. A joint's bounds
        are those under its frame name, else under ``actuated``/``passive``, else ``default``.

        Returns
        -------
        evotol.robots.clearance.model.ClearanceMechanism
            The clearance model (bounds: ``beta_xy``, ``beta_z`` in rad, ``b_xy``, ``b_z`` in m).

        Raises
        ------
        evotol.errors.ValidationError
            No ``[clearance]`` table, a chain joint that is not a revolute or prismatic frame, or
            a joint without bounds.
        """
        return clearance_mechanism(self.mechanism, self.kin, self.name, self.workspace.names)


def model_from_table(table: dict, base_dir=None) -> MechanismModel:
    """The ``[robot]`` table of a study file: ``mechanism = "file.toml"`` (optionally ``sources =
    [...]`` patterns overriding the file's ``[tolerances]``), or ``urdf = "arm.urdf"`` with the
    rest of a description inline (``tip``, ``[robot.end_effector]``, ``[robot.assembly]``,
    ``[robot.tolerances]``).

    Parameters
    ----------
    table : dict
        The ``[robot]`` table as parsed from TOML.
    base_dir : str or Path or None, optional
        Directory of the study file: relative ``mechanism`` and ``urdf`` paths are resolved
        against it.

    Returns
    -------
    MechanismModel
        The error model of the description.

    Raises
    ------
    evotol.errors.ValidationError
        Neither ``mechanism`` nor ``urdf`` in the table, a key other than ``mechanism`` and
        ``sources`` next to ``mechanism``, a description that is not found or has a mistake
        (names the field), or no toleranced source.
    """
    if "urdf" in table:
        spec = {k: v for k, v in table.items() if k != "sources"}
        where = str(Path(base_dir) / "study.toml") if base_dir else ""
        return MechanismModel(mechanism_from_dict(spec, path=where), sources=table.get("sources"))
    if "mechanism" not in table:
        raise ValidationError("robot.mechanism", None, "a description file or the name of a shipped one "
                              "(mechanism = \"file.toml\"), or urdf = \"arm.urdf\" with the description inline")
    extra = set(table) - {"mechanism", "sources"}
    if extra:
        k = sorted(extra)[0]
        raise ValidationError(f"robot.{k}", table[k], "only 'mechanism' and 'sources' next to robot.mechanism")
    return MechanismModel(resolve_description(table["mechanism"], base_dir), sources=table.get("sources"))

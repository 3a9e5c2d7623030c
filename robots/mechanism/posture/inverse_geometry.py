"""Inverse geometry of a described mechanism: the joint variables that close its loops at given poses.

Gauss-Newton (min-norm steps, batched over poses) on the loop-closure equations plus the
end-effector coordinate equations, with *all* joint variables free and the pose fixed; seeded at
the description's assembly configuration and continued along straight paths from the assembly
pose to every target pose in steps, so the working mode does not jump. With the actuated joints
held, the same Newton closes the loops on the passive joints (forward geometry with errors).

:class:`InverseGeometry` is a mixin of :class:`evotol.robots.mechanism.kinematics.tree.Kinematics`: it uses
the kinematics' forward state, frame and loop Jacobians and its joint variables.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.clearance.kinematics import rotation_vector
from evotol.robots.mechanism.posture import working_mode
from evotol.robots.mechanism.description.limits import check_joint_limits, unreachable_message
from evotol.robots.mechanism.kinematics.rotations import AXIS_ROT


class InverseGeometry:
    """Inverse geometry, assembly and passive-joint closure of a :class:`Kinematics
    <evotol.robots.mechanism.kinematics.tree.Kinematics>` (see the module docstring).

    A mixin: the methods use ``self.state``, ``self.loop_residual``, ``self.loop_jacobian``,
    ``self.frame_jacobian``, ``self.loop_row_is_length`` and the joint variables, orientation
    entries and length scale that :class:`~evotol.robots.mechanism.kinematics.tree.Kinematics` sets up.
    """

    def _target_orientation(self, poses: np.ndarray) -> np.ndarray | None:
        if not self.orientation:
            return None
        env = {**self.mech.parameters, **{c.name: poses[:, i] for i, c in enumerate(self.mech.coordinates)}}
        R = np.broadcast_to(np.eye(4), (len(poses), 4, 4))
        for ax, e in self.orientation:
            R = R @ AXIS_ROT[ax](np.broadcast_to(np.real(e(env)), (len(poses),)))
        return R[:, :3, :3]

    def _ig_system(self, q: dict, poses: np.ndarray, Rt):
        n = len(poses)
        st = self.state(q, n, wrt=self.variables)
        F = [self.loop_residual(st)]
        J = [self.loop_jacobian(st, self.variables)]
        Je = self.frame_jacobian(st, self.mech.end_effector, self.variables)
        p = st.world[self.mech.end_effector][:, :3, 3]
        for i, ax in self.coord_axes:
            F.append((p[:, ax] - poses[:, i])[:, None])
            J.append(Je[:, ax:ax + 1])
        if Rt is not None:
            R = st.world[self.mech.end_effector][:, :3, :3]
            F.append(rotation_vector(R @ np.swapaxes(Rt, 1, 2)))
            J.append(Je[:, 3:])
        is_len = np.concatenate([self.loop_row_is_length(), np.ones(len(self.coord_axes), bool),
                                 np.zeros(3 if Rt is not None else 0, bool)])
        return np.concatenate(F, axis=1), np.concatenate(J, axis=1), is_len

    def _newton(self, q: dict, names, system, n: int, max_iter: int, tol: float = 1e-12, final_check: bool = True,
                posture: dict | None = None):
        """Gauss-Newton with min-norm steps on ``system(q) -> (F, J over all variables, is_length)``
        for the unknowns ``names``; returns (q, scaled residual (n,)). ``final_check=False`` skips
        the evaluation after the last step (the residual returned is then the one before it: a
        continuation step that only tracks the branch).

        ``posture`` (joint values): where there are more unknowns than equations (a redundant arm),
        each step is ``q <- q_ref + J^+ (J (q - q_ref) - F)``, Newton's step for the configuration
        nearest to ``q_ref`` (Euclidean norm of the joint values, rad and m) that solves ``F = 0``:
        at convergence ``q - q_ref`` has no component in the self-motion (null space of J)."""
        idx = [self.variables.index(x) for x in names]
        q = {k: np.array(np.broadcast_to(v, (n,)), float) for k, v in q.items()}
        res = np.full(n, np.inf)
        moved = 0.0                         # largest self-motion of the last redundant step (rad or m)
        for it in range(max_iter + 1):
            if it == max_iter and not final_check:
                break
            F, J, is_len = system(q)
            w = np.where(is_len, 1.0 / self.length_scale, 1.0)
            Fs, Js = F * w, J[:, :, idx] * w[:, None]
            res = np.abs(Fs).max(axis=1) if Fs.shape[1] else np.zeros(n)
            if (np.all(res < tol) and moved <= 1e-11) or it == max_iter:
                break
            if posture is not None and Js.shape[1] < len(idx):
                # redundant: min-norm correction of the residual plus the null-space pull to q_ref
                d = np.stack([q[x] - posture[x] for x in names], axis=1)
                y = np.einsum("nki,ni->nk", Js, d) - Fs
                JJt = np.einsum("nki,nli->nkl", Js, Js)
                lam = 1e-13 * np.maximum(np.einsum("nii->n", JJt), 1e-300)
                JJt[:, np.arange(Js.shape[1]), np.arange(Js.shape[1])] += lam[:, None]
                new = np.einsum("nki,nk->ni", Js, np.linalg.solve(JJt, y[..., None])[..., 0])
                moved = float(np.abs(new - d).max()) if n else 0.0
                for c, x in enumerate(names):
                    q[x] = posture[x] + new[:, c]
                continue
            # Gauss-Newton step from the damped normal equations (batched small solves; the
            # damping only matters where some unknowns do not enter, e.g. an idle passive joint)
            JtJ = np.einsum("nki,nkj->nij", Js, Js)
            lam = 1e-13 * np.maximum(np.einsum("nii->n", JtJ), 1e-300)
            JtJ[:, np.arange(len(idx)), np.arange(len(idx))] += lam[:, None]
            step = np.linalg.solve(JtJ, np.einsum("nki,nk->ni", Js, Fs)[..., None])[..., 0]
            for c, x in enumerate(names):
                q[x] = q[x] - step[:, c]
        return q, res

    def assembly(self) -> tuple[np.ndarray, dict]:
        """The declared assembly configuration, closed by Newton at the assembly pose.

        Newton starts from ``[assembly] joints`` (0 for a joint not given) at ``assembly_pose``
        (default: the middle of the box; a serial arm described without a task box: the pose its
        assembly joints reach); the result is cached.

        Returns
        -------
        pose : (n_coordinates,) ndarray
            The assembly pose (SI: m, rad).
        q : dict of str to float
            Every joint variable there (rad or m).

        Raises
        ------
        evotol.errors.ValidationError
            An ``[assembly] joints`` key that is not a joint variable.
        evotol.errors.KinematicsError
            The loops do not close there (scaled residual above 1e-9), the solution is far from
            the declared joints (another working mode, :func:`working_mode.check_reached
            <evotol.robots.mechanism.posture.working_mode.check_reached>`), or a joint is outside its limits.
        """
        if self._assembly is None:
            m = self.mech
            q0 = {x: np.array([float(m.assembly_joints.get(x, 0.0))]) for x in self.variables}
            if m.assembly_pose:
                pose = np.array(m.assembly_pose, float)[None]
            elif not m.task_box:    # a serial arm without a task box: where its declared assembly joints put it
                p = self.state(q0, 1).world[m.end_effector][:, :3, 3]
                pose = np.array([[p[0, ax] for _, ax in self.coord_axes]], float)
            else:
                pose = np.array([(c.low + c.high) / 2 for c in m.coordinates], float)[None]
            unknown = set(m.assembly_joints) - set(self.variables)
            if unknown:
                raise ValidationError("assembly.joints", sorted(unknown)[0], f"a joint variable: {self.variables}")
            Rt = self._target_orientation(pose)
            q, res = self._newton(q0, self.variables, lambda q: self._ig_system(q, pose, Rt), 1, 100)
            if res[0] > 1e-9:
                what = "the loops do not close at" if m.loops else "the arm does not reach"   # serial: no loops
                check = "the frames, the loops and [assembly]" if m.loops else "the frames and [assembly] (pose and joints)"
                raise KinematicsError(f"{m.name}: {what} the assembly pose {pose[0].tolist()} from the declared assembly "
                                      f"joints (scaled residual {res[0]:.2g}); check {check}", poses=pose)
            working_mode.check_reached(self, pose, q0, q)
            check_joint_limits(m.name, m.limits, q, pose, [c.name for c in m.coordinates], "assembly pose")
            self._assembly = (pose[0], {k: float(v[0]) for k, v in q.items()})
        return self._assembly

    def inverse_geometry(self, poses, max_step: float = 0.1) -> dict:
        """All joint variables (n,) at poses (n, n_coordinates) in SI units, continued from the
        assembly configuration along straight paths in steps of at most ``max_step`` of the
        workspace box. Raises KinematicsError naming the first pose where the loops cannot close
        (out of reach) or the Newton system is singular.

        A redundant mechanism takes the solution nearest to the assembly joints. The last few
        results are cached by the poses' bytes: the returned dict is shared, do not modify it.

        Returns
        -------
        dict of str to (n,) ndarray
            Every joint variable at the poses (rad or m).

        Raises
        ------
        evotol.errors.ValidationError
            An ``[assembly] joints`` key that is not a joint variable (from :meth:`assembly`).
        evotol.errors.KinematicsError
            A pose where the loops cannot close (scaled residual not below 1e-9), or a joint
            outside its limits, naming the first such pose; or a failed :meth:`assembly`.
        """
        poses = np.atleast_2d(np.asarray(poses, float))
        key = poses.tobytes()
        if key in self._cache:
            return self._cache[key]
        x0, q0 = self.assembly()
        n = len(poses)
        span = np.array([max(c.high - c.low, 1e-12) for c in self.mech.coordinates])
        dist = np.abs((poses - x0) / span).max() if n else 0.0
        K = int(np.clip(np.ceil(dist / max_step), 1, 200))
        q = {k: np.full(n, v) for k, v in q0.items()}
        for s in np.linspace(1.0 / K, 1.0, K):
            target = x0 + s * (poses - x0)
            Rt = self._target_orientation(target)
            # intermediate steps only track the branch: one Gauss-Newton correction each (the
            # residual left is second order in the step); the last one converges fully
            q, res = self._newton(q, self.variables, lambda q: self._ig_system(q, target, Rt), n,
                                  1 if s < 1 else 40, tol=1e-6 if s < 1 else 1e-12, final_check=s >= 1, posture=q0)
        bad = ~(res < 1e-9)
        if bad.any():
            raise KinematicsError(unreachable_message(self.mech, poses, bad, res), poses=poses[bad])
        check_joint_limits(self.mech.name, self.mech.limits, q, poses, [c.name for c in self.mech.coordinates])
        if len(self._cache) > 8:
            self._cache.clear()
        self._cache[key] = q
        return q

    def solve_passive(self, q: dict, n: int, *, params=None, offsets=None, max_iter: int = 40):
        """Close the loops with the actuated joints held (forward geometry with errors): Newton on
        the passive joints from ``q``; returns (q, state, scaled residual).

        Parameters
        ----------
        q : dict of str to (n,) ndarray
            Every joint variable (rad or m): the actuated ones are held, the passive ones are the
            starting point.
        params : dict or None, optional
            Overrides of design parameters (perturbed values, m or rad).
        offsets : dict or None, optional
            Additive DH-entry and placement errors, as in :meth:`state`.
        max_iter : int, optional
            Largest number of Gauss-Newton iterations.

        Returns
        -------
        q : dict of str to (n,) ndarray
            The joint variables with the passive ones solved.
        state : State
            The state there (no twists).
        residual : (n,) ndarray
            Largest loop-closure residual per configuration, lengths divided by the mechanism's
            largest length (dimensionless); zeros without loops or passive joints. Not checked
            here: the caller decides what is closed.
        """
        def system(qq):
            st = self.state(qq, n, wrt=self.passive, params=params, offsets=offsets)
            return self.loop_residual(st), self._full(self.loop_jacobian(st, self.passive)), self.loop_row_is_length()

        if self.mech.loops and self.passive:
            q, res = self._newton(q, self.passive, system, n, max_iter)
        else:
            res = np.zeros(n)
        return q, self.state(q, n, params=params, offsets=offsets, twists=False), res

    def _full(self, Jp: np.ndarray) -> np.ndarray:
        """Embed a Jacobian over the passive variables into one over all variables."""
        J = np.zeros(Jp.shape[:2] + (len(self.variables),))
        J[:, :, [self.variables.index(x) for x in self.passive]] = Jp
        return J

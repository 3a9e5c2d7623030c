"""Forward kinematics of the Delta robot with errors (Brahmia et al. 2023, eq. 3 with eq. 5): the loop
closure of the three legs solved for the platform position and the free passive joints.

* A parallelogram of revolute joints with errors is over-constrained (a spatial 4R loop has
  mobility -2), so the two branches of a leg end at slightly different points. The leg's end
  point is the midpoint of the two branch ends (the least-squares closure of the two branches).
  The forward kinematics with errors then solves the 9 equations "leg end point i = P" (eq. 3)
  for ``P`` and the free passive joints ``q2_i, q3_i``, given the commanded actuated angles.

:class:`DeltaClosure` is a mixin of :class:`evotol.robots.delta.model.DeltaRobot`, which supplies the
leg end points (:class:`evotol.robots.delta.chains.DeltaChains`), the nominal inverse kinematics and the
iteration settings ``newton_tol`` and ``max_iter``. Units: metres and radians.

The parameters several definitions of this module share are described once, here.

Parameters
----------
poses : array_like, shape (n, 3)
    Commanded platform positions, m.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import ConvergenceError, KinematicsError, ValidationError
from evotol.robots.delta.parameters import PARAMETER_NAMES


class DeltaClosure:
    """Loop closure with errors: forward kinematics, residual, exact Jacobians (mixin of
    :class:`evotol.robots.delta.model.DeltaRobot`)."""

    def _residual(self, X, q1, errors):
        """Loop-closure residual: leg end point i minus P, (..., 9). X = (P, q2_1, q3_1, ..., q3_3)."""
        P = X[..., :3]
        q2 = X[..., 3::2]
        q3 = X[..., 4::2]
        legs = self.leg_points(q1, q2, q3, errors)  # (..., 3, 3)
        return (legs - P[..., None, :]).reshape(*legs.shape[:-2], 9)

    def _closure_jacobian(self, X, q1, errors, h=1e-30):
        """d residual / d X, (..., 9, 9), by complex step (exact to rounding)."""
        shape = np.broadcast_shapes(X.shape[:-1], q1.shape[:-1], errors.shape[:-1])
        J = np.zeros(shape + (9, 9))
        J[..., :, :3] = -np.tile(np.eye(3), (3, 1))
        q2 = X[..., 3::2].astype(complex)
        q3 = X[..., 4::2].astype(complex)
        for k, (a, b) in enumerate(((q2 + 1j * h, q3), (q2, q3 + 1j * h))):
            legs = self.leg_points(q1, a, b, errors).imag / h  # (..., 3 legs, 3): leg i depends on its own joints
            for i in range(3):
                J[..., 3 * i:3 * i + 3, 3 + 2 * i + k] = legs[..., i, :]
        return J

    def _nominal_state(self, poses):
        """Nominal IK ``q1``, state ``X`` and closure Jacobian ``J`` at ``poses`` (n, 3) m, read-only.

        Kept for the last poses asked (one entry): a solver of problem (12) asks for the same pose
        at every evaluation of its objective, and the state depends on nothing else (the geometry
        is frozen; a new geometry object empties it)."""
        return self._nominal_cached(poses)[:3]

    def _nominal_cached(self, poses):
        """``(q1, X, J, J^-1)`` at ``poses``, kept for the last poses asked (see :meth:`_nominal_state`)."""
        key = (poses.shape, poses.tobytes())
        hit = self.__dict__.get("_nominal_entry")
        if hit is not None and hit[0] is self.geometry and hit[1] == key:
            return hit[2]
        q1, q2, q3 = self._ik(poses)
        X = np.empty((len(poses), 9))
        X[:, :3] = poses
        X[:, 3::2], X[:, 4::2] = q2, q3
        zero = np.zeros((len(poses), len(PARAMETER_NAMES)))
        J = self._closure_jacobian(X, q1, zero)
        cond = np.linalg.cond(J)
        if np.any(cond > 1e8):
            k = int(np.argmax(cond))
            raise KinematicsError(f"delta: pose {poses[k].tolist()} m is (near) singular "
                                  f"(loop-closure Jacobian condition {cond[k]:.3g})", poses=poses[cond > 1e8])
        state = (q1, X, J, np.linalg.inv(J))
        for a in state:
            a.setflags(write=False)
        self._nominal_entry = (self.geometry, key, state)
        return state

    def forward_kinematics(self, poses, errors) -> np.ndarray:
        """Platform position of the robot *with errors*, commanded to the nominal IK of ``poses``.

        poses: (n, 3) m; errors: (n, s, 47) SI (or (s, 47) / (47,), broadcast over poses).
        Solves the 9 loop-closure equations (eq. 3 with eq. 5: leg end point i = P) for P and the
        free passive joints q2_i, q3_i by a chord-Newton iteration from the nominal solution
        (Jacobian at the nominal pose, exact by complex step), vectorised over poses and samples,
        until the step is below ``newton_tol`` (m / rad). Returns (n, s, 3) m. Raises
        ConvergenceError naming the pose if it does not converge.

        Parameters
        ----------
        errors : array_like, shape (n, s, 47), (s, 47) or (47,)
            Error parameters (:data:`PARAMETER_NAMES`), SI; ``s`` samples per pose.

        Returns
        -------
        ndarray, shape (n, s, 3)
            Actual platform positions, m.

        Raises
        ------
        ValidationError
            If ``poses`` or ``errors`` has a wrong shape or non-finite entries.
        KinematicsError
            If a pose is outside the workspace, out of reach or (near) singular.
        ConvergenceError
            If the iteration does not converge within ``max_iter`` iterations.
        """
        return self._solve(poses, errors)[1][..., :3]

    def closure_residual(self, poses, errors) -> np.ndarray:
        """Max over legs of ``|leg end point - P|`` (m) at the solution of :meth:`forward_kinematics`.

        Parameters
        ----------
        errors : array_like, shape (n, s, 47), (s, 47) or (47,)
            Error parameters, SI.

        Returns
        -------
        ndarray, shape (n, s)
            Largest loop-closure residual over the three legs, m.

        Raises
        ------
        ValidationError, KinematicsError, ConvergenceError
            As :meth:`forward_kinematics`.
        """
        q1, X, errors = self._solve(poses, errors)
        r = self._residual(X, q1[:, None, :], errors).reshape(*X.shape[:-1], 3, 3)
        return np.max(np.linalg.norm(r, axis=-1), axis=-1)

    def _solve(self, poses, errors):
        poses = self.check_poses(poses)
        errors = self._check_errors(errors, len(poses))
        q1, X0, _, Jinv = self._nominal_cached(poses)
        Jinv = Jinv[:, None]                           # (n, 1, 9, 9)
        q1b = q1[:, None, :]
        X = np.broadcast_to(X0[:, None, :], errors.shape[:2] + (9,)).copy()
        for _ in range(self.max_iter):
            r = self._residual(X, q1b, errors)
            step = np.einsum("nsij,nsj->nsi", np.broadcast_to(Jinv, r.shape + (9,)), r)
            X -= step
            if np.max(np.abs(step), initial=0.0) < self.newton_tol:
                return q1, X, errors
        bad = np.max(np.abs(step), axis=-1) >= self.newton_tol
        k = int(np.argwhere(bad.any(axis=1))[0, 0])
        raise ConvergenceError(f"delta: forward kinematics with errors did not converge at pose "
                               f"{poses[k].tolist()} m after {self.max_iter} iterations "
                               f"(step {np.max(np.abs(step)):.3g})")

    def position_and_jacobian(self, pose, errors, h: float = 1e-30):
        """Platform position with errors and its exact Jacobian w.r.t. the 47 errors *at* those errors.

        pose: (3,) m; errors: (s, 47) SI. Returns P (s, 3) m and dP/de (s, 3, 47) by the implicit
        function theorem at the solved loop closure (dX/de = -(dr/dX)^-1 dr/de, both by complex
        step). Used by gradient-based solvers of the paper's problem (12).

        Parameters
        ----------
        pose : array_like, shape (3,)
            Commanded platform position, m.
        errors : array_like, shape (s, 47) or (47,)
            Error parameters at which to evaluate, SI.
        h : float
            Complex step, dimensionless (exact to rounding for any small value).

        Returns
        -------
        P : ndarray, shape (s, 3)
            Actual platform positions, m.
        dP_de : ndarray, shape (s, 3, 47)
            Jacobian of ``P`` w.r.t. the errors, m per m or m per rad.

        Raises
        ------
        ValidationError, KinematicsError, ConvergenceError
            As :meth:`forward_kinematics`.
        """
        pose = self.check_poses(pose)
        q1, X, errors = self._solve(pose, np.atleast_2d(errors)[None])
        X, errors = X[0], errors[0]                              # (s, 9), (s, 47)
        JX = self._closure_jacobian(X, q1, errors)              # (s, 9, 9)
        m = errors.shape[-1]
        E = errors[:, None, :] + np.eye(m)[None] * (1j * h)      # (s, m, 47)
        dr = self._residual(X[:, None, :], q1[:, None, :], E).imag / h  # (s, m, 9)
        dX = -np.linalg.solve(JX[:, None], dr[..., None])[..., 0]       # (s, m, 9)
        return X[:, :3], dX[..., :3].transpose(0, 2, 1)

    def _check_errors(self, errors, n_poses):
        try:
            errors = np.asarray(errors, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ValidationError("errors", errors, "an array of numbers") from exc
        if errors.ndim == 1:
            errors = errors[None, None, :]
        elif errors.ndim == 2:
            errors = errors[None, :, :]
        if errors.ndim != 3 or errors.shape[-1] != len(PARAMETER_NAMES) or errors.shape[0] not in (1, n_poses):
            raise ValidationError("errors shape", errors.shape,
                                  f"(n_poses={n_poses}, n_samples, {len(PARAMETER_NAMES)})")
        if not np.all(np.isfinite(errors)):
            raise ValidationError("errors", "non-finite entries", "finite numbers")
        return np.broadcast_to(errors, (n_poses,) + errors.shape[1:])

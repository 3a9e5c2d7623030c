"""The controller's compensation: actuator corrections that make the identified model reach a pose.

After the fit, the controller holds the identified model. To reach a task pose whose nominal joint
values are ``q`` it commands ``q + Δq`` with ``Δq`` such that the identified model's tool frame is
the nominal one: Newton on the actuators (chord method: the nominal actuator Jacobian, which is
invertible away from singular poses), on all six rows for an arm with six or more actuators, on
x, y and the rotation about z for a planar mechanism with three, on the position otherwise. The
true robot's error at the pose is then the nonlinear model's error at ``q + Δq``
(:func:`residual`). Used by the simulated calibration and by the linear-range bounds.
"""
from __future__ import annotations

import numpy as np

#: Newton iterations of the compensation at most; it stops once the residual is below ``TOL`` (m, rad)
ITERATIONS, TOL = 12, 1e-13


def controller_rows(robot) -> list[int]:
    """Rows of the error twist the controller's correction cancels (module docstring).

    Parameters
    ----------
    robot : evotol.robots.mechanism.model.error_model.MechanismModel
        The model (its actuated joints; planar or not).

    Returns
    -------
    list of int
        Row indices into ``[dp; dphi]``.
    """
    n_act = len(robot.kin.actuated)
    if n_act >= 6:
        return [0, 1, 2, 3, 4, 5]
    if robot.mechanism.planar and n_act >= 3:
        return [0, 1, 5]
    return [0, 1, 2]


class Compensation:
    """A model with every actuator offset as a source, and the Newton compensation at fixed joints.

    Parameters
    ----------
    joints : (n, n_variables) ndarray
        Nominal joint values of the poses to reach (rad, m).
    """

    def __init__(self, robot, joints):
        names = list(robot.source_names)
        missing = [a for a in robot.kin.actuated if a not in names]
        model = robot
        if missing:
            from evotol.robots.mechanism.model.error_model import MechanismModel

            model = MechanismModel(robot.mechanism, sources=names + missing, workspace=robot.workspace)
        cols = list(model.source_names)
        self.model, self.joints = model, np.asarray(joints, float)
        self.src = [cols.index(n) for n in names]
        self.act = [cols.index(a) for a in robot.kin.actuated]
        self.rows = controller_rows(robot)
        Jq = model.sensitivity_at_joints(self.joints)[:, self.rows][:, :, self.act]
        self.Jq_pinv = np.linalg.pinv(Jq)

    def _full(self, E: np.ndarray) -> np.ndarray:
        out = np.zeros(E.shape[:-1] + (self.model.n_columns,))
        out[..., self.src] = E
        return out

    def corrections(self, E_ident: np.ndarray) -> np.ndarray:
        """Actuator corrections ``Δq`` (n, m, n_act) so that models with errors ``E_ident`` reach the nominal poses.

        Parameters
        ----------
        E_ident : (m, n_columns) ndarray
            The identified source errors of ``m`` robots (m or rad), the robot's columns.

        Returns
        -------
        (n, m, n_actuated) ndarray
            Corrections per pose and robot (rad or m).
        """
        n = len(self.joints)
        base = np.broadcast_to(self._full(E_ident), (n,) + E_ident.shape[:1] + (self.model.n_columns,))
        dq = np.zeros((n, E_ident.shape[0], len(self.act)))
        for _ in range(ITERATIONS):
            E = base.copy()
            E[:, :, self.act] += dq
            F = self.model.pose_error_at_joints(self.joints, E)[:, :, self.rows]
            if np.abs(F).max() < TOL:
                break
            dq -= np.einsum("pak,psk->psa", self.Jq_pinv, F)
        return dq

    def residual(self, E_true: np.ndarray, E_ident: np.ndarray) -> np.ndarray:
        """Error (n, m, 6) of robots with ``E_true`` at the poses, commanded with the identified ``E_ident``.

        Parameters
        ----------
        E_true : (m, n_columns) ndarray
            The robots' true source errors (m or rad).
        E_ident : (m, n_columns) ndarray
            What the fit identified (zero outside the identified sources).

        Returns
        -------
        (n, m, 6) ndarray
            ``[dp (m); rotation vector (rad)]`` of the tool at each pose after compensation.
        """
        dq = self.corrections(E_ident)
        E = np.broadcast_to(self._full(E_true), dq.shape[:2] + (self.model.n_columns,)).copy()
        E[:, :, self.act] += dq
        return self.model.pose_error_at_joints(self.joints, E)

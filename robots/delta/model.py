"""Delta parallel robot with Khalil–Kleinfinger geometric errors (Brahmia et al. 2023) as a
:class:`evotol.robots.base.RobotErrorModel`: its sources, first-order sensitivity and nonlinear pose error.

Model (Brahmia, Kerboua, Kelaiaia, Latreche, *Appl. Sci.* 13:10703, 2023, Sec. 2): the KK chains
of the legs are :mod:`evotol.robots.delta.chains`, the nominal kinematics :mod:`evotol.robots.delta.kinematics`,
the forward kinematics with errors :mod:`evotol.robots.delta.closure`; :class:`DeltaRobot` joins them.

The position-only model leaves rows 3-5 (orientation) of the error twist at zero, as the paper
does (eq. 3 constrains positions only).
"""
from __future__ import annotations

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.base import RobotErrorModel, SourceSpec, Workspace
from evotol.robots.delta.chains import DeltaChains
from evotol.robots.delta.closure import DeltaClosure
from evotol.robots.delta.geometry import DeltaGeometry
from evotol.robots.delta.kinematics import DeltaNominalKinematics
from evotol.robots.delta.parameters import _DESCRIPTIONS, LINEAR, PARAMETER_NAMES


class DeltaRobot(DeltaChains, DeltaNominalKinematics, DeltaClosure, RobotErrorModel):
    """Delta robot error model (Brahmia et al. 2023) as a :class:`evotol.robots.base.RobotErrorModel`.

    Pose coordinates: platform centre ``(x, y, z)`` in metres, base frame (``z`` towards the
    platform). Sources: the 47 geometric error parameters (:data:`PARAMETER_NAMES`), each an
    interval, in m (group ``"linear"``) or rad (group ``"angular"``).

    Parameters
    ----------
    geometry : DeltaGeometry or dict or None
        Nominal dimensions, m; a dict takes keys among ``La, Lb, Ra, Rb, d`` (the others keep
        their defaults); None: :class:`DeltaGeometry` ().
    workspace : Workspace or None
        Pose box; None: ``x, y`` in [-0.1, 0.1] m, ``z`` in [0.25, 0.5] m (displayed in mm).
    newton_tol : float
        Stopping step of the forward kinematics with errors, m / rad.
    max_iter : int
        Maximum number of chord-Newton iterations.

    Raises
    ------
    ValidationError
        If ``geometry`` has unknown keys or is neither a :class:`DeltaGeometry` nor a dict, or a
        length is not positive.

    Notes
    -----
    The KK chains (``branch_points``, ``leg_points``, ``open_chain_points``) come from
    :class:`~evotol.robots.delta.chains.DeltaChains`, the nominal kinematics (``inverse_kinematics``,
    ``forward_kinematics_nominal``) from :class:`~evotol.robots.delta.kinematics.DeltaNominalKinematics`,
    the kinematics with errors (``forward_kinematics``, ``closure_residual``,
    ``position_and_jacobian``) from :class:`~evotol.robots.delta.closure.DeltaClosure`.
    """

    name = "delta"

    def __init__(self, geometry: DeltaGeometry | dict | None = None, workspace: Workspace | None = None,
                 *, newton_tol: float = 1e-14, max_iter: int = 60):
        if isinstance(geometry, dict):  # e.g. from a study file: geometry = {La = 0.26, Lb = 0.48}
            unknown = set(geometry) - {"La", "Lb", "Ra", "Rb", "d"}
            if unknown:
                raise ValidationError("DeltaRobot geometry", sorted(unknown), "keys among La, Lb, Ra, Rb, d (m)")
            geometry = DeltaGeometry(**{k: float(v) for k, v in geometry.items()})
        if geometry is not None and not isinstance(geometry, DeltaGeometry):
            raise ValidationError("DeltaRobot geometry", geometry, "a DeltaGeometry or a dict of lengths (m)")
        self.geometry = geometry or DeltaGeometry()
        self.workspace = workspace or Workspace(("x", "y", "z"), (-0.1, -0.1, 0.25), (0.1, 0.1, 0.5),
                                                ("m", "m", "m"), ("mm", "mm", "mm"), (1e3, 1e3, 1e3))
        self.sources = tuple(
            SourceSpec(n, 1, "m" if n in LINEAR else "rad", "linear" if n in LINEAR else "angular",
                       f"Δ{n}: {_DESCRIPTIONS[n.split('_')[0]]}" + (f", leg {n.split('_')[1]}" if "_" in n else ""))
            for n in PARAMETER_NAMES)
        self.newton_tol, self.max_iter = float(newton_tol), int(max_iter)

    # --- protocol -------------------------------------------------------------------------------
    def sensitivity(self, poses) -> np.ndarray:
        """First-order map (n, 6, 47): d P / d e = -J_X^{-1} d r / d e (implicit function of eq. 3).

        ``d r / d e`` by complex step through the KK chains (exact to rounding). Poses are platform
        positions (n, 3), m. Rows 3-5 are zero (position-only model).

        Raises
        ------
        ValidationError
            If ``poses`` is not a finite (n, 3) array.
        KinematicsError
            If a pose is outside the workspace, out of reach or (near) singular.
        """
        poses = self.check_poses(poses)
        q1, X0, J0 = self._nominal_state(poses)
        n, m = len(poses), len(PARAMETER_NAMES)
        h = 1e-30
        E = np.eye(m)[None] * (1j * h)               # (1, m, 47)
        dr = self._residual(X0[:, None, :], q1[:, None, :], E).imag / h  # (n, m, 9)
        dX = -np.linalg.solve(J0[:, None], dr[..., None])[..., 0]       # (n, m, 9)
        out = np.zeros((n, 6, m))
        out[:, :3, :] = dX[..., :3].transpose(0, 2, 1)
        return out

    def pose_error(self, poses, errors) -> np.ndarray:
        """Nonlinear position error (n, s, 6): forward kinematics with errors minus the commanded pose
        (m, columns 0-2; columns 3-5, orientation, zero). ``errors`` may also be (s, 47) or (47,).

        Raises
        ------
        ValidationError, KinematicsError, ConvergenceError
            As :meth:`forward_kinematics`.
        """
        poses = self.check_poses(poses)
        P = self.forward_kinematics(poses, errors)
        out = np.zeros(P.shape[:2] + (6,))
        out[..., :3] = P - poses[:, None, :]
        return out

"""The planar 5R symmetrical mechanism as an evotol robot error model (:mod:`evotol.robots.base`).

Error sources (SI units; a design of Table 2 scaled by ``D`` metres):

======================  ====  ====  ==========================================================
source                  dim   unit  meaning
======================  ====  ====  ==========================================================
A1B1, A2B2              1     m     crank length errors (eq. 7, one per physical link)
B1P, B2P                1     m     coupler length errors
OA1, OA2                1     m     base half-length errors (A_1 = (-(r3 + e), 0))
theta1, theta2          1     rad   actuator angle errors (eqs. 8 / 23)
clearance_A1, _A2       2     m     radial clearance of the active joints, a disk ``|c| <= r_c``
clearance_B1, _B2       2     m     radial clearance of the passive elbow joints (Sec. 2.5)
======================  ====  ====  ==========================================================

The end-effector joint P is in free flight (Sec. 2.5, assumption 3) and is not a source. The
pose is the end-effector position ``(x, y)`` in metres; the error twist fills rows 0-1 (dx, dy)
and leaves the other rows zero (a point has no orientation).

First-order map: differentiating ``|P - B_i|^2 = rho_i^2`` gives
``(P - B_i) . dP = (P - B_i) . dB_i + r2 drho_i``, i.e. ``dP = J_x^{-1} [...]`` with
``dB_i = dA_i + e(theta_i) dl_i + r1 e_perp(theta_i) dtheta_i + c_Bi``. ``check_robot`` compares
it with central differences of the nonlinear :meth:`Planar5R.pose_error`.

The declared workspace is the square inscribed in the maximum inscribed circle (eqs. 20-22) so
every pose of the box lies in the usable workspace; the sensitivity accepts any pose of the usable
workspace inside that box and raises :class:`KinematicsError` at poses whose LCI is below
``lci_min`` (next to a singular locus).
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.base import RobotErrorModel, SourceSpec, Workspace
from evotol.robots.planar5r import kinematics as K
from evotol.robots.planar5r.kinematics.perturbed_compiled import perturbed_position_stacked
from evotol.robots.planar5r.design import Design5R, get_case

#: the error sources of the 5R model (Lara-Molina 2019 Sec. 2): link lengths (m), actuator angles
#: (rad) and radial joint clearances (m, two components each)
SOURCES = (
    SourceSpec("A1B1", 1, "m", "link length", "crank A1B1 length error"),
    SourceSpec("A2B2", 1, "m", "link length", "crank A2B2 length error"),
    SourceSpec("B1P", 1, "m", "link length", "coupler B1P length error"),
    SourceSpec("B2P", 1, "m", "link length", "coupler B2P length error"),
    SourceSpec("OA1", 1, "m", "link length", "base half-length OA1 error"),
    SourceSpec("OA2", 1, "m", "link length", "base half-length OA2 error"),
    SourceSpec("theta1", 1, "rad", "actuator", "actuator 1 angle error"),
    SourceSpec("theta2", 1, "rad", "actuator", "actuator 2 angle error"),
    SourceSpec("clearance_A1", 2, "m", "active joint clearance", "radial clearance of the actuated joint A1"),
    SourceSpec("clearance_A2", 2, "m", "active joint clearance", "radial clearance of the actuated joint A2"),
    SourceSpec("clearance_B1", 2, "m", "passive joint clearance", "radial clearance of the elbow joint B1"),
    SourceSpec("clearance_B2", 2, "m", "passive joint clearance", "radial clearance of the elbow joint B2"),
)

#: error-parameter name of :func:`kinematics.perturbed_position` for each stacked column.
COLUMN_PARAMETERS = ("dA1B1", "dA2B2", "dB1P", "dB2P", "dOA1", "dOA2", "dth1", "dth2",
                     "cA1x", "cA1y", "cA2x", "cA2y", "cB1x", "cB1y", "cB2x", "cB2y")


class Planar5R(RobotErrorModel):
    """5R symmetrical parallel mechanism of design ``case`` (Table 2 letter or :class:`Design5R`)
    scaled by ``D`` metres (eq. 1: physical length = non-dimensional length x D).

    working_mode: elbow signs (``"+-"``: both elbows outward, see :mod:`evotol.robots.planar5r.kinematics`).
    assembly: sigma of eq. 15 (+1 = the paper's choice).
    lci_min: poses with a smaller local conditioning index are refused (KinematicsError).

    Parameters
    ----------
    case : str or Design5R
        Table 2 letter ``"a"`` ... ``"d"`` or a non-dimensional design.
    D : float
        Scale, m: physical lengths are the design's times ``D``.
    working_mode : str or tuple of int
        Elbow signs (see :func:`evotol.robots.planar5r.kinematics.conventions.working_mode_signs`).
    assembly : {1, -1}
        Assembly mode sigma of eq. 15.
    lci_min : float
        Smallest accepted local conditioning index, dimensionless.

    Raises
    ------
    ValidationError
        If ``case`` is unknown, ``D`` is not a positive finite number, or ``working_mode`` or
        ``assembly`` is invalid.
    KinematicsError
        If the MIC closed form (eq. 22) does not exist for the design.
    """

    def __init__(self, case="b", D: float = 1.0, working_mode=K.DEFAULT_WORKING_MODE, assembly: int = 1,
                 lci_min: float = 1e-3):
        self.design: Design5R = get_case(case)
        if not (isinstance(D, (int, float)) and np.isfinite(D) and D > 0):
            raise ValidationError("Planar5R.D", D, "a positive length in metres")
        K.working_mode_signs(working_mode)
        if assembly not in (1, -1):
            raise ValidationError("Planar5R.assembly", assembly, "+1 or -1")
        self.case = case if isinstance(case, str) else "custom"
        self.D, self.working_mode, self.assembly, self.lci_min = float(D), working_mode, int(assembly), float(lci_min)
        self.r1, self.r2, self.r3 = (self.design.r1 * D, self.design.r2 * D, self.design.r3 * D)
        mic = K.mic_closed_form(self.design.r1, self.design.r2, self.design.r3)
        self.mic_radius, self.mic_center_y = mic["radius"] * D, mic["center_y"] * D
        half = self.mic_radius / np.sqrt(2.0)
        self.name = f"planar5r-{self.case}"
        self.sources = SOURCES
        self.workspace = Workspace(("x", "y"), (-half, self.mic_center_y - half), (half, self.mic_center_y + half),
                                   ("m", "m"), display_units=("mm", "mm"), display_scale=(1e3, 1e3))

    def __repr__(self):
        return (f"Planar5R(case={self.case!r}, r=({self.design.r1:g}, {self.design.r2:g}, {self.design.r3:g}), "
                f"D={self.D:g} m, working_mode={self.working_mode!r}, assembly={self.assembly})")

    # --- poses ------------------------------------------------------------------------------
    def evaluation_poses(self, ring: float = 0.7) -> np.ndarray:
        """The nine poses a..i (m): the MIC centre and eight points at ``ring x r_MIC`` every
        45 deg counter-clockwise from +x (the paper's pose coordinates are not printed).

        Parameters
        ----------
        ring : float
            Radius of the ring of eight poses as a fraction of ``r_MIC``, dimensionless (up to
            ``1 / sqrt(2)`` the poses stay in the declared square workspace).

        Returns
        -------
        ndarray, shape (9, 2)
            Poses ``(x, y)``, m: the MIC centre first.
        """
        ang = np.deg2rad(np.arange(0, 360, 45))
        rr = ring * self.mic_radius
        ring_pts = np.stack([rr * np.cos(ang), self.mic_center_y + rr * np.sin(ang)], -1)
        return np.vstack([[0.0, self.mic_center_y], ring_pts])

    def miw_poses(self, rings=(0.35, 0.7), n_per_ring: int = 8) -> np.ndarray:
        """Poses (m) spread over the maximum inscribed workspace: centre + rings (fractions of
        r_MIC, <= 1/sqrt(2) so they stay in the declared square workspace).

        Parameters
        ----------
        rings : sequence of float
            Ring radii as fractions of ``r_MIC``, dimensionless; the 2nd, 4th, ... rings are rotated
            by half a step.
        n_per_ring : int
            Poses per ring.

        Returns
        -------
        ndarray, shape (1 + len(rings) n_per_ring, 2)
            Poses ``(x, y)``, m: the MIC centre first.
        """
        pts = [[0.0, self.mic_center_y]]
        for k, f in enumerate(rings):
            ang = 2 * np.pi * (np.arange(n_per_ring) + 0.5 * (k % 2)) / n_per_ring
            pts.extend(np.stack([f * self.mic_radius * np.cos(ang), self.mic_center_y + f * self.mic_radius * np.sin(ang)], -1))
        return np.asarray(pts)

    def nominal_angles(self, poses) -> np.ndarray:
        """Crank angles (rad), (n, 2), after checking that every pose is usable.

        Parameters
        ----------
        poses : array_like, shape (n, 2) or (2,)
            End-effector positions ``(x, y)``, m.

        Returns
        -------
        ndarray, shape (n, 2)
            Crank angles ``theta_1, theta_2``, rad.

        Raises
        ------
        ValidationError
            If ``poses`` is not a finite (n, 2) array.
        KinematicsError
            If a pose is outside the declared workspace or the theoretical workspace, in the other
            assembly mode, or has an LCI below ``lci_min``.
        """
        poses = self.check_poses(poses)
        theta = K.inverse_kinematics(poses, self.r1, self.r2, self.r3, self.working_mode)
        jx, jq = K.jacobians(poses, theta, self.r1, self.r3)
        det = jx[:, 0, 0] * jx[:, 1, 1] - jx[:, 0, 1] * jx[:, 1, 0]
        lci = K.local_conditioning_index(poses, self.r1, self.r2, self.r3, self.working_mode)
        bad = (np.sign(det) != self.assembly) | (lci < self.lci_min)
        if bad.any():
            raise KinematicsError(f"{self.name}: pose {poses[bad][0].tolist()} (x, y in m) is not in the usable "
                                  f"workspace (LCI {lci[bad][0]:.3g} < {self.lci_min:g} or other assembly mode)",
                                  poses=poses[bad])
        return theta

    # --- contract -----------------------------------------------------------------------------
    def sensitivity(self, poses) -> np.ndarray:
        """First-order map (n, 6, 16): ``[dx, dy, 0, 0, 0, 0]`` (m) per unit source error (see module),
        poses ``(x, y)`` (n, 2) or (2,) in m; columns in the order of :data:`SOURCES` (two per
        clearance).

        Raises
        ------
        ValidationError
            If ``poses`` is not a finite (n, 2) array.
        KinematicsError
            If a pose is outside the declared workspace or the theoretical workspace, in the other
            assembly mode, or has an LCI below ``lci_min``.
        """
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        theta = self.nominal_angles(poses)
        B = K.crank_points(theta, self.r1, self.r3)
        w = poses[:, None, :] - B                                      # rows P - B_i
        G = np.linalg.inv(w)                                           # columns g_i = J_x^{-1} e_i
        e = np.stack([np.cos(theta), np.sin(theta)], -1)               # (n, 2, 2): e(theta_i)
        eperp = np.stack([-np.sin(theta), np.cos(theta)], -1)
        n = len(poses)
        cols = np.zeros((n, 2, 16))
        for i in range(2):
            g = G[:, :, i]                                             # (n, 2)
            wi = w[:, i, :]
            cols[:, :, 0 + i] = g * np.sum(wi * e[:, i], -1)[:, None]          # crank length
            cols[:, :, 2 + i] = g * self.r2                                      # coupler length
            cols[:, :, 4 + i] = g * (wi[:, 0] * (-1.0 if i == 0 else 1.0))[:, None]  # base half-length
            cols[:, :, 6 + i] = g * (self.r1 * np.sum(wi * eperp[:, i], -1))[:, None]  # actuator angle
            for base in (8 + 2 * i, 12 + 2 * i):                                 # clearance A_i, B_i
                cols[:, :, base:base + 2] = g[:, :, None] * wi[:, None, :]
        out = np.zeros((n, 6, 16))
        out[:, :2, :] = cols
        return out

    def errors_dict(self, errors: np.ndarray) -> dict:
        """Stacked source errors (..., 16) -> keyword arrays of :func:`kinematics.perturbed_position`.

        Parameters
        ----------
        errors : array_like, shape (..., 16)
            Stacked source errors, m or rad, in the column order of :meth:`sensitivity`.

        Returns
        -------
        dict of str to ndarray, each shape (...)
            Errors keyed by the names of :data:`COLUMN_PARAMETERS`.

        Raises
        ------
        ValidationError
            If the last axis is not of length 16.
        """
        errors = np.asarray(errors, dtype=float)
        if errors.shape[-1] != self.n_columns:
            raise ValidationError("errors shape", errors.shape, f"(..., {self.n_columns}) stacked as {self.source_names}")
        return {k: errors[..., j] for j, k in enumerate(COLUMN_PARAMETERS)}

    def pose_error(self, poses, errors, failures: str = "raise") -> np.ndarray:
        """Exact end-effector error (n_poses, n_samples, 6) for stacked source errors
        (n_poses, n_samples, 16), by re-solving the loop closure (no linearisation); columns
        ``dx, dy`` in m, the others zero.

        Parameters
        ----------
        failures : {"raise", "nan"}
            What a sample whose loop cannot close (the two couplers cannot meet) gives:
            :class:`KinematicsError` naming the pose (``"raise"``) or a NaN row (``"nan"``; the
            core's nonlinear yield counts it as a miss).

        Raises
        ------
        ValidationError
            If ``failures`` is invalid, or ``poses`` or ``errors`` has a wrong shape.
        KinematicsError
            If a pose is not usable (see :meth:`nominal_angles`), or, with ``failures="raise"``, a
            sample cannot be assembled.
        """
        if failures not in ("raise", "nan"):
            raise ValidationError("failures", failures, "'raise' or 'nan'")
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        theta = self.nominal_angles(poses)
        errors = np.asarray(errors, dtype=float)
        if errors.ndim != 3 or errors.shape[0] != len(poses) or errors.shape[2] != self.n_columns:
            raise ValidationError("errors shape", errors.shape, f"({len(poses)}, n_samples, {self.n_columns})")
        # one compiled pass over poses x samples, the same numbers as K.perturbed_position (issue 43)
        px, py, h2 = perturbed_position_stacked(theta, self.r1, self.r2, self.r3, errors, self.assembly)
        ok = h2 >= 0
        bad = ~np.all(ok, axis=1)
        if bad.any() and failures == "raise":
            raise KinematicsError(f"{self.name}: pose {poses[bad][0].tolist()} cannot be assembled with the given "
                                  f"source errors", poses=poses[bad])
        out = np.zeros(errors.shape[:2] + (6,))
        out[..., 0] = px - poses[:, 0:1]
        out[..., 1] = py - poses[:, 1:2]
        out[~ok] = np.nan
        return out

"""3-UCR parallel robot (telescope secondary-mirror support), Yao, Wang, Zhou & Zhou 2013.

Geometry (Sec. 2.1, Fig. 1): base joints A_i on a circle of radius r_B, platform joints a_i on a
circle of radius r_p, both at angles φ_i = 0°, 120°, 240°; O-XYZ with OA_1 along X. Each leg is
U (two revolute pairs R_i1 ⊥ A_iO, horizontal, and R_i2 ⊥ R_i1) – C (prismatic r_i, the actuated
length l_i, and R_i3 ∥ r_i) – R (R_i4, axis u_i ⊥ c a_i, i.e. tangential in the platform).

Pose (α, β, Z_c): z-x-z Euler angles with γ = -α (eq. 7) and X_c, Y_c from the revolute-joint
constraints u_i · n_i = 0 (eq. 5), whose closed form is eq. 8 (checked in the tests).

Error sources (Sec. 2.3 and 5: "three length errors, nine revolute joints errors"):
  * ``l1..l3`` – actuated leg-length errors δl_i, intervals (m);
  * ``U{i}a`` – radial clearance of the U joint's first pair R_i1 (axis t_i tangential,
    horizontal): the joint centre A_i moves in the disk spanned by (radial, vertical), radius ε (m);
  * ``U{i}b`` – radial clearance of R_i2 (axis w_i ∝ t_i × n_i): disk spanned by (t_i, w_i × t_i);
  * ``R{i}`` – radial clearance of the platform revolute joint (axis u_i): a_i moves in the disk
    spanned by the platform's radial and normal directions.

  Each clearance is the paper's eq. 12: a displacement of radius r ≤ ε in the plane ⊥ the axis.

Two first-order error models (eq. 10: δl = J_x δx + J_p δp, solved for δx = [δp_c; δθ]):
  * ``variant="verified"`` – derived from the kinematics: the constraint row of J_x is
    ``[u_iᵀ, (s_i × u_i + l_i·u_i × n_i)ᵀ]`` because the axis u_i = R u_iᵉ turns with the platform.
    It matches central finite differences of the nonlinear model (:meth:`pose_error`) to 1e-7.
  * ``variant="paper"`` – eq. 11 exactly as printed: constraint row ``[u_iᵀ, (s_i × u_i)ᵀ]``. It
    omits the term l_i (u_i × n_i) and therefore does not match finite differences (the printed
    J_p rows are the same as ours). Kept because the paper's numbers come from it.

The parameters several definitions of this module share are described once, here.

Parameters
----------
R : ndarray, shape (n, 3, 3)
    Platform orientations.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.base import RobotErrorModel, SourceSpec, Workspace

_PHI = np.array([0.0, 2 * np.pi / 3, 4 * np.pi / 3])
VARIANTS = ("verified", "paper")


def _rot_zxz(alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """R = R_z(α) R_x(β) R_z(-α), eq. 7; shape (n, 3, 3)."""
    sa, ca, sb, cb = np.sin(alpha), np.cos(alpha), np.sin(beta), np.cos(beta)
    R = np.empty(alpha.shape + (3, 3))
    R[..., 0, 0] = ca ** 2 + sa ** 2 * cb
    R[..., 0, 1] = sa * ca * (1 - cb)
    R[..., 0, 2] = sa * sb
    R[..., 1, 0] = sa * ca * (1 - cb)
    R[..., 1, 1] = sa ** 2 + ca ** 2 * cb
    R[..., 1, 2] = -ca * sb
    R[..., 2, 0] = -sa * sb
    R[..., 2, 1] = ca * sb
    R[..., 2, 2] = cb
    return R


def _rodrigues(v: np.ndarray) -> np.ndarray:
    """Rotation matrices exp([v]×) for rotation vectors v (..., 3)."""
    th = np.linalg.norm(v, axis=-1)[..., None, None]
    K = np.zeros(v.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    K[..., 1, 0], K[..., 2, 0], K[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    small = th < 1e-8
    th_safe = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th ** 2 / 6, np.sin(th_safe) / th_safe)
    b = np.where(small, 0.5 - th ** 2 / 24, (1 - np.cos(th_safe)) / th_safe ** 2)
    return np.eye(3) + a * K + b * (K @ K)


def _log_so3(R: np.ndarray) -> np.ndarray:
    """Rotation vector of R (..., 3, 3), valid for angles well below π (errors are tiny)."""
    cos = np.clip((np.trace(R, axis1=-2, axis2=-1) - 1) / 2, -1, 1)
    th = np.arccos(cos)
    w = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], -1)
    f = np.where(th < 1e-8, 0.5 + th ** 2 / 12, th / (2 * np.sin(np.maximum(th, 1e-300))))
    return f[..., None] * w


class UCR3(RobotErrorModel):
    """3-UCR robot of Yao et al. 2013 (see module docstring). Lengths in m, angles in rad.

    Parameters
    ----------
    r_p : float
        Radius of the platform-joint circle (``a_i``), m.
    r_B : float
        Radius of the base-joint circle (``A_i``), m.
    variant : {"verified", "paper"}
        First-order model used by :meth:`sensitivity` (see the module docstring).
    alpha_range_deg, beta_range_deg : tuple of float
        Workspace ranges of the Euler angles ``alpha`` and ``beta``, deg (stored in rad).
    zc_range : tuple of float
        Workspace range of the platform height ``Z_c``, m.

    Raises
    ------
    ValidationError
        If ``r_p`` or ``r_B`` is not a positive finite number, or ``variant`` is unknown.
    """

    def __init__(self, r_p: float = 0.1, r_B: float = 0.14, variant: str = "verified",
                 alpha_range_deg=(-5.0, 5.0), beta_range_deg=(-5.0, 5.0), zc_range=(0.255, 0.305)):
        for field, v in (("r_p", r_p), ("r_B", r_B)):
            if not (np.isfinite(v) and v > 0):
                raise ValidationError(field, v, "a positive radius in metres")
        if variant not in VARIANTS:
            raise ValidationError("variant", variant, f"one of {VARIANTS}")
        self.r_p, self.r_B, self.variant = float(r_p), float(r_B), variant
        self.name = f"3-UCR ({variant})"
        c, s, z = np.cos(_PHI), np.sin(_PHI), np.zeros(3)
        self.A = r_B * np.stack([c, s, z], 1)          # base joints, base frame
        self.a_e = r_p * np.stack([c, s, z], 1)        # platform joints, platform frame
        self.u_e = np.stack([-s, c, z], 1)             # R_i4 axes, platform frame
        self.t_base = np.stack([-s, c, z], 1)          # R_i1 axes (horizontal, ⊥ OA_i)
        self.e_rad = np.stack([c, s, z], 1)
        self.workspace = Workspace(
            names=("alpha", "beta", "Zc"),
            low=(np.radians(alpha_range_deg[0]), np.radians(beta_range_deg[0]), zc_range[0]),
            high=(np.radians(alpha_range_deg[1]), np.radians(beta_range_deg[1]), zc_range[1]),
            units=("rad", "rad", "m"), display_units=("deg", "deg", "m"),
            display_scale=(180 / np.pi, 180 / np.pi, 1.0))
        src = [SourceSpec(f"l{i + 1}", 1, "m", "length", f"actuated length error of leg {i + 1}") for i in range(3)]
        src += [SourceSpec(f"U{i + 1}a", 2, "m", "U joint", f"radial clearance of U-joint pair R_{i + 1}1 (base-fixed axis)") for i in range(3)]
        src += [SourceSpec(f"U{i + 1}b", 2, "m", "U joint", f"radial clearance of U-joint pair R_{i + 1}2") for i in range(3)]
        src += [SourceSpec(f"R{i + 1}", 2, "m", "R joint", f"radial clearance of platform revolute joint R_{i + 1}4") for i in range(3)]
        self.sources = tuple(src)

    # --- geometry -------------------------------------------------------------------------
    def platform_pose(self, poses) -> tuple[np.ndarray, np.ndarray]:
        """Rotation R (n,3,3) and centre p_c (n,3) for poses (α, β, Z_c); X_c, Y_c from eq. 5.

        Parameters
        ----------
        poses : array_like, shape (n, 3) or (3,)
            Poses ``(alpha, beta, Z_c)``: rad, rad, m.

        Returns
        -------
        R : ndarray, shape (n, 3, 3)
            Platform orientation (eq. 7), dimensionless.
        p_c : ndarray, shape (n, 3)
            Platform centre ``(X_c, Y_c, Z_c)``, m.

        Raises
        ------
        ValidationError
            If ``poses`` is not a finite (n, 3) array.
        KinematicsError
            If a pose is outside the workspace, or the three constraints of eq. 5 are inconsistent
            (least-squares residual above 1e-9 m).
        """
        P = self.check_poses(poses)
        R = _rot_zxz(P[:, 0], P[:, 1])
        U = np.einsum("nij,kj->nki", R, self.u_e)                    # (n, 3 legs, 3)
        rhs = np.einsum("nki,ki->nk", U, self.A) - U[:, :, 2] * P[:, 2:3]
        M = U[:, :, :2]
        # normal equations, batched (M is 3x2 and well conditioned in the workspace)
        MtM = np.einsum("nki,nkj->nij", M, M)
        Mtb = np.einsum("nki,nk->ni", M, rhs)
        xy = np.linalg.solve(MtM, Mtb[..., None])[..., 0]
        p = np.concatenate([xy, P[:, 2:3]], axis=1)
        resid = np.max(np.abs(np.einsum("nki,ni->nk", M, xy) - rhs), axis=1)
        if np.any(resid > 1e-9):
            bad = int(np.argmax(resid))
            raise KinematicsError(f"3-UCR: joint constraints (eq. 5) inconsistent at pose {P[bad].tolist()}", P[bad])
        return R, p

    def legs(self, R: np.ndarray, p: np.ndarray):
        """Leg vectors: s_i = R a_iᵉ, u_i = R u_iᵉ, lengths l_i and unit vectors n_i (eq. 4).

        Parameters
        ----------
        p : ndarray, shape (n, 3)
            Platform centres, m.

        Returns
        -------
        s : ndarray, shape (n, 3, 3)
            Platform joint vectors ``R a_i^e`` per leg, base frame, m.
        u : ndarray, shape (n, 3, 3)
            Axes ``R u_i^e`` of the platform revolute joints, unit.
        l : ndarray, shape (n, 3)
            Leg lengths, m.
        n : ndarray, shape (n, 3, 3)
            Unit leg vectors ``A_i -> a_i``.
        """
        s = np.einsum("nij,kj->nki", R, self.a_e)
        u = np.einsum("nij,kj->nki", R, self.u_e)
        L = p[:, None, :] + s - self.A
        l = np.linalg.norm(L, axis=2)
        return s, u, l, L / l[..., None]

    def jacobian_x(self, poses, variant: str | None = None) -> np.ndarray:
        """J_x of eq. 10–11, shape (n, 6, 6); ``variant`` 'verified' or 'paper' (see module doc).

        Parameters
        ----------
        poses : array_like, shape (n, 3) or (3,)
            Poses ``(alpha, beta, Z_c)``: rad, rad, m.
        variant : {"verified", "paper"} or None
            Which model; None: the robot's ``variant``.

        Returns
        -------
        ndarray, shape (n, 6, 6)
            ``J_x``: rows 0-2 ``[n_iᵀ, (s_i × n_i)ᵀ]`` (leg lengths), rows 3-5 the joint
            constraints; applied to ``δx = [δp_c (m); δθ (rad)]`` it gives m.

        Raises
        ------
        ValidationError
            An unknown ``variant`` (a typo would silently give the paper's printed model), or
            as :meth:`platform_pose`.
        KinematicsError
            As :meth:`platform_pose`.
        """
        variant = self.variant if variant is None else variant
        if variant not in VARIANTS:
            raise ValidationError("variant", variant, f"one of {VARIANTS} or None (the robot's)")
        R, p = self.platform_pose(poses)
        s, u, l, n = self.legs(R, p)
        return self._jx(s, u, l, n, variant)

    @staticmethod
    def _jx(s, u, l, n, variant):
        Jx = np.empty(s.shape[:1] + (6, 6))
        Jx[:, :3, :3] = n
        Jx[:, :3, 3:] = np.cross(s, n)
        Jx[:, 3:, :3] = u
        rot = np.cross(s, u)
        if variant == "verified":
            rot = rot + l[..., None] * np.cross(u, n)
        Jx[:, 3:, 3:] = rot
        return Jx

    def clearance_bases(self, R: np.ndarray, n: np.ndarray):
        """Orthonormal disk bases (base frame) of the clearances: U_a, U_b, R; each (n, 3 legs, 3, 2).

        Parameters
        ----------
        n : ndarray, shape (n, 3, 3)
            Unit leg vectors (from :meth:`legs`).

        Returns
        -------
        Ua, Ub, Rb : ndarray, each shape (n, 3, 3, 2)
            For each leg, two orthonormal columns (unit) spanning the clearance disk of ``R_i1``,
            ``R_i2`` and ``R_i4``.
        """
        N = len(R)
        Ua = np.broadcast_to(np.stack([self.e_rad, np.tile([0.0, 0.0, 1.0], (3, 1))], -1), (N, 3, 3, 2))
        t = np.broadcast_to(self.t_base, n.shape)
        w = np.cross(t, n)
        w /= np.linalg.norm(w, axis=-1, keepdims=True)
        Ub = np.stack([t, np.cross(w, t)], -1)
        z_e = np.tile([0.0, 0.0, 1.0], (3, 1))
        Rb = np.einsum("nij,kjc->nkic", R, np.stack([self.e_rad, z_e], -1))
        return Ua, Ub, Rb

    # --- contract -------------------------------------------------------------------------
    def sensitivity(self, poses) -> np.ndarray:
        """First-order map (n, 6, 21): δx = J_x⁻¹ (δl − J_p δp) per unit source error (eq. 10).

        Poses are ``(alpha, beta, Z_c)`` (rad, rad, m). Columns in the order of ``sources``:
        ``l1..l3``, then two columns per disk ``U1a..U3a``, ``U1b..U3b``, ``R1..R3``.

        Raises
        ------
        ValidationError
            If ``poses`` is not a finite (n, 3) array.
        KinematicsError
            If a pose is outside the workspace, eq. 5 is inconsistent, or ``J_x`` is singular
            (condition number above 1e10).
        """
        P = self.check_poses(poses)
        R, p = self.platform_pose(P)
        s, u, l, n = self.legs(R, p)
        Jx = self._jx(s, u, l, n, self.variant)
        cond = np.linalg.cond(Jx)
        if np.any(~np.isfinite(cond) | (cond > 1e10)):
            bad = int(np.argmax(np.where(np.isfinite(cond), cond, np.inf)))
            raise KinematicsError(f"3-UCR: singular J_x (cond {cond[bad]:.3g}) at pose {P[bad].tolist()}", poses=P[[bad]])
        Ua, Ub, Rb = self.clearance_bases(R, n)
        N = len(R)
        rhs = np.zeros((N, 6, self.n_columns))
        col = 0
        for i in range(3):                                     # lengths
            rhs[:, i, col] = 1.0
            col += 1
        for basis, sign in ((Ua, 1.0), (Ub, 1.0), (Rb, -1.0)):  # δA enters +, δa enters −
            for i in range(3):
                rhs[:, i, col:col + 2] = sign * np.einsum("nj,njc->nc", n[:, i], basis[:, i])
                rhs[:, 3 + i, col:col + 2] = sign * np.einsum("nj,njc->nc", u[:, i], basis[:, i])
                col += 2
        return np.linalg.solve(Jx, rhs)

    def pose_error(self, poses, errors, tol: float = 1e-15, max_iter: int = 30) -> np.ndarray:
        """Nonlinear error: re-solve the six loop equations with perturbed lengths and joints.

        Chord-Newton iterations on ``|p + R a_i' − A_i'| = l_i + δl_i`` and
        ``(R u_iᵉ)·(p + R a_i' − A_i') = 0`` with the verified Jacobian; ``errors`` (m) in the column
        order of :meth:`sensitivity`; returns ``[δp_c (m); rotation vector of R R₀ᵀ (rad)]``.

        Parameters
        ----------
        tol : float
            Stopping threshold on the largest loop-equation residual, m.
        max_iter : int
            Maximum number of chord-Newton iterations.

        Raises
        ------
        ValidationError
            If ``poses`` or ``errors`` has a wrong shape.
        KinematicsError
            If a pose is outside the workspace, eq. 5 is inconsistent, or the iteration does not
            converge within ``max_iter`` iterations.
        """
        P = self.check_poses(poses)
        E = np.asarray(errors, dtype=float)
        if E.ndim != 3 or E.shape[0] != len(P) or E.shape[2] != self.n_columns:
            raise ValidationError("errors shape", E.shape, f"({len(P)}, n_samples, {self.n_columns})")
        R0, p0 = self.platform_pose(P)
        _, _, l0, n0 = self.legs(R0, p0)
        Ua, Ub, Rb_nominal = self.clearance_bases(R0, n0)
        # platform-frame basis of the R-joint disks (radial, normal)
        Rb_e = np.stack([self.e_rad, np.tile([0.0, 0.0, 1.0], (3, 1))], -1)
        dl = E[:, :, 0:3]
        dA = (np.einsum("nkjc,nskc->nskj", Ua, E[:, :, 3:9].reshape(len(P), -1, 3, 2))
              + np.einsum("nkjc,nskc->nskj", Ub, E[:, :, 9:15].reshape(len(P), -1, 3, 2)))
        da_e = np.einsum("kjc,nskc->nskj", Rb_e, E[:, :, 15:21].reshape(len(P), -1, 3, 2))
        S = E.shape[1]
        A = self.A + dA                                           # (n, S, 3, 3)
        a_e = self.a_e + da_e
        lt = l0[:, None, :] + dl
        R = np.broadcast_to(R0[:, None], (len(P), S, 3, 3)).copy()
        p = np.broadcast_to(p0[:, None], (len(P), S, 3)).copy()
        # Chord Newton: the errors are tiny, so the nominal pose's verified Jacobian is an excellent
        # fixed iteration matrix (linear convergence with ratio ~ |error|/|link|, i.e. 1e-4 here).
        s0, u0, _, _ = self.legs(R0, p0)
        Jinv = np.linalg.inv(self._jx(s0, u0, l0, n0, "verified"))[:, None]      # (n, 1, 6, 6)
        for _ in range(max_iter):
            s = np.einsum("nsij,nskj->nski", R, a_e)
            u = np.einsum("nsij,kj->nski", R, self.u_e)
            L = p[:, :, None, :] + s - A
            l = np.linalg.norm(L, axis=-1)
            F = np.concatenate([l - lt, np.einsum("nski,nski->nsk", u, L)], axis=-1)
            if np.max(np.abs(F)) < tol:
                break
            dx = -np.einsum("nsij,nsj->nsi", np.broadcast_to(Jinv, F.shape[:2] + (6, 6)), F)
            p = p + dx[..., :3]
            R = _rodrigues(dx[..., 3:]) @ R
        else:
            raise KinematicsError(f"3-UCR: forward kinematics with errors did not converge (|F| = {np.max(np.abs(F)):.3g})")
        dtheta = _log_so3(R @ np.swapaxes(R0, -1, -2)[:, None])
        return np.concatenate([p - p0[:, None], dtheta], axis=-1)


#: The 21 columns of :meth:`UCR3.sensitivity` as columns of the shipped description
#: ``robots/mechanisms/ucr3.toml``: (description source, sign). Lengths l_i = the actuated prismatic
#: variables; the U-joint disks U_ia (radial, vertical) = the base frame's d and b; U_ib (t_i,
#: w_i x t_i) = U_ia.r and U_ib.d; the platform-joint disks R_i (radial, normal in the platform) =
#: minus the platform row's d and r (they move the platform relative to a_i, i.e. a_i by the
#: opposite amount).
DESCRIPTION_COLUMNS = (tuple((f"l{i}", 1) for i in (1, 2, 3))
                       + tuple((f"U{i}a.{k}", 1) for i in (1, 2, 3) for k in ("d", "b"))
                       + tuple((c, 1) for i in (1, 2, 3) for c in (f"U{i}a.r", f"U{i}b.d"))
                       + tuple((f"P{i}.{k}", -1) for i in (1, 2, 3) for k in ("d", "r")))


def columns_from_description(S: np.ndarray, source_names) -> np.ndarray:
    """The description's sensitivity ``S`` (n, 6, n_columns; columns named ``source_names``) in the
    column order and signs of :meth:`UCR3.sensitivity` (n, 6, 21) (:data:`DESCRIPTION_COLUMNS`).

    Parameters
    ----------
    S : ndarray, shape (n, 6, m)
        Sensitivity computed from the description, m per source unit.
    source_names : sequence of str
        Names of its ``m`` columns (must include every name of :data:`DESCRIPTION_COLUMNS`).

    Returns
    -------
    ndarray, shape (n, 6, 21)
        The selected, sign-corrected columns.
    """
    names = list(source_names)
    return np.stack([sign * S[:, :, names.index(c)] for c, sign in DESCRIPTION_COLUMNS], -1)


def yao2013_poses(n_alpha: int = 11, n_beta: int = 11, n_z: int = 6, robot: UCR3 | None = None) -> np.ndarray:
    """Grid over the paper's workspace α, β ∈ [-5°, 5°], Z_c ∈ [0.255, 0.305] m.

    Parameters
    ----------
    n_alpha, n_beta, n_z : int
        Points per coordinate ``alpha``, ``beta``, ``Z_c``.
    robot : UCR3 or None
        Robot whose workspace is gridded; None: ``UCR3()``.

    Returns
    -------
    ndarray, shape ``(n_alpha * n_beta * n_z, 3)``
        Poses ``(alpha, beta, Z_c)``: rad, rad, m.
    """
    return (robot or UCR3()).workspace.grid([n_alpha, n_beta, n_z])

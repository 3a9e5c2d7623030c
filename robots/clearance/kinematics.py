"""Modified Denavit-Hartenberg (Khalil-Kleinfinger) frames, rigid transforms and adjoint maps.

A mechanism is described as a **tree of frames** (Khalil & Kleinfinger 1986, the notation of
Deng 2012, Tabs. II.1, II.2 and IV.1). Frame ``j`` has an antecedent ``a(j)`` and

    ^{a(j)}T_j = Rot(z, gamma_j) Trans(z, b_j) Rot(x, alpha_j) Trans(x, d_j) Rot(z, theta_j) Trans(z, r_j)

with ``sigma_j = 0`` revolute joint about ``z_j`` (``theta_j`` variable), ``1`` prismatic along
``z_j`` (``r_j`` variable), ``2`` a fixed frame (no joint). With ``gamma = b = 0`` this is the
product ``S_alpha S_d S_theta S_r`` of Deng 2012 eqs. III.7-III.11.

Any DH parameter may be a number or the name of a variable; the robot's inverse geometric model
supplies the variables as arrays over poses, so the whole tree is evaluated for many poses in one
vectorised call. Lengths in metres, angles in radians.

Twists and error screws use the thesis's order ``[rotation (3); translation (3)]`` (eq. III.1).

The parameters several definitions of this module share are described once, here.

Parameters
----------
a : float or array_like
    Rotation angle(s), rad, any shape ``(...)``.
n : int
    Number of poses.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence, Union

import numpy as np

from evotol.errors import ValidationError

Param = Union[float, int, str]
DH_FIELDS = ("gamma", "b", "alpha", "d", "theta", "r")


@dataclass(frozen=True)
class DHFrame:
    """One row of a modified DH table (Khalil-Kleinfinger).

    name: frame name (e.g. ``"1"`` or ``"E11"``); antecedent: name of frame ``a(j)`` (``"0"`` is the
    base frame); sigma: 0 revolute, 1 prismatic, 2 fixed; mu: 1 actuated, 0 passive (only a
    label here -- clearance bounds say what is locked). gamma, b, alpha, d, theta, r: numbers
    (m, rad) or names of pose-dependent variables.

    Parameters
    ----------
    name : str
        Frame name (e.g. ``"1"`` or ``"E11"``).
    antecedent : str
        Name of the antecedent frame ``a(j)`` (``"0"``: the base frame).
    sigma : int, optional
        0 (default): revolute joint about ``z_j``; 1: prismatic joint along ``z_j``; 2: fixed
        frame (no joint).
    mu : int, optional
        1: actuated, 0 (default): passive (a label only).
    gamma : float or str, optional
        Rotation about ``z_{a(j)}``, rad, or the name of a variable (default 0).
    b : float or str, optional
        Translation along ``z_{a(j)}``, m, or a variable name (default 0).
    alpha : float or str, optional
        Rotation about ``x``, rad, or a variable name (default 0).
    d : float or str, optional
        Translation along ``x``, m, or a variable name (default 0).
    theta : float or str, optional
        Rotation about ``z_j``, rad, or a variable name (default 0; the joint variable of a
        revolute joint).
    r : float or str, optional
        Translation along ``z_j``, m, or a variable name (default 0; the joint variable of a
        prismatic joint).

    Raises
    ------
    ValidationError
        ``sigma`` not 0, 1 or 2; ``mu`` not 0 or 1; or the frame its own antecedent.
    """

    name: str
    antecedent: str
    sigma: int = 0
    mu: int = 0
    gamma: Param = 0.0
    b: Param = 0.0
    alpha: Param = 0.0
    d: Param = 0.0
    theta: Param = 0.0
    r: Param = 0.0

    def __post_init__(self):
        if self.sigma not in (0, 1, 2):
            raise ValidationError(f"DHFrame({self.name!r}).sigma", self.sigma, "0 (revolute), 1 (prismatic) or 2 (fixed)")
        if self.mu not in (0, 1):
            raise ValidationError(f"DHFrame({self.name!r}).mu", self.mu, "0 (passive) or 1 (actuated)")
        if self.name == self.antecedent:
            raise ValidationError(f"DHFrame({self.name!r}).antecedent", self.antecedent, "another frame")

    @property
    def is_joint(self) -> bool:
        """bool: True when the frame carries a joint (revolute or prismatic, ``sigma`` 0 or 1)."""
        return self.sigma in (0, 1)


def rot_x(a):
    """Homogeneous rotation about the ``x`` axis, broadcast over arrays.

    Returns
    -------
    (..., 4, 4) ndarray
        Homogeneous transforms ``Rot(x, a)`` (no translation).
    """
    a = np.asarray(a, float)
    c, s = np.cos(a), np.sin(a)
    T = np.zeros(a.shape + (4, 4))
    T[..., 0, 0] = 1
    T[..., 1, 1], T[..., 1, 2], T[..., 2, 1], T[..., 2, 2] = c, -s, s, c
    T[..., 3, 3] = 1
    return T


def rot_y(a):
    """Homogeneous rotation about the ``y`` axis, broadcast over arrays.

    Returns
    -------
    (..., 4, 4) ndarray
        Homogeneous transforms ``Rot(y, a)`` (no translation).
    """
    a = np.asarray(a, float)
    c, s = np.cos(a), np.sin(a)
    T = np.zeros(a.shape + (4, 4))
    T[..., 0, 0], T[..., 0, 2], T[..., 2, 0], T[..., 2, 2] = c, s, -s, c
    T[..., 1, 1] = 1
    T[..., 3, 3] = 1
    return T


def rot_z(a):
    """Homogeneous rotation about the ``z`` axis, broadcast over arrays.

    Returns
    -------
    (..., 4, 4) ndarray
        Homogeneous transforms ``Rot(z, a)`` (no translation).
    """
    a = np.asarray(a, float)
    c, s = np.cos(a), np.sin(a)
    T = np.zeros(a.shape + (4, 4))
    T[..., 0, 0], T[..., 0, 1], T[..., 1, 0], T[..., 1, 1] = c, -s, s, c
    T[..., 2, 2] = 1
    T[..., 3, 3] = 1
    return T


def trans(x=0.0, y=0.0, z=0.0):
    """Homogeneous translation, broadcast over arrays.

    Parameters
    ----------
    x, y, z : float or array_like, optional
        Translation components, m (default 0); broadcast together to a shape ``(...)``.

    Returns
    -------
    (..., 4, 4) ndarray
        Homogeneous transforms ``Trans(x, y, z)`` (identity rotation).
    """
    x, y, z = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float), np.asarray(z, float))
    T = np.zeros(x.shape + (4, 4))
    T[..., 0, 0] = T[..., 1, 1] = T[..., 2, 2] = T[..., 3, 3] = 1
    T[..., 0, 3], T[..., 1, 3], T[..., 2, 3] = x, y, z
    return T


def kk_transform(gamma, b, alpha, d, theta, r) -> np.ndarray:
    """^{a(j)}T_j of the modified DH convention, broadcast over arrays; shape (..., 4, 4).

    ``Rot(z, gamma) Trans(z, b) Rot(x, alpha) Trans(x, d) Rot(z, theta) Trans(z, r)`` (module
    docstring; Deng 2012 eqs. III.7-III.11 with ``gamma = b = 0``).

    Parameters
    ----------
    gamma : float or array_like
        Rotation about the antecedent's ``z``, rad.
    b : float or array_like
        Translation along the antecedent's ``z``, m.
    alpha : float or array_like
        Rotation about ``x``, rad.
    d : float or array_like
        Translation along ``x``, m.
    theta : float or array_like
        Rotation about the new ``z``, rad.
    r : float or array_like
        Translation along the new ``z``, m.

    Returns
    -------
    (..., 4, 4) ndarray
        Homogeneous transforms, the six parameters broadcast together to the shape ``(...)``.
    """
    g, b, al, d, th, r = np.broadcast_arrays(*(np.asarray(v, float) for v in (gamma, b, alpha, d, theta, r)))
    return rot_z(g) @ trans(z=b) @ rot_x(al) @ trans(x=d) @ rot_z(th) @ trans(z=r)


def skew(v: np.ndarray) -> np.ndarray:
    """Skew-symmetric matrix ``[v]x`` with ``[v]x w = v x w``; v (..., 3) -> (..., 3, 3).

    Parameters
    ----------
    v : (..., 3) array_like
        Vectors (any units).

    Returns
    -------
    (..., 3, 3) ndarray
        Skew-symmetric matrices ``[v]x``, in the units of ``v``.
    """
    v = np.asarray(v, float)
    S = np.zeros(v.shape[:-1] + (3, 3))
    S[..., 0, 1], S[..., 0, 2] = -v[..., 2], v[..., 1]
    S[..., 1, 0], S[..., 1, 2] = v[..., 2], -v[..., 0]
    S[..., 2, 0], S[..., 2, 1] = -v[..., 1], v[..., 0]
    return S


def adjoint(T: np.ndarray) -> np.ndarray:
    """adj(S) of Deng 2012 eq. III.14 for twists ordered [rotation; translation]:
    ``[[R, 0], [[t]x R, R]]``; maps a screw in frame j+1 to frame j. T (..., 4, 4) -> (..., 6, 6).

    Parameters
    ----------
    T : (..., 4, 4) ndarray
        Homogeneous transforms ``^jT_{j+1}`` (rotation ``R``, translation ``t`` in m).

    Returns
    -------
    (..., 6, 6) ndarray
        Adjoint matrices; the lower-left block ``[t]x R`` is in m (maps rad to m).
    """
    R, t = T[..., :3, :3], T[..., :3, 3]
    A = np.zeros(T.shape[:-2] + (6, 6))
    A[..., :3, :3] = R
    A[..., 3:, 3:] = R
    A[..., 3:, :3] = skew(t) @ R
    return A


def inv_transform(T: np.ndarray) -> np.ndarray:
    """Inverse of rigid homogeneous transforms, ``[[R^T, -R^T t], [0, 1]]``.

    Parameters
    ----------
    T : (..., 4, 4) ndarray
        Rigid homogeneous transforms (rotation ``R``, translation ``t`` in m).

    Returns
    -------
    (..., 4, 4) ndarray
        The inverse transforms (``R`` assumed orthonormal).
    """
    R, t = T[..., :3, :3], T[..., :3, 3]
    Ti = np.zeros_like(T)
    Rt = np.swapaxes(R, -1, -2)
    Ti[..., :3, :3] = Rt
    Ti[..., :3, 3] = -np.einsum("...ij,...j->...i", Rt, t)
    Ti[..., 3, 3] = 1
    return Ti


def exp_screw(s: np.ndarray) -> np.ndarray:
    """Homogeneous transform exp([s]) of a screw s = [rotation; translation] (..., 6) (Rodrigues).

    Parameters
    ----------
    s : (..., 6) array_like
        Screws ``[rotation (rad); translation (m)]``.

    Returns
    -------
    (..., 4, 4) ndarray
        Homogeneous transforms ``exp([s])`` (series expansions below a rotation of 1e-12 rad).
    """
    s = np.asarray(s, float)
    w, v = s[..., :3], s[..., 3:]
    th = np.linalg.norm(w, axis=-1)
    W = skew(w)
    W2 = W @ W
    small = th < 1e-12
    ths = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th ** 2 / 6, np.sin(ths) / ths)
    b = np.where(small, 0.5 - th ** 2 / 24, (1 - np.cos(ths)) / ths ** 2)
    c = np.where(small, 1.0 / 6 - th ** 2 / 120, (ths - np.sin(ths)) / ths ** 3)
    eye = np.broadcast_to(np.eye(3), W.shape)
    R = eye + a[..., None, None] * W + b[..., None, None] * W2
    V = eye + b[..., None, None] * W + c[..., None, None] * W2
    T = np.zeros(s.shape[:-1] + (4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = np.einsum("...ij,...j->...i", V, v)
    T[..., 3, 3] = 1
    return T


def rotation_vector(R: np.ndarray) -> np.ndarray:
    """Rotation vector (axis * angle, rad) of rotation matrices R (..., 3, 3).

    Parameters
    ----------
    R : (..., 3, 3) array_like
        Rotation matrices.

    Returns
    -------
    (..., 3) ndarray
        Rotation vectors, rad (angle in ``[0, pi]``). Inaccurate near an angle of ``pi``, where
        the formula divides by ``sin(angle)``; meant for small error rotations.
    """
    R = np.asarray(R, float)
    cos = np.clip((np.trace(R, axis1=-2, axis2=-1) - 1) / 2, -1.0, 1.0)
    th = np.arccos(cos)
    vee = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], -1)
    s = np.sin(th)
    fac = np.where(th < 1e-8, 0.5 + th ** 2 / 12, th / (2 * np.where(th < 1e-8, 1.0, s)))
    return vee * fac[..., None]


class DHTree:
    """A tree of :class:`DHFrame` s rooted at the base frame ``"0"``, evaluated over many poses.

    Parameters
    ----------
    frames : sequence of DHFrame
        The frames (rows of the DH table), in any order.
    base : str, optional
        Name of the base frame (default ``"0"``); no frame may use it.

    Raises
    ------
    ValidationError
        Duplicate frame names; a frame named like the base; an antecedent that is neither the
        base nor a frame of the tree; or a cycle in the antecedents.
    """

    def __init__(self, frames: Sequence[DHFrame], base: str = "0"):
        self.base = base
        self.frames = {f.name: f for f in frames}
        if len(self.frames) != len(frames):
            raise ValidationError("DHTree frames", [f.name for f in frames], "unique frame names")
        if base in self.frames:
            raise ValidationError("DHTree base", base, "a name not used by any frame")
        for f in frames:
            if f.antecedent != base and f.antecedent not in self.frames:
                raise ValidationError(f"DHFrame({f.name!r}).antecedent", f.antecedent, "the base or another frame of the tree")
        self.order = self._topological_order()

    def _topological_order(self) -> list[str]:
        order, seen = [], {self.base}
        pending = list(self.frames)
        while pending:
            progress = False
            for name in list(pending):
                if self.frames[name].antecedent in seen:
                    order.append(name)
                    seen.add(name)
                    pending.remove(name)
                    progress = True
            if not progress:
                raise ValidationError("DHTree", pending, "a tree (no cycles in antecedents)")
        return order

    def path(self, frame: str) -> list[str]:
        """Frames from the base (excluded) to ``frame`` (included).

        Parameters
        ----------
        frame : str
            Name of a frame of the tree (or the base: empty path).

        Returns
        -------
        list of str
            Frame names, base side first.
        """
        out = []
        while frame != self.base:
            out.append(frame)
            frame = self.frames[frame].antecedent
        return out[::-1]

    def variables(self) -> set[str]:
        """Names of the pose-dependent variables used by the frames' DH parameters.

        Returns
        -------
        set of str
            Every DH parameter given as a name instead of a number.
        """
        return {getattr(f, k) for f in self.frames.values() for k in DH_FIELDS if isinstance(getattr(f, k), str)}

    def local_transforms(self, values: Mapping[str, np.ndarray], n: int) -> dict[str, np.ndarray]:
        """^{a(j)}T_j for every frame, shape (n, 4, 4).

        Parameters
        ----------
        values : mapping of str to array_like
            Value of each variable (m or rad, as its DH parameter), a scalar or an ``(n,)``
            array over poses.

        Returns
        -------
        dict of str to (n, 4, 4) ndarray
            Transform from each frame's antecedent to the frame, per pose.

        Raises
        ------
        ValidationError
            A variable used by a frame is missing from ``values``.
        """
        out = {}
        for name, f in self.frames.items():
            args = []
            for k in DH_FIELDS:
                p = getattr(f, k)
                if isinstance(p, str):
                    if p not in values:
                        raise ValidationError(f"DH variable of frame {name!r}", p, f"one of {sorted(values)}")
                    args.append(np.broadcast_to(np.asarray(values[p], float), (n,)))
                else:
                    args.append(np.full(n, float(p)))
            out[name] = kk_transform(*args)
        return out

    def world_transforms(self, values: Mapping[str, np.ndarray], n: int) -> dict[str, np.ndarray]:
        """^0T_j for every frame, shape (n, 4, 4) (the base frame ``"0"`` is the identity).

        Parameters
        ----------
        values : mapping of str to array_like
            Value of each variable (m or rad), a scalar or an ``(n,)`` array over poses.

        Returns
        -------
        dict of str to (n, 4, 4) ndarray
            Transform from the base to each frame (and the base itself), per pose.

        Raises
        ------
        ValidationError
            A variable used by a frame is missing from ``values``.
        """
        local = self.local_transforms(values, n)
        world = {self.base: np.broadcast_to(np.eye(4), (n, 4, 4)).copy()}
        for name in self.order:
            world[name] = world[self.frames[name].antecedent] @ local[name]
        return world

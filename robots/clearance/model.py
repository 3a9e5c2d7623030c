"""Joint clearances as bounded error screws and their linear map to the end-effector (Deng 2012 Ch. III, V).

Model
-----
Every joint ``j`` has an **error screw** ``s_j = [dr_x, dr_y, dr_z, dt_x, dt_y, dt_z]`` expressed in
its own DH frame (joint axis = ``z_j``), eq. III.1, bounded by four **clearance bounds**
(:class:`ClearanceBounds`, eqs. III.3-III.6)::

    dr_x^2 + dr_y^2 <= dbeta_xy^2,  |dr_z| <= dbeta_z,  dt_x^2 + dt_y^2 <= db_xy^2,  |dt_z| <= db_z

A mechanism is a set of **bodies** (the fixed base, the moving platform ``P``, and for hybrid legs
intermediate *sub-end-effectors* such as the elbows of the IRSBot-2, Ch. V) connected by serial
**chains** of joints. The error of a body is a small-displacement twist ``[dtheta; dp]`` taken at
the body's reference point and expressed in base-frame axes (the thesis's ``N_i`` in eq. III.18).
A chain from body ``A`` to body ``B`` through joints ``j`` gives (eqs. III.22-III.24, V.1, V.4)::

    delta_B = M^e_AB delta_A + sum_j M_j s_j,
    M_j    = [[R_j, 0], [-[p_B - p_j]x R_j, R_j]]      (= prod N . prod adj(S_k)^-1, eq. III.24)
    M^e_AB = [[I, 0], [-[p_B - p_A]x, I]]

where ``R_j, p_j`` are the world orientation and origin of joint frame ``j``. Two chains that end
on the same body must give the same twist (the loop-closure equalities III.13, V.3, V.28).

Stacking all chains gives the linear system ``E_s s + E_d delta = 0`` (``delta`` = twists of the
non-base bodies). A set of screws is **consistent** when this system has a solution ``delta``;
then the platform twist is ``delta_P = C s`` with ``C = -(E_d^+ E_s)_P``, and consistency reads
``B^T s = 0`` with ``B = E_s^T N``, ``N`` an orthonormal basis of ``null(E_d^T)``. ``B`` has
``m = 6 (n_chains - n_bodies)`` columns: the number of independent loop equations. The pair
``(C, B)`` at a pose is all the optimisation needs (:class:`PoseMaps`).

Planar mechanisms (all joint axes parallel to the base ``z`` axis) split exactly into an
in-plane block (``dr_z, dt_x, dt_y`` -> ``dtheta_z, dp_x, dp_y``) and an out-of-plane block
(``dr_x, dr_y, dt_z`` -> ``dtheta_x, dtheta_y, dp_z``); the clearance set is a product over the two
blocks, so each maximum is computed per block and combined exactly (``p_max^2 = p_in^2 + p_out^2``).

The plain values (bounds, joints, chains, blocks) live in :mod:`evotol.robots.clearance.parts`, the
per-pose maps in :mod:`evotol.robots.clearance.pose_maps`; both are importable from here too. The
reduction of the chain equations to those maps (the sparse loop basis) is
:mod:`evotol.robots.clearance.loops`; the nonlinear chain model that checks the error mapping
(:func:`twist_between`, also importable from here) is :mod:`evotol.robots.clearance.nonlinear`.

The parameters several definitions of this module share are described once, here.

Parameters
----------
chain : str or Chain
    The chain, or its name.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Callable, Mapping, Sequence

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.clearance import loops, nonlinear
from evotol.robots.clearance.kinematics import DHTree, skew
from evotol.robots.clearance.nonlinear import twist_between  # noqa: F401
from evotol.robots.clearance.parts import (BOUND_NAMES, BOUND_UNITS, CONE_COMPONENTS, FULL, PLANAR, Block, Chain,
                                    ClearanceBounds, Joint)
from evotol.robots.clearance.pose_maps import PoseMaps

__all__ = ["BOUND_NAMES", "BOUND_UNITS", "CONE_COMPONENTS", "FULL", "PLANAR", "Block", "Chain", "ClearanceBounds",
           "ClearanceMechanism", "Joint", "PoseMaps", "twist_between"]


class ClearanceMechanism:
    """A mechanism with joint clearances, built once and evaluated at many poses.

    tree: the modified-DH frame tree; joints: the joints with clearance; bodies: body name -> DH
    frame of its reference point (``"base"`` -> the base frame is implicit); chains: serial chains
    between bodies; end_effector: the body whose error is reported; joint_values: the inverse
    geometric model, ``poses (n, d) -> {variable: (n,) array}`` for the DH variables; planar: the
    joint axes are all parallel to the base ``z`` axis (enables the exact in/out-of-plane split).

    Parameters
    ----------
    name : str
        Mechanism name (used in messages and by :meth:`sub_mechanism`).
    tree : DHTree
        The modified-DH frame tree (lengths in m, angles in rad).
    joints : sequence of Joint
        The joints with clearance (unique names; each frame a revolute or prismatic frame of
        ``tree``). Their order is the order of the joints in bounds arrays and screws.
    bodies : mapping of str to str
        Body name -> DH frame of its reference point; ``"base"`` is added with the tree's base
        frame when absent.
    chains : sequence of Chain
        Serial chains between bodies (joints listed in path order).
    end_effector : str
        The body whose error is reported (not ``"base"``).
    joint_values : callable
        Inverse geometric model: ``poses (n, d) ndarray -> {variable name: (n,) array}`` giving the
        DH variables (m, rad) at each pose.
    planar : bool, optional
        True: all joint axes parallel to the base ``z`` axis; the in-plane and out-of-plane blocks
        are solved separately (default False: one spatial block).
    pose_names : sequence of str, optional
        Names of the pose coordinates (default ``("x", "y")``).

    Raises
    ------
    ValidationError
        Duplicate joint names; a joint frame that is not a joint frame of the tree; an unknown
        end effector; a chain naming an unknown body or joint, or listing its joints out of path
        order (or off the path).
    """

    def __init__(self, *, name: str, tree: DHTree, joints: Sequence[Joint], bodies: Mapping[str, str],
                 chains: Sequence[Chain], end_effector: str, joint_values: Callable[[np.ndarray], dict],
                 planar: bool = False, pose_names: Sequence[str] = ("x", "y")):
        self.name = name
        self.tree = tree
        self.joints = tuple(joints)
        self.joint_index = {j.name: i for i, j in enumerate(self.joints)}
        if len(self.joint_index) != len(self.joints):
            raise ValidationError(f"{name} joints", [j.name for j in self.joints], "unique names")
        for j in self.joints:
            if j.frame not in tree.frames or not tree.frames[j.frame].is_joint:
                raise ValidationError(f"{name} joint {j.name!r}.frame", j.frame, "a revolute/prismatic frame of the DH tree")
        self.bodies = dict(bodies)
        self.bodies.setdefault("base", tree.base)
        self.body_names = [b for b in self.bodies if b != "base"]
        if end_effector not in self.body_names:
            raise ValidationError(f"{name} end_effector", end_effector, f"one of {self.body_names}")
        self.end_effector = end_effector
        self.chains = tuple(chains)
        for c in self.chains:
            for b in (c.start, c.end):
                if b not in self.bodies:
                    raise ValidationError(f"{name} chain {c.name!r} body", b, f"one of {sorted(self.bodies)}")
            for jn in c.joints:
                if jn not in self.joint_index:
                    raise ValidationError(f"{name} chain {c.name!r} joint", jn, f"one of {sorted(self.joint_index)}")
            path = tree.path(c.path_end or self.bodies[c.end])
            frames = [self.joints[self.joint_index[jn]].frame for jn in c.joints]
            if any(f not in path for f in frames) or [path.index(f) for f in frames] != sorted(path.index(f) for f in frames):
                raise ValidationError(f"{name} chain {c.name!r}", c.joints, f"joints in path order along {path}")
        self.joint_values = joint_values
        self.planar = planar
        self.blocks = PLANAR if planar else FULL
        self.pose_names = tuple(pose_names)

    # ------------------------------------------------------------------ bounds helpers
    @property
    def n_joints(self) -> int:
        """int: number of joints with clearance."""
        return len(self.joints)

    @property
    def n_screw_variables(self) -> int:
        """int: number of scalar screw components, ``6 * n_joints``."""
        return 6 * self.n_joints

    def default_bounds(self) -> np.ndarray:
        """Bounds array (n_joints, 4) [beta_xy, beta_z, b_xy, b_z] from the joints' own bounds.

        Returns
        -------
        (n_joints, 4) ndarray
            Rows in the order of ``joints``; columns ``[beta_xy (rad), beta_z (rad), b_xy (m),
            b_z (m)]``.
        """
        return np.array([j.bounds.as_array() for j in self.joints])

    def thesis_bounds(self, *, b_xy=1e-4, b_z=1e-4, beta_xy=0.01, h=None, beta_z_passive: float = 0.2,
                      beta_z_active: float = 0.0) -> np.ndarray:
        """Bounds array (..., n_joints, 4) by the thesis's convention (Sec. III.1.1), vectorised.

        b_xy, b_z (m), beta_xy (rad), h (m): scalars or arrays broadcasting to (..., n_joints)
        (one column per joint, in the order of ``self.joints``); ``beta_xy = b_xy / h`` (eq.
        III.2) when ``h`` is given; ``beta_z`` = ``beta_z_active`` for actuated joints,
        ``beta_z_passive`` for passive ones. E.g. 32 768 tolerance combinations of the 5-bar:
        ``mech.thesis_bounds(b_xy=B_XY, b_z=B_Z)`` with ``B_XY, B_Z`` of shape (32768, 5).

        Parameters
        ----------
        b_xy : float or array_like, optional
            Radial play, m (default 1e-4 m), broadcasting to ``(..., n_joints)``.
        b_z : float or array_like, optional
            Axial play, m (default 1e-4 m), broadcasting to ``(..., n_joints)``.
        beta_xy : float or array_like, optional
            Tilt of the joint axes, rad (default 0.01 rad); ignored when ``h`` is given.
        h : float or array_like or None, optional
            Joint lengths, m: ``beta_xy = b_xy / h``. None (default): use ``beta_xy``.
        beta_z_passive : float, optional
            Rotation bound about the axis of passive joints, rad (default 0.2 rad).
        beta_z_active : float, optional
            Rotation bound about the axis of actuated joints, rad (default 0: locked).

        Returns
        -------
        (..., n_joints, 4) ndarray
            Columns ``[beta_xy (rad), beta_z (rad), b_xy (m), b_z (m)]``.

        Raises
        ------
        ValidationError
            A joint length ``h <= 0``, or a resulting bound negative or not finite.
        """
        nj = self.n_joints
        bxy, bz = np.asarray(b_xy, float), np.asarray(b_z, float)
        if h is not None:
            h = np.asarray(h, float)
            if np.any(h <= 0):
                raise ValidationError("thesis_bounds h", h, "joint lengths > 0 (m)")
            bxy_, h_ = np.broadcast_arrays(bxy, h)
            beta = bxy_ / h_
        else:
            beta = np.asarray(beta_xy, float)
        active = np.array([j.active for j in self.joints])
        bz_rot = np.where(active, beta_z_active, beta_z_passive)
        shape = np.broadcast_shapes(np.shape(bxy), np.shape(bz), np.shape(beta), (nj,))
        out = np.empty(shape + (4,))
        out[..., 0] = beta
        out[..., 1] = bz_rot
        out[..., 2] = bxy
        out[..., 3] = bz
        if not np.all(np.isfinite(out)) or np.any(out < 0):
            raise ValidationError("thesis_bounds", "negative or non-finite values", "bounds >= 0 (m, rad)")
        return out

    def with_bounds(self, bounds: Mapping[str, ClearanceBounds] | Callable[[Joint], ClearanceBounds]) -> "ClearanceMechanism":
        """A copy with other clearance bounds (a dict by joint name or a function of the joint).

        Parameters
        ----------
        bounds : mapping of str to ClearanceBounds, or callable
            New bounds by joint name (joints not named keep theirs), or a function
            ``Joint -> ClearanceBounds``.

        Returns
        -------
        ClearanceMechanism
            A shallow copy whose joints carry the new bounds (tree, chains and model shared).
        """
        new = object.__new__(ClearanceMechanism)
        new.__dict__.update(self.__dict__)
        fn = bounds if callable(bounds) else (lambda j: bounds.get(j.name, j.bounds))
        new.joints = tuple(replace(j, bounds=fn(j)) for j in self.joints)
        return new

    def with_active(self, names: Sequence[str], beta_z_active: float = 0.0) -> "ClearanceMechanism":
        """Actuation redundancy (Sec. IV.4): the named joints become actuated (``beta_z`` locked).

        Parameters
        ----------
        names : sequence of str
            Names of the joints to actuate.
        beta_z_active : float, optional
            Their rotation bound about the axis, rad (default 0: locked).

        Returns
        -------
        ClearanceMechanism
            A copy with these joints marked active and their ``beta_z`` set to ``beta_z_active``.

        Raises
        ------
        ValidationError
            A name that is not a joint of the mechanism.
        """
        for n in names:
            if n not in self.joint_index:
                raise ValidationError("with_active joint", n, f"one of {sorted(self.joint_index)}")
        new = self.with_bounds(lambda j: replace(j.bounds, beta_z=beta_z_active) if j.name in names else j.bounds)
        new.joints = tuple(replace(j, active=True) if j.name in names else j for j in new.joints)
        return new

    def sub_mechanism(self, chains: Sequence[str], name: str | None = None) -> "ClearanceMechanism":
        """The mechanism restricted to some chains (e.g. one open serial leg, Sec. IV.4).

        Parameters
        ----------
        chains : sequence of str
            Names of the chains to keep.
        name : str or None, optional
            Name of the new mechanism (default: ``"<name>[<chains>]"``).

        Returns
        -------
        ClearanceMechanism
            A mechanism with the kept chains, the joints they use and the bodies they connect;
            same tree, end effector, inverse geometric model and planarity.

        Raises
        ------
        ValidationError
            A chain name that is not a chain of the mechanism, or a restricted mechanism that is
            not valid (e.g. the end effector not on the kept chains).
        """
        keep = [c for c in self.chains if c.name in chains]
        if len(keep) != len(chains):
            raise ValidationError("sub_mechanism chains", chains, f"names among {[c.name for c in self.chains]}")
        used = {jn for c in keep for jn in c.joints}
        bodies = {c.end for c in keep} | {c.start for c in keep}
        return ClearanceMechanism(name=name or f"{self.name}[{','.join(chains)}]", tree=self.tree,
                                  joints=[j for j in self.joints if j.name in used],
                                  bodies={b: f for b, f in self.bodies.items() if b in bodies},
                                  chains=keep, end_effector=self.end_effector, joint_values=self.joint_values,
                                  planar=self.planar, pose_names=self.pose_names)

    # ------------------------------------------------------------------ kinematics
    def world(self, poses: np.ndarray) -> dict[str, np.ndarray]:
        """World transforms of every frame at the nominal joint values of each pose.

        Returns
        -------
        dict of str to (n, 4, 4) ndarray
            ``^0T_j`` for every frame of the tree and the base (translations in m).
        """
        poses = np.atleast_2d(np.asarray(poses, float))
        values = self.joint_values(poses)
        return self.tree.world_transforms(values, len(poses))

    def error_mapping(self, poses: np.ndarray, chain: str | Chain) -> tuple[np.ndarray, np.ndarray]:
        """Error mapping matrices of one chain (eqs. III.22-III.24, V.1): ``M`` (n, 6, 6 n_joints)
        for its joints' screws and ``M^e`` (n, 6, 6) for the start body's twist.

        Returns
        -------
        M : (n, 6, 6 * n_chain_joints) ndarray
            ``[M_j ...]`` for the chain's joints in order: the end body's twist ``[dtheta; dp]``
            (rad, m; base axes) per unit joint screw ``[dr; dt]`` (in the joint's frame).
        Me : (n, 6, 6) ndarray
            ``M^e_AB``: the end body's twist per unit twist of the start body.
        """
        W = self.world(poses)
        return self._chain_maps(W, self._chain(chain))

    def _chain(self, chain: str | Chain) -> Chain:
        return chain if isinstance(chain, Chain) else {c.name: c for c in self.chains}[chain]

    def error_mapping_thesis(self, poses: np.ndarray, chain: str | Chain) -> np.ndarray:
        """The thesis's literal eq. III.24 for a chain starting at the base:
        ``M_j = (prod_l N_l) prod_{k=n_f}^{j+1} adj(S_k)^-1`` (products of adjoints of the DH
        transforms along the chain's path, then ``N`` = the end frame's orientation in the base).
        Kept to check :meth:`error_mapping` (which uses world poses) against the thesis.

        Parameters
        ----------
        chain : str or Chain
            The chain, or its name (one that starts at the base).

        Returns
        -------
        (n, 6, 6 * n_chain_joints) ndarray
            ``[M_j ...]`` for the chain's joints in order, as :meth:`error_mapping` ``M``.
        """
        return nonlinear._error_mapping_thesis(self, poses, chain)

    def _chain_maps(self, W, c: Chain):
        pB = W[self.bodies[c.end]][:, :3, 3]
        pA = W[self.bodies[c.start]][:, :3, 3]
        n = len(pB)
        blocks = []
        for jn in c.joints:
            T = W[self.joints[self.joint_index[jn]].frame]
            R = T[:, :3, :3]
            Mj = np.zeros((n, 6, 6))
            Mj[:, :3, :3] = R
            Mj[:, 3:, 3:] = R
            Mj[:, 3:, :3] = -skew(pB - T[:, :3, 3]) @ R
            blocks.append(Mj)
        Me = np.zeros((n, 6, 6))
        Me[:, :3, :3] = np.eye(3)
        Me[:, 3:, 3:] = np.eye(3)
        Me[:, 3:, :3] = -skew(pB - pA)
        M = np.concatenate(blocks, axis=2) if blocks else np.zeros((n, 6, 0))
        return M, Me

    def linear_system(self, poses: np.ndarray):
        """``E_s`` (n, 6 n_chains, 6 n_joints) and ``E_d`` (n, 6 n_chains, 6 n_bodies) of
        ``E_s s + E_d delta = 0`` (all chains; the end-effector is body 0 of ``delta``).

        Returns
        -------
        Es : (n, 6 * n_chains, 6 * n_joints) ndarray
            Screw part (six rows per chain, six columns per joint in the order of ``joints``).
        Ed : (n, 6 * n_chains, 6 * n_bodies) ndarray
            Body-twist part (six columns per non-base body, the end effector first).
        """
        W = self.world(poses)
        n = len(next(iter(W.values())))
        bodies = [self.end_effector] + [b for b in self.body_names if b != self.end_effector]
        bidx = {b: i for i, b in enumerate(bodies)}
        nc = len(self.chains)
        Es = np.zeros((n, 6 * nc, 6 * self.n_joints))
        Ed = np.zeros((n, 6 * nc, 6 * len(bodies)))
        for ci, c in enumerate(self.chains):
            M, Me = self._chain_maps(W, c)
            r = slice(6 * ci, 6 * ci + 6)
            for k, jn in enumerate(c.joints):
                j = self.joint_index[jn]
                Es[:, r, 6 * j:6 * j + 6] -= M[:, :, 6 * k:6 * k + 6]
            b = bidx[c.end]
            Ed[:, r, 6 * b:6 * b + 6] += np.eye(6)
            if c.start != "base":
                a = bidx[c.start]
                Ed[:, r, 6 * a:6 * a + 6] -= Me
        return Es, Ed

    def pose_maps(self, poses: np.ndarray, split: bool = True) -> list[PoseMaps]:
        """The per-pose linear maps (one :class:`PoseMaps` per decoupled block), computed once.
        ``split=False`` keeps one 6-D block even for a planar mechanism (the thesis's form).

        Raises KinematicsError if the chains do not determine the bodies' twists (a body left
        free) -- never returns NaN.

        Parameters
        ----------
        split : bool, optional
            True (default): one map per decoupled block (two for a planar mechanism); False: one
            6-D block.

        Returns
        -------
        list of PoseMaps
            One per block, each holding the maps at all ``n`` poses.

        Raises
        ------
        KinematicsError
            The chains do not determine every body's error twist at some pose (``poses`` of the
            exception: the offending ones).
        ValidationError
            A block that splits a clearance cone, or a planar block that does not decouple
            (joint axes not all parallel to ``z``).
        """
        return loops._block_maps(self, poses, split)

    # ------------------------------------------------------------------ nonlinear checks
    def chain_end_pose(self, poses: np.ndarray, chain: str | Chain, screws: Mapping[str, np.ndarray] | None = None,
                       start_twist: np.ndarray | None = None) -> np.ndarray:
        """Nonlinear pose (n, 4, 4) of a chain's end body with joint error screws applied
        (``T_j -> T_j exp([s_j])``, s_j in frame j) and an optional start-body twist
        ``[dtheta; dp]`` (base axes, at the start body's point). Used to check the error
        mapping matrices against finite differences.

        Parameters
        ----------
        screws : mapping of str to array_like or None, optional
            Error screw ``[dr; dt]`` (rad, m; ``(6,)`` or ``(n, 6)``) by joint name; joints not
            named have none. None (default): no joint error.
        start_twist : array_like or None, optional
            Twist ``[dtheta; dp]`` (rad, m) of the start body, ``(6,)`` or ``(n, 6)``; None
            (default): none.

        Returns
        -------
        (n, 4, 4) ndarray
            World transform of the chain's end body (translation in m).
        """
        return nonlinear._chain_end_pose(self, poses, chain, screws, start_twist)

"""The nonlinear chain model of a clearance mechanism, to check its first-order error mapping
(Deng 2012 eqs. III.14-III.24).

A joint's error screw is applied as ``T_j -> T_j exp([s_j])`` (``s_j`` in frame ``j``) and the
chain's end pose compared with the nominal one by :func:`twist_between`: central finite
differences of the chain's end pose
(:meth:`~evotol.robots.clearance.model.ClearanceMechanism.chain_end_pose`) must equal the mapping matrices of
:meth:`~evotol.robots.clearance.model.ClearanceMechanism.error_mapping` (tested to 1e-11). The thesis's
literal eq. III.24 (products of inverse adjoints of the DH transforms,
:meth:`~evotol.robots.clearance.model.ClearanceMechanism.error_mapping_thesis`) is kept to check the same
matrices against the thesis (1e-15). Those two methods are documented on the mechanism and do
their work here.
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from evotol.robots.clearance.kinematics import adjoint, exp_screw, inv_transform, rotation_vector
from evotol.robots.clearance.parts import Chain

__all__ = ["twist_between"]


def _chain_transforms(mech, poses: np.ndarray, chain: str | Chain):
    """(chain, n_poses, local transforms, world transforms) at the nominal joint values."""
    poses = np.atleast_2d(np.asarray(poses, float))
    n = len(poses)
    values = mech.joint_values(poses)
    return (mech._chain(chain), n, mech.tree.local_transforms(values, n),
            mech.tree.world_transforms(values, n))


def _error_mapping_thesis(mech, poses: np.ndarray, chain: str | Chain) -> np.ndarray:
    """The work of :meth:`evotol.robots.clearance.model.ClearanceMechanism.error_mapping_thesis` (eq. III.24; see it)."""
    c, n, local, W = _chain_transforms(mech, poses, chain)
    end_frame = c.path_end or mech.bodies[c.end]
    path = mech.tree.path(end_frame)
    # the path's transforms after each frame, plus the constant cut offset to the end body
    S = [local[f] for f in path] + [inv_transform(W[end_frame]) @ W[mech.bodies[c.end]]]
    R_end = W[mech.bodies[c.end]][:, :3, :3]
    N = np.zeros((n, 6, 6))
    N[:, :3, :3] = R_end
    N[:, 3:, 3:] = R_end
    blocks = []
    for jn in c.joints:
        k0 = path.index(mech.joints[mech.joint_index[jn]].frame)
        P = np.broadcast_to(np.eye(6), (n, 6, 6)).copy()
        for T in S[k0 + 1:]:                       # adj(S_{j+1})^-1 ... adj(S_nf)^-1 (III.15)
            P = np.linalg.inv(adjoint(T)) @ P
        blocks.append(N @ P)
    return np.concatenate(blocks, axis=2)


def _chain_end_pose(mech, poses: np.ndarray, chain: str | Chain, screws: Mapping[str, np.ndarray] | None = None,
                    start_twist: np.ndarray | None = None) -> np.ndarray:
    """The work of :meth:`evotol.robots.clearance.model.ClearanceMechanism.chain_end_pose` (see it)."""
    c, n, local, W = _chain_transforms(mech, poses, chain)
    start_frame = mech.bodies[c.start]
    end_frame = c.path_end or mech.bodies[c.end]
    path = mech.tree.path(end_frame)
    k0 = path.index(start_frame) + 1 if start_frame != mech.tree.base else 0
    T = W[start_frame].copy()
    if start_twist is not None:
        st = np.broadcast_to(start_twist, (n, 6))
        # world twist at the start point -> displacement T_A' = D T_A with D about p_A
        pA = T[:, :3, 3]
        D = exp_screw(np.concatenate([st[:, :3], st[:, 3:] - np.cross(st[:, :3], pA)], axis=1))
        T = D @ T
    frame_of = {mech.joints[mech.joint_index[jn]].frame: jn for jn in c.joints}
    for f in path[k0:]:
        T = T @ local[f]
        if screws is not None and f in frame_of and frame_of[f] in screws:
            T = T @ exp_screw(np.broadcast_to(screws[frame_of[f]], (n, 6)))
    offset = inv_transform(W[end_frame]) @ W[mech.bodies[c.end]]
    return T @ offset


def twist_between(T0: np.ndarray, T1: np.ndarray) -> np.ndarray:
    """Finite displacement ``[rotation vector; dp]`` (base axes) from pose T0 to T1, (..., 6).

    Parameters
    ----------
    T0 : (..., 4, 4) ndarray
        Homogeneous transforms of the reference poses (m).
    T1 : (..., 4, 4) ndarray
        Homogeneous transforms of the displaced poses (m).

    Returns
    -------
    (..., 6) ndarray
        Rotation vector of ``R1 R0^T`` (rad) followed by ``p1 - p0`` (m).
    """
    return np.concatenate([rotation_vector(T1[..., :3, :3] @ np.swapaxes(T0[..., :3, :3], -1, -2)),
                           T1[..., :3, 3] - T0[..., :3, 3]], axis=-1)

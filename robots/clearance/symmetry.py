"""Exact reuse of certified maxima across a mirror symmetry, proven pose by pose (issue 13).

A mechanism is mirror-symmetric between poses ``x`` and ``x'`` when its first-order clearance
problem at ``x'`` is the reflected problem at ``x`` with the joints renamed. With the per-pose
maps of :meth:`ClearanceMechanism.pose_maps` (target twist ``C s``, consistency ``B^T s = 0``,
each row of the screw vector ``s`` bounded by its joint's disk or interval), the statement is:

* there is a joint permutation ``pi`` (given: e.g. leg 1 <-> leg 2) and a sign ``sigma_r = ±1``
  per row such that ``C'[:, pi(r)] = R C[:, r] sigma_r`` for the position and the rotation parts,
  ``R`` the reflection (``v' = S v``, ``w' = det(S) S w``);
* the consistency spaces agree: ``{s : B^T s = 0}`` is mapped onto ``{s' : B'^T s' = 0}`` by
  ``s'_{pi(r)} = sigma_r s_r`` (tested as: the columns of the signed, permuted ``B'`` lie in the
  column space of ``B``, and the ranks agree);
* the bounds agree: joint ``k`` and ``pi(k)`` have the same clearance bounds (a disk and a
  symmetric interval are invariant under any sign change of their coordinates).

Then the map ``s -> s'`` is a bijection of the feasible screw sets with ``|C' s'| = |C s|``, so
the global maxima, their maximisers (mapped) and their certified upper bounds are equal. The
check is numerical to round-off (``rtol``), per pose pair: it proves the symmetry of the
description, not of the plotted numbers. :func:`mirror_maxima` returns the maxima at the mirrored
poses from those at the originals, and raises where the proof fails.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from evotol.errors import KinematicsError, ValidationError


def _row_permutation(cols: np.ndarray, joint_map) -> np.ndarray:
    """Row index at the mirrored pose of every row (rows indexed by ``cols`` = 6 * joint + comp)."""
    row_of_col = {int(c): r for r, c in enumerate(cols)}
    try:
        return np.array([row_of_col[6 * int(joint_map[c // 6]) + c % 6] for c in cols])
    except KeyError as exc:
        raise KinematicsError(f"mirror symmetry: joint map sends a clearance row to a joint component without one ({exc})") from None


def prove_mirror(mech, poses, mirrored, joint_map, reflection, rtol: float = 1e-9) -> dict:
    """Prove, pose pair by pose pair, that the clearance problem at ``mirrored[i]`` is the reflected
    problem at ``poses[i]`` (see the module docstring). Returns the per-row signs (``signs``,
    (n_pairs, n_rows) of the one block), the row permutation and the largest residuals; raises
    :class:`KinematicsError` naming the first pose pair where it fails.

    joint_map: sequence, ``joint_map[k]`` = index of the joint that joint ``k`` becomes.
    reflection: (3, 3) orthogonal matrix of the mirror in base axes (e.g. diag(-1, 1, 1)).

    Parameters
    ----------
    mech : ClearanceMechanism
        The mechanism (one decoupled block: not split as planar); its joints' own bounds are
        the ones checked.
    poses : (n_pairs, d) array_like
        Original poses in the mechanism's pose coordinates (m).
    mirrored : (n_pairs, d) array_like
        Their mirror poses, in the same order.
    joint_map : sequence of int
        ``joint_map[k]``: index of the joint that joint ``k`` becomes (a permutation).
    reflection : (3, 3) array_like
        Orthogonal matrix of the mirror in base axes, dimensionless.
    rtol : float, optional
        Relative tolerance of the residuals, dimensionless (default 1e-9: round-off).

    Returns
    -------
    dict
        ``"signs"`` (n_pairs, n_rows) row signs; ``"row_permutation"`` (n_rows,) row index at the
        mirrored pose of each row; ``"cols"`` the rows' screw indices; ``"joint_map"``;
        ``"max_map_residual"`` and ``"max_consistency_residual"`` (relative, dimensionless);
        ``"reflection"`` (3, 3); ``"n_pairs"``.

    Raises
    ------
    KinematicsError
        ``reflection`` not an orthogonal 3 x 3 matrix; ``joint_map`` not a permutation of the
        joints, or one that sends a clearance row to a component without one; a joint and its
        mirror with different bounds; a mechanism with more than one decoupled block; or the
        symmetry failing at a pose pair (the first one is named).
    """
    S = np.asarray(reflection, float)
    if S.shape != (3, 3) or not np.allclose(S @ S.T, np.eye(3), atol=1e-12):
        raise KinematicsError(f"mirror symmetry: reflection must be an orthogonal 3 x 3 matrix, got {S.tolist()}")
    poses, mirrored = np.atleast_2d(poses), np.atleast_2d(mirrored)
    bounds = mech.default_bounds()
    jm = np.asarray(joint_map, int)
    if sorted(jm.tolist()) != list(range(len(mech.joints))):
        raise KinematicsError(f"mirror symmetry: joint map {jm.tolist()} is not a permutation of the {len(mech.joints)} joints")
    if not np.array_equal(bounds[jm], bounds):
        raise KinematicsError("mirror symmetry: a joint and its mirror have different clearance bounds")
    a, b = mech.pose_maps(poses), mech.pose_maps(mirrored)
    if len(a) != 1:
        raise KinematicsError("mirror symmetry: only mechanisms with one decoupled block are supported")
    a, b = a[0], b[0]
    perm = _row_permutation(a.cols, jm)
    Rp = S[np.ix_([c - 3 for c in a.pos_comps], [c - 3 for c in a.pos_comps])]
    Rr = (np.linalg.det(S) * S)[np.ix_(list(a.rot_comps), list(a.rot_comps))]
    src = np.concatenate([np.einsum("ij,njr->nir", Rp, a.C_pos), np.einsum("ij,njr->nir", Rr, a.C_rot)], axis=1)
    dst = np.concatenate([b.C_pos[:, :, perm], b.C_rot[:, :, perm]], axis=1)
    scale = np.maximum(np.abs(src).max(axis=(1, 2)), 1e-300)[:, None]
    dot = np.einsum("nir,nir->nr", src, dst)
    signs = np.where(np.abs(dot) > (rtol * scale) ** 2, np.sign(dot), 1.0)
    c_res = np.abs(dst * signs[:, None, :] - src).max(axis=(1, 2)) / scale[:, 0]
    Bm = b.B[:, perm, :] * signs[:, :, None]
    Q, _ = np.linalg.qr(a.B)                                        # (n, rows, m): basis of B's columns
    resid = Bm - Q @ np.einsum("nrk,nrm->nkm", Q, Bm)
    b_res = np.linalg.norm(resid, axis=(1, 2)) / np.maximum(np.linalg.norm(Bm, axis=(1, 2)), 1e-300)
    rank_ok = np.linalg.matrix_rank(a.B) == np.linalg.matrix_rank(b.B)
    bad = np.flatnonzero((c_res > rtol) | (b_res > rtol) | ~rank_ok)
    if bad.size:
        i = bad[0]
        raise KinematicsError(f"mirror symmetry fails between poses {poses[i].tolist()} and {mirrored[i].tolist()}: "
                              f"map residual {c_res[i]:.2e}, consistency residual {b_res[i]:.2e}")
    return {"signs": signs, "row_permutation": perm, "cols": a.cols, "joint_map": jm,
            "max_map_residual": float(c_res.max()), "max_consistency_residual": float(b_res.max()),
            "reflection": S, "n_pairs": len(poses)}


def mirror_maxima(result, proof: dict):
    """The certified maxima at the mirrored poses of :func:`prove_mirror`, from ``result`` (a
    :class:`~evotol.robots.clearance.maxerror.MaxPoseError` at the original poses, in the same order):
    equal values and bounds, maximising screws renamed and sign-changed, twists reflected.

    Parameters
    ----------
    result : MaxPoseError
        Result at the original poses of the proof, in the same order.
    proof : dict
        The return value of :func:`prove_mirror`.

    Returns
    -------
    MaxPoseError
        The result at the mirrored poses (no work of its own: ``n_solves = 0``, ``n_newton = 0``,
        ``seconds = 0``; ``p_extra`` and ``r_extra`` copied unchanged).
    """
    jm, cols, signs, S = proof["joint_map"], proof["cols"], proof["signs"], proof["reflection"]
    det = np.linalg.det(S)

    def screws(s):
        out = np.zeros_like(s)
        flat_in, flat_out = s.reshape(len(s), -1), out.reshape(len(out), -1)
        for r, c in enumerate(cols):
            flat_out[:, 6 * jm[c // 6] + c % 6] = signs[:, r] * flat_in[:, c]
        return out

    def twists(t):                                  # [dtheta; dp] in base axes
        return np.concatenate([det * t[:, :3] @ S.T, t[:, 3:] @ S.T], axis=1)

    return replace(result, p_max=result.p_max.copy(), p_upper=result.p_upper.copy(), r_max=result.r_max.copy(),
                   r_upper=result.r_upper.copy(), p_screws=screws(result.p_screws), r_screws=screws(result.r_screws),
                   p_twist=twists(result.p_twist), r_twist=twists(result.r_twist), n_solves=0, n_newton=0,
                   seconds=0.0)


def grid_max_pose_error_mirrored(mech, poses, joint_map, reflection, pose_reflection, **grid_kw):
    """:func:`~evotol.robots.clearance.grid.grid_max_pose_error` over ``poses`` solving only one pose of
    every mirror pair: pose ``j`` is the mirror of pose ``i`` when ``poses[j] = pose_reflection *
    poses[i]`` (element-wise, e.g. ``(-1, 1)`` for x -> -x in the x-z plane). The symmetry is proven
    for every pair (:func:`prove_mirror`) before the maxima are reused. Returns the result in the
    order of ``poses`` and a summary: poses solved, pairs reused, largest proof residuals.

    Parameters
    ----------
    mech : ClearanceMechanism
        The mechanism (one decoupled block, see :func:`prove_mirror`).
    poses : (n, d) array_like
        Poses in the mechanism's pose coordinates (m); mirror partners are matched after
        rounding to 12 decimals.
    joint_map : sequence of int
        ``joint_map[k]``: index of the joint that joint ``k`` becomes under the mirror.
    reflection : (3, 3) array_like
        Orthogonal matrix of the mirror in base axes.
    pose_reflection : (d,) array_like
        Element-wise factors mapping a pose to its mirror (e.g. ``(-1, 1)``).
    **grid_kw
        Passed to :func:`~evotol.robots.clearance.grid.grid_max_pose_error` (``tol``, ``workers``,
        ``scheduler``, ``options``, ...); without ``chunk_size`` and ``scheduler`` the chunk size
        is chosen to give equal chunks on the local processes. The proof uses the joints' own
        bounds, so ``bounds`` is refused here.

    Returns
    -------
    result : MaxPoseError
        One case per pose, in the order of ``poses`` (``seconds``: wall time; ``n_solves``: those
        of the solved poses).
    summary : dict
        ``"n_poses"``, ``"n_solved"``, ``"n_reused"``, ``"max_map_residual"`` and
        ``"max_consistency_residual"`` (relative, dimensionless).

    Raises
    ------
    KinematicsError
        The mirror symmetry cannot be proven for a reused pair (:func:`prove_mirror`).
    ValidationError
        ``bounds`` given in ``grid_kw`` (the reused maxima would be those of the joints' own
        bounds, not of the given ones).
    """
    import time

    from evotol.robots.clearance.grid import grid_max_pose_error
    from evotol.robots.clearance.maxerror import MaxPoseError

    if grid_kw.get("bounds") is not None:
        raise ValidationError("bounds", "given", "no bounds: the mirror proof holds for the joints' own bounds only "
                              "(use grid_max_pose_error for other bounds)")
    t0 = time.perf_counter()
    poses = np.atleast_2d(np.asarray(poses, float))
    key = {tuple(np.round(p, 12)): i for i, p in enumerate(poses)}
    partner = np.array([key.get(tuple(np.round(p * pose_reflection, 12)), -1) for p in poses])
    solve = np.flatnonzero((partner < 0) | (partner >= np.arange(len(poses))))   # one of each pair (and self-mirrors)
    reuse = np.flatnonzero((partner >= 0) & (partner < np.arange(len(poses))))  # j whose mirror partner[j] is solved
    if "chunk_size" not in grid_kw and not grid_kw.get("scheduler"):
        # equal chunks, a multiple of the local processes: half a grid in 256-pose chunks leaves
        # one process idle for most of the last round
        from evotol._runtime.executor.backends import worker_count

        w = worker_count(grid_kw.get("workers"))
        n_chunks = -(-len(solve) // 256)
        n_chunks = -(-n_chunks // w) * w
        grid_kw = {**grid_kw, "chunk_size": max(1, -(-len(solve) // n_chunks))}
    solved = grid_max_pose_error(mech, poses[solve], **grid_kw)
    parts, order = [solved], [solve]
    summary = {"n_poses": len(poses), "n_solved": int(len(solve)), "n_reused": int(len(reuse)),
               "max_map_residual": 0.0, "max_consistency_residual": 0.0}
    if reuse.size:
        pos_in_solved = {int(i): k for k, i in enumerate(solve)}
        src = np.array([pos_in_solved[int(partner[j])] for j in reuse])
        proof = prove_mirror(mech, poses[partner[reuse]], poses[reuse], joint_map, reflection)
        parts.append(mirror_maxima(solved.take(src), proof))
        order.append(reuse)
        summary.update(max_map_residual=proof["max_map_residual"], max_consistency_residual=proof["max_consistency_residual"])
    out = MaxPoseError.concat(parts)
    inverse = np.empty(len(poses), int)
    inverse[np.concatenate(order)] = np.arange(len(poses))
    out = out.take(inverse)
    out.n_solves = solved.n_solves
    out.seconds = time.perf_counter() - t0
    return out, summary


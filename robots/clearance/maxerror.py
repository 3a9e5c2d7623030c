"""Global maximum pose error under joint clearances, with a certificate (Deng 2012 eqs. III.26-III.27).

The thesis maximises ``||dp||^2`` (or ``||dtheta||^2``) over the clearance screws -- a nonconvex
problem it attacks with 200 local solves per pose. The feasible error twists form a convex,
centrally symmetric set ``P`` (an intersection over chains of Minkowski sums of the joints'
disk x interval x disk x interval sets), so::

    p_max = max_{x in P} ||x_pos|| = max_{|u| = 1} h_P(u),      h_P = support function of P.

Each ``h_P(u)`` is a small convex problem solved with a two-sided certificate
(:mod:`evotol.robots.clearance.support`). The maximum over unit directions ``u`` is found by
branch and bound on the circle (2 target components) or the half sphere (3 components;
``h(u) = h(-u)`` by symmetry): for a patch spanned by unit vectors ``u_1..u_q``,
``max_patch h <= max_i h(u_i) / d`` where ``d`` is the distance from the origin to the flat
patch (positive homogeneity + subadditivity of ``h``); patches whose bound does not exceed the
best attained norm by more than the tolerance are discarded, the others are split. A second,
often much tighter bound interpolates the vertices' **dual points** across the patch (weak
duality holds for any dual point and the problem's data are linear in the direction:
:func:`_interpolated_bound`), so patches on round parts of the error set prune without being
split. The result carries

* ``p_max``: a value **attained** by an explicit feasible set of joint error screws (returned);
* ``p_upper``: a **certified** upper bound (dual certificates on the directions + patch bound);

and likewise for the rotation. Their relative gap is at most ``tol`` (default 1e-3).

Modules: :mod:`.branch_bound` (the branch and bound of one block), :mod:`.patches` (patches of
directions and their bounds), :mod:`.options` (the settings, one frozen value passed down),
:mod:`~evotol.robots.clearance.result` (:class:`MaxPoseError`), :mod:`.sampling` (random clearance states, for comparison).
"""
from __future__ import annotations

import time

import numpy as np

from evotol.errors import ValidationError
from evotol._runtime.executor import parallel_map
from evotol._runtime.blas_threads import one_blas_thread
from evotol.robots.clearance.branch_bound import maximise_norm
from evotol.robots.clearance.certificate import _gram_pinv
from evotol.robots.clearance.model import ClearanceMechanism, PoseMaps
from evotol.robots.clearance.options import DEFAULT, EngineOptions
from evotol.robots.clearance.result import MaxPoseError
from evotol.robots.clearance.support import warm_up

__all__ = ["ClearanceEvaluator", "MaxPoseError", "as_bounds", "evaluate_cases", "max_pose_error"]


def as_bounds(mech: ClearanceMechanism, bounds, n: int) -> np.ndarray:
    """Check a bounds array against a mechanism (the joints' own bounds when None).

    Parameters
    ----------
    mech : ClearanceMechanism
        The mechanism (its number of joints, and its default bounds).
    bounds : array_like or None
        ``(..., n_joints, 4)``, columns ``[beta_xy (rad), beta_z (rad), b_xy (m), b_z (m)]`` in the
        order of ``mech.joints``; None: ``mech.default_bounds()``.
    n : int
        Number of poses or cases (not used by the check).

    Returns
    -------
    (..., n_joints, 4) ndarray
        The bounds as a float array.

    Raises
    ------
    ValidationError
        A shape not ending in ``(n_joints, 4)``, or negative or non-finite entries.
    """
    if bounds is None:
        b = mech.default_bounds()
    else:
        b = np.asarray(bounds, float)
    if b.shape[-2:] != (mech.n_joints, 4):
        raise ValidationError("bounds shape", b.shape, f"(..., {mech.n_joints}, 4): [beta_xy, beta_z, b_xy, b_z] per joint "
                              f"{[j.name for j in mech.joints]}")
    if not np.all(np.isfinite(b)) or np.any(b < 0):
        raise ValidationError("bounds", "negative or non-finite entries", "finite values >= 0 (rad, m)")
    return b


def evaluate_cases(mech: ClearanceMechanism, maps: list[PoseMaps], pose_index: np.ndarray, bounds: np.ndarray, *,
                   tol: float = 1e-3, tol_solve: float = 2e-5, extra=None,
                   options: EngineOptions = DEFAULT) -> MaxPoseError:
    """Maximum pose errors of the cases ``(pose_index[i], bounds[i])`` (see :func:`_evaluate_cases`)
    with the engine's settings ``options`` (:mod:`evotol.robots.clearance.options`).

    Identical sub-problems (same pose and same bounds on a decoupled block) are solved once; the
    BLAS runs on one thread during the call.

    Parameters
    ----------
    mech : ClearanceMechanism
        The mechanism (its joints name the screws of the result).
    maps : list of PoseMaps
        Precomputed per-pose maps, ``mech.pose_maps(poses)``.
    pose_index : (n_cases,) int array_like
        Pose (index into the poses of ``maps``) of each case.
    bounds : array_like
        Clearance bounds broadcasting to ``(n_cases, n_joints, 4)``, columns ``[beta_xy (rad),
        beta_z (rad), b_xy (m), b_z (m)]``.
    tol_solve : float, optional
        Relative precision of each support-function solve (default 2e-5).
    extra : tuple or None, optional
        ``(J, t)``: other independent interval error sources added to the clearance error.
        ``J`` (n_poses, 6, q) maps them to the end-effector twist ``[dtheta; dp]`` (rad, m; base
        axes), ``t`` (q,) or (n_cases, q) are their half-widths (in the sources' units). Each
        source must act on one decoupled block only. None (default): clearances only.

    Returns
    -------
    MaxPoseError
        Per case: attained and certified maxima (m, rad), maximising screws and twists, and the
        values of the extra sources at the maximisers (when ``extra`` is given).

    Raises
    ------
    ValidationError
        ``J`` not of shape ``(n_poses, 6, q)``; negative or non-finite half-widths ``t``; or a
        source acting on two decoupled blocks.
    """
    # the batched 30x30 solves are several times faster without OpenBLAS threading, and grid
    # workers must not oversubscribe the cores
    with one_blas_thread():
        return _evaluate_cases(mech, maps, pose_index, bounds, tol=tol, tol_solve=tol_solve, extra=extra,
                               options=options)


def _evaluate_cases(mech: ClearanceMechanism, maps: list[PoseMaps], pose_index: np.ndarray, bounds: np.ndarray, *,
                    tol: float = 1e-3, tol_solve: float = 2e-5, extra=None,
                    options: EngineOptions = DEFAULT) -> MaxPoseError:
    """Maximum pose errors for cases ``(pose_index[i], bounds[i])`` using precomputed ``maps``
    (``mech.pose_maps(poses)``). bounds: (n_cases, n_joints, 4). Identical sub-problems (same
    pose and same bounds on a decoupled block) are solved once.

    extra: optional ``(J, t)``: other independent error sources added to the clearance error --
    ``J`` (n_poses, 6, q) maps them to the end-effector twist ``[dtheta; dp]`` (thesis order, base
    axes), ``t`` (q,) or (n_cases, q) are their interval half-widths (e.g. link-length and
    actuator tolerances through the geometric sensitivity J_p). The support functions of the
    clearance set and of the box ``|e_k| <= t_k`` add up (Minkowski sum), so the combined
    worst case is computed by the same certified method."""

    t0 = time.perf_counter()
    pose_index = np.asarray(pose_index, int)
    n = len(pose_index)
    bounds = np.broadcast_to(bounds, (n, mech.n_joints, 4))
    screws = {w: np.zeros((n, mech.n_joints * 6)) for w in ("p", "r")}
    sq = {w: np.zeros((n, 2)) for w in ("p", "r")}   # squared (lower, upper) summed over blocks
    q = 0
    if extra is not None:
        J, t = np.asarray(extra[0], float), np.asarray(extra[1], float)
        q = J.shape[-1]
        if J.ndim != 3 or J.shape[1] != 6 or J.shape[0] != maps[0].C_pos.shape[0]:
            raise ValidationError("extra J shape", J.shape, f"(n_poses={maps[0].C_pos.shape[0]}, 6, q)")
        t = np.broadcast_to(t, (n, q))
        if np.any(t < 0) or not np.all(np.isfinite(t)):
            raise ValidationError("extra tolerances", "negative or non-finite", "half-widths >= 0")
        owner = -np.ones(q, int)
        for b, pm in enumerate(maps):
            comps = list(pm.block.components)
            hit = np.abs(J[:, comps, :]).max(axis=(0, 1)) > 0
            if np.any(hit & (owner >= 0)):
                raise ValidationError("extra J", "a source acting on two decoupled blocks",
                                      "sources that act in-plane or out-of-plane only (or a non-planar mechanism)")
            owner[hit] = b
    extra_val = {w: np.zeros((n, q)) for w in ("p", "r")}
    n_solves = n_newton = 0
    for b, pm in enumerate(maps):
        D = pm.row_bounds(bounds)                                   # (n, R)
        Cp, Cr, B = pm.C_pos, pm.C_rot, pm.B
        mine = np.nonzero(owner == b)[0] if q else np.zeros(0, int)
        if mine.size:
            comps = list(pm.block.components)
            Jb = J[:, :, mine]
            Cp = np.concatenate([Cp, Jb[:, list(pm.pos_comps), :]], axis=2)
            Cr = np.concatenate([Cr, Jb[:, list(pm.rot_comps), :]], axis=2)
            B = np.concatenate([B, np.zeros((B.shape[0], mine.size, B.shape[2]))], axis=1)
            D = np.concatenate([D, t[:, mine]], axis=1)
        key = np.concatenate([pose_index[:, None].astype(float), D], axis=1)
        _, first, back = np.unique(key, axis=0, return_index=True, return_inverse=True)
        back = back.ravel()
        pidx, Du = pose_index[first], D[first]
        Bt = B[pidx] * Du[..., None]
        gi = _gram_pinv(Bt) if pm.n_loops else np.zeros((len(pidx), 0, 0))
        R = pm.n_rows
        for w, C in (("p", Cp), ("r", Cr)):
            if C.shape[1] == 0:
                continue
            Ct = C[pidx] * Du[:, None, :]
            tgt = maximise_norm(Ct, Bt, gi, pm.n_disk, tol=tol, tol_solve=tol_solve, groups=pm.groups, options=options)
            n_solves += tgt.n_solves
            n_newton += tgt.n_newton
            sq[w][:, 0] += tgt.lower[back] ** 2
            sq[w][:, 1] += tgt.upper[back] ** 2
            sfull = tgt.sigma[back] * D
            screws[w][:, pm.cols] = sfull[:, :R]
            if mine.size:
                extra_val[w][:, mine] = sfull[:, R:]
    twists = {}
    for w in ("p", "r"):
        tw = np.zeros((n, 6))
        for pm in maps:
            s = screws[w][:, pm.cols]
            tw[:, list(pm.pos_comps)] = np.einsum("nkr,nr->nk", pm.C_pos[pose_index], s)
            tw[:, list(pm.rot_comps)] = np.einsum("nkr,nr->nk", pm.C_rot[pose_index], s)
        if q:
            tw += np.einsum("nkq,nq->nk", J[pose_index], extra_val[w])
        twists[w] = tw
    res = MaxPoseError(
        p_max=np.sqrt(sq["p"][:, 0]), p_upper=np.sqrt(sq["p"][:, 1]),
        r_max=np.sqrt(sq["r"][:, 0]), r_upper=np.sqrt(sq["r"][:, 1]),
        p_screws=screws["p"].reshape(n, -1, 6), r_screws=screws["r"].reshape(n, -1, 6),
        p_twist=twists["p"], r_twist=twists["r"], joint_names=tuple(j.name for j in mech.joints),
        n_solves=n_solves, seconds=time.perf_counter() - t0, n_newton=n_newton,
        p_extra=extra_val["p"] if q else None, r_extra=extra_val["r"] if q else None)
    return res


def max_pose_error(mech: ClearanceMechanism, poses, bounds=None, *, tol: float = 1e-3, extra=None,
                   options: EngineOptions = DEFAULT) -> MaxPoseError:
    """Global maximum positional and rotational error at each pose (Deng 2012 eqs. III.26-III.27,
    V.8, V.13), with explicit maximising screws and certified upper bounds.

    poses: (n, d) in the mechanism's pose coordinates (m); bounds: None (the joints' own bounds),
    an array (n_joints, 4) for all poses or (n, n_joints, 4) per pose, columns
    ``[beta_xy (rad), beta_z (rad), b_xy (m), b_z (m)]`` in the order of ``mech.joints``.
    tol: relative gap between the attained value and the certified bound (default 0.1 %).
    extra: optional ``(J, t)`` of other interval error sources added to the clearances (see
    :func:`evaluate_cases`), e.g. geometric tolerances through the 5-bar's J_p.
    options: the engine's settings (:data:`evotol.robots.clearance.options.DEFAULT`; ``LEGACY``: before
    issue 13; ``NUMPY``: the NumPy Newton iteration).

    Parameters
    ----------
    bounds : array_like or None, optional
        None (default: the joints' own bounds), ``(n_joints, 4)`` for all poses or
        ``(n, n_joints, 4)`` per pose; columns ``[beta_xy (rad), beta_z (rad), b_xy (m), b_z (m)]``.
    extra : tuple or None, optional
        ``(J, t)`` of other interval error sources (see :func:`evaluate_cases`); None (default):
        clearances only.

    Returns
    -------
    MaxPoseError
        One case per pose: ``p_max``/``p_upper`` (m), ``r_max``/``r_upper`` (rad), the
        maximising screws and twists.

    Raises
    ------
    ValidationError
        Bounds of a wrong shape, negative or non-finite; or a bad ``extra`` (see
        :func:`evaluate_cases`).
    KinematicsError
        The chains do not determine every body's error twist at a pose
        (:meth:`~evotol.robots.clearance.model.ClearanceMechanism.pose_maps`).
    """
    poses = np.atleast_2d(np.asarray(poses, float))
    b = as_bounds(mech, bounds, len(poses))
    maps = mech.pose_maps(poses)
    idx = np.arange(len(poses))
    return evaluate_cases(mech, maps, idx, np.broadcast_to(b, (len(poses),) + b.shape[-2:]), tol=tol, extra=extra,
                          options=options)


def _evaluate_chunk(args):
    mech, maps, idx, b, tol, options = args
    return evaluate_cases(mech, maps, idx, b, tol=tol, options=options)


class ClearanceEvaluator:
    """Evaluate many clearance-bound sets at fixed poses; the per-pose maps are computed once.

    >>> ev = ClearanceEvaluator(mech, poses)           # poses (n, d), metres
    >>> ev.evaluate(bounds, pose_index=0)              # bounds (n_sets, n_joints, 4)
    >>> ev.evaluate_poses(bounds)                      # bounds (n_joints, 4) or (n, n_joints, 4)

    Parameters
    ----------
    poses : (n, d) or (d,) array_like
        Poses in the mechanism's pose coordinates (m); their maps are computed here.

    Raises
    ------
    KinematicsError
        The chains do not determine every body's error twist at a pose.
    ValidationError
        A planar mechanism whose blocks do not decouple.
    """

    def __init__(self, mech: ClearanceMechanism, poses, *, tol: float = 1e-3, options: EngineOptions = DEFAULT):
        self.mech = mech
        self.poses = np.atleast_2d(np.asarray(poses, float))
        self.maps = mech.pose_maps(self.poses)
        self.tol = tol
        self.options = options

    def evaluate(self, bounds, pose_index=0, *, workers: int = 1, scheduler=None, chunk_size: int = 4096) -> MaxPoseError:
        """All bound sets at their poses. ``workers > 1`` (local processes) or ``scheduler`` (a
        Dask address or Client) split the sets into chunks of ``chunk_size`` solved in parallel;
        results come back in order.

        Parameters
        ----------
        bounds : array_like
            Bound sets ``(..., n_joints, 4)`` (flattened to ``(n_sets, n_joints, 4)``), columns
            ``[beta_xy (rad), beta_z (rad), b_xy (m), b_z (m)]``.
        pose_index : int or (n_sets,) int array_like, optional
            Pose (index into ``poses``) of each set (default 0: the first pose).
        workers : int or None, optional
            Local processes (default 1: in this process; None: all CPUs).
        scheduler : str or distributed.Client or None, optional
            Dask scheduler address or client (default None: local).
        chunk_size : int, optional
            Sets per parallel chunk (default 4096); no parallel run for at most ``chunk_size``
            sets.

        Returns
        -------
        MaxPoseError
            One case per set, in the order of ``bounds`` (``seconds``: wall time).

        Raises
        ------
        ValidationError
            Bounds of a wrong shape, negative or non-finite, or a pose index out of range.
        """
        b = as_bounds(self.mech, bounds, 0)
        b = b.reshape((-1,) + b.shape[-2:])
        idx = np.broadcast_to(np.asarray(pose_index, int), (len(b),))
        if idx.size and (idx.min() < 0 or idx.max() >= len(self.poses)):
            raise ValidationError("pose_index", pose_index, f"indices in [0, {len(self.poses)})")
        if (workers is None or workers > 1 or scheduler is not None) and len(b) > chunk_size:
            t0 = time.perf_counter()
            items = [(self.mech, self.maps, idx[s:s + chunk_size], b[s:s + chunk_size], self.tol, self.options)
                     for s in range(0, len(b), chunk_size)]
            warm_up()     # compile the solver's kernels once here, not once per worker
            out = MaxPoseError.concat(parallel_map(_evaluate_chunk, items, workers=workers, scheduler=scheduler))
            out.seconds = time.perf_counter() - t0
            return out
        return evaluate_cases(self.mech, self.maps, idx, b, tol=self.tol, options=self.options)

    def evaluate_poses(self, bounds=None) -> MaxPoseError:
        """One bound set (or one per pose) at every pose.

        Parameters
        ----------
        bounds : array_like or None, optional
            None (default: the joints' own bounds), ``(n_joints, 4)`` for all poses or
            ``(n_poses, n_joints, 4)``; columns ``[beta_xy (rad), beta_z (rad), b_xy (m), b_z (m)]``.

        Returns
        -------
        MaxPoseError
            One case per pose.

        Raises
        ------
        ValidationError
            Bounds of a wrong shape, negative or non-finite.
        """
        n = len(self.poses)
        b = as_bounds(self.mech, bounds, n)
        return evaluate_cases(self.mech, self.maps, np.arange(n), np.broadcast_to(b, (n,) + b.shape[-2:]), tol=self.tol,
                              options=self.options)

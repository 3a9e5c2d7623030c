"""Certified maximum pose errors of many mechanisms of one family in one engine call.

A dimension sweep (e.g. the IRSBot-2 designs of Deng 2012 Sec. VII.2) builds one
:class:`~evotol.robots.clearance.model.ClearanceMechanism` per design; designs of one family share joints,
chains and clearance bounds, only their dimensions differ. Their per-pose maps
(``mech.pose_maps``) then stack along the pose axis and :func:`evotol.robots.clearance.evaluate_cases`
solves every (design, pose) case in one vectorised call -- the numbers of one
:func:`evotol.robots.clearance.max_pose_error` call per design (within the 0.1 % certificate), at a
lower cost per case.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from evotol.robots.clearance.maxerror import evaluate_cases, max_pose_error


def _same_layout(a, b) -> bool:
    return (a.block == b.block and a.n_disk == b.n_disk and np.array_equal(a.cols, b.cols)
            and np.array_equal(a.cone_joint, b.cone_joint) and np.array_equal(a.cone_kind, b.cone_kind)
            and a.B.shape[1:] == b.B.shape[1:] and a.C_pos.shape[1:] == b.C_pos.shape[1:]
            and a.C_rot.shape[1:] == b.C_rot.shape[1:])


def max_pose_error_stacked(mechanisms: list, points: list) -> list[tuple[np.ndarray, np.ndarray]]:
    """``[(p_max (m), r_max (rad)) at points[k]]`` for every ``mechanisms[k]`` (poses in metres).

    One vectorised engine call when the mechanisms' pose maps and default bounds stack; one
    :func:`~evotol.robots.clearance.max_pose_error` call per mechanism otherwise.

    Parameters
    ----------
    mechanisms : list of ClearanceMechanism
        One mechanism per design (each evaluated with its joints' own bounds).
    points : list of array_like
        ``points[k]``: poses ``(n_k, d)`` of ``mechanisms[k]``, m.

    Returns
    -------
    list of (ndarray, ndarray)
        Per mechanism, ``(p_max (n_k,) in m, r_max (n_k,) in rad)``: the attained maxima.
    """
    if not mechanisms:
        return []
    maps = [m.pose_maps(np.asarray(pt, float)) for m, pt in zip(mechanisms, points)]
    ref = mechanisms[0]
    stackable = (all(len(mp) == len(maps[0]) and all(_same_layout(a, b) for a, b in zip(mp, maps[0])) for mp in maps)
                 and all(np.array_equal(m.default_bounds(), ref.default_bounds()) for m in mechanisms))
    if not stackable:
        out = []
        for m, pt in zip(mechanisms, points):
            res = max_pose_error(m, pt)
            out.append((np.asarray(res.p_max), np.asarray(res.r_max)))
        return out
    merged = [replace(pm, C_pos=np.concatenate([mp[k].C_pos for mp in maps]),
                      C_rot=np.concatenate([mp[k].C_rot for mp in maps]),
                      B=np.concatenate([mp[k].B for mp in maps])) for k, pm in enumerate(maps[0])]
    n = sum(len(pt) for pt in points)
    b = ref.default_bounds()
    res = evaluate_cases(ref, merged, np.arange(n), np.broadcast_to(b, (n,) + b.shape))
    out, s = [], 0
    for pt in points:
        out.append((res.p_max[s:s + len(pt)], res.r_max[s:s + len(pt)]))
        s += len(pt)
    return out

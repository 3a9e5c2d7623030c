"""Loop closure: a clearance mechanism's chain equations reduced to the per-pose maps of each
decoupled block (Deng 2012 eqs. III.13, III.22-III.24, V.1-V.4, V.28).

All chains stacked give ``E_s s + E_d delta = 0``
(:meth:`~evotol.robots.clearance.model.ClearanceMechanism.linear_system`). Per block of components this
module lays out the clearance cones (disks first, then intervals), computes the end-effector rows
``C = -(E_d^+ E_s)_P`` and the loop-equation map ``B = E_s^T N`` with ``N`` a basis of
``null(E_d^T)``: a *sparse* one when it can be built -- one block of columns per independent loop
(2-chain loops between chains joining the same bodies, loops closed through the base for chains
reaching a body from different bodies) -- else the SVD basis, and the row groups of ``B`` (its
block sparsity, used by the Newton systems). The result, one
:class:`~evotol.robots.clearance.pose_maps.PoseMaps` per block, is what
:meth:`evotol.robots.clearance.model.ClearanceMechanism.pose_maps` returns.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.clearance.parts import CONE_COMPONENTS, FULL, POS, ROT
from evotol.robots.clearance.pose_maps import PoseMaps


def _block_maps(mech, poses: np.ndarray, split: bool = True) -> list[PoseMaps]:
    """The work of :meth:`evotol.robots.clearance.model.ClearanceMechanism.pose_maps` (see it)."""
    poses = np.atleast_2d(np.asarray(poses, float))
    Es, Ed = mech.linear_system(poses)
    nb = Ed.shape[2] // 6
    out = []
    blocks = mech.blocks if split else FULL
    for blk in blocks:
        comps = list(blk.components)
        rows = [6 * c + k for c in range(len(mech.chains)) for k in comps]
        bcols = [6 * b + k for b in range(nb) for k in comps]
        # cone layout: disks first, then intervals (cones split by the block are an error)
        disk, inter = [], []
        for j in range(mech.n_joints):
            for kind, cc in enumerate(CONE_COMPONENTS):
                inside = [k in comps for k in cc]
                if all(inside):
                    (disk if len(cc) == 2 else inter).append((j, kind, [6 * j + k for k in cc]))
                elif any(inside):
                    raise ValidationError(f"block {blk.name}", cc, "cones entirely inside one block")
        cones = disk + inter
        cols = np.array([c for _, _, cc in cones for c in cc], dtype=int)
        if len(blocks) > 1:  # check that the block really decouples
            other_cols = np.setdiff1d(np.arange(Es.shape[2]), cols)
            other_b = np.setdiff1d(np.arange(Ed.shape[2]), bcols)
            leak = max(np.abs(Es[:, rows][:, :, other_cols]).max(initial=0.0),
                       np.abs(Ed[:, rows][:, :, other_b]).max(initial=0.0))
            scale = max(np.abs(Es).max(), 1.0)
            if leak > 1e-9 * scale:
                raise ValidationError(f"{mech.name}: planar block {blk.name}", float(leak),
                                      "zero coupling with the other block (are all joint axes parallel to z?)")
        es = Es[:, rows][:, :, cols]
        ed = Ed[:, rows][:, :, bcols]
        U, S, Vt = np.linalg.svd(ed, full_matrices=True)
        nbc = ed.shape[2]
        singular = S[:, -1] < 1e-9 * np.maximum(S[:, 0], 1e-300)   # an all-zero block is singular too
        if np.any(singular):
            bad = np.nonzero(singular)[0]
            raise KinematicsError(f"{mech.name}: the chains do not determine every body's error twist at pose "
                                  f"{poses[bad[0]].tolist()}", poses=poses[bad])
        # C = -(Ed^+ Es) restricted to the end-effector (body 0) components
        pinv = np.einsum("nji,nj,nkj->nik", Vt, 1.0 / S, U[:, :, :nbc])
        C = -(pinv @ es)[:, :len(comps), :]
        N, loops = _loop_basis(mech, ed, len(comps))
        if N is None:
            N = U[:, :, nbc:]
            loops = [list(range(len(mech.chains)))] * (N.shape[2] // max(len(comps), 1))
        B = np.swapaxes(es, 1, 2) @ N
        groups = _groups(mech, cones, loops, len(comps), len(disk))
        pos = tuple(i for i, k in enumerate(comps) if k in POS)
        rot = tuple(i for i, k in enumerate(comps) if k in ROT)
        out.append(PoseMaps(block=blk, cols=cols, cone_joint=np.array([c[0] for c in cones], int),
                            cone_kind=np.array([c[1] for c in cones], int), n_disk=len(disk),
                            pos_comps=tuple(comps[i] for i in pos), rot_comps=tuple(comps[i] for i in rot),
                            C_pos=C[:, list(pos), :], C_rot=C[:, list(rot), :], B=B, groups=groups))
    return out


def _loop_basis(mech, ed: np.ndarray, nc: int):
    """A sparse basis of the loop equations, ``N`` with ``E_d^T N = 0``: one ``nc``-column block
    per independent loop. Chains between the same two bodies pair up (2-chain loops: the
    parallelograms' and the distal modules' loops, the two legs of the 5-bar); groups of
    chains reaching a body from different bodies are closed through the tree of first
    chains back to the base (the IRSBot-2's leg-to-leg loop, 4 chains). Each loop touches
    few chains, so ``B = E_s^T N`` is block sparse -- the Newton systems are assembled per
    group of rows (several times cheaper than with a dense null-space basis). Returns
    (None, None) if the construction does not give a basis (then an SVD basis is used)."""
    n = ed.shape[0]
    chains = mech.chains
    bodies = [mech.end_effector] + [b for b in mech.body_names if b != mech.end_effector]
    bidx = {b: i for i, b in enumerate(bodies)}
    start = [bidx.get(c.start, -1) if c.start != "base" else -1 for c in chains]
    end = [bidx[c.end] for c in chains]
    # tree: first chain into each body, reached from the base outwards
    tree_in, reached = {}, {-1}
    changed = True
    while changed:
        changed = False
        for ci, c in enumerate(chains):
            if start[ci] in reached and end[ci] not in reached:
                tree_in[end[ci]] = ci
                reached.add(end[ci])
                changed = True
    if len(reached) != len(bodies) + 1:
        return None, None

    def Me(ci):                     # M^e of chain ci restricted to the block, (n, nc, nc)
        r = slice(nc * ci, nc * ci + nc)
        sb = start[ci]
        return -ed[:, r, nc * sb:nc * sb + nc]

    def pair(c1, c2):
        lam = {c1: np.broadcast_to(np.eye(nc), (n, nc, nc)).copy(), c2: -np.broadcast_to(np.eye(nc), (n, nc, nc))}
        if start[c1] != start[c2]:
            for c, sign in ((c1, 1.0), (c2, -1.0)):
                W = sign * np.swapaxes(Me(c), 1, 2)        # wrench balance at the start body
                b = start[c]
                while b != -1:
                    t = tree_in[b]
                    lam[t] = lam.get(t, 0) + W
                    W = np.swapaxes(Me(t), 1, 2) @ W if start[t] != -1 else None
                    b = start[t]
        return lam

    loops = []
    for b in range(len(bodies)):
        ins = [ci for ci in range(len(chains)) if end[ci] == b]
        by_start = {}
        for ci in ins:
            by_start.setdefault(start[ci], []).append(ci)
        refs = []
        for grp in by_start.values():
            refs.append(grp[0])
            for ci in grp[1:]:
                loops.append(pair(ci, grp[0]))
        for r in refs[1:]:
            loops.append(pair(r, refs[0]))
    if not loops:
        return np.zeros((n, ed.shape[1], 0)), []
    N = np.zeros((n, ed.shape[1], nc * len(loops)))
    touched = []
    for li, lam in enumerate(loops):
        for ci, L in lam.items():
            N[:, nc * ci:nc * ci + nc, nc * li:nc * li + nc] = L
        touched.append(sorted(ci for ci, L in lam.items() if np.abs(L).max() > 0))
    scale = max(np.abs(ed).max(), 1.0)
    if np.abs(np.swapaxes(ed, 1, 2) @ N).max() > 1e-10 * scale * max(np.abs(N).max(), 1.0):
        return None, None
    sv = np.linalg.svd(N, compute_uv=False)
    if np.any(sv[:, -1] < 1e-8 * sv[:, 0]) or N.shape[2] != ed.shape[1] - ed.shape[2]:
        return None, None
    return N, touched


def _groups(mech, cones, loops, nc: int, n_disk: int) -> tuple:
    """Row groups of B with their loop columns (see PoseMaps.groups)."""
    support = {}
    for j in range(mech.n_joints):
        jn = mech.joints[j].name
        cs = {ci for ci, c in enumerate(mech.chains) if jn in c.joints}
        support[j] = tuple(sorted(k for li, ch in enumerate(loops) if cs & set(ch) for k in range(nc * li, nc * li + nc)))
    groups = {}
    for ci_, (j, kind, cc) in enumerate(cones):
        g = groups.setdefault(support[j], ([], []))
        if ci_ < n_disk:
            g[0].append(ci_)
        else:
            g[1].append(2 * n_disk + (ci_ - n_disk))
    return tuple((np.array(d, int), np.array(i, int), np.array(cols, int)) for cols, (d, i) in groups.items() if len(cols))

"""The worst case over many poses, one block of poses at a time (issue 43 item 4: memory that grows with
what is kept). The support coefficients ``c[p, d, j]`` of :func:`~evotol.measures.linear.support_coefficients`
take ``8 D n`` bytes a pose (600 directions x 36 sources: 173 kB), more than everything a study keeps
about a pose; above a size they are computed for a block of poses, used and dropped.

:func:`worst_case_by_blocks` gives the numbers of :func:`~evotol.measures.linear.worst_case` on all poses
at once: every pose's grid maximum, ascent and bound are its own. Two things couple poses, and both are
kept: ``top_only``'s test for a pose that may hold a design's largest error uses the largest grid value
over *all* poses (a first pass over the blocks finds it), and the ascent's common stopping test, which
makes the attained values agree to round-off and the worst directions to the ascent's precision.
Blocks are taken by up to :data:`MAX_THREADS` threads at a time (one per core).
"""
from __future__ import annotations

import os
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from evotol.measures.linear.stackup import WorstCase, worst_case
from evotol.measures.linear.support import IntervalShape, support_constant
from evotol.measures.linear.support_grid import LazySupport, support_grid

#: threads that take blocks of poses at the same time (NumPy and BLAS release the GIL in their loops); each
#: block's numbers are its own, so they do not depend on the number of threads
MAX_THREADS = 4


class PoseBlocks(Sequence):
    """``[(poses, (c, D, delta[, const]))]`` for consecutive blocks of ``step`` poses (the layout of
    :meth:`evotol.core.problem.ToleranceProblem.coefficients`), ``c`` a
    :class:`~evotol.measures.linear.support_grid.LazySupport`: never kept whole.

    Parameters
    ----------
    blocks : list of ndarray
        The sources' blocks ``B_j`` (n_poses, 3, dim_j) of one component.
    D : ndarray, shape (n_directions, 3)
        The direction grid.
    delta : float
        Its covering angle (rad).
    shape : IntervalShape or None
        The intervals' shape; None: plain ±t (no ``const``).
    step : int
        Poses per block (>= 1).
    """

    def __init__(self, blocks: list, D: np.ndarray, delta: float, shape: IntervalShape | None, step: int):
        self.blocks, self.D, self.delta, self.shape, self.step = blocks, D, delta, shape, int(step)
        self.n_poses = blocks[0].shape[0]

    def __len__(self) -> int:
        return -(-self.n_poses // self.step)

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        if not -len(self) <= i < len(self):
            raise IndexError(i)
        i %= len(self)
        sl = slice(i * self.step, min(self.n_poses, (i + 1) * self.step))
        part = [B[sl] for B in self.blocks]
        c = LazySupport(part, self.D, self.shape)           # computed a few poses at a time when used
        return sl, (c, self.D, self.delta) if self.shape is None else (c, self.D, self.delta,
                                                                         support_constant(part, self.D, self.shape))


def worst_case_by_blocks(blocks: list, t: np.ndarray, pieces, top_only: bool = False,
                         shape: IntervalShape | None = None, n_starts: int = 8) -> WorstCase:
    """:func:`~evotol.measures.linear.worst_case` of designs ``t`` over every pose, block by block.

    Parameters
    ----------
    blocks : list of ndarray
        Every pose's blocks ``B_j`` (n_poses, 3, dim_j); each block of poses takes its rows.
    t : array_like, shape (n_designs, n_src) or (n_src,)
        The designs' tolerances, one row per design (SI: m or rad).
    pieces : sequence of (slice, tuple)
        :meth:`evotol.core.problem.ToleranceProblem.coefficient_blocks`: the poses and coefficients of
        each block; one block ``slice(None)`` is the plain call.
    top_only, shape, n_starts
        As :func:`~evotol.measures.linear.worst_case`.

    Returns
    -------
    WorstCase
        Per design and pose (the design axis dropped for a single design ``t``).
    """
    if len(pieces) == 1 and pieces[0][0] == slice(None):
        return worst_case(blocks, t, coefficients=pieces[0][1], top_only=top_only, shape=shape, n_starts=n_starts)
    t = np.asarray(t, dtype=float)
    T = np.atleast_2d(t)
    level = None
    with ThreadPoolExecutor(max_workers=max(1, min(len(pieces), os.cpu_count() or 1, MAX_THREADS))) as pool:
        if top_only:        # the largest grid value of each design over every pose: a first pass
            level = np.full(T.shape[0], -np.inf)
            for top in pool.map(lambda piece: support_grid(piece[1], T).max(axis=(1, 2)), pieces):
                level = np.maximum(level, top)
        parts = list(pool.map(lambda piece: worst_case([B[piece[0]] for B in blocks], T, coefficients=piece[1],
                                                       top_only=top_only, shape=shape, n_starts=n_starts,
                                                       top_level=level), pieces))
    res = WorstCase(*(np.concatenate([getattr(r, f) for r in parts], axis=1) for f in WorstCase.__dataclass_fields__))
    return WorstCase(*(getattr(res, f)[0] for f in WorstCase.__dataclass_fields__)) if t.ndim == 1 else res

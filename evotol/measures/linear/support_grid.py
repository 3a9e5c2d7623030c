"""Grid values of the support function, ``g[n, p, d] = c[p, d, :]·t_n (+ const)``, from support
coefficients that are stored or that are never stored whole (issue 43 item 4: memory that grows with
what is kept, and time that does not grow with what is thrown away).

Above :data:`~evotol.core.problem.tolerance_problem.COEFFICIENT_CACHE_BYTES` a component's coefficients
``c[p, d, j]`` (:func:`~evotol.measures.linear.support_coefficients`; 173 kB a pose for 600 directions and
36 sources) are not kept. Written out for a block of hundreds of poses and read back for the product with
the designs, they made the worst case of 10 648 UR5 poses memory-bound (1.8 GB written and read per
evaluation); :class:`LazySupport` computes them a few poses at a time, in a buffer that stays in the
processor's cache, and multiplies at once: the same products of the same coefficients.
"""
from __future__ import annotations

import numpy as np

from evotol.measures.linear.support import IntervalShape, line_coefficients, support_coefficients

#: bytes of coefficients computed and multiplied at a time (they stay in the processor's cache)
STEP_BYTES = 1 << 20


class LazySupport:
    """The support coefficients of a block of poses, computed a step of poses at a time when a grid is
    asked for (:func:`support_grid`) and never kept.

    Parameters
    ----------
    blocks : list of ndarray
        Each source's block ``B_j`` (n_poses, 3, dim_j) at this block's poses, one component.
    D : ndarray, shape (n_dir, 3)
        The direction grid.
    interval_shape : IntervalShape or None
        As ``shape`` of :func:`~evotol.measures.linear.support_coefficients`.
    """

    def __init__(self, blocks: list, D: np.ndarray, interval_shape: IntervalShape | None):
        self.blocks, self.D, self.interval_shape = blocks, D, interval_shape
        #: what the stored array would be: (n_poses, n_dir, n_src)
        self.shape = (blocks[0].shape[0], D.shape[0], len(blocks))

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        c = support_coefficients(self.blocks, self.D, self.interval_shape)
        return c if dtype is None else c.astype(dtype)

    def grid(self, T: np.ndarray) -> np.ndarray:
        """``g[n, p, d] = c[p, d, :]·T[n]`` (m or rad), a step of poses at a time.

        Parameters
        ----------
        T : ndarray, shape (n_designs, n_src)
            One design a row (tolerances, SI: m or rad).

        Returns
        -------
        ndarray, shape (n_designs, n_poses, n_dir)
            The grid values without the offsets' constant.
        """
        P, nd, m = self.shape
        step = max(1, STEP_BYTES // (8 * nd * m))
        out = np.empty((T.shape[0], P, nd))
        if all(B.shape[2] == 1 for B in self.blocks):       # intervals only: support_coefficients' steps, inlined
            Bl, sh = np.concatenate(self.blocks, axis=2), self.interval_shape     # concatenated once, not per step
            buf = np.empty((step, nd, m))
            for s in range(0, P, step):
                seg = buf[:min(step, P - s)]
                line_coefficients(Bl[s:s + step], self.D, None if sh is None else (sh.rho, sh.kappa), seg)
                out[:, s:s + seg.shape[0]] = _product(seg, T)
            return out
        for s in range(0, P, step):
            c = support_coefficients([B[s:s + step] for B in self.blocks], self.D, self.interval_shape)
            out[:, s:s + c.shape[0]] = _product(c, T)
        return out


def support_rows(c, pp: np.ndarray, dd: np.ndarray) -> np.ndarray:
    """The coefficient rows ``c[pp[i], dd[i], :]`` (the worst case's constraint rows), from stored or
    :class:`LazySupport` coefficients (computed for those poses only, a step at a time).

    Parameters
    ----------
    c : ndarray or LazySupport
        The coefficients (n_poses, n_dir, n_src).
    pp, dd : ndarray of int
        Pose and direction of each row.

    Returns
    -------
    ndarray, shape (len(pp), n_src)
        The rows (m or rad per unit of tolerance).
    """
    if isinstance(c, np.ndarray):
        return c[pp, dd, :]
    out = np.empty((len(pp), c.shape[2]))
    poses, inv = np.unique(pp, return_inverse=True)
    step = max(1, STEP_BYTES // (8 * c.shape[1] * c.shape[2]))
    for s in range(0, len(poses), step):
        sel = (inv >= s) & (inv < s + step)
        part = support_coefficients([B[poses[s:s + step]] for B in c.blocks], c.D, c.interval_shape)
        out[sel] = part[inv[sel] - s, dd[sel]]
    return out


def _product(c: np.ndarray, T: np.ndarray) -> np.ndarray:
    """``c[p, d, :]·T[n]`` as (n, p, d)."""
    return np.moveaxis((c.reshape(-1, c.shape[2]) @ T.T).reshape(c.shape[0], c.shape[1], -1), 2, 0)


def support_grid(coefficients: tuple, T: np.ndarray) -> np.ndarray:
    """The grid values ``c[p, d, :]·t_n + const[p, d]`` of designs ``T`` from coefficients
    ``(c, D, delta[, const])``, ``c`` stored (an array) or not (:class:`LazySupport`).

    Parameters
    ----------
    coefficients : tuple
        ``(c, D, delta[, const])`` of :meth:`evotol.core.problem.ToleranceProblem.coefficient_blocks`.
    T : ndarray, shape (n_designs, n_src)
        The designs (SI: m or rad).

    Returns
    -------
    ndarray, shape (n_designs, n_poses, n_dir)
        The support function's value along each grid direction (m or rad).
    """
    c = coefficients[0]
    grid = _product(c, T) if isinstance(c, np.ndarray) else c.grid(T)
    if len(coefficients) > 3:
        grid += coefficients[3][None]
    return grid

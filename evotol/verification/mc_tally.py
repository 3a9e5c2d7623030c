"""What a Monte Carlo verification keeps of one design's samples, pose chunk by pose chunk.

:func:`evotol.verification.montecarlo.verify_designs` draws each chunk's unit samples once and hands
every design's first-order errors (and nonlinear errors, where the robot has a model) to that design's
:class:`Tally`; a tally keeps per pose only what the result reports (exceed rates, the largest error,
its 95 % quantile, the yields) and the linearisation error, never the samples themselves.
"""
from __future__ import annotations

import numpy as np

from evotol.verification.nonlinear import ROWS       # the rows of an error twist each component takes


class Tally:
    """Per-pose statistics of one design's samples, added chunk by chunk.

    Parameters
    ----------
    components : sequence of (str, float)
        The constrained components and their limits (m or rad).
    n_poses : int
        Poses of the problem.
    nonlinear : bool
        Whether nonlinear errors are added too.
    """

    def __init__(self, components, n_poses: int, nonlinear: bool):
        self.components = list(components)
        self.exceed = {c: np.zeros(n_poses) for c, _ in self.components}
        self.exceed_nl = {c: np.zeros(n_poses) for c, _ in self.components} if nonlinear else {}
        self.maxerr = {c: np.zeros(n_poses) for c, _ in self.components}
        self.q95 = {c: np.zeros(n_poses) for c, _ in self.components}
        self.inside_lin = np.zeros(n_poses)
        self.inside_nl = np.zeros(n_poses) if nonlinear else None
        self.lin_err, self.lin_scale = 0.0, 0.0

    def add(self, idx: np.ndarray, lin: np.ndarray, nl: np.ndarray | None) -> None:
        """Add the samples of the poses ``idx``.

        Parameters
        ----------
        idx : ndarray of int, shape (k,)
            The chunk's poses.
        lin : ndarray, shape (k, n_samples, 6)
            First-order error twists (m, rad).
        nl : ndarray, shape (k, n_samples, 6), or None
            Nonlinear error twists (NaN: not assembled, a miss); None without a nonlinear model.
        """
        ok = np.ones(lin.shape[:2], dtype=bool)
        for c, lim in self.components:
            nrm = np.linalg.norm(lin[:, :, ROWS[c]], axis=2)
            ok &= nrm <= lim
            self.exceed[c][idx] = np.mean(nrm > lim, axis=1)
            self.maxerr[c][idx] = nrm.max(axis=1)
            self.q95[c][idx] = np.quantile(nrm, 0.95, axis=1)
        self.inside_lin[idx] = ok.mean(axis=1)
        if nl is None:
            return
        assembled = np.all(np.isfinite(nl), axis=2)
        if assembled.any():
            self.lin_err = max(self.lin_err, float(np.max(np.abs(nl - lin)[assembled])))
        self.lin_scale = max(self.lin_scale, float(np.max(np.abs(lin))))
        ok = np.ones(lin.shape[:2], dtype=bool)
        for c, lim in self.components:
            nrm = np.linalg.norm(nl[:, :, ROWS[c]], axis=2)
            ok &= nrm <= lim                                 # NaN (not assembled) is a miss
            self.exceed_nl[c][idx] = np.mean(~(nrm <= lim), axis=1)
        self.inside_nl[idx] = ok.mean(axis=1)

    @property
    def linearisation_error(self) -> float | None:
        """``max |nonlinear − linear| / max |linear|`` over the samples (dimensionless); None without
        nonlinear errors (or without any first-order error)."""
        return (self.lin_err / self.lin_scale) if self.exceed_nl and self.lin_scale > 0 else None

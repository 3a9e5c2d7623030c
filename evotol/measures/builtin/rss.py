"""The ``rss`` measure: root sum square of every source's worst-case effect t_j‖B_j‖₂ at each pose,
plus the norm of the mean shift of asymmetric intervals added linearly (:func:`evotol.measures.linear.rss`,
``docs/tolerances.md``)."""
from __future__ import annotations

import numpy as np

from evotol.measures import linear as measures
from evotol.measures.protocol import COMPONENTS, ComponentErrors, Evaluation, Measure, evaluation_of, violation


def _shift_shares(problem, comp: str, T: np.ndarray, S: np.ndarray, val: np.ndarray) -> np.ndarray:
    """... plus each interval source's part of the mean shift's norm: ``c_j (B_j·ŝ) / value`` with
    ``c_j = offset_j + κ_j t_j`` and ŝ the unit shift (issue 34: the side a one-sided tolerance
    binds on). The parts sum to ``|s| / value``, so all shares sum to 1; a source whose shift
    opposes the total has a negative part."""
    n_hat = S / np.where((nrm := np.linalg.norm(S, axis=-1, keepdims=True)) > 0, nrm, 1.0)
    sh = problem.shape
    out = np.zeros(S.shape[:2] + (T.shape[1],))
    for j, B in enumerate(problem.blocks[comp]):
        if B.shape[2] == 1 and (sh.offset[j] != 0 or sh.kappa[j] != 0):
            c = sh.offset[j] + sh.kappa[j] * T[:, j]                                      # (n,)
            out[..., j] = c[:, None] * np.einsum("npk,pk->np", n_hat, B[:, :, 0]) / np.where(val > 0, val, 1.0)
    return out


class RSSMeasure(Measure):
    """Statistical stack-up: sqrt(Σ_j (ρ_j t_j ‖B_j‖₂)²) + ``|s(t)|`` (m or rad) per pose."""

    name = "rss"

    def evaluate(self, problem, T: np.ndarray, top_only: bool = False) -> Evaluation:
        """RSS errors per pose, also as the ``*_bound``, and each source's share (``*_contrib``: of the
        RSS part by variance, of the mean shift by each source's projection on it; they sum to 1);
        ``top_only`` is ignored (the RSS is cheap at every pose).
        """
        plain = problem.shape.plain
        Th = T if plain else T * problem.shape.rho
        parts = {}
        for comp in COMPONENTS:
            S = None if plain else measures.mean_shift(problem.blocks[comp], problem.shape, T)     # (n, P, 3)
            shift = None if plain else np.linalg.norm(S, axis=-1)
            val = measures.rss(problem.sensitivities[comp], Th, shift)
            sq = (Th[:, None, :] * problem.sensitivities[comp][None]) ** 2
            if shift is None:
                contrib = sq / np.where(val ** 2 > 0, val ** 2, 1.0)[..., None]
            else:   # share of the RSS part, scaled by the RSS part's share of the total ...
                r = val - shift
                contrib = sq / np.where(r ** 2 > 0, r ** 2, 1.0)[..., None] * (r / np.where(val > 0, val, 1.0))[..., None]
                contrib = contrib + _shift_shares(problem, comp, T, S, val)

            parts[comp] = ComponentErrors(val, val, contrib)
        return evaluation_of(parts, violation(problem, parts))

    def brute_force(self, problem, t: np.ndarray) -> dict[str, np.ndarray]:
        """Pose by pose and source by source: the largest singular value of each block (SVD), the
        half-widths ρ_j t_j, and the mean shift Σ_j B_j c_j with c_j = offset_j + κ_j t_j; returns
        ``"position"`` (m) and ``"orientation"`` (rad) RSS errors per pose.
        """
        sh = problem.shape
        out = {}
        for comp in COMPONENTS:
            vals = []
            for p in range(problem.n_poses):
                sq, shift = 0.0, np.zeros(3)
                for j, B in enumerate(problem.blocks[comp]):
                    sq += (sh.rho[j] * t[j] * np.linalg.svd(B[p], compute_uv=False)[0]) ** 2
                    if B.shape[2] == 1:
                        shift += B[p][:, 0] * (sh.offset[j] + sh.kappa[j] * t[j])
                vals.append(np.sqrt(sq) + np.linalg.norm(shift))
            out[comp] = np.array(vals)
        return out


RSS = RSSMeasure()

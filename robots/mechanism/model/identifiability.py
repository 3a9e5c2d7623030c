"""Which directions a set of error sources can move the end-effector in: rank, blind and
duplicated directions of the sensitivities stacked over poses.

The sensitivities ``S`` (n, 6, n_sources) of the poses of a workspace are stacked into one
(6 n, n_sources) matrix ``A``; every column is scaled to unit norm first (m and rad columns side by
side), so the rank is a property of the directions, not of the units. Then

* **rank**: singular values of ``A`` above ``rtol`` times the largest;
* **blind source**: a column that is zero at every pose (the source moves nothing);
* **duplicated sources**: two columns equal up to sign (``|cos| > 1 - rtol``), e.g. the roll and yaw
  of a URDF origin at pitch = pi/2, or a joint offset and the rotation of its own origin about the
  joint axis;
* **dependent combinations**: the rest of the null space of ``A`` (a basis, named by its largest
  coefficients);
* **missing directions**: columns of a *reference* model (for a URDF arm: every placement twist
  of every joint origin and of the tip, the span of Pinocchio's placement regressor) that the
  sources cannot reproduce (relative residual of the least-squares fit above ``sqrt(rtol)``).
"""
from __future__ import annotations

import numpy as np


def _stack(S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(unit-norm columns (6 n, m), column norms (m,)) of sensitivities (n, 6, m)."""
    A = np.asarray(S, float).reshape(-1, S.shape[-1])
    norms = np.linalg.norm(A, axis=0)
    return A / np.where(norms > 0, norms, 1.0), norms


def stacked_rank(S: np.ndarray, rtol: float = 1e-9) -> int:
    """Rank of the sensitivities (n, 6, m) stacked over poses, columns at unit norm.

    Parameters
    ----------
    S : ndarray (n, 6, m)
        ``[dp (m); dphi (rad)]`` per unit error of each of ``m`` sources at ``n`` poses.
    rtol : float
        Singular values below ``rtol`` times the largest count as zero.

    Returns
    -------
    int
        Number of independent source directions over all poses (0 for no sources).
    """
    A, _ = _stack(S)
    if A.size == 0:
        return 0
    s = np.linalg.svd(A, compute_uv=False)
    return int((s > rtol * max(s[0], 1e-300)).sum())


def analyse(S: np.ndarray, names, reference: np.ndarray | None = None, reference_names=None, rtol: float = 1e-9) -> dict:
    """Rank, blind, duplicated and dependent sources, and reference directions no source reaches.

    Parameters
    ----------
    S : ndarray (n, 6, m)
        Sensitivities of the ``m`` sources at ``n`` poses.
    names : sequence of str
        The sources' names.
    reference, reference_names : ndarray (n, 6, k), sequence of str, optional
        A model whose span the sources should cover (same poses).
    rtol : float
        Relative tolerance of the rank and of the duplicate test.

    Returns
    -------
    dict
        ``rank``, ``n_sources``, ``blind`` (names), ``duplicated`` (``[a, b, sign]``),
        ``dependent`` (each a list of ``[name, coefficient]``, largest first), and with a reference
        ``reference_rank``, ``combined_rank`` and ``missing`` (reference names with their residual).
    """
    names = list(names)
    A, norms = _stack(S)
    scale = norms.max() if norms.size else 0.0
    blind = [names[i] for i in range(len(names)) if norms[i] <= rtol * max(scale, 1e-300)]
    live = [i for i in range(len(names)) if names[i] not in blind]
    C = A[:, live].T @ A[:, live]
    dup, in_dup = [], set()
    for a in range(len(live)):
        for b in range(a + 1, len(live)):
            if abs(C[a, b]) > 1 - rtol:
                dup.append([names[live[a]], names[live[b]], int(np.sign(C[a, b]))])
                in_dup.add(live[b])
    rank = stacked_rank(S, rtol)
    dependent = []
    keep = [i for i in live if i not in in_dup]
    if keep:
        U, s, Vt = np.linalg.svd(A[:, keep], full_matrices=True)
        r = int((s > rtol * max(s[0], 1e-300)).sum())
        for v in Vt[r:]:
            order = np.argsort(-np.abs(v))
            dependent.append([[names[keep[i]], float(v[i])] for i in order if abs(v[i]) > 1e-3 * np.abs(v).max()][:6])
    out = {"rank": rank, "n_sources": len(names), "blind": blind, "duplicated": dup, "dependent": dependent}
    if reference is not None:
        B, bn = _stack(reference)
        rn = list(reference_names) if reference_names is not None else [f"reference[{i}]" for i in range(B.shape[1])]
        out["reference_rank"] = stacked_rank(reference, rtol)
        out["combined_rank"] = stacked_rank(np.concatenate([np.asarray(S, float), np.asarray(reference, float)], -1), rtol)
        coef, *_ = np.linalg.lstsq(A[:, live], B, rcond=None) if live else (np.zeros((0, B.shape[1])),)
        res = np.linalg.norm(B - A[:, live] @ coef, axis=0) if live else np.ones(B.shape[1])
        out["missing"] = [[rn[i], float(res[i])] for i in range(B.shape[1]) if bn[i] > 0 and res[i] > np.sqrt(rtol)]
    return out

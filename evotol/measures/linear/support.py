"""The support function of a linear error model with asymmetric intervals: where each interval
sits (:class:`IntervalShape`), the mean shift of the error set, and the support coefficients and
constant that make h(u) = row·t + const for a fixed direction u (the rows of the worst-case measure,
:mod:`evotol.measures.linear.stackup`, and of :mod:`evotol.measures.constraints`).

Notation: at one pose, source j (tolerance t_j, error vector e_j with ``|e_j| <= t_j``, dimension 1, 2
or 3) moves the end-effector by B_j e_j, where B_j is the 3×dim block of the sensitivity for the
position (m/m or m/rad) or the orientation (rad/...).

Asymmetric intervals (``docs/tolerances.md``). An interval source j may sit in
[offset_j − minus_j t_j, offset_j + plus_j t_j]: its centre is c_j = offset_j + κ_j t_j
(κ = (plus − minus)/2) and its half-width ρ_j t_j (ρ = (plus + minus)/2). The error set is then
s(t) + K with the mean shift s(t) = Σ_j B_j c_j and K the centred set of half-widths ρ_j t_j; it
is no longer centrally symmetric, so the support function

    h(u) = u·s(t) + Σ_j ρ_j t_j ‖B_jᵀu‖

is maximised over the **full** sphere (both halves of the direction grid). h is still convex and
positively homogeneous in u, so the same ascent, attained value and proven bound hold (the
covering angle of the full grid equals that of ±hemisphere). For fixed u, h is affine in t:
the rows of :mod:`evotol.measures.constraints` gain a constant term u·Σ_j B_j offset_j. RSS with a shift:
``|s(t)| + sqrt(Σ_j (ρ_j t_j ‖B_j‖₂)²)`` (mean shift added linearly to the RSS of the variation,
the CETOL/3DCS convention for a mean shift).

The parameters several definitions of this module share are described once, here.

Parameters
----------
D : ndarray, shape (n_dir, 3)
    Unit directions u_d.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class IntervalShape:
    """Where each source's interval sits (see module docstring): error of interval source j in
    [offset_j + (κ_j − ρ_j) t_j, offset_j + (κ_j + ρ_j) t_j]; disks/balls have ρ = 1, κ = offset = 0.

    Parameters
    ----------
    rho : ndarray, shape (n_src,)
        Half-width factor ρ_j = (plus + minus)/2 (dimensionless).
    kappa : ndarray, shape (n_src,)
        Centre factor κ_j = (plus − minus)/2 (dimensionless).
    offset : ndarray, shape (n_src,)
        Offset of the interval's nominal (SI: m or rad).
    """

    rho: np.ndarray
    kappa: np.ndarray
    offset: np.ndarray

    @classmethod
    def symmetric_unit(cls, n: int) -> "IntervalShape":
        """The plain shape ±t of ``n`` sources: ρ = 1, κ = 0, offset = 0.

        Parameters
        ----------
        n : int
            Number of sources.

        Returns
        -------
        IntervalShape
            The plain shape.
        """
        return cls(np.ones(n), np.zeros(n), np.zeros(n))

    @property
    def centred(self) -> bool:
        """True when every interval is centred on zero (the error set is centrally symmetric)."""
        return not (np.any(self.kappa != 0) or np.any(self.offset != 0))

    @property
    def plain(self) -> bool:
        """Centred with ρ = 1: the classical symmetric tolerance ±t."""
        return self.centred and bool(np.all(self.rho == 1))


def _interval_columns(blocks: list[np.ndarray]) -> list[int]:
    return [j for j, B in enumerate(blocks) if B.shape[2] == 1]


def mean_shift(blocks: list[np.ndarray], shape: IntervalShape, T: np.ndarray) -> np.ndarray:
    """s(t) = Σ_j B_j (offset_j + κ_j t_j) over interval sources, shape (n_designs, n_poses, 3).

    Parameters
    ----------
    shape : IntervalShape
        Where each interval sits.
    T : array_like, shape (n_designs, n_src) or (n_src,)
        Tolerances (SI: m or rad).

    Returns
    -------
    ndarray, shape (n_designs, n_poses, 3)
        Mean shift of the end-effector error (m or rad); disk/ball sources add nothing.
    """
    T = np.atleast_2d(T)
    out = np.zeros((T.shape[0], blocks[0].shape[0], 3))
    for j in _interval_columns(blocks):
        if shape.offset[j] != 0 or shape.kappa[j] != 0:
            c = shape.offset[j] + shape.kappa[j] * T[:, j]                 # (n,)
            out += c[:, None, None] * blocks[j][None, :, :, 0]
    return out


#: poses per in-place step of :func:`support_coefficients` (a step's coefficients stay in cache)
_POSES_PER_STEP = 64


def line_coefficients(Bl: np.ndarray, D: np.ndarray, rho_kappa, out: np.ndarray) -> None:
    """``out[p, d, k] = ρ_k |u_d·b_k| + κ_k u_d·b_k`` of interval sources, in place: one (d, 3) @ (3, m)
    product per pose.

    Parameters
    ----------
    Bl : ndarray, shape (n_poses, 3, m)
        The interval sources' columns ``b_k``.
    rho_kappa : tuple of ndarray or None
        ``(ρ, κ)`` of those sources; None: plain ±t (``|u_d·b_k|``).
    out : ndarray, shape (n_poses, n_dir, m)
        Written.
    """
    np.matmul(D, Bl, out=out)
    if rho_kappa is None:
        np.abs(out, out=out)
    else:
        out[...] = rho_kappa[0] * np.abs(out) + rho_kappa[1] * out


def support_coefficients(blocks: list[np.ndarray], D: np.ndarray, shape: IntervalShape | None = None) -> np.ndarray:
    """c[p, d, j] = ρ_j ‖B_jᵀ u_d‖ + κ_j u_d·b_j for blocks B_j (n_poses, 3, dim_j); shape
    (n_poses, n_dir, n_src). With the default shape (ρ = 1, κ = 0): ‖B_jᵀ u_d‖.

    Parameters
    ----------
    shape : IntervalShape or None
        Interval shape; None: plain ±t.

    Returns
    -------
    ndarray, shape (n_poses, n_dir, n_src)
        Support coefficients c[p, d, j] (m or rad per unit of tolerance).
    """
    out = np.empty((blocks[0].shape[0], D.shape[0], len(blocks)))
    line = [j for j, B in enumerate(blocks) if B.shape[2] == 1]
    if line:        # interval sources: |u_d·b_j| of all at once, a (d, 3) @ (3, m) product per pose, in place
        Bl = np.concatenate([blocks[j] for j in line], axis=2)                       # (p, 3, m_line)
        c = out if len(line) == len(blocks) else np.empty((len(Bl), D.shape[0], len(line)))
        for s in range(0, len(Bl), _POSES_PER_STEP):
            line_coefficients(Bl[s:s + _POSES_PER_STEP], D, None if shape is None else (shape.rho[line], shape.kappa[line]),
                              c[s:s + _POSES_PER_STEP])
        if c is out:
            return out
        out[:, :, line] = c
    for j, B in enumerate(blocks):
        if B.shape[2] == 1:
            continue
        proj = np.matmul(np.swapaxes(B, 1, 2), D.T)          # (p, k, d)
        out[:, :, j] = np.sqrt(np.sum(proj * proj, axis=1))
        if shape is not None:
            if shape.rho[j] != 1:
                out[:, :, j] *= shape.rho[j]
    return out


def support_constant(blocks: list[np.ndarray], D: np.ndarray, shape: IntervalShape | None) -> np.ndarray:
    """u_d·Σ_j B_j offset_j, shape (n_poses, n_dir): the part of h that does not scale with t.

    Parameters
    ----------
    shape : IntervalShape or None
        Interval shape; None: no offsets (zeros).

    Returns
    -------
    ndarray, shape (n_poses, n_dir)
        The offsets' part of the support function (m or rad).
    """
    s0 = np.zeros((blocks[0].shape[0], 3))
    if shape is not None:
        for j in _interval_columns(blocks):
            if shape.offset[j] != 0:
                s0 += shape.offset[j] * blocks[j][:, :, 0]
    return s0 @ D.T

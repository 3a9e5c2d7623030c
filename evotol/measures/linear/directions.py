"""Direction grids for the worst-case measure (:mod:`evotol.measures.linear.stackup`): unit directions u
on a hemisphere (Fibonacci), a half circle (planar output) or the single z direction, each with its
covering angle δ -- every unit vector is within δ of ±a grid direction, so the maximum of the
support function over the grid divided by cos δ is a proven upper bound on the worst-case error.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np


@lru_cache(maxsize=16)
def hemisphere(n: int = 600) -> tuple[np.ndarray, float]:
    """Fibonacci directions on the upper unit hemisphere (z >= 0), shape (n, 3), and the covering
    angle δ (rad) of the full sphere by ±these directions (measured by dense random probing and
    inflated by 10 %, so 1/cos δ is a safe bound factor)."""
    i = np.arange(n) + 0.5
    z = i / n                       # uniform in (0, 1): equal-area on the hemisphere
    phi = np.pi * (1 + 5 ** 0.5) * i
    r = np.sqrt(1 - z ** 2)
    D = np.stack([r * np.cos(phi), r * np.sin(phi), z], 1)
    # Exact covering angle of the sphere by ±D: the largest angle between a vertex of the
    # spherical Voronoi diagram of ±D and its generator (the points farthest from the set).
    from scipy.spatial import SphericalVoronoi

    pts = np.concatenate([D, -D])
    sv = SphericalVoronoi(pts, radius=1.0, threshold=1e-9)
    best = np.max(sv.vertices @ pts.T, axis=1)   # cos of the angle to the nearest point
    delta = float(np.arccos(np.clip(best.min(), -1, 1))) * (1 + 1e-9)
    return D, delta


def circle(n: int = 360) -> tuple[np.ndarray, float]:
    """Half circle of directions in the xy plane, (n, 3), covering angle δ = π/(2n).

    Parameters
    ----------
    n : int
        Number of directions.

    Returns
    -------
    D : ndarray, shape (n, 3)
        Unit directions at angles (i + 1/2)·π/n, i = 0 ... n − 1.
    delta : float
        Covering angle of the full circle by ±D (rad).
    """
    a = (np.arange(n) + 0.5) * np.pi / n
    return np.stack([np.cos(a), np.sin(a), np.zeros(n)], 1), np.pi / (2 * n)


def directions_for(blocks: np.ndarray, n: int = 600, full_sphere: bool = False) -> tuple[np.ndarray, float]:
    """Pick sphere or circle directions for position/orientation blocks (..., 3, k).

    ``full_sphere``: both halves (±D), for error sets that are not centrally symmetric.

    Parameters
    ----------
    blocks : ndarray, shape (..., 3, k)
        Sensitivity columns (rows x, y, z of the component); only which rows are non-zero matters.
    n : int
        Number of hemisphere directions (a circle gets ``max(n // 2, 90)``).
    full_sphere : bool
        Return ±D (both halves) instead of one half.

    Returns
    -------
    D : ndarray, shape (n_dir, 3)
        Unit directions: a half circle in the xy plane when the z row is zero, the single
        direction z when only the z row is non-zero, else a Fibonacci hemisphere.
    delta : float
        Covering angle (rad) of the sphere (or circle) by ±D; 0 for the single direction.
    """
    active = np.any(np.abs(blocks) > 0, axis=tuple(i for i in range(blocks.ndim) if i != blocks.ndim - 2))
    if not active[2] and active[:2].any():
        D, delta = circle(max(n // 2, 90))
    elif not active[0] and not active[1] and active[2]:
        D, delta = np.array([[0.0, 0.0, 1.0]]), 0.0
    else:
        D, delta = hemisphere(n)
    if full_sphere:
        D = np.concatenate([D, -D])
    return D, delta

"""Plane-geometry helpers shared by the robot models: largest rectangles in a sampled workspace."""
from __future__ import annotations

import functools

import numpy as np

from evotol.errors import ValidationError


def largest_rectangle(mask: np.ndarray) -> tuple[int, int, int, int, int]:
    """Largest axis-aligned all-True rectangle of grid points in a 2-D boolean array.

    Returns ``(area_in_cells, r0, r1, c0, c1)`` with inclusive row/column indices; the area
    counts cell spans ``(r1 - r0) * (c1 - c0)`` (point grid: the rectangle's corners are grid
    points that are all kept). Histogram-stack algorithm (largest rectangle under a histogram,
    row by row), O(rows x cols); of equal areas, the first found (lowest last row) is kept. Compiled
    with numba (issue 43: a 161 x 161 grid took about 8 ms in Python and 0.2 ms compiled; the dimension
    synthesis searches 341 of them); :func:`largest_rectangle_reference` is the same algorithm in Python.

    Parameters
    ----------
    mask : (rows, cols) array_like of bool
        True at the kept grid points (e.g. workspace samples that satisfy a criterion).

    Returns
    -------
    area : int
        Number of cell spans ``(r1 - r0) * (c1 - c0)`` (multiply by the grid spacings for an
        area in m^2); 0 when no rectangle spans a cell.
    r0, r1 : int
        First and last row, inclusive.
    c0, c1 : int
        First and last column, inclusive.

    Raises
    ------
    evotol.errors.ValidationError
        A mask that is not 2-D.

    Notes
    -----
    When no rectangle of positive area exists the result is ``(0, 0, -1, 0, -1)`` (an empty
    range), even if single True points or lines exist.
    """
    mask = np.ascontiguousarray(mask, bool)
    if mask.ndim != 2:
        raise ValidationError("mask", mask.shape, "a 2-D (rows, cols) array of kept grid points")
    kernel = _compiled()
    if kernel is None:
        return largest_rectangle_reference(mask)
    return tuple(int(v) for v in kernel(mask))


def largest_rectangle_reference(mask: np.ndarray) -> tuple[int, int, int, int, int]:
    """:func:`largest_rectangle` in plain Python: the reference the compiled kernel equals, result for
    result (the same histogram stack, the same order, integers only), and its fallback without numba.

    Parameters
    ----------
    mask : (rows, cols) array_like of bool
        The grid points to search (True: kept).

    Returns
    -------
    tuple of int
        ``(area, r0, r1, c0, c1)`` as :func:`largest_rectangle`.
    """
    mask = np.asarray(mask, bool)
    nr, nc = mask.shape
    best = (0, 0, -1, 0, -1)
    heights = np.zeros(nc, int)
    for r in range(nr):
        heights = np.where(mask[r], heights + 1, 0)
        stack: list[int] = []
        hs = heights.tolist() + [0]
        for c in range(nc + 1):
            while stack and hs[stack[-1]] >= hs[c]:
                top = stack.pop()
                hgt = hs[top]
                left = stack[-1] + 1 if stack else 0
                w = c - left
                area = (hgt - 1) * (w - 1)
                if hgt > 0 and area > best[0]:
                    best = (area, r - hgt + 1, r, left, c - 1)
            stack.append(c)
    return best


def _histogram_stack(mask):
    """Kernel body of :func:`largest_rectangle_reference` (compiled by :func:`_compiled`): the column
    heights in one array with a zero sentinel at ``nc``, the stack in another."""
    nr, nc = mask.shape
    best_area, b_r0, b_r1, b_c0, b_c1 = 0, 0, -1, 0, -1
    hs = np.zeros(nc + 1, np.int64)
    stack = np.empty(nc + 1, np.int64)
    for r in range(nr):
        for c in range(nc):
            hs[c] = hs[c] + 1 if mask[r, c] else 0
        depth = 0
        for c in range(nc + 1):
            while depth > 0 and hs[stack[depth - 1]] >= hs[c]:
                depth -= 1
                hgt = hs[stack[depth]]
                left = stack[depth - 1] + 1 if depth > 0 else 0
                area = (hgt - 1) * (c - left - 1)
                if hgt > 0 and area > best_area:
                    best_area, b_r0, b_r1, b_c0, b_c1 = area, r - hgt + 1, r, left, c - 1
            stack[depth] = c
            depth += 1
    return best_area, b_r0, b_r1, b_c0, b_c1


@functools.lru_cache(maxsize=1)
def _compiled():
    """The compiled :func:`_histogram_stack` (numba, cached on disk), or None without numba."""
    from evotol._runtime.numba_cache import njit

    try:
        return njit(cache=True)(_histogram_stack)      # imports numba
    except ImportError:
        return None


def largest_centred_rectangle(mask: np.ndarray, column: int) -> tuple[int, int, int, int]:
    """Largest all-True rectangle of ``mask`` symmetric about ``column``.

    Returns ``(area_in_cells, r0, r1, half_width)``: rows ``r0..r1`` and columns
    ``column - half_width .. column + half_width`` (inclusive); area ``2 half_width (r1 - r0)``
    cell spans. Reduces to :func:`largest_rectangle` on the mask of half-widths: entry ``(r, k)``
    is True when row ``r`` is True from ``column - k`` to ``column + k``, a prefix in ``k``, so
    its largest rectangle starts at ``k = 0``.

    Parameters
    ----------
    mask : (rows, cols) array_like of bool
        True at the kept grid points.
    column : int
        Index of the symmetry column (e.g. the column of ``x = 0`` for a robot symmetric about
        the y axis).

    Returns
    -------
    area : int
        ``2 half_width (r1 - r0)`` cell spans; 0 when none.
    r0, r1 : int
        First and last row, inclusive.
    half_width : int
        Columns on each side of ``column`` (-1 when no rectangle was found).
    """
    mask = np.asarray(mask, bool)
    half = min(column, mask.shape[1] - 1 - column)
    both = mask[:, column:column + half + 1] & mask[:, column::-1][:, :half + 1]
    area, r0, r1, _, c1 = largest_rectangle(np.logical_and.accumulate(both, axis=1))
    return 2 * area, r0, r1, c1

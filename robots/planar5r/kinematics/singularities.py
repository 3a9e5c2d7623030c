"""Singular loci of the planar 5R mechanism (Lara-Molina et al. 2019, Sec. 2.4, eqs. 16-19).

Type I (serial) singularities: the circles of eqs. 16-19 bounding the theoretical workspace
(``A_i, B_i, P`` aligned); type II (parallel): ``B_1, B_2, P`` aligned, traced parametrically
per working mode; and the distance of points to the nearest of them.
"""
from __future__ import annotations

import numpy as np

from evotol.robots.planar5r.kinematics.conventions import DEFAULT_WORKING_MODE, cross2, working_mode_signs
from evotol.robots.planar5r.kinematics.position import circle_intersection


def type1_circles(r1, r2, r3) -> list[dict]:
    """The circles bounding the theoretical workspace, eqs. 16-19 (type I singular loci).

    Returns
    -------
    list of dict
        Four dicts with ``"name"``, centre abscissa ``"cx"`` (on ``y = 0``) and ``"radius"``,
        length unit.
    """
    return [dict(name="C1o (eq. 16)", cx=-r3, radius=r1 + r2), dict(name="C1i (eq. 17)", cx=-r3, radius=abs(r1 - r2)),
            dict(name="C2o (eq. 18)", cx=r3, radius=r1 + r2), dict(name="C2i (eq. 19)", cx=r3, radius=abs(r1 - r2))]


def type2_locus(r1, r2, r3, working_mode=DEFAULT_WORKING_MODE, n: int = 20000) -> np.ndarray:
    """Points (k, 2) of the type II singular locus of one working mode (``B_1, B_2, P`` aligned).

    Two families: ``P`` the midpoint of ``B_1B_2`` with ``|B_1B_2| = 2 r2`` (parametrised by the
    coupler direction ``u``: ``P`` is on the circles of radius r1 about ``A_1 - r2 u`` and
    ``A_2 + r2 u``), and ``B_1 = B_2`` (possible when ``r1 >= r3``): ``P`` on the circle of
    radius r2 about ``(0, +-sqrt(r1^2 - r3^2))``. Only points whose elbows are in the requested
    working mode are kept.

    Parameters
    ----------
    n : int
        Samples of the coupler direction (and of each ``B_1 = B_2`` circle).

    Returns
    -------
    ndarray, shape (k, 2)
        Points of the locus, length unit.

    Raises
    ------
    ValidationError
        If ``working_mode`` is invalid.
    """
    m1, m2 = working_mode_signs(working_mode)
    phi = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    ux, uy = np.cos(phi), np.sin(phi)
    pts, elbows = [], []
    for sig in (1, -1):
        px, py, h2 = circle_intersection(-r3 - r2 * ux, -r2 * uy, r1, r3 + r2 * ux, r2 * uy, r1, sig)
        ok = h2 >= 0
        pts.append(np.stack([px[ok], py[ok]], -1))
        elbows.append(np.stack([px[ok] + r2 * ux[ok], py[ok] + r2 * uy[ok],
                                px[ok] - r2 * ux[ok], py[ok] - r2 * uy[ok]], -1))
    if r1 >= r3:
        yb = np.sqrt(r1 * r1 - r3 * r3)
        for sy in (1, -1):
            px, py = r2 * ux, sy * yb + r2 * uy
            pts.append(np.stack([px, py], -1))
            elbows.append(np.stack([np.zeros_like(px), np.full_like(px, sy * yb)] * 2, -1))
    P, E = np.concatenate(pts), np.concatenate(elbows)
    s1 = np.sign(cross2(P[:, 0] + r3, P[:, 1], E[:, 0] + r3, E[:, 1]))
    s2 = np.sign(cross2(P[:, 0] - r3, P[:, 1], E[:, 2] - r3, E[:, 3]))
    return P[(s1 == m1) & (s2 == m2)]


def distance_to_singular_loci(points, r1, r2, r3, working_mode=DEFAULT_WORKING_MODE, locus=None) -> np.ndarray:
    """Distance (n,) from points (n, 2) to the nearest singular locus (eqs. 16-19 and type II).

    Parameters
    ----------
    points : array_like, shape (n, 2)
        Points, length unit.
    locus : ndarray, shape (k, 2), or None
        Precomputed type II locus; None: :func:`type2_locus`.

    Returns
    -------
    ndarray, shape (n,)
        Distance to the nearest type I circle or type II locus point, length unit.
    """
    points = np.atleast_2d(np.asarray(points, dtype=float))
    d = np.full(len(points), np.inf)
    for c in type1_circles(r1, r2, r3):
        d = np.minimum(d, np.abs(np.hypot(points[:, 0] - c["cx"], points[:, 1]) - c["radius"]))
    locus = type2_locus(r1, r2, r3, working_mode) if locus is None else locus
    if len(locus):
        from scipy.spatial import cKDTree

        d = np.minimum(d, cKDTree(locus).query(points)[0])
    return d

"""Usable workspace and its maximum inscribed circle, planar 5R (Lara-Molina et al. 2019, Sec. 2.4, eqs. 20-22).

The MIC in closed form (eqs. 21-22) and found numerically (an independent check), and the
usable workspace: the connected region bounded by singular loci, with its LCI map, on a grid.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.planar5r.kinematics.conventions import DEFAULT_WORKING_MODE
from evotol.robots.planar5r.kinematics.jacobians import inverse_condition_number, jacobians, type2_determinant
from evotol.robots.planar5r.kinematics.position import inverse_kinematics_raw
from evotol.robots.planar5r.kinematics.singularities import distance_to_singular_loci, type2_locus


def mic_closed_form(r1, r2, r3) -> dict:
    """Maximum inscribed circle ``x^2 + (y - y_MIC)^2 = r_MIC^2`` (eq. 20) by eqs. 21-22.

    eq. 21 (``r1 + r3 < r2``): ``r_MIC = (r1 + r2 - |r1 - r2|)/2``,
    ``y_MIC = sqrt((r1 + r2 + |r1 - r2|)^2 / 4 - r3^2)``.
    eq. 22 (otherwise): ``y_col = sqrt(r1^2 - (r2 - r3)^2)``,
    ``y_MIC = ((r1 + r2 + y_col)^2 - r3^2) / (2 (r1 + r2 + y_col))``, ``r_MIC = |y_MIC| - y_col``.
    ``y_col`` is the height of the type II posture with ``B_1 = (-r2, y)``, ``P = (0, y)``,
    ``B_2 = (r2, y)``; eq. 22's circle touches it and the outer circles eqs. 16/18.

    Returns
    -------
    dict
        ``"radius"`` (``r_MIC``) and ``"center_y"`` (``y_MIC``), length unit; ``"equation"``:
        ``"eq21"`` or ``"eq22"``; for eq. 22 also ``"y_col"``, length unit.

    Raises
    ------
    ValidationError
        If ``r1``, ``r2`` or ``r3`` is not a scalar (eqs. 21-22 are for one design).
    KinematicsError
        If eq. 22 applies and ``r1 < abs(r2 - r3)``.
    """
    for name, r in (("r1", r1), ("r2", r2), ("r3", r3)):
        if np.ndim(r) != 0:
            raise ValidationError(name, np.asarray(r).tolist(), "a scalar length")
    if r1 + r3 < r2:
        return dict(radius=(r1 + r2 - abs(r1 - r2)) / 2,
                    center_y=float(np.sqrt((r1 + r2 + abs(r1 - r2)) ** 2 / 4 - r3 * r3)), equation="eq21")
    arg = r1 * r1 - (r2 - r3) ** 2
    if arg < 0:
        raise KinematicsError(f"5R: eq. 22 needs r1 >= |r2 - r3| (r1={r1:g}, r2={r2:g}, r3={r3:g})")
    y_col = float(np.sqrt(arg))
    R = r1 + r2 + y_col
    yc = (R * R - r3 * r3) / (2 * R)
    return dict(radius=abs(yc) - y_col, center_y=yc, y_col=y_col, equation="eq22")


def mic_numeric(r1, r2, r3, working_mode=DEFAULT_WORKING_MODE, assembly=1, n: int = 4001) -> dict:
    """MIC found numerically: the largest circle centred on the symmetry axis ``x = 0``,
    inside the usable workspace, and touching no singular locus (independent check of eqs. 21-22).

    Parameters
    ----------
    n : int
        Grid size on the axis ``0 <= y <= r1 + r2`` (``y = 0`` dropped) before the local
        refinement.

    Returns
    -------
    dict
        ``"radius"`` and ``"center_y"``, length unit.

    Raises
    ------
    ValidationError
        If ``working_mode`` is invalid.
    KinematicsError
        If no point of the axis is reachable in the working and assembly modes.
    """
    from scipy.optimize import minimize_scalar

    locus = type2_locus(r1, r2, r3, working_mode, n=40000)
    ys = np.linspace(0, r1 + r2, n)[1:]
    pts = np.stack([np.zeros_like(ys), ys], -1)
    t1, t2, ok = inverse_kinematics_raw(pts[:, 0], pts[:, 1], r1, r2, r3, working_mode)
    th = np.stack([t1, t2], -1)
    det = type2_determinant(pts, th, r1, r3)
    ok &= np.sign(det) == assembly
    if not ok.any():
        raise KinematicsError(f"5R: no usable point on the symmetry axis for r=({r1:g}, {r2:g}, {r3:g}), "
                              f"working mode {working_mode}, assembly {assembly}")
    d = np.where(ok, distance_to_singular_loci(pts, r1, r2, r3, working_mode, locus), -np.inf)
    i = int(np.argmax(d))
    lo, hi = ys[max(i - 1, 0)], ys[min(i + 1, len(ys) - 1)]
    res = minimize_scalar(lambda y: -distance_to_singular_loci([[0.0, y]], r1, r2, r3, working_mode, locus)[0],
                          bounds=(lo, hi), method="bounded", options=dict(xatol=1e-10))
    return dict(radius=float(-res.fun), center_y=float(res.x))


@dataclass(frozen=True)
class UsableWorkspaceMap:
    """The usable workspace on a grid: ``mask[j, i]`` for the point ``(x[i], y[j])``; ``lci`` is
    NaN outside the mask (a plotting array, not a kinematic result).

    Parameters
    ----------
    x : ndarray, shape (nx,)
        Grid abscissae, length unit.
    y : ndarray, shape (ny,)
        Grid ordinates, length unit.
    mask : ndarray of bool, shape (ny, nx)
        True in the usable workspace.
    lci : ndarray, shape (ny, nx)
        Local conditioning index, dimensionless (NaN outside ``mask``).
    seed : tuple of float
        Point ``(x, y)`` the region was grown from, length unit.
    """

    x: np.ndarray
    y: np.ndarray
    mask: np.ndarray
    lci: np.ndarray
    seed: tuple[float, float]

    @property
    def area(self) -> float:
        """Area of the masked grid cells, length unit squared."""
        return float(self.mask.sum() * (self.x[1] - self.x[0]) * (self.y[1] - self.y[0]))

    @property
    def lci_max(self) -> float:
        """Largest LCI in the usable workspace, dimensionless."""
        return float(np.nanmax(self.lci))

    def points(self) -> np.ndarray:
        """Grid points of the usable workspace.

        Returns
        -------
        ndarray, shape (k, 2)
            Points ``(x, y)`` where ``mask`` is True, length unit.
        """
        X, Y = np.meshgrid(self.x, self.y)
        return np.stack([X[self.mask], Y[self.mask]], -1)


def usable_workspace(r1, r2, r3, working_mode=DEFAULT_WORKING_MODE, assembly=1, n: int = 241,
                     seed=None, refine: bool = True) -> UsableWorkspaceMap:
    """Usable workspace (Sec. 2.4): the connected region around ``seed`` (default: the numeric
    MIC centre) where both chains reach ``P`` in ``working_mode`` and ``sign(det J_x)`` equals the
    assembly mode, i.e. bounded by singular loci. A first ``n x n`` grid covers the theoretical
    workspace's bounding box; with ``refine`` a second grid of equal spacing (``n`` points along
    the longer side) covers the bounding box of the region found. The LCI map is computed on it.

    Parameters
    ----------
    n : int
        Grid points per side of the first grid.
    seed : tuple of float or None
        Point ``(x, y)`` of the region, length unit; None: the centre of :func:`mic_numeric`.
    refine : bool
        Recompute on a second grid fitted to the region.

    Returns
    -------
    UsableWorkspaceMap
        The region and its LCI map.

    Raises
    ------
    ValidationError
        If ``working_mode`` is invalid.
    KinematicsError
        If the seed point is not in the usable workspace (or, with no ``seed``, as
        :func:`mic_numeric`).
    """
    from scipy import ndimage

    if seed is None:
        seed = (0.0, mic_numeric(r1, r2, r3, working_mode, assembly)["center_y"])

    def evaluate(x, y):
        X, Y = np.meshgrid(x, y)
        t1, t2, ok = inverse_kinematics_raw(X, Y, r1, r2, r3, working_mode)
        P = np.stack([X, Y], -1)
        jx, jq = jacobians(P, np.stack([t1, t2], -1), r1, r3)
        det = jx[..., 0, 0] * jx[..., 1, 1] - jx[..., 0, 1] * jx[..., 1, 0]
        good = ok & (np.sign(det) == assembly) & (jq[..., 0] != 0) & (jq[..., 1] != 0)
        labels, _ = ndimage.label(good)
        j, i = int(np.argmin(np.abs(y - seed[1]))), int(np.argmin(np.abs(x - seed[0])))
        if labels[j, i] == 0:
            raise KinematicsError(f"5R: seed point {list(seed)} is not in the usable workspace", poses=np.array([seed]))
        mask = labels == labels[j, i]
        adj = np.stack([np.stack([jx[..., 1, 1], -jx[..., 0, 1]], -1), np.stack([-jx[..., 1, 0], jx[..., 0, 0]], -1)], -2)
        return mask, np.where(mask, inverse_condition_number(adj * jq[..., None, :]), np.nan)

    R = r1 + r2
    x = np.linspace(-(R - r3), R - r3, n)
    y = np.linspace(-R, R, n)
    mask, lci = evaluate(x, y)
    if refine:
        X, Y = np.meshgrid(x, y)
        dx = x[1] - x[0]
        x0, x1 = X[mask].min() - 2 * dx, X[mask].max() + 2 * dx
        y0, y1 = Y[mask].min() - 2 * dx, Y[mask].max() + 2 * dx
        h = max(x1 - x0, y1 - y0) / (n - 1)
        x = np.linspace(x0, x1, int(round((x1 - x0) / h)) + 1)
        y = np.linspace(y0, y1, int(round((y1 - y0) / h)) + 1)
        mask, lci = evaluate(x, y)
    return UsableWorkspaceMap(x=x, y=y, mask=mask, lci=lci, seed=(float(seed[0]), float(seed[1])))

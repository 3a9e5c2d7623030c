"""Singularity-free sub-workspaces of the IRSBot-2 (Deng 2012 Sec. VII.2.1 and Figs. VI.4-VI.5):
the largest rectangle of the x-z plane in the working mode away from both singularity types.

Units: metres; poses are ``(x, z)`` in metres.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evotol.errors import KinematicsError
from evotol.robots.geometry import largest_centred_rectangle, largest_rectangle
from evotol.robots.irsbot2.model import IRSBot2


@dataclass(frozen=True)
class SubWorkspace:
    """A singularity-free rectangle of the x-z plane (SI units) and its Fig. VII.10 points.

    Parameters
    ----------
    area : float
        Area of the rectangle, m².
    x : tuple of float
        ``(x_min, x_max)``, m.
    z : tuple of float
        ``(z_min, z_max)``, m.
    step : float
        Grid step of the search, m.
    n_kept : int
        Number of grid points satisfying the criteria.
    """

    area: float                 # m²
    x: tuple[float, float]      # (x_min, x_max), m
    z: tuple[float, float]      # (z_min, z_max), m
    step: float                 # grid step, m
    n_kept: int                 # kept grid points

    @property
    def points(self) -> np.ndarray:
        """Right-down corner, centre and left-up corner (Fig. VII.10), shape (3, 2) [x, z] in m."""
        (x0, x1), (z0, z1) = self.x, self.z
        return np.array([[x1, z0], [(x0 + x1) / 2, (z0 + z1) / 2], [x0, z1]])


def singularity_free_rectangle(robot: IRSBot2, *, n: int = 161, margin_deg: float = 2.0,
                               below_elbows: bool = False) -> SubWorkspace:
    """Largest rectangle of the x-z plane below the base (z < -e) in which the robot is assembled in
    its working mode, on the V side of the Type 2 singularity (sin(psi_1 - psi_2) < 0) and at least
    ``margin_deg`` away from both singularity types, by discretising the reachable region with
    n x n points -- the "cuboid-shaped sub-workspace" of Deng 2012 Sec. VII.2.1 ([BPC10]).
    ``below_elbows``: also require the platform below both elbows (a stricter variant).

    Parameters
    ----------
    robot : IRSBot2
        The robot, in the elbows-out mode ``(-1, -1)``.
    n : int
        Grid points per axis.
    margin_deg : float
        Minimum distance to both singularity types, deg (as the sine of the angles).
    below_elbows : bool
        Also require the platform below both elbows.

    Returns
    -------
    SubWorkspace
        The rectangle (area 0 and zero ranges if no grid point qualifies).

    Raises
    ------
    ValidationError
        If ``robot.modes`` is not ``(-1, -1)`` (from :meth:`IRSBot2.planar_legs`).
    """
    reach = robot.base_x + robot.l1 + robot.l2eq
    depth = robot.l1 + robot.l2eq
    xs = np.linspace(-reach, reach, n)
    zs = np.linspace(-depth - robot.e, -robot.e, n)
    step = max(xs[1] - xs[0], zs[1] - zs[0])
    X, Z = np.meshgrid(xs, zs)                                   # rows: z, columns: x
    g = robot.planar_legs(X, Z)
    s = math.sin(math.radians(margin_deg))
    keep = (g["reachable"] & (g["sin_t2"] <= -s) & (np.abs(g["sin_t1_1"]) >= s) & (np.abs(g["sin_t1_2"]) >= s)
            & (Z < -robot.e))
    if below_elbows:
        keep &= (np.sin(g["psi1"]) > 0) & (np.sin(g["psi2"]) > 0)
    area, r0, r1, c0, c1 = largest_rectangle(keep)
    if c1 < c0 or area == 0:
        return SubWorkspace(0.0, (0.0, 0.0), (0.0, 0.0), float(step), int(keep.sum()))
    dx, dz = xs[1] - xs[0], zs[1] - zs[0]
    return SubWorkspace(float(area * dx * dz), (float(xs[c0]), float(xs[c1])), (float(zs[r0]), float(zs[r1])),
                        float(step), int(keep.sum()))


def centred_singularity_free_rectangle(robot: IRSBot2, margin: float = 0.2, step: float = 1e-3, x_max: float = 0.2,
                                       z_range=(-0.3, 0.0)) -> dict[str, float]:
    """Largest rectangle ``[-w, w] x [z_low, z_high]`` (m) symmetric about x = 0 inside the reachable
    workspace with ``|sin(psi1 - psi2)| >= margin`` and ``min_i |sin(q_i - psi_i)| >= margin``, on a
    grid of ``step`` (the rectangle of Deng 2012 Figs. VI.4-VI.5, whose criterion the thesis does
    not state). Returns ``half_width``, ``z_low``, ``z_high`` and ``area`` (m, m²).

    Parameters
    ----------
    robot : IRSBot2
        The robot.
    margin : float
        Minimum of both singularity measures, dimensionless (a sine).
    step : float
        Grid step, m.
    x_max : float
        Largest half-width searched, m.
    z_range : tuple of float
        ``(z_min, z_max)`` searched, m.

    Returns
    -------
    dict of str to float
        ``"half_width"``, ``"z_low"``, ``"z_high"`` (m) and ``"area"`` (m²).

    Raises
    ------
    KinematicsError
        If no rectangle about ``x = 0`` satisfies the margins (or a reachable point fails a
        distal chain).
    """
    xs = np.arange(0.0, x_max + step / 2, step)
    zs = np.arange(z_range[0], z_range[1] + step / 2, step)
    X, Z = np.meshgrid(np.concatenate([-xs[:0:-1], xs]), zs)
    pts = np.stack([X.ravel(), Z.ravel()], 1)
    ok = robot.reachable(pts)
    good = np.zeros(len(pts), bool)
    if ok.any():
        q = pts[ok]
        good[np.nonzero(ok)[0]] = (np.abs(robot.parallel_singularity(q)) >= margin) & (robot.serial_singularity(q) >= margin)
    area, r0, r1, half = largest_centred_rectangle(good.reshape(X.shape), len(xs) - 1)
    if area == 0:
        raise KinematicsError(f"no rectangle about x = 0 with singularity margin {margin} in x <= {x_max} m, "
                              f"z in {tuple(z_range)} m", poses=pts[:0])
    return {"half_width": half * step, "z_low": zs[r0], "z_high": zs[r1], "area": (2 * half * step) * ((r1 - r0) * step)}

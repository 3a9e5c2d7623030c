"""Nominal geometry and workspace of the Delta robot (Brahmia et al. 2023, Sec. 2.1.1 / 3.1, Fig. 5):
its dimensions, the 15 postures of the cylindrical workspace, and uniform points in that cylinder.

Units: metres (the postures are in mm, as printed).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.errors import ValidationError

#: The 15 postures of the regular cylindrical workspace (Fig. 5), mm. P1, P3, P6, P9 are given by
#: the paper; the others are our reading of Fig. 5: five vertical lines (axis, +x, +y, -x, -y at
#: radius 100 mm) times three heights (z = 250, 375, 500 mm), numbered line by line.
POSTURES_MM: dict[str, tuple[float, float, float]] = {}
for _line, (_x, _y) in enumerate(((0, 0), (100, 0), (0, 100), (-100, 0), (0, -100))):
    for _lev, _z in enumerate((250.0, 375.0, 500.0)):
        POSTURES_MM[f"P{3 * _line + _lev + 1}"] = (float(_x), float(_y), _z)
del _line, _x, _y, _lev, _z


@dataclass(frozen=True)
class DeltaGeometry:
    """Nominal dimensions (m), Brahmia et al. 2023 Sec. 2.1.1 / 3.1.

    Parameters
    ----------
    La : float
        Upper-arm length, m (0.260).
    Lb : float
        Length of the two parallelogram rods, m (0.480).
    Ra : float
        Base radius ``O0-A_i``, m (0.194).
    Rb : float
        Platform radius ``P-B_i``, m (0.030).
    d : float
        Half-width of the parallelogram bars, m (0.020).

    Raises
    ------
    ValidationError
        If a length is not finite and positive.
    """

    La: float = 0.260   # upper arm
    Lb: float = 0.480   # parallelogram rods
    Ra: float = 0.194   # base radius
    Rb: float = 0.030   # platform radius
    d: float = 0.020    # half-width of the parallelogram bars

    def __post_init__(self):
        for f in ("La", "Lb", "Ra", "Rb", "d"):
            v = getattr(self, f)
            if not (np.isfinite(v) and v > 0):
                raise ValidationError(f"DeltaGeometry.{f}", v, "a positive length in metres")

    @property
    def theta(self) -> np.ndarray:
        """Leg angles theta_i = 2 pi (i - 1) / 3 (rad)."""
        return 2 * np.pi * np.arange(3) / 3


def cylinder_poses(n: int, radius: float = 0.1, z_range=(0.25, 0.5), seed: int | None = 0) -> np.ndarray:
    """``n`` scrambled-Halton points uniform in the cylindrical workspace, shape (n, 3), m.

    Parameters
    ----------
    n : int
        Number of points (at least 1).
    radius : float
        Radius of the cylinder about the base axis, m.
    z_range : tuple of float
        ``(z_min, z_max)`` heights of the cylinder, m.
    seed : int or None
        Seed of the scrambled Halton sequence (None: not reproducible).

    Returns
    -------
    (n, 3) ndarray
        Platform positions ``(x, y, z)``, m, uniform in the disk of ``radius`` times ``z_range``.

    Raises
    ------
    ValidationError
        If ``n`` is below 1.
    """
    from scipy.stats import qmc

    if int(n) < 1:
        raise ValidationError("cylinder_poses n", n, "a positive integer")
    u = qmc.Halton(d=3, scramble=True, seed=seed).random(int(n))
    r = radius * np.sqrt(u[:, 0])  # uniform in the disk
    phi = 2 * np.pi * u[:, 1]
    z = z_range[0] + (z_range[1] - z_range[0]) * u[:, 2]
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)

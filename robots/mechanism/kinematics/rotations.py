"""Small rotation helpers of the mechanism kinematics, vectorised over poses."""
from __future__ import annotations

import numpy as np

from evotol.robots.clearance.kinematics import rot_x, rot_y, rot_z

#: the elementary rotation (..., 4, 4) about each axis (the one definition: evotol.robots.clearance.kinematics)
AXIS_ROT = {"x": rot_x, "y": rot_y, "z": rot_z}


def rot_z_inverse(th):
    """Rot(z, -theta) (n, 3, 3): undoes a joint row's rotation to reach its placement axes.

    Parameters
    ----------
    th : (n,) ndarray
        Angles theta (rad); a 1-D array (``len`` is taken).

    Returns
    -------
    (n, 3, 3) ndarray
        The rotation matrices ``Rot(z, -theta)``.
    """
    c, s = np.cos(th), np.sin(th)
    R = np.zeros((len(c), 3, 3))
    R[:, 0, 0], R[:, 0, 1], R[:, 1, 0], R[:, 1, 1], R[:, 2, 2] = c, s, -s, c, 1.0
    return R


def cross_rows(a, b):
    """Row-wise cross product of (n, 3) arrays (np.cross is slow for small rows).

    Parameters
    ----------
    a, b : (n, 3) ndarray
        The factors, row by row (any units; the result's is their product).

    Returns
    -------
    (n, 3) ndarray
        ``a[i] x b[i]`` per row, of ``a``'s dtype.
    """
    out = np.empty_like(a)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out

"""The ISO 9283 test cube and its five poses (ISO 9283:1998 §6.8, summarised in docs/iso9283.md).

The cube's edges are parallel to the base axes. P1 is its centre; P2–P5 lie on the diagonals of the
diagonal plane through the edge ``{y = y_min, z = z_min}`` and the opposite edge
``{y = y_max, z = z_max}`` (corners ``C1 = (x_min, y_min, z_min)``, ``C2 = (x_max, y_min, z_min)``,
``C3 = (x_max, y_max, z_max)``, ``C4 = (x_min, y_max, z_max)``), each at 10 % of the diagonal's
length from a corner: ``P2 = C1 + 0.1 (C3 − C1)``, ``P3 = C2 + 0.1 (C4 − C2)``,
``P4 = C3 + 0.1 (C1 − C3)``, ``P5 = C4 + 0.1 (C2 − C4)``. The orientation is the robot's fixed task
orientation (the workspace's other coordinates at mid-range).

Parameters
----------
robot : evotol.robots.mechanism.model.error_model.MechanismModel
    The mechanism (a workspace with coordinates x, y, z).
cube : TestCube
    A test cube.
positions : (n, 3) array_like
    Positions (m, base frame).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.errors import KinematicsError, ValidationError

#: share of the diagonal between a corner and its pose (ISO 9283: 10 % ± 2 %)
CORNER_SHARE = 0.1


@dataclass(frozen=True)
class TestCube:
    """A test cube with edges parallel to the base axes.

    Parameters
    ----------
    centre : tuple of float
        Its centre (m, base frame).
    edge : float
        Its edge length (m).
    """

    __test__ = False      # not a pytest class
    centre: tuple
    edge: float

    def corners(self) -> np.ndarray:
        """The eight corners.

        Returns
        -------
        (8, 3) ndarray
            Corners (m).
        """
        h = self.edge / 2
        return np.array(self.centre) + h * np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)])


def iso_positions(cube: TestCube) -> np.ndarray:
    """P1–P5 (5, 3) of a cube, m (module docstring).

    Parameters
    ----------
    cube : TestCube
        The test cube.

    Returns
    -------
    (5, 3) ndarray
        Commanded positions P1..P5 (m).

    Examples
    --------
    >>> iso_positions(TestCube((0.0, 0.0, 0.0), 1.0))[1].round(2).tolist()
    [-0.4, -0.4, -0.4]
    """
    c, h = np.asarray(cube.centre, float), cube.edge / 2
    C1, C2 = c + h * np.array([-1, -1, -1]), c + h * np.array([1, -1, -1])
    C3, C4 = c + h * np.array([1, 1, 1]), c + h * np.array([-1, 1, 1])
    s = CORNER_SHARE
    return np.array([c, C1 + s * (C3 - C1), C2 + s * (C4 - C2), C3 + s * (C1 - C3), C4 + s * (C2 - C4)])


def _xyz(robot) -> list[int]:
    names = list(robot.workspace.names)
    if not all(a in names for a in "xyz"):
        raise ValidationError("iso9283 workspace", tuple(names), "coordinates x, y, z (a positioning task)")
    return [names.index(a) for a in "xyz"]


def full_poses(robot, positions) -> np.ndarray:
    """Workspace poses for positions: x, y, z set, the other coordinates at mid-range.

    Returns
    -------
    (n, n_coordinates) ndarray
        Poses (SI).
    """
    ws = robot.workspace
    P = np.tile((np.array(ws.low) + np.array(ws.high)) / 2, (len(positions), 1))
    P[:, _xyz(robot)] = positions
    return P


def cube_problem(robot, cube: TestCube) -> str | None:
    """Why a cube cannot be a test cube of this robot (a corner outside the workspace box or out of
    reach / beyond a joint limit), or None when it can.

    Returns
    -------
    str or None
        The reason, or None.
    """
    idx = _xyz(robot)
    lo, hi = np.array(robot.workspace.low)[idx], np.array(robot.workspace.high)[idx]
    pts = np.vstack([cube.corners(), iso_positions(cube)])
    out = np.any((pts < lo - 1e-12) | (pts > hi + 1e-12), axis=1)
    if out.any():
        return f"corner {pts[np.argmax(out)].tolist()} m lies outside the workspace box {lo.tolist()}..{hi.tolist()} m"
    try:
        robot.joint_values(full_poses(robot, pts))
    except KinematicsError as exc:
        return f"a corner is out of reach or beyond a joint limit ({str(exc).splitlines()[0]})"
    return None


def check_cube(robot, cube: TestCube) -> TestCube:
    """The cube, or a one-line :class:`ValidationError` when it is not inside the workspace.

    Returns
    -------
    TestCube
        The same cube.

    Raises
    ------
    evotol.errors.ValidationError
        A corner outside the workspace box or out of reach (:func:`cube_problem`), or an edge ≤ 0.
    """
    if not cube.edge > 0:
        raise ValidationError("iso9283.cube edge", cube.edge, "a positive length (m)")
    why = cube_problem(robot, cube)
    if why:
        raise ValidationError("iso9283.cube", {"centre": list(cube.centre), "edge": cube.edge},
                              f"a cube inside the workspace and the joint limits: {why}")
    return cube


def largest_cube(robot, centre=None, iterations: int = 30) -> TestCube:
    """The largest test cube about ``centre`` (default: the workspace box's centre) whose corners lie
    in the workspace box and are reachable within the joint limits: bisection on the edge.

    A bisection on the edge finds the largest cube only if every smaller cube about the centre is
    valid too (true for a box and for a reachable set star-shaped about the centre); the result is
    checked like a given cube.

    Parameters
    ----------
    centre : (3,) array_like or None
        The cube's centre (m); None: the workspace box's centre.
    iterations : int
        Bisection steps on the edge.

    Returns
    -------
    TestCube
        The cube found (edge to within ``edge_max / 2^iterations``).

    Raises
    ------
    evotol.errors.ValidationError
        The centre itself is outside the workspace or out of reach.
    """
    idx = _xyz(robot)
    lo, hi = np.array(robot.workspace.low)[idx], np.array(robot.workspace.high)[idx]
    c = (lo + hi) / 2 if centre is None else np.asarray(centre, float)
    edge_max = 2 * float(np.min(np.minimum(c - lo, hi - c)))
    if edge_max <= 0 or cube_problem(robot, TestCube(tuple(c), 1e-9)):
        raise ValidationError("iso9283.cube centre", c.tolist(), "a point inside the workspace box and within reach")
    if cube_problem(robot, TestCube(tuple(c), edge_max)) is None:
        return TestCube(tuple(c.tolist()), edge_max)
    a, b = 0.0, edge_max
    for _ in range(iterations):
        m = (a + b) / 2
        a, b = (m, b) if cube_problem(robot, TestCube(tuple(c), m)) is None else (a, m)
    return check_cube(robot, TestCube(tuple(c.tolist()), a))

"""``[poses]``: the workspace poses of a study file (``grid``, ``latin_hypercube`` or ``list``), and
its ``refine`` option (the whole workspace, :mod:`evotol.allocators.workspace_refinement`).
"""
from __future__ import annotations

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.base import RobotErrorModel


def read_poses(spec: dict, robot: RobotErrorModel) -> np.ndarray:
    """The poses of ``[poses]`` (default ``grid = 5``), in the robot's workspace coordinates.

    Parameters
    ----------
    spec : dict
        The parsed study file (``seed`` seeds a Latin hypercube).
    robot : evotol.robots.base.RobotErrorModel
        The study's robot (its workspace makes grids and Latin hypercubes).

    Returns
    -------
    numpy.ndarray, shape (n_poses, workspace.dim)
        The poses (SI: m, rad); checked by the problem, not here.

    Raises
    ------
    ValidationError
        A ``[poses]`` table with none of ``grid``, ``latin_hypercube``, ``list``; a grid, a Latin
        hypercube or ``refine`` over a workspace the description does not state
        (:attr:`evotol.robots.base.Workspace.stated`).
    """
    ps = spec.get("poses", {"grid": 5})
    box = [k for k in ("grid", "latin_hypercube", "refine") if k in ps]
    if box and not robot.workspace.stated:      # a box the description does not state (issue 39 item 4)
        raise ValidationError(f"poses.{box[0]}", ps[box[0]], f"poses a stated task box gives: {robot.name}'s "
                              f"description has no [end_effector] coordinates (state them, or give the poses as "
                              f"[poses] joints = [...] or [poses] list = [...])")
    if "grid" in ps:
        return robot.workspace.grid(ps["grid"])
    if "latin_hypercube" in ps:
        return robot.workspace.latin_hypercube(ps["latin_hypercube"], seed=spec.get("seed", 0))
    if "list" in ps:
        return np.asarray(ps["list"], dtype=float)
    raise ValidationError("poses", ps, "one of grid = [n, ...], latin_hypercube = n, list = [[...], ...]")


def refine_option(spec: dict):
    """The ``[poses] refine`` setting as allocator keyword: False, True or a dict of options.

    Returns
    -------
    bool or dict
        False when absent; the options table as a dict; else ``bool(refine)``.
    """
    ref = spec.get("poses", {}).get("refine", False)
    return dict(ref) if isinstance(ref, dict) else bool(ref)

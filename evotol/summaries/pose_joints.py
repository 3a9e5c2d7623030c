"""The joints a study's arm uses at every pose, for its JSON and page (issue 33 item 2).

Where the poses are tool poses, the inverse geometry chose the joints (holding the assembly's
branch, :mod:`evotol.robots.mechanism.posture.held`); where they are joint configurations, they are the poses
themselves. Either way the report shows them, revolute joints wrapped to (-180°, 180°].
"""
from __future__ import annotations

import numpy as np

from evotol.core.axis_limits import configurations
from evotol.errors import EvotolError
from evotol.robots.mechanism.posture.held import joint_table


def pose_joints(problem) -> dict:
    """The joints used at every configuration of a problem (SI, wrapped), or empty.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The study's problem: a mechanism description's model, its joint-space form, or either
        behind per-axis limits (:class:`evotol.core.axis_limits.AxisErrorModel`, one configuration
        per axis slot) or allocated clearances.

    Returns
    -------
    dict
        :func:`evotol.robots.mechanism.posture.held.joint_table` plus ``poses`` (the configurations, SI);
        empty for a robot without joint variables or when the joints cannot be solved.
    """
    robot, poses = configurations(problem.model, problem.poses)
    try:
        table = joint_table(robot, poses)
    except EvotolError:          # a pose the model refuses was already refused when the problem was built
        return {}
    return {**table, "poses": poses.tolist()} if table else {}

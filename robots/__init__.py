"""Robot error models (plugins). See :mod:`evotol.robots.base` for the protocol and :mod:`evotol.robots.checks`
for the conformance checks a plugin passes."""
from evotol.robots.base import RobotErrorModel, SourceSpec, Workspace
from evotol.robots.checks import check_robot, robot_checks

__all__ = ["RobotErrorModel", "SourceSpec", "Workspace", "check_robot", "robot_checks"]

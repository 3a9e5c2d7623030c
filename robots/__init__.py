"""Robot error models (plugins). See :mod:`robots.base` for the protocol and :mod:`robots.checks`
for the conformance checks a plugin passes."""
from robots.base import RobotErrorModel, SourceSpec, Workspace
from robots.checks import check_robot, robot_checks

__all__ = ["RobotErrorModel", "SourceSpec", "Workspace", "check_robot", "robot_checks"]

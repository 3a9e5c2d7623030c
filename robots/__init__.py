"""Robot error models (plugins). See :mod:`robots.base` for the protocol."""
from robots.base import RobotErrorModel, SourceSpec, Workspace, check_robot

__all__ = ["RobotErrorModel", "SourceSpec", "Workspace", "check_robot"]

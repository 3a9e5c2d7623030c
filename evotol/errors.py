"""The one small error hierarchy of evotol (see STYLE.md, "Errors")."""
from __future__ import annotations


class EvotolError(Exception):
    """Base class of every error evotol raises on purpose."""


class ValidationError(EvotolError, ValueError):
    """Bad input: names the field, the value, and what was expected."""

    def __init__(self, field: str, value, expected: str):
        if hasattr(value, "item") and getattr(value, "ndim", 1) == 0:
            value = value.item()  # print 1.0, not np.float64(1.0)
        self.field, self.value, self.expected = field, value, expected
        super().__init__(f"{field} = {value!r}: expected {expected}")


class KinematicsError(EvotolError):
    """A pose is out of reach of the mechanism or at a singularity.

    ``poses`` holds the offending pose(s), in the units of the robot's workspace coordinates.
    """

    def __init__(self, message: str, poses=None):
        self.poses = poses
        super().__init__(message)


class ConvergenceError(EvotolError):
    """A numerical solver did not reach the requested tolerance."""


class InfeasibleError(EvotolError):
    """No allowed design meets the requirement: names the requirement, the smallest achievable
    error (every tolerance at its lower bound) and the pose where it occurs."""

    def __init__(self, requirement: str, smallest_error: float, pose, detail: str = ""):
        self.requirement, self.smallest_error, self.pose = requirement, smallest_error, pose
        super().__init__(f"infeasible: {requirement} cannot be met; with every free tolerance at its lower bound the "
                         f"error is {smallest_error:.6g} at pose {pose}" + (f" ({detail})" if detail else ""))


class CheckFailed(EvotolError, AssertionError):
    """A conformance check failed (a robot, cost model or measure breaks its contract): names the
    plugin, the check and what was measured. Raised, not asserted, so it holds under ``python -O``;
    an ``AssertionError`` too, so pytest reports it as a failed assertion."""

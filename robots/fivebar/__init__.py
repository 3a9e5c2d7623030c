"""The planar 5-bar linkage of Deng 2012, Ch. IV (this package hands on the names of its modules).

* :mod:`.linkage` -- :class:`FiveBar`: inverse and forward geometry (eqs. IV.1-IV.19), parallel
  singularity, modified DH table IV.1 and the joint-clearance mechanism (Sec. IV.3);
* :mod:`.geometric` -- :class:`FiveBarGeometric`, the sensitivity to link-length and actuator
  errors (eqs. IV.27-IV.43), and :func:`combined_max_pose_error` (clearances and geometric
  variations together, Sec. VIII.2).
"""
from evotol.robots.fivebar.geometric import GEOMETRIC_SOURCES, GEOMETRIC_WORKSPACE  # noqa: F401
from evotol.robots.fivebar.geometric import FiveBarGeometric, combined_max_pose_error
from evotol.robots.fivebar.linkage import JOINT_NAMES, MM  # noqa: F401
from evotol.robots.fivebar.linkage import THESIS_LENGTHS, THESIS_WORKSPACE, FiveBar

__all__ = ["FiveBar", "FiveBarGeometric", "combined_max_pose_error", "THESIS_LENGTHS", "THESIS_WORKSPACE"]

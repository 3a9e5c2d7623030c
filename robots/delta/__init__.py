"""Delta parallel robot with Khalil–Kleinfinger geometric errors (Brahmia et al. 2023).

* :mod:`.parameters` -- the 47 error parameters of eq. (12) (``PARAMETER_NAMES``, ``LINEAR``, ``ANGULAR``);
* :mod:`.geometry` -- nominal dimensions (:class:`DeltaGeometry`), the 15 postures of Fig. 5
  (``POSTURES_MM``) and uniform points of the cylindrical workspace (:func:`cylinder_poses`);
* :mod:`.chains` -- the legs as KK trees with errors (eqs. 1-2, 4, 6, Tables 1-2) and what differs
  from the printed paper;
* :mod:`.kinematics` -- nominal inverse and forward kinematics (eqs. 3, 11);
* :mod:`.closure` -- forward kinematics with errors (loop closure, eq. 3 with eq. 5);
* :mod:`.model` -- :class:`DeltaRobot`, the :class:`evotol.robots.base.RobotErrorModel` plugin.
"""
from evotol.robots.delta.geometry import POSTURES_MM, DeltaGeometry, cylinder_poses
from evotol.robots.delta.model import DeltaRobot
from evotol.robots.delta.parameters import ANGULAR, LINEAR, PARAMETER_NAMES

__all__ = ["DeltaGeometry", "DeltaRobot", "POSTURES_MM", "PARAMETER_NAMES", "LINEAR", "ANGULAR",
           "cylinder_poses"]

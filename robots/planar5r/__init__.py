"""Planar 5R symmetrical parallel mechanism under link-length uncertainty, actuator errors and
joint clearances (Lara-Molina, Koroishi, Policarpo and Steffen, COBEM 2019).

* :mod:`.design` -- non-dimensional design space (s, t), Table 2 cases (eqs. 1-6);
* :mod:`.kinematics` -- inverse / forward kinematics with both branches, perturbed forward
  kinematics, Jacobians, singular loci, usable workspace, MIC, LCI (eqs. 9-22);
* :mod:`.uncertainty` -- Table 1 / Sec. 2.5 random variables, MC and Latin hypercube sampling,
  per-pose statistics, LHS-vs-MC convergence;
* :mod:`.model` -- :class:`Planar5R`, the :class:`evotol.robots.base.RobotErrorModel` plugin.
"""
from evotol.robots.planar5r.design import CASES, TABLE2_PRINTED, Design5R, get_case
from evotol.robots.planar5r.model import SOURCES, Planar5R
from evotol.robots.planar5r.uncertainty import UncertaintyModel, pose_statistics, sample_deviations

__all__ = ["CASES", "TABLE2_PRINTED", "Design5R", "get_case", "Planar5R", "SOURCES", "UncertaintyModel",
           "pose_statistics", "sample_deviations"]

"""Your own mechanism from a description file: modified-DH frames, loops, end-effector, sources.

>>> from evotol.robots.mechanism import MechanismModel
>>> robot = MechanismModel("robots/mechanisms/fivebar.toml")    # a RobotErrorModel
>>> robot.sensitivity(robot.workspace.grid(5)).shape            # (25, 6, n_sources)
>>> robot.clearance_mechanism()                                 # for evotol.robots.clearance.max_pose_error

Sub-packages, one concept each (issue 39 item 5):

* :mod:`.description` -- reading a description: :mod:`.description.reader` (the TOML loader),
  :mod:`.description.expressions` (safe entry expressions, complex-step derivatives),
  :mod:`.description.parts` (frames, loops, points, coordinates, clearances),
  :mod:`.description.mechanism` (the whole description, its source names),
  :mod:`.description.standard_dh` (a textbook's standard-DH table), :mod:`.description.shipped`
  (finding a description by path or shipped name), :mod:`.description.limits` (joint limits),
  :mod:`.description.plausibility` (values that parse but do not mean what was written);
* :mod:`.urdf` -- serial arms from URDF: :mod:`.urdf.reader` (read with Pinocchio),
  :mod:`.urdf.check` (agreement with Pinocchio and finite differences);
* :mod:`.kinematics` -- :mod:`.kinematics.tree` (forward kinematics of the frame tree, exact
  first-order maps), :mod:`.kinematics.placement` (placement errors as local twists),
  :mod:`.kinematics.rotations`, :mod:`.kinematics.serial`, :mod:`.kinematics.serial_kernels` and
  :mod:`.kinematics.serial_newton` (the compiled path of a serial chain: sensitivities, Monte Carlo,
  inverse geometry and posture check), :mod:`.kinematics.forward_at` (the chain at given joint values);
* :mod:`.posture` -- :mod:`.posture.inverse_geometry` (continued Newton inverse geometry),
  :mod:`.posture.working_mode` (the declared assembly), :mod:`.posture.held` (the posture over a task);
* :mod:`.model` -- the error model: :mod:`.model.error_model` (:class:`MechanismModel`),
  :mod:`.model.sources` (its error sources), :mod:`.model.joint_space` (poses as joint
  configurations), :mod:`.model.clearances` (the clearance mechanism), :mod:`.model.random_sources`
  (what changes from cycle to cycle), :mod:`.model.identifiability` (rank, blind and duplicated
  directions);
* :mod:`.callouts` -- drawing callouts: :mod:`.callouts.zones` (exact zones as placement errors),
  :mod:`.callouts.model` (the error model carrying them), :mod:`.callouts.table` (the study-file table);
* :mod:`.checks` -- what ``evotol check-mechanism`` checks (:mod:`.checks.description`) and shows
  (:mod:`.checks.inspection`).

``docs/mechanisms.md`` documents the file format.

The parameters several definitions of this package share are described once, here.

Parameters
----------
n : int
    Number of configurations.
model : evotol.robots.mechanism.model.error_model.MechanismModel
    The mechanism's error model.
path : str or Path
    The URDF file.
poses : (n, n_coordinates) array_like
    Target poses (SI: m, rad).
max_step : float, optional
    Largest continuation step, as a fraction of each coordinate's range (dimensionless;
    at most 200 steps).
zones : {"exact", "boxes"}
    The zone model.
"""
from evotol.robots.mechanism.description.reader import load_mechanism, mechanism_from_dict
from evotol.robots.mechanism.kinematics.tree import Kinematics
from evotol.robots.mechanism.description.mechanism import Mechanism
from evotol.robots.mechanism.model.error_model import MechanismModel
from evotol.robots.mechanism.description.parts import ClearanceChain, ClearanceSpec, Coordinate, Frame, Loop, Point

__all__ = ["ClearanceChain", "ClearanceSpec", "Coordinate", "Frame", "Kinematics", "Loop", "Mechanism", "MechanismModel",
           "Point", "load_mechanism", "mechanism_from_dict"]

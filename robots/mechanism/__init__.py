"""Your own mechanism from a description file: modified-DH frames, loops, end-effector, sources.

>>> from evotol.robots.mechanism import MechanismModel
>>> robot = MechanismModel("robots/mechanisms/fivebar.toml")    # a RobotErrorModel
>>> robot.sensitivity(robot.workspace.grid(5)).shape            # (25, 6, n_sources)
>>> robot.clearance_mechanism()                                 # for evotol.robots.clearance.max_pose_error

Modules: :mod:`.expressions` (safe entry expressions, complex-step derivatives), :mod:`.parts`
(frames, loops, points, coordinates, clearances), :mod:`.mechanism` (the whole description, its
source names), :mod:`.description` (the TOML loader), :mod:`.shipped` (finding a description by
path or shipped name), :mod:`.kinematics` (forward kinematics, exact first-order maps),
:mod:`.inverse_geometry` (continued Newton inverse geometry), :mod:`.model` (the error model),
:mod:`.sources` (its error sources), :mod:`.clearance_model` (the clearance mechanism). Serial arms
from URDF (issue 23): :mod:`.urdf` (reading a URDF with Pinocchio), :mod:`.placement` (placement
errors as local twists), :mod:`.limits` (joint limits), :mod:`.serial` and :mod:`.serial_kernels`
(the compiled path of a serial chain), :mod:`.identifiability` (rank, blind and duplicated
directions), :mod:`.urdf_check` (agreement with Pinocchio and finite differences),
:mod:`.inspection` (what ``evotol check-mechanism`` shows).
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

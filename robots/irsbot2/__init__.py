"""The IRSBot-2 (Deng 2012, Ch. II and VI): inverse geometry, modified DH tables II.1-II.2, clearance model.

A 2-DOF translational spatial robot (two hybrid legs: a parallelogram in series with a spatial
distal module of two links); the platform point ``P = (x, 0, z)`` moves in the plane ``x_0 O z_0``.
Units: metres and radians; poses are ``(x, z)`` in metres.

* :mod:`.parameters` -- Tabs. VI.1 and VI.4 (``THESIS_VI1``, ``THESIS_VI4``);
* :mod:`.model` -- :class:`IRSBot2`: geometry, equivalent planar legs, inverse geometry
  (eqs. II.1-II.35, with the corrections listed there), singularity measures, reachability;
* :mod:`.dh_tables` -- the modified DH tables II.1-II.2 (row 28 corrected), their joint values
  and loop closure (mixin of :class:`IRSBot2`);
* :mod:`.clearance` -- the clearance mechanism (Ch. V-VI, mixin of :class:`IRSBot2`), its leg
  swap :func:`mirror_joint_map` and the error-map square :data:`MAP_WORKSPACE`;
* :mod:`.subworkspace` -- singularity-free rectangles (Sec. VII.2.1, Figs. VI.4-VI.5).

The parameters several definitions of this package share are described once, here.

Parameters
----------
poses : array_like, shape (n, 2) or (2,)
    Platform points ``(x, z)``, m.
"""
from evotol.robots.irsbot2.clearance import MAP_WORKSPACE, IRSBot2Clearances, mirror_joint_map
from evotol.robots.irsbot2.dh_tables import IRSBot2DHTables
from evotol.robots.irsbot2.model import IRSBot2
from evotol.robots.irsbot2.parameters import MM, PI, THESIS_VI1, THESIS_VI4
from evotol.robots.irsbot2.subworkspace import SubWorkspace, centred_singularity_free_rectangle, singularity_free_rectangle

__all__ = ["IRSBot2", "IRSBot2DHTables", "IRSBot2Clearances", "mirror_joint_map", "MAP_WORKSPACE", "SubWorkspace",
           "singularity_free_rectangle", "centred_singularity_free_rectangle", "THESIS_VI1", "THESIS_VI4", "MM", "PI"]

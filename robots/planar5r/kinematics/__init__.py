"""Kinematics of the planar 5R symmetrical parallel mechanism (Lara-Molina et al. 2019, Secs. 2.3-2.5).

This package hands on the names of its modules, so ``from evotol.robots.planar5r import kinematics as K``
gives them all:

* :mod:`.conventions` -- frame (``A_1 = (-r3, 0)``, eqs. 11-12 / 16-19), working and assembly
  modes as signs of cross products, shared input checks;
* :mod:`.position` -- inverse kinematics (4 working modes), forward kinematics (both assembly
  modes) and the paper's closed form eqs. 13-15;
* :mod:`.perturbed` -- forward kinematics with geometric errors, actuator errors and joint
  clearances (Sec. 2.5);
* :mod:`.jacobians` -- ``J_x``, ``J_q``, ``det J_x`` and the LCI (Sec. 3);
* :mod:`.singularities` -- type I circles (eqs. 16-19), type II locus, distance to them;
* :mod:`.workspace` -- usable workspace and its MIC (eqs. 20-22, closed form and numeric search).

The parameters several definitions of this package share are described once, here.

Parameters
----------
r1, r2, r3 : float
    Crank ``A_iB_i``, coupler ``B_iP`` and half base ``OA_i`` lengths, in one length unit
    (dimensionless in the paper, m in :class:`~evotol.robots.planar5r.model.Planar5R`).
working_mode : str or tuple of int
    ``"+-"`` (default), ``"-+"``, ``"++"``, ``"--"`` or a pair ``(m_1, m_2)`` of +1/-1.
assembly : {1, -1}
    Assembly mode sigma (side of ``B_1 -> B_2`` on which ``P`` lies).
"""
from evotol.robots.planar5r.kinematics.conventions import DEFAULT_WORKING_MODE, WORKING_MODES, cross2, working_mode_signs
from evotol.robots.planar5r.kinematics.jacobians import (inverse_condition_number, jacobian, jacobians,
                                                  local_conditioning_index, type2_determinant)
from evotol.robots.planar5r.kinematics.perturbed import ERROR_PARAMETERS, perturbed_position
from evotol.robots.planar5r.kinematics.position import (circle_intersection, crank_points, forward_kinematics,
                                                 forward_kinematics_eq15, inverse_kinematics, inverse_kinematics_raw)
from evotol.robots.planar5r.kinematics.singularities import distance_to_singular_loci, type1_circles, type2_locus
from evotol.robots.planar5r.kinematics.workspace import UsableWorkspaceMap, mic_closed_form, mic_numeric, usable_workspace

__all__ = ["working_mode_signs", "cross2", "inverse_kinematics_raw", "inverse_kinematics", "circle_intersection",
           "crank_points", "forward_kinematics", "forward_kinematics_eq15", "perturbed_position", "jacobians",
           "jacobian", "type2_determinant", "inverse_condition_number", "local_conditioning_index", "type1_circles",
           "type2_locus", "mic_closed_form", "distance_to_singular_loci", "mic_numeric", "UsableWorkspaceMap",
           "usable_workspace", "WORKING_MODES", "DEFAULT_WORKING_MODE", "ERROR_PARAMETERS"]

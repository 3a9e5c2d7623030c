"""The IRSBot-2 with joint clearances (Deng 2012, Ch. V-VI): the clearance mechanism on the DH
tree, the leg-swap symmetry of its joints, and the square of the error maps (Figs. VI.1/VI.3).

:class:`IRSBot2Clearances` is a mixin of :class:`evotol.robots.irsbot2.model.IRSBot2`: it reads the
robot's :meth:`~evotol.robots.irsbot2.dh_tables.IRSBot2DHTables.dh_tree` and
:meth:`~evotol.robots.irsbot2.dh_tables.IRSBot2DHTables.dh_values`.

Units: metres and radians; poses are ``(x, z)`` in metres.
"""
from __future__ import annotations

from evotol.robots.base import Workspace
from evotol.robots.clearance.model import Chain, ClearanceBounds, ClearanceMechanism, Joint
from evotol.robots.irsbot2.parameters import MM


class IRSBot2Clearances:
    """The IRSBot-2's clearance model (mixin of :class:`evotol.robots.irsbot2.model.IRSBot2`, which
    supplies the DH tree and its joint values).
    """

    def clearance_mechanism(self, *, parallelograms: bool = False, distal: ClearanceBounds | None = None,
                            actuated: ClearanceBounds | None = None, passive: ClearanceBounds | None = None) -> ClearanceMechanism:
        """The IRSBot-2 with joint clearances (Ch. V-VI).

        parallelograms=False: clearances in the distal module only (Sec. VI.1): four serial chains
        of four revolute joints from the (rigid) elbows to the platform, 16 joints, 96 screw
        variables, 18 loop equations -> the thesis's 78 variables. parallelograms=True (Sec. VI.2):
        the elbows become sub-end-effectors of the two parallelogram sub-robots (chains ``A_i-B_i``
        and ``D_i-C_i``), 24 joints -> 114 variables (eq. VI.38).

        Defaults: distal joints Tab. VI.3 (beta_xy 0.01 rad, beta_z 0.2 rad, 0.1 mm, 0.1 mm);
        parallelograms Tabs. VI.7-VI.9: actuated ``A_i`` beta_z = 0.001 rad, passive ``B_i, C_i, D_i``
        beta_z = 0.2 rad (the captions of Tabs. VI.8 and VI.9 are swapped in the thesis: the
        table indexed ``p,12,1`` -- leg 2's actuated joint -- has 0.001 rad).

        Parameters
        ----------
        parallelograms : bool
            Also model the clearances of the two parallelograms (Sec. VI.2).
        distal : ClearanceBounds or None
            Bounds of the 16 distal joints; None: Tab. VI.3 (0.01 rad, 0.2 rad, 0.1 mm, 0.1 mm).
        actuated : ClearanceBounds or None
            Bounds of the actuated joints ``A_i`` (with ``parallelograms``); None: 0.01 rad,
            0.001 rad, 0.1 mm, 0.1 mm.
        passive : ClearanceBounds or None
            Bounds of the passive parallelogram joints ``B_i, C_i, D_i``; None: as ``distal``.

        Returns
        -------
        ClearanceMechanism
            Spatial mechanism with end-effector ``P`` and pose names ``("x", "z")``.
        """
        distal = distal or ClearanceBounds(0.01, 0.2, 0.1 * MM, 0.1 * MM)
        actuated = actuated or ClearanceBounds(0.01, 0.001, 0.1 * MM, 0.1 * MM)
        passive = passive or ClearanceBounds(0.01, 0.2, 0.1 * MM, 0.1 * MM)
        joints, chains = [], []
        distal_frames = {("1", 1): ("7", "8", "9", "10", "11"), ("2", 1): ("12", "13", "14", "15", "16"),
                         ("1", 2): ("23", "24", "25", "26", "27"), ("2", 2): ("28", "29", "30", "31", "32")}
        bodies = {"P": "11"}
        for i in (1, 2):
            elbow = f"E{i}"
            if parallelograms:
                A, B_, D, C = (("1", "2", "3", "4") if i == 1 else ("17", "18", "19", "20"))
                cut = "5" if i == 1 else "21"
                joints += [Joint(f"A{i}", A, True, actuated), Joint(f"B{i}", B_, False, passive),
                           Joint(f"D{i}", D, False, passive), Joint(f"C{i}", C, False, passive)]
                bodies[elbow] = "6" if i == 1 else "22"
                chains += [Chain(f"p1{i}", "base", elbow, (f"A{i}", f"B{i}")),
                           Chain(f"p2{i}", "base", elbow, (f"D{i}", f"C{i}"), path_end=cut)]
            for j in ("1", "2"):
                f7, f8, f9, f10, fp = distal_frames[(j, i)]
                names = (f"E{j}{i}-{f7}", f"E{j}{i}-{f8}", f"F{j}{i}-{f9}", f"F{j}{i}-{f10}")
                joints += [Joint(nm, fr, False, distal) for nm, fr in zip(names, (f7, f8, f9, f10))]
                chains.append(Chain(f"d{j}{i}", elbow if parallelograms else "base", "P", names, path_end=fp))
        return ClearanceMechanism(name="IRSBot-2" + (" (distal + parallelograms)" if parallelograms else " (distal module)"),
                                  tree=self.dh_tree(), joints=joints, bodies=bodies, chains=chains, end_effector="P",
                                  joint_values=self.dh_values, planar=False, pose_names=("x", "z"))


def mirror_joint_map(mech: ClearanceMechanism) -> list[int]:
    """Joint ``k`` -> its mirror image under x -> -x: leg 1 <-> leg 2. :meth:`IRSBot2.clearance_mechanism`
    lists leg 2's joints in the same order as leg 1's, so the map swaps the two halves of the list;
    :func:`evotol.robots.clearance.symmetry.prove_mirror` proves (per pose pair) that it is a symmetry.

    Parameters
    ----------
    mech : ClearanceMechanism
        A mechanism from :meth:`IRSBot2.clearance_mechanism`.

    Returns
    -------
    list of int
        Index of the mirror joint of each joint.
    """
    n = len(mech.joints)
    return [(k + n // 2) % n for k in range(n)]


#: the Cartesian square of the error maps (Figs. VI.1/VI.3). The thesis's text does not give its
#: range; this square is centred on the z axis, inside the workspace of Tabs. VI.1-VI.2 and, like
#: the thesis's (Fig. VI.2), crossed by the parallel singularity.
MAP_WORKSPACE = Workspace(names=("x", "z"), low=(-30 * MM, -70 * MM), high=(30 * MM, -10 * MM), units=("m", "m"),
                          display_units=("mm", "mm"), display_scale=(1e3, 1e3))


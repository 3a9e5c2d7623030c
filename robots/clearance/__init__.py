"""Joint-clearance error-screw engine: global maximum pose error with a certificate (Deng 2012, Ch. III-VI).

Quick use
---------
>>> import numpy as np
>>> from evotol.robots.fivebar import FiveBar
>>> from evotol.robots.clearance import max_pose_error
>>> mech = FiveBar().clearance_mechanism()          # Tab. IV.1-IV.2, thesis clearances
>>> res = max_pose_error(mech, [[0.0, 0.07]])       # poses in metres
>>> res.p_max, res.p_upper, res.r_max, res.r_upper  # attained value and certified bound (m, rad)
>>> res.p_screws[0]                                 # (n_joints, 6) screws that attain p_max
>>> res.dominant_joints(0)                          # which joints use their clearance

Many clearance-bound sets at fixed poses (tolerance synthesis, issue 3)
-----------------------------------------------------------------------
:class:`ClearanceEvaluator` computes the per-pose linear maps **once** (kinematics, error mapping
matrices, loop-equation null spaces) and then evaluates any number of bound sets; identical
sub-problems (same pose and same bounds on a decoupled block -- for a planar robot the in-plane
block only sees ``beta_z, b_xy``, the out-of-plane block only ``beta_xy, b_z``) are solved once::

    from evotol.robots.fivebar import FiveBar
    from evotol.robots.clearance import ClearanceEvaluator
    mech = FiveBar().clearance_mechanism()            # joints A, C, B, D, E (mech.joints order)
    ev = ClearanceEvaluator(mech, [[0.0, 0.070]])      # one pose (m): maps computed here
    bounds = mech.thesis_bounds(b_xy=BXY, b_z=BZ)      # BXY, BZ: (n_sets, 5) in metres
    res = ev.evaluate(bounds)                          # all sets at pose 0 (pose_index=0), one process
    res = ev.evaluate(bounds, workers=None)            # ... chunks on all local cores (or scheduler=...)
    res.p_max, res.p_upper, res.r_max, res.r_upper     # (n_sets,) arrays; res.gap <= 1e-3

Cost: the 5-bar's 32 768 tolerance combinations of the thesis's Sec. VII.1.2 at (0, 70) mm take
under 1 s (dedup leaves 1 024 in-plane + 32 out-of-plane problems) with ``beta_xy`` fixed;
when ``beta_xy = b_xy / h`` varies with every set, every set is a new out-of-plane problem with
a nearly round rotation set (many directions): ~2.5 min of CPU, i.e. ~75 s on two workers; the per-set bracket is ``[res.p_max, res.p_upper]``. Results are
arrays in the order of ``bounds``; ``res.p_screws[i]`` are the maximising joint screws.

``bounds`` is an array ``(n_sets, n_joints, 4)`` with columns ``[beta_xy (rad), beta_z (rad),
b_xy (m), b_z (m)]`` (Deng eqs. III.3-III.6); ``pose_index`` (int or (n_sets,) array) picks the
pose of each set. ``ev.evaluate_poses(bounds)`` evaluates one bound set (or one per pose) at
every pose. For a design (dimension) sweep build one mechanism per design, e.g.
``IRSBot2(l1=..., l2=...).clearance_mechanism(...)``, and call ``max_pose_error`` on its few
poses; the cost is dominated by the number of (pose, bound-set) cases.

Other entry points: ``grid.grid_max_pose_error(mech, poses, workers=None, scheduler=None)``
(local processes or a Dask cluster), ``sample_max_errors`` (what plain Monte Carlo of the
clearances would report -- it falls short of the worst case), ``max_pose_error(...,
extra=(J, t))`` (clearances plus other interval sources, e.g. ``evotol.robots.fivebar.combined_max_pose_error``).

Modules: :mod:`.kinematics` (modified DH / Khalil-Kleinfinger frames, adjoints),
:mod:`.model` (the mechanism: bodies, error mapping matrices, loop equations; its plain values
in :mod:`.parts`, its per-pose maps in :mod:`.pose_maps`, built by :mod:`.loops` (the sparse loop
basis); the nonlinear chain model that checks them in :mod:`.nonlinear`), :mod:`.support`
(per-direction convex problem with a duality certificate; its bounds in :mod:`.certificate`),
:mod:`.newton_kernel` (its Newton iteration and centring steps compiled with numba; the NumPy
iteration in :mod:`.newton_numpy` is the reference and the fallback; the kernel bodies in
:mod:`.newton_kernel_bodies`),
:mod:`.maxerror` (:func:`max_pose_error`, :class:`ClearanceEvaluator`), :mod:`.branch_bound` (the
branch and bound over directions) and :mod:`.patches` (its patches and bounds), :mod:`.options`
(the engine's settings, one frozen :class:`EngineOptions` passed down; ``LEGACY``: before issue
13), :mod:`.result` (:class:`MaxPoseError`), :mod:`.sampling` (random clearance states),
:mod:`.multistart` (the thesis's QR + multistart local optimisation, the baseline),
:mod:`.grid` (grid studies on local cores or a Dask cluster).

The parameters several definitions of this package share are described once, here.

Parameters
----------
poses : (n, d) or (d,) array_like
    Poses in the mechanism's pose coordinates (m).
options : EngineOptions, optional
    The engine's settings (default :data:`evotol.robots.clearance.options.DEFAULT`).
nd : int
    Number of disk cones.
mech : ClearanceMechanism
    The mechanism.
tol : float, optional
    Relative gap between the attained value and the certified bound (default 1e-3).
n_solves : int, optional
    Support problems solved (default 0).
gram_inv : (K, m, m) ndarray or None, optional
    Precomputed ``pinv(B^T B)`` (None: computed here).
"""
from evotol.robots.clearance.kinematics import DHFrame, DHTree, adjoint, kk_transform
from evotol.robots.clearance.maxerror import ClearanceEvaluator, MaxPoseError, evaluate_cases, max_pose_error
from evotol.robots.clearance.options import EngineOptions
from evotol.robots.clearance.sampling import sample_max_errors
from evotol.robots.clearance.model import BOUND_NAMES, Chain, ClearanceBounds, ClearanceMechanism, Joint, PoseMaps
from evotol.robots.clearance.multistart import MultistartResult, multistart_max_pose_error
from evotol.robots.clearance.nonlinear import twist_between

__all__ = ["BOUND_NAMES", "Chain", "ClearanceBounds", "ClearanceEvaluator", "ClearanceMechanism", "DHFrame", "DHTree",
           "EngineOptions",
           "Joint", "MaxPoseError", "MultistartResult", "PoseMaps", "adjoint", "evaluate_cases", "kk_transform",
           "max_pose_error", "multistart_max_pose_error", "sample_max_errors", "twist_between"]

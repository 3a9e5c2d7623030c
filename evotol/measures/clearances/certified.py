"""The certified worst case of geometric tolerances and clearance bounds together (Deng 2012
Sec. VII.1 stated as an optimisation; issue 12 item 5): the robot with its clearance classes as
sources (:class:`WithClearances`), the ``worst_case`` measure's engine call and random consistent
clearance states. The classes themselves are in :mod:`evotol.measures.clearances.classes`.

Measure. At pose p, the geometric sources (intervals ``|δ_j| <= t_j`` through the first-order map J_g)
and the clearance screws s (each joint's s_k in its set C_k(c), consistent with the loops,
``B^T s = 0``) move the end-effector by ``J_g δ + C s``. The reachable set is the Minkowski sum
``P_g(t) + P_c(c)``, and the worst case ``W(t, c) = max |J_g δ + C s|`` is computed by the
certified engine of :mod:`evotol.robots.clearance` (``evaluate_cases(..., extra=(J_g, t))``): a value
**attained** by explicit screws and source errors, and a **proven upper bound** (relative gap
<= ``tol``, default 1e-3).

Structure (proved in ``docs/clearance_allocation.md``, checked numerically in the tests):
  * W is nondecreasing in every t_j and c_k (C_k(c) = c·B_k grows with c, B_k convex and
    containing 0), and positively homogeneous of degree 1 in (t, c) when no fixed bound is
    nonzero;
  * for a fixed direction u the clearance support function h_c(u; c) is *concave* in c (a
    mixture of two feasible screw sets is feasible for the mixed bounds) -- with loops, W is
    **not convex** in (t, c): along random segments of the 5-bar's thesis problem it exceeds
    its chord by up to 150-400 %, and two parallel chains give W = min(c_1, c_2) exactly.

So the certified optimum's cutting planes do not apply; :mod:`evotol.allocators.monotone` uses
the monotonicity instead (polyblock outer approximation: a proven lower bound on the cost).

The parameters several definitions of this module share are described once, here.

Parameters
----------
geometric : bool
    Whether the robot's geometric sources are included (False: clearances only).
poses : numpy.ndarray, (n_poses, d)
    Poses (m or rad).
robot : WithClearances
    The robot with its clearance classes.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from evotol.measures.clearances.classes import ClearanceSources
from evotol.errors import ValidationError
from evotol.robots.base import RobotErrorModel

#: screw component (row of a joint's [dr; dt] in its frame) -> bound component index
_SCREW_KIND = (0, 0, 1, 2, 2, 3)
#: twist order of the engine [dtheta; dp] -> evotol's [dp; dtheta]
_TO_ENGINE = [3, 4, 5, 0, 1, 2]


def error_sources(robot: RobotErrorModel, clearances: ClearanceSources, geometric: bool = True) -> tuple:
    """The sources of a robot with clearance classes, in order: the robot's (when ``geometric``)
    followed by the classes -- the sources of :class:`WithClearances` and of a
    :class:`~evotol.core.problem.ToleranceProblem` with ``clearances`` (a study file reads them to
    know which ``[sources.NAME]`` exist before the problem is built).

    Parameters
    ----------
    robot : RobotErrorModel
        The robot whose geometric sources come first (interval sources only).
    clearances : ClearanceSources
        The clearance classes, appended after the geometric sources.

    Returns
    -------
    tuple of evotol.robots.base.SourceSpec
        The geometric sources (if any), then ``clearances.sources``.

    Raises
    ------
    evotol.errors.ValidationError
        A class named like a geometric source, or a geometric source that is not an interval
        (dim != 1).
    """
    own = tuple(robot.sources) if geometric else ()
    clash = {s.name for s in own} & set(clearances.names)
    if clash:
        raise ValidationError("clearances.classes", sorted(clash), f"names other than the sources of {robot.name}")
    for s in own:
        if s.dim != 1:
            raise ValidationError(f"{robot.name} source {s.name!r}", s.shape,
                                  "interval sources only next to clearances (the engine adds intervals)")
    return own + tuple(clearances.sources)


class WithClearances(RobotErrorModel):
    """A robot's geometric sources followed by clearance classes, for :class:`ToleranceProblem`.

    The clearance classes have no linear column: ``sensitivity`` gives them zero columns, and the
    problem evaluates them only through the certified engine (:func:`worst_case`). Not a robot to
    use on its own (its first-order map omits the clearances).

    Parameters
    ----------
    robot : RobotErrorModel
        The robot whose geometric sources come first (interval sources only).
    clearances : ClearanceSources
        The clearance classes, appended as sources after the geometric ones.

    Raises
    ------
    evotol.errors.ValidationError
        A class named like a geometric source, or a geometric source that is not an interval
        (dim != 1).
    """

    def __init__(self, robot: RobotErrorModel, clearances: ClearanceSources, geometric: bool = True):
        self.base, self.clearances, self.geometric = robot, clearances, bool(geometric)
        self.name = f"{robot.name} + clearances" if geometric else f"{robot.name} (clearances)"
        self.workspace = robot.workspace
        self.sources = error_sources(robot, clearances, geometric)
        self.n_geometric = len(self.sources) - len(clearances.sources)

    def sensitivity(self, poses) -> np.ndarray:
        """First-order map of the geometric sources (the wrapped robot's), with zero columns for the
        clearance classes.
        """
        J = np.asarray(self.base.sensitivity(poses), float) if self.geometric else \
            np.zeros((len(self.check_poses(poses)), 6, 0))
        return np.concatenate([J, np.zeros(J.shape[:2] + (len(self.clearances.classes),))], axis=2)

    def pose_error(self, poses, errors) -> np.ndarray:   # pragma: no cover - guarded by has_nonlinear_model
        """Not available: clearances have no nonlinear model (:attr:`has_nonlinear_model` is False).

        Raises
        ------
        evotol.errors.ValidationError
            Always.
        """
        raise ValidationError("pose_error", self.name, "geometric sources only: clearances are first order")

    @property
    def has_nonlinear_model(self) -> bool:
        """False: clearances are evaluated first order only (certified engine)."""
        return False


@dataclass(frozen=True)
class ClearanceWorstCase:
    """Certified worst case at every pose of designs (n_designs, n_poses) per component
    (``"position"`` m, ``"orientation"`` rad): attained value, proven bound, worst direction (unit,
    base axes, (n, P, 3)) and each source's share of the error at that direction ((n, P, n_src);
    the shares miss what the fixed, unallocated clearance bounds contribute).

    Parameters
    ----------
    value : dict
        Component -> (n_designs, n_poses) attained worst-case error (m or rad).
    bound : dict
        Component -> (n_designs, n_poses) proven upper bound (m or rad).
    direction : dict
        Component -> (n_designs, n_poses, 3) unit direction of the worst error (base axes).
    contrib : dict
        Component -> (n_designs, n_poses, n_sources) each source's share of the attained error,
        as a fraction of it (dimensionless).
    n_solves : int
        Number of support problems the engine solved (its work).
    """

    value: dict
    bound: dict
    direction: dict
    contrib: dict
    n_solves: int


def _only(maps, comp: str):
    """The maps with the other target removed: the engine then skips it (position-only
    requirements do not pay for the rotational branch and bound)."""
    import dataclasses

    if comp == "position":
        return [dataclasses.replace(pm, C_rot=pm.C_rot[:, :0], rot_comps=()) for pm in maps]
    return [dataclasses.replace(pm, C_pos=pm.C_pos[:, :0], pos_comps=()) for pm in maps]


def worst_case(robot: WithClearances, poses: np.ndarray, jacobian: np.ndarray, T,
               components: Sequence[str] = ("position", "orientation")) -> ClearanceWorstCase:
    """Certified worst-case position (m) and orientation (rad) error of designs T (n, n_sources)
    at every pose: the geometric intervals through ``jacobian`` (n_poses, 6, n_sources; the
    clearance columns are ignored) plus the consistent clearance screws inside the classes' bounds
    (Minkowski sum; :func:`evotol.robots.clearance.evaluate_cases` with ``extra``). Only the listed
    ``components`` are computed.

    Parameters
    ----------
    jacobian : numpy.ndarray, (n_poses, 6, n_sources)
        First-order map of the twist ``[dp; dtheta]`` (:meth:`WithClearances.sensitivity`).
    T : array_like, (n, n_sources) or (n_sources,)
        Designs: geometric tolerances first, then the class tolerances (m or rad).
    components : sequence of {"position", "orientation"}
        Error components to compute.

    Returns
    -------
    ClearanceWorstCase
        Attained values, proven bounds, worst directions and shares per component.
    """
    from evotol.robots.clearance import evaluate_cases

    cl = robot.clearances
    T = np.atleast_2d(np.asarray(T, float))
    n, P, g = T.shape[0], len(poses), robot.n_geometric
    maps = cl.maps(poses)
    if len(components) == 1:
        maps = _only(maps, components[0])
    idx = np.tile(np.arange(P), n)                                   # case = (design, pose)
    bounds = np.repeat(cl.bounds(T[:, g:]), P, axis=0)
    extra = None
    if g:
        Jg = jacobian[:, _TO_ENGINE, :g]
        extra = (Jg, np.repeat(T[:, :g], P, axis=0))
    res = evaluate_cases(cl.mechanism, maps, idx, bounds, tol=cl.tol, extra=extra)
    out = ClearanceWorstCase({}, {}, {}, {}, res.n_solves)
    for comp in components:
        w, rows = ("p", slice(3, 6)) if comp == "position" else ("r", slice(0, 3))
        val = getattr(res, f"{w}_max")
        tw = getattr(res, f"{w}_twist")
        inv = 1.0 / np.where(val > 0, val, 1.0)
        u = tw[:, rows] * inv[:, None]
        contrib = np.zeros((n * P, T.shape[1]))
        if g:   # u·J_j δ_j for the geometric sources at the maximiser
            contrib[:, :g] = np.einsum("ck,ckj,cj->cj", u, Jg[idx][:, rows], getattr(res, f"{w}_extra"))
        S = getattr(res, f"{w}_screws").reshape(n * P, -1)
        for pm in maps:   # u·C_col s_col summed over the columns a class owns
            C, comps = (pm.C_pos, pm.pos_comps) if w == "p" else (pm.C_rot, pm.rot_comps)
            if not comps:
                continue
            part = np.einsum("ck,ckr,cr->cr", tw[:, list(comps)] * inv[:, None], C[idx], S[:, pm.cols])
            own = cl.owner[pm.cols // 6, np.array(_SCREW_KIND)[pm.cols % 6]]
            for r in np.flatnonzero(own >= 0):
                contrib[:, g + own[r]] += part[:, r]
        out.value[comp] = val.reshape(n, P)
        out.bound[comp] = getattr(res, f"{w}_upper").reshape(n, P)
        out.direction[comp] = u.reshape(n, P, 3)
        out.contrib[comp] = (contrib * inv[:, None]).reshape(n, P, -1)
    return out


def sample_twists(robot: WithClearances, poses: np.ndarray, c: np.ndarray, n_samples: int, rng,
                  mode: str = "uniform") -> np.ndarray:
    """End-effector twists ``[dp; dtheta]`` (n_poses, n_samples, 6) of random consistent clearance
    states for class tolerances c (n_classes,): every joint's screw drawn uniformly inside (or, with
    ``mode="boundary"``, on the boundary of) its disks and intervals, projected onto the loop
    equations ``B^T s = 0`` and scaled back into the set -- the sampling of
    :func:`evotol.robots.clearance.sample_max_errors`, per sample instead of its maximum.

    Parameters
    ----------
    c : array_like, (n_classes,)
        Class tolerances (m or rad).
    n_samples : int
        Samples per pose.
    rng : numpy.random.Generator
        Random generator.
    mode : {"uniform", "boundary"}
        Screws drawn inside their sets or on their boundaries.

    Returns
    -------
    numpy.ndarray
        (n_poses, n_samples, 6) twists ``[dp; dtheta]`` (m, rad).
    """
    cl = robot.clearances
    b = cl.bounds(np.asarray(c, float)[None])[0]
    maps = cl.maps(poses)
    out = np.zeros((len(poses), n_samples, 6))
    for p in range(len(poses)):
        for pm in maps:
            s = pm.sample_screws(p, b, n_samples, rng, mode)
            out[p][:, [_TO_ENGINE.index(k) for k in pm.pos_comps]] += s @ pm.C_pos[p].T
            out[p][:, [_TO_ENGINE.index(k) for k in pm.rot_comps]] += s @ pm.C_rot[p].T
    return out

"""The whole workspace: allocate on a few poses, then search the workspace for the pose of
largest normalised error, add it and re-solve, until the requirement holds everywhere searched.

Cutting planes over poses. A design that holds the requirement on a subset of poses may miss it
elsewhere; the error is a continuous function of the pose, so the search is

1. a dense pose set -- ``candidates`` given by the user (e.g. Halton points of a cylinder) or a
   regular grid of the workspace box (``grid`` points per axis) -- evaluated exactly, and
2. (``local=True``) a local maximisation of the normalised error over the pose coordinates
   (a vectorised pattern search inside the workspace box) from the worst dense poses,

so the worst pose found may lie between grid points. The ``add`` worst violating poses are added
and the allocation repeated until the worst error found is within the requirement (relative
``tol``). A lower bound certified on a subset of poses is a lower bound for the whole workspace,
so the certified optimum's certificate carries over; its feasibility is certified on the poses
searched (denser grids: :func:`worst_pose` on the result).

:func:`hold_on_workspace` is the GA's final check: the same search, but the design is scaled
(one factor on every free tolerance, bisection) until it holds at the poses found.

The parameters several definitions of this module share are described once, here.

Parameters
----------
tol : float
    The requirement holds when the normalised error is <= 1 + tol (dimensionless).
dense : ToleranceProblem, optional
    A ready dense problem (overrides ``candidates`` and ``grid``).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from evotol.measures import linear as measures
from evotol.errors import EvotolError, ValidationError, is_integer
from evotol.core.problem import ToleranceProblem


@dataclass
class WorstPose:
    """The pose of largest normalised error found by the search (SI pose coordinates).

    Parameters
    ----------
    pose : numpy.ndarray, (dim,)
        The worst pose found (workspace coordinates, m or rad).
    normalised_error : float
        Its normalised error: max over constrained components of error / bound (dimensionless;
        <= 1 meets the requirement).
    grid_errors : numpy.ndarray, (n_dense,)
        Normalised error at every dense pose.
    dense_poses : numpy.ndarray, (n_dense, dim)
        The dense poses (m or rad).
    local_poses : numpy.ndarray, (k, dim), optional
        End points of the k local searches (m or rad); None without local search.
    local_errors : numpy.ndarray, (k,), optional
        Their normalised errors by the cheaper search evaluation (for the worst case a lower
        estimate); None without local search.
    """

    pose: np.ndarray
    normalised_error: float      # max over constrained components of error / bound
    grid_errors: np.ndarray      # (n_dense,) normalised error at every dense pose
    dense_poses: np.ndarray
    local_poses: np.ndarray | None = None     # (k, dim) end points of the local searches
    local_errors: np.ndarray | None = None    # (k,) their (search) normalised errors


def _normalised(problem: ToleranceProblem, T: np.ndarray, top_only: bool = False) -> np.ndarray:
    """(n_designs, n_poses) max over components of error / bound (exact evaluation; with
    ``top_only`` exact at the poses that can hold the maximum, lower estimates elsewhere)."""
    ev = problem.evaluate(T, top_only=top_only)
    return np.max(np.stack([getattr(ev, c) / lim for c, lim in problem.components]), axis=0)


def _normalised_search(problem: ToleranceProblem, T: np.ndarray, n_directions: int = 150) -> np.ndarray:
    """Cheaper normalised error for the local search: constrained components only, a coarser
    direction grid to start the (exact, attained) ascent -- a lower estimate, used only to steer."""
    if problem.requirement.measure != "worst_case":
        return _normalised(problem, T)
    shape = None if problem.shape.plain else problem.shape
    out = [measures.worst_case(problem.blocks[c], T, n_directions=n_directions, shape=shape).value / lim
           for c, lim in problem.components]
    return np.max(np.stack(out), axis=0)


#: why a calibrated problem is not refined over the workspace (docs/combinations.md, issue 39)
REFINE_REASON = ("the calibration's noise allowance, the random sources' share and the linear-range caps are "
                 "computed at the problem's poses, and rebuilding them at every pose the search adds costs about a "
                 "second a pose; give denser poses instead")


def check_refinable(problem: ToleranceProblem) -> None:
    """Refuse, before any work, a problem whose requirement share depends on its poses: a calibrated one.

    A calibrated problem (:func:`evotol.calibration.calibrated_problem`) takes the instrument noise, the
    random sources and the second-order terms off the requirement at its own poses, and caps each source
    at the linear range found there; a copy at other poses (``at_poses``) keeps them, so a search over
    new poses would judge them against allowances computed elsewhere (docs/combinations.md, issue 39).

    Raises
    ------
    ValidationError
        ``refine`` on a calibrated problem, one line naming both.
    """
    if problem.calibration is not None:
        raise ValidationError("refine", "a calibrated problem", f"a problem without calibration: {REFINE_REASON} "
                              "(calibrated_problem(problem.at_poses(denser), plan))")


def dense_problem(problem: ToleranceProblem, candidates=None, grid: int | list | None = None) -> ToleranceProblem:
    """The problem on the dense search set: ``candidates`` (array of poses) or a workspace grid.

    Parameters
    ----------
    problem : ToleranceProblem
        The problem (its robot's workspace box gives the grid).
    candidates : array_like, (n, dim), optional
        Poses to search (m or rad); take precedence over ``grid``.
    grid : int or list of int, optional
        Grid points per axis of the workspace box (one count, or one per axis). Default:
        ``4 * max(2, round(n_poses ** (1 / dim)))``.

    Returns
    -------
    ToleranceProblem
        The same problem at the dense poses.
    """
    if candidates is not None:
        return problem.at_poses(candidates)
    counts = grid if grid is not None else 4 * max(2, round(problem.n_poses ** (1 / problem.model.workspace.dim)))
    return problem.at_poses(problem.model.workspace.grid(counts))


def worst_pose(problem: ToleranceProblem, t, dense: ToleranceProblem, local: bool = True, n_local: int = 3,
               levels: int = 8) -> WorstPose:
    """Largest normalised error of design t over the dense poses, then refined by local
    maximisation over the pose coordinates inside the workspace box: a vectorised pattern search
    from the ``n_local`` worst dense poses (each level evaluates the 3^dim neighbours at step h
    of every start in one call, moves to the best, halves h; h starts at half the dense spacing).

    Parameters
    ----------
    problem : ToleranceProblem
        The problem (requirement, robot and its workspace box).
    t : array_like or mapping
        The design: tolerances per source (m or rad), anything ``problem.as_array`` takes.
    dense : ToleranceProblem
        The problem on the dense pose set (:func:`dense_problem`).
    local : bool
        Whether to refine by local pattern search between the dense poses.
    n_local : int
        Number of worst dense poses the local searches start from.
    levels : int
        Number of step halvings of each local search.

    Returns
    -------
    WorstPose
        The worst pose and its normalised error; a local maximum replaces the worst dense pose
        only if its exact normalised error is larger.
    """
    t = problem.as_array(t)
    ne = _normalised(dense, t[None], top_only=True)[0]
    k = int(np.argmax(ne))
    best_pose, best = dense.poses[k].copy(), float(ne[k])
    if local:
        ws = problem.model.workspace
        lo, hi = np.asarray(ws.low, float), np.asarray(ws.high, float)
        d = lo.size
        starts = dense.poses[np.argsort(-ne)[:n_local]]
        # initial step: half the typical spacing of the dense set along each axis
        n_axis = max(2.0, len(dense.poses) ** (1 / d))
        h = (hi - lo) / (n_axis - 1) / 2
        offsets = np.array(np.meshgrid(*[[-1.0, 0.0, 1.0]] * d, indexing="ij")).reshape(d, -1).T   # (3^d, d)
        centres, values = starts.copy(), ne[np.argsort(-ne)[:n_local]].copy()
        for _ in range(levels):
            cand = np.clip(centres[:, None, :] + offsets[None] * h, lo, hi).reshape(-1, d)
            try:
                v = _normalised_search(problem.at_poses(cand), t[None])[0].reshape(len(centres), -1)
            except EvotolError:      # some neighbour out of reach: keep the centres, finer steps
                h = h / 2
                continue
            j = np.argmax(v, axis=1)
            vb = v[np.arange(len(centres)), j]
            move = vb > values
            centres[move] = cand.reshape(len(centres), -1, d)[np.arange(len(centres)), j][move]
            values[move] = vb[move]
            h = h / 2
        local_poses, local_errors = centres, values
        i = int(np.argmax(values))
        if values[i] > best:    # judge the found pose exactly
            exact = float(_normalised(problem.at_poses(centres[i][None]), t[None])[0, 0])
            if exact > best:
                best, best_pose = exact, centres[i].copy()
        return WorstPose(best_pose, best, ne, dense.poses, local_poses, local_errors)
    return WorstPose(best_pose, best, ne, dense.poses)


def refine_poses(problem: ToleranceProblem, allocate, *, candidates=None, grid=None, start=None, local: bool = True,
                 add: int = 8, max_rounds: int = 10, tol: float = 1e-9, dense: ToleranceProblem | None = None,
                 n_final: int = 12, n_local: int = 3):
    """Run ``allocate(sub_problem)`` on a growing pose set until its design holds on the dense
    search set (and at the local maxima between its poses). See the module docstring.

    problem: the coarse problem (its poses start the set unless ``start`` indexes ``candidates``).
    Local ascents start from the 3 worst dense poses each round, and from the ``n_final`` worst
    before the search is declared done.
    Returns (result on the last pose set, info dict: rounds, worst_pose, worst_normalised_error,
    n_poses, poses_added).

    Parameters
    ----------
    problem : ToleranceProblem
        The coarse problem; its poses start the set unless ``start`` is given.
    allocate : callable
        ``allocate(sub_problem)`` -> a result with the design ``t`` (e.g. an
        ``AllocationResult``).
    candidates : array_like, (n, dim), optional
        The dense search poses (m or rad); with them no local search is done.
    grid : int or list of int, optional
        Grid points per axis of the workspace box when ``candidates`` is None
        (:func:`dense_problem`).
    start : array_like of int, optional
        Indices into the dense poses of the initial pose set (index mode: later poses are added
        as indices too, listed in ``info["pose_indices"]``).
    local : bool
        Whether to search locally between dense poses (only without ``candidates``).
    add : int
        At most this many worst violating dense poses are added per round (plus, with local
        search, the worst pose and up to ``add`` violating local maxima).
    max_rounds : int
        Maximum number of allocations (>= 1).
    n_final : int
        Number of local searches of the final sweep before the search is declared done.
    n_local : int
        Number of local searches per round (from the worst dense poses).

    Returns
    -------
    result : object
        What ``allocate`` returned on the last pose set.
    info : dict
        ``rounds``, ``worst_pose`` (list, m or rad), ``worst_normalised_error``, ``n_poses``,
        ``poses_added`` (dense poses added), ``n_dense_poses``, ``holds`` (bool), and
        ``pose_indices`` in index mode.

    Raises
    ------
    ValidationError
        If ``allocate`` is not callable, ``max_rounds`` is not a positive integer, or the problem is
        calibrated (:func:`check_refinable`).
    """
    if not callable(allocate):
        raise ValidationError("allocate", allocate, "a function problem -> AllocationResult")
    check_refinable(problem)
    if not is_integer(max_rounds, 1):
        raise ValidationError("max_rounds", max_rounds, "a positive integer")
    dense = dense if dense is not None else dense_problem(problem, candidates, grid)
    if start is not None:
        sub = dense.with_poses(start)
        idx = np.asarray(start)
    else:
        sub, idx = problem, None
    added = 0
    for rnd in range(1, max_rounds + 1):
        res = allocate(sub)
        use_local = local and candidates is None
        wp = worst_pose(problem, res.t, dense, local=use_local, n_local=n_local)
        if use_local and wp.normalised_error - 1 <= tol and n_final > n_local:
            # looks done: a final sweep ascends from every good dense pose, not only the best few
            wp = worst_pose(problem, res.t, dense, local=True, n_local=n_final)
        excess = wp.grid_errors - 1
        if wp.normalised_error - 1 <= tol:
            break
        if rnd == max_rounds:
            break
        new = np.argsort(-excess)[:add]
        new = new[excess[new] > tol]
        if idx is not None:                 # index mode: the pose set is a subset of the candidates
            idx = np.union1d(idx, new)
            sub = dense.with_poses(idx)
        else:
            poses = dense.poses[new]
            if use_local:   # every local maximum that misses the requirement (a few per round)
                lp = wp.local_poses[wp.local_errors - 1 > tol][:add]
                poses = np.vstack([poses, wp.pose[None], lp])
            sub = sub.with_added_poses(poses)
        added += len(new)
    info = {"rounds": rnd, "worst_pose": wp.pose.tolist(), "worst_normalised_error": wp.normalised_error,
            "n_poses": int(sub.n_poses), "poses_added": int(added), "n_dense_poses": int(dense.n_poses),
            "holds": bool(wp.normalised_error - 1 <= tol)}
    if idx is not None:
        info["pose_indices"] = idx
    return res, info


def allocate_on_workspace(allocate, problem: ToleranceProblem, refine: bool | dict = True, **options):
    """The allocator ``allocate`` over the whole workspace: :func:`refine_poses` runs
    ``allocate(sub_problem, **options)`` on a growing pose set until its design holds on the dense
    search set; the refinement's record goes in ``result.info["refinement"]``.

    A wrapper around an allocator (``allocate_optimum(problem, refine=True)`` is
    ``allocate_on_workspace(<the optimum on the given poses>, problem, True)``): the allocator is
    not called back through itself, so its own checks run once, before the search.

    Parameters
    ----------
    allocate : callable
        ``allocate(problem, **options)`` -> :class:`evotol.core.result.AllocationResult`, an
        allocator on the problem's poses.
    problem : ToleranceProblem
        The coarse problem; its poses start the set.
    refine : bool or dict
        ``True``, or a dict of :func:`refine_poses` options (``grid``, ``candidates``, ``local``,
        ``add``, ``max_rounds``, ...).
    **options
        Keyword arguments passed to ``allocate`` at every round.

    Returns
    -------
    evotol.core.result.AllocationResult
        ``allocate``'s result on the last pose set (its ``problem`` holds those poses), with
        ``info["refinement"]``: ``rounds``, ``worst_pose`` (m or rad), ``worst_normalised_error``,
        ``n_poses``, ``poses_added``, ``n_dense_poses``, ``holds``.

    Raises
    ------
    ValidationError
        ``refine`` is neither True nor a dict, or a bad :func:`refine_poses` option.
    """
    if refine is not True and not isinstance(refine, dict):
        raise ValidationError("refine", refine, "True or a dict of refinement options")
    opts = {} if refine is True else dict(refine)
    result, info = refine_poses(problem, partial(allocate, **options), **opts)
    result.info["refinement"] = {k: v for k, v in info.items() if k != "pose_indices"}
    return result


def scale_into_requirement(problem: ToleranceProblem, t) -> np.ndarray:
    """Scale the free tolerances of ``t`` by one factor (bisection, 40 halvings) so the exact
    error at every pose of ``problem`` meets the requirement; returns t unchanged if it already
    does (the error is nondecreasing in the factor, offsets included).

    Parameters
    ----------
    problem : ToleranceProblem
        The problem whose poses and requirement are to be met.
    t : array_like, (n_sources,)
        The design (m or rad per source).

    Returns
    -------
    numpy.ndarray
        (n_sources,) the design (m or rad), free tolerances scaled down (clipped to their
        bounds) to the largest factor found that meets the requirement; ``t`` itself if it
        already holds. Never scaled up.

    Raises
    ------
    InfeasibleError
        If even the lower bounds miss the requirement (``problem.check_feasible``).
    ValidationError
        If no factor down to 1e-12 meets the requirement otherwise.
    """
    t = np.asarray(t, float)
    f = problem.free

    def excess(k):
        tt = problem.full(np.clip(t[f] * k, problem.lower[f], problem.upper[f])[None])[0]
        return problem.evaluate(tt[None], top_only=True).violation[0], tt

    v, _ = excess(1.0)
    if v <= 0:
        return t
    lo, hi = 0.5, 1.0
    while excess(lo)[0] > 0:
        lo /= 2
        if lo < 1e-12:
            problem.check_feasible()
            raise ValidationError("t", t.tolist(), "a design that can be scaled into the requirement")
    for _ in range(40):
        mid = (lo + hi) / 2
        if excess(mid)[0] <= 0:
            lo = mid
        else:
            hi = mid
    return excess(lo)[1]


def hold_on_workspace(problem: ToleranceProblem, t, *, candidates=None, grid=None, local: bool = True,
                      max_rounds: int = 10, tol: float = 1e-9, dense: ToleranceProblem | None = None,
                      n_final: int = 12):
    """The GA's final check: scale design t until it holds at the worst poses found on the
    dense set (+ local maxima). Returns (t, info).

    Parameters
    ----------
    problem : ToleranceProblem
        The problem (requirement, robot and workspace).
    t : array_like or mapping
        The design (m or rad per source).
    candidates : array_like, (n, dim), optional
        Dense search poses (m or rad); with them (or ``local=False``) the design is scaled
        once to hold at every dense pose.
    grid : int or list of int, optional
        Grid points per axis of the workspace box (:func:`dense_problem`).
    local : bool
        Whether to search locally between the dense poses.
    max_rounds : int
        Maximum number of search-and-scale rounds.
    n_final : int
        Number of local searches of the final sweep.

    Returns
    -------
    t : numpy.ndarray
        (n_sources,) the scaled design (m or rad).
    info : dict
        ``rounds``, ``scaled`` (bool), ``worst_pose`` (list, m or rad),
        ``worst_normalised_error`` and ``holds`` of the design returned (``holds``: its worst
        normalised error is within ``tol`` of 1, False when ``max_rounds`` ran out first), and
        ``n_dense_poses``.

    Raises
    ------
    InfeasibleError, ValidationError
        As :func:`scale_into_requirement`.
    """
    check_refinable(problem)
    dense = dense if dense is not None else dense_problem(problem, candidates, grid)
    t = problem.as_array(t)
    if candidates is not None or not local:
        t2 = scale_into_requirement(dense, t)
        wp = worst_pose(problem, t2, dense, local=False)
        return t2, {"rounds": 1, "scaled": bool(not np.allclose(t2, t)), "worst_pose": wp.pose.tolist(),
                    "worst_normalised_error": wp.normalised_error, "holds": bool(wp.normalised_error - 1 <= tol),
                    "n_dense_poses": int(dense.n_poses)}
    found = problem
    t0 = t
    for rnd in range(1, max_rounds + 1):
        wp = worst_pose(problem, t, dense, local=True)
        if wp.normalised_error - 1 <= tol:
            wp = worst_pose(problem, t, dense, local=True, n_local=n_final)
        if wp.normalised_error - 1 <= tol:
            break
        found = found.with_added_poses(np.vstack([dense.poses[np.argsort(-wp.grid_errors)[:8]], wp.pose[None]]))
        t = scale_into_requirement(found, t)
    else:
        # the rounds ran out after a scaling: check the design returned, so the report describes it
        wp = worst_pose(problem, t, dense, local=True, n_local=n_final)
    return t, {"rounds": rnd, "scaled": bool(not np.allclose(t, t0)), "worst_pose": wp.pose.tolist(),
               "worst_normalised_error": wp.normalised_error, "holds": bool(wp.normalised_error - 1 <= tol),
               "n_dense_poses": int(dense.n_poses)}

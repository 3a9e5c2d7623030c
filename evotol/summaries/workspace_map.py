"""Error maps over the continuous workspace: an allocation's error on 2-D slices of the workspace box.

An allocation is computed (and certified) on a finite set of poses; the map shows what it does
between them. Each slice varies two workspace coordinates over their whole range on an
``n × n`` grid and holds the others at the worst allocation pose's values (for a 3-D workspace
the third coordinate at its low end, middle and high end, and at the worst pose's value). Every grid pose is evaluated exactly under the
problem's own measure (:meth:`evotol.core.problem.ToleranceProblem.evaluate`), so the largest value on
a map may exceed the largest value over the allocation poses: that is a pose the allocation set
missed (``evotol run``'s ``[poses] refine`` adds such poses).

Poses out of reach or at a singularity (:class:`evotol.errors.KinematicsError`) are left out
(NaN in the map) and counted.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError, ValidationError
from evotol.core.problem import ToleranceProblem

#: grid points per axis of a slice
DEFAULT_N = 21
#: at most this many tries to drop unreachable poses before giving up on a slice
_MAX_RETRIES = 50


def slice_specs(workspace, anchor, n: int = DEFAULT_N) -> list[dict]:
    """The slices to draw: the first two coordinates (x, y of a planar or spatial mechanism) varied,
    the others held at ``anchor`` (SI); a 3-D workspace also gets the slices at the third
    coordinate's low and high ends; a 1-D workspace one line.

    Parameters
    ----------
    workspace : evotol.robots.base.Workspace
        The workspace box: ``low``, ``high`` (SI: m, rad) and ``dim``. Only coordinates with
        ``high > low`` are varied.
    anchor : array-like
        The pose (SI) that fixes the coordinates not varied, usually the worst allocation pose.
    n : int
        Grid points per varied axis (default ``DEFAULT_N`` = 21).

    Returns
    -------
    list of dict
        ``axes`` (indices varied), ``fixed`` (index -> SI value), ``grid`` ((m, dim) poses, SI),
        ``shape`` (rows, columns of the map), ``axis_values`` (each varied axis's ``n`` grid
        values, SI).

    Raises
    ------
    ValidationError
        No coordinate of the workspace has a range (``high > low``) to map.
    """
    anchor = np.asarray(anchor, dtype=float)
    lo, hi = np.asarray(workspace.low, float), np.asarray(workspace.high, float)
    varied = [i for i in range(workspace.dim) if hi[i] > lo[i]]
    if not varied:
        raise ValidationError("workspace", list(zip(lo, hi)), "a coordinate with a range to map")
    axes = varied[:2]
    others = [i for i in range(workspace.dim) if i not in axes]
    anchors = [anchor]
    if workspace.dim == 3 and others and others[0] in varied:
        k = others[0]
        values = [lo[k], anchor[k], hi[k]]
        if np.isclose(anchor[k], lo[k]) or np.isclose(anchor[k], hi[k]):
            values.insert(1, 0.5 * (lo[k] + hi[k]))          # an end anchor: the middle slice too
        values = sorted(v for i, v in enumerate(values) if not any(np.isclose(v, w) for w in values[:i]))
        anchors = [np.where(np.arange(3) == k, v, anchor) for v in values]
    specs = []
    for a in anchors:
        axis_values = [np.linspace(lo[i], hi[i], n) for i in axes]
        mesh = np.meshgrid(*axis_values[::-1], indexing="ij")[::-1]   # rows: second axis, columns: first
        grid = np.tile(a, (mesh[0].size, 1))
        for i, m in zip(axes, mesh):
            grid[:, i] = m.ravel()
        specs.append({"axes": axes, "fixed": {i: float(a[i]) for i in others}, "grid": grid,
                      "shape": mesh[0].shape, "axis_values": axis_values})
    return specs


def _reachable_problem(problem: ToleranceProblem, grid: np.ndarray):
    """``problem`` on the reachable poses of ``grid``; returns (problem or None, kept mask)."""
    keep = np.ones(len(grid), dtype=bool)
    for _ in range(_MAX_RETRIES):
        if not keep.any():
            return None, keep
        try:
            return problem.at_poses(grid[keep]), keep
        except KinematicsError as exc:
            bad = np.atleast_2d(np.asarray(getattr(exc, "poses", None) if getattr(exc, "poses", None) is not None
                                           else np.empty((0, grid.shape[1])), dtype=float))
            hit = np.zeros(len(grid), dtype=bool)
            for b in bad:
                hit |= np.all(np.isclose(grid, b, rtol=0, atol=1e-12), axis=1)
            if not (hit & keep).any():     # the error names no pose of ours: give up on the slice
                return None, np.zeros(len(grid), dtype=bool)
            keep &= ~hit
    return None, np.zeros(len(grid), dtype=bool)


def error_map_slices(problem: ToleranceProblem, T, anchor, n: int = DEFAULT_N) -> list[dict]:
    """Errors of designs ``T`` on the slices of :func:`slice_specs` under the problem's measure.

    Parameters
    ----------
    problem : ToleranceProblem
        The problem whose measure and robot are evaluated.
    T : array-like
        Designs, (n_designs, n_sources) SI tolerances (one evaluation for all of them).
    anchor : array-like
        Pose (SI) fixing the coordinates not varied.
    n : int
        Grid points per axis.

    Returns
    -------
    list of dict
        Per slice: ``x_name``/``y_name`` (varied coordinates; ``y_name`` None for a 1-D
        workspace), ``x``/``y`` (their grid values, SI), ``fixed`` (name -> SI value), ``values``
        (component -> (n_designs, rows, columns) nested lists of errors, m or rad, NaN where
        out of reach), ``unreachable`` (count).
    """
    T = np.atleast_2d(np.asarray(T, dtype=float))
    ws = problem.model.workspace
    out = []
    for spec in slice_specs(ws, anchor, n):
        sub, keep = _reachable_problem(problem, spec["grid"])
        values = {}
        for comp, _ in problem.components:
            full = np.full((len(T), len(spec["grid"])), np.nan)
            if sub is not None:
                full[:, keep] = getattr(sub.evaluate(T), comp)
            values[comp] = full.reshape((len(T), *spec["shape"])).tolist()
        ax = spec["axes"]
        out.append({"x_name": ws.names[ax[0]], "y_name": ws.names[ax[1]] if len(ax) > 1 else None,
                    "x": spec["axis_values"][0].tolist(),
                    "y": spec["axis_values"][1].tolist() if len(ax) > 1 else None,
                    "fixed": {ws.names[i]: v for i, v in spec["fixed"].items()}, "values": values,
                    "unreachable": int((~keep).sum())})
    return out

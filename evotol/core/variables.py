"""Tolerance variables of a problem (``docs/tolerances.md``): which sources an optimiser moves.

A free source carries one variable; a ``shared`` group (e.g. the three legs made from one
drawing) is one variable driving all its members (t_j = x_v for every member j; its range is the
intersection of the members' ranges); locked and fixed sources carry none. Cost is counted per
part (``shared_cost="part"``: every member pays its own cost model) or once per variable
(``"variable"``: only the group's first member).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from evotol.errors import ValidationError
from evotol._runtime.keyword_checks import did_you_mean
from evotol.robots.base import RobotErrorModel

#: how a shared tolerance is costed: every member part pays its own cost model ("part") or only
#: the group's first member ("variable"); the values ``shared_cost`` accepts
SHARED_COSTS = ("part", "variable")


@dataclass(frozen=True)
class ToleranceVariables:
    """The map from free variables to source tolerances.

    Built by :func:`tolerance_variables`.

    Parameters
    ----------
    shared : dict
        Group name -> tuple of member source names.
    shared_cost : {"part", "variable"}
        Cost counted per part (every member) or once per variable (the group's first member).
    lower, upper : ndarray, shape (n_sources,)
        Tolerance ranges (SI: m or rad) after the groups' intersections.
    leader : ndarray of int, shape (n_sources,)
        Index of the source whose variable drives each source (itself unless a follower).
    follower : ndarray of bool, shape (n_sources,)
        True for a group member other than the group's first.
    locked : ndarray of bool, shape (n_sources,)
        True for a locked or fixed source (no variable).
    free : ndarray of bool, shape (n_sources,)
        True where the source carries a variable (neither locked nor a follower).
    variable_matrix : ndarray, shape (n_sources, n_variables)
        0/1 map ``t = M x`` from the variables to the unlocked sources' tolerances (rows of locked
        sources are zero).
    variables : tuple of str
        Each variable's name (the group's or the source's).
    cost_weight : ndarray, shape (n_sources,)
        1 where a source's cost is counted, 0 for fixed sources (and followers under
        ``shared_cost="variable"``, and the members after the first of a drawing callout).
    tied : dict
        Callout name -> its member sources (the robot's ``tied_sources``, issue 35): one variable
        each, costed once whatever ``shared_cost``; not listed in ``shared``.
    """

    shared: dict
    shared_cost: str
    lower: np.ndarray
    upper: np.ndarray
    leader: np.ndarray
    follower: np.ndarray
    locked: np.ndarray
    free: np.ndarray
    variable_matrix: np.ndarray
    variables: tuple
    cost_weight: np.ndarray
    tied: dict = None


def tolerance_variables(robot, tolerances: Mapping, lower: np.ndarray, upper: np.ndarray,
                        locked_values: np.ndarray, shared, shared_cost: str) -> ToleranceVariables:
    """The variables of a problem's sources.

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        Its ``sources`` (names, units) in order.
    tolerances : mapping
        Source name -> :class:`evotol.Tolerance`, in the robot's source order.
    lower, upper : ndarray, shape (n_sources,)
        The tolerances' ranges (SI: m or rad).
    locked_values : ndarray, shape (n_sources,)
        The locked value of each source (SI), NaN if free.
    shared : mapping or None
        Group name -> member source names.
    shared_cost : str
        ``"part"`` or ``"variable"``.

    Returns
    -------
    ToleranceVariables
        The map from the free variables to the sources' tolerances.

    Raises
    ------
    ValidationError
        A bad ``shared_cost``; a group naming an unknown, locked or already grouped source, sources
        of different units or with disjoint ranges.
    """
    if shared_cost not in SHARED_COSTS:
        raise ValidationError("shared_cost", shared_cost, f"one of {SHARED_COSTS}")
    names = list(tolerances)
    n = len(names)
    lower, upper = lower.copy(), upper.copy()
    leader = np.arange(n)
    groups = {}
    if shared is not None and not isinstance(shared, Mapping):
        raise ValidationError("shared", shared, "a mapping group name -> list of source names")
    seen: dict[str, str] = {}
    index = {nm: j for j, nm in enumerate(names)}
    # a drawing callout's zone members (evotol.robots.mechanism.callouts.model): one tolerance, costed once
    tied = dict(robot.tied_sources) if isinstance(robot, RobotErrorModel) else {}
    for g, members in {**tied, **(shared or {})}.items():
        if g in tied and all(tolerances[m].locked is not None for m in members):
            continue                              # a locked callout: no variable, costed once below
        if isinstance(members, str) or not isinstance(members, Sequence) or len(members) == 0:
            raise ValidationError(f"shared.{g}", members, "a non-empty list of source names")
        for m in members:
            if m not in index:
                raise ValidationError(f"shared.{g}", m, f"a source of {robot.name}: {names}" + did_you_mean(str(m), names))
            if m in seen:
                raise ValidationError(f"shared.{g}", m, f"a source named in one shared group only, once "
                                      f"(already in {seen[m]!r})")
            seen[m] = g
            if tolerances[m].locked is not None:
                raise ValidationError(f"shared.{g}", m, "free sources only (this one is locked or fixed)")
        idx = [index[m] for m in members]
        units = {robot.sources[j].unit for j in idx}
        if len(units) > 1:
            raise ValidationError(f"shared.{g}", list(members), f"sources of one unit (got {sorted(units)})")
        lo, hi = lower[idx].max(), upper[idx].min()
        if lo > hi:
            raise ValidationError(f"shared.{g}", list(members), f"overlapping tolerance ranges (largest lower "
                                  f"{lo:g} > smallest upper {hi:g})")
        lower[idx], upper[idx] = lo, hi
        leader[idx] = idx[0]
        groups[str(g)] = tuple(members)
    follower = leader != np.arange(n)
    locked = ~np.isnan(locked_values)
    free = ~locked & ~follower
    fi = np.flatnonzero(free)
    M = np.zeros((n, fi.size))
    M[np.arange(n)[~locked], np.searchsorted(fi, leader[~locked])] = 1.0
    group_of = {index[m[0]]: g for g, m in groups.items()}
    w = np.ones(n)
    w[[j for j, nm in enumerate(names) if tolerances[nm].is_fixed]] = 0.0
    if shared_cost == "variable":
        w[follower] = 0.0
    w[[index[m] for ms in tied.values() for m in ms[1:]]] = 0.0
    return ToleranceVariables({g: m for g, m in groups.items() if g not in tied}, shared_cost, lower, upper, leader,
                              follower, locked, free, M, tuple(group_of.get(j, names[j]) for j in fi), w,
                              {g: tuple(m) for g, m in tied.items()})

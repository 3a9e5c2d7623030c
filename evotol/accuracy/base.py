"""The measure protocol and what a measure returns.

A *measure* judges designs against the requirement: ``measure.evaluate(problem, T, top_only)``
returns an :class:`Evaluation` of the designs ``T`` (n_designs, n_sources; SI) at every pose of
``problem`` (a :class:`evotol.problem.ToleranceProblem`). Measures are registered by name in
:mod:`evotol.accuracy.registry` (built-ins and the entry-point group ``evotol.measures``) and
proven by :mod:`evotol.accuracy_checks`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

#: the two error components of an end-effector (position m, orientation rad)
COMPONENTS = ("position", "orientation")

#: a :class:`evotol.problem.ToleranceProblem` (that module imports this one, so it is not imported here)
Problem = Any


@dataclass
class Evaluation:
    """Errors of designs at every pose under one measure."""

    position: np.ndarray | None      # (n_designs, n_poses) m
    orientation: np.ndarray | None   # (n_designs, n_poses) rad
    position_bound: np.ndarray | None = None     # certified upper bound (worst case)
    orientation_bound: np.ndarray | None = None
    position_contrib: np.ndarray | None = None   # (n_designs, n_poses, n_src) fractions
    orientation_contrib: np.ndarray | None = None
    position_direction: np.ndarray | None = None  # (n_designs, n_poses, 3) worst direction
    orientation_direction: np.ndarray | None = None
    violation: np.ndarray = field(default=None)   # (n_designs,) max normalised error − 1
    probability: np.ndarray | None = None         # yield measure: (n_designs, n_poses) lower bound of the yield
    exact: bool = True                            # yield measure: False when sources were moment-matched (CLT)


@dataclass(frozen=True)
class ComponentErrors:
    """One component's errors of designs at every pose (m for position, rad for orientation).

    value: (n_designs, n_poses) the measure's error; bound: a proven upper bound of it (None when
    the measure has none); contrib: (n_designs, n_poses, n_sources) each source's share;
    direction: (n_designs, n_poses, 3) the worst direction (unit vector), where the measure has one.
    """

    value: np.ndarray
    bound: np.ndarray | None = None
    contrib: np.ndarray | None = None
    direction: np.ndarray | None = None


def violation(problem: Problem, parts: Mapping[str, ComponentErrors]) -> np.ndarray:
    """(n_designs,) largest error over the poses and the constrained components, divided by its
    bound, minus 1 (<= 0: the design meets the requirement)."""
    n = next(iter(parts.values())).value.shape[0]
    out = np.full(n, -np.inf)
    for comp, lim in problem.components:
        out = np.maximum(out, np.max(parts[comp].value, axis=1) / lim - 1)
    return out


def evaluation_of(parts: Mapping[str, ComponentErrors], violation: np.ndarray, **extra) -> Evaluation:
    """The :class:`Evaluation` holding ``parts`` (component -> errors; a missing component stays
    None), the ``violation`` and any further field (``probability``, ``exact``)."""
    pos, ori = parts.get("position"), parts.get("orientation")
    return Evaluation(
        position=None if pos is None else pos.value, orientation=None if ori is None else ori.value,
        position_bound=None if pos is None else pos.bound, orientation_bound=None if ori is None else ori.bound,
        position_contrib=None if pos is None else pos.contrib,
        orientation_contrib=None if ori is None else ori.contrib,
        position_direction=None if pos is None else pos.direction,
        orientation_direction=None if ori is None else ori.direction,
        violation=violation, **extra)


class Measure:
    """An accuracy measure (the protocol; subclass it or follow it).

    Attributes
    ----------
    name : str
        The name a :class:`evotol.Requirement` selects it by (``measure="..."``).
    clearances : bool
        True if it also evaluates problems with allocated joint clearances
        (``ToleranceProblem(..., clearances=)``); otherwise such a problem refuses it.
    brute_force_rtol, brute_force_atol : float
        How close :meth:`evaluate` must come to :meth:`brute_force` in the conformance check.
    monotone_rtol : float
        The relative decrease of an error the conformance check tolerates when a tolerance
        grows (0 up to rounding for an exact measure; a sampled estimate may say how much noise).
    """

    name: str = ""
    clearances: bool = False
    brute_force_rtol: float = 1e-9
    brute_force_atol: float = 0.0
    monotone_rtol: float = 1e-9

    def evaluate(self, problem: Problem, T: np.ndarray, top_only: bool = False) -> Evaluation:
        """Errors of designs at every pose of ``problem``.

        Parameters
        ----------
        problem : evotol.problem.ToleranceProblem
            The problem (robot sensitivities, tolerances, requirement, poses).
        T : ndarray, shape (n_designs, n_sources)
            Source tolerances (SI: m or rad), already validated.
        top_only : bool
            The value needs to be exact only at the poses that can hold the largest error
            (enough for feasibility); a measure may ignore it.

        Returns
        -------
        Evaluation
            ``position`` (m) / ``orientation`` (rad) errors (n_designs, n_poses) and the
            ``violation`` (n_designs,) of the requirement's bounds.
        """
        raise NotImplementedError

    def brute_force(self, problem: Problem, t: np.ndarray) -> dict[str, np.ndarray]:
        """A slow, independent computation of one design ``t`` (n_sources,) on a small problem
        (conformance check): Evaluation field name -> (n_poses,) values. Optional."""
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"<measure {self.name!r}>"

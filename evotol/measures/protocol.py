"""The measure protocol and what a measure returns.

A *measure* judges designs against the requirement: ``measure.evaluate(problem, T, top_only)``
returns an :class:`Evaluation` of the designs ``T`` (n_designs, n_sources; SI) at every pose of
``problem`` (a :class:`evotol.core.problem.ToleranceProblem`). Measures are registered by name in
:mod:`evotol.measures.registry` (built-ins and the entry-point group ``evotol.measures``) and
proven by :mod:`evotol.core.measure_checks`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

#: the two error components of an end-effector (position m, orientation rad)
COMPONENTS = ("position", "orientation")

#: a :class:`evotol.core.problem.ToleranceProblem` (that module imports this one, so it is not imported here)
Problem = Any


@dataclass
class Evaluation:
    """Errors of designs at every pose under one measure.

    A measure leaves the fields it does not compute None.

    Parameters
    ----------
    position : ndarray, shape (n_designs, n_poses), or None
        The measure's position error (m).
    orientation : ndarray, shape (n_designs, n_poses), or None
        The measure's orientation error (rad).
    position_bound : ndarray, shape (n_designs, n_poses), optional
        A proven upper bound of ``position`` (m), e.g. the worst case's certified bound.
    orientation_bound : ndarray, shape (n_designs, n_poses), optional
        A proven upper bound of ``orientation`` (rad).
    position_contrib : ndarray, shape (n_designs, n_poses, n_sources), optional
        Each source's share of the position error (dimensionless fraction).
    orientation_contrib : ndarray, shape (n_designs, n_poses, n_sources), optional
        Each source's share of the orientation error (dimensionless fraction).
    position_direction : ndarray, shape (n_designs, n_poses, 3), optional
        Worst position-error direction (unit vector).
    orientation_direction : ndarray, shape (n_designs, n_poses, 3), optional
        Worst orientation-error direction (unit vector).
    violation : ndarray, shape (n_designs,)
        Largest error / bound − 1 over the poses and constrained components (dimensionless;
        <= 0: the design meets the requirement).
    probability : ndarray, shape (n_designs, n_poses), optional
        ``yield`` measure: a lower bound of the yield at each pose (dimensionless, 0 to 1).
    exact : bool
        ``yield`` measure: False when sources were moment-matched (central limit theorem).

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> ev = problem.evaluate([[1e-5, 1e-5, 1e-5], [4e-5, 1e-5, 1e-5]])
    >>> ev.position.shape                                      # (n_designs, n_poses)
    (2, 1)
    >>> [round(float(v), 12) for v in ev.violation]            # <= 0: meets the requirement
    [-0.65, -0.35]
    """

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

    Parameters
    ----------
    value : ndarray, shape (n_designs, n_poses)
        The measure's error (m or rad).
    bound : ndarray, shape (n_designs, n_poses), optional
        A proven upper bound of ``value`` (None when the measure has none).
    contrib : ndarray, shape (n_designs, n_poses, n_sources), optional
        Each source's share (dimensionless fraction).
    direction : ndarray, shape (n_designs, n_poses, 3), optional
        The worst direction (unit vector), where the measure has one.
    """

    value: np.ndarray
    bound: np.ndarray | None = None
    contrib: np.ndarray | None = None
    direction: np.ndarray | None = None


def violation(problem: Problem, parts: Mapping[str, ComponentErrors]) -> np.ndarray:
    """(n_designs,) largest error over the poses and the constrained components, divided by its
    bound, minus 1 (<= 0: the design meets the requirement).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        Supplies the constrained components and their bounds (``problem.components``).
    parts : Mapping[str, ComponentErrors]
        Component name -> errors; must hold every constrained component.

    Returns
    -------
    ndarray, shape (n_designs,)
        ``max(value / bound) − 1`` (dimensionless).
    """
    n = next(iter(parts.values())).value.shape[0]
    out = np.full(n, -np.inf)
    for comp, lim in problem.components:
        out = np.maximum(out, np.max(parts[comp].value, axis=1) / lim - 1)
    return out


def evaluation_of(parts: Mapping[str, ComponentErrors], violation: np.ndarray, **extra) -> Evaluation:
    """The :class:`Evaluation` holding ``parts`` (component -> errors; a missing component stays
    None), the ``violation`` and any further field (``probability``, ``exact``).

    Parameters
    ----------
    parts : Mapping[str, ComponentErrors]
        ``"position"`` and/or ``"orientation"`` -> errors (m, rad).
    violation : ndarray, shape (n_designs,)
        As :func:`violation` returns (dimensionless).
    **extra
        Further :class:`Evaluation` fields (``probability``, ``exact``).

    Returns
    -------
    Evaluation
        The fields of ``parts`` spread over ``position*`` / ``orientation*``.
    """
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
        problem : evotol.core.problem.ToleranceProblem
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

        Raises
        ------
        NotImplementedError
            Always, in the protocol class: a measure overrides it.
        """
        raise NotImplementedError

    def brute_force(self, problem: Problem, t: np.ndarray) -> dict[str, np.ndarray]:
        """A slow, independent computation of one design ``t`` (n_sources,) on a small problem
        (conformance check): Evaluation field name -> (n_poses,) values. Optional.

        Parameters
        ----------
        problem : evotol.core.problem.ToleranceProblem
            A small problem (few sources and poses).
        t : ndarray, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        dict of str to ndarray, shape (n_poses,)
            :class:`Evaluation` field name (e.g. ``"position"`` in m, ``"orientation"`` in rad,
            ``"probability"``) -> values per pose.

        Raises
        ------
        NotImplementedError
            Always, in the protocol class: a measure without a brute force (the conformance
            check then skips that comparison).
        """
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"<measure {self.name!r}>"

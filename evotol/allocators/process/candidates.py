"""The candidate processes of a source: :class:`Process` and the checks of a source's list of them
(conventions: :mod:`evotol.allocators.process`; Chase, Greenwood, Loosli & Hauglund 1990).

A process is a cost model ``c_p(t)``, the tolerance range ``[lo_p, hi_p]`` it holds and an optional
set-up cost ``F_p``. :func:`checked_processes` refuses what :class:`ProcessProblem
<evotol.allocators.process.problem.ProcessProblem>` cannot use, including a process that another
one of the same source covers and undercuts everywhere (``_dominated``: it can never be chosen,
usually a unit slip in a cost curve).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from evotol.cost_models.base import CostModel
from evotol.errors import ValidationError
from evotol.core.problem import Tolerance
from evotol.robots.base import RobotErrorModel


@dataclass(frozen=True)
class Process:
    """One candidate manufacturing process of a source.

    Parameters
    ----------
    name : str
        E.g. ``"turn"``, ``"grind"``.
    cost : evotol.cost_models.CostModel
        Cost model of the tolerance (SI t), valid (positive, non-increasing) on the range.
    lower, upper : float
        Tolerances this process holds (SI: m or rad), 0 < lower <= upper.
    fixed_cost : float
        Set-up cost added when the process is chosen (cost units, >= 0).

    Notes
    -----
    A plain value: :class:`ProcessProblem` checks it and raises
    :class:`evotol.errors.ValidationError` naming the source and the process.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import Process
    >>> grind = Process("grinding", PowerCost(3.0, 1.0, scale=1e-3), lower=2e-6, upper=2e-5)
    >>> grind.name, grind.lower, grind.upper                   # tolerance range (m)
    ('grinding', 2e-06, 2e-05)
    """

    name: str
    cost: CostModel
    lower: float
    upper: float
    fixed_cost: float = 0.0

    def total(self, t) -> np.ndarray:
        """Cost of the process at tolerance t: set-up cost + the cost model.

        Parameters
        ----------
        t : float or array_like
            Tolerance(s) (m or rad).

        Returns
        -------
        numpy.ndarray
            ``fixed_cost + cost.cost(t)`` (cost units), shaped like t.
        """
        return self.fixed_cost + self.cost.cost(t)


def _dominated(a: Process, b: Process, n: int = 33) -> bool:
    """True when b covers a's range and is cheaper everywhere on it (a can never be chosen)."""
    if not (b.lower <= a.lower and b.upper >= a.upper):
        return False
    t = np.geomspace(a.lower, a.upper, n)
    return bool(np.all(b.total(t) < a.total(t)))


def checked_processes(robot: RobotErrorModel, processes: Mapping[str, Sequence[Process]], *,
                      check_dominance: bool = True) -> dict[str, tuple[Process, ...]]:
    """Every source's candidate processes, checked (what :class:`ProcessProblem
    <evotol.allocators.process.problem.ProcessProblem>` refuses).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The error model whose sources need processes.
    processes : Mapping[str, Sequence[Process]]
        Source name -> non-empty list of :class:`Process`.
    check_dominance : bool
        Refuse a process that another one of the same source covers and undercuts everywhere
        (usually a unit slip in a cost curve).

    Returns
    -------
    dict of str to tuple of Process
        Source name -> its processes, in the robot's source order.

    Raises
    ------
    evotol.errors.ValidationError
        A source without processes or a process for no source, a process that is not a
        :class:`Process`, duplicate process names, a negative or non-finite ``fixed_cost``, a cost
        model invalid on its range, or a dominated process.
    """
    if not isinstance(processes, Mapping):
        raise ValidationError("processes", processes, "a mapping source name -> list of Process")
    names = robot.source_names
    missing = [n for n in names if n not in processes]
    if missing:
        raise ValidationError("processes", sorted(processes), f"a process list for every source of {robot.name}; missing {missing}")
    extra = [n for n in processes if n not in names]
    if extra:
        raise ValidationError(f"processes[{extra[0]!r}]", extra[0], f"a source of {robot.name}: {list(names)}")
    out: dict[str, tuple[Process, ...]] = {}
    for n in names:
        plist = processes[n]
        if isinstance(plist, Process) or not isinstance(plist, Sequence) or len(plist) == 0:
            raise ValidationError(f"processes[{n!r}]", plist, "a non-empty list of Process (at least one way to make it)")
        seen = set()
        for p in plist:
            if not isinstance(p, Process):
                raise ValidationError(f"processes[{n!r}] entry", p, "an evotol.allocators.process.Process")
            field_ = f"processes[{n!r}][{p.name!r}]"
            if p.name in seen:
                raise ValidationError(f"processes[{n!r}] name", p.name, "unique process names per source")
            seen.add(p.name)
            if not isinstance(p.fixed_cost, (int, float, np.floating)) or not np.isfinite(p.fixed_cost) or p.fixed_cost < 0:
                raise ValidationError(f"{field_}.fixed_cost", p.fixed_cost, "a finite cost >= 0")
            try:
                Tolerance(p.cost, p.lower, p.upper).validate(n)
            except ValidationError as exc:
                raise ValidationError(f"{field_}: {exc.field}", exc.value, exc.expected) from None
        if check_dominance:
            for a, b in itertools.permutations(plist, 2):
                if _dominated(a, b):
                    t = np.sqrt(a.lower * a.upper)
                    raise ValidationError(
                        f"processes[{n!r}][{a.name!r}]", f"cost {float(a.total(t)):.4g} at t = {t:.3g}",
                        f"a process that can be the cheapest somewhere: {b.name!r} covers its range "
                        f"[{a.lower:.3g}, {a.upper:.3g}] and costs less everywhere on it (here {float(b.total(t)):.4g}); "
                        "check the units of the cost curves, or pass check_dominance=False")
        out[n] = tuple(plist)
    return out

"""Pareto fronts: the one front type and the one knee definition used by every NSGA-II front in evotol.

The parameters several definitions of this module share are described once, here.

Parameters
----------
F : array_like, (n, m)
    Objective values of the n front members (any units; all minimised).
log : sequence of bool, optional
    Per objective, whether it is taken as log10 before normalising. Default: none.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
import pandas as pd

from evotol.errors import ValidationError


def _normalised(F: np.ndarray, log: Sequence[bool] | None) -> np.ndarray:
    """Every objective scaled to [0, 1] over the front, after log10 where ``log``."""
    G = np.asarray(F, dtype=float).copy()
    for j, lg in enumerate(log or [False] * G.shape[1]):
        if lg:
            G[:, j] = np.log10(np.maximum(G[:, j], 1e-300))
    span = G.max(0) - G.min(0)
    return (G - G.min(0)) / np.where(span > 0, span, 1.0)


def ideal_point_knee(F: np.ndarray, log: Sequence[bool] | None = None) -> int:
    """Index of the knee of a Pareto front ``F`` (n, m), all objectives minimised: the point
    nearest (Euclidean) to the ideal point after normalising every objective to [0, 1] over the
    front (log10 first where ``log``). On the front ``y = 1/x`` in log-log axes it is ``x = 1``.

    Returns
    -------
    int
        Row index (0-based) of the knee in ``F``.

    Raises
    ------
    ValidationError
        If ``F`` is not a non-empty 2-D array.
    """
    F = np.asarray(F, dtype=float)
    if F.ndim != 2 or len(F) == 0:
        raise ValidationError("Pareto front F", F.shape, "a non-empty (n, m) array")
    return int(np.argmin(np.linalg.norm(_normalised(F, log), axis=1)))


def knee_points(F: np.ndarray, log: Sequence[bool] | None = None) -> np.ndarray:
    """Indices of the knee points of a Pareto front ``F`` (n, m), all objectives minimised.

    Both marks of the one knee definition, deduplicated: :func:`ideal_point_knee` and the high
    trade-off points of pymoo's ``HighTradeoffPoints`` (Rachmawati & Srinivasan 2009) on the same
    normalised front.

    Returns
    -------
    numpy.ndarray of int
        Sorted row indices of the knee points in ``F``; empty if ``F`` is empty or not 2-D. The
        high trade-off points are added only for ``n >= 4`` and skipped on a degenerate front.
    """
    F = np.asarray(F, dtype=float)
    if F.ndim != 2 or len(F) == 0:
        return np.zeros(0, dtype=int)
    N = _normalised(F, log)
    knees = {int(np.argmin(np.linalg.norm(N, axis=1)))}
    if len(F) >= 4:
        try:
            from pymoo.mcdm.high_tradeoff import HighTradeoffPoints

            ht = HighTradeoffPoints().do(N)
            if ht is not None:
                knees.update(int(i) for i in np.atleast_1d(ht))
        except (ValueError, IndexError, np.linalg.LinAlgError):   # degenerate fronts
            pass
    return np.array(sorted(knees), dtype=int)


def non_dominated(F: np.ndarray) -> np.ndarray:
    """Indices of the non-dominated rows of ``F`` (n, m), all objectives minimised (pymoo's sort).

    Parameters
    ----------
    F : array_like, (n, m)
        Objective values of n points (any units; all minimised).

    Returns
    -------
    numpy.ndarray of int
        Row indices of the points that no other point dominates.
    """
    from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

    return NonDominatedSorting().do(np.asarray(F, dtype=float), only_non_dominated_front=True)


@dataclass
class ParetoFront:
    """Non-dominated designs sorted by cost: the one front type of evotol.

    ``table`` has a ``cost`` column, the second objective's column (``objective``; default
    ``normalised_error`` = max error / bound, <= 1 meets the requirement) and one column per design
    variable (SI tolerances; for process selection also the chosen process per source).
    :func:`evotol.allocators.allocate_nsga2` and
    :func:`evotol.allocators.process.process_front` return it.

    Parameters
    ----------
    table : pandas.DataFrame
        One row per front member, sorted by cost.
    seconds : float
        Wall time of the run that produced the front (s).
    history : pandas.DataFrame or None
        Per generation statistics, when the run recorded them.
    objective : str
        Column of the second (minimised) objective.
    limit : float
        A member is feasible when ``table[objective] <= limit × (1 + rtol)`` (1 for a normalised
        error; the allowed miss probability for a yield front).
    rtol : float
        Relative tolerance of that test (``allocate_nsga2``: the rule of :mod:`evotol.measures.feasibility`,
        1e-6, on the proven bound; its ``proven_ratio`` column holds it for the members checked).
    objectives : tuple of (column, sense, log), optional
        Every objective of the front: sense +1 minimised, -1 maximised; ``log`` where the knee is
        read on a log scale. Default: ``cost`` and ``objective``, both minimised. The first one is
        what :meth:`cheapest_feasible` optimises (a design study's front, e.g. workspace area vs.
        p_max vs. r_max from :func:`evotol.design.nsga2`, has no cost: its "cheapest" is the best in
        its first objective).

    Raises
    ------
    ValidationError
        If ``table`` lacks a column of ``objectives``.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import allocate_nsga2
    >>> front = allocate_nsga2(problem, pop_size=20, n_gen=10, seed=0)
    >>> list(front.table.columns[:2])                          # one row per front member
    ['cost', 'normalised_error']
    >>> best = front.cheapest_feasible()                        # meets the requirement, cheapest
    >>> bool(best["normalised_error"] <= 1.0), bool(best["cost"] >= 97.42)   # optimum: 97.426
    (True, True)
    """

    table: pd.DataFrame
    seconds: float = 0.0
    history: pd.DataFrame | None = field(default=None, repr=False)
    objective: str = "normalised_error"
    limit: float = 1.0
    rtol: float = 1e-9
    objectives: tuple[tuple[str, int, bool], ...] | None = None

    def __post_init__(self):
        if self.objectives is None:     # a cost-vs-accuracy front: two minimised objectives
            self.objectives = (("cost", 1, False), (self.objective, 1, False))
        missing = [c for c, _, _ in self.objectives if c not in self.table.columns]
        if missing:
            raise ValidationError("ParetoFront.table", list(self.table.columns)[:8], f"the objective columns {missing}")

    def __repr__(self) -> str:
        """One line: the members, the objectives and their ranges (``table`` holds the designs)."""
        ranges = ", ".join(f"{c} {self.table[c].min():.4g} .. {self.table[c].max():.4g}" for c, _, _ in self.objectives)
        return f"ParetoFront({len(self.table)} members, {ranges}, seconds={self.seconds:.3g})"

    def to_frame(self) -> pd.DataFrame:
        """The front as a table, one row per member (a copy of ``table``: objectives, then each
        design's tolerances in SI).

        Returns
        -------
        pandas.DataFrame
            The members, sorted as the front is.
        """
        return self.table.copy()

    @property
    def cost(self) -> np.ndarray:
        """The first objective of every member (for a cost-vs-accuracy front: the cost, ascending)."""
        return self.table[self.objectives[0][0]].to_numpy()

    @property
    def error(self) -> np.ndarray:
        """The second objective of every member (``table[objective]``)."""
        return self.table[self.objective].to_numpy()

    def cheapest_feasible(self) -> pd.Series:
        """The cheapest member with ``objective <= limit × (1 + rtol)``.

        Returns
        -------
        pandas.Series
            That row of ``table`` (best in the first of ``objectives``: least cost, or greatest
            if that objective is maximised).

        Raises
        ------
        ValidationError
            When no member meets the limit.
        """
        ok = self.table[self.table[self.objective] <= self.limit * (1 + self.rtol)]
        if ok.empty:
            raise ValidationError("Pareto front", "no design", f"a design with {self.objective} <= {self.limit:g}")
        first, sense, _ = self.objectives[0]
        return ok.loc[ok[first].idxmin() if sense > 0 else ok[first].idxmax()]

    def _minimised(self) -> np.ndarray:
        return np.column_stack([sense * self.table[c].to_numpy(dtype=float) for c, sense, _ in self.objectives])

    def knee(self) -> int:
        """Row of the knee (:func:`ideal_point_knee`: nearest to the ideal point with every
        objective scaled to [0, 1] over the front, log10 first where an objective says so).

        Returns
        -------
        int
            Positional row index (for ``table.iloc``) of the knee.

        Raises
        ------
        ValidationError
            If the front is empty.
        """
        return ideal_point_knee(self._minimised(), [lg and sense > 0 for _, sense, lg in self.objectives])

    def knees(self) -> pd.DataFrame:
        """Every knee point (:func:`knee_points`: the ideal-point knee and pymoo's high trade-off
        points), as rows of the table.

        Returns
        -------
        pandas.DataFrame
            The knee rows of ``table`` (empty for an empty front).
        """
        return self.table.iloc[knee_points(self._minimised(), [lg and sense > 0 for _, sense, lg in self.objectives])]

"""The accuracy requirement as explicit constraint rows, for optimisers.

Both measures are positively homogeneous and convex in the tolerances t:

* worst case: ``|error| <= E`` at pose p  ⇔  Σ_j t_j ‖B_jᵀu‖ / E <= 1 for every unit direction u,
  an infinite family of *linear* rows a·t <= 1 (one per pose and direction);
* RSS: Σ_j (s_pj / E)² t_j² <= 1, one *quadratic* row b·t² <= 1 per pose.

Worst-case rows are generated lazily (cutting planes): a working set starts from each pose's
worst grid direction at a few probe designs and grows whenever an exact evaluation
(:meth:`ToleranceProblem.evaluate`, refined direction) finds a row the set misses. The working set
gives a *lower* estimate of the violation, exact on the rows it holds; ``check`` makes it exact for
the designs it is given. Optimisers must judge their final answers with ``ToleranceProblem.evaluate``.

Asymmetric intervals (offsets, minus != plus; :mod:`evotol.measures.linear`): a worst-case row becomes
affine, a·t + a0 <= 1 with a0 = u·Σ_j B_j offset_j / E (``A0``); directions cover the full sphere.
RSS rows with a mean shift, ``|s_p(t)|/E + sqrt(b·t²) <= 1``, are not in ``B`` (they are not
quadratic): ``violation`` evaluates them exactly through the problem.
Rows are in *source* space (one coefficient per source); optimisers map them to the free
variables with :meth:`ToleranceProblem.to_variables` (shared tolerances).

The parameters several definitions of this module share are described once, here.

Parameters
----------
T : numpy.ndarray, (n_designs, n_sources) or (n_sources,)
    Tolerance designs in source space (m or rad).
"""
from __future__ import annotations

import numpy as np

from evotol.errors import ValidationError
from evotol.measures.linear.support_grid import support_grid, support_rows


class ConstraintRows:
    """The accuracy requirement of a ``worst_case`` or ``rss`` problem as a working set of convex
    rows in source space (module docstring): linear rows ``A t + A0 <= 1`` (worst case, grown
    lazily by :meth:`check`) and quadratic rows ``B t² <= 1`` (RSS, all of them).

    Parameters
    ----------
    problem : ToleranceProblem
        The problem; its requirement's measure must be ``worst_case`` or ``rss``.
    n_probe : int
        Number of random probe designs (log-uniform between the bounds; the geometric mean and
        the upper bounds are added) whose worst grid directions seed the worst-case working set.
    seed : int
        Seed of the probe designs.

    Raises
    ------
    evotol.errors.ValidationError
        If the problem's measure is neither ``worst_case`` nor ``rss``.
    """

    def __init__(self, problem: ToleranceProblem, n_probe: int = 16, seed: int = 0):
        self.problem = problem
        measure = problem.requirement.measure
        if measure not in ("worst_case", "rss"):
            raise ValidationError("requirement.measure", measure,
                                  "'worst_case' or 'rss' (the measures with convex constraint rows)")
        self.measure = measure
        n = problem.n_sources
        self.A = np.zeros((0, n))    # linear rows  a·t + a0 <= 1
        self.A0 = np.zeros(0)        # their constants (offsets of asymmetric intervals)
        self.B = np.zeros((0, n))    # quadratic rows b·t² <= 1
        self._keys: set = set()
        self.shifted_rss = measure == "rss" and problem.asymmetric
        if measure == "rss":
            rows = [(problem.sensitivities[c] / lim) ** 2 for c, lim in problem.components]
            self.B = np.unique(np.concatenate(rows, axis=0), axis=0)
        else:
            rng = np.random.default_rng(seed)
            lo, hi = np.log(problem.lower), np.log(problem.upper)
            probes = np.exp(rng.uniform(lo, hi, size=(n_probe, n)))
            probes = np.concatenate([probes, np.sqrt(problem.lower * problem.upper)[None], problem.upper[None]])
            probes = problem.full(probes[:, problem.free])
            for comp, lim in problem.components:
                for sl, coef in problem.coefficient_blocks(comp):      # one block, or blocks of poses (issue 43)
                    c, D = coef[0], coef[1]
                    const = coef[3] if len(coef) > 3 else None
                    grid = support_grid(coef, probes)                           # (n_probe, poses, directions)
                    k = np.argmax(grid, axis=2)                              # (n_probe, poses of the block)
                    flat = np.unique((np.arange(c.shape[0])[None, :] * D.shape[0] + k).ravel())
                    pp, dd = np.divmod(flat, D.shape[0])
                    first = sl.start or 0
                    self._add_linear(support_rows(c, pp, dd) / lim, [(comp, first + int(a), int(b)) for a, b in zip(pp, dd)],
                                     None if const is None else const[pp, dd] / lim)
            self.check(probes)
            self.prune(probes)

    # --- rows ------------------------------------------------------------------------------
    def _add_linear(self, rows: np.ndarray, keys, consts=None) -> int:
        new = [i for i, k in enumerate(keys) if k not in self._keys]
        if not new:
            return 0
        self._keys.update(keys[i] for i in new)
        self.A = np.concatenate([self.A, rows[new]], axis=0)
        self.A0 = np.concatenate([self.A0, np.zeros(len(new)) if consts is None else np.asarray(consts, float)[new]])
        return len(new)

    @property
    def n_rows(self) -> int:
        """Number of rows in the working set (linear + quadratic)."""
        return self.A.shape[0] + self.B.shape[0]

    def violation(self, T: np.ndarray) -> np.ndarray:
        """max over working rows of (row value − 1), per design (n_designs,). A lower estimate for
        the worst case until checked (:meth:`check`); exact for RSS.

        Returns
        -------
        numpy.ndarray
            (n_designs,) violation, dimensionless (normalised error − 1; <= 0 meets the rows).
            With a mean-shifted RSS requirement, the problem's exact RSS violation.
        """
        T = np.atleast_2d(T)
        v = np.full(T.shape[0], -np.inf)
        if self.A.shape[0]:
            M = T @ self.A.T
            if self.A0.any():                 # offsets (asymmetric intervals); otherwise adding zeros changes no bit
                M += self.A0                  # in place: a (designs x rows) temporary less (4 of a GA's 5 ms)
            v = np.maximum(v, np.max(M, axis=1) - 1)
        if self.shifted_rss:
            return self.problem.evaluate(T, "rss").violation
        if self.B.shape[0]:
            v = np.maximum(v, np.sqrt(np.max((T ** 2) @ self.B.T, axis=1)) - 1)
        return v

    def normalised_error(self, T: np.ndarray) -> np.ndarray:
        """max error / bound over poses and components (working rows).

        Returns
        -------
        numpy.ndarray
            (n_designs,) normalised error, dimensionless (<= 1 meets the rows).
        """
        return self.violation(T) + 1

    def check(self, T: np.ndarray) -> tuple[np.ndarray, int]:
        """Exact violation of designs T (refined worst directions); adds the rows it finds.
        Returns (violation (n_designs,), number of rows added).

        Returns
        -------
        violation : numpy.ndarray
            (n_designs,) exact violation (normalised error − 1, dimensionless) from
            :meth:`ToleranceProblem.evaluate`; for RSS, :meth:`violation`.
        added : int
            Number of linear rows added to the working set (0 for RSS).
        """
        T = np.atleast_2d(T)
        if self.measure == "rss":
            return self.violation(T), 0
        ev = self.problem.evaluate(T, "worst_case", top_only=True,             # the violation's components only
                                   components=[c for c, _ in self.problem.components])
        added = 0
        for comp, lim in self.problem.components:
            val = getattr(ev, comp)
            u = getattr(ev, f"{comp}_direction")
            p = np.argmax(val, axis=1)                       # worst pose per design
            for i, pi in enumerate(p):
                uu = u[i, pi]
                row, const = self.problem.support_row(comp, int(pi), uu)
                key = (comp, int(pi), tuple(np.round(uu, 9)))
                added += self._add_linear(row[None] / lim, [key], [const / lim])
        return ev.violation, added

    def prune(self, T: np.ndarray, keep_ratio: float = 0.8) -> int:
        """Drop linear rows below ``keep_ratio`` × the largest row value for every design in T.

        Safe: the working set only ever under-estimates the error, and ``check`` re-adds any
        row that becomes the maximum. Returns the number of rows dropped.

        Parameters
        ----------
        T : numpy.ndarray, (n_designs, n_sources) or (n_sources,)
            Designs (m or rad) at which the rows are compared; a row is kept if it reaches the
            threshold for at least one design.
        keep_ratio : float
            Threshold as a fraction of each design's largest row value (dimensionless).

        Returns
        -------
        int
            Number of linear rows dropped.
        """
        if self.A.shape[0] == 0:
            return 0
        V = np.atleast_2d(T) @ self.A.T + self.A0
        keep = np.any(V >= keep_ratio * V.max(axis=1, keepdims=True), axis=0)
        dropped = int((~keep).sum())
        if dropped:
            self.A = self.A[keep]
            self.A0 = self.A0[keep]
            self._keys = set()  # keys no longer match rows; duplicates are harmless
        return dropped

    # --- helpers for optimisers --------------------------------------------------------------
    def scale_to_boundary(self, T: np.ndarray, iters: int = 40) -> np.ndarray:
        """Scale each design's free tolerances by one factor so it meets the working rows with
        equality (within bounds), by bisection on the factor; locked tolerances are kept (the
        error is nondecreasing in the factor, offsets included, so bisection is exact).

        Parameters
        ----------
        T : numpy.ndarray, (n_designs, n_sources) or (n_sources,)
            Designs in source space (m or rad).
        iters : int
            Bisection steps on the factor (after doubling it until infeasible, at most 30 times).

        Returns
        -------
        numpy.ndarray
            (n_designs, n_sources) scaled designs (m or rad), clipped to the bounds; feasible on
            the working rows (the factor's lower end). A design infeasible even at the lower
            bounds comes back at them.
        """
        p = self.problem
        T = np.atleast_2d(np.array(T, dtype=float))
        free = p.free
        lo_f = np.zeros(T.shape[0])
        hi_f = np.full(T.shape[0], 1.0)
        # grow hi until infeasible or upper bounds reached
        for _ in range(30):
            Th = p.full(np.clip(T[:, free] * hi_f[:, None], p.lower[free], p.upper[free]))
            feas = self.violation(Th) <= 0
            at_top = np.all(Th[:, free] >= p.upper[free], axis=1)
            grow = feas & ~at_top
            if not grow.any():
                break
            lo_f = np.where(grow, hi_f, lo_f)
            hi_f = np.where(grow, hi_f * 2, hi_f)
        for _ in range(iters):
            mid = 0.5 * (lo_f + hi_f)
            Tm = p.full(np.clip(T[:, free] * mid[:, None], p.lower[free], p.upper[free]))
            feas = self.violation(Tm) <= 0
            lo_f = np.where(feas, mid, lo_f)
            hi_f = np.where(feas, hi_f, mid)
        return p.full(np.clip(T[:, free] * lo_f[:, None], p.lower[free], p.upper[free]))


class ExactRows(ConstraintRows):
    """The requirement judged by the problem's exact measure, with no rows: the interface of
    :class:`ConstraintRows` for a measure that has no convex rows -- the certified worst case of
    clearance sources (:mod:`evotol.measures.clearances`), which is not convex in the tolerances.
    ``violation`` is exact (one engine evaluation per call); ``check`` adds nothing.

    Parameters
    ----------
    problem : ToleranceProblem
        The problem, judged by its own measure (:meth:`ToleranceProblem.evaluate`).
    """

    def __init__(self, problem: ToleranceProblem):
        self.problem = problem
        self.measure = "exact"
        n = problem.n_sources
        self.A, self.A0, self.B = np.zeros((0, n)), np.zeros(0), np.zeros((0, n))
        self._keys = set()
        self.shifted_rss = False

    def violation(self, T: np.ndarray) -> np.ndarray:
        """Exact violation of designs T by the problem's measure (no working rows)."""
        return self.problem.evaluate(np.atleast_2d(T), top_only=True).violation

    def check(self, T: np.ndarray) -> tuple[np.ndarray, int]:
        """Exact violation of designs T, as :meth:`violation`; no rows to add (``added`` is always 0)."""
        return self.violation(T), 0

    def prune(self, T: np.ndarray, keep_ratio: float = 0.8) -> int:
        """Nothing to drop (no rows): ignores its arguments and returns 0."""
        return 0

    def boundary_scale(self, T: np.ndarray, iters: int = 4, rtol: float = 1e-6) -> np.ndarray:
        """Designs scaled onto the requirement's boundary: t <- clip(t / error) on the free
        tolerances (exact when the measure is positively homogeneous and no bound clips; the
        engine's attained value is homogeneous to its certificate gap), then shrunk by
        (1 - rtol) / error until none is outside. A few exact evaluations per call.

        Parameters
        ----------
        T : numpy.ndarray, (n_designs, n_sources) or (n_sources,)
            Designs in source space (m or rad).
        iters : int
            Rescaling passes onto the boundary (``|error − 1| > rtol`` moves); then up to 8
            shrinking passes for designs still outside.
        rtol : float
            Relative tolerance on the normalised error (dimensionless).

        Returns
        -------
        numpy.ndarray
            (n_designs, n_sources) scaled designs (m or rad), clipped to the bounds; a design
            that a bound stops may remain outside.
        """
        p = self.problem
        f = p.free
        T = np.atleast_2d(np.array(T, dtype=float))
        active = np.arange(T.shape[0])
        for it in range(iters + 8):
            if active.size == 0:
                break
            ne = self.normalised_error(T[active])
            shrink = (1 - rtol) if it >= iters else 1.0
            move = (ne > 1) if it >= iters else (np.abs(ne - 1) > rtol)
            Tn = p.full(np.clip(T[active][:, f] * (shrink / ne[:, None]), p.lower[f], p.upper[f]))
            moved = np.any(np.abs(Tn - T[active]) > 1e-12 * np.abs(T[active]), axis=1)
            T[active[move]] = Tn[move]
            active = active[move & moved]
        return T


def constraint_rows(problem: ToleranceProblem, seed: int = 0) -> ConstraintRows | None:
    """The requirement as optimisers use it: lazy convex rows for ``worst_case`` / ``rss``,
    :class:`ExactRows` for clearance sources, None for the sampled measures.

    Parameters
    ----------
    problem : ToleranceProblem
        The problem.
    seed : int
        Seed of the probe designs of :class:`ConstraintRows`.

    Returns
    -------
    ConstraintRows, ExactRows or None
        The rows, or None when the measure has none (Monte Carlo, yield, ...).
    """
    if problem.clearances is not None:
        return ExactRows(problem)
    if problem.requirement.measure in ("worst_case", "rss"):
        return ConstraintRows(problem, seed=seed)
    return None

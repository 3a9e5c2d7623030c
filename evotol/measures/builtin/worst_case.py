"""The ``worst_case`` measure: the largest error of the linear model over every error inside the
tolerances, exact up to the proven bound (:func:`evotol.measures.linear.worst_case`, support function
over a direction grid); with allocated joint clearances, the certified engine's worst case of the
geometric intervals plus the clearances (:func:`evotol.measures.clearances.worst_case`)."""
from __future__ import annotations

import itertools

import numpy as np

from evotol.measures import clearances as clearance_measure

from evotol.measures import linear as measures
from evotol.measures.protocol import COMPONENTS, ComponentErrors, Evaluation, Measure, evaluation_of, violation
from evotol.errors import ValidationError


class WorstCaseMeasure(Measure):
    """Worst-case position (m) and orientation (rad) error at every pose (``docs/tolerances.md``)."""

    name = "worst_case"
    clearances = True

    def evaluate(self, problem, T: np.ndarray, top_only: bool = False, components=None) -> Evaluation:
        """Attained worst case (``position`` / ``orientation``), proven bound (``*_bound``), worst
        direction (``*_direction``) and each source's share (``*_contrib``), per component.

        ``top_only`` refines only the poses that can hold the largest error (others keep a lower grid
        estimate); it is not used with clearance sources.

        Parameters
        ----------
        components : sequence of str, optional
            The components computed (default both), the others left None. They must hold the
            requirement's constrained ones, which the violation reads: a feasibility check of a
            position requirement need not compute the orientation (half of a GA's checks). With
            clearance sources the engine computes the constrained components, as without it.

        Raises
        ------
        evotol.errors.ValidationError
            Clearance sources next to intervals that are not centred ±t; ``components`` without a
            constrained component, or with one that is not ``position``/``orientation``.
        """
        if components is None:
            components = COMPONENTS
        missing = [c for c, _ in problem.components if c not in components]
        if missing or any(c not in COMPONENTS for c in components):
            raise ValidationError("components", list(components), f"a subset of {list(COMPONENTS)} holding the "
                                  f"constrained {[c for c, _ in problem.components]}")
        if problem.clearances is not None:
            return self._with_clearances(problem, T)
        shape = None if problem.shape.plain else problem.shape
        parts = {}
        for comp in components:
            wc = measures.worst_case_by_blocks(problem.blocks[comp], T, problem.coefficient_blocks(comp),
                                               top_only=top_only, shape=shape)
            parts[comp] = ComponentErrors(wc.value, wc.bound, wc.contributions, wc.direction)
        return evaluation_of(parts, violation(problem, parts))

    @staticmethod
    def _with_clearances(problem, T: np.ndarray) -> Evaluation:
        """The certified worst case of geometric intervals + clearance classes (engine)."""
        if not problem.shape.plain:
            raise ValidationError("tolerances", "offset/minus/plus", "centred intervals ±t next to clearance sources")
        comps = [c for c, _ in problem.components]
        wc = clearance_measure.worst_case(problem.error_model, problem.poses, problem.jacobian, T, comps)
        parts = {c: ComponentErrors(wc.value[c], wc.bound[c], wc.contrib[c], wc.direction[c]) for c in comps}
        return evaluation_of(parts, violation(problem, parts))

    def brute_force(self, problem, t: np.ndarray) -> dict[str, np.ndarray]:
        """The largest error norm over every vertex of the box of interval ends (exact for a problem of
        interval sources only: the norm is convex, its maximum sits at a vertex); returns
        ``"position"`` (m) and ``"orientation"`` (rad) worst case per pose.

        Raises
        ------
        evotol.errors.ValidationError
            A source that is not an interval (1-D), or a problem with clearance sources.
        """
        if any(s.dim != 1 for s in problem.error_model.sources) or problem.clearances is not None:
            raise ValidationError("problem", problem.error_model.name, "interval (1-D) sources only for the vertex search")
        ends = problem.intervals(t)                          # (n_sources, 2)
        out = {}
        for comp in COMPONENTS:
            B = np.concatenate(problem.blocks[comp], axis=2)   # (n_poses, 3, n_sources)
            best = np.zeros(problem.n_poses)
            for signs in itertools.product((0, 1), repeat=problem.n_sources):
                e = ends[np.arange(problem.n_sources), signs]
                best = np.maximum(best, np.linalg.norm(B @ e, axis=1))
            out[comp] = best
        return out


WORST_CASE = WorstCaseMeasure()

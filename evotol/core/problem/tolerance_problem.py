"""The tolerance-allocation problem: named error sources with tolerances (:mod:`evotol.core.tolerance`),
an accuracy requirement (:mod:`evotol.core.requirement`) over a set of workspace poses, and a robot
error model that maps source errors to end-effector errors.

Design variables are the tolerances t_j (SI units: m or rad; the bound on the norm of source j's
error vector). The problem is a small, printable value plus cached arrays; every evaluation is
vectorised over a population of designs ``T`` of shape (n_designs, n_sources) and done by a
registered measure (:mod:`evotol.measures`).

Tolerance variables (:mod:`evotol.core.variables`, ``docs/tolerances.md``). The optimisers search the
*free variables* X (n_designs, n_variables): one per free source, a ``shared`` group being one
variable for all its members. :meth:`~evotol.core.problem.tolerance_problem.ToleranceProblem.full`
maps X to source tolerances T, inserting locked and fixed sources; ``problem.free`` marks the
sources that carry a variable.

This module holds the problem's construction and validation, its basic properties, the
worst-case support coefficients and the evaluation under a measure; the class takes its derived
copies (:mod:`evotol.core.problem.derived`), variable mapping (:mod:`evotol.core.problem.variable_mapping`)
and costs (:mod:`evotol.core.problem.costs`) from the mixins defined there.
"""
from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from evotol.measures import clearances as clearance_measure

from evotol.measures.statistical import distributions

from evotol.measures import linear as measures

from evotol.core import plausibility
from evotol.measures import registry as measure_registry
from evotol.measures.protocol import Evaluation
from evotol.measures.builtin.statistical_yield import first_order_yield
from evotol.errors import InfeasibleError, ValidationError
from evotol._runtime.keyword_checks import did_you_mean
from evotol.units.display import error_unit
from evotol.core.problem.costs import ProblemCosts
from evotol.core.problem.derived import DerivedProblems
from evotol.core.problem.variable_mapping import VariableMapping
from evotol.core.requirement import Requirement
from evotol.core.tolerance import Tolerance
from evotol.core.variables import tolerance_variables
from evotol.robots.base import RobotErrorModel

#: bytes of one component's support coefficients kept for every pose; above it they are computed by blocks of
#: poses (a quarter of it each) when used and not kept (:meth:`ToleranceProblem.coefficient_blocks`, issue 43)
COEFFICIENT_CACHE_BYTES = 2 ** 30

__all__ = ["ToleranceProblem"]


class ToleranceProblem(DerivedProblems, VariableMapping, ProblemCosts):
    """Tolerance allocation over a robot's workspace (see module docstring).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The error model (sources, sensitivities at poses).
    tolerances : Mapping[str, Tolerance]
        Source name -> :class:`Tolerance`, one entry per robot source.
    requirement : Requirement
        The accuracy to hold at every pose.
    poses : array_like, shape (n_poses, workspace.dim)
        Workspace poses (SI units: m, rad), at least one.
    n_directions : int
        Hemisphere directions for the worst-case measure (more: tighter bound).
    shared : Mapping[str, Sequence[str]] or None
        Group name -> member source names; each group is one tolerance variable.
    shared_cost : {"part", "variable"}
    all_given : bool
        Accept a problem whose every tolerance is fixed or locked: nothing to allocate, only to
        analyse (:mod:`evotol.verification.tolerance_analysis`); default False (such a problem is an error).
        ``"part"`` (default: cost counted for every member) or ``"variable"`` (once).
    clearances : evotol.measures.clearances.ClearanceSources or None
        Joint-clearance classes allocated with the robot's (interval) sources; their names follow
        the robot's source names, and the ``worst_case`` measure is then the certified engine's
        (:func:`evotol.measures.clearances.worst_case`). With tolerances for none of the robot's own
        sources, the problem allocates clearances only.

    Attributes
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The robot as the user described it: the innermost model of ``model``'s composition
        (:attr:`evotol.robots.base.RobotErrorModel.described`), without the parts a study adds.
    model : evotol.robots.base.RobotErrorModel
        The error model passed in, unchanged: the described robot with the parts composed around it
        (joint configurations, per-axis limits, drawing callouts, calibration; ``docs/architecture.md``).
    clearances : evotol.measures.clearances.ClearanceSources or None
        The joint-clearance classes passed in, held beside the robot.
    error_model : evotol.robots.base.RobotErrorModel
        The one place the problem's sources and sensitivities come from: ``robot`` itself, or
        with clearance classes :class:`evotol.measures.clearances.WithClearances` (the robot's
        interval sources, unless none has a tolerance, followed by the classes, which have zero
        first-order columns). ``names``, ``groups()``, ``units()``, the Jacobian and the measures
        read it.
    warnings : list of str
        The problem's plausibility lines (:func:`evotol.core.plausibility.problem_warnings`:
        probable unit slips), computed once when it is built and issued then.
    calibration : evotol.calibration.problem.CalibrationInfo or None
        The calibration the problem assumes (plan, identification, noise share, linear-range bounds),
        set by :func:`evotol.calibration.calibrated_problem`; None for a robot that is not calibrated.
    uncalibrated : ToleranceProblem or None
        With ``calibration``: the same problem without it (what calibration buys is compared with it).

    Raises
    ------
    evotol.errors.ValidationError
        Before any computation: a robot, requirement, tolerance, pose array, ``shared`` group or
        ``clearances`` that is not what is expected (the message names the field and the value).
    evotol.errors.KinematicsError
        A pose out of reach or at a singularity of the robot.

    See Also
    --------
    evotol.core.problem.derived.DerivedProblems : ``with_requirement``, ``with_poses``, ``at_poses``,
        ``with_tolerances``, ``with_added_poses``.
    evotol.core.problem.variable_mapping.VariableMapping : ``full``, ``to_variables``, ``locked_part``,
        ``as_array``, ``intervals``, ``source_errors``.
    evotol.core.problem.costs.ProblemCosts : ``cost``, ``free_cost``, ``source_costs``, ``dcost``,
        ``variable_dcost``.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import Requirement, Tolerance, ToleranceProblem
    >>> from evotol.robots.ucr3 import UCR3
    >>> robot = UCR3()
    >>> tol = {s.name: Tolerance(PowerCost(1.0, 1.0, scale=1e-5), lower=1e-6, upper=1e-4)
    ...        for s in robot.sources}
    >>> problem = ToleranceProblem(robot, tol, Requirement(position=5e-5, measure="rss"),
    ...                            robot.workspace.grid([2, 2, 2]))
    >>> problem.n_poses, problem.n_sources
    (8, 12)
    >>> problem.evaluate([[1e-5] * 12]).position.shape         # RSS error (m) per design and pose
    (1, 8)
    """

    #: set by evotol.calibration.calibrated_problem (Attributes); declared here, never looked up with getattr
    calibration = None
    uncalibrated = None
    #: set by evotol.core.shop (a study file's [shop]): source -> (floor, key) and the smallest measurable zones
    shop_floors: dict | None = None
    measurable: dict | None = None

    def __init__(self, robot: RobotErrorModel, tolerances: Mapping[str, Tolerance], requirement: Requirement,
                 poses, n_directions: int = 600, shared: Mapping[str, Sequence[str]] | None = None,
                 shared_cost: str = "part", clearances: "clearance_measure.ClearanceSources | None" = None,
                 all_given: bool = False):
        if not isinstance(robot, RobotErrorModel):
            raise ValidationError("robot", robot, "a evotol.robots.base.RobotErrorModel")
        if not isinstance(requirement, Requirement):
            raise ValidationError("requirement", requirement, "an evotol.Requirement")
        requirement.validate()
        if clearances is not None:
            if not isinstance(clearances, clearance_measure.ClearanceSources):
                raise ValidationError("clearances", clearances, "an evotol.measures.clearances.ClearanceSources")
            # tolerances for none of the robot's own sources: a clearance-only problem
            geometric = not isinstance(tolerances, Mapping) or any(n in tolerances for n in robot.source_names)
            model = clearance_measure.WithClearances(robot, clearances, geometric)
            self._check_clearance_measure(requirement)
        else:
            model = robot
        self.model, self.clearances, self.error_model = robot, clearances, model
        names = model.source_names
        if not isinstance(tolerances, Mapping):
            raise ValidationError("tolerances", tolerances, "a mapping source name -> Tolerance")
        missing = [n for n in names if n not in tolerances]
        extra = [n for n in tolerances if n not in names]
        if extra:
            raise ValidationError(f"tolerances[{extra[0]!r}]", extra[0], f"a source of {model.name}: {list(names)}"
                                  + did_you_mean(str(extra[0]), names))
        if missing:
            raise ValidationError("tolerances", sorted(tolerances), f"an entry for every source of {model.name}; missing {missing}")
        for n, src in zip(names, model.sources):
            if not isinstance(tolerances[n], Tolerance):
                raise ValidationError(f"tolerances[{n!r}]", tolerances[n], "an evotol.Tolerance")
            tolerances[n].validate(n, src.dim)
        self.requirement = requirement
        self.tolerances = {n: tolerances[n] for n in names}
        self.distributions = [distributions.as_distribution(self.tolerances[s.name].distribution,
                                                            f"tolerances[{s.name!r}].distribution", s.dim)
                              for s in model.sources]
        self.names = names
        self.poses = self._check_pose_set(poses)
        self.n_directions = int(n_directions)
        J = np.asarray(model.sensitivity(self.poses), dtype=float)
        if J.shape != (len(self.poses), 6, model.n_columns) or not np.all(np.isfinite(J)):
            raise ValidationError(f"{model.name}.sensitivity", J.shape, f"finite array of shape {(len(self.poses), 6, model.n_columns)}")
        self._set_jacobian(J)
        tols = [self.tolerances[n] for n in names]
        self.shape = measures.IntervalShape(np.array([t.rho for t in tols]), np.array([t.kappa for t in tols]),
                                            np.array([float(t.offset) for t in tols]))
        self.lower = np.array([t.lower for t in tols], dtype=float)
        self.upper = np.array([t.upper for t in tols], dtype=float)
        locked = [t.locked for t in tols]
        self.locked_values = np.array([np.nan if v is None else v for v in locked])
        self._set_shared(shared, shared_cost)
        if not self.free.any() and not all_given:     # all_given: an analysis (evotol.verification.tolerance_analysis)
            raise ValidationError("tolerances", "all locked", "at least one source free to optimise")
        self._coeff_cache: dict[str, tuple] = {}
        self._measure_cache: dict[str, object] = {}
        self.warnings = plausibility.problem_warnings(self)        # unit slips (issue 27): one line each,
        plausibility.warn(self.warnings)                            # computed once, issued once

    @property
    def robot(self) -> RobotErrorModel:
        """The robot as the user described it (the innermost part of :attr:`model`)."""
        return self.model.described

    def __copy__(self) -> "ToleranceProblem":
        """A shallow copy whose measures' caches start empty (the ``with_*`` copies change what
        they depend on: requirement, poses, tolerances)."""
        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        new._measure_cache = {}
        return new

    def measure_cache(self, key: str, build):
        """The value a measure cached under ``key`` on this problem, built by ``build()`` on first
        use (e.g. common Monte Carlo samples, the yield model's moments).

        Parameters
        ----------
        key : str
            Cache key (one per measure and purpose).
        build : callable
            Called without arguments to make the value when ``key`` is not cached yet.

        Returns
        -------
        object
            The cached value. The ``with_*`` copies start with an empty cache.
        """
        if key not in self._measure_cache:
            self._measure_cache[key] = build()
        return self._measure_cache[key]

    def _check_pose_set(self, poses) -> np.ndarray:
        if poses is None or (hasattr(poses, "__len__") and len(poses) == 0):
            raise ValidationError("poses", [] if poses is None else poses, "at least one workspace pose")
        return self.error_model.check_poses(poses)

    def _set_jacobian(self, J: np.ndarray) -> None:
        self.jacobian = J
        sl = self.error_model.column_slices
        self.blocks = {"position": [J[:, 0:3, s] for s in sl], "orientation": [J[:, 3:6, s] for s in sl]}
        self.sensitivities = {k: measures.spectral_norms(b) for k, b in self.blocks.items()}

    def _set_shared(self, shared, shared_cost: str) -> None:
        v = tolerance_variables(self.error_model, self.tolerances, self.lower, self.upper, self.locked_values,
                                shared, shared_cost)
        self.shared, self.shared_cost, self.lower, self.upper = v.shared, v.shared_cost, v.lower, v.upper
        self.leader, self.follower, self.locked, self.free = v.leader, v.follower, v.locked, v.free
        self.variable_matrix, self.variables, self.cost_weight = v.variable_matrix, v.variables, v.cost_weight

    # --- basic properties ---------------------------------------------------------------------
    @staticmethod
    def _clearance_measures() -> tuple[str, ...]:
        """Names of the registered measures that judge clearance sources."""
        return tuple(n for n, m in measure_registry.available().items() if m.clearances)

    @classmethod
    def _check_clearance_measure(cls, requirement: Requirement) -> None:
        if not measure_registry.get(requirement.measure).clearances:
            raise ValidationError("requirement.measure", requirement.measure,
                                  f"one of {cls._clearance_measures()} with clearance sources (the certified engine's measure)")

    @property
    def n_sources(self) -> int:
        """Number of error sources (tolerances), dimensionless."""
        return len(self.names)

    @property
    def n_poses(self) -> int:
        """Number of workspace poses checked, dimensionless."""
        return len(self.poses)

    @property
    def n_variables(self) -> int:
        """Number of free tolerance variables (a ``shared`` group counts once), dimensionless."""
        return int(self.free.sum())

    @property
    def asymmetric(self) -> bool:
        """Some interval is not centred on zero (offset or minus != plus)."""
        return not self.shape.centred

    @property
    def components(self) -> list[tuple[str, float]]:
        """(component, bound) pairs that the requirement constrains."""
        out = []
        if self.requirement.position is not None:
            out.append(("position", float(self.requirement.position)))
        if self.requirement.orientation is not None:
            out.append(("orientation", float(self.requirement.orientation)))
        return out

    def groups(self) -> list[str]:
        """The robot's group label of each source, in source order.

        Returns
        -------
        list of str
            One group name per source (``error_model.sources[j].group``).
        """
        return [s.group for s in self.error_model.sources]

    def units(self) -> list[str]:
        """The SI unit of each source's tolerance, in source order.

        Returns
        -------
        list of str
            One unit per source (``"m"`` or ``"rad"``, ``error_model.sources[j].unit``).
        """
        return [s.unit for s in self.error_model.sources]

    # --- accuracy -------------------------------------------------------------------------------
    def coefficients(self, component: str):
        """Cached (c[p, d, j], directions, δ[, const[p, d]]) of the worst-case support function
        (const: the offsets' part, only for asymmetric intervals).

        Parameters
        ----------
        component : {"position", "orientation"}
            The error component.

        Returns
        -------
        tuple
            ``(c, D, delta)`` or, for non-plain interval shapes, ``(c, D, delta, const)``:
            ``c`` (n_poses, n_directions, n_sources) support coefficients (m or rad per unit of
            tolerance), ``D`` (n_directions, 3) unit directions, ``delta`` their covering angle
            (rad; see :func:`evotol.measures.linear.directions_for`), ``const``
            (n_poses, n_directions) the offsets' part (m or rad).
        """
        if component not in self._coeff_cache:
            blocks = self.blocks[component]
            D, delta = self.directions(component)
            if self.shape.plain:
                self._coeff_cache[component] = (measures.support_coefficients(blocks, D), D, delta)
            else:
                self._coeff_cache[component] = (measures.support_coefficients(blocks, D, self.shape), D, delta,
                                                measures.support_constant(blocks, D, self.shape))
        return self._coeff_cache[component]

    def directions(self, component: str) -> tuple[np.ndarray, float]:
        """The direction grid of the worst-case support function and its covering angle (the ``D``,
        ``delta`` of :meth:`coefficients`, without building the coefficients).

        Parameters
        ----------
        component : {"position", "orientation"}
            The error component whose direction grid is asked for.

        Returns
        -------
        tuple
            ``D`` (n_directions, 3) unit directions and ``delta`` (rad;
            :func:`evotol.measures.linear.directions_for`).
        """
        if component in self._coeff_cache:          # the cached coefficients' own grid
            return tuple(self._coeff_cache[component][1:3])
        blocks = self.blocks[component]
        seen = self.__dict__.setdefault("_direction_cache", {}).get(component)
        if seen is not None and seen[0] is blocks and seen[1] == (self.n_directions, self.asymmetric):
            return seen[2]                          # the same blocks object: the same grid (issue 43: 0.2 s a call at 10^5 poses)
        found = measures.directions_for(np.concatenate(blocks, axis=2), self.n_directions, full_sphere=self.asymmetric)
        self._direction_cache[component] = (blocks, (self.n_directions, self.asymmetric), found)
        return found

    def coefficient_blocks(self, component: str) -> list[tuple[slice, tuple]]:
        """The support coefficients by blocks of poses: ``[(poses, (c, D, delta[, const]))]``.

        One block, the cached :meth:`coefficients`, when they fit in :data:`COEFFICIENT_CACHE_BYTES`;
        otherwise blocks of consecutive poses computed when asked for and not kept, so memory grows
        with the poses' results, not with poses x directions x sources (issue 43 item 4).

        Parameters
        ----------
        component : {"position", "orientation"}
            The error component whose coefficients are asked for.

        Returns
        -------
        list of (slice, tuple)
            The poses of each block and its coefficients in the layout of :meth:`coefficients`; a lazy
            sequence (:class:`evotol.measures.linear.PoseBlocks`) when blocked.
        """
        if component in self._coeff_cache:
            return [(slice(None), self._coeff_cache[component])]
        per_pose = self.coefficient_bytes(component) / max(self.n_poses, 1)
        if self.n_poses * per_pose <= COEFFICIENT_CACHE_BYTES:
            return [(slice(None), self.coefficients(component))]
        D, delta = self.directions(component)
        return measures.PoseBlocks(self.blocks[component], D, delta, None if self.shape.plain else self.shape,
                                   max(1, int(COEFFICIENT_CACHE_BYTES // (4 * per_pose))))

    def coefficient_bytes(self, component: str) -> int:
        """Bytes of a component's support coefficients at every pose: ``c`` and, for asymmetric
        intervals, ``const`` (:meth:`coefficients`), ``8 P D (n_sources + [asymmetric])``.

        Parameters
        ----------
        component : {"position", "orientation"}
            The error component whose coefficients are sized.

        Returns
        -------
        int
            Bytes, whether or not they are built (blocks of poses above :data:`COEFFICIENT_CACHE_BYTES`).
        """
        return 8 * self.n_poses * len(self.directions(component)[0]) * (self.n_sources + int(bool(self.asymmetric)))

    def support_row(self, component: str, pose: int, u: np.ndarray) -> tuple[np.ndarray, float]:
        """The worst-case row at one pose and direction u: h(u) = row·t + const (SI).

        Parameters
        ----------
        component : {"position", "orientation"}
            The error component.
        pose : int
            Pose index.
        u : ndarray, shape (3,)
            Unit direction.

        Returns
        -------
        row : ndarray, shape (n_sources,)
            Support coefficient of each source (m or rad per unit of tolerance).
        const : float
            The offsets' part (m or rad; 0 for plain centred intervals).
        """
        if self.shape.plain:
            return np.array([np.linalg.norm(B[pose].T @ u) for B in self.blocks[component]]), 0.0
        blocks = [B[pose:pose + 1] for B in self.blocks[component]]
        row = measures.support_coefficients(blocks, u[None], None if self.shape.plain else self.shape)[0, 0]
        const = 0.0 if self.shape.plain else float(measures.support_constant(blocks, u[None], self.shape)[0, 0])
        return row, const

    def evaluate(self, T, measure: str | None = None, top_only: bool = False, components=None) -> Evaluation:
        """Errors of designs at every pose under a measure.

        Parameters
        ----------
        T : array_like, shape (n_designs, n_sources) or (n_sources,)
            Source tolerances (SI: m or rad), or one design as a name -> value mapping.
        measure : str, optional
            A registered measure (:mod:`evotol.measures.registry`); default the requirement's.
        top_only : bool
            Exact only at the poses that can hold the largest error (faster; enough for
            feasibility).
        components : sequence of str, optional
            ``worst_case`` only: the components computed (default both; the others None). They must
            hold the constrained ones (:meth:`WorstCaseMeasure.evaluate
            <evotol.measures.builtin.worst_case.WorstCaseMeasure.evaluate>`).

        Returns
        -------
        Evaluation
            Errors per design and pose (m, rad) and the requirement's ``violation``.

        Raises
        ------
        ValidationError
            An unknown measure, a measure that cannot judge clearance sources, bad tolerances, or
            ``components`` with another measure than ``worst_case`` or without a constrained one.
        """
        T = np.atleast_2d(self.as_array(T))
        name = measure or self.requirement.measure
        m = measure_registry.get(name)
        if self.clearances is not None and not m.clearances:
            raise ValidationError("measure", name, f"one of {self._clearance_measures()} with clearance sources")
        if components is None:
            return m.evaluate(self, T, top_only)
        if name != "worst_case":
            raise ValidationError("components", list(components), f"None with the {name!r} measure (worst_case only)")
        return m.evaluate(self, T, top_only, components=components)

    def first_order_yield(self):
        """The ``yield`` measure's statistical model of this problem (cached):
        :class:`evotol.measures.statistical.FirstOrderYield`, or :class:`~evotol.measures.statistical.SampledYield`
        for ``Requirement(model="nonlinear")``.

        Returns
        -------
        evotol.measures.statistical.FirstOrderYield or evotol.measures.statistical.SampledYield
            The cached model.
        """
        return first_order_yield(self)

    def max_errors(self, T, measure: str | None = None) -> dict[str, np.ndarray]:
        """Largest error over the poses, per constrained component: name -> (n_designs,).

        Parameters
        ----------
        T : array_like, shape (n_designs, n_sources) or (n_sources,)
            Designs (SI: m or rad), or one design as a name -> value mapping.
        measure : str, optional
            A registered measure; default the requirement's.

        Returns
        -------
        dict of str to ndarray, shape (n_designs,)
            ``"position"`` (m) and/or ``"orientation"`` (rad) maximum over the poses, for the
            components the requirement constrains.
        """
        ev = self.evaluate(T, measure)
        return {c: np.max(getattr(ev, c), axis=1) for c, _ in self.components}

    def check_feasible(self) -> None:
        """Raise :class:`InfeasibleError` if even every free tolerance at its lower bound misses
        the requirement (names the requirement, the smallest achievable error and its pose).

        Raises
        ------
        evotol.errors.InfeasibleError
            The design with every free tolerance at its lower bound violates the requirement.
        """
        T = self.full(self.lower[self.free][None])
        ev = self.evaluate(T)
        if ev.violation[0] <= 1e-9:
            return
        worst = max(self.components, key=lambda cl: np.max(getattr(ev, cl[0])[0]) / cl[1])
        comp, lim = worst
        val = getattr(ev, comp)[0]
        p = int(np.argmax(val))
        unit = "m" if comp == "position" else "rad"
        raise InfeasibleError(f"{self.requirement.measure} {comp} error <= {lim:g} {unit}", float(val[p]),
                              self.poses[p].tolist(), f"pose index {p}")

    # --- summary --------------------------------------------------------------------------------
    def describe(self) -> str:
        """A printable summary: robot, poses, measure, requirement and each source's range, cost
        and interval shape (also ``str(problem)``; the ``repr`` is one short line).

        Returns
        -------
        str
            Several lines of text.
        """
        r = self.requirement
        lines = [f"ToleranceProblem: {self.error_model.name}, {self.n_poses} poses, measure {r.measure}",
                 f"  requirement: position <= {r.position} m, orientation <= {r.orientation} rad"]
        for n, s in zip(self.names, self.error_model.sources):
            tol = self.tolerances[n]
            lk = (" fixed" if tol.is_fixed else f", locked at {tol.locked:g}") if tol.locked is not None else ""
            sh = ""
            if tol.offset or tol.minus != 1 or tol.plus != 1:
                sh = f"  interval [{tol.offset:g} - {tol.minus:g} t, {tol.offset:g} + {tol.plus:g} t]"
            lines.append(f"  {n:8s} {s.shape:8s} [{tol.lower:.3g}, {tol.upper:.3g}] {s.unit}  cost {tol.cost!r}{lk}{sh}")
        for g, m in self.shared.items():
            lines.append(f"  shared {g}: {', '.join(m)} (cost per {self.shared_cost})")
        return "\n".join(lines)

    __str__ = describe

    def __repr__(self) -> str:
        """One line: the robot, the counts and the requirement (``print(problem)`` gives every source)."""
        units = {c: error_unit(self, c) for c, _ in self.components}     # "1": an assembly's fractions of its limits
        req = ", ".join(f"{c} <= {lim:g}" + (f" {units[c]}" if units[c] != "1" else " of the limits")
                        for c, lim in self.components)
        return (f"ToleranceProblem(robot={self.error_model.name!r}, {self.n_sources} sources, {self.n_poses} poses, "
                f"requirement={req} ({self.requirement.measure}))")

    def __getstate__(self) -> dict:
        """The problem without its private caches (support coefficients, measures' samples): they
        are rebuilt on first use, so a pickle sent to a worker carries the problem only."""
        state = self.__dict__.copy()
        state["_coeff_cache"], state["_measure_cache"], state["_direction_cache"] = {}, {}, {}
        return state

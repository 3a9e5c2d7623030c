"""The tolerance-allocation problem: named error sources with tolerances (:mod:`evotol.tolerance`),
an accuracy requirement (:mod:`evotol.requirement`) over a set of workspace poses, and a robot
error model that maps source errors to end-effector errors.

Design variables are the tolerances t_j (SI units: m or rad; the bound on the norm of source j's
error vector). The problem is a small, printable value plus cached arrays; every evaluation is
vectorised over a population of designs ``T`` of shape (n_designs, n_sources) and done by a
registered measure (:mod:`evotol.accuracy`).

Tolerance variables (:mod:`evotol.variables`, ``docs/tolerances.md``). The optimisers search the
*free variables* X (n_designs, n_variables): one per free source, a ``shared`` group being one
variable for all its members. :meth:`ToleranceProblem.full` maps X to source tolerances T,
inserting locked and fixed sources; ``problem.free`` marks the sources that carry a variable.
"""
from __future__ import annotations

import copy
import dataclasses
from typing import Mapping, Sequence

import numpy as np

from evotol import clearances as clearance_measure, distributions, measures, plausibility
from evotol.accuracy import registry as measure_registry
from evotol.accuracy.base import Evaluation
from evotol.accuracy.statistical_yield import first_order_yield
from evotol.errors import InfeasibleError, ValidationError
from evotol.keywords import did_you_mean
from evotol.requirement import Requirement
from evotol.tolerance import COST_WIDTHS, Tolerance
from evotol.variables import SHARED_COSTS, tolerance_variables
from robots.base import RobotErrorModel

__all__ = ["ToleranceProblem", "Tolerance", "Requirement", "Evaluation", "COST_WIDTHS", "SHARED_COSTS"]


class ToleranceProblem:
    """Tolerance allocation over a robot's workspace (see module docstring).

    Parameters
    ----------
    robot : robots.base.RobotErrorModel
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
        ``"part"`` (default: cost counted for every member) or ``"variable"`` (once).
    clearances : evotol.clearances.ClearanceSources or None
        Joint-clearance classes allocated with the robot's (interval) sources; their names follow
        the robot's source names, and the ``worst_case`` measure is then the certified engine's
        (:func:`evotol.clearances.worst_case`). With tolerances for none of the robot's own
        sources, the problem allocates clearances only.

    Raises
    ------
    evotol.errors.ValidationError
        Before any computation: a robot, requirement, tolerance, pose array, ``shared`` group or
        ``clearances`` that is not what is expected (the message names the field and the value).
    evotol.errors.KinematicsError
        A pose out of reach or at a singularity of the robot.
    """

    def __init__(self, robot: RobotErrorModel, tolerances: Mapping[str, Tolerance], requirement: Requirement,
                 poses, n_directions: int = 600, shared: Mapping[str, Sequence[str]] | None = None,
                 shared_cost: str = "part", clearances: "clearance_measure.ClearanceSources | None" = None):
        if not isinstance(robot, RobotErrorModel):
            raise ValidationError("robot", robot, "a robots.base.RobotErrorModel")
        if not isinstance(requirement, Requirement):
            raise ValidationError("requirement", requirement, "an evotol.Requirement")
        requirement.validate()
        if clearances is not None:
            if not isinstance(clearances, clearance_measure.ClearanceSources):
                raise ValidationError("clearances", clearances, "an evotol.clearances.ClearanceSources")
            # tolerances for none of the robot's own sources: a clearance-only problem
            geometric = not isinstance(tolerances, Mapping) or any(n in tolerances for n in robot.source_names)
            robot = clearance_measure.WithClearances(robot, clearances, geometric)
            self._check_clearance_measure(requirement)
        names = robot.source_names
        if not isinstance(tolerances, Mapping):
            raise ValidationError("tolerances", tolerances, "a mapping source name -> Tolerance")
        missing = [n for n in names if n not in tolerances]
        extra = [n for n in tolerances if n not in names]
        if extra:
            raise ValidationError(f"tolerances[{extra[0]!r}]", extra[0], f"a source of {robot.name}: {list(names)}"
                                  + did_you_mean(str(extra[0]), names))
        if missing:
            raise ValidationError("tolerances", sorted(tolerances), f"an entry for every source of {robot.name}; missing {missing}")
        for n, src in zip(names, robot.sources):
            if not isinstance(tolerances[n], Tolerance):
                raise ValidationError(f"tolerances[{n!r}]", tolerances[n], "an evotol.Tolerance")
            tolerances[n].validate(n, src.dim)
        self.robot, self.requirement = robot, requirement
        self.tolerances = {n: tolerances[n] for n in names}
        self.distributions = [distributions.as_distribution(self.tolerances[s.name].distribution,
                                                            f"tolerances[{s.name!r}].distribution", s.dim)
                              for s in robot.sources]
        self.names = names
        self.poses = self._check_pose_set(poses)
        self.n_directions = int(n_directions)
        J = np.asarray(robot.sensitivity(self.poses), dtype=float)
        if J.shape != (len(self.poses), 6, robot.n_columns) or not np.all(np.isfinite(J)):
            raise ValidationError(f"{robot.name}.sensitivity", J.shape, f"finite array of shape {(len(self.poses), 6, robot.n_columns)}")
        self._set_jacobian(J)
        tols = [self.tolerances[n] for n in names]
        self.shape = measures.IntervalShape(np.array([t.rho for t in tols]), np.array([t.kappa for t in tols]),
                                            np.array([float(t.offset) for t in tols]))
        self.lower = np.array([t.lower for t in tols], dtype=float)
        self.upper = np.array([t.upper for t in tols], dtype=float)
        locked = [t.locked for t in tols]
        self.locked_values = np.array([np.nan if v is None else v for v in locked])
        self._set_shared(shared, shared_cost)
        if not self.free.any():
            raise ValidationError("tolerances", "all locked", "at least one source free to optimise")
        self._coeff_cache: dict[str, tuple] = {}
        self._measure_cache: dict[str, object] = {}
        plausibility.warn(plausibility.problem_warnings(self))      # unit slips (issue 27): one line each

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
        return self.robot.check_poses(poses)

    def _set_jacobian(self, J: np.ndarray) -> None:
        self.jacobian = J
        sl = self.robot.column_slices
        self.blocks = {"position": [J[:, 0:3, s] for s in sl], "orientation": [J[:, 3:6, s] for s in sl]}
        self.sensitivities = {k: measures.spectral_norms(b) for k, b in self.blocks.items()}

    def _set_shared(self, shared, shared_cost: str) -> None:
        v = tolerance_variables(self.robot, self.tolerances, self.lower, self.upper, self.locked_values,
                                shared, shared_cost)
        self.shared, self.shared_cost, self.lower, self.upper = v.shared, v.shared_cost, v.lower, v.upper
        self.leader, self.follower, self.locked, self.free = v.leader, v.follower, v.locked, v.free
        self.variable_matrix, self.variables, self.cost_weight = v.variable_matrix, v.variables, v.cost_weight

    # --- basic properties ---------------------------------------------------------------------
    @property
    def clearances(self) -> "clearance_measure.ClearanceSources | None":
        """The allocated joint-clearance classes, or None."""
        return self.robot.clearances if isinstance(self.robot, clearance_measure.WithClearances) else None

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
            One group name per source (``robot.sources[j].group``).
        """
        return [s.group for s in self.robot.sources]

    def units(self) -> list[str]:
        """The SI unit of each source's tolerance, in source order.

        Returns
        -------
        list of str
            One unit per source (``"m"`` or ``"rad"``, ``robot.sources[j].unit``).
        """
        return [s.unit for s in self.robot.sources]

    def with_requirement(self, **changes) -> "ToleranceProblem":
        """A copy with some requirement fields changed (shares the cached sensitivities).

        Parameters
        ----------
        **changes
            :class:`Requirement` fields and their new values (``position`` in m, ``orientation``
            in rad, ``measure`` ...), as for :func:`dataclasses.replace`.

        Returns
        -------
        ToleranceProblem
            The copy; measure caches start empty.

        Raises
        ------
        evotol.errors.ValidationError
            The changed requirement is invalid, or its measure cannot judge the problem's
            clearance sources.
        TypeError
            A name that is not a :class:`Requirement` field.
        """
        new = copy.copy(self)
        new.requirement = dataclasses.replace(self.requirement, **changes)
        new.requirement.validate()
        if self.clearances is not None:
            self._check_clearance_measure(new.requirement)
        return new

    def with_poses(self, idx) -> "ToleranceProblem":
        """A copy on the subset ``idx`` of the poses (indices or boolean mask), reusing the
        sensitivities already computed (no call to the robot).

        Parameters
        ----------
        idx : array_like of int, or bool ndarray, shape (n_poses,)
            Pose indices (negative ones count from the end) or a boolean mask over the poses.

        Returns
        -------
        ToleranceProblem
            The copy on the selected poses.

        Raises
        ------
        evotol.errors.ValidationError
            A mask of the wrong shape, an empty selection, or indices that are not integers in
            ``[-n_poses, n_poses)``.
        """
        idx = np.asarray(idx)
        if idx.dtype == bool:
            if idx.shape != (self.n_poses,):
                raise ValidationError("idx", idx.shape, f"a boolean mask of shape ({self.n_poses},)")
            idx = np.flatnonzero(idx)
        if idx.size == 0:
            raise ValidationError("poses", [], "at least one workspace pose")
        if not np.issubdtype(idx.dtype, np.integer) or idx.min() < -self.n_poses or idx.max() >= self.n_poses:
            raise ValidationError("idx", idx.tolist()[:5], f"pose indices in [0, {self.n_poses})")
        new = copy.copy(self)
        new.poses = self.poses[idx]
        new._set_jacobian(self.jacobian[idx])
        new._coeff_cache = {k: (v[0][idx],) + tuple(v[1:3]) + ((v[3][idx],) if len(v) > 3 else ())
                            for k, v in self._coeff_cache.items()}
        return new

    def at_poses(self, poses) -> "ToleranceProblem":
        """A copy on other poses (same tolerances and requirement; sensitivities computed for them).

        Parameters
        ----------
        poses : array_like, shape (n, workspace.dim)
            The new workspace poses (SI: m, rad), at least one.

        Returns
        -------
        ToleranceProblem
            The copy on ``poses``.

        Raises
        ------
        evotol.errors.ValidationError
            No pose, a malformed pose array, or sensitivities that are not finite there.
        evotol.errors.KinematicsError
            A pose outside the robot's workspace.
        """
        P = self._check_pose_set(poses)
        J = np.asarray(self.robot.sensitivity(P), dtype=float)
        if J.shape != (len(P), 6, self.robot.n_columns) or not np.all(np.isfinite(J)):
            raise ValidationError(f"{self.robot.name}.sensitivity", P.tolist()[:3], "finite sensitivities at the poses")
        new = copy.copy(self)
        new.poses = P
        new._set_jacobian(J)
        new._coeff_cache = {}
        return new

    def with_tolerances(self, **fields) -> "ToleranceProblem":
        """A copy with some :class:`Tolerance` fields changed for every source (a scalar, or an
        array/sequence in source order), e.g. ``with_tolerances(offset=c)`` to evaluate interval
        designs [c − t, c + t]; reuses the sensitivities, re-validates every tolerance.

        Parameters
        ----------
        **fields
            Any of ``offset`` (SI: m or rad), ``minus``, ``plus`` (dimensionless factors),
            ``cost_width`` and ``contains_nominal``; each a scalar for every source or one value
            per source, shape (n_sources,).

        Returns
        -------
        ToleranceProblem
            The copy with the changed tolerances.

        Raises
        ------
        evotol.errors.ValidationError
            A field not in the list above, a value of the wrong shape, or a tolerance made invalid.
        """
        allowed = ("offset", "minus", "plus", "cost_width", "contains_nominal")
        for k in fields:
            if k not in allowed:
                raise ValidationError(f"with_tolerances.{k}", k, f"one of {allowed}" + did_you_mean(k, allowed))
        n = self.n_sources
        tols = {}
        for j, nm in enumerate(self.names):
            ch = {}
            for k, v in fields.items():
                arr = np.asarray(v, dtype=object if isinstance(v, str) else float)
                ch[k] = (arr.item() if arr.ndim == 0 else (float(arr[j]) if arr.shape == (n,) else None))
                if ch[k] is None:
                    raise ValidationError(k, np.shape(v), f"a scalar or one value per source ({n})")
            tols[nm] = dataclasses.replace(self.tolerances[nm], **ch)
        for nm, src in zip(self.names, self.robot.sources):
            tols[nm].validate(nm, src.dim)
        new = copy.copy(self)
        new.tolerances = tols
        new.shape = measures.IntervalShape(np.array([t.rho for t in tols.values()]),
                                           np.array([t.kappa for t in tols.values()]),
                                           np.array([float(t.offset) for t in tols.values()]))
        new._coeff_cache = {}
        return new

    def with_added_poses(self, poses) -> "ToleranceProblem":
        """A copy with more poses appended (sensitivities computed only for the new ones).

        Parameters
        ----------
        poses : array_like, shape (n, workspace.dim)
            Poses to append (SI: m, rad).

        Returns
        -------
        ToleranceProblem
            The copy on the old poses followed by ``poses``.

        Raises
        ------
        evotol.errors.ValidationError
            A malformed pose array, or sensitivities that are not finite at the new poses.
        evotol.errors.KinematicsError
            A pose outside the robot's workspace.
        """
        P = self.robot.check_poses(poses)
        J = np.asarray(self.robot.sensitivity(P), dtype=float)
        if not np.all(np.isfinite(J)):
            raise ValidationError(f"{self.robot.name}.sensitivity", P.tolist()[:3], "finite sensitivities at the added poses")
        new = copy.copy(self)
        new.poses = np.vstack([self.poses, P])
        new._set_jacobian(np.concatenate([self.jacobian, J], axis=0))
        new._coeff_cache = {}
        return new

    def full(self, X_free: np.ndarray) -> np.ndarray:
        """Tolerances of every source from the free variables: (n, n_variables) -> (n, n_sources);
        inserts locked/fixed values and copies each shared variable to all its members.

        Parameters
        ----------
        X_free : array_like, shape (n, n_variables) or (n_variables,)
            Values of the free variables (SI: m or rad).

        Returns
        -------
        ndarray, shape (n, n_sources)
            Tolerance of every source (SI: m or rad).
        """
        X_free = np.atleast_2d(X_free)
        T = np.empty((X_free.shape[0], self.n_sources))
        T[:, self.free] = X_free
        T[:, self.locked] = self.locked_values[self.locked]
        if self.follower.any():
            T[:, self.follower] = T[:, self.leader[self.follower]]
        return T

    def to_variables(self, A: np.ndarray) -> np.ndarray:
        """Row coefficients per source (..., n_sources) -> per free variable (..., n_variables)
        (a shared variable collects its members' coefficients).

        Parameters
        ----------
        A : ndarray, shape (..., n_sources)
            Coefficients per source (units of the row per unit of tolerance).

        Returns
        -------
        ndarray, shape (..., n_variables)
            ``A @ variable_matrix``: the coefficients per free variable.
        """
        return A @ self.variable_matrix

    def locked_part(self, A: np.ndarray, power: int = 1) -> np.ndarray:
        """Row values of the locked/fixed sources: ``A[:, locked] @ t_locked**power`` (zeros if none).

        Parameters
        ----------
        A : ndarray, shape (n_rows, n_sources)
            Row coefficients per source.
        power : int
            Power of the locked tolerances (1: linear rows, 2: squared rows as in RSS).

        Returns
        -------
        ndarray, shape (n_rows,)
            The constant part of each row due to the locked sources.
        """
        lk = self.locked
        if not lk.any():
            return np.zeros(A.shape[0])
        return A[:, lk] @ self.locked_values[lk] ** power

    def as_array(self, tolerances: Mapping[str, float] | np.ndarray) -> np.ndarray:
        """A design as an array in source order; accepts a name -> value mapping (SI).

        Parameters
        ----------
        tolerances : Mapping[str, float] or array_like, shape (..., n_sources)
            Tolerances (SI: m or rad), by source name or in source order.

        Returns
        -------
        ndarray, shape (n_sources,) or (..., n_sources)
            The tolerances as floats in source order.

        Raises
        ------
        evotol.errors.ValidationError
            A mapping without a value for every source, an array whose last axis is not
            n_sources, or a value that is negative or not finite.
        """
        if isinstance(tolerances, Mapping):
            missing = [n for n in self.names if n not in tolerances]
            if missing:
                raise ValidationError("tolerances", sorted(tolerances), f"a value for every source; missing {missing}")
            t = np.array([float(tolerances[n]) for n in self.names])
        else:
            t = np.asarray(tolerances, dtype=float)
            if t.shape[-1] != self.n_sources:
                raise ValidationError("tolerances shape", t.shape, f"(..., {self.n_sources})")
        if not np.all(np.isfinite(t)) or np.any(t < 0):
            raise ValidationError("tolerances", t.tolist(), "non-negative finite values (SI)")
        return t

    def intervals(self, t) -> np.ndarray:
        """(n_sources, 2) interval ends [offset − minus·t, offset + plus·t] of design t (SI); for
        disk/ball sources [−t, t] (the bound on the norm).

        Parameters
        ----------
        t : Mapping[str, float] or array_like, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        ndarray, shape (n_sources, 2)
            Lower and upper end of each source's interval (SI: m or rad).

        Raises
        ------
        evotol.errors.ValidationError
            A bad design (see :meth:`as_array`).
        """
        t = self.as_array(t)
        return np.array([self.tolerances[n].interval(t[j]) for j, n in enumerate(self.names)])

    def source_errors(self, Z: list[np.ndarray], t: np.ndarray) -> list[np.ndarray]:
        """Map unit samples Z_j (n, dim_j; ``|z| <= 1``, centred) to errors inside the intervals of
        design t (SI): e_j = offset_j + κ_j t_j + ρ_j t_j z_j (centred sources: t_j z_j).

        Parameters
        ----------
        Z : list of ndarray, each shape (n, dim_j)
            Unit samples per source (dimensionless).
        t : ndarray, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        list of ndarray, each shape (n, dim_j)
            Source errors (SI: m or rad).
        """
        sh = self.shape
        out = []
        for j, z in enumerate(Z):
            if sh.rho[j] == 1 and sh.kappa[j] == 0 and sh.offset[j] == 0:
                out.append(z * t[j])
            else:
                out.append(sh.offset[j] + sh.kappa[j] * t[j] + sh.rho[j] * t[j] * z)
        return out

    # --- cost -----------------------------------------------------------------------------------
    def cost(self, T, include_locked: bool = True) -> np.ndarray:
        """Total cost of designs T (n, n_sources) -> (n,); a single design gives a scalar.
        Fixed sources cost nothing; with ``shared_cost="variable"`` a shared group pays once.
        ``include_locked=False``: only the sources driven by a variable (what an optimiser moves).

        Parameters
        ----------
        T : array_like, shape (n, n_sources) or (n_sources,)
            Designs (SI: m or rad).
        include_locked : bool
            Count the locked sources too (default); False: only the free ones.

        Returns
        -------
        ndarray, shape (n,), or float
            Total cost per design (cost units); a float for a single design.
        """
        T = np.asarray(T, dtype=float)
        single = T.ndim == 1
        T2 = np.atleast_2d(T)
        c = np.zeros(T2.shape[0])
        for j, n in enumerate(self.names):
            if self.cost_weight[j] and (include_locked or not self.locked[j]):
                c += self.tolerances[n].cost_of(T2[:, j])
        return float(c[0]) if single else c

    def free_cost(self, t: np.ndarray) -> float:
        """Cost of the sources driven by a variable at one design t (n_sources,), summed one scalar
        at a time (what the optimum's objective uses; the locked part is a constant).

        Parameters
        ----------
        t : ndarray, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        float
            Cost of the free sources (cost units).
        """
        return sum(float(self.tolerances[n].cost_of(t[j])) for j, n in enumerate(self.names)
                   if self.cost_weight[j] and not self.locked[j])

    def source_costs(self, t) -> np.ndarray:
        """Cost of each source at one design (0 where no cost is counted: fixed sources, and
        the members after the first of a group with ``shared_cost="variable"``).

        Parameters
        ----------
        t : Mapping[str, float] or array_like, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        ndarray, shape (n_sources,)
            Cost per source (cost units).

        Raises
        ------
        evotol.errors.ValidationError
            A bad design (see :meth:`as_array`).
        """
        t = self.as_array(t)
        return np.array([float(self.tolerances[n].cost_of(t[j])) * self.cost_weight[j] for j, n in enumerate(self.names)])

    def dcost(self, t: np.ndarray) -> np.ndarray:
        """∂cost/∂t_j per source (n_sources,).

        Parameters
        ----------
        t : ndarray, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        ndarray, shape (n_sources,)
            Cost derivative per source (cost units per m or rad; 0 where no cost is counted).
        """
        return np.array([float(self.tolerances[n].dcost_of(t[j])) * self.cost_weight[j] if self.cost_weight[j] else 0.0
                         for j, n in enumerate(self.names)])

    def variable_dcost(self, t: np.ndarray) -> np.ndarray:
        """∂cost/∂x_v per free variable (n_variables,) at source tolerances t.

        Parameters
        ----------
        t : ndarray, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        ndarray, shape (n_variables,)
            Cost derivative per free variable (cost units per m or rad).
        """
        return self.dcost(t) @ self.variable_matrix

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
            (rad; see :func:`evotol.measures.directions_for`), ``const``
            (n_poses, n_directions) the offsets' part (m or rad).
        """
        if component not in self._coeff_cache:
            blocks = self.blocks[component]
            D, delta = measures.directions_for(np.concatenate(blocks, axis=2), self.n_directions,
                                               full_sphere=self.asymmetric)
            if self.shape.plain:
                self._coeff_cache[component] = (measures.support_coefficients(blocks, D), D, delta)
            else:
                self._coeff_cache[component] = (measures.support_coefficients(blocks, D, self.shape), D, delta,
                                                measures.support_constant(blocks, D, self.shape))
        return self._coeff_cache[component]

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

    def evaluate(self, T, measure: str | None = None, top_only: bool = False) -> Evaluation:
        """Errors of designs at every pose under a measure.

        Parameters
        ----------
        T : array_like, shape (n_designs, n_sources) or (n_sources,)
            Source tolerances (SI: m or rad), or one design as a name -> value mapping.
        measure : str, optional
            A registered measure (:mod:`evotol.accuracy.registry`); default the requirement's.
        top_only : bool
            Exact only at the poses that can hold the largest error (faster; enough for
            feasibility).

        Returns
        -------
        Evaluation
            Errors per design and pose (m, rad) and the requirement's ``violation``.

        Raises
        ------
        ValidationError
            An unknown measure, a measure that cannot judge clearance sources, or bad tolerances.
        """
        T = np.atleast_2d(self.as_array(T))
        name = measure or self.requirement.measure
        m = measure_registry.get(name)
        if self.clearances is not None and not m.clearances:
            raise ValidationError("measure", name, f"one of {self._clearance_measures()} with clearance sources")
        return m.evaluate(self, T, top_only)

    def first_order_yield(self):
        """The ``yield`` measure's statistical model of this problem (cached):
        :class:`evotol.statistical.FirstOrderYield`, or :class:`~evotol.statistical.SampledYield`
        for ``Requirement(model="nonlinear")``.

        Returns
        -------
        evotol.statistical.FirstOrderYield or evotol.statistical.SampledYield
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
        and interval shape (also the ``repr``).

        Returns
        -------
        str
            Several lines of text.
        """
        r = self.requirement
        lines = [f"ToleranceProblem: {self.robot.name}, {self.n_poses} poses, measure {r.measure}",
                 f"  requirement: position <= {r.position} m, orientation <= {r.orientation} rad"]
        for n, s in zip(self.names, self.robot.sources):
            tol = self.tolerances[n]
            lk = (" fixed" if tol.is_fixed else f", locked at {tol.locked:g}") if tol.locked is not None else ""
            sh = ""
            if tol.offset or tol.minus != 1 or tol.plus != 1:
                sh = f"  interval [{tol.offset:g} - {tol.minus:g} t, {tol.offset:g} + {tol.plus:g} t]"
            lines.append(f"  {n:8s} {s.shape:8s} [{tol.lower:.3g}, {tol.upper:.3g}] {s.unit}  cost {tol.cost!r}{lk}{sh}")
        for g, m in self.shared.items():
            lines.append(f"  shared {g}: {', '.join(m)} (cost per {self.shared_cost})")
        return "\n".join(lines)

    __repr__ = describe

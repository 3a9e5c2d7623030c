"""The tolerance-allocation problem: named error sources with cost models and bounds, an accuracy
requirement over a set of workspace poses, and a robot error model that maps source errors to
end-effector errors.

Design variables are the tolerances t_j (SI units: m or rad; the bound on the norm of source j's
error vector). The problem is a small, printable value plus cached arrays; every evaluation is
vectorised over a population of designs ``T`` of shape (n_designs, n_sources).

Tolerance variables (``docs/tolerances.md``). The optimisers search the *free variables* X
(n_designs, n_variables): one per free source, except that a ``shared`` group (e.g. the three
legs made from one drawing) is one variable driving all its member sources (t_j = x_v for every
member j). :meth:`ToleranceProblem.full` maps X to source tolerances T, inserting locked and
fixed sources; ``problem.free`` marks the sources that carry a variable (a group's first member).
Cost is counted per part (``shared_cost="part"``, default: every member pays its own cost model)
or once per variable (``"variable"``: only the first member's cost model).
"""
from __future__ import annotations

import copy
import dataclasses
import difflib
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from cost_models.base import CostModel
from evotol import clearances as clearance_measure, distributions, measures, plausibility, statistical
from evotol.errors import InfeasibleError, ValidationError
from robots.base import RobotErrorModel

DISTRIBUTIONS = distributions.KINDS
COST_WIDTHS = ("half", "full")
SHARED_COSTS = ("part", "variable")


@dataclass(frozen=True)
class Tolerance:
    """Settings of one error source's tolerance (all keyword fields; SI units: m or rad).

    cost: cost model of this tolerance, or None for a fixed source (:meth:`fixed`).
    lower, upper: allowed range of the tolerance t, 0 < lower <= upper.
    locked: if given, the tolerance is fixed at this value and not optimised (its cost counts).
    distribution: how the source is distributed inside its tolerance (Monte Carlo and the
        ``yield`` measure): a kind name (``"uniform"``, ``"normal"`` with t = 3σ,
        ``"truncated_normal"``, ``"contact"``) or an :class:`evotol.distributions.Distribution`
        (``sigma_k``, ``mean_shift``); conventions in :mod:`evotol.distributions`. For an
        asymmetric interval the distribution is placed on the interval: centre
        offset + (plus − minus)/2·t, half-width (minus + plus)/2·t.
    offset, minus, plus (interval sources only): the error lies in
        ``[offset − minus·t, offset + plus·t]``; ``offset`` is a fixed mean shift (SI),
        ``minus``/``plus`` fixed ratios (>= 0, not both 0). Default: the centred interval ±t.
    cost_width: which width the cost model is evaluated on: ``"half"`` (default: the half-width
        (minus + plus)/2·t, which is t for ±t -- the convention of the cost–tolerance literature
        for a symmetric ±t) or ``"full"`` (the whole width (minus + plus)·t, as a drawing states
        a tolerance zone).
    contains_nominal: if True, every allowed interval must contain 0 (the nominal value), which
        is checked at the smallest allowed tolerance.
    """

    cost: CostModel | None
    lower: float
    upper: float
    locked: float | None = None
    distribution: "str | distributions.Distribution" = "uniform"
    offset: float = 0.0
    minus: float = 1.0
    plus: float = 1.0
    cost_width: str = "half"
    contains_nominal: bool = False

    @classmethod
    def fixed(cls, t: float, **kwargs) -> "Tolerance":
        """A source with a known error bound t (SI) and no cost: not optimised, never priced."""
        return cls(cost=None, lower=t, upper=t, locked=t, **kwargs)

    @property
    def is_fixed(self) -> bool:
        return self.cost is None

    @property
    def rho(self) -> float:
        """Half-width per unit t: (minus + plus)/2."""
        return 0.5 * (float(self.minus) + float(self.plus))

    @property
    def kappa(self) -> float:
        """Centre shift per unit t: (plus − minus)/2."""
        return 0.5 * (float(self.plus) - float(self.minus))

    @property
    def width_factor(self) -> float:
        """Width the cost model sees per unit t: ρ (``cost_width="half"``) or 2ρ (``"full"``)."""
        return self.rho if self.cost_width == "half" else 2 * self.rho

    def interval(self, t: float) -> tuple[float, float]:
        """The interval [offset − minus·t, offset + plus·t] (SI) at tolerance t."""
        return self.offset - self.minus * t, self.offset + self.plus * t

    def cost_of(self, t):
        """Cost at tolerance t (array-like): the cost model at the width ``cost_width`` says; 0 if fixed."""
        if self.cost is None:
            return np.zeros_like(np.asarray(t, dtype=float))
        w = self.width_factor
        return self.cost.cost(t if w == 1 else w * np.asarray(t, dtype=float))

    def dcost_of(self, t):
        """d cost / d t (chain rule through the width factor)."""
        if self.cost is None:
            return np.zeros_like(np.asarray(t, dtype=float))
        w = self.width_factor
        return self.cost.dcost(t) if w == 1 else w * self.cost.dcost(w * np.asarray(t, dtype=float))

    def validate(self, name: str, dim: int = 1) -> None:
        f0 = f"tolerances[{name!r}]"
        if self.cost is not None and not isinstance(self.cost, CostModel):
            raise ValidationError(f"{f0}.cost", self.cost, "a cost_models.CostModel (or None with Tolerance.fixed)")
        if self.cost is None and self.locked is None:
            raise ValidationError(f"{f0}.cost", None, "a cost model; only Tolerance.fixed(t) (locked) may have none")
        for f in ("lower", "upper"):
            v = getattr(self, f)
            if not isinstance(v, (int, float, np.floating)) or not np.isfinite(v) or v <= 0:
                raise ValidationError(f"{f0}.{f}", v, "a positive finite tolerance in SI units (m or rad)")
        if self.lower > self.upper:
            raise ValidationError(f"{f0}.lower", self.lower, f"<= upper ({self.upper})")
        if self.locked is not None and not (isinstance(self.locked, (int, float, np.floating))
                                            and np.isfinite(self.locked) and self.locked > 0):
            raise ValidationError(f"{f0}.locked", self.locked, "a positive tolerance (SI) or None")
        if self.locked is not None and not (self.lower * (1 - 1e-12) <= self.locked <= self.upper * (1 + 1e-12)):
            raise ValidationError(f"{f0}.locked", self.locked,   # issue 15: was silently used
                                  f"a value within [lower, upper] = [{self.lower:.6g}, {self.upper:.6g}]")
        distributions.as_distribution(self.distribution, f"{f0}.distribution")
        for f in ("offset", "minus", "plus"):
            v = getattr(self, f)
            if not isinstance(v, (int, float, np.floating)) or not np.isfinite(v) or (f != "offset" and v < 0):
                raise ValidationError(f"{f0}.{f}", v, "a finite number (SI)" if f == "offset" else "a ratio >= 0")
        if self.minus + self.plus <= 0:
            raise ValidationError(f"{f0}.minus", (self.minus, self.plus), "minus + plus > 0")
        if self.cost_width not in COST_WIDTHS:
            raise ValidationError(f"{f0}.cost_width", self.cost_width, f"one of {COST_WIDTHS}")
        if dim != 1 and (self.offset != 0 or self.minus != 1 or self.plus != 1):
            raise ValidationError(f"{f0}.offset", (self.offset, self.minus, self.plus),
                                  f"offset = 0, minus = plus = 1 for a {dim}-D source (asymmetric intervals are for "
                                  "interval sources)")
        t_small = self.locked if self.locked is not None else self.lower
        lo, hi = self.interval(t_small)
        if self.contains_nominal and not (lo <= 0 <= hi):
            raise ValidationError(f"{f0}.offset", self.offset,
                                  f"an offset whose interval contains 0 at t = {t_small:g} "
                                  f"([{lo:.6g}, {hi:.6g}]; contains_nominal = True)")
        if self.cost is not None:
            w = self.width_factor
            a = min(self.lower, self.locked or self.lower)
            b = max(self.upper, self.locked or self.upper)
            self.cost.validate_range(w * a, w * b)


@dataclass(frozen=True)
class Requirement:
    """Accuracy the end-effector must hold at every pose.

    position: bound on |δp| (m), or None; orientation: bound on |δθ| (rad), or None.
    measure: ``"worst_case"`` (exact for the linear model, see :mod:`evotol.measures`),
        ``"rss"`` (root sum square of the sources' worst-case effects), or ``"mc_quantile"``
        (the ``quantile`` of |δp| over ``mc_samples`` Latin-hypercube samples, linear model), or
        ``"yield"``: at every pose P(|δp| ≤ position and |δθ| ≤ orientation) ≥ ``probability``
        for the first-order model (:mod:`evotol.statistical`; Bonferroni bound for both).
    probability: required yield of the ``yield`` measure in (0, 1) (default 0.9973 = 3σ), or
    ppm: the same given as allowed defects per million (probability = 1 − ppm·1e-6).
    model: ``"linear"`` (first-order model, exact probability) or ``"nonlinear"`` (``yield`` only:
        the robot's ``pose_error`` on ``mc_samples`` common Latin-hypercube samples from ``seed``,
        :class:`evotol.statistical.SampledYield`).
    """

    position: float | None = None
    orientation: float | None = None
    measure: str = "worst_case"
    quantile: float = 0.95
    mc_samples: int = 2000
    seed: int = 0
    probability: float | None = None
    ppm: float | None = None
    model: str = "linear"

    @property
    def required_yield(self) -> float:
        """The yield the ``yield`` measure requires (from ``probability`` or ``ppm``)."""
        if self.ppm is not None:
            return 1.0 - float(self.ppm) * 1e-6
        return 0.9973 if self.probability is None else float(self.probability)

    def validate(self) -> None:
        if self.position is None and self.orientation is None:
            raise ValidationError("requirement", self, "a position and/or orientation bound")
        for f in ("position", "orientation"):
            v = getattr(self, f)
            if v is not None and not (isinstance(v, (int, float, np.floating)) and np.isfinite(v) and v > 0):
                raise ValidationError(f"requirement.{f}", v, "a positive bound (m for position, rad for orientation) or None")
        if self.measure not in measures.MEASURES:
            raise ValidationError("requirement.measure", self.measure, f"one of {measures.MEASURES}")
        if not 0 < self.quantile < 1:
            raise ValidationError("requirement.quantile", self.quantile, "a probability in (0, 1)")
        if self.model not in ("linear", "nonlinear"):
            raise ValidationError("requirement.model", self.model, "'linear' or 'nonlinear'")
        if self.model == "nonlinear" and self.measure != "yield":
            raise ValidationError("requirement.model", self.model, "'linear' unless measure = 'yield'")
        if self.probability is not None and self.ppm is not None:
            raise ValidationError("requirement.ppm", self.ppm, "None when requirement.probability is given (one of the two)")
        if self.probability is not None:
            statistical.required_probability(self.probability)
        if self.ppm is not None and not (isinstance(self.ppm, (int, float, np.floating)) and 0 < self.ppm < 1e6):
            raise ValidationError("requirement.ppm", self.ppm, "defects per million in (0, 1e6)")
        if int(self.mc_samples) < 10:
            raise ValidationError("requirement.mc_samples", self.mc_samples, "at least 10 samples")


@dataclass
class Evaluation:
    """Errors of designs at every pose under the problem's measure (exact)."""

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


class ToleranceProblem:
    """Tolerance allocation over a robot's workspace (see module docstring).

    robot: a :class:`robots.base.RobotErrorModel`.
    tolerances: source name -> :class:`Tolerance`, one entry per robot source.
    requirement: :class:`Requirement`.
    poses: (n_poses, workspace.dim) array of workspace poses (SI units), at least one.
    n_directions: hemisphere directions for the worst-case measure (more: tighter bound).
    shared: group name -> member source names; each group is one tolerance variable.
    shared_cost: ``"part"`` (default: cost counted for every member) or ``"variable"`` (once).
    clearances: :class:`evotol.clearances.ClearanceSources` -- joint-clearance classes allocated
        with the robot's (interval) sources; their names follow the robot's source names, and the
        ``worst_case`` measure is then the certified engine's (:func:`evotol.clearances.worst_case`).
        With tolerances for none of the robot's own sources, the problem allocates clearances only.
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
            near = difflib.get_close_matches(str(extra[0]), names, n=1)
            raise ValidationError(f"tolerances[{extra[0]!r}]", extra[0], f"a source of {robot.name}: {list(names)}"
                                  + (f" (did you mean {near[0]!r}?)" if near else ""))
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
        self._mc_cache = None
        self._yield_cache = None
        plausibility.warn(plausibility.problem_warnings(self))      # unit slips (issue 27): one line each

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
        if shared_cost not in SHARED_COSTS:
            raise ValidationError("shared_cost", shared_cost, f"one of {SHARED_COSTS}")
        n = len(self.names)
        leader = np.arange(n)
        self.shared = {}
        if shared is not None and not isinstance(shared, Mapping):
            raise ValidationError("shared", shared, "a mapping group name -> list of source names")
        seen: dict[str, str] = {}
        index = {nm: j for j, nm in enumerate(self.names)}
        for g, members in (shared or {}).items():
            if isinstance(members, str) or not isinstance(members, Sequence) or len(members) == 0:
                raise ValidationError(f"shared.{g}", members, "a non-empty list of source names")
            for m in members:
                if m not in index:
                    near = difflib.get_close_matches(str(m), self.names, n=1)
                    raise ValidationError(f"shared.{g}", m, f"a source of {self.robot.name}: {list(self.names)}"
                                          + (f" (did you mean {near[0]!r}?)" if near else ""))
                if m in seen:
                    raise ValidationError(f"shared.{g}", m, f"a source named in one shared group only, once "
                                          f"(already in {seen[m]!r})")
                seen[m] = g
                tol = self.tolerances[m]
                if tol.locked is not None:
                    raise ValidationError(f"shared.{g}", m, "free sources only (this one is locked or fixed)")
            idx = [index[m] for m in members]
            units = {self.robot.sources[j].unit for j in idx}
            if len(units) > 1:
                raise ValidationError(f"shared.{g}", list(members), f"sources of one unit (got {sorted(units)})")
            lo, hi = self.lower[idx].max(), self.upper[idx].min()
            if lo > hi:
                raise ValidationError(f"shared.{g}", list(members), f"overlapping tolerance ranges (largest lower "
                                      f"{lo:g} > smallest upper {hi:g})")
            self.lower[idx], self.upper[idx] = lo, hi
            leader[idx] = idx[0]
            self.shared[str(g)] = tuple(members)
        self.shared_cost = shared_cost
        self.leader = leader
        self.follower = leader != np.arange(n)
        self.locked = ~np.isnan(self.locked_values)
        self.free = ~self.locked & ~self.follower
        fi = np.flatnonzero(self.free)
        M = np.zeros((n, fi.size))
        M[np.arange(n)[~self.locked], np.searchsorted(fi, leader[~self.locked])] = 1.0
        self.variable_matrix = M
        group_of = {index[m[0]]: g for g, m in self.shared.items()}
        self.variables = tuple(group_of.get(j, self.names[j]) for j in fi)
        w = np.ones(n)
        w[[j for j, nm in enumerate(self.names) if self.tolerances[nm].is_fixed]] = 0.0
        if shared_cost == "variable":
            w[self.follower] = 0.0
        self.cost_weight = w

    # --- basic properties ---------------------------------------------------------------------
    @property
    def clearances(self) -> "clearance_measure.ClearanceSources | None":
        """The allocated joint-clearance classes, or None."""
        return self.robot.clearances if isinstance(self.robot, clearance_measure.WithClearances) else None

    @staticmethod
    def _check_clearance_measure(requirement: Requirement) -> None:
        if requirement.measure != "worst_case":
            raise ValidationError("requirement.measure", requirement.measure,
                                  "'worst_case' with clearance sources (the certified engine's measure)")

    @property
    def n_sources(self) -> int:
        return len(self.names)

    @property
    def n_poses(self) -> int:
        return len(self.poses)

    @property
    def n_variables(self) -> int:
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
        return [s.group for s in self.robot.sources]

    def units(self) -> list[str]:
        return [s.unit for s in self.robot.sources]

    def with_requirement(self, **changes) -> "ToleranceProblem":
        """A copy with some requirement fields changed (shares the cached sensitivities)."""
        new = copy.copy(self)
        new.requirement = dataclasses.replace(self.requirement, **changes)
        new.requirement.validate()
        if self.clearances is not None:
            self._check_clearance_measure(new.requirement)
        new._mc_cache = None
        new._yield_cache = None
        return new

    def with_poses(self, idx) -> "ToleranceProblem":
        """A copy on the subset ``idx`` of the poses (indices or boolean mask), reusing the
        sensitivities already computed (no call to the robot)."""
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
        new._mc_cache = None
        new._yield_cache = None
        return new

    def at_poses(self, poses) -> "ToleranceProblem":
        """A copy on other poses (same tolerances and requirement; sensitivities computed for them)."""
        P = self._check_pose_set(poses)
        J = np.asarray(self.robot.sensitivity(P), dtype=float)
        if J.shape != (len(P), 6, self.robot.n_columns) or not np.all(np.isfinite(J)):
            raise ValidationError(f"{self.robot.name}.sensitivity", P.tolist()[:3], "finite sensitivities at the poses")
        new = copy.copy(self)
        new.poses = P
        new._set_jacobian(J)
        new._coeff_cache = {}
        new._mc_cache = None
        new._yield_cache = None
        return new

    def with_tolerances(self, **fields) -> "ToleranceProblem":
        """A copy with some :class:`Tolerance` fields changed for every source (a scalar, or an
        array/sequence in source order), e.g. ``with_tolerances(offset=c)`` to evaluate interval
        designs [c − t, c + t]; reuses the sensitivities, re-validates every tolerance."""
        allowed = ("offset", "minus", "plus", "cost_width", "contains_nominal")
        for k in fields:
            if k not in allowed:
                near = difflib.get_close_matches(k, allowed, n=1)
                raise ValidationError(f"with_tolerances.{k}", k, f"one of {allowed}" + (f" (did you mean {near[0]!r}?)" if near else ""))
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
        new._mc_cache = None
        new._yield_cache = None
        return new

    def with_added_poses(self, poses) -> "ToleranceProblem":
        """A copy with more poses appended (sensitivities computed only for the new ones)."""
        P = self.robot.check_poses(poses)
        J = np.asarray(self.robot.sensitivity(P), dtype=float)
        if not np.all(np.isfinite(J)):
            raise ValidationError(f"{self.robot.name}.sensitivity", P.tolist()[:3], "finite sensitivities at the added poses")
        new = copy.copy(self)
        new.poses = np.vstack([self.poses, P])
        new._set_jacobian(np.concatenate([self.jacobian, J], axis=0))
        new._coeff_cache = {}
        new._mc_cache = None
        new._yield_cache = None
        return new

    def full(self, X_free: np.ndarray) -> np.ndarray:
        """Tolerances of every source from the free variables: (n, n_variables) -> (n, n_sources);
        inserts locked/fixed values and copies each shared variable to all its members."""
        X_free = np.atleast_2d(X_free)
        T = np.empty((X_free.shape[0], self.n_sources))
        T[:, self.free] = X_free
        T[:, self.locked] = self.locked_values[self.locked]
        if self.follower.any():
            T[:, self.follower] = T[:, self.leader[self.follower]]
        return T

    def to_variables(self, A: np.ndarray) -> np.ndarray:
        """Row coefficients per source (..., n_sources) -> per free variable (..., n_variables)
        (a shared variable collects its members' coefficients)."""
        return A @ self.variable_matrix

    def locked_part(self, A: np.ndarray, power: int = 1) -> np.ndarray:
        """Row values of the locked/fixed sources: A[:, locked] @ t_locked**power (zeros if none)."""
        lk = self.locked
        if not lk.any():
            return np.zeros(A.shape[0])
        return A[:, lk] @ self.locked_values[lk] ** power

    def as_array(self, tolerances: Mapping[str, float] | np.ndarray) -> np.ndarray:
        """A design as an array in source order; accepts a name -> value mapping (SI)."""
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
        disk/ball sources [−t, t] (the bound on the norm)."""
        t = self.as_array(t)
        return np.array([self.tolerances[n].interval(t[j]) for j, n in enumerate(self.names)])

    def source_errors(self, Z: list[np.ndarray], t: np.ndarray) -> list[np.ndarray]:
        """Map unit samples Z_j (n, dim_j; |z| <= 1, centred) to errors inside the intervals of
        design t (SI): e_j = offset_j + κ_j t_j + ρ_j t_j z_j (centred sources: t_j z_j)."""
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
        ``include_locked=False``: only the sources driven by a variable (what an optimiser moves)."""
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
        at a time (what the optimum's objective uses; the locked part is a constant)."""
        return sum(float(self.tolerances[n].cost_of(t[j])) for j, n in enumerate(self.names)
                   if self.cost_weight[j] and not self.locked[j])

    def source_costs(self, t) -> np.ndarray:
        t = self.as_array(t)
        return np.array([float(self.tolerances[n].cost_of(t[j])) * self.cost_weight[j] for j, n in enumerate(self.names)])

    def dcost(self, t: np.ndarray) -> np.ndarray:
        """∂cost/∂t_j per source (n_sources,)."""
        return np.array([float(self.tolerances[n].dcost_of(t[j])) * self.cost_weight[j] if self.cost_weight[j] else 0.0
                         for j, n in enumerate(self.names)])

    def variable_dcost(self, t: np.ndarray) -> np.ndarray:
        """∂cost/∂x_v per free variable (n_variables,) at source tolerances t."""
        return self.dcost(t) @ self.variable_matrix

    # --- accuracy -------------------------------------------------------------------------------
    def coefficients(self, component: str):
        """Cached (c[p, d, j], directions, δ[, const[p, d]]) of the worst-case support function
        (const: the offsets' part, only for asymmetric intervals)."""
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
        """The worst-case row at one pose and direction u: h(u) = row·t + const (SI)."""
        if self.shape.plain:
            return np.array([np.linalg.norm(B[pose].T @ u) for B in self.blocks[component]]), 0.0
        blocks = [B[pose:pose + 1] for B in self.blocks[component]]
        row = measures.support_coefficients(blocks, u[None], None if self.shape.plain else self.shape)[0, 0]
        const = 0.0 if self.shape.plain else float(measures.support_constant(blocks, u[None], self.shape)[0, 0])
        return row, const

    def evaluate(self, T, measure: str | None = None, top_only: bool = False) -> Evaluation:
        """Exact errors at every pose of designs T (n, n_sources) under ``measure``
        (default: the requirement's). Returns an :class:`Evaluation`. ``top_only``: exact only at
        the poses that can hold the largest error (faster; enough for feasibility)."""
        T = np.atleast_2d(self.as_array(T))
        measure = measure or self.requirement.measure
        ev = Evaluation(None, None)
        if self.clearances is not None:
            return self._evaluate_clearances(T, measure)
        if measure == "yield":
            return self._evaluate_yield(T)
        viol = np.full(T.shape[0], -np.inf)
        plain = self.shape.plain
        for comp in ("position", "orientation"):
            if measure == "worst_case":
                wc = measures.worst_case(self.blocks[comp], T, coefficients=self.coefficients(comp), top_only=top_only,
                                         shape=None if plain else self.shape)
                val, bound, contrib, direction = wc.value, wc.bound, wc.contributions, wc.direction
            elif measure == "rss":
                Th = T if plain else T * self.shape.rho
                shift = None if plain else np.linalg.norm(measures.mean_shift(self.blocks[comp], self.shape, T), axis=-1)
                val = measures.rss(self.sensitivities[comp], Th, shift)
                bound, direction = val, None
                sq = (Th[:, None, :] * self.sensitivities[comp][None]) ** 2
                if shift is None:
                    contrib = sq / np.where(val ** 2 > 0, val ** 2, 1.0)[..., None]
                else:   # share of the RSS part, scaled by the RSS part's share of the total
                    r = val - shift
                    contrib = sq / np.where(r ** 2 > 0, r ** 2, 1.0)[..., None] * (r / np.where(val > 0, val, 1.0))[..., None]
            elif measure == "mc_quantile":
                val = self._mc_quantile(comp, T)
                bound, direction, contrib = val, None, None
            else:
                raise ValidationError("measure", measure, f"one of {measures.MEASURES}")
            setattr(ev, comp, val)
            setattr(ev, f"{comp}_bound", bound)
            setattr(ev, f"{comp}_contrib", contrib)
            setattr(ev, f"{comp}_direction", direction)
            lim = getattr(self.requirement, comp)
            if lim is not None:
                viol = np.maximum(viol, np.max(val, axis=1) / lim - 1)
        ev.violation = viol
        return ev

    def _evaluate_clearances(self, T: np.ndarray, measure: str) -> Evaluation:
        """The certified worst case of geometric intervals + clearance classes (engine)."""
        if measure != "worst_case":
            raise ValidationError("measure", measure, "'worst_case' with clearance sources")
        if not self.shape.plain:
            raise ValidationError("tolerances", "offset/minus/plus", "centred intervals ±t next to clearance sources")
        wc = clearance_measure.worst_case(self.robot, self.poses, self.jacobian, T, [c for c, _ in self.components])
        ev = Evaluation(None, None)
        viol = np.full(T.shape[0], -np.inf)
        for comp, lim in self.components:
            ev_fields = {"": wc.value, "_bound": wc.bound, "_contrib": wc.contrib, "_direction": wc.direction}
            for suffix, d in ev_fields.items():
                setattr(ev, comp + suffix, d[comp])
            viol = np.maximum(viol, np.max(wc.value[comp], axis=1) / lim - 1)
        ev.violation = viol
        return ev

    def first_order_yield(self) -> statistical.FirstOrderYield:
        """Cached moments of the linear model for the ``yield`` measure."""
        if getattr(self, "_yield_cache", None) is None:
            r = self.requirement
            shift = None if self.shape.plain else (self.shape.rho, self.shape.kappa, self.shape.offset)
            if r.model == "nonlinear":
                self._yield_cache = statistical.SampledYield(self.robot, self.poses, self.distributions,
                                                             dict(self.components), r.mc_samples, r.seed, shift=shift)
            else:
                self._yield_cache = statistical.FirstOrderYield(self.blocks, self.distributions, dict(self.components),
                                                                shift=shift)
        return self._yield_cache

    def _evaluate_yield(self, T: np.ndarray) -> Evaluation:
        y = self.first_order_yield().evaluate(T, self.requirement.required_yield)
        ev = Evaluation(None, None, violation=y.violation, probability=y.probability, exact=y.exact)
        for c in y.miss:
            setattr(ev, c, y.equivalent[c])
            setattr(ev, f"{c}_bound", y.equivalent[c])
            setattr(ev, f"{c}_contrib", y.contributions.get(c))
        return ev

    def max_errors(self, T, measure: str | None = None) -> dict[str, np.ndarray]:
        """Largest error over the poses, per constrained component: name -> (n_designs,)."""
        ev = self.evaluate(T, measure)
        return {c: np.max(getattr(ev, c), axis=1) for c, _ in self.components}

    def check_feasible(self) -> None:
        """Raise :class:`InfeasibleError` if even every free tolerance at its lower bound misses
        the requirement (names the requirement, the smallest achievable error and its pose)."""
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

    def _mc_quantile(self, comp: str, T: np.ndarray) -> np.ndarray:
        """Quantile of |error| over common Latin-hypercube samples of the linear model, per pose."""
        if self._mc_cache is None:
            self._mc_cache = distributions.unit_samples([s.dim for s in self.robot.sources], self.distributions,
                                                        self.requirement.mc_samples, method="lhs", seed=self.requirement.seed)
        Z = self._mc_cache                       # list over sources of (n_samples, dim)
        out = np.empty((T.shape[0], self.n_poses))
        for i, t in enumerate(T):
            E = self.source_errors(Z, t)
            e = sum(np.einsum("pik,sk->psi", B, E[j]) for j, B in enumerate(self.blocks[comp]))
            out[i] = np.quantile(np.linalg.norm(e, axis=2), self.requirement.quantile, axis=1)
        return out

    # --- summary --------------------------------------------------------------------------------
    def describe(self) -> str:
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

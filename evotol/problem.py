"""The tolerance-allocation problem: named error sources with cost models and bounds, an accuracy
requirement over a set of workspace poses, and a robot error model that maps source errors to
end-effector errors.

Design variables are the tolerances t_j (SI units: m or rad; the bound on the norm of source j's
error vector). The problem is a small, printable value plus cached arrays; every evaluation is
vectorised over a population of designs ``T`` of shape (n_designs, n_sources).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from cost_models.base import CostModel
from evotol import distributions, measures, statistical
from evotol.errors import ValidationError
from robots.base import RobotErrorModel

DISTRIBUTIONS = distributions.KINDS


@dataclass(frozen=True)
class Tolerance:
    """Settings of one error source's tolerance.

    cost: cost model of this tolerance (takes t in SI units).
    lower, upper: allowed range of the tolerance (SI: m or rad), 0 < lower <= upper.
    locked: if given, the tolerance is fixed at this value (SI) and not optimised.
    distribution: how the source is distributed inside its tolerance (Monte Carlo and the
        ``yield`` measure): a kind name (``"uniform"``, ``"normal"`` with t = 3σ,
        ``"truncated_normal"``, ``"contact"``) or an :class:`evotol.distributions.Distribution`
        (``sigma_k``, ``mean_shift``); conventions in :mod:`evotol.distributions`.
    """

    cost: CostModel
    lower: float
    upper: float
    locked: float | None = None
    distribution: "str | distributions.Distribution" = "uniform"

    def validate(self, name: str) -> None:
        if not isinstance(self.cost, CostModel):
            raise ValidationError(f"tolerances[{name!r}].cost", self.cost, "a cost_models.CostModel")
        for f in ("lower", "upper"):
            v = getattr(self, f)
            if not isinstance(v, (int, float, np.floating)) or not np.isfinite(v) or v <= 0:
                raise ValidationError(f"tolerances[{name!r}].{f}", v, "a positive finite tolerance in SI units (m or rad)")
        if self.lower > self.upper:
            raise ValidationError(f"tolerances[{name!r}].lower", self.lower, f"<= upper ({self.upper})")
        if self.locked is not None and not (np.isfinite(self.locked) and self.locked > 0):
            raise ValidationError(f"tolerances[{name!r}].locked", self.locked, "a positive tolerance (SI) or None")
        distributions.as_distribution(self.distribution, f"tolerances[{name!r}].distribution")
        self.cost.validate_range(min(self.lower, self.locked or self.lower), max(self.upper, self.locked or self.upper))


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
    """

    position: float | None = None
    orientation: float | None = None
    measure: str = "worst_case"
    quantile: float = 0.95
    mc_samples: int = 2000
    seed: int = 0
    probability: float | None = None
    ppm: float | None = None

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
    poses: (n_poses, workspace.dim) array of workspace poses (SI units).
    n_directions: hemisphere directions for the worst-case measure (more: tighter bound).
    """

    def __init__(self, robot: RobotErrorModel, tolerances: Mapping[str, Tolerance], requirement: Requirement,
                 poses, n_directions: int = 600):
        if not isinstance(robot, RobotErrorModel):
            raise ValidationError("robot", robot, "a robots.base.RobotErrorModel")
        if not isinstance(requirement, Requirement):
            raise ValidationError("requirement", requirement, "an evotol.Requirement")
        requirement.validate()
        names = robot.source_names
        missing = [n for n in names if n not in tolerances]
        extra = [n for n in tolerances if n not in names]
        if missing:
            raise ValidationError("tolerances", sorted(tolerances), f"an entry for every source of {robot.name}; missing {missing}")
        if extra:
            raise ValidationError(f"tolerances[{extra[0]!r}]", extra[0], f"a source of {robot.name}: {list(names)}")
        for n in names:
            if not isinstance(tolerances[n], Tolerance):
                raise ValidationError(f"tolerances[{n!r}]", tolerances[n], "an evotol.Tolerance")
            tolerances[n].validate(n)
        self.robot, self.requirement = robot, requirement
        self.tolerances = {n: tolerances[n] for n in names}
        self.distributions = [distributions.as_distribution(self.tolerances[s.name].distribution,
                                                            f"tolerances[{s.name!r}].distribution", s.dim)
                              for s in robot.sources]
        self.names = names
        self.poses = robot.check_poses(poses)
        self.n_directions = int(n_directions)
        J = np.asarray(robot.sensitivity(self.poses), dtype=float)
        if J.shape != (len(self.poses), 6, robot.n_columns) or not np.all(np.isfinite(J)):
            raise ValidationError(f"{robot.name}.sensitivity", J.shape, f"finite array of shape {(len(self.poses), 6, robot.n_columns)}")
        self.jacobian = J
        self.blocks = {"position": [J[:, 0:3, sl] for sl in robot.column_slices],
                       "orientation": [J[:, 3:6, sl] for sl in robot.column_slices]}
        self.sensitivities = {k: measures.spectral_norms(b) for k, b in self.blocks.items()}
        self.lower = np.array([self.tolerances[n].lower for n in names])
        self.upper = np.array([self.tolerances[n].upper for n in names])
        locked = [self.tolerances[n].locked for n in names]
        self.free = np.array([v is None for v in locked])
        self.locked_values = np.array([np.nan if v is None else v for v in locked])
        if not self.free.any():
            raise ValidationError("tolerances", "all locked", "at least one source free to optimise")
        self._coeff_cache: dict[str, tuple] = {}
        self._mc_cache = None
        self._yield_cache = None

    # --- basic properties ---------------------------------------------------------------------
    @property
    def n_sources(self) -> int:
        return len(self.names)

    @property
    def n_poses(self) -> int:
        return len(self.poses)

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
        import copy
        import dataclasses

        new = copy.copy(self)
        new.requirement = dataclasses.replace(self.requirement, **changes)
        new.requirement.validate()
        new._mc_cache = None
        new._yield_cache = None
        return new

    def full(self, X_free: np.ndarray) -> np.ndarray:
        """Insert locked tolerances: (n, n_free) -> (n, n_sources)."""
        X_free = np.atleast_2d(X_free)
        T = np.empty((X_free.shape[0], self.n_sources))
        T[:, self.free] = X_free
        T[:, ~self.free] = self.locked_values[~self.free]
        return T

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

    # --- cost -----------------------------------------------------------------------------------
    def cost(self, T) -> np.ndarray:
        """Total cost of designs T (n, n_sources) -> (n,); a single design gives a scalar."""
        T = np.asarray(T, dtype=float)
        single = T.ndim == 1
        T2 = np.atleast_2d(T)
        c = np.zeros(T2.shape[0])
        for j, n in enumerate(self.names):
            c += self.tolerances[n].cost.cost(T2[:, j])
        return float(c[0]) if single else c

    def source_costs(self, t) -> np.ndarray:
        t = self.as_array(t)
        return np.array([float(self.tolerances[n].cost.cost(t[j])) for j, n in enumerate(self.names)])

    def dcost(self, t: np.ndarray) -> np.ndarray:
        return np.array([float(self.tolerances[n].cost.dcost(t[j])) for j, n in enumerate(self.names)])

    # --- accuracy -------------------------------------------------------------------------------
    def coefficients(self, component: str):
        """Cached (c[p, d, j], directions, δ) of the worst-case support function."""
        if component not in self._coeff_cache:
            blocks = self.blocks[component]
            D, delta = measures.directions_for(np.concatenate(blocks, axis=2), self.n_directions)
            self._coeff_cache[component] = (measures.support_coefficients(blocks, D), D, delta)
        return self._coeff_cache[component]

    def evaluate(self, T, measure: str | None = None, top_only: bool = False) -> Evaluation:
        """Exact errors at every pose of designs T (n, n_sources) under ``measure``
        (default: the requirement's). Returns an :class:`Evaluation`. ``top_only``: exact only at
        the poses that can hold the largest error (faster; enough for feasibility)."""
        T = np.atleast_2d(self.as_array(T))
        measure = measure or self.requirement.measure
        ev = Evaluation(None, None)
        if measure == "yield":
            return self._evaluate_yield(T)
        viol = np.full(T.shape[0], -np.inf)
        for comp in ("position", "orientation"):
            if measure == "worst_case":
                wc = measures.worst_case(self.blocks[comp], T, coefficients=self.coefficients(comp), top_only=top_only)
                val, bound, contrib, direction = wc.value, wc.bound, wc.contributions, wc.direction
            elif measure == "rss":
                val = measures.rss(self.sensitivities[comp], T)
                bound, direction = val, None
                sq = (T[:, None, :] * self.sensitivities[comp][None]) ** 2
                contrib = sq / np.where(val ** 2 > 0, val ** 2, 1.0)[..., None]
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

    def first_order_yield(self) -> statistical.FirstOrderYield:
        """Cached moments of the linear model for the ``yield`` measure."""
        if getattr(self, "_yield_cache", None) is None:
            self._yield_cache = statistical.FirstOrderYield(self.blocks, self.distributions, dict(self.components))
        return self._yield_cache

    def _evaluate_yield(self, T: np.ndarray) -> Evaluation:
        y = self.first_order_yield().evaluate(T, self.requirement.required_yield)
        ev = Evaluation(None, None, violation=y.violation, probability=y.probability, exact=y.exact)
        for c in y.miss:
            setattr(ev, c, y.equivalent[c])
            setattr(ev, f"{c}_bound", y.equivalent[c])
            setattr(ev, f"{c}_contrib", y.contributions[c])
        return ev

    def max_errors(self, T, measure: str | None = None) -> dict[str, np.ndarray]:
        """Largest error over the poses, per constrained component: name -> (n_designs,)."""
        ev = self.evaluate(T, measure)
        return {c: np.max(getattr(ev, c), axis=1) for c, _ in self.components}

    def _mc_quantile(self, comp: str, T: np.ndarray) -> np.ndarray:
        """Quantile of |error| over common Latin-hypercube samples of the linear model, per pose."""
        if self._mc_cache is None:
            self._mc_cache = distributions.unit_samples([s.dim for s in self.robot.sources], self.distributions,
                                                        self.requirement.mc_samples, method="lhs", seed=self.requirement.seed)
        Z = self._mc_cache                       # list over sources of (n_samples, dim)
        out = np.empty((T.shape[0], self.n_poses))
        for i, t in enumerate(T):
            e = sum(np.einsum("pik,sk->psi", B, Z[j] * t[j]) for j, B in enumerate(self.blocks[comp]))
            out[i] = np.quantile(np.linalg.norm(e, axis=2), self.requirement.quantile, axis=1)
        return out

    # --- summary --------------------------------------------------------------------------------
    def describe(self) -> str:
        r = self.requirement
        lines = [f"ToleranceProblem: {self.robot.name}, {self.n_poses} poses, measure {r.measure}",
                 f"  requirement: position <= {r.position} m, orientation <= {r.orientation} rad"]
        for n, s in zip(self.names, self.robot.sources):
            tol = self.tolerances[n]
            lk = f", locked at {tol.locked:g}" if tol.locked is not None else ""
            lines.append(f"  {n:8s} {s.shape:8s} [{tol.lower:.3g}, {tol.upper:.3g}] {s.unit}  cost {tol.cost!r}{lk}")
        return "\n".join(lines)

    __repr__ = describe

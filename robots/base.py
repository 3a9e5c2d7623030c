"""The robot error-model protocol every plugin in ``robots/`` follows.

A robot error model knows nothing about costs or optimisers. It declares

* its **error sources** (:class:`SourceSpec`): each source is a small vector ``e_j`` of
  dimension ``dim`` whose Euclidean norm is bounded by the source's tolerance ``t_j``:
  ``dim = 1`` is an interval ``|e| <= t`` (a length error, a joint offset), ``dim = 2`` a disk
  (the radial clearance of a revolute joint, Yao et al. 2013 eq. 12), ``dim = 3`` a ball
  (a spherical joint's clearance);
* its **workspace** (:class:`Workspace`): named pose coordinates with units and ranges, so a
  problem can lay a grid or a Latin hypercube over it;
* the **first-order map** ``sensitivity(poses)`` of shape ``(n_poses, 6, n_columns)`` from the
  stacked source vectors to the end-effector error twist ``[dp (m); dtheta (rad)]``
  (``n_columns = sum(dim_j)``; rows 0-2 position in metres, rows 3-5 small rotation in
  radians, both in the base frame; a planar robot fills the rows it does not move with zeros);
* optionally the **nonlinear** ``pose_error(poses, errors)`` that re-solves the kinematics with
  the given source errors, so Monte Carlo verification can measure the linearisation error.

Everything is in SI units inside (m, rad). Poses outside the workspace or at a singularity raise
:class:`evotol.errors.KinematicsError` naming the pose, never return NaN.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from evotol.errors import KinematicsError, ValidationError, is_integer
from evotol.robots.checks import check_robot, robot_checks  # noqa: F401  (the one-call conformance API)
from evotol.units import UNITS

SHAPES = {1: "interval", 2: "disk", 3: "ball"}


@dataclass(frozen=True)
class SourceSpec:
    """One error source of a robot.

    Parameters
    ----------
    name : str
        Unique identifier, e.g. ``"l1"`` or ``"U1a"``.
    dim : {1, 2, 3}
        1 (interval), 2 (disk) or 3 (ball) -- the error is a vector of this size, norm <= t.
    unit : {"m", "rad"}
        The unit of the error vector's components.
    group : str
        Family the source belongs to (``"length"``, ``"U joint"``...), used by cost models,
        reports and the sensitivity rule.
    description : str
        One line for reports.

    Raises
    ------
    evotol.errors.ValidationError
        A ``dim`` other than 1, 2, 3 or a ``unit`` other than ``"m"``, ``"rad"``.
    """

    name: str
    dim: int = 1
    unit: str = "m"
    group: str = "default"
    description: str = ""

    def __post_init__(self):
        if self.dim not in SHAPES:
            raise ValidationError(f"SourceSpec({self.name!r}).dim", self.dim, "1, 2 or 3")
        if self.unit not in UNITS:
            raise ValidationError(f"SourceSpec({self.name!r}).unit", self.unit, f"one of {UNITS}")

    @property
    def shape(self) -> str:
        """The error set's shape: ``"interval"``, ``"disk"`` or ``"ball"`` (from ``dim``)."""
        return SHAPES[self.dim]


@dataclass(frozen=True)
class Workspace:
    """Named pose coordinates with units and closed ranges ``[low, high]``.

    ``units`` are the SI units of the coordinates as the robot takes them (``"m"``, ``"rad"``).
    ``display_scale`` converts each coordinate to the unit shown in reports (e.g. rad -> deg).

    Parameters
    ----------
    names : tuple of str
        Coordinate names, e.g. ``("x", "y", "z")``; their count is the workspace dimension.
    low, high : tuple of float
        Lower and upper bound of each coordinate, in its SI unit (m or rad); ``low == high``
        fixes a coordinate.
    units : tuple of str
        SI unit of each coordinate as the robot takes it (``"m"``, ``"rad"``).
    display_units : tuple of str, optional
        Unit of each coordinate in reports (e.g. ``"mm"``, ``"deg"``); empty (default): ``units``.
    display_scale : tuple of float, optional
        Factor from the SI value to the displayed value, per coordinate (e.g. ``1000`` for m ->
        mm); empty (default): all 1.
    stated : bool, optional
        True (default) when the ranges are a task box the user stated; False when they only bound
        what the robot reaches (a serial arm described without ``[end_effector]`` coordinates,
        :mod:`evotol.robots.mechanism.description.reach`): grids and samples over it are refused.

    Raises
    ------
    evotol.errors.ValidationError
        ``low``, ``high`` or ``units`` without one entry per name, or a range that is not
        finite with ``low <= high``.
    """

    names: tuple[str, ...]
    low: tuple[float, ...]
    high: tuple[float, ...]
    units: tuple[str, ...]
    display_units: tuple[str, ...] = ()
    display_scale: tuple[float, ...] = ()
    stated: bool = True

    def __post_init__(self):
        n = len(self.names)
        for f in ("low", "high", "units"):
            if len(getattr(self, f)) != n:
                raise ValidationError(f"Workspace.{f}", getattr(self, f), f"{n} entries, one per coordinate")
        for name, lo, hi in zip(self.names, self.low, self.high):
            if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                raise ValidationError(f"Workspace range of {name}", (lo, hi), "finite low <= high")
        if not self.display_units:
            object.__setattr__(self, "display_units", self.units)
        if not self.display_scale:
            object.__setattr__(self, "display_scale", tuple(1.0 for _ in self.names))

    @property
    def dim(self) -> int:
        """Number of pose coordinates (dimensionless count)."""
        return len(self.names)

    def grid(self, counts: int | Sequence[int]) -> np.ndarray:
        """Full grid with ``counts`` points per coordinate, shape (prod(counts), dim).

        Parameters
        ----------
        counts : int or sequence of int
            Points per coordinate, one count for all or one per coordinate; a count of 1 takes the
            range's midpoint, more are evenly spaced from ``low`` to ``high`` inclusive. Whole
            floats (``3.0``) are accepted.

        Returns
        -------
        (prod(counts), dim) ndarray
            The grid poses in SI units (m, rad), first coordinate varying slowest
            (``indexing="ij"``).

        Raises
        ------
        evotol.errors.ValidationError
            Not one count per coordinate, a non-whole count, or a count below 1.
        """
        counts = [counts] * self.dim if np.isscalar(counts) else list(counts)
        whole = all(isinstance(c, (int, np.integer)) and not isinstance(c, bool) or
                    isinstance(c, (float, np.floating)) and float(c).is_integer() for c in counts)
        if len(counts) != self.dim or not whole or any(int(c) < 1 for c in counts):   # 3.5 was truncated to 3
            raise ValidationError("grid counts", counts, f"{self.dim} positive integers")
        axes = [np.linspace(lo, hi, int(c)) if c > 1 else np.array([(lo + hi) / 2])
                for lo, hi, c in zip(self.low, self.high, counts)]
        mesh = np.meshgrid(*axes, indexing="ij")
        return np.stack([m.ravel() for m in mesh], axis=1)

    def latin_hypercube(self, n: int, seed: int | None = 0) -> np.ndarray:
        """``n`` Latin-hypercube poses (scipy.stats.qmc), shape (n, dim), reproducible from seed.

        Parameters
        ----------
        n : int
            Number of poses, at least 1.
        seed : int or None, optional
            Seed of the Latin hypercube sampler; ``None`` draws a fresh one (not reproducible).

        Returns
        -------
        (n, dim) ndarray
            Poses inside ``[low, high]`` per coordinate, in SI units (m, rad).

        Raises
        ------
        evotol.errors.ValidationError
            ``n`` is not a positive integer (bools and floats are refused).
        """
        from scipy.stats import qmc

        if not is_integer(n, 1):   # 3.5 was truncated to 3
            raise ValidationError("latin_hypercube n", n, "a positive integer")
        u = qmc.LatinHypercube(d=self.dim, seed=seed).random(int(n))
        # affine map rather than qmc.scale, which rejects a fixed coordinate (low == high)
        lo, hi = np.asarray(self.low, float), np.asarray(self.high, float)
        return lo + u * (hi - lo)

    def contains(self, poses: np.ndarray, rtol: float = 1e-9) -> np.ndarray:
        """Which poses lie inside the workspace box, with a small tolerance.

        Parameters
        ----------
        poses : (n, dim) or (dim,) array_like
            Poses in SI units (m, rad).
        rtol : float, optional
            Tolerance, relative to each coordinate's span (a span below 1 counts as 1, so it is
            absolute there, in m or rad); dimensionless.

        Returns
        -------
        (n,) ndarray of bool
            True where every coordinate is within ``[low - rtol span, high + rtol span]``.
        """
        poses = np.atleast_2d(poses)
        lo, hi = np.asarray(self.low), np.asarray(self.high)
        span = np.maximum(hi - lo, 1.0)
        return np.all((poses >= lo - rtol * span) & (poses <= hi + rtol * span), axis=1)


class RobotErrorModel:
    """Base class of robot error models (see the module docstring for the contract).

    Subclasses set ``name``, ``sources`` and ``workspace`` and implement ``sensitivity``;
    ``pose_error`` (nonlinear propagation) is optional.

    Examples
    --------
    >>> from evotol import RobotErrorModel
    >>> from evotol.robots.ucr3 import UCR3
    >>> robot = UCR3()                                          # the 3-UCR parallel robot
    >>> isinstance(robot, RobotErrorModel), robot.workspace.names
    (True, ('alpha', 'beta', 'Zc'))
    >>> robot.sensitivity([[0.0, 0.0, 0.28]]).shape            # (n_poses, 6, n_columns)
    (1, 6, 21)
    """

    name: str = "robot"
    sources: tuple[SourceSpec, ...] = ()
    workspace: Workspace
    #: the part this model adds to the model it wraps (:data:`PARTS`); None for a robot as described
    part: str | None = None
    #: the model this one wraps (None for a robot as described)
    base: "RobotErrorModel | None" = None
    #: True when the model also maps joint values (``sensitivity_at_joints``, ``pose_error_at_joints``,
    #: ``joint_values``, ``kin``, ``mechanism``): a described mechanism and the parts that keep its joints
    joint_maps: bool = False

    #: (dropped, total, the first five dropped poses) set on the robot as described by ``[poses]
    #: drop_unreachable`` (evotol/studyfile/joint_poses.py); None: none dropped. Not a field: set after reading.
    dropped_poses = None

    # --- composition (docs/architecture.md, "The error model, composed") ----------------------
    @property
    def tied_sources(self) -> Mapping[str, tuple[str, ...]]:
        """Callout name -> its member sources, costed as one tolerance; every part keeps its base's ties."""
        return self.base.tied_sources if self.base is not None else {}

    def parts(self) -> tuple["RobotErrorModel", ...]:
        """The models of the composition, from the outside in (this model first, the described robot last).

        Returns
        -------
        tuple of RobotErrorModel
            Each part's model.
        """
        out, model = [], self
        while model is not None:
            out.append(model)
            model = model.base
        return tuple(out)

    def part_of(self, kind: str) -> "RobotErrorModel | None":
        """The model of the composition that adds ``kind`` (one of :data:`PARTS`), or None.

        Parameters
        ----------
        kind : str
            ``"callouts"``, ``"joint_space"``, ``"axis_limits"``, ``"calibration"`` or ``"clearances"``.

        Returns
        -------
        RobotErrorModel or None
            That part's model.

        Raises
        ------
        ValueError
            ``kind`` is not one of :data:`PARTS` (a misspelt part would otherwise read as absent).
        """
        if kind not in PARTS:
            raise ValueError(f"part {kind!r}: expected one of {PARTS}")
        return next((m for m in self.parts() if m.part == kind), None)

    def notes(self) -> list[str]:
        """Sentences the report states about the model (a redundant arm's posture, a dropped pose, ...).

        Returns
        -------
        list of str
            The base model's notes for a part; for a described robot, the poses dropped as unreachable
            (:attr:`dropped_poses`), if any.
        """
        if self.base is not None:
            return list(self.base.notes())
        return [dropped_line(self.dropped_poses)] if self.dropped_poses else []

    @property
    def described(self) -> "RobotErrorModel":
        """The robot as the user described it: the innermost model of the composition."""
        return self.parts()[-1]

    def rebuilt(self, inner: "RobotErrorModel") -> "RobotErrorModel":
        """This part around another inner model (a part overrides it; the described robot has none).

        Parameters
        ----------
        inner : RobotErrorModel
            The model to wrap instead of ``base``.

        Returns
        -------
        RobotErrorModel
            The same part on ``inner``.

        Raises
        ------
        NotImplementedError
            A model that is not a part of a composition.
        """
        raise NotImplementedError(f"{type(self).__name__} cannot be rebuilt on another model")

    def with_part(self, kind: str, change) -> "RobotErrorModel":
        """The composition with the part ``kind`` replaced by ``change(part_model)`` and the outer parts rebuilt.

        Parameters
        ----------
        kind : str
            One of :data:`PARTS`, present in the composition.
        change : callable
            ``change(model) -> model``: the new model of that part (e.g. callouts under boxes).

        Returns
        -------
        RobotErrorModel
            The new composition (this model is not changed).

        Raises
        ------
        ValueError
            No part ``kind`` in the composition.
        """
        chain = self.parts()
        k = next((i for i, m in enumerate(chain) if m.part == kind), None)
        if k is None:
            raise ValueError(f"{self.name}: no {kind!r} part in the composition {[m.part for m in chain]}")
        model = change(chain[k])
        for outer in reversed(chain[:k]):
            model = outer.rebuilt(model)
        return model

    def nonlinear_checks(self, problem, t, seed: int = 0) -> dict:
        """The checks the parts of the composition add to a Monte Carlo verification on the nonlinear model.

        :func:`evotol.verification.verify` calls this on the problem's model and stores the result as
        ``MonteCarloResult.part_checks``; it knows no part by name. A part adds its own entries to its
        base's (the calibration part: ``"calibration"``, the simulated calibration of the design).

        Parameters
        ----------
        problem : evotol.core.problem.ToleranceProblem
            The problem being verified.
        t : (n_sources,) ndarray
            The design (SI).
        seed : int
            The verification's seed.

        Returns
        -------
        dict
            Check name -> a result with ``to_dict()``; empty for a robot as described.
        """
        return self.base.nonlinear_checks(problem, t, seed) if self.base is not None else {}

    def clearance_mechanism(self):
        """The robot's joints with their clearances (:class:`evotol.robots.clearance.ClearanceMechanism`).

        A part keeps its base's; a robot without joint clearances refuses in one line.

        Returns
        -------
        evotol.robots.clearance.ClearanceMechanism
            The clearance model of the described robot.

        Raises
        ------
        evotol.errors.ValidationError
            A robot whose plugin declares no joint clearances.
        """
        if self.base is not None:
            return self.base.clearance_mechanism()
        raise ValidationError("clearances", self.name, "a robot with joint clearances (its plugin defines "
                              "clearance_mechanism())")

    def __repr__(self) -> str:
        """One line: the class, the robot's name and its counts (``<... object at 0x...>`` before)."""
        try:
            counts = f", {len(self.sources)} sources, {self.n_columns} error columns"
        except AttributeError:     # a half-built model (a subclass's __init__ failed): the name alone
            counts = ""
        return f"{type(self).__name__}(name={self.name!r}{counts})"

    # --- contract -----------------------------------------------------------------------

    def sensitivity(self, poses: np.ndarray) -> np.ndarray:
        """First-order map, shape (n_poses, 6, n_columns): [dp (m); dtheta (rad)] per unit error.

        Parameters
        ----------
        poses : (n_poses, workspace.dim) ndarray
            Poses in the workspace coordinates, SI units (m, rad).

        Returns
        -------
        (n_poses, 6, n_columns) ndarray
            End-effector error twist per unit of each stacked source component: rows 0-2
            position (m per source unit), rows 3-5 small rotation (rad per source unit), base frame.

        Raises
        ------
        NotImplementedError
            Always, in the base class: a subclass implements it.
        """
        raise NotImplementedError

    def pose_error(self, poses: np.ndarray, errors: np.ndarray) -> np.ndarray:
        """Nonlinear end-effector error twist for given source errors.

        Parameters
        ----------
        poses : (n_poses, workspace.dim) ndarray
            Poses in the workspace coordinates, SI units (m, rad).
        errors : (n_poses, n_samples, n_columns) ndarray
            Stacked source error vectors, in each source's unit (m or rad).

        Returns
        -------
        (n_poses, n_samples, 6) ndarray
            [dp (m); small-rotation vector (rad)] of the end effector, base frame.

        Raises
        ------
        NotImplementedError
            Always, in the base class (the robot has no nonlinear error model); a subclass may
            implement it.
        """
        raise NotImplementedError(f"{self.name} has no nonlinear error model")

    @property
    def has_nonlinear_model(self) -> bool:
        """True when the subclass overrides :meth:`pose_error` (nonlinear model available)."""
        return type(self).pose_error is not RobotErrorModel.pose_error

    def without_nonlinear_model(self) -> str:
        """Why this model has no nonlinear :meth:`pose_error`, said of the model the user built: the parts of
        the composition that have none when the described robot has one, else the robot.

        Returns
        -------
        str
            ``"UR5 has one, but not with its calibration part"``, or ``"<name> has none"``.
        """
        lacking = [m.part for m in self.parts() if m.part and not m.has_nonlinear_model]
        if lacking and self.described.has_nonlinear_model:
            return f"{self.described.name} has one, but not with its {' and '.join(lacking)} part"
        return f"{self.name} has none"

    # --- helpers ------------------------------------------------------------------------
    @property
    def source_names(self) -> tuple[str, ...]:
        """Names of the error sources, in source order."""
        return tuple(s.name for s in self.sources)

    @property
    def column_slices(self) -> tuple[slice, ...]:
        """Slice of the stacked error vector that belongs to each source, in source order."""
        out, start = [], 0
        for s in self.sources:
            out.append(slice(start, start + s.dim))
            start += s.dim
        return tuple(out)

    @property
    def n_columns(self) -> int:
        """Length of the stacked error vector, ``sum(dim_j)`` over the sources (dimensionless)."""
        return sum(s.dim for s in self.sources)

    def check_poses(self, poses) -> np.ndarray:
        """Validate an array of poses against the workspace; returns float array (n, dim).

        Parameters
        ----------
        poses : (n, workspace.dim) or (workspace.dim,) array_like
            Poses in SI units (m, rad); a single pose is promoted to one row.

        Returns
        -------
        (n, workspace.dim) ndarray of float
            The poses.

        Raises
        ------
        evotol.errors.ValidationError
            Not convertible to numbers, the wrong shape, or a non-finite entry.
        evotol.errors.KinematicsError
            A pose outside the workspace (see :meth:`Workspace.contains`); names the first one.
        """
        try:
            arr = np.asarray(poses, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ValidationError("poses", poses, "an array of numbers") from exc
        if arr.ndim == 1:
            arr = arr[None, :]
        if arr.ndim != 2 or arr.shape[1] != self.workspace.dim:
            raise ValidationError("poses shape", arr.shape, f"(n, {self.workspace.dim}) with columns {self.workspace.names}")
        bad = ~np.all(np.isfinite(arr), axis=1)
        if bad.any():
            raise ValidationError("poses", arr[bad][0].tolist(), "finite numbers")
        outside = ~self.workspace.contains(arr)
        if outside.any():
            raise KinematicsError(
                f"{self.name}: pose {arr[outside][0].tolist()} ({', '.join(self.workspace.names)}) "
                f"is outside the workspace {list(zip(self.workspace.low, self.workspace.high))}",
                poses=arr[outside])
        return arr


#: the parts a model can be composed of, in the order they are composed (docs/architecture.md):
#: source transforms of the described robot (callouts), the pose set (joint configurations), the
#: calibration projection, the requirement's components (per-axis limits), joint clearances
def dropped_line(dropped: tuple) -> str:
    """The report line on poses dropped as unreachable (``RobotErrorModel.dropped_poses``).

    Parameters
    ----------
    dropped : tuple
        ``(dropped, total, first five dropped poses (SI))``.

    Returns
    -------
    str
        One sentence.
    """
    n, total, first = dropped
    return (f"{n} of {total} poses dropped ([poses] drop_unreachable): out of reach, singular, outside the joint "
            f"limits or on another branch; the first (SI): {first}.")


PARTS = ("callouts", "joint_space", "calibration", "axis_limits", "clearances")

"""The accuracy requirement: bounds on the end-effector's position and orientation errors and the
measure (a name in :mod:`evotol.measures.registry`) that judges them."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.measures import statistical
from evotol.measures import registry as measure_registry
from evotol.errors import ValidationError, is_integer, is_real
from evotol.units.quantity import parse_quantity


@dataclass(frozen=True)
class Requirement:
    """Accuracy the end-effector must hold at every pose.

    Parameters
    ----------
    position : float or str or None
        Bound on the position error ``|δp|`` (m, or a string with its unit such as ``"0.5 mm"``,
        ``docs/units.md``), or None.
    orientation : float or str or None
        Bound on the orientation error ``|δθ|`` (rad, or ``"0.1 mrad"``, ``"30 arcsec"``), or None.
        At least one of the two is given.
    measure : str
        The name of a registered measure (:mod:`evotol.measures.registry`); built in:
        ``"worst_case"`` (exact for the linear model, see :mod:`evotol.measures.linear`), ``"rss"`` (root
        sum square of the sources' worst-case effects), ``"mc_quantile"`` (the ``quantile`` of
        ``|δp|`` over ``mc_samples`` Latin-hypercube samples, linear model), or ``"yield"``: at
        every pose P(``|δp|`` ≤ position and ``|δθ|`` ≤ orientation) ≥ ``probability`` for the
        first-order model (:mod:`evotol.measures.statistical`; Bonferroni bound for both).
    quantile : float
        Quantile of the ``mc_quantile`` measure, in (0, 1) (1, dimensionless).
    mc_samples : int
        Latin-hypercube samples of the ``mc_quantile`` measure and of the nonlinear ``yield``
        (at least 10).
    seed : int
        Seed of those samples (a non-negative integer).
    probability : float or None
        Required yield of the ``yield`` measure in (0, 1) (default 0.9973 = 3σ), or
    ppm : float or None
        the same given as allowed defects per million (probability = 1 − ppm·1e-6).
    model : {"linear", "nonlinear"}
        ``"linear"`` (first-order model, exact probability) or ``"nonlinear"`` (``yield`` only:
        the robot's ``pose_error`` on ``mc_samples`` common Latin-hypercube samples from
        ``seed``, :class:`evotol.measures.statistical.SampledYield`).

    Notes
    -----
    A plain value: nothing is checked at construction. :meth:`validate` (called by
    :class:`evotol.core.problem.ToleranceProblem`) raises :class:`evotol.errors.ValidationError`.

    Examples
    --------
    >>> from evotol import Requirement
    >>> req = Requirement(position=5e-5, measure="rss")      # RSS position error <= 0.05 mm
    >>> req.validate()
    >>> req.measure, req.position, req.orientation
    ('rss', 5e-05, None)
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

    def __post_init__(self):
        # a bound written with its unit ("0.5 mm", "0.5*mm", "0.1 mrad": the one unit grammar,
        # evotol.units.quantity) is read to SI here, in Python as in a study file
        for f, kind in (("position", "length"), ("orientation", "angle")):
            v = getattr(self, f)
            if isinstance(v, str):
                object.__setattr__(self, f, parse_quantity(v, f"requirement.{f}", kind))

    @property
    def required_yield(self) -> float:
        """The yield the ``yield`` measure requires (from ``probability`` or ``ppm``)."""
        if self.ppm is not None:
            return 1.0 - float(self.ppm) * 1e-6
        return 0.9973 if self.probability is None else float(self.probability)

    def validate(self) -> None:
        """Check the requirement.

        Raises
        ------
        evotol.errors.ValidationError
            No bound, a non-positive bound, an unknown ``measure`` or ``model``, a ``quantile``,
            ``probability`` or ``ppm`` out of range, both ``probability`` and ``ppm``, or
            ``mc_samples`` not an integer >= 10, or a ``seed`` that is not a non-negative integer.
        """
        if self.position is None and self.orientation is None:
            raise ValidationError("requirement", self, "a position and/or orientation bound")
        for f in ("position", "orientation"):
            v = getattr(self, f)
            if v is not None and not (isinstance(v, (int, float, np.floating)) and np.isfinite(v) and v > 0):
                raise ValidationError(f"requirement.{f}", v, "a positive bound (m for position, rad for orientation) or None")
        measure_registry.get(self.measure, field="requirement.measure")
        q = self.quantile
        if not (is_real(q) and 0 < q < 1):
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
        n = self.mc_samples
        if not is_integer(n, 10):
            raise ValidationError("requirement.mc_samples", n, "an integer >= 10 (samples)")
        if not is_integer(self.seed, 0):
            raise ValidationError("requirement.seed", self.seed, "a non-negative integer (random seed)")


"""Machining cost plus a quadratic (Taguchi) quality-loss term of the same tolerance.

``c(t) = c_m(t) + q·t²``: ``c_m`` is any cost model (the machining cost, non-increasing in t) and
``q·t² >= 0`` the expected quality loss the tolerance causes (``evotol.core.quality_loss`` computes
``q`` from the loss coefficients and the sensitivities; docs/process_selection.md, "Quality
loss"). The sum is convex when ``c_m`` is, but it is **not** monotone: a loose tolerance is cheap
to machine and dear in loss, so the optimum may lie inside the requirement. The range check
therefore checks the machining model only.
"""
from __future__ import annotations

import numpy as np

from evotol.cost_models.base import CostModel
from evotol.errors import ValidationError


class QualityLossCost(CostModel):
    """``c_m(t) + q·t²`` (t SI; q in cost units per SI unit², >= 0).

    Parameters
    ----------
    machining : CostModel
        The machining cost–tolerance model (validated as usual: positive, non-increasing).
    q : float
        Loss coefficient per squared tolerance, ``q = Σ_k K_k (∂Y_k/∂x)² / 9`` for σ = t/3.

    Raises
    ------
    ValidationError
        ``machining`` is not a cost model, or ``q`` is negative or not finite.
    """

    name = "quality_loss"
    param_names = ()

    def __init__(self, machining: CostModel, q: float):
        if not isinstance(machining, CostModel):
            raise ValidationError("QualityLossCost machining", machining, "a cost_models CostModel")
        try:
            q = float(q)
        except (TypeError, ValueError):
            raise ValidationError("QualityLossCost q", q, "a finite number >= 0 (cost per SI unit²)") from None
        if not (np.isfinite(q) and q >= 0):
            raise ValidationError("QualityLossCost q", q, "a finite number >= 0 (cost per SI unit²)")
        self.machining, self.q = machining, q
        self.p = np.zeros(0)
        self.scale = machining.scale
        self.convex = machining.convex

    @property
    def params(self) -> dict[str, float]:
        """The machining model's coefficients (keyed ``"machining.<name>"``) and ``q`` (cost per SI unit²)."""
        return {**{f"machining.{k}": v for k, v in self.machining.params.items()}, "q": self.q}

    def cost(self, t) -> np.ndarray:
        """Machining cost plus quality loss, ``c_m(t) + q·t²``."""
        t = np.asarray(t, dtype=float)
        return self.machining.cost(t) + self.q * t ** 2

    def dcost(self, t) -> np.ndarray:
        """``c_m'(t) + 2·q·t``."""
        t = np.asarray(t, dtype=float)
        return self.machining.dcost(t) + 2 * self.q * t

    def d2cost(self, t) -> np.ndarray:
        """``c_m''(t) + 2·q``."""
        return self.machining.d2cost(t) + 2 * self.q

    __call__ = cost

    def loss(self, t) -> np.ndarray:
        """The quality-loss part ``q·t²`` alone (cost units).

        Parameters
        ----------
        t : float or array_like
            Tolerance(s) in SI units (m or rad), any shape.

        Returns
        -------
        ndarray
            ``q·t²`` (cost units), same shape as ``t``.
        """
        return self.q * np.asarray(t, dtype=float) ** 2

    def validate_range(self, t_min: float, t_max: float | None, n: int = 257) -> None:
        """The machining model's range check (the loss term is increasing by design); ``t_max = None``
        means ``100 * scale`` of the machining model.
        """
        self.machining.validate_range(t_min, t_max, n)

    def __repr__(self) -> str:
        return f"QualityLossCost({self.machining!r}, q={self.q:.6g})"

    def to_dict(self) -> dict:
        """The model as ``{"model": "quality_loss", "machining": <its to_dict()>, "q": q}`` (q in cost per
        SI unit²). :func:`evotol.cost_models.registry.from_dict` does not rebuild it: ``quality_loss`` is not a
        registered model name.
        """
        return {"model": self.name, "machining": self.machining.to_dict(), "q": self.q}

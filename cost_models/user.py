"""User cost models: from a Python callable, or registered by another package as an entry point.

A package registers a model class under the entry-point group ``evotol.cost_models``::

    [project.entry-points."evotol.cost_models"]
    my_model = "my_pkg.costs:MyCost"     # a CostModel subclass
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from evotol.cost_models.base import CostModel
from evotol.errors import ValidationError


class CallableCost(CostModel):
    """Wraps ``func(x)`` (and optionally ``dfunc(x)``), x = t/scale; derivative by central differences otherwise.

    It has no coefficients (``params`` is empty); it pickles only when ``func`` does, and a study
    file cannot name it (``to_dict`` records the callable's name, not its code).

    Parameters
    ----------
    func : callable
        ``func(x)``: the cost (cost units) at ``x = t / scale``, an ndarray of any shape; a scalar
        or broadcastable result is broadcast to the shape of ``x``.
    dfunc : callable, optional
        ``dfunc(x)``: d cost / dx (cost units per shop unit), same shape as ``x``; by default
        central differences of ``func`` (relative step 1e-6).
    name : str, default "user"
        The model's name, as reports show it.
    scale : float, default 1.0
        SI size (m or rad) of the tolerance unit ``x`` is measured in.
    convex : bool, default False
        Whether the cost is convex in ``t`` (lets allocators certify optima; the conformance
        check verifies it on a range).
    t_min : float, optional
        Smallest tolerance used (SI). When ``t_min`` or ``t_max`` is given, the construction
        checks that the cost is non-negative and non-increasing on the range; a missing
        ``t_min`` then means 0.
    t_max : float, optional
        Largest tolerance used (SI); missing while ``t_min`` is given means ``100 * scale``.

    Raises
    ------
    ValidationError
        ``func`` is not callable, ``dfunc`` is neither callable nor None, ``scale`` is not
        positive, or the cost is negative or increasing on a given range.
    """

    param_names = ()
    convex = False

    def __init__(self, func: Callable, dfunc: Callable | None = None, *, name: str = "user",
                 scale: float = 1.0, convex: bool = False, t_min: float | None = None,
                 t_max: float | None = None):
        if not callable(func):
            raise ValidationError("CallableCost func", func, "a callable cost(x)")
        if dfunc is not None and not callable(dfunc):
            raise ValidationError("CallableCost dfunc", dfunc, "a callable d cost/dx or None")
        self.func, self.dfunc = func, dfunc
        self.name = str(name)
        self.convex = bool(convex)
        super().__init__(scale=scale, t_min=t_min, t_max=t_max)

    def _f(self, x):
        out = np.asarray(self.func(x), dtype=float)
        return np.broadcast_to(out, np.shape(x)).copy() if out.shape != np.shape(x) else out

    def _df(self, x):
        if self.dfunc is not None:
            return np.asarray(self.dfunc(x), dtype=float)
        h = 1e-6 * np.maximum(np.abs(x), 1e-8)
        return (self._f(x + h) - self._f(x - h)) / (2 * h)

    def to_dict(self):
        """A record of the model: its name, the callable's qualified name and ``scale``.

        :func:`evotol.cost_models.registry.from_dict` cannot rebuild it (the code is not stored).

        Returns
        -------
        dict
            ``{"model": name, "callable": qualname, "scale": scale}`` (``scale`` in SI).
        """
        return {"model": self.name, "callable": getattr(self.func, "__qualname__", repr(self.func)), "scale": self.scale}


def entry_point_models() -> dict[str, type]:
    """Cost-model classes registered by installed packages under ``evotol.cost_models``.

    Returns
    -------
    dict of str to type
        ``{entry-point name: CostModel subclass}`` (empty when none is installed).

    Raises
    ------
    ValidationError
        An entry point loads something that is not a CostModel subclass.
    """
    from evotol._runtime.plugins import group_entry_points

    found = {}
    for ep in group_entry_points("evotol.cost_models"):
        cls = ep.load()
        if not (isinstance(cls, type) and issubclass(cls, CostModel)):
            raise ValidationError(f"entry point evotol.cost_models:{ep.name}", cls, "a CostModel subclass")
        found[ep.name] = cls
    return found

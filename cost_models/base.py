"""The cost–tolerance model protocol and its conformance check.

A cost model is a function of one tolerance ``t`` (SI units: m or rad). Coefficients are usually
quoted for tolerances in a shop unit (e.g. 1e-5 m for Yao et al. 2013, or mm); ``scale`` is that
unit in SI, so every model evaluates ``f(t / scale)`` with ``f`` the textbook formula.

Contract (see :func:`cost_models.checks.check_cost_model`): vectorised ``cost(t)`` and ``dcost(t)`` (d cost / d t,
per SI unit), ``params`` (a dict), ``name``; the cost is positive and non-increasing on the
allowed range ``[t_min, t_max]`` (SI), which :meth:`CostModel.validate_range` checks with a clear
message naming the model, the parameters and where it fails.
"""
from __future__ import annotations

from typing import ClassVar

import numpy as np

from evotol.errors import ValidationError


class CostModel:
    """Base class: subclasses define ``name``, ``param_names`` and ``_f(x)``, ``_df(x)`` in shop units."""

    name: ClassVar[str] = "cost"
    param_names: ClassVar[tuple[str, ...]] = ()
    formula: ClassVar[str] = ""
    #: True when the model is convex in t for every valid parameter set (allocators then may
    #: certify optima); models whose convexity depends on parameters check it in ``is_convex``.
    convex: ClassVar[bool] = True
    #: representative parameters (shop units, ``scale = 1e-5`` m) for :meth:`example`, which the
    #: conformance test builds for every registered model; a plugin sets its own
    example_params: ClassVar[tuple[float, ...] | None] = None

    def __init__(self, *params: float, scale: float = 1.0, t_min: float | None = None,
                 t_max: float | None = None, **kw: float):
        names = self.param_names
        if params and kw:
            raise ValidationError(f"{self.name} parameters", (params, kw), "positional or keyword, not both")
        if kw:
            unknown = set(kw) - set(names)
            if unknown:
                raise ValidationError(f"{self.name} parameter", sorted(unknown)[0], f"one of {names}")
            missing = [n for n in names if n not in kw]
            if missing:
                raise ValidationError(f"{self.name} parameter {missing[0]}", None, "a value")
            params = tuple(kw[n] for n in names)
        if len(params) != len(names):
            raise ValidationError(f"{self.name} parameters", params, f"{len(names)} values {names}")
        vals = []
        for n, v in zip(names, params):
            try:
                fv = float(v)
            except (TypeError, ValueError):
                raise ValidationError(f"{self.name}.{n}", v, "a real number") from None
            if not np.isfinite(fv):
                raise ValidationError(f"{self.name}.{n}", v, "a finite number")
            vals.append(fv)
        self.p = np.array(vals)
        try:
            self.scale = float(scale)
        except (TypeError, ValueError):
            raise ValidationError(f"{self.name}.scale", scale, "a positive number (SI size of the coefficient unit)") from None
        if not (np.isfinite(self.scale) and self.scale > 0):
            raise ValidationError(f"{self.name}.scale", scale, "a positive number (SI size of the coefficient unit)")
        self._check_params()
        if t_min is not None or t_max is not None:
            self.validate_range(t_min if t_min is not None else 0.0, t_max)

    @classmethod
    def example(cls) -> "CostModel":
        """A representative instance (``example_params``, ``scale = 1e-5`` m, used on 0.5-8 x scale)."""
        if cls.example_params is None:
            raise NotImplementedError(f"{cls.__name__} sets no example_params (needed by the conformance test)")
        return cls(*cls.example_params, scale=1e-5)

    # --- to implement ----------------------------------------------------------------------
    def _f(self, x: np.ndarray) -> np.ndarray:  # cost at x = t/scale
        raise NotImplementedError

    def _df(self, x: np.ndarray) -> np.ndarray:  # d cost / dx
        raise NotImplementedError

    def _d2f(self, x: np.ndarray) -> np.ndarray:  # second derivative, finite differences by default
        h = 1e-6 * np.maximum(np.abs(x), 1e-6)
        return (self._df(x + h) - self._df(x - h)) / (2 * h)

    def _check_params(self) -> None:
        """Parameter checks that do not need a range (e.g. signs)."""

    # --- public API --------------------------------------------------------------------------
    @property
    def params(self) -> dict[str, float]:
        return dict(zip(self.param_names, self.p.tolist()))

    def cost(self, t) -> np.ndarray:
        """Cost of tolerance ``t`` (SI), vectorised."""
        return self._f(np.asarray(t, dtype=float) / self.scale)

    def dcost(self, t) -> np.ndarray:
        """d cost / d t (per SI unit), vectorised."""
        return self._df(np.asarray(t, dtype=float) / self.scale) / self.scale

    def d2cost(self, t) -> np.ndarray:
        """d² cost / d t² (per SI unit²), vectorised."""
        return self._d2f(np.asarray(t, dtype=float) / self.scale) / self.scale ** 2

    __call__ = cost

    def is_convex(self, t_min: float, t_max: float, n: int = 257) -> bool:
        """Whether the cost is convex on [t_min, t_max] (checked on a log-spaced grid)."""
        t = _range_grid(t_min, t_max, n)
        d2 = self.d2cost(t)
        return bool(np.all(d2 >= -1e-9 * np.max(np.abs(d2)) - 1e-300))

    def validate_range(self, t_min: float, t_max: float | None, n: int = 257) -> None:
        """Reject parameters that make the cost negative or increasing in t on [t_min, t_max] (SI)."""
        if t_max is None:
            t_max = 100 * self.scale
        if not (np.isfinite(t_min) and np.isfinite(t_max) and 0 <= t_min <= t_max):
            raise ValidationError(f"{self.name} tolerance range", (t_min, t_max), "0 <= t_min <= t_max, finite (SI units)")
        t = _range_grid(t_min, t_max, n) if t_max > t_min else np.array([t_max])
        c, dc = self.cost(t), self.dcost(t)
        bad = np.flatnonzero(~np.isfinite(c) | (c < 0))
        if bad.size:
            i = bad[0]
            raise ValidationError(f"{self.name}{self.params}", f"cost({t[i]:.6g}) = {c[i]:.6g}",
                                  f"a non-negative finite cost on [{t_min:.6g}, {t_max:.6g}] (SI)")
        tol = 1e-9 * max(1.0, float(np.max(np.abs(dc))))
        bad = np.flatnonzero(dc > tol)
        if bad.size:
            i = bad[0]
            raise ValidationError(f"{self.name}{self.params}", f"dcost/dt({t[i]:.6g}) = {dc[i]:.6g} > 0",
                                  f"a cost that does not increase with the tolerance on [{t_min:.6g}, {t_max:.6g}] (SI)")

    def __repr__(self) -> str:
        ps = ", ".join(f"{k}={v:.6g}" for k, v in self.params.items())
        return f"{type(self).__name__}({ps}, scale={self.scale:g})"

    def to_dict(self) -> dict:
        return {"model": self.name, **self.params, "scale": self.scale}


def _range_grid(t_min: float, t_max: float, n: int) -> np.ndarray:
    # t = 0 is excluded: most models are unbounded there and no tolerance is exactly zero.
    lo = t_min if t_min > 0 else t_max * 1e-6
    return np.unique(np.concatenate([np.geomspace(lo, t_max, n), np.linspace(lo, t_max, n)]))

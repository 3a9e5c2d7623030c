"""The cost–tolerance model protocol and its conformance check.

A cost model is a function of one tolerance ``t`` (SI units: m or rad). Coefficients are usually
quoted for tolerances in a shop unit (e.g. 1e-5 m for Yao et al. 2013, or mm); ``scale`` is that
unit in SI, so every model evaluates ``f(t / scale)`` with ``f`` the textbook formula.

Contract (see :func:`evotol.cost_models.checks.check_cost_model`): vectorised ``cost(t)`` and ``dcost(t)`` (d cost / d t,
per SI unit), ``params`` (a dict), ``name``; the cost is positive and non-increasing on the
allowed range ``[t_min, t_max]`` (SI), which :meth:`CostModel.validate_range` checks with a clear
message naming the model, the parameters and where it fails.
"""
from __future__ import annotations

from typing import ClassVar

import numpy as np

from evotol.errors import ValidationError


class CostModel:
    """Base class: subclasses define ``name``, ``param_names`` and ``_f(x)``, ``_df(x)`` in shop units.

    Every model evaluates its textbook formula ``f(x)`` at ``x = t / scale``: ``t`` is the
    tolerance in SI units (m or rad), ``scale`` the SI size of the shop unit its coefficients are
    quoted for. Costs are in the cost units of the coefficients (e.g. relative cost).

    Parameters
    ----------
    *params : float
        The coefficients in the order of ``param_names`` (shop units, i.e. for ``x = t / scale``).
        Give them positionally or by keyword (``**kw``), not both.
    scale : float, default 1.0
        SI size (m or rad) of the tolerance unit the coefficients refer to, e.g. ``1e-5`` m for
        Yao et al. (2013); 1.0 means the coefficients are for SI tolerances.
    t_min : float, optional
        Smallest tolerance the model is used at (SI). When ``t_min`` or ``t_max`` is given, the
        construction checks the model on ``[t_min, t_max]`` with :meth:`validate_range` (a
        missing ``t_min`` then means 0); when neither is given, no range is checked.
    t_max : float, optional
        Largest tolerance the model is used at (SI); missing while ``t_min`` is given means
        ``100 * scale``.
    **kw : float
        The coefficients by name (every name of ``param_names``, no other), instead of ``*params``.

    Raises
    ------
    ValidationError
        Coefficients given both positionally and by keyword, an unknown or missing name, the
        wrong number of them, a coefficient that is not a finite real number, ``scale`` not a
        positive finite number, a parameter check of the subclass failing, or the cost being
        negative or increasing in ``t`` on ``[t_min, t_max]``.
    """

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
        """A representative instance (``example_params``, ``scale = 1e-5`` m, used on 0.5-8 x scale).

        Returns
        -------
        CostModel
            An instance of the class built from ``example_params`` with ``scale = 1e-5``.

        Raises
        ------
        NotImplementedError
            The class sets no ``example_params``.
        """
        if cls.example_params is None:
            raise NotImplementedError(f"{cls.__name__} sets no example_params (needed by the conformance test)")
        return cls(*cls.example_params, scale=1e-5)

    @classmethod
    def initial_guess(cls, tolerances, costs, *, scale: float = 1.0) -> np.ndarray:
        """Starting coefficients for fitting the model to ``(t, cost)`` data (:func:`evotol.cost_models.fit.fit`).

        Each model carries its own guess (a log-linear or linear least-squares fit of its
        formula, in the subclass's ``_guess``); a model without one starts from ones.

        Parameters
        ----------
        tolerances : array_like
            Tolerances of the data points (SI: m or rad), positive; flattened.
        costs : array_like
            Costs at those tolerances (cost units), as many as ``tolerances``; flattened.
        scale : float, default 1.0
            SI size of the tolerance unit the coefficients refer to (e.g. ``1e-5`` m).

        Returns
        -------
        ndarray
            One starting value per coefficient, in the order of ``param_names`` (shop units).
        """
        x = np.asarray(tolerances, dtype=float).ravel() / scale
        return np.asarray(cls._guess(x, np.asarray(costs, dtype=float).ravel()), dtype=float)

    # --- to implement ----------------------------------------------------------------------
    @classmethod
    def _guess(cls, x: np.ndarray, c: np.ndarray) -> np.ndarray:  # starting coefficients at x = t/scale
        return np.ones(len(cls.param_names))

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
        """The coefficients by name, ``{name: value}`` (shop units, for ``x = t / scale``)."""
        return dict(zip(self.param_names, self.p.tolist()))

    def cost(self, t) -> np.ndarray:
        """Cost of tolerance ``t`` (SI), vectorised.

        Parameters
        ----------
        t : float or array_like
            Tolerance(s) in SI units (m or rad), any shape.

        Returns
        -------
        ndarray
            The cost (cost units), same shape as ``t``.
        """
        return self._f(np.asarray(t, dtype=float) / self.scale)

    def dcost(self, t) -> np.ndarray:
        """d cost / d t (per SI unit), vectorised.

        Parameters
        ----------
        t : float or array_like
            Tolerance(s) in SI units (m or rad), any shape.

        Returns
        -------
        ndarray
            The derivative of the cost with respect to ``t`` (cost units per m or per rad), same
            shape as ``t``.
        """
        return self._df(np.asarray(t, dtype=float) / self.scale) / self.scale

    def d2cost(self, t) -> np.ndarray:
        """d² cost / d t² (per SI unit²), vectorised.

        Finite differences of ``dcost`` unless the model gives the second derivative in closed form.

        Parameters
        ----------
        t : float or array_like
            Tolerance(s) in SI units (m or rad), any shape.

        Returns
        -------
        ndarray
            The second derivative of the cost with respect to ``t`` (cost units per m² or per
            rad²), same shape as ``t``.
        """
        return self._d2f(np.asarray(t, dtype=float) / self.scale) / self.scale ** 2

    __call__ = cost

    def is_convex(self, t_min: float, t_max: float, n: int = 257) -> bool:
        """Whether the cost is convex on [t_min, t_max] (checked on a log-spaced grid).

        The grid joins ``n`` log-spaced and ``n`` linearly spaced tolerances; ``t = 0`` is
        excluded (``t_min = 0`` starts the grid at ``1e-6 * t_max``). Small negative second
        derivatives (relative ``1e-9``) count as convex.

        Parameters
        ----------
        t_min : float
            Smallest tolerance (SI: m or rad).
        t_max : float
            Largest tolerance (SI).
        n : int, default 257
            Number of points of each of the two grids.

        Returns
        -------
        bool
            True when ``d2cost`` is non-negative on the grid.
        """
        t = _range_grid(t_min, t_max, n)
        d2 = self.d2cost(t)
        return bool(np.all(d2 >= -1e-9 * np.max(np.abs(d2)) - 1e-300))

    def validate_range(self, t_min: float, t_max: float | None, n: int = 257) -> None:
        """Reject parameters that make the cost negative or increasing in t on [t_min, t_max] (SI).

        Checked on ``n`` log-spaced plus ``n`` linearly spaced tolerances (``t = 0`` excluded), or
        at ``t_max`` alone when ``t_min == t_max``.

        Parameters
        ----------
        t_min : float
            Smallest tolerance (SI: m or rad), >= 0.
        t_max : float or None
            Largest tolerance (SI); None means ``100 * scale``.
        n : int, default 257
            Number of points of each of the two grids.

        Raises
        ------
        ValidationError
            The range is not finite with ``0 <= t_min <= t_max``, the cost is negative or not
            finite somewhere on it, or ``dcost`` is positive somewhere (the message names the
            model, its parameters and the first tolerance where it fails).
        """
        if t_max is None:
            t_max = 100 * self.scale
        if not (np.isfinite(t_min) and np.isfinite(t_max) and 0 <= t_min <= t_max):
            raise ValidationError(f"{self.name} tolerance range", (t_min, t_max), "0 <= t_min <= t_max, finite (SI units)")
        # a range this model (these coefficients) passed is not checked again: a stack of 5 000 dimensions
        # shares one model and one range (4 s of grids at 5 000, twice per study)
        key = (float(t_min), float(t_max), int(n), self.p.tobytes(), float(self.scale))
        passed = self.__dict__.setdefault("_ranges_passed", set())
        if key in passed:
            return
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
        passed.add(key)

    def __repr__(self) -> str:
        ps = ", ".join(f"{k}={v:.6g}" for k, v in self.params.items())
        return f"{type(self).__name__}({ps}, scale={self.scale:g})"

    def to_dict(self) -> dict:
        """The model as a study-file table, which :func:`evotol.cost_models.registry.from_dict` rebuilds.

        Returns
        -------
        dict
            ``{"model": name, <coefficient>: value, ..., "scale": scale}`` (``scale`` in SI).
        """
        return {"model": self.name, **self.params, "scale": self.scale}


def _range_grid(t_min: float, t_max: float, n: int) -> np.ndarray:
    # t = 0 is excluded: most models are unbounded there and no tolerance is exactly zero.
    lo = t_min if t_min > 0 else t_max * 1e-6
    return np.unique(np.concatenate([np.geomspace(lo, t_max, n), np.linspace(lo, t_max, n)]))

"""Fit any cost model to shop data (scipy.optimize.least_squares) and report the fit quality."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from evotol.cost_models.base import CostModel
from evotol.errors import ValidationError


@dataclass(frozen=True)
class FitResult:
    """A fitted cost model and the quality of its fit to the data (returned by :func:`fit`).

    Parameters
    ----------
    model : CostModel
        The fitted model (coefficients in units of its ``scale``).
    r2 : float
        Coefficient of determination of the costs (dimensionless; 1.0 when the data costs are
        all equal).
    rmse : float
        Root-mean-square residual (cost units).
    max_relative_error : float
        Largest ``|residual| / |cost|`` over the data points (dimensionless; 0.01 is 1 %).
    residuals : (n,) ndarray
        Fitted cost minus data cost at each data point, in the data's order (cost units).
    """
    model: CostModel
    r2: float              #: coefficient of determination
    rmse: float            #: root-mean-square residual (cost units)
    max_relative_error: float
    residuals: np.ndarray

    def summary(self) -> str:
        """One line: the model, R², RMSE and the largest relative error (in %).

        Returns
        -------
        str
            The summary line.
        """
        return (f"{self.model!r}: R² = {self.r2:.5f}, RMSE = {self.rmse:.4g}, "
                f"max relative error = {100 * self.max_relative_error:.2f} %")


def fit(model, tolerances, costs, *, scale: float = 1.0, p0=None) -> FitResult:
    """Least-squares fit of ``model`` (a CostModel class or registered name) to ``(t, cost)`` data.

    ``tolerances`` are in SI units, coefficients are fitted in units of ``scale``. Returns the
    fitted model with R², RMSE and the largest relative error. Raises ValidationError when the
    data are unusable or the best fit violates the model's validity (negative/increasing cost).

    Parameters
    ----------
    model : type or str
        The :class:`~evotol.cost_models.base.CostModel` subclass, or its registered name or alias
        (e.g. ``"exponential"``, ``"index"``).
    tolerances : array_like
        Tolerances of the data points (SI: m or rad), positive; flattened.
    costs : array_like
        Costs at those tolerances (cost units), non-negative, as many as ``tolerances``.
    scale : float, default 1.0
        SI size of the tolerance unit the fitted coefficients refer to (e.g. ``1e-5`` m).
    p0 : array_like, optional
        Initial coefficients (in units of ``scale``, order of ``param_names``); by default the
        model's own :meth:`~evotol.cost_models.base.CostModel.initial_guess` (log-linear or linear least
        squares on the data for the built-in models, ones for a model that defines none).

    Returns
    -------
    FitResult
        The fitted model, checked on the data's tolerance range, with R², RMSE, largest
        relative error and the residuals.

    Raises
    ------
    ValidationError
        ``model`` is an unknown name; ``costs`` and ``tolerances`` differ in size; fewer than
        (number of coefficients + 1) data points; tolerances not positive and finite; costs
        negative or not finite; or the fitted coefficients are invalid for the model or make
        the cost negative or increasing between the smallest and largest tolerance; a ``p0``
        that is not one finite value per coefficient.
    """
    from evotol.cost_models.registry import get

    cls = get(model) if isinstance(model, str) else model
    t = np.asarray(tolerances, dtype=float).ravel()
    c = np.asarray(costs, dtype=float).ravel()
    if t.shape != c.shape:
        raise ValidationError("costs", c.shape, f"as many costs as tolerances {t.shape}")
    n = len(cls.param_names)
    if t.size < n + 1:
        raise ValidationError("tolerances", t.size, f"at least {n + 1} data points to fit {n} parameters")
    if not (np.all(np.isfinite(t)) and np.all(t > 0)):
        raise ValidationError("tolerances", t.tolist(), "positive finite values (SI)")
    if not (np.all(np.isfinite(c)) and np.all(c >= 0)):
        raise ValidationError("costs", c.tolist(), "non-negative finite values")
    x = t / scale
    if p0 is None:
        guess = cls.initial_guess(t, c, scale=scale)
    else:
        try:
            guess = np.asarray(p0, float).ravel()
        except (TypeError, ValueError):
            guess = np.full(0, np.nan)
        if guess.size != n or not np.all(np.isfinite(guess)):
            raise ValidationError("p0", p0, f"{n} finite initial coefficients {tuple(cls.param_names)}")

    def model_values(p):
        m = object.__new__(cls)
        m.p, m.scale = np.asarray(p, float), 1.0
        return m._f(x)

    # Levenberg-Marquardt: unbounded, and the data outnumber the coefficients (checked above)
    res = least_squares(lambda p: model_values(p) - c, guess, method="lm", x_scale="jac", max_nfev=20000)
    fitted = cls(*res.x, scale=scale, t_min=float(t.min()), t_max=float(t.max()))
    r = fitted.cost(t) - c
    ss_tot = float(np.sum((c - c.mean()) ** 2))
    r2 = 1 - float(np.sum(r ** 2)) / ss_tot if ss_tot > 0 else 1.0
    return FitResult(fitted, r2, float(np.sqrt(np.mean(r ** 2))),
                     float(np.max(np.abs(r) / np.maximum(np.abs(c), 1e-300))), r)

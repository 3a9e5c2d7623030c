"""Conformance checks for cost models, one small named check each (scikit-learn's
``sklearn/utils/estimator_checks.py`` style).

:func:`cost_model_checks` yields ``(name, check)`` pairs, each check a callable of no argument
that raises :class:`evotol.errors.CheckFailed` saying what failed (not an ``assert``: the
checks hold under ``python -O``); a test turns each into its own pytest id::

    @pytest.mark.parametrize("check", list(cost_model_checks(MyCost(...))), ids=lambda c: c[0])
    def test_my_cost(check):
        check[1]()

:func:`check_cost_model` runs them all and reports every failure, not only the first.

The range ``[t_min, t_max]`` (SI) is where the model is used; the default is 0.05 to 10 times
the model's ``scale`` (its shop unit).

The parameters several definitions of this module share are described once, here.

Parameters
----------
model : CostModel
    The model checked.
t_min : float
    Smallest tolerance of the range (SI: m or rad).
t_max : float
    Largest tolerance of the range (SI).
rtol : float, default 1e-5
    Tolerance of :func:`check_derivative_matches_fd`.
"""
from __future__ import annotations

import functools
import pickle
from typing import Callable, Iterator

import numpy as np

from evotol.cost_models.base import CostModel
from evotol.cost_models.compound import SumCost
from evotol.cost_models.registry import ALIASES, available, from_dict
from evotol._runtime.check_suite import require, run_checks


def _grid(t_min: float, t_max: float, n: int = 50) -> np.ndarray:
    return np.linspace(t_min, t_max, n)


def check_named(model: CostModel, t_min: float, t_max: float) -> dict:
    """The model has a name (study files and reports refer to it by name).

    Parameters
    ----------
    t_min : float
        Smallest tolerance of the range (SI: m or rad); unused here (every check takes the range).
    t_max : float
        Largest tolerance of the range (SI); unused here.

    Returns
    -------
    dict
        Empty (nothing measured).

    Raises
    ------
    CheckFailed
        The model has no (or an empty) ``name``.
    """
    require(getattr(model, "name", ""), f"{type(model).__name__}: cost model has no name")
    return {}


def check_vectorised(model: CostModel, t_min: float, t_max: float) -> dict:
    """``cost`` and ``dcost`` keep the shape of ``t`` and agree with element-wise calls.

    Returns
    -------
    dict
        Empty (nothing measured).

    Raises
    ------
    CheckFailed
        A shape is not kept (1-D and 2-D grids on the range) or a scalar call differs from the
        vectorised one.
    """
    t = _grid(t_min, t_max)
    c = model.cost(t)
    require(c.shape == t.shape, f"{model.name}: cost(t) shape {c.shape} != {t.shape}")
    c2 = model.cost(t.reshape(5, 10))
    require(c2.shape == (5, 10) and np.allclose(c2.ravel(), c),
            f"{model.name}: cost is not vectorised over arrays")
    single = np.array([float(model.cost(x)) for x in t[::7]])
    require(np.allclose(single, c[::7], rtol=1e-12, atol=0), f"{model.name}: cost(t)[i] != cost(t[i])")
    require(model.dcost(t).shape == t.shape,
            f"{model.name}: dcost(t) shape {model.dcost(t).shape} != {t.shape}")
    return {}


def check_positive_and_monotone(model: CostModel, t_min: float, t_max: float) -> dict:
    """On the range the cost is finite, non-negative and non-increasing in t (a looser tolerance
    never costs more), measured on the cost values themselves, not only on ``dcost``.

    Returns
    -------
    dict
        Empty (nothing measured).

    Raises
    ------
    CheckFailed
        The cost is negative, not finite, or rises between two of 200 log-spaced tolerances.
    ValidationError
        :meth:`~evotol.cost_models.base.CostModel.validate_range` rejects the range.
    """
    model.validate_range(t_min, t_max)        # raises ValidationError naming where it fails
    t = np.geomspace(t_min, t_max, 200)
    c = model.cost(t)
    require(np.all(np.isfinite(c)) and np.all(c >= 0),
            f"{model.name}: cost negative or not finite on the range")
    rise = np.diff(c)
    worst = float(rise.max())
    require(worst <= 1e-9 * max(1.0, float(np.abs(c).max())),
            f"{model.name}: cost increases by {worst:.3g} between t = {t[rise.argmax()]:.6g} and {t[rise.argmax() + 1]:.6g}")
    return {}


def check_derivative_matches_fd(model: CostModel, t_min: float, t_max: float, rtol: float = 1e-5) -> dict:
    """``dcost`` matches central finite differences of ``cost`` (relative to its largest value).

    Parameters
    ----------
    rtol : float, default 1e-5
        Largest allowed difference, relative to the largest ``|dcost|`` on the range.

    Returns
    -------
    dict
        ``{"dcost_fd_relative_error": err}``, the measured relative difference.

    Raises
    ------
    CheckFailed
        The relative difference exceeds ``rtol``.
    """
    t = _grid(t_min, t_max)[1:-1]
    h = 1e-6 * (t_max - t_min)
    fd = (model.cost(t + h) - model.cost(t - h)) / (2 * h)
    d = model.dcost(t)
    err = float(np.max(np.abs(fd - d)) / max(np.max(np.abs(d)), 1e-300))
    require(err <= rtol, f"{model.name}: dcost differs from finite differences by {err:.3g} (relative)")
    return {"dcost_fd_relative_error": err}


def check_convexity_flag(model: CostModel, t_min: float, t_max: float) -> dict:
    """A model that declares ``convex = True`` is convex on the range: second differences of the
    cost values (independent of ``d2cost``) are >= 0, and ``is_convex`` agrees.

    Returns
    -------
    dict
        ``{"convex": bool}``, the model's flag (a model declaring ``convex = False`` is not checked).

    Raises
    ------
    CheckFailed
        The model declares ``convex = True`` but its chord slopes on 400 log-spaced tolerances
        decrease, or :meth:`~evotol.cost_models.base.CostModel.is_convex` says False on the range.
    """
    if not model.convex:
        return {"convex": False}
    t = np.geomspace(t_min, t_max, 400)
    c = model.cost(t)
    # slopes of consecutive chords must not decrease (convexity on a non-uniform grid)
    s = np.diff(c) / np.diff(t)
    drop = float(-(np.diff(s)).min()) if len(s) > 1 else 0.0
    require(drop <= 1e-7 * max(float(np.abs(s).max()), 1e-300),
            f"{model.name}: declares convex = True but its chord slopes decrease by {drop:.3g} on [{t_min:.3g}, {t_max:.3g}]")
    require(model.is_convex(t_min, t_max),
            f"{model.name}: declares convex = True but is_convex() is False on the range")
    return {"convex": True}


def check_dict_round_trip(model: CostModel, t_min: float, t_max: float) -> dict:
    """``evotol.cost_models.from_dict(model.to_dict())`` rebuilds the same model (same class, same costs).

    Returns
    -------
    dict
        Empty (nothing measured).

    Raises
    ------
    CheckFailed
        The rebuilt model has another class, other costs on the range, or another ``to_dict()``.
    """
    d = model.to_dict()
    back = from_dict(dict(d))
    require(type(back) is type(model), f"{model.name}: from_dict(to_dict()) gives {type(back).__name__}")
    t = _grid(t_min, t_max)
    require(np.array_equal(back.cost(t), model.cost(t)), f"{model.name}: from_dict(to_dict()) costs differ")
    require(back.to_dict() == d, f"{model.name}: to_dict changes on a round trip: {d} -> {back.to_dict()}")
    return {}


def check_pickle_round_trip(model: CostModel, t_min: float, t_max: float) -> dict:
    """The model pickles (cost models travel to worker processes and Dask) and costs the same after.

    Returns
    -------
    dict
        Empty (nothing measured).

    Raises
    ------
    CheckFailed
        The unpickled model's costs differ on the range.
    """
    back = pickle.loads(pickle.dumps(model))
    t = _grid(t_min, t_max)
    require(np.array_equal(back.cost(t), model.cost(t)),
            f"{model.name}: costs differ after a pickle round trip")
    return {}


def _registered(model: CostModel) -> bool:
    """Whether a study file can name the model (registered, entry point, or a sum of those)."""
    if isinstance(model, SumCost):
        return all(_registered(m) for m in model.models)
    return available().get(ALIASES.get(model.name, model.name)) is type(model)


def cost_model_checks(model: CostModel, t_min: float | None = None, t_max: float | None = None,
                      rtol: float = 1e-5) -> Iterator[tuple[str, Callable[[], dict]]]:
    """The named checks that apply to ``model`` on ``[t_min, t_max]`` (SI); see module docstring.

    The dict round trip applies to models a study file can name (registered or entry points,
    and sums of them); a :class:`~evotol.cost_models.user.CallableCost` wraps Python code and has none.

    Parameters
    ----------
    model : CostModel
        The model to check.
    t_min : float, optional
        Smallest tolerance of the range (SI: m or rad); default ``0.05 * model.scale``.
    t_max : float, optional
        Largest tolerance of the range (SI); default ``10 * model.scale``.

    Yields
    ------
    name : str
        The check's function name (e.g. ``"check_vectorised"``).
    check : callable
        The check bound to the model and range, called with no argument; returns a dict of
        measurements, raises :class:`~evotol.errors.CheckFailed` when it fails.
    """
    t_max = float(t_max) if t_max is not None else 10 * model.scale
    t_min = float(t_min) if t_min is not None else 0.05 * model.scale
    checks = [check_named, check_vectorised, check_positive_and_monotone,
              functools.partial(check_derivative_matches_fd, rtol=rtol), check_convexity_flag,
              check_pickle_round_trip]
    if _registered(model):
        checks.append(check_dict_round_trip)
    for c in checks:
        name = getattr(c, "func", c).__name__
        yield name, functools.partial(c, model, t_min, t_max)


def check_cost_model(model: CostModel, t_min: float | None = None, t_max: float | None = None,
                     rtol: float = 1e-5) -> dict:
    """Run every check of :func:`cost_model_checks`; returns the merged measurements.

    Raises one :class:`evotol.errors.CheckFailed` listing every failed check (not only the first).

    Parameters
    ----------
    model : CostModel
        The model to check.
    t_min : float, optional
        Smallest tolerance of the range (SI: m or rad); default ``0.05 * model.scale``.
    t_max : float, optional
        Largest tolerance of the range (SI); default ``10 * model.scale``.

    Returns
    -------
    dict
        The merged measurements of the checks (e.g. ``dcost_fd_relative_error``, ``convex``).

    Raises
    ------
    CheckFailed
        One or more checks failed (every failure listed).
    """
    return run_checks(str(getattr(model, 'name', model)), cost_model_checks(model, t_min, t_max, rtol))

"""Stack analysis of a one-dimensional gap as a tolerance handbook gives it.

A **stack** is a gap ``g = Σ_i a_i x_i`` of dimensions ``x_i`` with sensitivities ``a_i`` (a
direction ±1 in a loop diagram, or ∂g/∂x_i). Each dimension has a nominal ``n_i`` and a signed
lower and upper deviation ``l_i <= u_i`` as a drawing gives them (``+0.010 / −0.004``:
``u = 0.010``, ``l = −0.004``; one-sided ``+0 / −0.031``: ``u = 0``, ``l = −0.031``), so
``x_i ∈ [n_i + l_i, n_i + u_i]``. A one-sided or unequal tolerance enters every method the same
way: through the **zone centre** ``m_i = n_i + (l_i + u_i)/2`` and the **half-width**
``h_i = (u_i − l_i)/2`` (Drake, *Dimensioning and Tolerancing Handbook*, McGraw-Hill 1999, ch. 9:
convert to an equal-bilateral tolerance about the mean before stacking).

Figures (all in the stack's length unit; the functions are homogeneous in it):

* nominal gap ``g_0 = Σ a_i n_i``; mean gap ``μ = Σ a_i m_i``;
* **worst case** (arithmetic): ``μ ± T_wc``, ``T_wc = Σ |a_i| h_i`` -- the exact extremes over
  the tolerance box (the box's corners), computed as ``g_0 + Σ min/max(a_i l_i, a_i u_i)``;
* **RSS** (statistical, every tolerance ``h_i = 3σ_i``): ``μ ± T_rss``,
  ``T_rss = sqrt(Σ (a_i h_i)²)`` -- both by the one linear-stack model's functions
  (:func:`evotol.robots.assembly.linear_stack.worst_case_deviation`,
  :func:`~evotol.robots.assembly.linear_stack.rss_half_width`), which
  :class:`evotol.robots.assembly.LinearStack` uses too;
* **modified RSS** (Drake ch. 9, eq. of the "MRSS" model): ``μ ± C_f T_rss`` with the correction
  factor ``C_f = 1 + 0.5 (T_wc − T_rss) / (T_rss (√n − 1))`` (``n`` the number of dimensions;
  ``C_f = 1`` for ``n = 1``, where ``T_wc = T_rss``);
* **normal model with a stated capability and mean shift** (:class:`StackModel`): each dimension
  normal with ``h_i = 3 C_p σ_i`` and its mean shifted by ``k h_i`` (``k`` a fraction of the
  half-width; six-sigma practice: ``C_p = 2``, a 1.5σ shift is ``k = 0.25``). Two ways to stack
  the shift, both from Drake ch. 9: ``"dynamic"`` (DRSS: ``σ_i,eff = h_i / (3 C_p (1 − k))``, the
  mean at the zone centre) and ``"static"`` (the shifts added arithmetically,
  ``δ = Σ |a_i| k h_i``, toward the limit being checked, ``σ_i = h_i / (3 C_p)``);
* ``C_p = (USL − LSL) / (6σ_g)`` and ``C_pk = min(USL − μ_g, μ_g − LSL) / (3σ_g)`` of the gap
  against its limits (with the static model, ``μ_g`` is the shifted mean of the side checked);
* the **fraction outside each limit**: exact (the normal CDF) when every dimension is normal;
  Monte Carlo with a Clopper–Pearson interval otherwise (uniform or triangular inputs);
* **contributions to each side**: each dimension's part of the worst-case deviation below and
  above the nominal gap, and its share of the gap's variance.

The parameters several definitions of this module share are described once, here.

Parameters
----------
stack : Stack
    The stack.
model : StackModel
    Capability and mean shift.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from evotol.errors import ValidationError, is_integer
from evotol.measures.stack_model import (DISTRIBUTIONS, SHIFT_MODELS, Stack, StackDimension, StackModel,  # noqa: F401 -- one door
                                         _finite)
from evotol._runtime.random_state import seed_from
from evotol.robots.assembly.linear_stack import rss_half_width as linear_rss, worst_case_deviation, zone_extremes

__all__ = ["Stack", "StackDimension", "StackModel", "DISTRIBUTIONS", "SHIFT_MODELS", "worst_case",
           "rss_half_width", "mrss_factor", "gap_moments", "fraction_outside", "check_model", "sample_gap",
           "contributions", "capability", "StackAnalysis", "analyse_stack"]


def worst_case(stack: Stack) -> tuple[float, float]:
    """Worst-case (arithmetic) gap limits: the gap's extremes over the tolerance box.

    Returns
    -------
    tuple of float
        ``(μ − T_wc, μ + T_wc)``, ``T_wc = Σ |a_i| h_i`` (length unit).
    """
    a, n, _, _ = stack.arrays()
    below, above = worst_case_deviation(a, *stack.deviations())
    g0 = float(a @ n)
    return g0 + float(below), g0 + float(above)


def rss_half_width(stack: Stack) -> float:
    """``T_rss = sqrt(Σ (a_i h_i)²)`` (length unit).

    Returns
    -------
    float
        The RSS half-width (every tolerance ``3σ``).
    """
    a, _, _, h = stack.arrays()
    return float(linear_rss(a, h))


def mrss_factor(stack: Stack) -> float:
    """Drake's MRSS correction factor ``C_f = 1 + 0.5 (T_wc − T_rss) / (T_rss (√n − 1))``.

    Parameters
    ----------
    stack : Stack
        The stack (``n`` = its number of dimensions).

    Returns
    -------
    float
        ``C_f`` (dimensionless); 1 for one dimension.
    """
    n = len(stack.dimensions)
    lo, hi = worst_case(stack)
    t_wc, t_rss = 0.5 * (hi - lo), rss_half_width(stack)
    if n == 1 or t_rss == 0:
        return 1.0
    return float(1.0 + 0.5 * (t_wc - t_rss) / (t_rss * (np.sqrt(n) - 1.0)))


def gap_moments(stack: Stack, model: StackModel = StackModel()) -> dict:
    """Mean and standard deviation of the gap under ``model`` (normal dimensions' σ; the other
    distributions' own variances).

    Returns
    -------
    dict
        ``mean`` (μ, zone centres), ``sigma`` (σ_g), ``shift`` (the static model's δ, 0 for the
        dynamic one), ``variance_share`` (per dimension, fractions summing to 1), all in the
        length unit except the shares.
    """
    a, _, m, h = stack.arrays()
    sd = np.empty_like(h)
    for i, d in enumerate(stack.dimensions):
        if d.distribution == "normal":
            sd[i] = h[i] / (3 * model.cp)
        elif d.distribution == "uniform":
            sd[i] = h[i] / np.sqrt(3)
        else:  # symmetric triangular on [-h, h]
            sd[i] = h[i] / np.sqrt(6)
    if model.shift_model == "dynamic" and model.k:
        sd = sd / (1 - model.k)
        shift = 0.0
    else:
        shift = float(np.abs(a) @ (model.k * h))
    var = (a * sd) ** 2
    total = float(var.sum())
    return {"mean": float(a @ m), "sigma": float(np.sqrt(total)), "shift": shift,
            "variance_share": (var / total if total > 0 else np.zeros_like(var)).tolist()}


def _cp_interval(k: int, n: int, confidence: float) -> tuple[float, float]:
    ci = stats.binomtest(k, n).proportion_ci(confidence_level=confidence, method="exact")
    return float(ci.low), float(ci.high)


def fraction_outside(stack: Stack, model: StackModel = StackModel(), *, n_samples: int = 200_000, seed=0,
                     confidence: float = 0.95, rng: int | np.random.Generator | None = None) -> dict:
    """Fraction of assemblies below LSL and above USL.

    Exact (normal CDF) when every dimension is normal; else Monte Carlo over the dimensions'
    distributions with a Clopper–Pearson interval at ``confidence``. With the static shift the
    mean is moved by ``δ`` toward the limit being checked (a separate worst direction per side).

    Parameters
    ----------
    stack : Stack
        The stack, with at least one limit.
    n_samples : int
        Monte Carlo samples (non-normal dimensions only).
    seed : int or numpy.random.Generator
        Seed of the Monte Carlo.
    confidence : float
        Confidence level of the Clopper–Pearson interval (0 < c < 1).
    rng : int, numpy.random.Generator or None, optional
        As SciPy's ``rng``: an integer seed, or a Generator drawn from once for the seed of the run;
        replaces ``seed`` (which keeps working).

    Returns
    -------
    dict
        ``method`` (``"exact normal"`` or ``"Monte Carlo"``), ``below`` and ``above`` (fractions,
        None where there is no limit), with ``below_interval`` / ``above_interval``,
        ``n_samples`` and ``confidence`` for Monte Carlo.

    Raises
    ------
    evotol.errors.ValidationError
        A stack without limits, the dynamic shift model with non-normal dimensions (it is
        defined for normal processes), ``n_samples < 1`` or a confidence outside (0, 1).
    """
    seed = seed if rng is None else seed_from(rng, seed)       # seed= already takes a Generator as it is
    check_model(stack, model)
    if stack.lower_limit is None and stack.upper_limit is None:
        raise ValidationError("lower_limit", None, "a lower or upper limit of the gap to count assemblies outside")
    if not 0 < _finite("confidence", confidence) < 1:
        raise ValidationError("confidence", confidence, "a level between 0 and 1")
    mo = gap_moments(stack, model)
    lo, hi = stack.lower_limit, stack.upper_limit
    if all(d.distribution == "normal" for d in stack.dimensions):
        s = mo["sigma"]
        below = None if lo is None else float(stats.norm.cdf((lo - (mo["mean"] - mo["shift"])) / s)) if s > 0 \
            else float(mo["mean"] - mo["shift"] < lo)
        above = None if hi is None else float(stats.norm.sf((hi - (mo["mean"] + mo["shift"])) / s)) if s > 0 \
            else float(mo["mean"] + mo["shift"] > hi)
        return {"method": "exact normal", "below": below, "above": above}
    if not is_integer(n_samples, 1):
        raise ValidationError("n_samples", n_samples, "a positive number of Monte Carlo samples")
    g = sample_gap(stack, model, int(n_samples), seed)
    out = {"method": "Monte Carlo", "n_samples": int(n_samples), "confidence": confidence, "below": None, "above": None}
    if lo is not None:
        k = int(np.sum(g - mo["shift"] < lo))
        out["below"], out["below_interval"] = k / n_samples, _cp_interval(k, int(n_samples), confidence)
    if hi is not None:
        k = int(np.sum(g + mo["shift"] > hi))
        out["above"], out["above_interval"] = k / n_samples, _cp_interval(k, int(n_samples), confidence)
    return out


def check_model(stack: Stack, model: StackModel) -> None:
    """Refuse a model the stack's distributions do not support, before any work.

    Parameters
    ----------
    model : StackModel
        The model.

    Raises
    ------
    evotol.errors.ValidationError
        A dynamic mean shift (k > 0) with a non-normal dimension.
    """
    if model.shift_model == "dynamic" and model.k > 0:
        odd = [d.name for d in stack.dimensions if d.distribution != "normal"]
        if odd:
            raise ValidationError("model.shift_model", "dynamic", f"'static' for non-normal dimensions ({odd[0]}: "
                                  "the dynamic RSS inflates a normal process's σ)")


def sample_gap(stack: Stack, model: StackModel, n: int, seed=0) -> np.ndarray:
    """Gap values of ``n`` random assemblies (zone-centred dimensions; the static shift is not
    included: it is added toward each limit by :func:`fraction_outside`).

    Parameters
    ----------
    model : StackModel
        Capability (normal dimensions' σ = h/(3 C_p)) and the dynamic shift's σ inflation.
    n : int
        Number of assemblies.
    seed : int or numpy.random.Generator
        Random seed.

    Returns
    -------
    (n,) ndarray
        Gap values (length unit).
    """
    rng = np.random.default_rng(seed)
    a, _, m, h = stack.arrays()
    g = np.full(n, float(a @ m))
    infl = 1 / (1 - model.k) if model.shift_model == "dynamic" else 1.0
    for ai, hi, d in zip(a, h, stack.dimensions):
        if d.distribution == "normal":
            z = rng.normal(0.0, hi / (3 * model.cp) * infl, n)
        elif d.distribution == "uniform":
            z = rng.uniform(-hi, hi, n)
        else:
            z = rng.triangular(-hi, 0.0, hi, n)
        g += ai * z
    return g


def contributions(stack: Stack) -> list[dict]:
    """Each dimension's part of the worst-case gap below and above the nominal gap.

    Returns
    -------
    list of dict
        Per dimension: ``name``, ``below`` and ``above`` (its deviation of the gap from the
        nominal gap at the lower and the upper worst case, length unit: ``min``/``max`` of
        ``a·l`` and ``a·u``) and ``below_percent`` / ``above_percent`` (its share of that side's
        total deviation; a one-sided dimension adds nothing to one side).
    """
    a, *_ = stack.arrays()
    lo, hi = zone_extremes(a, *stack.deviations())
    slo, shi = float(lo.sum()), float(hi.sum())
    return [{"name": d.name, "below": float(l) + 0.0, "above": float(u) + 0.0,
             "below_percent": 100 * float(l) / slo + 0.0 if slo else 0.0,
             "above_percent": 100 * float(u) / shi + 0.0 if shi else 0.0}
            for d, l, u in zip(stack.dimensions, lo, hi)]


def capability(mean: float, sigma: float, lower: float | None, upper: float | None, shift: float = 0.0) -> dict:
    """``C_p`` and ``C_pk`` of a normal gap against its limits.

    Parameters
    ----------
    mean, sigma : float
        The gap's mean and standard deviation (length unit).
    lower, upper : float or None
        LSL and USL (length unit).
    shift : float
        The static model's mean shift δ, moved toward each limit (length unit).

    Returns
    -------
    dict
        ``cp`` (None unless both limits), ``cpk`` (the smaller of ``cpl`` and ``cpu``), ``cpl``
        ``(μ − δ − LSL)/(3σ)``, ``cpu`` ``(USL − μ − δ)/(3σ)``; None where a limit is missing or σ = 0.
    """
    if sigma <= 0:
        return {"cp": None, "cpk": None, "cpl": None, "cpu": None}
    cpl = None if lower is None else (mean - shift - lower) / (3 * sigma)
    cpu = None if upper is None else (upper - mean - shift) / (3 * sigma)
    sides = [c for c in (cpl, cpu) if c is not None]
    return {"cp": None if lower is None or upper is None else (upper - lower) / (6 * sigma),
            "cpk": min(sides) if sides else None, "cpl": cpl, "cpu": cpu}


@dataclass(frozen=True)
class StackAnalysis:
    """Every figure of :func:`analyse_stack` (length unit of the stack; fractions and indices 1).

    Parameters
    ----------
    figures : dict
        JSON-ready figures (see :func:`analyse_stack`).
    """

    figures: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """The figures as plain data.

        Returns
        -------
        dict
            A copy of :attr:`figures`.
        """
        return dict(self.figures)


def analyse_stack(stack: Stack, models: dict | None = None, *, n_samples: int = 200_000, seed=0,
                  confidence: float = 0.95, rng: int | np.random.Generator | None = None) -> StackAnalysis:
    """The handbook's stack figures (module docstring), under one or more stated models.

    Parameters
    ----------
    models : dict of str to StackModel, optional
        Named statistical models (default ``{"rss": StackModel()}``, t = 3σ normal).
    n_samples, seed, confidence, rng
        Monte Carlo settings of :func:`fraction_outside` (non-normal dimensions only).

    Returns
    -------
    StackAnalysis
        ``gap``, ``unit``, ``limits`` ``[LSL, USL]``, ``nominal``, ``mean``, ``worst_case``,
        ``rss`` and ``mrss`` (each ``limits``, ``half_width``; ``mrss`` with ``factor``),
        ``contributions`` (:func:`contributions`) and per model ``models[name]``: ``model``
        (its statement), ``sigma``, ``shift``, capability (:func:`capability`), fractions
        (:func:`fraction_outside`), ``variance_share``.

    Raises
    ------
    evotol.errors.ValidationError
        A model the stack does not support (:func:`check_model`), checked for every model
        before the first one is computed.
    """
    seed = seed if rng is None else seed_from(rng, seed)
    models = {"rss": StackModel()} if models is None else dict(models)
    for mo in models.values():
        check_model(stack, mo)
    a, n, m, h = stack.arrays()
    mu = float(a @ m)
    wc = worst_case(stack)
    t_rss, cf = rss_half_width(stack), float(mrss_factor(stack))
    out = {"gap": stack.gap, "unit": stack.unit, "limits": [stack.lower_limit, stack.upper_limit],
           "dimensions": [{"name": d.name, "nominal": d.nominal, "lower": d.lower, "upper": d.upper,
                           "sensitivity": d.sensitivity, "distribution": d.distribution,
                           **({"same_part_as": d.same_part_as} if d.same_part_as else {})} for d in stack.dimensions],
           "nominal": float(a @ n), "mean": mu,
           "worst_case": {"limits": list(wc), "half_width": 0.5 * (wc[1] - wc[0])},
           "rss": {"limits": [mu - t_rss, mu + t_rss], "half_width": t_rss, "convention": "every tolerance ±3σ"},
           "mrss": {"limits": [mu - cf * t_rss, mu + cf * t_rss], "half_width": cf * t_rss, "factor": cf,
                    "n": len(a), "convention": "C_f = 1 + 0.5 (T_wc - T_rss) / (T_rss (sqrt(n) - 1)) (Drake ch. 9)"},
           "contributions": contributions(stack), "models": {}}
    has_limits = stack.lower_limit is not None or stack.upper_limit is not None
    for name, mo in models.items():
        g = gap_moments(stack, mo)
        entry = {"model": mo.describe(), "cp_input": mo.cp, "k": mo.k, "shift_model": mo.shift_model,
                 "sigma": g["sigma"], "shift": g["shift"], "variance_share": g["variance_share"],
                 **capability(g["mean"], g["sigma"], stack.lower_limit, stack.upper_limit, g["shift"])}
        if has_limits:
            entry["outside"] = fraction_outside(stack, mo, n_samples=n_samples, seed=seed, confidence=confidence)
        out["models"][name] = entry
    return StackAnalysis(out)

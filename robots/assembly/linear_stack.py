"""A linear tolerance stack ``y_k = Σ_j a_kj x_j`` as an assembly function whose sensitivities are
given (Chase, *Dimensioning and Tolerancing Handbook* ch. 14: the arithmetic / statistical stack).

The one linear-stack model: :class:`LinearStack` is the robot an allocation works on, and the
handbook's stack (:class:`evotol.measures.stack_model.Stack`, one gap with drawn zones and limits) is
built into one by :meth:`~evotol.measures.stack_model.Stack.linear_stack`. Both take their worst case
and RSS from the two functions here:

* **worst case** over zones ``x_j ∈ [n_j + l_j, n_j + u_j]`` (signed deviations ``l_j <= u_j``): the
  response's deviation from its nominal lies in ``[Σ_j min(a_j l_j, a_j u_j), Σ_j max(a_j l_j, a_j u_j)]``,
  the exact extremes over the box (a linear function takes them at its corners), Drake 1999 ch. 9;
  for a centred zone ``±h_j`` this is ``±Σ_j |a_j| h_j``;
* **RSS** (every half-width ``h_j = 3σ_j``): ``T_rss = sqrt(Σ_j (a_j h_j)²)``.

Units: sensitivities in response unit per dimension unit (e.g. m/m); dimensions SI (m or rad).
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.assembly.function import AssemblyFunction


def zone_extremes(a, lower, upper) -> tuple[np.ndarray, np.ndarray]:
    """Each term's least and greatest part ``min/max(a_j l_j, a_j u_j)`` of a response's deviation.

    Parameters
    ----------
    a : array_like, (..., n)
        Sensitivities ∂y/∂x_j (response unit per dimension unit).
    lower, upper : array_like, (n,)
        Signed lower and upper deviations of each zone from its nominal, ``lower <= upper``
        (dimension unit).

    Returns
    -------
    (below, above) : tuple of numpy.ndarray, shaped like ``a``
        The terms' parts of the lowest and the highest deviation (response unit).
    """
    a = np.asarray(a, dtype=float)
    lo, hi = a * np.asarray(lower, dtype=float), a * np.asarray(upper, dtype=float)
    return np.minimum(lo, hi), np.maximum(lo, hi)


def worst_case_deviation(a, lower, upper) -> tuple[np.ndarray | float, np.ndarray | float]:
    """The worst case of ``y − y_nominal`` over the zones (module docstring): its least and greatest value.

    Parameters
    ----------
    a : array_like, (n,) or (k, n)
        Sensitivities of one response or of k responses (response unit per dimension unit).
    lower, upper : array_like, (n,)
        Signed deviations of each zone, ``lower <= upper`` (dimension unit).

    Returns
    -------
    (below, above) : tuple of float or numpy.ndarray, (k,)
        ``Σ_j min(a_j l_j, a_j u_j)`` and ``Σ_j max(a_j l_j, a_j u_j)`` (response unit).

    Examples
    --------
    >>> worst_case_deviation([1.0, -2.0], [-0.1, 0.0], [0.1, 0.3])   # x1 ± 0.1, x2 +0.3/0, gap = x1 − 2 x2
    (np.float64(-0.7), np.float64(0.1))
    """
    below, above = zone_extremes(a, lower, upper)
    return below.sum(axis=-1), above.sum(axis=-1)


def rss_half_width(a, half_width) -> np.ndarray | float:
    """``T_rss = sqrt(Σ_j (a_j h_j)²)``: the RSS half-width of a response, every ``h_j = 3σ_j``.

    Parameters
    ----------
    a : array_like, (n,) or (k, n)
        Sensitivities (response unit per dimension unit).
    half_width : array_like, (n,)
        Half-widths of the zones (dimension unit).

    Returns
    -------
    float or numpy.ndarray, (k,)
        The RSS half-width (response unit).

    Examples
    --------
    >>> float(rss_half_width([1.0, -2.0], [0.3, 0.2]))      # sqrt(0.3² + 0.4²)
    0.5
    """
    return np.sqrt(np.sum((np.asarray(a, dtype=float) * np.asarray(half_width, dtype=float)) ** 2, axis=-1))


class _LinearResponses:
    """``y_k = Σ_j a_kj x_j`` as a picklable callable (robots go to worker processes and Dask)."""

    def __init__(self, dims: tuple[str, ...], matrix: np.ndarray):
        self.dims, self.matrix = dims, matrix

    def __call__(self, **x):
        X = np.stack([x[d] for d in self.dims], axis=-1)
        return tuple(X @ self.matrix[i] for i in range(self.matrix.shape[0]))


class LinearStack(AssemblyFunction):
    """A linear tolerance stack ``y_k = Σ_j a_kj x_j``: sensitivities given, nothing to derive.

    Parameters
    ----------
    sensitivities : Mapping
        Dimension name -> a_j (one response) or response name -> {dimension -> a_kj} (response
        unit per dimension unit, e.g. m/m).
    limits : Mapping[str, float]
        Response name -> allowed deviation (the response's unit), one entry per response.
    nominal : Mapping[str, float] or None
        Dimension -> nominal value (SI: m or rad); only Monte Carlo reports use it.
    name : str
        Name of the stack (reports, messages).
    **kw
        Further options of :class:`AssemblyFunction` (``units``, ``groups``).

    Raises
    ------
    evotol.errors.ValidationError
        Empty or non-finite sensitivities, or a response that has no limit.

    Examples
    --------
    >>> from evotol import LinearStack
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> stack.source_names
    ('x1', 'x2', 'x3')
    >>> stack.sensitivity([[0]])[0, 2] * 1e-4                  # row 2: a_j / L, times L = 0.1 mm
    array([ 1. , -2. ,  0.5])
    """

    def __init__(self, sensitivities: Mapping, limits: Mapping[str, float], *, nominal: Mapping[str, float] | None = None,
                 name: str = "linear stack", **kw):
        if not isinstance(sensitivities, Mapping) or not sensitivities:
            raise ValidationError("stack sensitivities", sensitivities, "a mapping dimension -> a_j (or response -> {dimension -> a_kj})")
        first = next(iter(sensitivities.values()))
        rows = dict(sensitivities) if isinstance(first, Mapping) else {next(iter(limits)): dict(sensitivities)}
        dims: list[str] = []
        for r in rows.values():
            dims += [d for d in r if d not in dims]
        extra = [r for r in rows if r not in limits]
        if extra:
            raise ValidationError("stack sensitivities response", extra[0], f"one of the limits {list(limits)}")
        A = np.zeros((len(limits), len(dims)))
        for i, r in enumerate(limits):
            for j, d in enumerate(dims):
                v = rows.get(r, {}).get(d, 0.0)
                if not isinstance(v, (int, float, np.floating, np.integer)) or not np.isfinite(v):
                    raise ValidationError(f"stack sensitivities[{r!r}][{d!r}]", v, "a finite number")
                A[i, j] = float(v)
        self.matrix = A
        self.nominal_given = nominal is not None      # reports leave the nominal blank when it was not given
        nominal = dict(nominal or {d: 0.0 for d in dims})

        super().__init__(_LinearResponses(tuple(dims), A), {d: nominal.get(d, 0.0) for d in dims}, limits, name=name, **kw)

    def worst_case(self, lower, upper) -> tuple[np.ndarray, np.ndarray]:
        """Worst-case deviations of every response over the zones (:func:`worst_case_deviation`).

        Parameters
        ----------
        lower, upper : array_like, (n_dims,)
            Signed deviations of each dimension's zone, in ``source_names`` order (SI: m or rad).

        Returns
        -------
        (below, above) : tuple of numpy.ndarray, (n_responses,)
            The least and greatest deviation of each response from its nominal (response unit).
        """
        return worst_case_deviation(self.matrix, lower, upper)

    def rss(self, half_width) -> np.ndarray:
        """RSS half-width of every response (:func:`rss_half_width`).

        Parameters
        ----------
        half_width : array_like, (n_dims,)
            Half-widths of the zones, in ``source_names`` order (SI: m or rad).

        Returns
        -------
        numpy.ndarray, (n_responses,)
            ``sqrt(Σ_j (a_kj h_j)²)`` (response unit).
        """
        return rss_half_width(self.matrix, half_width)

    def _derive(self, P):
        # the sensitivities are given: no complex step over n dimensions (an n x n evaluation; 7.6 s at
        # n = 5 000, issue 43); the complex step of a linear function returned them exactly
        self.complex_step_check = 0.0
        return np.broadcast_to(self.matrix, (len(P),) + self.matrix.shape).copy(), "exact (linear: the sensitivities given)"

    def jacobian(self, points) -> np.ndarray:
        """``∂y_k/∂x_j = a_kj`` at every point: the given sensitivities (no differentiation).

        Parameters
        ----------
        points : (n, n_dims) or (n_dims,) array_like
            Dimension values (SI: m or rad).

        Returns
        -------
        (n, n_responses, n_dims) ndarray
            The matrix ``a`` at each point (response unit per dimension unit).
        """
        P = np.atleast_2d(np.asarray(points, dtype=float))
        return self._derive(P)[0]

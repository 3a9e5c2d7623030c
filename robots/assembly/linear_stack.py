"""A linear tolerance stack ``y_k = Σ_j a_kj x_j`` as an assembly function whose sensitivities are
given (Chase, *Dimensioning and Tolerancing Handbook* ch. 14: the arithmetic / statistical stack).

Units: sensitivities in response unit per dimension unit (e.g. m/m); dimensions SI (m or rad).
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.assembly.function import AssemblyFunction


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

"""Variable mapping of a :class:`~evotol.core.problem.ToleranceProblem` (:mod:`evotol.core.variables`,
``docs/tolerances.md``): the optimisers search the *free variables* X (n_designs, n_variables), one
per free source, a ``shared`` group being one variable for all its members. ``full`` maps X to
source tolerances T, inserting locked and fixed sources; ``to_variables`` and ``locked_part``
carry row coefficients the other way; ``as_array``, ``intervals`` and ``source_errors`` read a
design in source order and turn it into intervals and source errors (SI units: m or rad).
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from evotol.errors import ValidationError

__all__ = ["VariableMapping"]


class VariableMapping:
    """Designs between free variables, source tolerances, intervals and source errors (a mixin of
    :class:`~evotol.core.problem.ToleranceProblem`: it reads the problem's variable matrix, locked
    values, tolerances and interval shape).
    """

    def full(self, X_free: np.ndarray) -> np.ndarray:
        """Tolerances of every source from the free variables: (n, n_variables) -> (n, n_sources);
        inserts locked/fixed values and copies each shared variable to all its members.

        Parameters
        ----------
        X_free : array_like, shape (n, n_variables) or (n_variables,)
            Values of the free variables (SI: m or rad).

        Returns
        -------
        ndarray, shape (n, n_sources)
            Tolerance of every source (SI: m or rad).
        """
        X_free = np.atleast_2d(X_free)
        T = np.empty((X_free.shape[0], self.n_sources))
        T[:, self.free] = X_free
        T[:, self.locked] = self.locked_values[self.locked]
        if self.follower.any():
            T[:, self.follower] = T[:, self.leader[self.follower]]
        return T

    def to_variables(self, A: np.ndarray) -> np.ndarray:
        """Row coefficients per source (..., n_sources) -> per free variable (..., n_variables)
        (a shared variable collects its members' coefficients).

        Parameters
        ----------
        A : ndarray, shape (..., n_sources)
            Coefficients per source (units of the row per unit of tolerance).

        Returns
        -------
        ndarray, shape (..., n_variables)
            ``A @ variable_matrix``: the coefficients per free variable.
        """
        return A @ self.variable_matrix

    def locked_part(self, A: np.ndarray, power: int = 1) -> np.ndarray:
        """Row values of the locked/fixed sources: ``A[:, locked] @ t_locked**power`` (zeros if none).

        Parameters
        ----------
        A : ndarray, shape (n_rows, n_sources)
            Row coefficients per source.
        power : int
            Power of the locked tolerances (1: linear rows, 2: squared rows as in RSS).

        Returns
        -------
        ndarray, shape (n_rows,)
            The constant part of each row due to the locked sources.
        """
        lk = self.locked
        if not lk.any():
            return np.zeros(A.shape[0])
        return A[:, lk] @ self.locked_values[lk] ** power

    def as_array(self, tolerances: Mapping[str, float] | np.ndarray) -> np.ndarray:
        """A design as an array in source order; accepts a name -> value mapping (SI).

        Parameters
        ----------
        tolerances : Mapping[str, float] or array_like, shape (..., n_sources)
            Tolerances (SI: m or rad), by source name or in source order.

        Returns
        -------
        ndarray, shape (n_sources,) or (..., n_sources)
            The tolerances as floats in source order.

        Raises
        ------
        evotol.errors.ValidationError
            A mapping without a value for every source, an array whose last axis is not
            n_sources, or a value that is negative or not finite.
        """
        if isinstance(tolerances, Mapping):
            missing = [n for n in self.names if n not in tolerances]
            if missing:
                raise ValidationError("tolerances", sorted(tolerances), f"a value for every source; missing {missing}")
            t = np.array([float(tolerances[n]) for n in self.names])
        else:
            t = np.asarray(tolerances, dtype=float)
            if t.shape[-1] != self.n_sources:
                raise ValidationError("tolerances shape", t.shape, f"(..., {self.n_sources})")
        if not np.all(np.isfinite(t)) or np.any(t < 0):
            raise ValidationError("tolerances", t.tolist(), "non-negative finite values (SI)")
        return t

    def intervals(self, t) -> np.ndarray:
        """(n_sources, 2) interval ends [offset − minus·t, offset + plus·t] of design t (SI); for
        disk/ball sources [−t, t] (the bound on the norm).

        Parameters
        ----------
        t : Mapping[str, float] or array_like, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        ndarray, shape (n_sources, 2)
            Lower and upper end of each source's interval (SI: m or rad).

        Raises
        ------
        evotol.errors.ValidationError
            A bad design (see :meth:`as_array`).
        """
        t = self.as_array(t)
        return np.array([self.tolerances[n].interval(t[j]) for j, n in enumerate(self.names)])

    def source_errors(self, Z: list[np.ndarray], t: np.ndarray) -> list[np.ndarray]:
        """Map unit samples Z_j (n, dim_j; ``|z| <= 1``, centred) to errors inside the intervals of
        design t (SI): e_j = offset_j + κ_j t_j + ρ_j t_j z_j (centred sources: t_j z_j).

        Parameters
        ----------
        Z : list of ndarray, each shape (n, dim_j)
            Unit samples per source (dimensionless).
        t : ndarray, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        list of ndarray, each shape (n, dim_j)
            Source errors (SI: m or rad).
        """
        sh = self.shape
        out = []
        for j, z in enumerate(Z):
            if sh.rho[j] == 1 and sh.kappa[j] == 0 and sh.offset[j] == 0:
                out.append(z * t[j])
            else:
                out.append(sh.offset[j] + sh.kappa[j] * t[j] + sh.rho[j] * t[j] * z)
        return out

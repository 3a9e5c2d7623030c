"""Manufacturing cost of the designs of a :class:`~evotol.core.problem.ToleranceProblem`: the total
(per design, or of the free sources only), each source's share, and the derivatives per source and
per free variable. Fixed sources cost nothing; with ``shared_cost="variable"`` a shared group pays
once (``cost_weight``, :mod:`evotol.core.variables`).
"""
from __future__ import annotations

import numpy as np

__all__ = ["ProblemCosts"]


class ProblemCosts:
    """Cost of designs and its derivatives (a mixin of :class:`~evotol.core.problem.ToleranceProblem`:
    it reads the problem's tolerances' cost models, ``cost_weight``, ``locked`` and
    ``variable_matrix``).
    """

    def cost(self, T, include_locked: bool = True) -> np.ndarray:
        """Total cost of designs T (n, n_sources) -> (n,); a single design gives a scalar.
        Fixed sources cost nothing; with ``shared_cost="variable"`` a shared group pays once.
        ``include_locked=False``: only the sources driven by a variable (what an optimiser moves).

        Parameters
        ----------
        T : array_like, shape (n, n_sources) or (n_sources,)
            Designs (SI: m or rad).
        include_locked : bool
            Count the locked sources too (default); False: only the free ones.

        Returns
        -------
        ndarray, shape (n,), or float
            Total cost per design (cost units); a float for a single design.
        """
        T = np.asarray(T, dtype=float)
        single = T.ndim == 1
        T2 = np.atleast_2d(T)
        c = np.zeros(T2.shape[0])
        for j, n in enumerate(self.names):
            if self.cost_weight[j] and (include_locked or not self.locked[j]):
                c += self.tolerances[n].cost_of(T2[:, j])
        return float(c[0]) if single else c

    def free_cost(self, t: np.ndarray) -> float:
        """Cost of the sources driven by a variable at one design t (n_sources,), summed one scalar
        at a time (what the optimum's objective uses; the locked part is a constant).

        Parameters
        ----------
        t : ndarray, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        float
            Cost of the free sources (cost units).
        """
        return sum(float(self.tolerances[n].cost_of(t[j])) for j, n in enumerate(self.names)
                   if self.cost_weight[j] and not self.locked[j])

    def source_costs(self, t) -> np.ndarray:
        """Cost of each source at one design (0 where no cost is counted: fixed sources, and
        the members after the first of a group with ``shared_cost="variable"``).

        Parameters
        ----------
        t : Mapping[str, float] or array_like, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        ndarray, shape (n_sources,)
            Cost per source (cost units).

        Raises
        ------
        evotol.errors.ValidationError
            A bad design (see :meth:`as_array`).
        """
        t = self.as_array(t)
        return np.array([float(self.tolerances[n].cost_of(t[j])) * self.cost_weight[j] for j, n in enumerate(self.names)])

    def dcost(self, t: np.ndarray) -> np.ndarray:
        """∂cost/∂t_j per source (n_sources,).

        Parameters
        ----------
        t : ndarray, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        ndarray, shape (n_sources,)
            Cost derivative per source (cost units per m or rad; 0 where no cost is counted).
        """
        return np.array([float(self.tolerances[n].dcost_of(t[j])) * self.cost_weight[j] if self.cost_weight[j] else 0.0
                         for j, n in enumerate(self.names)])

    def variable_dcost(self, t: np.ndarray) -> np.ndarray:
        """∂cost/∂x_v per free variable (n_variables,) at source tolerances t.

        Parameters
        ----------
        t : ndarray, shape (n_sources,)
            One design (SI: m or rad).

        Returns
        -------
        ndarray, shape (n_variables,)
            Cost derivative per free variable (cost units per m or rad).
        """
        return self.dcost(t) @ self.variable_matrix


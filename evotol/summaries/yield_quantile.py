"""The error at the required yield: a quantile of the stated model, for the report's yield column (issue 33 item 6).

The ``yield`` measure judges a design by its probability; the error it reports per pose is the
*k-sigma equivalent* ``E·k_req/k(q)`` (:mod:`evotol.measures.builtin.statistical_yield`), which equals
the error at the required probability only when the design sits exactly on the requirement (issue
33: at E = 2 mm it showed 0.498 mm where the 99.73 % error is 0.558 mm). A report's column named
"error" must be the error: :func:`yield_quantiles` computes, per pose and component, the
``p``-quantile of ``|δp|`` (``|δθ|``) of the first-order model with the sources' stated
distributions (``Distribution``: uniform, normal with ``t = k σ``, mean shifts, disks and balls),
from ``n`` common Monte Carlo samples (seeded, the same at every pose), with the distribution-free
confidence interval of the quantile from the order statistics (binomial, 95 %).

The parameters several definitions of this module share are described once, here.

Parameters
----------
seed : int, optional
    Seed of the samples.
"""
from __future__ import annotations

import numpy as np
from scipy.stats import binom

from evotol.measures.statistical import distributions

ROWS = {"position": slice(0, 3), "orientation": slice(3, 6)}


def yield_quantiles(problem, t, probability: float, n: int = 100_000, seed: int = 0,
                    chunk: int = 16) -> dict:
    """The ``probability``-quantile of each constrained error component at every pose (first-order model).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem (sensitivities, the sources' distributions and interval shapes).
    t : array_like, shape (n_sources,)
        The design (SI: m or rad).
    probability : float
        In (0, 1), e.g. the requirement's ``required_yield``.
    n : int, optional
        Monte Carlo samples (common to every pose).
    chunk : int, optional
        Poses per batch (memory: chunk x n x 3 floats).

    Returns
    -------
    dict
        Component -> ``{"value": (n_poses,), "low": (n_poses,), "high": (n_poses,)}``: the
        quantile (m or rad) and its 95 % order-statistic interval; plus ``"n_samples"`` and
        ``"probability"``.
    """
    t = problem.as_array(t)
    Z = distributions.unit_samples([s.dim for s in problem.model.sources], problem.distributions, int(n),
                                   method="mc", seed=seed)
    E = np.concatenate(problem.source_errors(Z, t), axis=1)          # (n, n_columns), SI
    k = int(np.ceil(probability * n)) - 1                             # the order statistic of the quantile
    lo_k = max(int(binom.ppf(0.025, n, probability)) - 1, 0)
    hi_k = min(int(binom.ppf(0.975, n, probability)), n - 1)
    out = {"n_samples": int(n), "probability": float(probability)}
    for comp, _ in problem.components:
        vals = np.empty((3, problem.n_poses))
        for a in range(0, problem.n_poses, chunk):
            J = problem.jacobian[a:a + chunk, ROWS[comp]]                     # (c, 3, n_columns)
            norms = np.sort(np.linalg.norm(np.einsum("pik,sk->psi", J, E), axis=2), axis=1)
            vals[:, a:a + chunk] = norms[:, [k, lo_k, hi_k]].T
        out[comp] = {"value": vals[0], "low": vals[1], "high": vals[2]}
    return out


def largest_quantile(problem, t, probability: float, n: int = 100_000, seed: int = 0, rtol: float = 1e-9) -> dict:
    """The largest quantile over the poses, per constrained component, as a report states it.

    Where the first-order yield model is exact (every source normal: the miss probability of a
    normal error vector, :mod:`evotol.measures.statistical`), the largest quantile is the smallest
    bound ``E`` with ``min over poses P(|δ| <= E) >= probability``: one bisection on ``E`` over every
    pose at once, exact to ``rtol``. Otherwise (uniform sources and the like, which the model
    moment-matches) it is the largest of the Monte Carlo quantiles of :func:`yield_quantiles`, with
    its 95 % interval.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem.
    t : array_like, shape (n_sources,)
        The design (SI).
    probability : float
        The required yield, in (0, 1).
    n : int, optional
        Monte Carlo samples (when the model is not exact).
    rtol : float, optional
        Relative precision of the bisection.

    Returns
    -------
    dict
        Component -> ``{"value", "low", "high"}`` (m or rad; ``low == high == value`` when exact)
        and its ``"pose"`` index; ``"method"`` (``"exact (normal sources)"`` or ``"Monte Carlo"``),
        ``"n_samples"`` (0 when exact) and ``"probability"``.
    """
    t = problem.as_array(t)
    out = {"probability": float(probability)}
    comps = [c for c, _ in problem.components]
    base = problem.with_requirement(measure="yield", probability=float(probability), ppm=None, model="linear")
    exact = all(base.with_requirement(**{c: lim, **{o: None for o in comps if o != c}}).evaluate(t[None]).exact
                for c, lim in problem.components)
    if not exact:
        q = yield_quantiles(problem, t, probability, n, seed)
        out.update({"method": "Monte Carlo", "n_samples": q["n_samples"]})
        for comp in comps:
            p = int(np.argmax(q[comp]["value"]))
            out[comp] = {"value": float(q[comp]["value"][p]), "low": float(q[comp]["low"][p]),
                         "high": float(q[comp]["high"][p]), "pose": p}
        return out
    out.update({"method": "exact (normal sources)", "n_samples": 0})
    for comp, lim in problem.components:
        single = base.with_requirement(**{c: (lim if c == comp else None) for c in comps})
        wc = float(np.max(getattr(problem.evaluate(t[None], measure="worst_case"), comp)[0]))
        lo, hi = 0.0, max(wc, lim) * 1.01 + 1e-300

        def meets(E):
            return float(np.min(single.with_requirement(**{comp: E}).evaluate(t[None]).probability[0])) >= probability
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if meets(mid) else (mid, hi)
            if hi - lo <= rtol * hi:
                break
        prob = single.with_requirement(**{comp: hi}).evaluate(t[None]).probability[0]
        out[comp] = {"value": hi, "low": hi, "high": hi, "pose": int(np.argmin(prob))}
    return out

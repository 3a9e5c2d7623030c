"""The study's other methods on the random sources of a calibrated budget (issue 44 item 3 inside item 4,
docs/iso9283.md): the GA, the equal-effect rule, equal tolerances and the Lagrange closed form, each judged
like the least-cost design (:func:`evotol.calibration.random_allocation.least_cost`) by the budget's own check
(:meth:`evotol.calibration.random_budget.RandomBudget.ok`: exact quantile of the fit's error, proven worst
case, the ISO figures if required), with every systematic tolerance at its upper bound as there.

Each source's **normalised effect** per unit tolerance is what it adds alone, at tolerance 1 (SI) with every
other random source at 0, to each figure, over that figure's limit: the position figure
``max_i q_i + max_i w_i`` over the budget (less its value at ``τ = 0``, the noise alone), and with an ISO
target the calibrated AP over ``AP_budget`` and RP over its aim; ``e_k`` is the largest of these. Then:

* **equal tolerances**: every random tolerance the same value ``c`` (SI), clipped to its bounds;
* **equal effect** (the sensitivity rule): ``τ_k = s / e_k``, every source the same normalised effect;
* **Lagrange** (Spotts 1973; Chase & Greenwood 1988): least cost on the worst-case stack-up
  ``Σ_k e_k τ_k = 1`` (:func:`evotol.allocators.iso9283_baselines.stack_up`);
* **GA** (pymoo, log tolerances, feasibility first): least cost subject to the position figure with the
  quantile as ``κ_i sqrt(λ_max(C_i(τ)))`` (``κ_i`` the exact quantile's ratio at the least-cost design, the
  form :func:`least_cost` solves), the ISO AP alike and RP on the first 2 000 of the fixed draws, a whole
  population at once; the search's surrogate is not what it is judged by.

Every design is then moved onto the boundary along its ray (:meth:`RandomBudget.onto_boundary`: one common
factor, found by the exact check) and judged: ``feasible`` only if :meth:`RandomBudget.ok` holds; its cost
beside the least-cost design's.

Parameters
----------
rb : evotol.calibration.random_budget.RandomBudget
    The calibrated budget every function here reads.
"""
from __future__ import annotations

import numpy as np
from pymoo.core.problem import Problem

from evotol._runtime.blas_threads import single_threaded_blas
from evotol.allocators.iso9283_baselines import stack_up
from evotol.allocators.iso9283_ga import run_ga
from evotol.allocators.monotone import MonotoneProblem, polyblock_search
from evotol.calibration.random_budget import RandomBudget

#: what each method's design is, for the block (method -> sentence)
CALIBRATED_RULES = {
    "equal": "equal tolerances (every random tolerance the same value in SI, clipped to its bounds)",
    "sensitivity": "the equal-effect rule (each random source the same effect per unit tolerance on the calibrated "
                   "figures, over each figure's limit)",
    "lagrange": "the Lagrange closed form on the worst-case stack-up of the sources' normalised effects",
    "ga": "pymoo's GA in log space on a convex surrogate of the budget (the fit's quantile as κ sqrt(λ_max), RP on "
          "2 000 of the fixed draws)",
    "monotone": "the polyblock bracket of the least cost (Tuy 2000), started from the least-cost design",
}

#: the calibrated ``monotone``'s budget of checked designs (the exact check costs about 7 ms a design; a count, not a
#: time, so that the bracket is the same on every machine)
MONOTONE_EVALUATIONS = 150


def _figures(rb: RandomBudget, t) -> np.ndarray:
    """Each figure of a design over its limit: position, and with an ISO target AP and RP."""
    out = [rb.position(t) / rb.budget]
    if rb.AP is not None:
        out.append(rb.ap(t).max() / rb.AP)
    if rb.RP is not None:
        out.append(rb.rp_value(t).max() / rb.rp_aim)
    return np.array(out)


def normalised_effects(rb: RandomBudget) -> np.ndarray:
    """``e_k`` (module docstring): each source's largest added figure over its limit per unit tolerance.

    Parameters
    ----------

    Returns
    -------
    (K,) ndarray
        Per unit tolerance (1 / SI unit).
    """
    K = len(rb.lo)
    zero = _figures(rb, np.zeros(K))
    return np.array([(_figures(rb, np.eye(K)[k]) - zero).max() for k in range(K)])


def rule_tolerances(rb: RandomBudget, rule: str) -> np.ndarray:
    """The design of ``equal``, ``sensitivity`` or ``lagrange`` before it is moved onto the boundary (SI).

    Parameters
    ----------
    rule : str
        ``equal``, ``sensitivity`` or ``lagrange``.

    Returns
    -------
    (K,) ndarray
    """
    if rule == "equal":
        return np.full(len(rb.lo), float(np.sqrt(rb.lo.min() * rb.hi.max())))
    e = np.maximum(normalised_effects(rb), 1e-300)
    if rule == "sensitivity":
        return 1.0 / e
    return stack_up(rb.costs, rb.lo, rb.hi, e, 1.0, rss=False)


class _Surrogate(Problem):
    """The GA's problem: cost, and the largest figure over its limit minus 1 on the convex surrogate."""

    def __init__(self, rb: RandomBudget, kappa, kappa_iso, n_draws: int = 2000):
        super().__init__(n_var=len(rb.lo), n_obj=1, n_ieq_constr=1, xl=np.log(rb.lo), xu=np.log(rb.hi))
        self.rb, self.kappa, self.kappa_iso = rb, kappa, kappa_iso
        self.E = None if rb.RP is None else np.asarray(rb.iso["E"], float)[:, :n_draws]

    def _evaluate(self, X, out, *args, **kwargs):
        rb, T = self.rb, np.exp(X)
        out["F"] = sum(np.asarray(c.cost(T[:, k]), float) for k, c in enumerate(rb.costs))[:, None]
        w, q = _surrogate(T, rb.task, self.kappa)
        g = (w.max(-1) + q.max(-1)) / rb.budget                        # the budget: max w + max q over the poses
        if rb.AP is not None:                                           # AP: at each ISO pose, w + q
            g = np.maximum(g, np.add(*_surrogate(T, rb.iso_figure, self.kappa_iso)).max(-1) / rb.AP)
        if self.E is not None:
            e = self.E @ T.T                                              # (p, n, 3, designs)
            lens = np.sqrt(np.einsum("pnis,pnis->pns", e, e))
            g = np.maximum(g, (lens.mean(1) + 3 * lens.std(1, ddof=1)).max(0) / rb.rp_aim)
        out["G"] = (g - 1.0)[:, None]


def _surrogate(T, fig, kappa):
    """Per design and pose the worst case ``w_i`` and ``κ_i sqrt(λ_max(C_i))`` (m) of a calibrated figure
    (:class:`evotol.calibration.random_budget.Figure`): its convex form, for a whole population at once."""
    w = (fig.s0 + np.einsum("sk,knd->snd", T, fig.support)).max(-1) / fig.cos_delta
    lam = np.linalg.eigvalsh(fig.C0 + np.einsum("sk,knij->snij", T * T, fig.cov))[..., -1]
    return w, kappa * np.sqrt(np.maximum(lam, 1e-300))


@single_threaded_blas
def ga_tolerances(rb: RandomBudget, optimum, pop_size: int = 100, n_gen: int = 200, seed: int = 0) -> tuple:
    """The GA's design (module docstring) before it is moved onto the boundary, and its evaluations.

    Parameters
    ----------
    optimum : (K,) array_like
        The least-cost design, where ``κ`` is taken.
    pop_size, n_gen, seed : int
        pymoo's GA settings and the seed of its Latin-hypercube start.

    Returns
    -------
    tuple
        ``(τ (K,) ndarray, evaluations)``.
    """
    t0 = np.asarray(optimum, float)
    q, s = rb.task.exact(t0)
    kappa_iso = None
    if rb.AP is not None:
        qi, si = rb.iso_figure.exact(t0)
        kappa_iso = qi / np.maximum(si, 1e-300)
    X, n_eval = run_ga(_Surrogate(rb, q / np.maximum(s, 1e-300), kappa_iso), pop_size, n_gen, seed)
    return np.exp(X), n_eval


def monotone_bracket(rb: RandomBudget, optimum, max_evaluations: int = MONOTONE_EVALUATIONS, rel_gap: float = 1e-2,
                     batch: int = 16) -> tuple:
    """The polyblock bracket of the least cost in the calibrated budget (:func:`polyblock_search` in ``log τ``, the
    least-cost design as the incumbent): ``(τ, bracket)``.

    The position figure and the calibrated AP never decrease when a tolerance grows (module docstring of
    :mod:`evotol.calibration.random_budget`), so without an RP target the lower bound is proven; the RP on fixed
    draws is not monotone (:mod:`evotol.allocators.iso9283_monotone`), and with it the lower bound holds for the
    designs whose every smaller design meets RP.

    Parameters
    ----------
    optimum : (K,) array_like
        The least-cost design (SI), feasible by the budget's check.
    max_evaluations : int
        The search's budget of checked designs (it stops at the first round past it).
    rel_gap, batch
        As :func:`evotol.allocators.monotone.polyblock_search` (the study's ``[methods] monotone`` settings).

    Returns
    -------
    tuple
        ``(τ (K,) ndarray, dict)``: the best design found (the incumbent when none is cheaper) and ``lower_bound``,
        ``upper_bound``, ``gap``, ``rounds``, ``evaluations``, ``converged``, ``stop``, ``lower_bound_proven_for``.
    """
    costs = rb.costs

    def var_costs(X):
        T = np.exp(X)
        return np.stack([np.asarray(c.cost(T[:, k]), float) for k, c in enumerate(costs)], 1)

    mp = MonotoneProblem(np.log(rb.lo), np.log(rb.hi), lambda X: np.array([rb.ok(t) for t in np.exp(X)]),
                         lambda X: var_costs(X).sum(1), var_costs)
    t0 = np.asarray(optimum, float)
    res = polyblock_search(mp, upper_bound=rb.cost(t0), max_evaluations=int(max_evaluations), rel_gap=float(rel_gap),
                           batch=int(batch))
    t = t0 if res["x"] is None else np.exp(res["x"])
    keys = ("lower_bound", "upper_bound", "gap", "rounds", "evaluations", "converged", "stop")
    return t, {**{k: res[k] for k in keys},
               "lower_bound_proven_for": "every design" if rb.RP is None else "the designs whose every smaller design "
                                         "meets RP (the sampled RP is not monotone)"}


def calibrated_design(rb: RandomBudget, method: str, optimum: dict, names, seed: int = 0, ga=None,
                      monotone=None) -> dict:
    """One method's random tolerances in the calibrated budget, moved onto the boundary and judged (SI).

    Parameters
    ----------
    method : str
        A key of :data:`CALIBRATED_RULES`.
    optimum : dict
        The least-cost design's result (its ``tolerances`` name -> value and ``cost``).
    names : sequence of str
        The random sources' names.
    seed : int
        The GA's seed unless ``ga`` sets one.
    ga : dict or None
        The GA's ``pop_size``, ``n_gen`` and ``seed``.
    monotone : dict or None
        The bracket's ``max_evaluations``, ``rel_gap`` and ``batch`` (:func:`monotone_bracket`'s defaults for
        the ones not given).

    Returns
    -------
    dict
        ``tolerances`` (name -> SI), ``cost``, ``gap_to_optimum`` (cost / least cost − 1), ``feasible``,
        ``figures`` (position over the budget, and AP, RP over theirs: at most 1 when feasible), with the ISO
        target ``iso`` (:meth:`RandomBudget.report`), for the GA ``evaluations``, and ``meaning``.
    """
    extra = {}
    if method == "monotone":
        t, extra = monotone_bracket(rb, [optimum["tolerances"][n] for n in names], **(monotone or {}))
        extra = {k: (float(v) if isinstance(v, (float, np.floating)) else v) for k, v in extra.items()}
    elif method == "ga":
        opts = {"pop_size": 100, "n_gen": 200, "seed": seed, **(ga or {})}
        t, n = ga_tolerances(rb, [optimum["tolerances"][n] for n in names], opts["pop_size"], opts["n_gen"], opts["seed"])
        extra = {**opts, "evaluations": n}
    else:
        t = rule_tolerances(rb, method)
    if method != "monotone":                  # the bracket's design is feasible as found
        t = rb.onto_boundary(t)
    cost = rb.cost(t)
    out = {"tolerances": {n: float(v) for n, v in zip(names, t)}, "cost": cost,
           "gap_to_optimum": cost / optimum["cost"] - 1, "feasible": bool(rb.ok(t)),
           "figures": _figures(rb, t).tolist(), **extra,
           "meaning": CALIBRATED_RULES[method] + ", in the calibrated budget with every systematic tolerance at its "
                      "upper bound as the least-cost design; moved onto the boundary by one common factor and judged by "
                      "the same check (exact quantile of the fit's error, proven worst case" +
                      (", ISO AP and RP on the fixed draws)" if rb.iso is not None else ")")}
    if rb.iso is not None:
        out["iso"] = rb.report(t)
    return out

"""The data of the report's what-if explorer (:mod:`evotol.reporting.explorer`), and how tight it is.

The explorer recomputes, in the browser, the cost and the first-order errors of any tolerance
vector at every allocation pose: the worst case h = max_u Σ_j (ρ_j t_j ‖B_jᵀu‖ + κ_j t_j u·b_j +
offset_j u·b_j) (:mod:`evotol.measures.linear`) over a fixed sample of directions u, and the RSS error
sqrt(Σ_j (ρ_j t_j s_pj)²) + ‖shift‖. It gets the sensitivity blocks B_j of every pose, the
directions the Python worst case starts from (:meth:`ToleranceProblem.coefficients`), the
spectral norms s_pj, the interval shapes and every source's cost model as its kind and parameters
(evaluated in JavaScript by the same formula as :mod:`cost_models`).

The sampled maximum is a lower bound of the certified worst case: for a direction sample with
covering angle δ it is at least cos δ times it (a convex set's farthest point lies within δ of a
sampled direction), so the page is at most 1 − cos δ low. :func:`sample_tightness` measures the
actual shortfall against :meth:`ToleranceProblem.evaluate` on the methods' allocations and on
random tolerance vectors within the bounds.

The explorer is omitted, with the reason, for problems it cannot recompute: joint clearances
(the certified engine is not a fixed linear map), a cost model it cannot express (a Python
callable, a plugin model), or more sensitivity numbers than a page should carry.
"""
from __future__ import annotations

import numpy as np

from evotol.cost_models import registry
from evotol.cost_models.base import CostModel
from evotol.cost_models.compound import SumCost
from evotol.core.problem import ToleranceProblem
from evotol.robots.mechanism.callouts.model import zone_per_t

#: the cost models the page evaluates (``explorer.js``: same kind, same formula, same parameters)
JS_COST_MODELS = ("exponential", "power", "reciprocal_power", "reciprocal", "reciprocal_square", "exp_reciprocal",
                  "polynomial3", "polynomial4", "linear_exponential")
#: the page carries at most this many sensitivity numbers (poses × 3 × columns × components)
MAX_NUMBERS = 400_000
#: random tolerance vectors (log-uniform within the bounds) on which the sample's tightness is measured
N_TIGHTNESS = 24


def cost_model_spec(model: CostModel | None) -> dict | None:
    """``{"model": kind, "params": [...], "scale": s}`` of a model the page can evaluate (a sum:
    ``{"model": "sum", "terms": [...]}``); ``{"model": "none"}`` for a fixed source; None when
    the page cannot express it (a subclass or plugin may change the formula).

    Parameters
    ----------
    model : CostModel or None
        A source's cost model; None for a fixed source (no cost).

    Returns
    -------
    dict or None
        The model's kind (one of ``JS_COST_MODELS``), coefficients ``params`` and ``scale`` (the
        model's unit of t, m or rad), or a sum's ``terms``; None when the page cannot evaluate it.
    """
    if model is None:
        return {"model": "none"}
    if type(model) is SumCost:
        terms = [cost_model_spec(m) for m in model.models]
        return None if any(t is None for t in terms) else {"model": "sum", "terms": terms}
    if model.name in JS_COST_MODELS and type(model) is registry.BUILTIN.get(model.name):
        return {"model": model.name, "params": model.p.tolist(), "scale": float(model.scale)}
    return None


def omitted_reason(problem: ToleranceProblem) -> str | None:
    """Why the page has no explorer for ``problem`` (None when it has one).

    Returns
    -------
    str or None
        The reason, one sentence: joint clearances, a cost model the page cannot evaluate, or
        more than ``MAX_NUMBERS`` sensitivity numbers; None when the explorer can be drawn.
    """
    if problem.clearances is not None:
        return ("the problem allocates joint clearances, whose certified worst case the page cannot recompute "
                "(it is not a fixed linear map of the tolerances)")
    for n, tol in problem.tolerances.items():
        if cost_model_spec(tol.cost) is None:
            return (f"the cost model of source {n} ({tol.cost!r}) has no formula the page can evaluate; "
                    f"the page knows {', '.join(JS_COST_MODELS)} and their sums")
    size = problem.n_poses * 3 * problem.jacobian.shape[2] * len(problem.components)
    if size > MAX_NUMBERS:
        return (f"{problem.n_poses} poses × {problem.jacobian.shape[2]} columns is {size} sensitivity numbers, "
                f"more than the page carries ({MAX_NUMBERS}); use fewer allocation poses for the explorer")
    return None


def sampled_worst_case(problem: ToleranceProblem, T: np.ndarray, component: str) -> np.ndarray:
    """The page's worst case: max over the direction sample of h(u), (n_designs, n_poses) (m or rad).

    A lower bound of the certified worst case (module docstring).

    Parameters
    ----------
    problem : ToleranceProblem
        Its support coefficients (:meth:`ToleranceProblem.coefficient_blocks`) are used.
    T : ndarray, shape (n_designs, n_sources) or (n_sources,)
        Tolerance vectors, SI (m or rad), in source order.
    component : {"position", "orientation"}
        The error component.

    Returns
    -------
    ndarray, shape (n_designs, n_poses)
        The sampled worst-case error at every pose, m (position) or rad (orientation).
    """
    out = []
    for _, coeff in problem.coefficient_blocks(component):     # one block, or blocks of poses (issue 43)
        c, T2 = coeff[0], np.atleast_2d(T)
        grid = np.einsum("pdj,nj->npd", c, T2) if isinstance(c, np.ndarray) else c.grid(np.asarray(T2, float))
        if len(coeff) > 3:
            grid = grid + coeff[3][None]
        out.append(grid.max(axis=2))
    return out[0] if len(out) == 1 else np.concatenate(out, axis=1)


def sample_tightness(problem: ToleranceProblem, designs: dict[str, np.ndarray], seed: int = 0) -> dict:
    """How far below the certified worst case the page's sampled worst case lies.

    Parameters
    ----------
    designs : dict
        Method name -> tolerance vector (SI, source order); :data:`N_TIGHTNESS` random vectors
        (log-uniform within the bounds, ``seed``) are added.
    seed : int
        Seed of those random vectors (default 0).

    Returns
    -------
    dict
        Per component: ``n_directions`` (count), ``covering_angle`` (rad), ``guaranteed`` (1 − cos δ:
        the page is never lower than this fraction below the true value), ``measured`` (largest
        1 − sampled / certified at the largest error of a design), ``measured_any_pose`` (the same
        over every pose), ``n_designs`` (count), ``worst_pose_agrees``.
    """
    rng = np.random.default_rng(seed)
    f = problem.free
    lo, hi = np.log(problem.lower[f]), np.log(problem.upper[f])
    X = np.exp(lo + (hi - lo) * rng.random((N_TIGHTNESS, int(f.sum()))))
    T = np.vstack([np.atleast_2d(problem.full(problem.as_array(t)[f][None])) for t in designs.values()]
                  + [problem.full(X)])
    ev = problem.evaluate(T, measure="worst_case")
    out = {}
    for comp, _ in problem.components:
        exact = getattr(ev, comp)
        page = sampled_worst_case(problem, T, comp)
        D, delta = problem.directions(comp)
        ratio = np.where(exact > 0, page / np.where(exact > 0, exact, 1.0), 1.0)
        worst = np.argmax(exact, axis=1)
        at_max = page.max(axis=1) / exact.max(axis=1)
        out[comp] = {"n_directions": int(len(D)), "covering_angle": float(delta), "guaranteed": float(1 - np.cos(delta)),
                     "measured": float(np.max(1 - at_max)), "measured_any_pose": float(np.max(1 - ratio)),
                     "n_designs": int(len(T)), "worst_pose_agrees": float(np.mean(np.argmax(page, axis=1) == worst))}
    return out


def explorer_data(problem: ToleranceProblem, designs: dict[str, np.ndarray], seed: int = 0) -> dict:
    """Everything the page's explorer needs (SI), or ``{"omitted": reason}``.

    Parameters
    ----------
    designs : dict
        Method name -> tolerance vector (SI, source order): the explorer's starting points.
    seed : int
        Seed of the random vectors of :func:`sample_tightness`.

    Returns
    -------
    dict
        ``sources`` (name, group, unit, rho, kappa, offset, minus, plus, zone_per_t (the drawn zone,
        :func:`evotol.summaries.drawing.tolerance_zone`), width (cost width factor),
        cost_weight, locked, cost), ``variables`` (name, members, lower, upper), ``components``
        (name, limit, directions, covering_angle, blocks (n_poses, 3, columns), owner (column ->
        source), sensitivity (n_poses, n_sources)), ``starts`` (method -> per-variable values),
        ``tightness`` (:func:`sample_tightness`), ``measure``.
    """
    reason = omitted_reason(problem)
    if reason is not None:
        return {"omitted": reason}
    sh = problem.shape
    sources, per_t = [], zone_per_t(problem.model)
    for j, (n, s) in enumerate(zip(problem.names, problem.error_model.sources)):
        tol = problem.tolerances[n]
        sources.append({"name": n, "group": s.group, "unit": s.unit, "dim": s.dim, "rho": float(sh.rho[j]),
                        "kappa": float(sh.kappa[j]), "offset": float(sh.offset[j]), "width": float(tol.width_factor),
                        # the drawn zone offset - minus·t·z .. offset + plus·t·z (evotol.summaries.drawing.tolerance_zone)
                        "minus": float(tol.minus), "plus": float(tol.plus),
                        "zone_per_t": float(per_t.get(n, 1.0)),
                        "cost_weight": float(problem.cost_weight[j]),
                        "locked": None if not problem.locked[j] else float(problem.locked_values[j]),
                        "cost": cost_model_spec(tol.cost)})
    fi = np.flatnonzero(problem.free)
    M = problem.variable_matrix
    variables = [{"name": v, "members": np.flatnonzero(M[:, k]).tolist(), "lower": float(problem.lower[j]),
                  "upper": float(problem.upper[j]), "unit": problem.error_model.sources[j].unit}
                 for k, (v, j) in enumerate(zip(problem.variables, fi))]
    owner = np.repeat(np.arange(problem.n_sources), [B.shape[2] for B in problem.blocks["position"]]).tolist()
    components = []
    for comp, lim in problem.components:
        D, delta = problem.directions(comp)
        components.append({"name": comp, "limit": float(lim), "directions": D.tolist(), "covering_angle": float(delta),
                           "blocks": np.concatenate(problem.blocks[comp], axis=2).tolist(), "owner": owner,
                           "sensitivity": problem.sensitivities[comp].tolist()})
    starts = {m: problem.as_array(t)[problem.free].tolist() for m, t in designs.items()}
    return {"measure": problem.requirement.measure, "sources": sources, "variables": variables,
            "components": components, "starts": starts,
            "tightness": sample_tightness(problem, designs, seed)}

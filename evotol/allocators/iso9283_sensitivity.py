"""The sensitivity ("equal effect") allocation of systematic and random sources under ISO 9283 AP and RP
(issue 44 item 3, docs/iso9283.md): the rule the accuracy-synthesis literature compares against, on the
problem of :func:`evotol.allocators.iso9283.allocate_iso9283`, so that its certified optimum shows what the
rule costs.

Rule (each step stated so that it can be redone by hand):

1. **AP shares.** A source's largest effect on the barycentre per unit tolerance, over the ISO poses:
   ``a_j = max_p ‖J_p e_j‖`` for a free systematic column ``j`` (``J_p`` the position rows of the
   first-order map at pose ``p``), ``a_k = max_p (‖J_p C_pk‖ + Σ_i ‖J_p e_i‖ |H_pik|)`` for a random source
   ``k`` whose fixed part (a lost motion's offset per approach) moves the barycentre (``C``, ``H`` the
   offset box's centre and half-widths per unit tolerance). Every one of the ``m_AP`` sources with
   ``a > 0`` gets the same share: ``a t = AP / m_AP`` (linear stack-up: the sum of the per-source maxima
   bounds AP, as the worst-case sensitivity rule of :mod:`evotol.allocators.sensitivity`).
2. **RP shares.** A random source's RP alone per unit tolerance, ``ρ_k = max_p RP_p(e_k)`` (``E l + 3 std l``
   on the optimum's fixed draws, with only source ``k`` at tolerance 1); every one of the ``K_RP`` sources
   with ``ρ > 0`` gets ``ρ τ = RP / sqrt(K_RP)`` (root-sum-square stack-up). A source in both lists
   takes the smaller tolerance.
3. **Onto the boundary.** AP is positively homogeneous of degree 1 in ``(t, τ)`` and RP in ``τ``: the
   tolerances are scaled by one common factor per figure so that AP's proven bound and the sampled RP
   reach the requirement (:func:`evotol.allocators.iso9283_ga.scale_to_boundary`, a few steps), then
   clipped to their bounds. The shares stay equal; the factor is set by the figures themselves, so the
   rule here is less conservative than its triangle-inequality form.
4. **Judged** like every allocator's design by :func:`evotol.allocators.iso9283.iso_check`: called
   feasible only if the proven AP bound meets AP and the RP on the fixed draws meets RP.

A source with no effect on either figure gets its upper bound; a systematic column that is not free keeps
its lower bound (its given value), as in the optimum.
"""
from __future__ import annotations

import numpy as np

from evotol.allocators.iso9283 import iso_check, iso_terms
from evotol.allocators.iso9283_ga import design_cost, population_figures, scale_to_boundary


def source_effects(terms: dict) -> tuple[np.ndarray, np.ndarray]:
    """Each source's effect per unit tolerance on the two figures (steps 1-2 of the rule, module docstring).

    Parameters
    ----------
    terms : dict
        The problem's parts (:func:`evotol.allocators.iso9283.iso_terms`): its first-order map and the lost
        motion's box give ``a``, its fixed draws ``rho``.

    Returns
    -------
    a : (m + K,) ndarray
        Largest effect on the barycentre over the poses (m per unit tolerance): ``max_p ‖J_p e_j‖`` for a
        systematic column, ``max_p (‖J_p C_pk‖ + Σ_i ‖J_p e_i‖ |H_pik|)`` for a random source.
    rho : (K,) ndarray
        RP with only random source ``k`` at tolerance 1, largest over the poses (m per unit tolerance;
        zeros without RP).
    """
    m, K, J, C, H = (terms[k] for k in ("m", "K", "J", "C", "H"))
    col = np.linalg.norm(J, axis=1)                                          # (p, m): ‖J_p e_j‖
    a = np.concatenate([col.max(0), (np.linalg.norm(np.einsum("pim,pmk->pik", J, C), axis=1)
                                     + np.einsum("pm,pmk->pk", col, np.abs(H))).max(0) if K else np.zeros(0)])
    rho = population_figures(terms, np.eye(m + K)[m:])[1].max(1) if terms["RP"] is not None and K else np.zeros(K)
    return a, rho


def equal_effect_shares(terms: dict) -> np.ndarray:
    """Steps 1-2 of the rule (module docstring): the tolerances before scaling onto the boundary (SI).

    Parameters
    ----------
    terms : dict
        :func:`evotol.allocators.iso9283.iso_terms`.

    Returns
    -------
    (m + K,) ndarray
        Systematic then random tolerances; no effect: upper bound; not free: lower bound.
    """
    m, K = terms["m"], terms["K"]
    a, rho = source_effects(terms)
    t = terms["hi"].copy()
    on_ap = terms["var"] & (a > 1e-12 * a.max(initial=0))
    if terms["AP"] is not None and on_ap.any():
        t[on_ap] = terms["AP"] / on_ap.sum() / a[on_ap]
    on_rp = rho > 0
    if on_rp.any():
        tau = np.full(K, np.inf)
        tau[on_rp] = terms["RP"] / np.sqrt(on_rp.sum()) / rho[on_rp]
        t[m:] = np.where(on_rp, np.minimum(tau, np.where(on_ap[m:], t[m:], np.inf)), t[m:])
    return np.where(terms["var"], np.clip(t, terms["lo"], terms["hi"]), terms["lo"])


def rule_design(terms: dict, costs, shares: np.ndarray, iters: int = 6) -> dict:
    """Step 3-4 of a rule: its tolerances scaled onto the AP/RP boundary and judged like every allocator's design.

    Parameters
    ----------
    terms : dict
        The problem's parts (:func:`evotol.allocators.iso9283.iso_terms`): the bounds, draws and requirement the
        design is scaled onto and judged by.
    costs : list of evotol.cost_models.base.CostModel or None
        Per column, systematic then random (:func:`evotol.allocators.iso9283_ga.design_cost`).
    shares : (m + K,) ndarray
        The rule's tolerances before scaling (SI).
    iters : int
        Scaling steps (:func:`evotol.allocators.iso9283_ga.scale_to_boundary`).

    Returns
    -------
    dict
        ``systematic`` (m,), ``random`` (K,) tolerances (SI), ``shares``, ``cost``, ``AP`` and ``AP_bound`` (p,),
        ``RP``, ``RP_fresh`` (p,), all m, ``feasible`` (:func:`evotol.allocators.iso9283.iso_check`).
    """
    t = scale_to_boundary(terms, shares[None], iters=iters)[0]
    chk = iso_check(terms, t)
    return {"systematic": t[:terms["m"]], "random": t[terms["m"]:], "shares": shares,
            "cost": float(design_cost(costs, t[None])[0]), "AP": chk["ap"][:, 0], "AP_bound": chk["ap"][:, 1],
            "RP": chk["RP"], "RP_fresh": chk["RP_fresh"], "feasible": chk["feasible"]}


def allocate_iso9283_sensitivity(robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds,
                                 AP, RP, *, n_samples: int = 10000, seed: int = 0) -> dict:
    """The equal-effect tolerances meeting AP (proven bound) and RP at every pose (module docstring).

    Parameters
    ----------
    robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, AP, RP, n_samples, seed
        As :func:`evotol.allocators.iso9283.allocate_iso9283` (SI; the RP draws' seed: the optimum's with the
        same seed).

    Returns
    -------
    dict
        ``systematic`` (m,), ``random`` (K,) tolerances (SI), ``shares`` (m + K,) the tolerances of steps 1-2,
        ``cost``, ``AP`` and ``AP_bound`` (p,), ``RP``, ``RP_fresh`` (p,), all m, ``feasible``
        (:func:`evotol.allocators.iso9283.iso_check`).

    Raises
    ------
    evotol.errors.ValidationError
        As :func:`evotol.allocators.iso9283.iso_terms`.
    """
    terms = iso_terms(robot, positions, sys_bounds, free, sources, rand_bounds, AP, RP, None, n_samples, seed)
    return rule_design(terms, list(sys_costs) + list(rand_costs), equal_effect_shares(terms))

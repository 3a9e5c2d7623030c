"""Choi et al. 2000 (as coded in yue-w/ToleranceAllocation): the overrunning clutch with process
selection, machining cost plus Taguchi quality loss, under the statistical contact-angle limit.

For A = 0, 20, 100 (K = A/T², T = 0.035 rad) the study computes the exact certified optimum of
machining cost + expected loss with process choice (branch and bound, checked by enumerating the
36 combinations), the GA and NSGA-II on the same problem, and recomputes each published
allocation beside it (processes, machining cost, loss, total, RSS angle, whether it holds the
limit), with the difference split into a process-choice part and a tolerance part. It repeats the
optimum under the worst-case limit, settles the cage nominal (101.69 mm in the code, 101.6 mm in
the literature) from the published numbers, and checks the optimum on the nonlinear angle by
Monte Carlo. Data and conventions: ``evotol/studies/_choi2000.py``, docs/process_selection.md.
"""
from __future__ import annotations

import time

import numpy as np

from evotol.allocators.nonlinear_limit import allocate_nonlinear_limit
from evotol.allocators.optimum import allocate_optimum
from evotol.allocators.process import (ProcessProblem, ProcessResult, allocate_process_ga, allocate_process_optimum,
                                       process_front)
from evotol.studies import Study, StudyResult
from evotol.studies import _choi2000 as choi
from evotol.studies._choi2000 import load, problem  # noqa: F401  (the study's data and problem, public here)
from evotol.studies._process_benchmarks import _mc_nonlinear

from evotol.units import MM
CONFIG = {"seed": 0, "pop_size": 60, "n_gen": 100, "n_mc": 200_000}
QUICK = {"pop_size": 30, "n_gen": 30, "n_mc": 20_000}


def design(pp: ProcessProblem, ids, t_mm) -> dict:
    """One design judged on ``pp``: processes (1-based ids), t (mm), machining cost, expected loss,
    total, RSS and worst-case angle (rad) and whether it holds the problem's limit.

    Parameters
    ----------
    pp : evotol.allocators.process.ProcessProblem
        The clutch problem (from ``_choi2000.problem``); its requirement's measure (``"rss"`` or
        ``"worst_case"``) decides which angle is held against the limit.
    ids : sequence of int
        Process per dimension X1..X4, 1-based as in the source.
    t_mm : sequence of float
        Tolerance per dimension, mm.

    Returns
    -------
    dict
        ``processes``, ``tolerances_mm`` (mm), ``machining_cost``, ``quality_loss`` and
        ``total_cost`` (cost units of the data), ``rss_rad`` and ``worst_case_rad`` (first-order
        contact-angle variation, rad), ``limit_rad`` (rad), ``measure_over_limit``
        (dimensionless), ``holds_limit`` and ``in_process_ranges`` (bool).
    """
    ch = np.asarray(ids, dtype=int) - 1
    T = np.asarray(t_mm, dtype=float) * MM
    S = pp.robot.gradient[0]
    L = float(pp.robot.limits[0])
    loss = float(pp.quality_loss(T)[0])
    total = float(pp.cost(ch, T)[0])
    rss, wc = float(np.sqrt(np.sum((S * T) ** 2))), float(np.sum(np.abs(S) * T))
    held = rss if pp.requirement.measure == "rss" else wc
    return {"processes": [int(i) for i in ids], "tolerances_mm": [float(t) for t in np.asarray(t_mm)],
            "machining_cost": total - loss, "quality_loss": loss, "total_cost": total, "rss_rad": rss,
            "worst_case_rad": wc, "limit_rad": L, "measure_over_limit": held / L,
            "holds_limit": bool(held <= L * (1 + 1e-9)), "in_process_ranges": bool(pp.in_ranges(ch, T)[0])}


def of_result(pp: ProcessProblem, r: ProcessResult) -> dict:
    """An allocator's result judged on ``pp`` by :func:`design`.

    Parameters
    ----------
    pp : evotol.allocators.process.ProcessProblem
        The clutch problem.
    r : evotol.allocators.process.ProcessResult
        Result whose ``processes`` (1-based ids) and ``tolerances`` (m) are judged.

    Returns
    -------
    dict
        The :func:`design` dict of those processes and tolerances.
    """
    ids = [int(r.processes[n]) for n in pp.names]
    return design(pp, ids, [r.tolerances[n] / MM for n in pp.names])


def optimum_on(pp: ProcessProblem, ids) -> dict:
    """The certified convex optimum with the processes fixed at ``ids`` (1-based).

    Parameters
    ----------
    pp : evotol.allocators.process.ProcessProblem
        The clutch problem.
    ids : sequence of int
        Process per dimension, 1-based.

    Returns
    -------
    dict
        The :func:`design` dict of the optimum, plus ``certificate_gap`` (relative gap of
        :func:`evotol.allocators.optimum.allocate_optimum`'s certificate).
    """
    ch = np.asarray(ids, dtype=int) - 1
    r = allocate_optimum(pp.subproblem(ch))
    out = design(pp, ids, r.t / MM)
    out["certificate_gap"] = float(r.certificate["gap"])
    return out


def onto_limit(pp: ProcessProblem, ids, t_mm) -> np.ndarray:
    """A design outside the RSS limit pulled onto it inside its process ranges: t ← clip(t·L/RSS)
    repeated (tolerances at a range's lower end stay there), in mm.

    Parameters
    ----------
    pp : evotol.allocators.process.ProcessProblem
        The clutch problem (its first response's gradient and limit define the RSS).
    ids : sequence of int
        Process per dimension, 1-based (its range clips the tolerances).
    t_mm : sequence of float
        Tolerances, mm.

    Returns
    -------
    (n_sources,) ndarray
        Tolerances, mm: unchanged when the RSS already holds the limit, otherwise scaled down
        and clipped (at most 200 rounds; the limit may still be exceeded if every tolerance
        reaches its range's lower end).
    """
    ch = np.asarray(ids, dtype=int) - 1
    idx = np.arange(pp.n_sources)
    lo, hi = pp.lo[idx, ch], pp.hi[idx, ch]
    S, L = pp.robot.gradient[0], float(pp.robot.limits[0])
    T = np.asarray(t_mm, dtype=float) * MM
    for _ in range(200):
        ratio = float(np.sqrt(np.sum((S * T) ** 2))) / L
        if ratio <= 1 + 1e-12:
            break
        T = np.clip(T / ratio, lo, hi)
    return T / MM


def explain(opt: dict, pub: dict, same_proc_opt: dict, scaled: dict) -> dict:
    """Split published − optimum into the process choice and the tolerances on those processes;
    ``scaled``: the published design scaled onto the limit when it lies outside (t × L / RSS).

    Parameters
    ----------
    opt : dict
        The optimum, a :func:`design` dict.
    pub : dict
        The published allocation, a :func:`design` dict.
    same_proc_opt : dict
        The optimum on the published processes (:func:`optimum_on`).
    scaled : dict
        The published design pulled onto the limit (:func:`design` of :func:`onto_limit`); used
        only when ``pub`` does not hold the limit.

    Returns
    -------
    dict
        ``same_processes`` (bool), ``process_choice_part`` and ``tolerance_part`` (cost units),
        ``max_relative_tolerance_difference`` (dimensionless), ``text`` (the explanation) and,
        when the published design exceeds the limit, ``published_scaled_to_limit_total_cost``
        (cost units) and ``published_scaled_to_limit_over_optimum`` (relative).
    """
    process_part = same_proc_opt["total_cost"] - opt["total_cost"]
    tolerance_part = pub["total_cost"] - same_proc_opt["total_cost"]
    same = pub["processes"] == opt["processes"]
    dt = max(abs(a / b - 1) for a, b in zip(pub["tolerances_mm"], same_proc_opt["tolerances_mm"]))
    words = [f"published total {pub['total_cost']:.5f} vs optimum {opt['total_cost']:.5f} "
             f"(relative {pub['total_cost'] / opt['total_cost'] - 1:+.2e})."]
    if same:
        words.append("Same processes as the optimum.")
    else:
        words.append(f"Processes {pub['processes']} instead of {opt['processes']}: the best allocation on the published "
                     f"processes costs {process_part:+.5f} more than the optimum.")
    words.append(f"On its processes the published tolerances cost {tolerance_part:+.3g} against that choice's "
                 f"certified optimum (largest relative tolerance difference {dt:.2%}).")
    out = {"same_processes": same, "process_choice_part": process_part, "tolerance_part": tolerance_part,
           "max_relative_tolerance_difference": dt}
    if not pub["holds_limit"]:
        words.append(f"It exceeds the limit by {pub['measure_over_limit'] - 1:.3%} (RSS {pub['rss_rad']:.6f} rad "
                     f"vs {pub['limit_rad']} rad), so it is not feasible as printed; pulled onto the limit inside its "
                     f"process ranges (t ← clip(t·T/RSS), repeated) it costs {scaled['total_cost']:.5f} "
                     f"(relative to the optimum {scaled['total_cost'] / opt['total_cost'] - 1:+.2e}).")
        out["published_scaled_to_limit_total_cost"] = scaled["total_cost"]
        out["published_scaled_to_limit_over_optimum"] = scaled["total_cost"] / opt["total_cost"] - 1
    out["text"] = " ".join(words)
    return out


def run_case(data: dict, cage: float, A: float, pub: dict | None, config: dict) -> dict:
    """One quality-loss case: the RSS and worst-case optima and the published allocation.

    Branch and bound checked by enumeration, GA and NSGA-II front, nonlinear Monte Carlo at the
    optimum, the published design with its split of the difference (:func:`explain`), the
    worst-case optimum and the allocation that holds the nonlinear worst-case limit.

    Parameters
    ----------
    data : dict
        The Choi 2000 data (``_choi2000.load``).
    cage : float
        Cage nominal X4, mm (101.69 or 101.6).
    A : float
        Taguchi loss coefficient A (cost units); K = A/T² with T = 0.035 rad.
    pub : dict or None
        The published allocation for this A (``_choi2000.published``: ``processes`` 1-based,
        ``t_mm`` in mm, ``processes_stated``), or ``None`` if there is none.
    config : dict
        Study config: ``seed``, ``pop_size``, ``n_gen`` (GA and NSGA-II) and ``n_mc`` (Monte
        Carlo samples).

    Returns
    -------
    dict
        JSON-ready case: ``optimum``, ``enumeration``, ``ga``, ``nsga2``,
        ``mc_nonlinear_at_optimum``, ``worst_case`` and, given ``pub``, ``published``,
        ``optimum_on_published_processes`` and ``difference``. Costs in cost units,
        tolerances in mm, angles in rad.
    """
    kw = {k: config[k] for k in ("pop_size", "n_gen", "seed")}
    pp = choi.problem(data, cage, "rss", A)
    bb = allocate_process_optimum(pp)
    en = allocate_process_optimum(pp, method="enumerate")
    opt = of_result(pp, bb)
    opt["certificate"] = {**bb.certificate, "n_nodes": bb.n_nodes, "n_convex_solves": bb.n_convex_solves,
                          "n_combinations": bb.n_combinations}
    ga = allocate_process_ga(pp, **kw)
    front = process_front(pp, **kw)
    best = front.cheapest_feasible()
    case = {"quality_loss_A": A, "K_per_rad2": A / float(pp.robot.limits[0]) ** 2, "optimum": opt,
            "enumeration": {"total_cost": en.cost, "n_convex_solves": en.n_convex_solves,
                            "same_optimum": bool(abs(en.cost - bb.cost) <= 1e-9 * bb.cost)},
            "ga_over_optimum": ga.cost / bb.cost - 1, "ga": of_result(pp, ga),
            "nsga2": {"front_size": len(front.table), "cheapest_feasible_total_cost": float(best["cost"]),
                      "cheapest_feasible_over_optimum": float(best["cost"]) / bb.cost - 1, "seconds": front.seconds},
            "mc_nonlinear_at_optimum": _mc_nonlinear(pp, bb.tolerances, config["n_mc"], config["seed"])}
    if pub is not None:
        p = design(pp, pub["processes"], pub["t_mm"])
        p["processes_stated_in_source"] = pub["processes_stated"]
        lb = bb.certificate["incumbent"] * (1 - bb.certificate["rtol"])     # every design that holds the limit costs >= lb
        p["certificate"] = {"proven_lower_bound": lb, "gap_to_proven_lower_bound": (p["total_cost"] - lb) / p["total_cost"],
                            "holds_limit": p["holds_limit"],
                            "note": "the branch-and-bound certificate of the optimum bounds every design that holds the "
                                    "limit; a published design outside the limit is not covered by it"}
        case["published"] = p
        same = optimum_on(pp, pub["processes"])
        case["optimum_on_published_processes"] = same
        scaled = design(pp, pub["processes"], onto_limit(pp, pub["processes"], pub["t_mm"]))
        case["difference"] = explain(opt, p, same, scaled)
    wc = choi.problem(data, cage, "worst_case", A)
    wbb = allocate_process_optimum(wc)
    wopt = of_result(wc, wbb)
    wopt["certificate"] = {**wbb.certificate, "n_nodes": wbb.n_nodes, "n_convex_solves": wbb.n_convex_solves}
    case["worst_case"] = {"optimum": wopt, "over_rss_optimum": wbb.cost / bb.cost - 1,
                          "enumeration_total_cost": allocate_process_optimum(wc, method="enumerate").cost,
                          "mc_nonlinear_at_optimum": _mc_nonlinear(wc, wbb.tolerances, config["n_mc"], config["seed"])}
    if pub is not None:
        case["worst_case"]["published"] = design(wc, pub["processes"], pub["t_mm"])
    nl = allocate_nonlinear_limit(wc, allocate_process_optimum)
    held = of_result(wc, nl.result)
    held["nonlinear_worst_case_over_limit"] = nl.worst_case["max_over_limit"]
    case["worst_case"]["nonlinear"] = {
        "linear_optimum_nonlinear_worst_case_over_limit": nl.linear_worst_case["max_over_limit"],
        "method": nl.linear_worst_case["responses"][0]["method"], "holding_the_nonlinear_limit": held,
        "cost_difference": nl.cost_difference, "cost_difference_over_linear": nl.cost_difference / nl.linear.cost,
        "iterations": nl.iterations, "converged": nl.converged,
        "mc_nonlinear": _mc_nonlinear(wc, nl.result.tolerances, config["n_mc"], config["seed"])}
    return case


def compute(config: dict) -> StudyResult:
    """Settle the cage nominal, then run the cases A = 0, 20, 100 (:func:`run_case`).

    Parameters
    ----------
    config : dict
        Study config: ``seed``, ``pop_size``, ``n_gen`` and ``n_mc`` (see :func:`run_case`).

    Returns
    -------
    StudyResult
        ``summary`` only: source and provenance, ``cage_nominal_mm`` (mm) with its evidence and
        rule, ``limit_rad`` (rad), the three ``cases`` and ``seconds`` (wall time, s).
    """
    t0 = time.perf_counter()
    data = choi.load()
    evidence = choi.nominal_evidence(data)
    cage = float(choi.consistent_cage(evidence))
    pubs = {p["A"]: p for p in choi.published(data)}
    cases = [run_case(data, cage, A, pubs.get(A), config) for A in (0.0, 20.0, 100.0)]
    summary = {"source": choi.CITE, "provenance": data["provenance"], "assembly_function": data["assembly_function"],
               "cage_nominal_mm": cage, "cage_nominal_evidence": evidence,
               "cage_nominal_rule": choi.consistent_cage.__doc__.strip().replace("\n   ", ""),
               "limit_rad": data["limit"]["half_width_T_rad"], "tolerance_convention": data["tolerance_convention"],
               "cases": cases, "seconds": time.perf_counter() - t0}
    return StudyResult(summary)


def render(result: StudyResult):
    """The HTML report of the study, from its summary.

    Returns
    -------
    evotol.reporting.html.Report
        The HTML report.
    """
    from evotol.studies._choi2000_report import render_report

    return render_report(result.summary)


STUDY = Study(name="choi2000-clutch", title="Overrunning clutch with quality loss: exact process selection vs. Choi 2000",
              compute=compute, render=render, config=CONFIG, quick=QUICK,
              seed_paper="Choi, Park & Salisbury 2000 (J. Manuf. Sci. Eng. 122(3):529), as coded in yue-w/ToleranceAllocation")

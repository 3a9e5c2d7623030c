"""5-bar clearance synthesis as an optimisation (Deng 2012 Sec. VII.1.2; issue 12 item 5).

The thesis sizes the ten clearances of the 5-bar -- radial Δb_xy (with Δβ_xy = Δb_xy / h, eq.
III.2) and axial Δb_z of joints A, C, B, D, E -- by a design of experiments over level sets
(``deng2012-tolsynth``). Here the same problem is an optimisation on the certified measure: the
cheapest clearances (``deng2012-tolsynth``'s reciprocal cost per clearance) that hold the maximum
positional error at pose (0, 70) mm below ``p_max_mm`` (0.05 mm: the filter of Fig. VII.4).

Compared on the same problem and the same certified engine (:mod:`evotol.measures.clearances`):
  * the DOE: the cheapest entry of the thesis's 4^5 x 2^5 level factorial that holds p_max;
  * the GA on continuous tolerances (pymoo, boundary repair by exact evaluations), started from
    a Latin hypercube only;
  * a proven lower bound on the optimal cost (polyblock, :mod:`evotol.allocators.monotone`; the
    worst case is monotone but not convex in the clearances, ``docs/clearance_allocation.md``);
  * Monte Carlo of the GA's design inside the clearance sets (evidence, not verification).
"""
from __future__ import annotations

import itertools
import time

import numpy as np

from evotol.allocators import allocate_ga, allocate_monotone
from evotol.measures.clearances import ClearanceSources, thesis_classes
from evotol.verification.montecarlo import verify
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from evotol.studies import Study, StudyResult
from evotol.studies.deng2012_tolsynth import H_MM, JOINTS, LEVELS_XY_MM, LEVELS_Z_MM, POSE_MM, default_cost_model
from evotol.robots.mechanism.model.error_model import MechanismModel, resolve_description
from evotol.units import MM

NAME = "deng2012-clearalloc"

CONFIG = {"seed": 0, "p_max_mm": 0.05, "n_entries": None, "pop_size": 20, "n_gen": 20, "max_evaluations": 300,
          "mc_samples": 2000}
QUICK = {"n_entries": 256, "pop_size": 8, "n_gen": 3, "max_evaluations": 40, "mc_samples": 200}


def make_problem(p_max_mm: float = 0.05) -> ToleranceProblem:
    """The thesis's ten clearance classes of the description-driven 5-bar at pose (0, 70) mm,
    tolerances in [1e-4, 0.1] mm (the DOE's range), requirement p_max <= ``p_max_mm``.

    Parameters
    ----------
    p_max_mm : float, optional
        Required maximum positional error, mm (default 0.05 mm, the filter of Fig. VII.4).

    Returns
    -------
    evotol.core.problem.ToleranceProblem
        Ten clearance sources (``thesis_classes`` with h = 10 mm), each with
        :func:`~evotol.studies.deng2012_tolsynth.default_cost_model`, at the single pose
        (0, 70) mm.
    """
    robot = MechanismModel(resolve_description("fivebar"))
    mech = robot.clearance_mechanism()
    cl = ClearanceSources(mech, thesis_classes(JOINTS, h=H_MM * MM))
    lo, hi = min(LEVELS_XY_MM) * MM, max(LEVELS_XY_MM) * MM
    tols = {n: Tolerance(default_cost_model(), lower=lo, upper=hi) for n in cl.names}
    return ToleranceProblem(robot, tols, Requirement(position=p_max_mm * MM), [[POSE_MM[0] * MM, POSE_MM[1] * MM]],
                            clearances=cl)


def factorial(n_entries: int | None, seed: int) -> np.ndarray:
    """The thesis's level sets (n, 10) in SI, class order bxy_A, bxy_C, bxy_B, bxy_D, bxy_E,
    bz_A ... bz_E; ``n_entries``: a random subset.

    Parameters
    ----------
    n_entries : int or None
        Number of entries drawn at random without replacement (kept in factorial order);
        ``None`` (or 0) returns all 4^5 x 2^5 = 32 768.
    seed : int
        Random seed of the subset.

    Returns
    -------
    (n, 10) ndarray
        Clearances, m.
    """
    L = np.array(list(itertools.product(LEVELS_XY_MM, repeat=5)))
    Z = np.array(list(itertools.product(LEVELS_Z_MM, repeat=5)))
    T = np.concatenate([np.repeat(L, len(Z), 0), np.tile(Z, (len(L), 1))], 1) * MM
    if n_entries:
        T = T[np.sort(np.random.default_rng(seed).choice(len(T), n_entries, replace=False))]
    return T


def _design(problem, t) -> dict:
    return {n: float(v) / MM for n, v in zip(problem.names, t)}


def compute(config: dict) -> StudyResult:
    """DOE, GA, polyblock lower bound and Monte Carlo on :func:`make_problem`.

    Parameters
    ----------
    config : dict
        Study config: ``seed``, ``quick``, ``p_max_mm`` (mm), ``n_entries`` (DOE subset or
        ``None``), ``pop_size`` and ``n_gen`` (GA), ``max_evaluations`` (polyblock) and
        ``mc_samples`` (Monte Carlo).

    Returns
    -------
    StudyResult
        ``summary`` only: per method (``doe``, ``ga``, ``bracket``) its cost (cost units),
        attained and certified p_max (mm), clearances (mm) and time (s); the proven lower bound
        and gap, the relative differences ``ga_vs_doe`` and ``ga_over_lower_bound``, the Monte
        Carlo check and ``seconds``.
    """
    t0 = time.perf_counter()
    seed = config["seed"]
    pr = make_problem(config["p_max_mm"])
    T = factorial(config["n_entries"], seed)
    t1 = time.perf_counter()
    ev = pr.evaluate(T)
    doe_seconds = time.perf_counter() - t1
    ok = ev.violation <= 1e-9
    cost = pr.cost(T)
    i = int(np.argmin(np.where(ok, cost, np.inf)))
    doe = {"n_entries": int(len(T)), "n_feasible": int(ok.sum()), "seconds": doe_seconds,
           "cost": float(cost[i]) if ok.any() else None, "p_max_mm": float(ev.position[i, 0] / MM),
           "p_upper_mm": float(ev.position_bound[i, 0] / MM), "tolerances_mm": _design(pr, T[i])}
    # the GA starts from a Latin hypercube only (no baseline or DOE design as a seed)
    ga = allocate_ga(pr, pop_size=config["pop_size"], n_gen=config["n_gen"], seed=seed, progress=False,
                     seed_with_baselines=False)
    mono = allocate_monotone(pr, incumbent=ga.t, max_evaluations=config["max_evaluations"])
    mc = verify(pr, ga.t, n_samples=config["mc_samples"], seed=seed, progress=False)
    cert = mono.certificate
    summary = {
        "study": NAME, "quick": config["quick"], "seed": seed, "pose_mm": list(POSE_MM), "h_mm": H_MM,
        "p_max_required_mm": config["p_max_mm"], "classes": list(pr.names),
        "cost_model": repr(default_cost_model()),
        "doe": doe,
        "ga": {"cost": ga.cost, "feasible": ga.feasible, "p_max_mm": ga.max_error() / MM,
               "p_upper_mm": float(np.max(ga.errors.position_bound)) / MM, "seconds": ga.seconds,
               "pop_size": config["pop_size"], "n_gen": config["n_gen"], "tolerances_mm": _design(pr, ga.t),
               "history": ga.history[["generation", "best_feasible"]].to_dict(orient="list")},
        "bracket": {"lower_bound": cert["lower_bound"], "best_cost": mono.cost, "gap": cert["gap"],
                    "evaluations": cert["evaluations"], "rounds": cert["rounds"], "seconds": mono.seconds,
                    "tolerances_mm": _design(pr, mono.t)},
        "ga_vs_doe": (ga.cost / doe["cost"] - 1) if doe["cost"] else None,
        "ga_over_lower_bound": ga.cost / cert["lower_bound"] - 1,
        "monte_carlo": mc.to_dict(),
        "seconds": time.perf_counter() - t0,
    }
    return StudyResult(summary)


def render(result: StudyResult):
    """The comparison table, the clearances per method and the Monte Carlo note.

    Returns
    -------
    evotol.reporting.html.Report
        The HTML report.
    """
    import plotly.graph_objects as go

    from evotol.reporting.html import Report

    s = result.summary
    d, g, b = s["doe"], s["ga"], s["bracket"]
    rep = Report("5-bar clearance synthesis as an optimisation (Deng 2012, Sec. VII.1.2)",
                 f"pose ({s['pose_mm'][0]:g}, {s['pose_mm'][1]:g}) mm, p_max <= {s['p_max_required_mm']:g} mm, "
                 f"h = {s['h_mm']:g} mm; cost {s['cost_model']} per clearance")
    rep.text("The thesis chooses the clearances from a design of experiments over level sets (deng2012-tolsynth). "
             "The same problem as an optimisation on the certified worst case: the DOE's best entry, the GA on "
             "continuous clearances, and a proven lower bound on the optimal cost (polyblock; the worst case is "
             "monotone but not convex in the clearances -- docs/clearance_allocation.md).")
    rows = [["DOE: cheapest feasible entry", d["cost"], d["p_max_mm"], d["p_upper_mm"],
             f"{d['n_feasible']} of {d['n_entries']} entries feasible ({d['seconds']:.1f} s)"],
            ["GA (continuous)", g["cost"], g["p_max_mm"], g["p_upper_mm"],
             f"{g['pop_size']} x {g['n_gen']}, {g['seconds']:.1f} s"],
            ["polyblock: best design / proven lower bound", f"{b['best_cost']:.4f} / {b['lower_bound']:.4f}", "", "",
             f"gap {100 * b['gap']:.1f} %, {b['evaluations']} evaluations, {b['seconds']:.1f} s"]]
    rep.table(rows, ["method", "cost", "p_max attained (mm)", "p_max certified bound (mm)", "note"])
    vs = s["ga_vs_doe"]
    rep.text(f"GA vs the DOE's best entry: {100 * vs:+.1f} % cost; GA above the proven lower bound by at most "
             f"{100 * s['ga_over_lower_bound']:.1f} %." if vs is not None else "No DOE entry holds the requirement.")
    fig = go.Figure()
    for lab, key in (("DOE best entry", "doe"), ("GA", "ga"), ("polyblock best", "bracket")):
        tol = s[key]["tolerances_mm"]
        fig.add_bar(x=list(tol), y=list(tol.values()), name=lab)
    fig.update_layout(title="Clearances (mm)", yaxis_type="log", barmode="group", yaxis_title="tolerance (mm)")
    rep.figure(fig)
    mc = s["monte_carlo"]
    rep.text(f"Monte Carlo of the GA's design ({mc['n_samples']} consistent clearance states): exceed rate "
             f"{mc['max_exceed_rate']:.3g}; the largest sampled error is {100 * mc['max_error_over_worst_case']['position']:.0f} % "
             "of the certified worst case (sampling does not find the worst case).", note=True)
    return rep


STUDY = Study(name=NAME, title="5-bar clearance synthesis as an optimisation: DOE vs GA vs proven lower bound "
                               "(Deng 2012 Sec. VII.1)",
              compute=compute, render=render, config=CONFIG, quick=QUICK, seed_paper="004 Deng 2012 (thesis), Ch. VII")

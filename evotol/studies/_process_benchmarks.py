"""Problems of the process-selection studies and benchmarks (data only; see docs/process_selection.md).

* The **one-way (overrunning) clutch** of Chase, *Dimensioning and Tolerancing Handbook* §14.7
  (and Chase, Greenwood, Loosli & Hauglund 1990): contact angle
  ``φ = arccos((a + c)/(e − c))`` (handbook eq. 14.6) of hub width ``a``, roller radius ``c`` and
  ring radius ``e``. Nominal a = 27.645 mm, c = 11.43 mm, e = 50.8 mm give φ0 = 7.018°; these are
  the diameters 55.29 / 22.86 / 101.6 mm the GA literature quotes, halved (same geometry).
* A **linear stack** (gap of a shaft/housing/spacer chain, signs ±1) with the same process catalogue.

The process catalogue (``A + B/t^k`` with t in mm, Chase's reciprocal-power form, ranges per
process) is evotol's illustrative data, **not** the published tables: those could not be
retrieved in this session (see the doc page). Cost units are arbitrary.
"""
from __future__ import annotations

import numpy as np

from evotol.cost_models.power import PowerCost
from evotol.allocators.nonlinear_limit import allocate_nonlinear_limit
from evotol.allocators.process import Process, ProcessProblem, allocate_process_optimum, assembly_problem
from evotol.robots.assembly import AssemblyFunction, LinearStack
from evotol.units import MM


#: process -> (lower mm, upper mm, fixed cost A, B, k): cost = A + B / t_mm^k on [lower, upper]
CATALOGUE = {
    "mill": (0.05, 0.30, 1.0, 0.40, 1.0),
    "turn": (0.02, 0.15, 2.0, 0.12, 1.0),
    "grind": (0.005, 0.05, 4.0, 0.02, 1.0),
    "hone": (0.002, 0.012, 6.0, 0.006, 1.0),
}


def process(name: str, size_factor: float = 1.0) -> Process:
    """A catalogue process; ``size_factor`` scales its costs (bigger parts cost more)."""
    lo, hi, A, B, k = CATALOGUE[name]
    return Process(name, PowerCost(size_factor * B, k, scale=MM), lo * MM, hi * MM, size_factor * A)


def clutch_angle(a, c, e):
    """Contact angle φ (rad) of the one-way clutch, Chase handbook eq. 14.6."""
    return np.arccos((a + c) / (e - c))


CLUTCH_NOMINAL = {"a": 27.645 * MM, "c": 11.43 * MM, "e": 50.8 * MM}
#: allowed deviation of the contact angle: ±2° (evotol's choice for the benchmark)
CLUTCH_LIMIT_RAD = float(np.radians(2.0))
CLUTCH_PROCESSES = {"a": ("mill", "turn", "grind"), "c": ("turn", "grind", "hone"), "e": ("turn", "grind", "hone")}
#: published numbers retrieved in this session (Chase, D&T Handbook §14.7)
CLUTCH_PUBLISHED = {
    "source": "K. W. Chase, 'Minimum-cost tolerance allocation', Dimensioning and Tolerancing Handbook (P. Drake, ed.), "
              "McGraw-Hill 1999, ch. 14, §14.7 'One-way clutch assembly'; Chase, Greenwood, Loosli & Hauglund, "
              "Manufacturing Review 3(1), 1990",
    "assembly_function": "phi = arccos((a + c) / (e - c)), eq. 14.6",
    "rss_angle_variation_rad": 0.01159,
    "rss_angle_variation_deg": 0.664,
    "tables": None,
    "sources_located": [
        "http://adcats.et.byu.edu/Publication/89-4/Proc_Sel_Paper1.html",
        "https://studylib.net/doc/8782616/least-cost-tolerance-allocation-for-mechanical-assemblies",
        "https://studylib.net/doc/18266955/manufacturing-tolerance-cost-minimization-using-discrete",
        "https://scribd.com/document/690411146/singh2004",
        "http://www.researchgate.net/publication/220583293",
        "https://www.crystalballservices.com/Research/Articles-on-Analytics-Risk/"
        "tolerance-analysis-using-worst-case-approach-continued-part-3-13-1"],
    "sources_note": "located with the search tools; only each page's opening (abstract, introduction) was "
                    "retrievable, not the example data (docs/process_selection.md, 'Where the published data were "
                    "looked for')",
    "note": "only the opening of §14.7 was retrievable: the transfer function and the RSS variation of the handbook's "
            "tolerances (0.01159 rad); the nominal tolerances, cost coefficients and the allocated tables were not, "
            "so no published cost can be recomputed here",
}


def clutch_assembly() -> AssemblyFunction:
    return AssemblyFunction(clutch_angle, CLUTCH_NOMINAL, {"phi": CLUTCH_LIMIT_RAD}, name="one-way clutch",
                            groups={"a": "hub", "c": "roller", "e": "ring"})


def clutch_problem(measure: str = "worst_case") -> ProcessProblem:
    asm = clutch_assembly()
    size = {"a": 1.0, "c": 0.6, "e": 1.4}
    procs = {n: [process(p, size[n]) for p in CLUTCH_PROCESSES[n]] for n in asm.source_names}
    return assembly_problem(asm, processes=procs, measure=measure)


#: linear stack: gap = housing − (shaft shoulder + spacer + bearing + ...), dimension -> sign
STACK_SIGNS = {"housing": 1.0, "shoulder": -1.0, "spacer1": -1.0, "bearing": -1.0, "spacer2": -1.0, "circlip": -1.0}
STACK_SIZE = {"housing": 1.6, "shoulder": 1.0, "spacer1": 0.5, "bearing": 0.8, "spacer2": 0.5, "circlip": 0.4}
STACK_GAP_LIMIT = 0.10 * MM   # gap within ±0.10 mm (worst case) -- evotol's choice


def stack_problem(measure: str = "worst_case", n_dims: int | None = None, limit: float = STACK_GAP_LIMIT,
                  names=("mill", "turn", "grind", "hone")) -> ProcessProblem:
    """The linear stack; ``n_dims`` > 6 repeats spacers (for the branch-and-bound benchmark)."""
    signs, size = dict(STACK_SIGNS), dict(STACK_SIZE)
    for i in range(6, n_dims or 6):
        signs[f"spacer{i - 3}"] = -1.0
        size[f"spacer{i - 3}"] = 0.3 + 0.1 * (i % 4)
    if n_dims is not None and n_dims < 6:
        signs = dict(list(signs.items())[:n_dims])
    asm = LinearStack(signs, {"gap": limit}, name="shaft-housing stack")
    procs = {n: [process(p, size[n]) for p in names] for n in asm.source_names}
    return assembly_problem(asm, processes=procs, measure=measure)


# --- the studies' compute and render (shared by chase1990_clutch and process_stack) -------------------
def _mm(d: dict) -> dict:
    return {k: v / MM for k, v in d.items()}


def _mc_nonlinear(pp: ProcessProblem, tolerances: dict, n: int, seed: int) -> dict:
    """Nonlinear Monte Carlo of the responses at a design: uniform in ±t (worst case) or normal with
    t = 3σ (RSS); returns the largest |Δy|/L and the fraction of assemblies outside the limits."""
    asm = pp.robot
    t = np.array([tolerances[s] for s in asm.source_names])
    rng = np.random.default_rng(seed)
    if pp.requirement.measure == "rss":
        E = rng.normal(0.0, t / 3.0, size=(n, t.size))
    else:
        E = rng.uniform(-t, t, size=(n, t.size))
    K = len(asm.response_names)
    out = asm.pose_error(asm.response_poses, np.broadcast_to(E, (K, n, t.size)))[..., 2]   # (K, n) in units of L
    return {"n_samples": n, "max_abs_normalised": float(np.max(np.abs(out))),
            "fraction_outside": float(np.mean(np.any(np.abs(out) > 1, axis=0))),
            "sampling": "normal, t = 3 sigma" if pp.requirement.measure == "rss" else "uniform in [-t, t]"}


def nonlinear_limit_block(pp: ProcessProblem, config: dict) -> dict:
    """Worst case: the proven nonlinear worst case of the linear (first-order) optimum and the allocation
    that holds the nonlinear limit (:func:`evotol.allocators.nonlinear_limit.allocate_nonlinear_limit`),
    with the cost difference and a nonlinear Monte Carlo of the new design."""
    r = allocate_nonlinear_limit(pp, allocate_process_optimum)
    wc0, wc1 = r.linear_worst_case["responses"][0], r.worst_case["responses"][0]
    return {"linear_optimum": {"cost": r.linear.cost, "processes": r.linear.processes,
                               "nonlinear_worst_case_over_limit": r.linear_worst_case["max_over_limit"],
                               "method": wc0["method"], "worst_point_offsets_mm": [v / MM for v in wc0["worst_point_offsets"]]},
            "nonlinear_limit": {"cost": r.result.cost, "processes": r.result.processes,
                                "tolerances_mm": _mm(r.result.tolerances),
                                "nonlinear_worst_case_over_limit": r.worst_case["max_over_limit"], "method": wc1["method"],
                                "certificate": r.result.certificate,
                                "mc_nonlinear": _mc_nonlinear(pp, r.result.tolerances, config["n_mc"], config["seed"])},
            "cost_difference": r.cost_difference, "cost_difference_over_linear": r.cost_difference / r.linear.cost,
            "iterations": r.iterations, "converged": r.converged, "history": r.history}


def run_case(pp: ProcessProblem, config: dict, enumerate_all: bool) -> dict:
    """Exact optimum (branch and bound; enumeration too when asked), GA, baselines, NSGA-II front."""
    import time

    from evotol.allocators.process import (allocate_process_baselines, allocate_process_ga,
                                           allocate_process_optimum, process_front)

    t0 = time.perf_counter()
    bb = allocate_process_optimum(pp)
    case = {"n_combinations": pp.n_combinations, "optimum_cost": bb.cost, "n_nodes": bb.n_nodes,
            "n_convex_solves": bb.n_convex_solves, "optimum_seconds": bb.seconds,
            "optimum": {"processes": bb.processes, "tolerances_mm": _mm(bb.tolerances), "cost": bb.cost,
                        "normalised_error": bb.normalised_error, "feasible": bb.feasible, "certificate": bb.certificate}}
    if enumerate_all:
        en = allocate_process_optimum(pp, method="enumerate")
        case["enumeration"] = {"cost": en.cost, "n_convex_solves": en.n_convex_solves, "processes": en.processes,
                               "seconds": en.seconds, "same_optimum": bool(abs(en.cost - bb.cost) <= 1e-9 * bb.cost)}
    ga = allocate_process_ga(pp, pop_size=config["pop_size"], n_gen=config["n_gen"], seed=config["seed"])
    case.update(ga_cost=ga.cost, ga_over_optimum=ga.cost / bb.cost - 1, ga_seconds=ga.seconds,
                ga={"processes": ga.processes, "tolerances_mm": _mm(ga.tolerances), "cost": ga.cost,
                    "normalised_error": ga.normalised_error, "feasible": ga.feasible, "history": ga.history})
    case["baselines"] = {k: {"method": r.method, "processes": r.processes, "tolerances_mm": _mm(r.tolerances),
                             "cost": r.cost, "over_optimum": r.cost / bb.cost - 1, "feasible": r.feasible,
                             "normalised_error": r.normalised_error}
                         for k, r in allocate_process_baselines(pp).items()}
    ga_kw = {k: config[k] for k in ("pop_size", "n_gen", "seed")}
    front = process_front(pp, **ga_kw)
    case["front"] = {"cost": front.cost.tolist(), "normalised_error": front.error.tolist()}
    yfront = process_front(pp, objective="yield", **ga_kw)
    case["yield_front"] = {"distribution": "normal, t = 3 sigma", "cost": yfront.cost.tolist(),
                           "yield": yfront.table["yield"].tolist(),
                           "yield_at_optimum": float(pp.assembly_yield([[bb.tolerances[n] for n in pp.names]])[0])}
    case["mc_nonlinear_at_optimum"] = _mc_nonlinear(pp, bb.tolerances, config["n_mc"], config["seed"])
    if pp.requirement.measure == "worst_case":
        case["nonlinear_limit"] = nonlinear_limit_block(pp, config)
    case["seconds"] = time.perf_counter() - t0
    return case


def summarise(cases: dict, published: dict, primary: str) -> dict:
    p = cases[primary]
    return {"published": published, "primary_case": primary, "optimum_cost": p["optimum_cost"], "ga_cost": p["ga_cost"],
            "ga_over_optimum": p["ga_over_optimum"], "n_nodes": p["n_nodes"], "n_convex_solves": p["n_convex_solves"],
            "cases": cases}


def render_cases(title: str, subtitle: str, summary: dict, problems_text: dict):
    """Report: published data, then per case the methods' processes, tolerances and costs, and the front."""
    import plotly.graph_objects as go

    from evotol.reporting import Report

    rep = Report(title, subtitle)
    rep.heading("Published data")
    pub = summary["published"]
    rep.table([[k, v if not isinstance(v, (dict, list)) else str(v)] for k, v in pub.items()], ["item", "value"],
              table_id="published")
    for label, case in summary["cases"].items():
        rep.heading(f"{label}: {problems_text.get(label, '')}")
        opt = case["optimum"]["cost"]
        rows = [["exact (branch and bound)", case["optimum"]["processes"], case["optimum"]["tolerances_mm"], opt, 0.0,
                 case["optimum"]["feasible"]],
                ["GA (pymoo)", case["ga"]["processes"], case["ga"]["tolerances_mm"], case["ga_cost"],
                 100 * case["ga_over_optimum"], case["ga"]["feasible"]]]
        for b in case["baselines"].values():
            rows.append([b["method"], b["processes"], b["tolerances_mm"], b["cost"], 100 * b["over_optimum"], b["feasible"]])
        nl = case.get("nonlinear_limit")
        if nl is not None:
            n = nl["nonlinear_limit"]
            rows.append(["exact on the linear rows, re-linearised until the nonlinear worst case holds", n["processes"],
                         n["tolerances_mm"], n["cost"], 100 * (n["cost"] / opt - 1), n["nonlinear_worst_case_over_limit"] <= 1 + 1e-9])
        rep.table([[m, ", ".join(f"{k}: {v}" for k, v in p.items()), ", ".join(f"{k}: {v:.4g}" for k, v in t.items()), c, r, f]
                   for m, p, t, c, r, f in rows],
                  ["method", "processes", "tolerances (mm)", "cost", "above optimum (%)", "feasible"], table_id=f"methods_{label}")
        cert = case["optimum"]["certificate"]
        txt = (f"{case['n_combinations']} process combinations; branch and bound visited {case['n_nodes']} nodes and "
               f"solved {case['n_convex_solves']} convex subproblems (leaf duality gap {cert['leaf_gap']:.2e}).")
        if "enumeration" in case:
            e = case["enumeration"]
            txt += (f" Full enumeration solved {e['n_convex_solves']} subproblems and found the same optimum: "
                    f"{e['same_optimum']}.")
        mc = case["mc_nonlinear_at_optimum"]
        txt += (f" Nonlinear Monte Carlo at the optimum ({mc['n_samples']} samples, {mc['sampling']}): largest "
                f"|Δy|/L = {mc['max_abs_normalised']:.4f}, fraction outside the limit {mc['fraction_outside']:.4%}.")
        if nl is not None:
            lo, n = nl["linear_optimum"], nl["nonlinear_limit"]
            txt += (f" Nonlinear worst case over the tolerance box ({lo['method']}): the linear optimum reaches "
                    f"{lo['nonlinear_worst_case_over_limit']:.4f} × the limit. Holding the real (nonlinear) limit "
                    f"({nl['iterations']} re-linearisations at the worst point) costs {n['cost']:.5g}, "
                    f"{100 * nl['cost_difference_over_linear']:+.2f} % over the linear optimum; its proven nonlinear worst "
                    f"case is {n['nonlinear_worst_case_over_limit']:.6f} × the limit and {n['mc_nonlinear']['n_samples']} "
                    f"uniform samples reach {n['mc_nonlinear']['max_abs_normalised']:.4f}.")
        rep.text(txt, note=True)
        fig = go.Figure()
        fig.add_scatter(x=case["front"]["normalised_error"], y=case["front"]["cost"], mode="markers", name="NSGA-II front")
        fig.add_scatter(x=[case["optimum"]["normalised_error"]], y=[opt], mode="markers", marker=dict(size=12, symbol="star"),
                        name="exact optimum")
        fig.add_scatter(x=[case["ga"]["normalised_error"]], y=[case["ga_cost"]], mode="markers", marker=dict(size=9, symbol="x"),
                        name="GA")
        fig.update_layout(xaxis_title="max error / limit", yaxis_title="cost", height=420)
        rep.figure(fig, div_id=f"front_{label}")
        yf = case.get("yield_front")
        if yf is not None:
            fig = go.Figure()
            fig.add_scatter(x=yf["yield"], y=yf["cost"], mode="markers", name="NSGA-II front (cost vs. yield)")
            fig.add_scatter(x=[yf["yield_at_optimum"]], y=[opt], mode="markers", marker=dict(size=12, symbol="star"),
                            name="exact optimum of this case")
            fig.update_layout(xaxis_title=f"yield P(|Δy| <= L), first-order model, {yf['distribution']}",
                              yaxis_title="cost", height=420)
            rep.figure(fig, div_id=f"yield_front_{label}")
    return rep

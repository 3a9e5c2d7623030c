"""The overrunning clutch of Choi et al. 2000 with process selection and quality loss (data and problem).

Data: ``evotol/studies/data/clutch_choi2000.json`` -- "Choi et al. 2000 as coded in
yue-w/ToleranceAllocation" (commit 3760b0a5, files clutch.m, compareprofit2.m, verifycost.m,
tolcostequation.m): four dimensions (hub X1, rollers X2 and X3, cage X4, mm), 2-3 processes per
part with cost ``a + b/t`` (t in mm) on a range, the contact angle

    Y = acos((X1 + (X2 + X3)/2) / (X4 − (X2 + X3)/2))   (rad),

its limit ±T = ±0.035 rad (statistical: 3σ_Y <= T with σ_j = t_j/3, i.e. RSS of the effects),
a Taguchi loss K = A/T², and the published allocations for A = 0, 20, 100.

The cage nominal is written 101.69 mm in the code and 101.6 mm in the wider clutch literature;
:func:`nominal_evidence` tests both against the published allocations (the study picks the one
they are consistent with).
"""
from __future__ import annotations

import json
from importlib import resources

import numpy as np

from evotol.cost_models.power import PowerCost
from evotol.allocators.process import Process, ProcessProblem, assembly_problem
from evotol.robots.assembly import AssemblyFunction
from evotol.units import MM

KSIGMA = 3.0
SOURCES = ("X1", "X2", "X3", "X4")
CITE = "Choi et al. 2000 as coded in yue-w/ToleranceAllocation"


def load() -> dict:
    """The data file, as shipped (with its provenance)."""
    return json.loads(resources.files("evotol.studies").joinpath("data/clutch_choi2000.json").read_text())


def contact_angle(X1, X2, X3, X4):
    """Contact angle (rad) of the overrunning clutch; dimensions in m (only ratios matter)."""
    h = (X2 + X3) / 2
    return np.arccos((X1 + h) / (X4 - h))


def nominal_mm(data: dict, cage_mm: float) -> dict[str, float]:
    n = data["nominal_mm"]
    return {"X1": n["hub_X1"], "X2": n["roller_X2"], "X3": n["roller_X3"], "X4": float(cage_mm)}


def assembly(data: dict, cage_mm: float) -> AssemblyFunction:
    nom = {k: v * MM for k, v in nominal_mm(data, cage_mm).items()}
    T = data["limit"]["half_width_T_rad"]
    return AssemblyFunction(contact_angle, nom, {"Y": T}, name=f"overrunning clutch (cage {cage_mm:g} mm)",
                            units=None, groups={"X1": "hub", "X2": "roller", "X3": "roller", "X4": "cage"})


def processes(data: dict) -> dict[str, list[Process]]:
    """Per dimension its processes (named by their 1-based id, as in the data file)."""
    out = {}
    for s, part in zip(SOURCES, data["parts"]):
        out[s] = [Process(str(p["id"]), PowerCost(p["b"], 1.0, scale=MM), p["t_min"] * MM, p["t_max"] * MM,
                          fixed_cost=p["a"]) for p in part["processes"]]
    return out


def problem(data: dict, cage_mm: float, measure: str = "rss", A: float = 0.0) -> ProcessProblem:
    """The process-selection problem: machining cost + expected loss (A) under the limit (measure)."""
    pp = assembly_problem(assembly(data, cage_mm), processes=processes(data), measure=measure)
    return pp.with_quality_loss(A) if A else pp


def published(data: dict) -> list[dict]:
    """Published allocations: A, 1-based process ids (A = 20: the A = 0 ids the code keeps), t (mm)."""
    out = []
    for p in data["published_allocations"]:
        ids = p["processes"] if isinstance(p["processes"], list) else [3, 2, 1, 3]
        stated = isinstance(p["processes"], list)
        out.append({"A": float(p["quality_loss_A"]), "processes": [int(i) for i in ids], "t_mm": list(p["t"]),
                    "processes_stated": stated})
    return out


def nominal_evidence(data: dict, cages=(101.69, 101.6)) -> dict:
    """Which cage nominal the published allocations are consistent with (three independent tests).

    For each candidate: (1) the nominal angle Y(x0) against the data's nominal 0.122 rad; (2) the
    RSS of the published A = 0 and A = 20 tolerances over T -- with machining cost only (A = 0) the
    cost falls with every t, so an optimum that is not at every upper bound has the RSS limit
    active (ratio 1); (3) at A = 100 the published RSS is below T (limit inactive), so each
    interior tolerance satisfies the loss-balance b_j / t_j² = 2 K S_j² t_j / 9, i.e.
    b_j / (S_j² t_j³) = 2K/9: the ratio of the measured value to 2K/9 should be 1.
    """
    parts = data["parts"]
    T = data["limit"]["half_width_T_rad"]
    out = {}
    for cage in cages:
        asm = assembly(data, cage)
        S = asm.gradient[0] * MM                      # rad per mm
        row = {"nominal_angle_rad": float(asm.y0[0]), "sensitivities_rad_per_mm": S.tolist()}
        for pub in published(data):
            t = np.array(pub["t_mm"])
            rss = float(np.sqrt(np.sum((S * t) ** 2)))
            key = f"A{pub['A']:g}"
            row[f"rss_over_T_{key}"] = rss / T
            if pub["A"] == 100:
                K = pub["A"] / T ** 2
                b = np.array([parts[j]["processes"][i - 1]["b"] for j, i in enumerate(pub["processes"])])
                lo = np.array([parts[j]["processes"][i - 1]["t_min"] for j, i in enumerate(pub["processes"])])
                interior = t > lo * (1 + 1e-9)
                ratio = b / (S ** 2 * t ** 3) / (2 * K / KSIGMA ** 2)
                row["loss_balance_ratio_A100"] = ratio[interior].tolist()
        out[f"{cage:g}"] = row
    return out


def consistent_cage(evidence: dict) -> str:
    """The candidate whose published A = 0 RSS is closest to the limit and whose A = 100 loss
    balance is closest to 1 (both tests must agree; otherwise the code's value is kept)."""
    def d0(k):
        return abs(evidence[k]["rss_over_T_A0"] - 1)

    def d100(k):
        return max(abs(r - 1) for r in evidence[k]["loss_balance_ratio_A100"])

    a, b = min(evidence, key=d0), min(evidence, key=d100)
    return a if a == b else "101.69"

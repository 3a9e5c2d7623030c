"""What calibration buys, as plain data for the JSON summary and the report (SI).

:func:`comparison` puts a calibrated design beside the uncalibrated optimum, source by source:
both tolerances, whether the source is identified, whether calibration frees it (its tolerance
at least ``FREED`` times the uncalibrated one), its first-order effect after calibration at the
worst pose (``max_p |(J M)_j| t_j``, the sources that still drive the error), and the bound that
caps it (:mod:`evotol.calibration.linear_range`). :func:`calibration_summary` adds the plan, the
identification (base set, condition number, unseen sources), the noise's share of the
requirement and the simulated calibration of each design.

The parameters several definitions of this module share are described once, here.

Parameters
----------
results : dict of str to evotol.core.result.AllocationResult
    The methods' results on the calibrated problem.
"""
from __future__ import annotations

import numpy as np

from evotol.allocators import allocate_optimum
from evotol.calibration.simulation import simulate_calibration

#: a tolerance at least this many times the uncalibrated one counts as freed by calibration
FREED = 1.5


def comparison(problem, t_calibrated, t_uncalibrated) -> list[dict]:
    """Per source: uncalibrated and calibrated tolerance, identified, freed, effect after calibration, cap.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The calibrated problem (``problem.calibration``).
    t_calibrated, t_uncalibrated : array_like (n_sources,)
        The two designs (m, rad).

    Returns
    -------
    list of dict
        One per source: ``source``, ``unit``, ``group``, ``uncalibrated``, ``calibrated`` (m or
        rad), ``ratio``, ``identified``, ``freed``, ``effect`` (m or rad: first-order position
        effect after calibration at the worst pose; 0 below 1e-9 of the requirement, round-off),
        ``effect_share`` (of the sum of effects),
        ``upper`` (the bound the calibrated problem gives it), ``capped_by`` (``"linear range"``,
        ``"compensation range"`` or ``""``; `` (binding)`` when the tolerance sits at that cap).
    """
    info = problem.calibration
    tc, tu = np.asarray(t_calibrated, float), np.asarray(t_uncalibrated, float)
    comp = "position" if problem.requirement.position is not None else "orientation"
    eff = (problem.sensitivities[comp] * tc[None]).max(axis=0)
    eff[eff <= 1e-9 * getattr(info.requirement, comp)] = 0.0       # round-off of J M: calibration removed it
    total = eff.sum()
    ident = set(info.identification.identified_names)
    out = []
    for j, (n, s) in enumerate(zip(problem.names, problem.model.sources)):
        b = info.bounds.get(n, {})
        cap = ""
        if b.get("bound") is not None and b["bound"] < b.get("upper_before", np.inf):
            cap = "compensation range" if b.get("compensation_range") == b["bound"] else "linear range"
            cap += " (binding)" if tc[j] >= problem.upper[j] * (1 - 1e-6) else ""
        out.append({"source": n, "unit": s.unit, "group": s.group, "uncalibrated": float(tu[j]), "calibrated": float(tc[j]),
                    "ratio": float(tc[j] / tu[j]) if tu[j] > 0 else None, "identified": n in ident,
                    "freed": bool(tc[j] >= FREED * tu[j]), "effect": float(eff[j]),
                    "effect_share": float(eff[j] / total) if total > 0 else 0.0, "upper": float(problem.upper[j]),
                    "capped_by": cap})
    return out


def _by_quantity(rows: list[dict]) -> dict:
    """Per-source rows as one table per quantity (source -> value), the JSON's unit rule for tolerances."""
    out = {"tolerances": {k: {r["source"]: r[k] for r in rows} for k in ("uncalibrated", "calibrated", "upper", "effect")},
           "effect_share_percent": {r["source"]: 100 * r["effect_share"] for r in rows},
           "identified": [r["source"] for r in rows if r["identified"]],
           "freed": [r["source"] for r in rows if r["freed"]],
           "capped_by": {r["source"]: r["capped_by"] for r in rows if r["capped_by"]}}
    return out


#: units of the calibration block's own keys (added to a study JSON's ``units`` block; docs/units.md)
UNIT_KEYS = {"k": "1: coverage factor (standard deviations)", "condition_number": "1 (dimensionless ratio)",
             "rank": "count", "coverage": "1: probability", "quantile_level": "1: probability"}


def calibration_summary(problem, results: dict, uncalibrated, checks: dict | None = None) -> dict:
    """The calibration block of a study's JSON summary (SI).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The calibrated problem.
    uncalibrated : evotol.core.result.AllocationResult
        The certified optimum of the uncalibrated problem (``problem.uncalibrated``).
    checks : dict of str to evotol.calibration.simulation.CalibrationCheck or dict, optional
        The simulated calibration of each method's design (or its ``to_dict``).

    Returns
    -------
    dict
        ``plan`` (:meth:`CalibrationInfo.to_dict`), ``uncalibrated`` (cost, feasible,
        tolerances), per method ``methods[m]`` with ``cost``, ``saving`` (fraction of the
        uncalibrated cost), ``n_freed``, the :func:`comparison` as one table per quantity
        (``tolerances``: ``uncalibrated``, ``calibrated``, ``upper``, ``effect``, source -> m or rad;
        ``effect_share_percent``; ``identified``, ``freed`` (names); ``capped_by``) and ``simulation``.
    """
    out = {"plan": problem.calibration.to_dict(),
           "uncalibrated": {"method": "optimum", "cost": float(uncalibrated.cost), "feasible": bool(uncalibrated.feasible),
                            "tolerances": dict(zip(problem.names, map(float, uncalibrated.t)))},
           "methods": {}}
    for m, r in results.items():
        rows = comparison(problem, r.t, uncalibrated.t)
        entry = {"cost": float(r.cost), "saving": float(1 - r.cost / uncalibrated.cost) if uncalibrated.cost else None,
                 "n_freed": int(sum(x["freed"] for x in rows)), **_by_quantity(rows)}
        if checks and m in checks:
            entry["simulation"] = checks[m] if isinstance(checks[m], dict) else checks[m].to_dict()
        out["methods"][m] = entry
    return out


def add_to_study(summary: dict, problem, results: dict, seed: int = 0, simulate: int | None = None,
                 uncalibrated=None) -> None:
    """What ``evotol run`` adds to a calibrated study's JSON summary: the uncalibrated optimum, the simulated
    calibration of every design, :func:`calibration_summary` under ``"calibration"``, and the units of its
    keys (:data:`UNIT_KEYS`) in ``summary["units"]["keys"]``.

    Parameters
    ----------
    summary : dict
        The study's JSON summary (:func:`evotol.summaries.user_study.study_summary`), changed in place.
    problem : evotol.core.problem.ToleranceProblem
        The calibrated problem (its ``uncalibrated`` problem is allocated here by the certified optimum).
    seed : int
        Seed of the simulated calibrations.
    simulate : int, optional
        Robots simulated per design (default ``problem.calibration.simulate``; 0: none; a model without a
        nonlinear joint-space model: none).
    uncalibrated : evotol.core.result.AllocationResult, optional
        The certified optimum of ``problem.uncalibrated``, as the study's loop ran it
        (:mod:`evotol.studyfile.comparisons`); None: solved here (a call from Python).
    """
    n = problem.calibration.simulate if simulate is None else simulate
    uncal = allocate_optimum(problem.uncalibrated) if uncalibrated is None else uncalibrated
    checks = {}
    if n and problem.calibration.identification.joints is not None:
        for m, r in results.items():   # verify() has simulated it already (its "calibration" entry), else here
            done = (summary.get("monte_carlo", {}).get(m) or {}).get("calibration")
            checks[m] = done if done is not None else simulate_calibration(problem, r.t, n_samples=n, seed=seed).to_dict()
    summary["calibration"] = calibration_summary(problem, results, uncal, checks)
    summary.setdefault("units", {}).setdefault("keys", {}).update(UNIT_KEYS)

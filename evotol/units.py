"""The JSON unit convention (docs/units.md): SI values, a ``units`` block, suffixes for the rest.

* Every number is in SI (m, rad, s) unless its key ends in a unit suffix (``_mm``, ``_deg``,
  ``_um``, ``_percent``): then the suffix is its unit (``p_max_mm``, ``r_max_deg``).
* Costs are in the unit of the cost models (whatever the user's shop data was in).
* Ratios are dimensionless and named as such (``normalised_error``, ``gap``, ``*_rate``).
* A JSON file carries a ``units`` block: ``convention`` (the sentence above), ``keys`` (the unit
  of every key, by key name), and per-source units for tolerance tables, whose keys are source
  names (a tolerance is in m or rad depending on the source).

:func:`unit_of` resolves the unit of any number in such a file from its JSON path, so a test can
check that no number is left without one. ``evotol run`` writes this block; the seed studies are
being moved to it by their owners (the table in docs/units.md says which already are).
"""
from __future__ import annotations

from typing import Sequence

CONVENTION = ("SI units (m, rad, s) unless the key ends in a unit suffix (_mm, _um, _deg, _percent); "
              "costs in the cost models' unit; ratios are dimensionless; tolerances per source in "
              "units.tolerances (m or rad)")

COST = "cost-model unit"
COUNT = "count"
RELATIVE = "1 (dimensionless ratio)"
SUFFIXES = {"_mm": "mm", "_um": "µm", "_deg": "deg", "_percent": "%", "_m": "m", "_rad": "rad", "_s": "s"}

#: unit of a number by its key (the last component of its JSON path)
KEYS = {
    "cost": COST, "lower_bound": COST, "budget": COST, "min_cost": COST,
    "max_position_error": "m", "max_position_error_bound": "m", "position_error": "m", "position": "m",
    "max_orientation_error": "rad", "max_orientation_error_bound": "rad", "orientation_error": "rad",
    "orientation": "rad",
    "normalised_error": RELATIVE + ": max error / requirement",
    "gap": RELATIVE + ": (cost - lower bound) / cost",
    "kkt_residual": RELATIVE + ": KKT residual / |gradient|",
    "proven_bound_over_requirement": RELATIVE,
    "max_exceed_rate": "1: fraction of samples above the requirement (worst pose)",
    "max_exceed_rate_nonlinear": "1: fraction of samples above the requirement (worst pose, nonlinear model)",
    "yield_estimate": "1: fraction of samples inside every bound (worst pose)",
    "yield_lower": "1: Clopper-Pearson lower bound of the yield", "yield_upper": "1: Clopper-Pearson upper bound of the yield",
    "yield_required": "1: required probability", "confidence": "1: confidence level", "worst_pose": "index",
    "linearisation_error": RELATIVE + ": max |nonlinear - linear| / max |linear| error",
    "initial_best": "fitness (cost + penalty, or normalised error in budget mode)",
    "penalty": COST,
    "seconds": "s",
    "seed": COUNT, "n_samples": COUNT, "rounds": COUNT, "active_rows": COUNT, "working_rows": COUNT,
    "pop_size": COUNT, "n_gen": COUNT, "n_elite": COUNT, "n_check": COUNT,
}
#: keys whose children are named by a requirement component (position, orientation): unit = ratio
RATIO_PARENTS = {"max_error_over_worst_case": RELATIVE + ": sampled max / worst case"}


def units_block(problem) -> dict:
    """The ``units`` block of a JSON file about ``problem`` (see the module docstring)."""
    per_source = dict(zip(problem.names, problem.units()))
    return {"convention": CONVENTION, "keys": dict(KEYS), "ratio_parents": dict(RATIO_PARENTS),
            "tolerances": per_source}


def unit_of(path: Sequence, block: dict) -> str | None:
    """Unit of the number at JSON ``path`` (list of keys / indices) under ``block``; None if unknown.

    Source names (under a ``tolerances`` table or as columns of ``pareto_front``) take the
    source's unit; other keys their suffix or ``block["keys"]``.
    """
    keys = [p for p in path if isinstance(p, str)]
    if not keys:
        return None
    last = keys[-1]
    if last in block.get("tolerances", {}) and ("tolerances" in keys or "pareto_front" in keys):
        return block["tolerances"][last]
    if len(keys) >= 2 and keys[-2] in block.get("ratio_parents", {}):
        return block["ratio_parents"][keys[-2]]
    if last in block.get("keys", {}):
        return block["keys"][last]
    for suffix, unit in SUFFIXES.items():
        if last.endswith(suffix):
            return unit
    return None


def numbers_without_unit(data, block: dict, path=()) -> list[str]:
    """JSON paths of the numbers in ``data`` whose unit :func:`unit_of` cannot resolve."""
    missing = []
    if isinstance(data, dict):
        for k, v in data.items():
            if k != "units":
                missing += numbers_without_unit(v, block, (*path, k))
    elif isinstance(data, list):
        for i, v in enumerate(data):
            missing += numbers_without_unit(v, block, (*path, i))
    elif isinstance(data, (int, float)) and not isinstance(data, bool):
        if unit_of(path, block) is None:
            missing.append("/".join(map(str, path)))
    return missing

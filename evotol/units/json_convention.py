"""The JSON unit convention (docs/units.md): SI values, a ``units`` block, suffixes for the rest.

* Every number is in SI (m, rad, s) unless its key ends in a unit suffix (``_mm``, ``_deg``,
  ``_um``, ``_percent``): then the suffix is its unit (``p_max_mm``, ``r_max_deg``).
* Costs are in the unit of the cost models (whatever the user's shop data was in).
* Ratios are dimensionless and named as such (``normalised_error``, ``gap``, ``*_rate``).
* A JSON file carries a ``units`` block: ``convention`` (the sentence above), ``keys`` (the unit
  of every key, by key name), and per-source units for tolerance tables, whose keys are source
  names (a tolerance is in m or rad depending on the source).

:func:`unit_of` resolves the unit of any number in such a file from its JSON path, so a test can
check that no number is left without one. ``evotol run`` writes this block, and so does every seed
study (:meth:`evotol.studies.Study.units_block`, with the study's own keys from
``evotol/studies/_summary_key_units.py``).
"""
from __future__ import annotations

import fnmatch
from typing import Mapping, Sequence

CONVENTION = ("SI units (m, rad, s) unless the key ends in a unit suffix (_mm, _um, _deg, _percent); "
              "costs in the cost models' unit; ratios are dimensionless; tolerances per source in "
              "units.tolerances (m or rad)")

COST = "cost-model unit"
COUNT = "count"
RELATIVE = "1 (dimensionless ratio)"
SUFFIXES = {"_mm2": "mm²", "_mm": "mm", "_um": "µm", "_deg": "deg", "_percent": "%", "_m": "m", "_rad": "rad", "_s": "s"}

#: unit of a number by its key (the last component of its JSON path)
KEYS = {
    "cost": COST, "lower_bound": COST, "budget": COST, "min_cost": COST,
    "max_position_error": "m", "max_position_error_bound": "m", "position_error": "m", "position": "m",
    "max_orientation_error": "rad", "max_orientation_error_bound": "rad", "orientation_error": "rad",
    "orientation": "rad",
    "normalised_error": RELATIVE + ": max error / requirement",
    "normalised_error_nonlinear": RELATIVE + ": max nonlinear worst-vertex error / requirement",
    "gap": RELATIVE + ": (cost - lower bound) / cost",
    "kkt_residual": RELATIVE + ": KKT residual / |gradient|",
    "proven_bound_over_requirement": RELATIVE,
    "max_exceed_rate": "1: fraction of samples above the requirement (worst pose)",
    "max_exceed_rate_nonlinear": "1: fraction of samples above the requirement (worst pose, nonlinear model)",
    "yield_estimate": "1: fraction of samples inside every bound (worst pose)",
    "yield_lower": "1: Clopper-Pearson lower bound of the yield", "yield_upper": "1: Clopper-Pearson upper bound of the yield",
    "yield_required": "1: required probability",
    "verdict_level": "1: per-pose confidence of the verdict's intervals (Bonferroni over the poses)",
    "verdict_interval": "1: Clopper-Pearson interval of the worst pose's yield at verdict_level", "confidence": "1: confidence level", "worst_pose": "index",
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
    """The ``units`` block of a JSON file about ``problem`` (see the module docstring).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        Its source ``names`` and their SI ``units()`` (m or rad) fill ``tolerances``.

    Returns
    -------
    dict
        The block of :func:`make_units_block` with the common ``keys`` only.
    """
    return make_units_block(tolerances=dict(zip(problem.names, problem.units())))


def make_units_block(keys: Mapping[str, str] | None = None, tolerances: Mapping[str, str] | None = None,
                     tables: Mapping[str, Mapping[str, str]] | None = None) -> dict:
    """A ``units`` block: the common ``keys`` updated by a writer's own ``keys``, per-source SI
    units (``tolerances``), tolerance ``tables`` in stated units (key -> {source: unit}) and the
    generic name rules (``patterns``).

    Parameters
    ----------
    keys : mapping of str to str, optional
        The writer's own key -> unit entries; they override the common :data:`KEYS`.
    tolerances : mapping of str to str, optional
        Source name -> SI unit (``"m"`` or ``"rad"``) of the tolerance tables.
    tables : mapping of str to mapping, optional
        Key of a tolerance table given in stated units -> {source name: unit}, e.g. the paper's
        mm/deg.

    Returns
    -------
    dict
        ``convention`` (str), ``keys``, ``ratio_parents``, ``tolerances``, ``tables`` (dicts) and
        ``patterns`` (list of ``[fnmatch pattern, unit]``); JSON-serialisable.
    """
    return {"convention": CONVENTION, "keys": {**KEYS, **dict(keys or {})},
            "ratio_parents": dict(RATIO_PARENTS), "tolerances": dict(tolerances or {}),
            "tables": {k: dict(v) for k, v in (tables or {}).items()},
            "patterns": [list(p) for p in PATTERNS]}


#: generic name rules, tried in order on a key when neither ``keys`` nor a suffix names its unit
#: (fnmatch patterns; documented in docs/units.md)
PATTERNS = (
    ("*seconds*", "s"), ("seconds_*", "s"), ("timing*", "s"),
    ("n_*", COUNT), ("*_count", COUNT), ("count", COUNT), ("index", "index"), ("*_index", "index"),
    ("seed", COUNT), ("generation", COUNT), ("generations", COUNT), ("*_evaluations", COUNT),
    ("*cost", COST), ("cost_*", COST), ("*_costs", COST), ("*_cost_*", COST),
    ("*_over_*", RELATIVE), ("over_*", RELATIVE), ("*relative_difference*", RELATIVE),
    ("*_resumed", COUNT), ("evaluations", COUNT), ("*_solves", COUNT), ("*_nodes", COUNT), ("*_ratio", RELATIVE), ("ratio*", RELATIVE), ("saving*", RELATIVE),
    ("*gap*", RELATIVE + ": relative gap"), ("*rtol*", RELATIVE), ("*_rel_*", RELATIVE), ("*rel_error*", RELATIVE),
    ("*_rate", "1: fraction"), ("*_rate_*", "1: fraction"), ("fraction*", "1: fraction"), ("*_fraction", "1: fraction"),
    ("*percent*", "%"), ("*share*", "%"),
)


def _key_unit(key: str, block: dict, patterns: bool = True) -> str | None:
    """Unit a key names by itself: ``keys`` entry, unit suffix or (``patterns``) generic name rule."""
    if key in block.get("keys", {}):
        return block["keys"][key]
    for suffix, unit in SUFFIXES.items():
        if key.endswith(suffix):
            return unit
    for pattern, unit in (block.get("patterns", ()) if patterns else ()):
        if fnmatch.fnmatchcase(key, pattern):
            return unit
    return None


def unit_of(path: Sequence, block: dict) -> str | None:
    """Unit of the number at JSON ``path`` (list of keys / indices) under ``block``; None if unknown.

    In order: a child of a ``ratio_parents`` key; a source name inside one of ``tables`` (a
    tolerance table in stated units, e.g. the paper's mm/deg); the number's own key (``keys``,
    unit suffix, generic ``patterns``); a source name under a key containing ``tolerance``
    (or ``pareto_front``): the unit suffix of that key if it has one, else the source's SI unit
    from ``tolerances``; finally the nearest enclosing key that names a unit (by ``keys`` or
    a suffix, not by a name rule: a list or table of numbers inherits its key's unit,
    ``verification_error_mm/case 1/3`` is in mm).

    Parameters
    ----------
    path : sequence of str or int
        The JSON path of the number: dict keys (str) and list indices (int, ignored).
    block : dict
        A ``units`` block, as made by :func:`make_units_block`.

    Returns
    -------
    str or None
        The unit (``"m"``, ``"rad"``, ``"mm"``, ``COST``, ...), or None when no rule applies.
    """
    keys = [p for p in path if isinstance(p, str)]
    if not keys:
        return None
    last = keys[-1]
    if len(keys) >= 2 and keys[-2] in block.get("ratio_parents", {}):
        return block["ratio_parents"][keys[-2]]
    for parent in reversed(keys[:-1]):
        table = block.get("tables", {}).get(parent)
        if table is not None and last in table:
            return table[last]
    own = _key_unit(last, block)
    if own is not None:
        return own
    if last in block.get("tolerances", {}):
        for parent in reversed(keys[:-1]):
            if "tolerance" in parent or parent == "pareto_front":
                suffix_unit = next((u for s, u in SUFFIXES.items() if parent.endswith(s)), None)
                return suffix_unit or block["tolerances"][last]
    for parent in reversed(keys[:-1]):
        unit = _key_unit(parent, block, patterns=False)
        if unit is not None:
            return unit
    return None


def numbers_without_unit(data, block: dict, path=()) -> list[str]:
    """JSON paths of the numbers in ``data`` whose unit :func:`unit_of` cannot resolve.

    Booleans are not numbers here; a ``units`` key is skipped wherever it occurs.

    Parameters
    ----------
    data : object
        Parsed JSON (dicts, lists, numbers, ...), searched recursively.
    block : dict
        The ``units`` block to resolve against.
    path : tuple, optional
        The JSON path of ``data`` itself (default: the root).

    Returns
    -------
    list of str
        The paths, keys and indices joined by ``/``; empty when every number has a unit.
    """
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

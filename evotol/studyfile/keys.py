"""The keys of a study file: every table evotol defines, and the check that refuses an unknown key
(a typo like ``lowr`` or ``[requirment]`` is an error naming the nearest valid key, never ignored).
"""
from __future__ import annotations

import dataclasses

from evotol._runtime.keyword_checks import check_table_keys
from evotol.core.axis_limits import AXIS_KEYS
from evotol.core.requirement import Requirement
from evotol.errors import ValidationError

TOP_KEYS = ("name", "seed", "robot", "poses", "requirement", "bounds", "cost", "sources", "shared", "shared_cost",
            "methods", "verify", "distribution", "sigma_k", "clearances", "quality_loss", "processes", "report", "calibration",
            "iso9283", "shop")
REPORT_KEYS = ("units", "precision")
POSE_KEYS = ("grid", "latin_hypercube", "list", "refine", "joints", "drop_unreachable")
REFINE_KEYS = ("grid", "local", "add", "max_rounds", "tol", "n_final", "n_local")
BOUND_KEYS = ("lower", "upper", "cost_width", "distribution", "contains_nominal")
SOURCE_KEYS = ("lower", "upper", "locked", "fixed", "cost", "distribution", "sigma_k", "mean_shift", "offset", "minus",
               "plus", "cost_width", "contains_nominal")
REQUIREMENT_KEYS = tuple(f.name for f in dataclasses.fields(Requirement)) + AXIS_KEYS + ("iso9283",)   # iso9283: evotol/studyfile/iso9283.py
#: keys of [bounds.GROUP] / [bounds.SOURCE]
GROUP_BOUND_KEYS = ("lower", "upper")


def check_study_keys(spec: dict) -> None:
    """Check every table of a study file whose keys evotol defines (typos like ``lowr`` or
    ``[requirment]`` are errors, not silently ignored).

    Raises
    ------
    ValidationError
        An unknown key in the top level, ``[poses]``, ``[poses.refine]``, ``[requirement]``,
        ``[report]``, ``[bounds]`` or a ``[sources.NAME]`` table; a ``refine`` that is neither a
        bool nor a table; a ``seed`` that is not a non-negative integer.
    """
    check_table_keys(spec, TOP_KEYS, "")
    check_table_keys(spec.get("poses", {}), POSE_KEYS, "poses")
    ref = spec.get("poses", {}).get("refine")
    if isinstance(ref, dict):
        check_table_keys(ref, REFINE_KEYS, "poses.refine")
    elif ref is not None and not isinstance(ref, bool):
        raise ValidationError("poses.refine", ref, "true, false or a table of refinement options")
    check_table_keys(spec.get("requirement", {}), REQUIREMENT_KEYS, "requirement")
    check_table_keys(spec.get("report", {}), REPORT_KEYS, "report")
    bounds = spec.get("bounds", {})   # sub-tables [bounds.GROUP] are checked once the robot is known
    check_table_keys({k: v for k, v in bounds.items() if not isinstance(v, dict)} if isinstance(bounds, dict) else bounds,
                     BOUND_KEYS, "bounds")
    for n, o in spec.get("sources", {}).items():
        check_table_keys(o, SOURCE_KEYS, f"sources.{n}")
    seed = spec.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValidationError("seed", seed, "a non-negative integer")

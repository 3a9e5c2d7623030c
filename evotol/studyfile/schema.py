"""A JSON Schema of the study file, generated from the reader's own key tables (issue 40).

Editors that read JSON Schema for TOML (VS Code's Even Better TOML, taplo, PyCharm) complete and
check a study file's keys with it: point the file at it with a first line
``#:schema ./study.schema.json`` (taplo's directive), or map ``*.toml`` study files to
``docs/study.schema.json`` in the editor's settings. ``evotol schema`` prints it;
``tests/test_study_schema.py`` checks that the shipped copy is up to date and that every shipped
study file validates.

The schema is built from the tuples the reader checks keys against (``evotol.studyfile.keys``, the
``[stack]``, ``[calibration]``, ``[clearances]`` and ``[processes]`` readers) and from the
signatures of the allocators and of ``verify`` (the keyword tables of ``[methods]`` and
``[verify]``), so a key added to the reader appears here without a second list. Values are typed
where the reader's rule is simple (a seed is a non-negative integer, ``refine`` a boolean or a
table); the reader's own checks stay the authority on values (``docs/errors.md``).
"""
from __future__ import annotations

import inspect
import json

from evotol.calibration.table import KEYS as CALIBRATION_KEYS
from evotol.measures.clearances.classes import CLASS_KEYS, TABLE_KEYS as CLEARANCE_KEYS
from evotol.studyfile import keys, processes, stack_table
from evotol.studyfile.methods import METHODS
from evotol.verification.montecarlo import verify

SCHEMA_URI = "https://json-schema.org/draft/2020-12/schema"
#: keywords evotol sets itself (never in a study file's method or verify table)
SET_BY_EVOTOL = ("problem", "pp", "budget", "tolerances", "progress")


def _table(names, description: str = "", extra=None, open_: bool = False, **props) -> dict:
    """An object schema whose properties are ``names`` (any value unless ``props`` types it)."""
    schema = {"type": "object", "properties": {n: props.get(n, {}) for n in names}}
    if description:
        schema["description"] = description
    schema["additionalProperties"] = extra if extra is not None else open_
    return schema


def _keywords(*functions) -> list[str]:
    """The keyword names of ``functions`` a study file may set (union, in order)."""
    out: list[str] = []
    for f in functions:
        for name, p in inspect.signature(f).parameters.items():
            if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY) and name not in SET_BY_EVOTOL and name not in out:
                out.append(name)
    return out


def _methods() -> dict:
    allocators: dict[str, list] = {}
    for registry in (METHODS, stack_table.STACK_METHODS, processes.METHODS):
        for name, f in registry.items():
            allocators.setdefault(name, []).append(f)
    return _table(sorted(allocators), "The allocators to run, each with its keyword table (e.g. ga = { pop_size = 60 }).",
                  **{n: _table(_keywords(*fs), f"Keywords of the '{n}' method.") for n, fs in allocators.items()})


def study_schema() -> dict:
    """The JSON Schema (draft 2020-12) of a study file, from the reader's key tables.

    Returns
    -------
    dict
        The schema, JSON-ready: top-level keys of a study file (``[robot]`` studies and
        ``[stack]`` studies), and the keys of each table whose keys evotol defines.

    Examples
    --------
    >>> schema = study_schema()
    >>> schema["additionalProperties"], "requirement" in schema["properties"]
    (False, True)
    >>> sorted(schema["properties"]["poses"]["properties"])[:3]
    ['drop_unreachable', 'grid', 'joints']
    """
    seed = {"type": "integer", "minimum": 0, "description": "Seed of the randomised methods (a non-negative integer)."}
    group_bounds = _table(keys.GROUP_BOUND_KEYS, "Bounds of one source group or source ([bounds.GROUP]).")
    top = {
        "name": {"type": "string", "description": "The study's name (its output files are NAME.html, NAME.json)."},
        "seed": seed,
        "robot": {"type": "object", "description": "The robot: model = NAME, mechanism = FILE, urdf = ..., or "
                                                   "assembly = 'module:function' (docs/mechanisms.md)."},
        "poses": _table(keys.POSE_KEYS, "The workspace poses the requirement holds at.",
                        refine={"oneOf": [{"type": "boolean"}, _table(keys.REFINE_KEYS)]}),
        "requirement": _table(keys.REQUIREMENT_KEYS, "The accuracy the design must hold (SI: m, rad)."),
        "bounds": _table(keys.BOUND_KEYS, "Default tolerance bounds (SI), and [bounds.GROUP] sub-tables.",
                         extra=group_bounds),
        "cost": {"type": "object", "description": "Cost models: [cost.default] and [cost.GROUP]."},
        "sources": _table((), "Per-source settings: [sources.NAME].", extra=_table(keys.SOURCE_KEYS)),
        "methods": _methods(),
        "verify": _table(_keywords(verify), "The Monte Carlo check of every method's design."),
        "clearances": _table(CLEARANCE_KEYS, "Joint clearances (docs/clearance_allocation.md).",
                             **{"class": {"type": "array", "items": _table(CLASS_KEYS)}}),
        "processes": {"type": "object", "description": "Candidate processes per source: [[processes.NAME]].",
                      "additionalProperties": {"type": "array", "items": _table(processes.PROCESS_KEYS)}},
        "calibration": _table(CALIBRATION_KEYS, "The calibration the robot will get (docs/calibration.md).",
                              seed=seed),
        "report": _table(keys.REPORT_KEYS, "Display units and precision of the report."),
        "stack": _table(stack_table.STACK_KEYS, "A tolerance stack (docs/stack_analysis.md).",
                        dimensions={"type": "object", "additionalProperties": _table(stack_table.DIMENSION_KEYS)},
                        models={"type": "object", "additionalProperties": _table(stack_table.MODEL_KEYS)},
                        allocation=_table(stack_table.ALLOCATION_KEYS)),
    }
    names = list(dict.fromkeys([*keys.TOP_KEYS, *stack_table.TOP_KEYS]))
    schema = _table(names, "An evotol study file (TOML), as evotol run reads it.",
                    **{n: top.get(n, {}) for n in names})
    return {"$schema": SCHEMA_URI, "title": "evotol study file", **schema}


def schema_text() -> str:
    """:func:`study_schema` as the JSON text ``evotol schema`` prints and ``docs/study.schema.json``
    holds (indent 2, a final newline).

    Returns
    -------
    str
        The JSON text.
    """
    return json.dumps(study_schema(), indent=2) + "\n"

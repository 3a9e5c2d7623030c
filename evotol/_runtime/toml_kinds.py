"""Which kind of evotol file a parsed TOML document is: a study file or a mechanism description
(issue 27 item 6). A file given where the other kind is expected is named as the wrong kind of
file, with the command that takes it -- not reported as an unknown key (``mechanism.seed = 0``)
or a near miss (``did you mean 'distribution'?``).

The kinds are told apart by their top-level tables: a study file has ``[robot]``,
``[requirement]``, ``[methods]``, ``[poses]``, ``[cost]``, ...; a description has ``[[frame]]``,
``[end_effector]``, ``[[loop]]``, ``[lengths]``, ``urdf``/``tip``, ... A document with keys of
both kinds (or of neither) is left to the key checks of its reader.
"""
from __future__ import annotations

from typing import Mapping

from evotol.errors import ValidationError

STUDY_KEYS = frozenset({"robot", "requirement", "methods", "poses", "cost", "bounds", "verify", "sources", "shared",
                        "shared_cost", "clearances", "seed", "processes", "stack"})
MECHANISM_KEYS = frozenset({"frame", "end_effector", "loop", "lengths", "angles", "point", "urdf", "tip", "assembly",
                            "tolerances", "clearance", "planar", "checks"})
WHAT = {"study": "a study file ([robot], [requirement], [methods], ...)",
        "mechanism": "a mechanism description ([[frame]] rows or urdf + tip, [end_effector], [assembly], ...)"}


def kind_of(spec: Mapping) -> str | None:
    """``"study"``, ``"mechanism"`` or None (both kinds' keys, or neither).

    Parameters
    ----------
    spec : mapping
        The parsed TOML document; anything else is of no kind.

    Returns
    -------
    {"study", "mechanism"} or None
        ``"study"`` when only study-file top-level keys occur, ``"mechanism"`` when only
        mechanism-description keys occur, None otherwise (or when ``spec`` is not a mapping).
    """
    if not isinstance(spec, Mapping):
        return None
    keys = set(spec)
    study, mech = bool(keys & STUDY_KEYS), bool(keys & MECHANISM_KEYS)
    if study and not mech:
        return "study"
    if mech and not study:
        return "mechanism"
    return None


def check_kind(spec: Mapping, expected: str, path, field: str | None = None) -> None:
    """Raise a ValidationError when ``spec`` (read from ``path``) is clearly the other kind of file.

    Parameters
    ----------
    spec : mapping
        The parsed TOML document.
    expected : {"study", "mechanism"}
        The kind the caller reads.
    path : str or Path
        The file, named in the message.
    field : str, optional
        The field to name (default ``"study file"`` / ``"mechanism file"``).

    Raises
    ------
    ValidationError
        ``mechanism file = 'study.toml': expected a mechanism description (...); this is a study
        file: run it with evotol run study.toml``.
    """
    kind = kind_of(spec)
    if kind is None or kind == expected:
        return
    found = sorted(set(spec) & (STUDY_KEYS if kind == "study" else MECHANISM_KEYS))
    if kind == "study":
        robot = spec.get("robot", {}) if isinstance(spec.get("robot"), Mapping) else {}
        use = f"run it with `evotol run {path}`" + (f"; its mechanism is {robot['mechanism']!r} (`evotol check-mechanism "
                                                    f"{robot['mechanism']}`)" if "mechanism" in robot else "")
    else:
        use = f"check it with `evotol check-mechanism {path}`, or name it in a study file: [robot] mechanism = '{path}'"
    raise ValidationError(field or f"{expected} file", str(path), f"{WHAT[expected]}; this is {WHAT[kind].split(' (')[0]} "
                                                                  f"(it has {', '.join(found)}): {use}")

"""An assembly function named in a study file: ``assembly = "module:function"`` resolved to the
function, and the ``[robot]`` table (nominal dimensions in SI, limits) turned into an
:class:`~robots.assembly.function.AssemblyFunction`.
"""
from __future__ import annotations

from typing import Callable, Mapping

from evotol.errors import ValidationError
from robots.assembly.function import AssemblyFunction


def resolve(spec: str) -> Callable:
    """``"package.module:function"`` -> the function (for study files).

    Parameters
    ----------
    spec : str
        Import path with exactly one ``:``, e.g. ``"mypkg.clutch:contact_angle"``.

    Returns
    -------
    callable
        The named object.

    Raises
    ------
    evotol.errors.ValidationError
        Not a string with one ``:``, a module or attribute that does not import, or an object
        that is not callable.
    """
    import importlib

    if not isinstance(spec, str) or spec.count(":") != 1:
        raise ValidationError("robot.assembly", spec, "'module:function', e.g. 'mypkg.clutch:contact_angle'")
    mod, fn = spec.split(":")
    try:
        f = getattr(importlib.import_module(mod), fn)
    except (ImportError, AttributeError) as exc:
        raise ValidationError("robot.assembly", spec, f"an importable function ({type(exc).__name__}: {exc})") from exc
    if not callable(f):
        raise ValidationError("robot.assembly", spec, "a callable")
    return f


def assembly_from_spec(spec: Mapping) -> AssemblyFunction:
    """The ``[robot]`` table of a study file that names an assembly function:

    ``assembly = "module:function"``, ``nominal = {dim = value (SI), ...}``,
    ``limits = {response = allowed deviation, ...}``, optional ``name``, ``units``, ``groups``.

    Parameters
    ----------
    spec : Mapping
        The table: ``assembly`` (str, ``"module:function"``), ``nominal`` (dimension -> value,
        SI: m or rad), ``limits`` (response -> allowed deviation, the response's unit), and
        optionally ``name`` (default: the ``assembly`` string), ``units`` (dimension -> ``"m"``
        or ``"rad"``), ``groups`` (dimension -> group).

    Returns
    -------
    AssemblyFunction
        The assembly's error model.

    Raises
    ------
    evotol.errors.ValidationError
        An unknown key, ``nominal`` or ``limits`` that is not a table, an ``assembly`` path that
        does not resolve (:func:`resolve`), or invalid values (see :class:`AssemblyFunction`).
    """
    spec = dict(spec)
    known = {"assembly", "nominal", "limits", "name", "units", "groups"}
    extra = sorted(set(spec) - known)
    if extra:
        raise ValidationError(f"robot.{extra[0]}", spec[extra[0]], f"one of {sorted(known)} for an assembly")
    for key in ("nominal", "limits"):
        if not isinstance(spec.get(key), Mapping):
            raise ValidationError(f"robot.{key}", spec.get(key), "a table, e.g. {a = 0.027, c = 0.011}")
    f = resolve(spec["assembly"])
    return AssemblyFunction(f, spec["nominal"], spec["limits"], name=spec.get("name", spec["assembly"]),
                            units=spec.get("units"), groups=spec.get("groups"))

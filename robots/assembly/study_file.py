"""An assembly function named in a study file: ``assembly = "module:function"`` resolved to the
function, and the ``[robot]`` table (nominal dimensions in SI, limits) turned into an
:class:`~evotol.robots.assembly.function.AssemblyFunction`.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Mapping

from evotol.errors import ValidationError
from evotol.robots.assembly.function import AssemblyFunction


def _beside(module: str, base_dir) -> bool:
    """Whether ``module`` is a file (``a/b.py``) or package (``a/b/``) in ``base_dir``."""
    p = Path(base_dir).joinpath(*module.split("."))
    return p.with_suffix(".py").is_file() or (p / "__init__.py").is_file()


def resolve(spec: str, base_dir=None) -> Callable:
    """``"package.module:function"`` -> the function (for study files).

    A module that Python cannot import is looked up beside the study file: when ``base_dir``
    holds ``module.py`` (or the package), ``base_dir`` is put first on ``sys.path`` and stays
    there, so that worker processes started from this one import it too (no ``PYTHONPATH=.``).

    Parameters
    ----------
    spec : str
        Import path with exactly one ``:``, e.g. ``"mypkg.clutch:contact_angle"``.
    base_dir : str or Path, optional
        The study file's folder, where a module that is not importable otherwise is looked up.

    Returns
    -------
    callable
        The named object.

    Raises
    ------
    evotol.errors.ValidationError
        Not a string with one ``:``, a module or attribute that does not import (neither
        installed nor beside the study file), or an object that is not callable.
    """
    import importlib
    import sys

    if not isinstance(spec, str) or spec.count(":") != 1:
        raise ValidationError("robot.assembly", spec, "'module:function', e.g. 'mypkg.clutch:contact_angle'")
    mod, fn = spec.split(":")
    try:
        try:
            module = importlib.import_module(mod)
        except ModuleNotFoundError as exc:
            missing = exc.name or ""
            if base_dir is None or not (mod == missing or mod.startswith(missing + ".")) or not _beside(mod, base_dir):
                raise
            folder = str(Path(base_dir).resolve())
            if folder not in sys.path:
                sys.path.insert(0, folder)
            importlib.invalidate_caches()
            module = importlib.import_module(mod)
        f = getattr(module, fn)
    except (ImportError, AttributeError) as exc:
        where = f" (nor {mod.replace('.', '/')}.py beside the study file in {base_dir})" if base_dir is not None else ""
        raise ValidationError("robot.assembly", spec, f"an importable function{where} ({type(exc).__name__}: {exc})") from exc
    if not callable(f):
        raise ValidationError("robot.assembly", spec, "a callable")
    return f


def assembly_from_spec(spec: Mapping, base_dir=None) -> AssemblyFunction:
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
    base_dir : str or Path, optional
        The study file's folder: a ``module`` there resolves without ``PYTHONPATH`` (:func:`resolve`).

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
    f = resolve(spec["assembly"], base_dir)
    return AssemblyFunction(f, spec["nominal"], spec["limits"], name=spec.get("name", spec["assembly"]),
                            units=spec.get("units"), groups=spec.get("groups"))

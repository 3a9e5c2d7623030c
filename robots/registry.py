"""Robots by name, for study files: built-ins, entry points (group ``evotol.robots``), or an
import path ``"package.module:ClassName"``."""
from __future__ import annotations

import importlib

from evotol.errors import ValidationError

BUILTIN = {
    "ucr3": "evotol.robots.ucr3:UCR3",
    "delta": "evotol.robots.delta:DeltaRobot",
    "planar5r": "evotol.robots.planar5r.model:Planar5R",
    "fivebar": "evotol.robots.fivebar:FiveBarGeometric",
}


def _load(path: str):
    mod, _, cls = path.partition(":")
    try:
        return getattr(importlib.import_module(mod), cls)
    except (ImportError, AttributeError) as exc:
        raise ValidationError("robot.model", path, f"an importable 'module:Class' ({exc})") from None


def available() -> dict[str, type]:
    """Every registered robot class by name: the built-ins and the ``evotol.robots`` entry points.

    Returns
    -------
    dict of str to type
        Robot classes by registered name; an entry point overrides a built-in of the same name.

    Raises
    ------
    evotol.errors.ValidationError
        A built-in's ``module:Class`` path does not import.
    """
    from evotol._runtime.plugins import group_entry_points

    found = {name: _load(path) for name, path in BUILTIN.items()}
    found.update({ep.name: ep.load() for ep in group_entry_points("evotol.robots")})
    return found


def get(name: str):
    """The robot class registered as ``name`` (or at import path ``module:Class``).

    An entry point of group ``evotol.robots`` takes precedence over a built-in of the same name.

    Parameters
    ----------
    name : str
        A registered name (``"ucr3"``, ``"delta"``, ``"planar5r"``, ``"fivebar"`` or an entry
        point's), or an import path ``"package.module:ClassName"`` (recognised by its ``:``).

    Returns
    -------
    type
        The robot class (not an instance).

    Raises
    ------
    evotol.errors.ValidationError
        An unknown name (the message lists the known ones), or an import path whose module or
        class does not import.
    """
    if ":" in name:
        return _load(name)
    from evotol._runtime.plugins import group_entry_points

    eps = {ep.name: ep for ep in group_entry_points("evotol.robots")}
    if name in eps:
        return eps[name].load()
    if name in BUILTIN:
        return _load(BUILTIN[name])
    raise ValidationError("robot.model", name, f"one of {sorted(set(BUILTIN) | set(eps))} or 'module:Class'")

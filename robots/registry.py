"""Robots by name, for study files: built-ins, entry points (group ``evotol.robots``), or an
import path ``"package.module:ClassName"``."""
from __future__ import annotations

import importlib

from evotol.errors import ValidationError

BUILTIN = {
    "ucr3": "robots.ucr3:UCR3",
    "delta": "robots.delta:DeltaRobot",
    "planar5r": "robots.planar5r.model:Planar5R",
    "fivebar": "robots.fivebar:FiveBarGeometric",
}


def _load(path: str):
    mod, _, cls = path.partition(":")
    try:
        return getattr(importlib.import_module(mod), cls)
    except (ImportError, AttributeError) as exc:
        raise ValidationError("robot.model", path, f"an importable 'module:Class' ({exc})") from None


def available() -> dict[str, type]:
    """Every registered robot class by name: the built-ins and the ``evotol.robots`` entry points."""
    from importlib.metadata import entry_points

    found = {name: _load(path) for name, path in BUILTIN.items()}
    found.update({ep.name: ep.load() for ep in entry_points(group="evotol.robots")})
    return found


def get(name: str):
    """The robot class registered as ``name`` (or at import path ``module:Class``)."""
    if ":" in name:
        return _load(name)
    from importlib.metadata import entry_points

    eps = {ep.name: ep for ep in entry_points(group="evotol.robots")}
    if name in eps:
        return eps[name].load()
    if name in BUILTIN:
        return _load(BUILTIN[name])
    raise ValidationError("robot.model", name, f"one of {sorted(set(BUILTIN) | set(eps))} or 'module:Class'")

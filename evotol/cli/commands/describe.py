"""``evotol describe ROBOT``: a robot's error sources (group, unit, shape) and its workspace.

ROBOT may also be a mechanism description: a shipped one by name (``evotol describe ur5``,
``planar3rpr``) or a description file (``evotol describe my_robot.toml``); a study file there is
named as the wrong kind of file (issue 27).

What a study file needs to name: the source names for ``[sources.NAME]``, the groups for
``[cost.GROUP]``, the units the tolerances are given in (SI: m or rad), and the workspace
coordinates and ranges for ``[poses]``. ROBOT is a built-in name, an entry point of the
``evotol.robots`` group or an import path ``module:Class``; ``--set key=value`` passes
constructor arguments (e.g. ``--set variant=paper``).
"""
from __future__ import annotations

import json


def register(subparsers) -> None:
    """Add the ``describe`` sub-command to the ``evotol`` parser.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        What ``ArgumentParser.add_subparsers()`` returned; the new parser's ``func`` default
        is :func:`cmd_describe`.
    """
    p = subparsers.add_parser(
        "describe", help="list a robot's error sources (groups, units, shapes) and its workspace",
        description=__doc__.split("\n\n", 1)[1])
    p.add_argument("robot", help="robot name (e.g. ucr3, delta, planar5r, fivebar), module:Class, a shipped mechanism "
                                 "description (ur5, planar3rpr, ...) or a description file (TOML)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="constructor argument of the robot (repeatable); VALUE is read as TOML (number, string...)")
    p.add_argument("--json", action="store_true", help="print the description as JSON")
    p.set_defaults(func=cmd_describe)


def _parse_set(items: list[str]) -> dict:
    import tomllib

    from evotol.errors import ValidationError

    kwargs = {}
    for item in items:
        key, eq, text = item.partition("=")
        if not eq or not key.strip():
            raise ValidationError("--set", item, "KEY=VALUE, e.g. variant=paper")
        try:
            kwargs[key.strip()] = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            kwargs[key.strip()] = text.strip()          # a bare word: a string
    return kwargs


def describe(robot) -> dict:
    """JSON-ready description of a robot: sources and workspace (SI units, with display units).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The robot or mechanism model.

    Returns
    -------
    dict
        ``robot`` (name), ``nonlinear_model`` (bool), ``sources`` (name, group, unit, shape,
        dim, description), ``groups`` (sorted) and ``workspace`` (per coordinate: name, SI
        ``unit``, ``low``/``high`` in it, ``display_unit`` and ``display_low``/``display_high``).
    """
    ws = robot.workspace
    return {
        "robot": robot.name,
        "nonlinear_model": bool(robot.has_nonlinear_model),
        "sources": [{"name": s.name, "group": s.group, "unit": s.unit, "shape": s.shape, "dim": s.dim,
                     "description": s.description} for s in robot.sources],
        "groups": sorted({s.group for s in robot.sources}),
        "workspace": [{"name": n, "unit": u, "low": lo, "high": hi, "display_unit": du,
                       "display_low": lo * k, "display_high": hi * k}
                      for n, u, lo, hi, du, k in zip(ws.names, ws.units, ws.low, ws.high,
                                                     ws.display_units, ws.display_scale)],
    }


def robot_for(name: str, settings: list[str]):
    """The robot ``evotol describe NAME`` means: a description file, a registered robot (with
    ``--set`` arguments), else a shipped mechanism description.

    Parameters
    ----------
    name : str
        A description file, a robot name (built-in, entry point or ``module:Class``) or the name
        of a shipped description.
    settings : list of str
        The ``--set KEY=VALUE`` items (VALUE read as TOML, else as a string).

    Returns
    -------
    evotol.robots.base.RobotErrorModel
        The robot, or a :class:`evotol.robots.mechanism.model.error_model.MechanismModel` of the description.

    Raises
    ------
    ValidationError
        An unknown name (listing robots and shipped descriptions), ``--set`` for a description,
        or a study file (the wrong kind of file).
    """
    from pathlib import Path

    from evotol.errors import ValidationError
    from evotol.robots import registry
    from evotol.robots.mechanism.model.error_model import SHIPPED, MechanismModel, resolve_description

    path = Path(name)
    description = path.is_file() or (":" not in name and (SHIPPED / f"{name}.toml").is_file())
    try:
        cls = None if path.is_file() else registry.get(name)
    except ValidationError as exc:
        if not description:
            shipped = sorted(f.stem for f in SHIPPED.glob("*.toml"))
            raise ValidationError(exc.field, name, f"{exc.expected}, a shipped mechanism description {shipped} or a "
                                                   "description file (TOML)") from None
        cls = None
    if cls is None:
        if settings:
            raise ValidationError("--set", settings, f"nothing for a mechanism description ({name} has no constructor "
                                                     "arguments: edit the file)")
        return MechanismModel(resolve_description(name))
    kwargs = _parse_set(settings)
    try:
        return cls(**kwargs)
    except TypeError as exc:
        raise ValidationError("--set", kwargs, f"constructor arguments accepted by {cls.__name__} ({exc})") from None


def cmd_describe(args) -> int:
    """Run ``evotol describe ROBOT`` (module docstring): print the robot's sources and workspace.

    Parameters
    ----------
    args : argparse.Namespace
        ``robot`` (name or file), ``set`` (list of ``KEY=VALUE``) and ``json`` (bool: print
        :func:`describe` as JSON).

    Returns
    -------
    int
        Exit status 0.

    Raises
    ------
    ValidationError
        As :func:`robot_for`: an unknown robot, bad ``--set`` arguments, or a study file.
    """
    robot = robot_for(args.robot, args.set)
    d = describe(robot)
    if args.json:
        print(json.dumps(d, indent=2))
        return 0
    print(f"{d['robot']}: {len(d['sources'])} error sources, {robot.n_columns} error components"
          f"{', nonlinear model for Monte Carlo' if d['nonlinear_model'] else ''}")
    print("tolerances are given in SI units (m or rad): the radius of an interval, disk or ball")
    rows = [("source", "group", "unit", "shape", "description")]
    rows += [(s["name"], s["group"], s["unit"], s["shape"], s["description"]) for s in d["sources"]]
    widths = [max(len(str(r[i])) for r in rows) for i in range(4)]
    for r in rows:
        print("  " + "  ".join(str(c).ljust(w) for c, w in zip(r[:4], widths)) + ("  " + r[4] if r[4] else ""))
    print("groups (for [cost.GROUP]): " + ", ".join(d["groups"]))
    print("workspace (pose coordinates for [poses], SI):")
    for w in d["workspace"]:
        shown = (f"  ({w['display_low']:.6g} .. {w['display_high']:.6g} {w['display_unit']})"
                 if w["display_unit"] != w["unit"] else "")
        print(f"  {w['name']:8s} {w['low']:.6g} .. {w['high']:.6g} {w['unit']}{shown}")
    return 0

"""``evotol check-calibration FILE``: what a calibration plan identifies, before any allocation.

FILE is a study file with a ``[calibration]`` table (``docs/calibration.md``) or a mechanism
description (then ``--noise`` and ``--count`` give the plan). The options override the table's
keys. Prints the plan, the base set the fit keeps (in the order taken: registration, actuator
offsets, then the rest), every source it drops and why (a combination of kept ones, or unseen),
the rank of all measured columns and the condition number of the kept ones; for a study file also
the noise's share of the requirement and the sources the linear range caps. Exit status 1 when
the condition number exceeds ``--max-condition``.
"""
from __future__ import annotations

import json


def register(subparsers) -> None:
    """Add the ``check-calibration`` sub-command to the ``evotol`` parser.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        What ``ArgumentParser.add_subparsers()`` returned; the new parser's ``func`` default is
        :func:`cmd_check_calibration`.
    """
    p = subparsers.add_parser("check-calibration", help="check a calibration plan: identifiable base set, condition number",
                              description=__doc__.split("\n\n", 1)[1])
    p.add_argument("file", help="study file with a [calibration] table, or a mechanism description (or a shipped name)")
    p.add_argument("--count", type=int, default=None, help="calibration configurations (Latin hypercube)")
    p.add_argument("--over", default=None, help="draw them over the 'workspace' (default) or the 'joints'")
    p.add_argument("--noise", default=None, help="instrument noise with its unit, e.g. '20 um'")
    p.add_argument("--identify", default=None, help="comma-separated source patterns, or 'identifiable'")
    p.add_argument("--instrument", default=None, help="'known' or 'unknown' (registration identified too)")
    p.add_argument("--max-condition", type=float, default=1e3, help="exit 1 above this condition number (default 1e3)")
    p.add_argument("--json", action="store_true", help="print the check as JSON")
    p.set_defaults(func=cmd_check_calibration)


def _overrides(args) -> dict:
    out = {}
    for k in ("count", "over", "noise", "instrument"):
        if getattr(args, k) is not None:
            out[k] = getattr(args, k)
    if args.identify is not None:
        out["identify"] = args.identify if args.identify == "identifiable" else [s.strip() for s in args.identify.split(",")]
    return out


def check_calibration(path, overrides: dict | None = None) -> dict:
    """The check of a plan (module docstring) as plain data (SI).

    Parameters
    ----------
    path : str or Path
        A study file with ``[calibration]``, or a mechanism description (or a shipped one's name).
    overrides : dict, optional
        ``[calibration]`` keys replacing the file's (``count``, ``noise``, ``identify`` ...).

    Returns
    -------
    dict
        ``name``, ``identification`` (:meth:`evotol.calibration.identification.Identification.to_dict`),
        and for a study file ``noise`` and ``capped`` (source -> linear-range bound, m or rad).

    Raises
    ------
    evotol.errors.ValidationError
        A file that does not load, a plan refused (:func:`evotol.calibration.table.plan_from_table`), or a
        mechanism description without ``--noise`` / ``--count``, or a ``[stack]`` or
        ``[processes]`` study (no robot).
    """
    import tomllib
    from pathlib import Path

    from evotol.calibration import calibrated_problem, identify
    from evotol.calibration.table import plan_from_table
    from evotol.errors import ValidationError

    p = Path(path)
    spec = tomllib.loads(p.read_text(encoding="utf-8")) if p.is_file() else {}
    table = {**spec.get("calibration", {}), **(overrides or {})}
    for kind in ("stack", "processes"):     # no robot to calibrate: say so, never ask for a noise (issue 41)
        if kind in spec:
            raise ValidationError("file", str(path), f"a study with a robot ([robot]) or a mechanism description: "
                                  f"a [{kind}] study has no robot to calibrate (calibration identifies a robot's "
                                  "geometry from measured poses, docs/calibration.md)")
    if "robot" in spec:
        from evotol.studyfile import load_problem

        plan, _ = plan_from_table(table, spec.get("seed", 0))
        problem = load_problem({k: v for k, v in spec.items() if k != "calibration"}, base_dir=p.parent)
        pc = calibrated_problem(problem, plan, simulate=0)
        info = pc.calibration
        capped = {n: b["upper"] for n, b in info.bounds.items() if b["upper"] < b["upper_before"]}
        return {"name": spec.get("name", p.stem), "identification": info.identification.to_dict(),
                "noise": info.noise, "capped": capped}
    from evotol.robots.mechanism.model.error_model import MechanismModel
    from evotol.robots.mechanism.description.shipped import resolve_description

    if "noise" not in table:
        raise ValidationError("--noise", None, "the instrument noise with its unit (a mechanism file has no [calibration])")
    plan, _ = plan_from_table(table)
    robot = MechanismModel(resolve_description(str(path), None))
    return {"name": robot.name, "identification": identify(robot, plan).to_dict()}


def cmd_check_calibration(args) -> int:
    """Run ``evotol check-calibration FILE`` (module docstring).

    Parameters
    ----------
    args : argparse.Namespace
        ``file``, ``count``, ``over``, ``noise``, ``identify``, ``instrument``, ``max_condition``, ``json``.

    Returns
    -------
    int
        0, or 1 when the condition number exceeds ``max_condition``.

    Raises
    ------
    evotol.errors.ValidationError
        What :func:`check_calibration` refuses.
    """
    out = check_calibration(args.file, _overrides(args))
    idn = out["identification"]
    ok = idn["condition_number"] <= args.max_condition
    if args.json:
        print(json.dumps(out, indent=2))
        return 0 if ok else 1
    print(f"{out['name']}: {idn['n_configurations']} calibration configurations, {idn['n_measurements']} measured coordinates")
    print(f"  identifiable directions (rank of the seen columns): {idn['rank']}; base set kept: {idn['n_identified']} sources"
          + (f" + registration {', '.join(idn['registration'])}" if idn["registration"] else ""))
    for n in idn["identified"]:
        print(f"    {n}")
    print(f"  condition number (unit-norm columns): {idn['condition_number']:.4g}"
          + ("" if ok else f"  -- above {args.max_condition:g}: spread the configurations or identify fewer sources"))
    if idn["dropped"]:
        print("  not kept:")
        for n, why in idn["dropped"].items():
            print(f"    {n}: {why}")
    for comp, n in (out.get("noise") or {}).items():
        if isinstance(n, dict):
            u, k = ("mm", 1e3) if comp == "position" else ("mrad", 1e3)
            print(f"  noise at the task poses ({comp}): sigma {n['sigma'] * k:.4g} {u}, {100 * n['level']:.2f} % quantile "
                  f"{n['allowance'] * k:.4g} {u}, second order {n['second_order'] * k:.3g} {u} (noise) + "
                  f"{n['remainder'] * k:.3g} {u} (sources); requirement "
                  f"{n['bound'] * k:.4g} {u} -> tolerances hold {n['geometric_bound'] * k:.4g} {u}")
    if out.get("capped"):
        print(f"  upper bounds capped by the linear range / compensation range: {len(out['capped'])} sources")
    return 0 if ok else 1

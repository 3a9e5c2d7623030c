"""``evotol check-mechanism FILE``: what a mechanism description gives, and whether it is right.

Prints what it understood, in display units (lengths in mm, angles in deg): the design
parameters, the assembly joints as declared and as solved by Newton, and the end-effector pose
there -- so a unit slip (``Rb = 250`` meaning mm) is visible before it becomes an answer. Then the
joint variables (actuated and passive), the error sources it generated (name, group,
unit), the largest loop-closure residual of the Newton inverse geometry over Latin-hypercube poses
of the workspace, and the agreement of the first-order sensitivities with central finite
differences of the nonlinear closure (``evotol.robots.base.check_robot``). With a ``[clearance]`` table it
also prints the certified maximum pose error at the assembly pose. Exit status 1 when the
finite-difference agreement is worse than ``--rtol``.
"""
from __future__ import annotations

import json
import math


def register(subparsers) -> None:
    """Add the ``check-mechanism`` sub-command to the ``evotol`` parser.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        What ``ArgumentParser.add_subparsers()`` returned; the new parser's ``func`` default
        is :func:`cmd_check_mechanism`.
    """
    p = subparsers.add_parser("check-mechanism", help="check a mechanism description: sources, loop closure, FD agreement",
                              description=__doc__.split("\n\n", 1)[1])
    p.add_argument("file", help="mechanism description (TOML), or the name of a shipped one (fivebar, irsbot2, ...)")
    p.add_argument("--poses", type=int, default=20, help="Latin-hypercube poses for the checks (default 20)")
    p.add_argument("--sources", default=None, help="comma-separated names/patterns overriding [tolerances] sources")
    p.add_argument("--rtol", type=float, default=1e-5, help="largest relative FD mismatch accepted (default 1e-5)")
    p.add_argument("--json", action="store_true", help="print the check as JSON")
    p.add_argument("--tip", default=None, help="with a URDF file: the end-effector link or frame (e.g. tool0)")
    p.add_argument("--at", default=None, help="joint values (joint order, comma-separated; SI or '30*deg'): print the "
                                              "forward kinematics there")
    p.set_defaults(func=cmd_check_mechanism)


DISPLAY = {"m": ("mm", 1e3), "rad": ("deg", 180 / math.pi)}


def _shown(value, unit: str) -> str:
    """``0.2`` m -> ``200 mm``; ``0.698`` rad -> ``40 deg``."""
    if value is None:
        return "-"
    u, k = DISPLAY.get(unit, (unit, 1.0))
    v = value * k
    return f"{0.0 if abs(v) < 1e-9 else v:.6g} {u}"        # round-off below 1e-9 mm / deg shows as 0


def _fd_text(fd_rel_error, ok: bool, rtol: float) -> str:
    """``1.2e-09 relative (OK)``; ``not computed (...)`` when the check gave no number (None: the
    model has no nonlinear ``pose_error`` to difference)."""
    if fd_rel_error is None:
        return "not computed (the model has no nonlinear pose error to difference)"
    return f"{fd_rel_error:.3g} relative ({'OK' if ok else 'FAILED, > %g' % rtol})"


def print_understood(out: dict) -> None:
    """The parameters, the assembly (declared and solved joints) and the end-effector pose, in mm
    and deg (:func:`evotol.robots.mechanism.checks.description.understood`).

    Parameters
    ----------
    out : dict
        The check's result: ``parameters``, ``assembly`` (``pose``, ``joints``) and
        ``end_effector`` (``frame``, ``position`` in m, ``yaw_pitch_roll`` in rad); values SI,
        printed to stdout in mm and deg.
    """
    params = [f"{p['name']} = {_shown(p['value'], p['unit'])}" for p in out.get("parameters", [])]
    for i in range(0, len(params), 6):
        print(("  parameters: " if i == 0 else "              ") + ", ".join(params[i:i + 6]))
    asm = out["assembly"]
    print("  assembly pose: " + ", ".join(f"{c['name']} = {_shown(c['value'], c['unit'])}" for c in asm["pose"]))
    w = max([len(j["name"]) for j in asm["joints"]] + [5])
    print(f"    {'joint':{w}s} {'declared':>14s} {'solved':>14s}")
    for j in asm["joints"]:
        print(f"    {j['name']:{w}s} {_shown(j['declared'], j['unit']):>14s} {_shown(j['solved'], j['unit']):>14s}")
    ee = out["end_effector"]
    print(f"  end-effector {ee['frame']} at the assembly: position ({', '.join(_shown(v, 'm')[:-3] for v in ee['position'])}) mm, "
          f"yaw/pitch/roll ({', '.join(_shown(v, 'rad')[:-4] for v in ee['yaw_pitch_roll'])}) deg")


def cmd_check_mechanism(args) -> int:
    """Run ``evotol check-mechanism FILE`` (module docstring); a ``.urdf`` file goes to
    :func:`cmd_check_urdf`.

    Parameters
    ----------
    args : argparse.Namespace
        ``file``, ``poses`` (count), ``sources`` (comma-separated names/patterns or None),
        ``rtol`` (dimensionless), ``json`` (bool), ``tip``.

    Returns
    -------
    int
        Exit status: 0, or 1 when the finite-difference agreement is worse than ``rtol`` (0 when
        it was not computed: no nonlinear model).

    Raises
    ------
    ValidationError
        A description that cannot be read or checked (from
        :func:`evotol.robots.mechanism.checks.description.check_mechanism`), a URDF file without ``--tip``, or a
        description file with ``--tip``.
    KinematicsError
        The loops do not close at the assembly, or close far from the declared joints.
    """
    srcs = [s.strip() for s in args.sources.split(",")] if args.sources else None
    if str(args.file).lower().endswith(".urdf"):
        return cmd_check_urdf(args, srcs)
    if getattr(args, "tip", None):      # never ignored in silence (issue 41): a description names its own end effector
        from evotol.errors import ValidationError

        raise ValidationError("--tip", args.tip, f"no --tip for a description file ({args.file}): its end effector is "
                              "the description's own (the [end_effector] table, or tip = ... beside its urdf = ...); "
                              "--tip names the end link of a .urdf file")
    # loaded here, not at import: every sub-command module is imported to build `evotol --help`,
    # which must not pay for NumPy, the clearance engine and Pinocchio (tests/test_front_door.py)
    from evotol.robots.mechanism.checks.description import check_mechanism

    if args.at is not None:          # the forward kinematics at given joints (issue 33)
        return print_forward_at(args)
    out = check_mechanism(args.file, args.poses, srcs)
    ok = out["fd_rel_error"] is None or out["fd_rel_error"] <= args.rtol
    if args.json:
        print(json.dumps(out, indent=2))
        return 0 if ok else 1
    print(f"{out['name']}  ({out['file']}{', planar' if out['planar'] else ''})")
    print_understood(out)
    print(f"  actuated joint variables: {', '.join(out['actuated']) or '-'}")
    print(f"  passive joint variables:  {', '.join(out['passive']) or '-'}")
    print(f"  {out['n_sources']} error sources:")
    for s in out["sources"]:
        print(f"    {s['name']:14s} {s['group']:9s} {s['unit']:4s} {s['description']}")
    print_callouts(out)
    print(f"  loop-closure residual over {out['n_poses']} poses: {out['closure_residual']:.3g} (m or rad)")
    print(f"  sensitivity vs central finite differences of the closure: {_fd_text(out['fd_rel_error'], ok, args.rtol)}")
    print_limits_and_rank(out)
    if "clearance_at_assembly" in out:
        c = out["clearance_at_assembly"]
        print(f"  clearance worst case at the assembly pose {c['pose']}: p_max {c['p_max_m'] * 1e3:.6g} mm "
              f"(bound {c['p_upper_m'] * 1e3:.6g}), r_max {c['r_max_rad']:.6g} rad (bound {c['r_upper_rad']:.6g})")
    print(f"  {out['seconds']:.2f} s")
    return 0 if ok else 1


def print_forward_at(args) -> int:
    """``--at``: the end-effector pose at the given joint values, in mm and deg.

    Parameters
    ----------
    args : argparse.Namespace
        ``file`` (a description or a shipped name) and ``at`` (comma-separated joint values).

    Returns
    -------
    int
        0 (or the JSON with ``--json``).

    Raises
    ------
    ValidationError
        A description that cannot be read, or joint values it refuses
        (:func:`evotol.robots.mechanism.kinematics.forward_at.forward_at`).
    """
    from evotol.robots.mechanism.kinematics.forward_at import forward_at
    from evotol.robots.mechanism.model.error_model import MechanismModel
    from evotol.robots.mechanism.description.shipped import resolve_description

    model = MechanismModel(resolve_description(args.file, None))
    out = forward_at(model, args.at)
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print(f"{model.name}: forward kinematics at " + ", ".join(f"{k} = {_shown(v, out['units'][k])}" for k, v in out["joints"].items()))
    print(f"  end-effector {out['frame']}: position ({', '.join(_shown(v, 'm')[:-3] for v in out['position'])}) mm")
    print("  orientation ZYX (yaw, pitch, roll): (" + ", ".join(_shown(v, 'rad')[:-4] for v in out["zyx"]) + ") deg")
    for i, row in enumerate(out["rotation"]):
        print(("  R = " if i == 0 else "      ") + "[" + ", ".join(f"{0.0 if abs(v) < 1e-12 else v: .6f}" for v in row) + "]")
    return 0


# ------------------------------------------------------------------ issue 23: URDF files, limits, rank
def print_callouts(out: dict) -> None:
    """The drawing callouts understood (issue 35, ``docs/callouts.md``), their zones in mm: the
    feature on the joint axis, the zone and the sources it became.

    Parameters
    ----------
    out : dict
        :func:`evotol.robots.mechanism.checks.description.check_mechanism`'s report; nothing is printed without
        ``callouts``.
    """
    cs = out.get("callouts") or []
    if not cs:
        return
    print(f"  {len(cs)} drawing callouts ({cs[0]['zones']} zones; t is each callout's value, allocated):")
    for c in cs:
        lo, hi = (v * 1e3 for v in c["ends"])
        axis = "(" + ", ".join(f"{v:g}" for v in c["axis"]) + ")"
        if c["kind"] == "axial":
            zone = f"shoulder face within ±t/2 along the axis {axis}"
        elif c["kind"] == "position":
            zone = (f"axis within a cylinder ⌀t from {lo:g} mm to {hi:g} mm along {axis}: each end's displacement in a "
                    "disc of radius t/2")
        else:
            zone = (f"axis direction within a cylinder ⌀t over {c['length'] * 1e3:g} mm ({lo:g} to {hi:g} mm along "
                    f"{axis}), location free")
        sym = f"{c['symbol']}t" if c["symbol"].endswith("⌀") else f"{c['symbol']} t"
        print(f"    {c['name']:30s} {sym} | {c['datums']} on {c['part']}: {zone}; sources "
              f"{', '.join(c['members'])}")


def print_limits_and_rank(out: dict) -> None:
    """Workspace box, joint limits and the rank of the sources over the workspace, in mm and deg,
    naming blind and duplicated sources (:mod:`evotol.robots.mechanism.checks.inspection`).

    Parameters
    ----------
    out : dict
        The check's result; its optional ``workspace``, ``limits`` (SI values), ``redundancy``
        and ``identifiability`` entries are printed to stdout.
    """
    if "workspace" in out:
        print("  workspace box: " + ", ".join(f"{c['name']} {_shown(c['low'], c['unit'])} .. {_shown(c['high'], c['unit'])}"
                                              for c in out["workspace"]))
    if "limits" in out:
        lim = [f"{j['name']} {_shown(j['lower'], j['unit'])} .. {_shown(j['upper'], j['unit'])}" if j["lower"] is not None
               else f"{j['name']} unlimited" for j in out["limits"]]
        for i in range(0, len(lim), 3):
            print(("  joint limits: " if i == 0 else "                ") + "; ".join(lim[i:i + 3]))
    if out.get("redundancy"):
        print(f"  redundancy: {out['redundancy']['text']}")
    r = out.get("identifiability")
    if not r:
        return
    own = r.get("rank_without_multipliers", r["rank"])
    pin_txt = (f"; Pinocchio's placement regressor {r['pinocchio_rank']}, both together {r['combined_rank']}"
               f" ({'same span' if r['pinocchio_rank'] == r['combined_rank'] == own else 'DIFFERENT span'}"
               f"{'; the mimic multipliers add %d' % (r['rank'] - own) if r['rank'] > own else ''})"
               if "pinocchio_rank" in r else "")
    print(f"  rank of the {r['n_sources']} sources over {r['over']}: {r['rank']}{pin_txt}")
    if r["blind"]:
        print(f"    blind (move nothing): {', '.join(r['blind'])}")
    if r.get("missing"):
        print(f"    missing (no source moves the tip this way): {', '.join(n for n, _ in r['missing'])}")
    for a, b, sg in r["duplicated"]:
        print(f"    duplicated: {a} = {'' if sg > 0 else '-'}{b}")
    for combo in r["dependent"]:
        print("    dependent: " + " ".join(f"{c:+.3g} {n}" for n, c in combo) + " = 0")


def cmd_check_urdf(args, srcs) -> int:
    """``evotol check-mechanism arm.urdf --tip tool0``: the URDF's chain, sources, rank, FD agreement.

    Parameters
    ----------
    args : argparse.Namespace
        As for :func:`cmd_check_mechanism`; ``file`` is the URDF file, ``tip`` its end-effector
        link or frame.
    srcs : list of str or None
        Source names/patterns overriding the default sources.

    Returns
    -------
    int
        Exit status: 0, or 1 when the finite-difference agreement is worse than ``args.rtol`` (0
        when it was not computed).

    Raises
    ------
    ValidationError
        No ``--tip`` given.
    """
    from evotol.errors import ValidationError
    from evotol.robots.mechanism.urdf.check import check_urdf_file

    if not args.tip:
        from evotol.robots.mechanism.kinematics.forward_at import urdf_end_links
        ends = urdf_end_links(args.file)
        raise ValidationError("--tip", None, "the URDF link or frame that is the end-effector; its end links: "
                                             + (", ".join(ends) if ends else "none found"))
    out = check_urdf_file(args.file, args.tip, args.poses, srcs)
    ok = out["fd_rel_error"] is None or out["fd_rel_error"] <= args.rtol
    if args.json:
        print(json.dumps(out, indent=2))
        return 0 if ok else 1
    print(f"{out['name']}  ({out['file']}, tip {out['tip']})")
    print_understood(out)
    print(f"  {out['n_sources']} error sources (nominal value):")
    for s in out["sources"]:
        nominal = f"{s['nominal']:.6g}" if s["unit"] == "1" else _shown(s["nominal"], s["unit"])
        print(f"    {s['name']:28s} {s['group']:9s} {nominal:>12s}  {s['description']}")
    print_limits_and_rank(out)
    print(f"  forward kinematics vs Pinocchio: {out['fk_vs_pinocchio']:.3g} m")
    print(f"  sensitivity vs central finite differences: {_fd_text(out['fd_rel_error'], ok, args.rtol)}")
    print(f"  {out['seconds']:.2f} s")
    return 0 if ok else 1

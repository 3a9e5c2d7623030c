"""ISO 9283 in a study file (docs/iso9283.md): ``[requirement] iso9283 = { AP = "0.5 mm", RP = "0.05 mm" }``
and the ``[iso9283]`` table -- the test cube, the yield, the simulated test and the random sources::

    [iso9283]
    cube = { centre = ["400*mm", 0, "300*mm"], edge = "200 mm" }   # default: the largest in the workspace
    yield = 0.99                  # AP at a yield; default: the worst case over the tolerances
    simulate = { robots = 200, cycles = 30, multidirectional = true }
    allocate = true               # allocate the random sources with the systematic ones (default false)
    calibrate = { configurations = 40, noise = "10 um", robots = 100 }   # the same robots calibrated

    [iso9283.random.backlash]     # one table per kind: backlash, encoder, radial_play, axial_play
    joints = "all"                # or a list of actuated joints (bearing play: also passive joints' frames)
    tolerance = "1 arcmin"        # one value or one per joint; encoder: or bits = 19, gear_ratio = 100
    variation = 0.1               # backlash: share that varies from cycle to cycle
    lower = "0.2 arcmin"          # bounds for the allocation
    upper = "5 arcmin"
    cost = { model = "reciprocal", a0 = 10, a1 = 5, scale = 2.9e-4 }

A quantity is a number (SI) or a string ``"<number> <unit>"`` / ``"<number>*<unit>"`` with a unit of
:data:`UNITS`. Everything is checked by :func:`read_iso9283` before any work.

Parameters
----------
spec : dict
    The parsed study file.
problem : evotol.core.problem.ToleranceProblem
    The study's problem (its robot must be a described mechanism, serial or closed-loop and spatial, without
    wrappers).
"""
from __future__ import annotations

import fnmatch
import math
import re
from dataclasses import dataclass, field

import numpy as np

import evotol.cost_models
from evotol._runtime.keyword_checks import check_table_keys
from evotol.errors import ValidationError
from evotol.allocators.iso9283 import allocate_iso9283
from evotol.calibration.iso9283 import predict_calibrated, simulate_calibrated
from evotol.measures.iso9283.budget import source_shares
from evotol.measures.iso9283 import (TestCube, check_cube, iso_positions, largest_cube, predict, predict_orientation,
                                     quantile_interval, simulate)
from evotol.robots.mechanism.model.error_model import MechanismModel
from evotol.calibration.random_share import IsoTarget, RandomPart
from evotol.studyfile.iso9283_calibrated import calibrated_block, calibrated_methods
from evotol.studyfile.iso9283_methods import (allocator_args, method_allocations, methods_scope,
                                              refuse_front_beside_calibration, study_method_options)
from evotol.studyfile.iso9283_verdict import verdicts
from evotol.robots.mechanism.model.random_sources import KINDS, RandomSource, column_loading, encoder_count, joint_frames

UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "rad": 1.0, "mrad": 1e-3, "urad": 1e-6, "µrad": 1e-6,
         "deg": math.pi / 180, "arcmin": math.pi / 180 / 60, "arcsec": math.pi / 180 / 3600}
TABLE_KEYS = ("cube", "yield", "simulate", "allocate", "random", "calibrate")
CALIBRATE_KEYS = ("configurations", "noise", "robots")
RANDOM_KEYS = ("joints", "tolerance", "bits", "gear_ratio", "variation", "lower", "upper", "cost")
SIM_KEYS = ("robots", "cycles", "multidirectional")
PLAY_KINDS = ("radial_play", "axial_play")
#: ISO 9283 figures a requirement may name: positional AP, RP (m) and orientational AP_a.. RP_c (rad, §7.2)
REQUIREMENT_KEYS = ("AP", "RP", "APa", "APb", "APc", "RPa", "RPb", "RPc")
ORIENTATION_KEYS = REQUIREMENT_KEYS[2:]


def quantity(raw, where: str) -> float:
    """A number (SI) or ``"<number> <unit>"`` / ``"<number>*<unit>"`` in SI.

    Parameters
    ----------
    raw : float or str
        The value as written.
    where : str
        The field's name for an error.

    Returns
    -------
    float
        The value in SI (m or rad).

    Raises
    ------
    evotol.errors.ValidationError
        Not a number with a known unit.

    Examples
    --------
    >>> round(quantity("0.5 mm", "x"), 6), round(quantity("2*arcmin", "x") * 1e6, 1)
    (0.0005, 581.8)
    """
    if isinstance(raw, (int, float)) and not isinstance(raw, bool):
        return float(raw)
    m = re.fullmatch(r"\s*([-+0-9.eE]+)\s*\*?\s*([a-zµ]+)\s*", str(raw))
    if not m or m.group(2) not in UNITS:
        raise ValidationError(where, raw, f"a number (SI) or '<number> <unit>' with a unit of {tuple(UNITS)}")
    try:
        return float(m.group(1)) * UNITS[m.group(2)]
    except ValueError:
        raise ValidationError(where, raw, "a number before the unit") from None


@dataclass
class IsoStudy:
    """What the file asks of ISO 9283 (SI), read and checked before work.

    Parameters
    ----------
    robot : evotol.robots.mechanism.model.error_model.MechanismModel
        The mechanism (a description, serial or closed-loop).
    cube : evotol.measures.iso9283.TestCube
        The test cube.
    AP, RP : float or None
        Required figures (m), None where not required.
    yield_ : float or None
        AP at this yield; None: worst case.
    sources : list of RandomSource
        The random sources at their catalogue tolerances.
    costs, lower, upper : list
        Per random source its cost model (or None) and allocation bounds (SI).
    simulate : dict
        ``robots``, ``cycles``, ``multidirectional``.
    allocate : bool
        Allocate the random sources with the systematic ones.
    calibrate : dict or None
        ``configurations``, ``noise`` (m), ``robots`` of a simulated calibration; None: none.
    orientation : dict
        Required orientation figures ``APa`` .. ``RPc`` (rad), the ones the file names.
    ga : dict or None
        The study's GA settings when it allocates the random sources to AP/RP too
        (:func:`evotol.studyfile.iso9283_methods.iso_ga_options`).
    rules : tuple of str
        The study's ``sensitivity``, ``equal``, ``lagrange``, ``monotone`` that allocate the random sources to AP/RP
        too, each by its rule (:func:`evotol.studyfile.iso9283_methods.iso_rules_wanted`).
    monotone : dict
        The ``[methods] monotone`` settings the ISO bracket takes (``max_evaluations``, ``rel_gap``, ``batch``; its
        defaults for the others).
    front : dict or None
        The study's ``nsga2`` settings when it also runs the ISO front, cost against AP with RP held
        (:func:`evotol.studyfile.iso9283_methods.iso_front_options`).
    calibrated : dict
        Inside ``[calibration]``: the study's methods that also allocate the random sources in the calibrated
        budget, with their settings (:func:`evotol.studyfile.iso9283_calibrated.calibrated_methods`).
    """

    robot: MechanismModel
    cube: TestCube
    AP: float | None
    RP: float | None
    yield_: float | None
    sources: list
    costs: list
    lower: list
    upper: list
    simulate: dict = field(default_factory=dict)
    allocate: bool = False
    calibrate: dict | None = None
    orientation: dict = field(default_factory=dict)
    ga: dict | None = None
    rules: tuple = ()
    monotone: dict = field(default_factory=dict)
    front: dict | None = None
    calibrated: dict = field(default_factory=dict)

    @property
    def positions(self) -> np.ndarray:
        """P1..P5 (5, 3), m."""
        return iso_positions(self.cube)


def _per_joint(raw, joints, where):
    vals = raw if isinstance(raw, list) else [raw] * len(joints)
    if len(vals) != len(joints):
        raise ValidationError(where, raw, f"one value or one per joint ({len(joints)})")
    return [quantity(v, where) for v in vals]


def _random_sources(table: dict, robot) -> tuple[list, list, list, list]:
    sources, costs, lower, upper = [], [], [], []
    for kind, o in table.items():
        where = f"iso9283.random.{kind}"
        if kind not in KINDS:
            raise ValidationError("iso9283.random", kind, f"a table per kind of random source, one of {KINDS}")
        check_table_keys(o, RANDOM_KEYS, where)
        sel = o.get("joints", "all")
        act = list(robot.kin.actuated)
        # bearing play may sit on a passive joint (named by its frame); backlash and encoder need an actuator
        pool = act + ([f for f in joint_frames(robot) if f not in act] if kind in PLAY_KINDS else [])
        joints = act if sel == "all" else [j for j in pool if any(fnmatch.fnmatch(j, p) for p in sel)]
        frame_of = {v: f for f, v in joint_frames(robot).items() if v in act}      # an actuator's frame: one play
        joints = [j for i, j in enumerate(joints) if frame_of.get(j, j) not in [frame_of.get(k, k) for k in joints[:i]]]
        passive = [] if sel == "all" or kind in PLAY_KINDS else \
            [j for j in joint_frames(robot) if j not in act and any(fnmatch.fnmatch(j, p) for p in sel)]
        if passive:
            var = joint_frames(robot)[passive[0]]
            raise ValidationError(f"{where}.joints", passive[0], f"an actuated joint of {act}: {kind} needs an actuator "
                                  + (f"(name the variable {var!r} of frame {passive[0]!r})" if var in act else
                                     f"({passive[0]!r} is a passive joint; bearing play, radial_play and axial_play, may "
                                     "sit on a passive joint)"))
        if not joints:
            raise ValidationError(f"{where}.joints", sel, f"'all' or names/patterns of actuated joints {act}"
                                  + (" or of joints' frames (bearing play)" if kind in PLAY_KINDS else ""))
        if "bits" in o:
            t = [encoder_count(float(o["bits"]), float(o.get("gear_ratio", 1.0)))] * len(joints)
        elif "tolerance" in o:
            t = _per_joint(o["tolerance"], joints, f"{where}.tolerance")
        else:
            raise ValidationError(f"{where}.tolerance", None, "the catalogue figure (or bits for an encoder)")
        lo = _per_joint(o.get("lower", 0.0), joints, f"{where}.lower")
        hi = _per_joint(o.get("upper", 0.0), joints, f"{where}.upper")
        cost = evotol.cost_models.from_dict(o["cost"]) if "cost" in o else None
        for j, tj, a, b in zip(joints, t, lo, hi):
            sources.append(RandomSource(kind, j, tj, float(o.get("variation", 0.1))))
            costs.append(cost)
            lower.append(a if a > 0 else tj / 10)
            upper.append(b if b > 0 else tj * 10)
    return sources, costs, lower, upper


#: how a study file writes each part of the composed model (evotol.robots.base.PARTS)
PART_WORDS = {"callouts": "[[robot.callouts]]", "joint_space": "[poses] joints", "calibration": "[calibration]",
              "axis_limits": "requirement per axis", "clearances": "[clearances]"}


def random_part(spec: dict, robot) -> RandomPart | None:
    """The ``[iso9283.random]`` sources at their catalogue values, for a calibrated budget; None without any.

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The uncalibrated model (a described arm).

    Returns
    -------
    evotol.calibration.random_share.RandomPart or None
        The sources, their tolerances (SI) and column loadings.

    Raises
    ------
    evotol.errors.ValidationError
        A bad random-source table, or random sources on a robot that is not a described arm.
    """
    table = spec.get("iso9283", {}).get("random", {}) if isinstance(spec.get("iso9283"), dict) else {}
    if not table:
        return None
    if not isinstance(robot, MechanismModel):
        raise ValidationError("iso9283.random", type(robot).__name__, "a mechanism description (serial or closed-loop)")
    sources, costs, lower, upper = _random_sources(table, robot)
    alloc = bool(spec["iso9283"].get("allocate", False))
    if alloc and any(c is None for c in costs):
        raise ValidationError(f"iso9283.random.{sources[costs.index(None)].kind}.cost", None,
                              "a cost model to allocate the random sources")
    req = spec.get("requirement", {}).get("iso9283") or {}
    iso = None
    if alloc and req:           # ISO AP/RP allocated inside the calibrated budget (issue 44)
        check_table_keys(req, REQUIREMENT_KEYS, "requirement.iso9283")
        iso = IsoTarget(tuple(map(tuple, iso_positions(_cube(spec["iso9283"], robot)).tolist())),
                        *(quantity(req[k], f"requirement.iso9283.{k}") if k in req else None for k in ("AP", "RP")))
    return RandomPart(tuple(sources), tuple(s.tolerance for s in sources), tuple(column_loading(robot, sources)),
                      *((tuple(costs), tuple(lower), tuple(upper)) if alloc else ()), iso=iso)


def _cube(table: dict, robot) -> TestCube:
    """``[iso9283] cube``, checked, else the largest in the workspace."""
    c = table.get("cube")
    if c is None:
        return largest_cube(robot)
    check_table_keys(c, ("centre", "edge"), "iso9283.cube")
    return check_cube(robot, TestCube(tuple(quantity(v, "iso9283.cube.centre") for v in c["centre"]),
                                      quantity(c["edge"], "iso9283.cube.edge")))


def check_composable(spec: dict) -> None:
    """Refuse, from the study file alone and so before any work, the parts ISO 9283 figures do not compose with.

    Parameters
    ----------
    spec : dict
        The parsed study file.

    Raises
    ------
    evotol.errors.ValidationError
        One line naming ``iso9283`` and the other part: ``[[robot.callouts]]``, ``[clearances]``, a
        requirement per axis; with ``[calibration]``, ``[iso9283] calibrate`` (a second calibration), an
        orientation figure, an ``nsga2`` with ``allocate = true``, or random sources on ``[poses] joints``. (``[poses] joints`` composes: the ISO poses are the test cube's.)
    """
    req = spec.get("requirement", {})
    if "iso9283" not in spec and "iso9283" not in req:
        return
    table = spec.get("iso9283", {})
    if "calibration" in spec and isinstance(table, dict) and table.get("calibrate"):
        raise ValidationError("iso9283.calibrate", table["calibrate"], "no calibrate beside [calibration]: one "
                              "calibration ([calibration] is the plan the tolerances are allocated for)")
    refuse_front_beside_calibration(spec, spec.get("methods") or {})
    if "calibration" in spec and isinstance(table, dict) and table.get("random") and "joints" in (spec.get("poses") or {}):
        raise ValidationError("iso9283.random", "[poses] joints", "task poses beside [calibration]: random sources in a "
                              "calibrated budget are not yet composed with joint configurations (docs/combinations.md)")
    ori = [k for k in ORIENTATION_KEYS if k in (req.get("iso9283") or {})]
    if "calibration" in spec and ori:
        raise ValidationError(f"requirement.iso9283.{ori[0]}", req["iso9283"][ori[0]], "no orientation figure beside "
                              "[calibration]: the calibrated orientation figures are not predicted yet (AP, RP are)")
    other = [("callouts" in spec.get("robot", {}), "callouts"),
             ("clearances" in spec, "clearances"),
             (any(isinstance(req.get(c), dict) for c in ("position", "orientation")), "axis_limits")]
    for present, part in other:
        if present:
            raise ValidationError("iso9283", PART_WORDS[part], "a study without it: the ISO 9283 figures are not yet "
                                  "composed with it (docs/combinations.md)")


def read_iso9283(spec: dict, problem) -> IsoStudy | None:
    """The study's ISO 9283 request, checked before any work; None when the file asks none.

    Returns
    -------
    IsoStudy or None
        The request (SI).

    Raises
    ------
    evotol.errors.ValidationError
        A bad key or quantity; a robot that is not a described mechanism, or a planar one; a cube outside the workspace or
        the joint limits; RP required without any random source; AP below what the random sources
        leave with every systematic tolerance at its lower bound (the noise floor), or RP below the
        random sources' own at their lower bounds (when allocated) or their catalogue values -- except when
        every tolerance is given and nothing is allocated: the figures are then checked, and the block
        says whether they meet the requirement; ``allocate`` with every tolerance given and no random source.
    """
    req = spec.get("requirement", {}).get("iso9283")
    table = spec.get("iso9283")
    if req is None and table is None:
        return None
    table = table or {}
    check_table_keys(table, TABLE_KEYS, "iso9283")
    check_table_keys(req or {}, REQUIREMENT_KEYS, "requirement.iso9283")
    check_table_keys(table.get("simulate", {}), SIM_KEYS, "iso9283.simulate")
    robot = problem.model.described      # with [calibration]: the arm inside the calibrated model
    check_composable(spec)
    # [poses] joints composes: the ISO poses are the test cube's, solved on the described arm (issue 44)
    part = next((m.part for m in problem.error_model.parts() if m.part and m.part not in ("calibration", "joint_space")), None)
    if part is not None:
        raise ValidationError("iso9283", PART_WORDS[part], "a mechanism without it: the ISO 9283 figures are not yet "
                              "composed with it (docs/combinations.md)")
    if not isinstance(robot, MechanismModel):
        raise ValidationError("iso9283", type(robot).__name__, "a mechanism description (serial or closed-loop)")
    if robot.kin.mech.planar:
        raise ValidationError("iso9283", f"planar mechanism {robot.kin.mech.name}", "a spatial mechanism: the ISO 9283 "
                              "test cube is 3-D (P2-P5 on a diagonal plane across z) and the standard defines no plane "
                              "analogue (docs/iso9283.md, Closed-loop mechanisms)")
    ap = quantity(req["AP"], "requirement.iso9283.AP") if req and "AP" in req else None
    rp = quantity(req["RP"], "requirement.iso9283.RP") if req and "RP" in req else None
    orientation = {k: quantity(req[k], f"requirement.iso9283.{k}") for k in ORIENTATION_KEYS if req and k in req}
    y = table.get("yield")
    if y is not None and not 0 < y < 1:
        raise ValidationError("iso9283.yield", y, "a share in (0, 1); leave it out for the worst case")
    sources, costs, lower, upper = _random_sources(table.get("random", {}), robot)
    for k in [k for k in ("RP", "RPa", "RPb", "RPc") if req and k in req and not sources][:1]:
        raise ValidationError(f"requirement.iso9283.{k}", req[k], "at least one random source in [iso9283.random] "
                              "(RP is what changes from cycle to cycle)")
    allocate = bool(table.get("allocate", False))
    if allocate and not sources and not problem.free.any():
        raise ValidationError("iso9283.allocate", True, "a random source in [iso9283.random] or a tolerance to allocate: "
                              "every systematic tolerance is given and there is no random source")
    if allocate and any(c is None for c in costs):
        i = costs.index(None)
        raise ValidationError(f"iso9283.random.{sources[i].kind}.cost", None, "a cost model to allocate the random sources")
    cube = _cube(table, robot)
    sim = {"robots": 200, "cycles": 30, "multidirectional": any(s.kind == "backlash" for s in sources),
           **table.get("simulate", {})}
    cal = table.get("calibrate")
    if cal is not None:
        check_table_keys(cal, CALIBRATE_KEYS, "iso9283.calibrate")
        cal = {"configurations": int(cal.get("configurations", 40)), "robots": int(cal.get("robots", 100)),
               "noise": quantity(cal.get("noise", 10e-6), "iso9283.calibrate.noise")}
        if cal["configurations"] * 3 < robot.n_columns or cal["noise"] < 0 or cal["robots"] < 1:
            raise ValidationError("iso9283.calibrate", cal, f"at least {-(-robot.n_columns // 3)} configurations, "
                                  "a noise >= 0 and at least 1 robot")
    iso = IsoStudy(robot, cube, ap, rp, y, sources, costs, lower, upper, sim, allocate, cal, orientation,
                   **study_method_options(spec, problem, orientation),     # ga, the rules, nsga2 on AP/RP too
                   calibrated=calibrated_methods(spec, problem))            # or in the calibrated budget
    _check_floor(iso, problem)
    return iso


def _check_floor(iso: IsoStudy, problem) -> None:
    """AP/RP below what the fixed parts leave: a one-line error before the methods run."""
    if (iso.AP is None and iso.RP is None and not iso.orientation) or not (iso.allocate or problem.free.any()):
        return          # every tolerance given and nothing allocated: a verdict, not a refusal
    t_rand = iso.lower if iso.allocate else [s.tolerance for s in iso.sources]
    floor = predict(iso.robot, iso.positions, problem.full(problem.lower[problem.free][None])[0], iso.sources, t_rand,
                    iso.yield_, n_samples=20000)
    # calibrated: the allocation checks the calibrated AP at the random sources' lower bounds itself
    if iso.AP is not None and problem.calibration is None and iso.AP < floor["AP"].max():
        raise ValidationError("requirement.iso9283.AP", iso.AP, f"more than {floor['AP'].max():.3g} m, the AP that the "
                              "random sources (lost motion) leave with every tolerance at its lower bound (the noise floor)")
    fo = predict_orientation(iso.robot, iso.positions, problem.full(problem.lower[problem.free][None])[0], iso.sources,
                             t_rand) if iso.orientation else None
    for k, v in iso.orientation.items():
        lowest = fo[k[:2]][:, "abc".index(k[2])].max()
        if v < lowest:
            raise ValidationError(f"requirement.iso9283.{k}", v, f"more than {lowest:.3g} rad, the {k} of every tolerance at "
                                  "its lower bound and the random sources at " + ("their lower bounds" if iso.allocate else "their catalogue values"))
    if iso.RP is not None and iso.RP < floor["RP"].max():
        raise ValidationError("requirement.iso9283.RP", iso.RP, f"more than {floor['RP'].max():.3g} m, the RP of the "
                              "random sources at " + ("their lower bounds" if iso.allocate else "their catalogue values"))


#: the yield at which AP is also predicted and simulated when the requirement is a worst case
COMPARISON_YIELD = 0.9


def _q(x, y):
    est, iv = quantile_interval(x, y)
    return est, list(iv)


def iso9283_block(iso: IsoStudy, problem, results: dict, seed: int = 0) -> dict:
    """The ``iso9283`` block of the study JSON (SI, docs/iso9283.md): the cube, the poses (commanded
    positions), per pose ``AP`` and ``RP`` each with ``predicted`` and, simulated on the nonlinear
    model, ``simulated`` and its 95 % ``interval``; the random sources; and with ``allocate`` the
    allocation of systematic and random sources together.

    The systematic tolerances are the study's ``optimum`` (else its first method's) design; without
    a result, every tolerance at its lower bound.

    Parameters
    ----------
    iso : IsoStudy
        The request (:func:`read_iso9283`).
    results : dict of str to evotol.core.result.AllocationResult
        The study's results.
    seed : int
        Seed of the sampling.

    Returns
    -------
    dict
        JSON-ready (lists, floats, strings); lengths in m.
    """
    from_method = "optimum" if "optimum" in results else next(iter(results), None)
    t_sys = np.asarray(results[from_method].t if from_method else problem.full(problem.lower[problem.free][None])[0], float)
    t_rand = np.array([s.tolerance for s in iso.sources])
    info = problem.calibration          # [calibration]: the random sources sit in the calibrated budget (issue 44)
    if info is not None and info.random is not None:
        t_rand = np.array(info.random.tolerances, float)
    block = {"cube": {"centre": list(iso.cube.centre), "edge": iso.cube.edge},
             "requirement": {"AP": iso.AP, "RP": iso.RP, "yield": iso.yield_, **iso.orientation},
             "systematic_from": from_method or ("lower bounds" if problem.free.any() else "given tolerances")}
    if info is not None:        # what the random sources take of it, and the study's methods on them
        block.update(calibrated_block(iso, info, results, seed))
    if iso.allocate and info is None:
        al = allocate_iso9283(*allocator_args(iso, problem), x0=np.concatenate([t_sys, t_rand]), seed=seed,
                              orientation=iso.orientation)
        t_sys, t_rand = al["systematic"], al["random"]
        block["systematic_from"] = "iso9283 allocation" if problem.free.any() else "given tolerances (random sources allocated)"
        block["allocation"] = {
            "cost": al["cost"], "feasible": al["feasible"], "active": al["active"], "message": al["message"],
            "systematic": dict(zip(iso.robot.source_names, t_sys.tolist())),
            "RP_sampled": al["RP"].tolist(), "RP_fresh_draws": al["RP_fresh"].tolist(),
            "RP_convex_bound": al["RP_convex_bound"].tolist(), "AP_bound": al["AP_bound"].tolist(),
            **({"orientation": al["orientation"]} if "orientation" in al else {}),
            "proven": "AP: the worst case over the tolerance box is convex in the tolerances; its proven bound "
                      "(grid / cos δ) meets the requirement. RP: sampled on fixed draws (not convex in general), "
                      "re-estimated on fresh draws; E l + 3 sqrt(E l²) is a convex upper bound."
                      + (" Orientation (APa..RPc): exact first-order worst case and 3 sigma, both convex: certified."
                         if iso.orientation else "")}
        block.update(method_allocations(iso, problem, al, seed))     # the study's ga, rules, nsga2 on it too
        block["methods"] = methods_scope(results, block)              # and which methods did not allocate to it
    block["random_sources"] = [{"name": s.name, "kind": s.kind, "joint": s.joint, "unit": s.unit, "tolerance": float(t),
                                "variation": s.variation if s.kind == "backlash" else None,
                                "cost": None if c is None else float(c.cost(t))}
                               for s, t, c in zip(iso.sources, t_rand, iso.costs)]
    P = iso.positions
    pred = predict(iso.robot, P, t_sys, iso.sources, t_rand, iso.yield_, seed=seed)
    # the worst case beside a quantile that a sample of robots can check (predicted and simulated alike)
    q_check = COMPARISON_YIELD if iso.yield_ is None else iso.yield_
    pred_q = pred if iso.yield_ is not None else predict(iso.robot, P, t_sys, iso.sources, t_rand, q_check,
                                                         n_samples=50000, seed=seed)
    sim_opts = iso.simulate
    user_req = problem.requirement if problem.calibration is None else problem.calibration.requirement
    orient = None if user_req.orientation is None and not iso.orientation else \
        predict_orientation(iso.robot, P, t_sys, iso.sources, t_rand)
    approaches = ("-z", "+x", "+y") if sim_opts["multidirectional"] else ("-z",)
    sim = simulate(iso.robot, P, t_sys, iso.sources, t_rand, n_robots=int(sim_opts["robots"]),
                   n_cycles=int(sim_opts["cycles"]), approaches=approaches, seed=seed)
    poses = []
    for i, p in enumerate(P):
        ap_est, ap_int = quantile_interval(sim["AP"][:, i], 1.0 if iso.yield_ is None else iso.yield_)
        rp = sim["RP"][:, i]
        entry = {"name": f"P{i + 1}", "position": p.tolist(),
                 "AP": {"predicted": float(pred["AP"][i]), "bound": float(pred["AP_bound"][i]),
                        "simulated": ap_est, "interval": list(ap_int)},
                 "AP_quantile": {"yield": q_check, "predicted": float(pred_q["AP"][i]),
                                 **dict(zip(("simulated", "interval"), _q(sim["AP"][:, i], q_check)))},
                 "RP": {"predicted": float(pred["RP"][i]), "gaussian_shortcut": float(pred["RP_gaussian"][i]),
                        "simulated": float(rp.mean()), "interval": np.percentile(rp, [2.5, 97.5]).tolist()}}
        if sim["vAP"] is not None:
            entry["vAP"] = {"simulated": float(sim["vAP"][:, i].mean()), "max": float(sim["vAP"][:, i].max())}
        if orient is not None:      # ISO 9283 §7.2: AP_a, AP_b, AP_c and RP_a, RP_b, RP_c (rad)
            ap_abc, rp_abc = np.abs(sim["AP_abc"][:, i]), sim["RP_abc"][:, i]              # (robots, 3)
            entry["AP_orientation"] = {a: {"predicted": float(orient["AP"][i, k]), "simulated": float(ap_abc[:, k].max()),
                                           "interval": list(quantile_interval(ap_abc[:, k], 1.0)[1])}
                                       for k, a in enumerate("abc")}
            entry["RP_orientation"] = {a: {"predicted": float(orient["RP"][i, k]), "simulated": float(rp_abc[:, k].mean()),
                                           "interval": np.percentile(rp_abc[:, k], [2.5, 97.5]).tolist()}
                                       for k, a in enumerate("abc")}
        poses.append(entry)
    block["poses"] = poses
    if info is not None:        # the same robots after the study's calibration: AP falls, RP stays (first order)
        pc = predict_calibrated(problem, P, t_sys, iso.sources, t_rand)
        for i, entry in enumerate(poses):
            entry["calibrated"] = {"AP": {"predicted": float(pc["AP"][i]), "systematic": float(pc["AP_systematic"][i]),
                                          "systematic_bound": float(pc["AP_bound"][i]),
                                          "noise_quantile": float(pc["noise_quantile"][i]), "level": pc["level"]},
                                   "RP": {"predicted": entry["RP"]["predicted"]}}
    if iso.calibrate:
        c = simulate_calibrated(iso.robot, P, t_sys, iso.sources, t_rand, n_robots=iso.calibrate["robots"],
                                n_cycles=int(sim_opts["cycles"]), n_configurations=iso.calibrate["configurations"],
                                noise=iso.calibrate["noise"], seed=seed)
        block["calibrated"] = {
            **iso.calibrate, "identified_rank": c["rank"], "n_columns": c["n_columns"],
            "poses": [{"name": f"P{i + 1}", **{f"{k}_{s}": float(f(c[k][:, i])) for k in ("AP_before", "AP_after", "RP_before", "RP_after")
                                               for s, f in (("mean", np.mean), ("max", np.max))}} for i in range(len(P))],
            "meaning": "the same simulated robots before and after a simulated laser-tracker calibration (position at the "
                       "configurations, least squares on the first-order map, joint compensation at the ISO poses), "
                       "each run through the ISO test; lengths in m"}
    shares = source_shares(iso.robot, P, t_sys, iso.sources, t_rand)
    block["what_each_source_buys"] = {
        "AP": {k: v for k, v in sorted(shares["AP"].items(), key=lambda kv: -kv[1]) if v >= 0.01},
        "RP": {k: v for k, v in sorted(shares["RP"].items(), key=lambda kv: -kv[1]) if v >= 0.01},
        "AP_pose": f"P{shares['AP_pose'] + 1}", "RP_pose": f"P{shares['RP_pose'] + 1}",
        "meaning": "share of the worst-case AP (first order, at its worst pose and direction) and of the RP variance "
                   "E|e|^2 (at its largest pose) each source takes; sources under 1 % left out"}
    ap_top = pred["AP_bound"].max() if info is None else max(e["calibrated"]["AP"]["predicted"] for e in poses)
    block["meets"] = {"AP": None if iso.AP is None else bool(ap_top <= iso.AP),
                      "RP": None if iso.RP is None else bool(pred["RP"].max() <= iso.RP)}
    block["verdict"] = verdicts(iso, pred, sim, None if info is None else ap_top, orient)
    block["simulation"] = {"robots": int(sim_opts["robots"]), "cycles": int(sim_opts["cycles"]), "approaches": list(approaches),
                           "model": "nonlinear (pose_error_at_joints)"}
    block["notes"] = [
        "AP predicted: first-order worst case over the tolerance box (attained; 'bound' proven) or the yield quantile "
        "(sampled); simulated: the largest (or yield quantile) over the simulated robots' ISO tests, its interval the "
        "95 % order-statistic interval (no upper end for the largest).",
        "RP predicted: E l + 3 std l of the linearised random sources, sampled (the Gaussian shortcut beside it for "
        "comparison only); simulated: the mean over the simulated 30-cycle tests, its interval the 2.5-97.5 % range "
        "of one test's RP.",
        "Lost motion is taken up against the approach motion (tool moving down): a fixed offset (AP, vAP), its "
        "cycle-to-cycle variation feeds RP."] + ([
        "Orientation (ISO 9283 7.2): per angle a, b, c (rotations about the base x, y, z: the components of the "
        "orientation error's rotation vector, first order) AP_a = |mean - commanded| (predicted: exact worst case over "
        "the tolerance box; simulated: the largest over the robots) and RP_a = 3 S_a (predicted: 3 sigma of the "
        "linearised random sources; simulated: mean over the tests), rad."] if orient is not None else [])
    return block

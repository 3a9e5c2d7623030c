"""Study ``mechanisms``: every shipped mechanism description checked against finite differences and
against the hand-written model of the same robot (issue 12).

For each ``robots/mechanisms/*.toml``: the number of generated sources, the largest relative
mismatch of the description-driven sensitivities against central finite differences of the
nonlinear loop closure (``fd_rel_error``), the largest relative difference from the hand-written
model where there is one (``builtin_rel_diff``: the 5-bar's sensitivities vs
``evotol.robots.fivebar.FiveBarGeometric`` (Deng 2012 eq. IV.43) at 50 poses and its certified clearance
maxima vs ``FiveBar().clearance_mechanism()``; the IRSBot-2's inverse geometry and certified
clearance maxima vs ``evotol.robots.irsbot2``; the 3-UCR's 21 columns vs ``evotol.robots.ucr3``; the Delta's
position rows for all 47 parameters and its nonlinear closure vs ``evotol.robots.delta``), and the wall time. For the 5-bar, ``p_max_mm`` and
``r_max_rad`` at pose (0, 70) mm with the thesis's clearances (all b 0.1 mm, beta_xy 0.01 rad,
passive beta_z 0.2 rad, actuated 0), each with its certified upper bound, and the time of the
certified clearance map from the description relative to the hand-written model.

Every mechanism also reports ``rank``: the rank of its sources' sensitivities stacked over the
workspace poses (columns at unit norm, :mod:`evotol.robots.mechanism.model.identifiability`), with its blind and
duplicated sources. The URDF arms (UR5, Panda) add ``pinocchio_rank`` (Pinocchio's placement
regressor of the chain over the same poses) and, in ``configurations``, the same ranks over random
configurations inside the joint limits, with and without the tip's placement, and the forward
kinematics and FD agreement there (issue 23 item 7).
"""
from __future__ import annotations

import time

import numpy as np

from evotol.reporting.html import Report
from evotol.studies import Study, StudyResult
from evotol.units import MM



def _rel(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


def _fivebar(model, cfg) -> dict:
    from evotol.robots.clearance import max_pose_error
    from evotol.robots.fivebar import FiveBar, FiveBarGeometric

    poses = model.workspace.latin_hypercube(50, seed=cfg["seed"])
    sens = _rel(model.sensitivity(poses), FiveBarGeometric().sensitivity(poses))
    pose = np.array([[0.0, 70 * MM]])
    a = max_pose_error(model.clearance_mechanism(), pose)
    b = max_pose_error(FiveBar().clearance_mechanism(), pose)
    # certified map on a grid: description vs hand-written (same engine, joint values from Newton vs closed form)
    n = cfg["map_grid"]
    x, y = np.linspace(-20 * MM, 20 * MM, n), np.linspace(55 * MM, 70 * MM, n)
    grid = np.stack([g.ravel() for g in np.meshgrid(x, y)], 1)
    t0 = time.perf_counter()
    max_pose_error(model.clearance_mechanism(), grid)
    t_desc = time.perf_counter() - t0
    t0 = time.perf_counter()
    max_pose_error(FiveBar().clearance_mechanism(), grid)
    t_hand = time.perf_counter() - t0
    return {"builtin_rel_diff": max(sens, _rel(a.p_max, b.p_max), _rel(a.r_max, b.r_max)),
            "builtin": {"sensitivity_rel_diff_50_poses": sens, "p_max_rel_diff": _rel(a.p_max, b.p_max),
                        "r_max_rel_diff": _rel(a.r_max, b.r_max), "compared_with": "evotol.robots.fivebar (eq. IV.43, Ch. IV clearances)"},
            "p_max_mm": float(a.p_max[0] / MM), "p_upper_mm": float(a.p_upper[0] / MM),
            "r_max_rad": float(a.r_max[0]), "r_upper_rad": float(a.r_upper[0]),
            "clearance_map": {"poses": len(grid), "seconds_description": t_desc, "seconds_hand_written": t_hand,
                              "ratio": t_desc / t_hand}}


def _irsbot2(model, cfg) -> dict:
    from evotol.robots.clearance import max_pose_error
    from evotol.robots.irsbot2 import IRSBot2

    r = IRSBot2()
    poses = model.workspace.latin_hypercube(50, seed=cfg["seed"])
    q, h = model.joint_values(poses), r.dh_values(poses)
    wrap = lambda a: (a + np.pi) % (2 * np.pi) - np.pi
    ig = max(float(np.abs(wrap(q[k] - h[k])).max()) for k in q if k in h)
    pose = np.array([[0.0, -50 * MM]])
    a = max_pose_error(model.clearance_mechanism(), pose)
    b = max_pose_error(r.clearance_mechanism(), pose)
    return {"builtin_rel_diff": max(_rel(a.p_max, b.p_max), _rel(a.r_max, b.r_max)),
            "builtin": {"joint_angle_abs_diff_rad_50_poses": ig, "p_max_rel_diff": _rel(a.p_max, b.p_max),
                        "r_max_rel_diff": _rel(a.r_max, b.r_max),
                        "compared_with": "evotol.robots.irsbot2 (eqs. II.5-II.35, Tab. VI.3 clearances) at (0, -50) mm"}}


def _ucr3(model, cfg) -> dict:
    from evotol.robots.ucr3 import UCR3, columns_from_description

    r = UCR3()
    poses = r.workspace.latin_hypercube(50, seed=cfg["seed"])
    S, H = model.sensitivity(poses), r.sensitivity(poses)
    D = columns_from_description(S, model.source_names)
    rel = _rel(D, H)
    return {"builtin_rel_diff": rel,
            "builtin": {"sensitivity_rel_diff_50_poses_21_columns": rel,
                        "compared_with": "evotol.robots.ucr3 (verified eq. 10; clearance disks = pairs of DH entries)"}}


def delta_columns(model, robot) -> list[int]:
    """Column of ``evotol.robots.delta`` for every source of ``delta.toml``: the names are equal except the
    joint offsets (``dq2_i``/``dq5_i`` are parameters there, q3, q4, q6, q7 the DH entries ``<j>_i.theta``).

    Parameters
    ----------
    model : evotol.robots.mechanism.model.error_model.MechanismModel
        The model of ``robots/mechanisms/delta.toml``.
    robot : evotol.robots.delta.DeltaRobot
        The hand-written Delta model.

    Returns
    -------
    list of int
        For each of ``model``'s sources, in order, the index of the same parameter among
        ``robot.source_names``.

    Raises
    ------
    ValueError
        If a source of ``model`` has no counterpart in ``robot`` (from ``list.index``).
    """
    hn = list(robot.source_names)

    def hand(n):
        if n.startswith("dq"):
            return n[1:]
        if n.endswith(".theta"):
            j, i = n.split(".")[0].split("_")
            return f"q{j}_{i}"
        return n

    return [hn.index(hand(n)) for n in model.source_names]


def _delta(model, cfg) -> dict:
    from evotol.robots.delta import DeltaRobot

    r = DeltaRobot()
    poses = r.workspace.latin_hypercube(50, seed=cfg["seed"])
    S, H = model.sensitivity(poses), r.sensitivity(poses)
    cols = delta_columns(model, r)
    rel = _rel(S[:, :3], H[:, :3, cols])
    E = np.random.default_rng(cfg["seed"]).uniform(-1e-3, 1e-3, (10, 4, len(cols)))
    Eh = np.zeros(E.shape[:2] + (len(r.source_names),))
    Eh[..., cols] = E
    nl = _rel(model.pose_error(poses[:10], E)[..., :3], r.pose_error(poses[:10], Eh)[..., :3])
    return {"builtin_rel_diff": max(rel, nl),
            "builtin": {"position_rows_rel_diff_50_poses": rel, "n_compared": len(cols),
                        "nonlinear_pose_error_rel_diff_10_poses_errors_1e-3": nl,
                        "compared_with": "evotol.robots.delta (Brahmia 2023, eq. 12's 47 parameters; legs closed at the rods' midpoint)"}}


def _urdf_ranks(path, cfg) -> dict:
    """Ranks of the default sources and of Pinocchio's placement regressor over random configurations
    inside the joint limits (the task box holds the tool orientation fixed, which lowers both), with
    and without the tip's placement; FK and FD agreement there (evotol.robots.mechanism.urdf.check)."""
    from evotol.robots.mechanism.model.error_model import MechanismModel
    from evotol.robots.mechanism.urdf.check import check_urdf_chain

    r = check_urdf_chain(MechanismModel(path), n=cfg["n_configurations"], seed=cfg["seed"])
    return {"n_configurations": cfg["n_configurations"], **r}


BUILTIN = {"5-bar": _fivebar, "IRSBot-2": _irsbot2, "3-UCR": _ucr3, "Delta": _delta}


def compute(cfg: dict) -> StudyResult:
    """Check every shipped description and compare it with its hand-written model.

    Parameters
    ----------
    cfg : dict
        Study config: ``seed``, ``n_poses`` (poses of the FD and rank checks), ``map_grid``
        (points per axis of the 5-bar's timed clearance map) and ``n_configurations`` (random
        configurations of the URDF arms).

    Returns
    -------
    StudyResult
        ``summary`` only: ``seed`` and ``mechanisms``, per mechanism name its file, sources,
        ``fd_rel_error`` and ``builtin_rel_diff`` (relative, dimensionless), closure residual,
        ranks, blind and duplicated sources and ``seconds``; plus the built-in comparison blocks
        (5-bar: ``p_max_mm`` in mm, ``r_max_rad`` in rad) and the URDF ``configurations``.
    """
    from evotol.robots.mechanism.checks.description import check_mechanism
    from evotol.robots.mechanism.model.error_model import SHIPPED, MechanismModel

    rows = {}
    for path in sorted(SHIPPED.glob("*.toml")):
        t0 = time.perf_counter()
        chk = check_mechanism(path, cfg["n_poses"])
        ident = chk["identifiability"]
        entry = {"file": path.name, "n_sources": chk["n_sources"], "sources": [s["name"] for s in chk["sources"]],
                 "fd_rel_error": chk["fd_rel_error"], "closure_residual": chk["closure_residual"], "builtin_rel_diff": None,
                 "rank": ident["rank"], "pinocchio_rank": ident.get("pinocchio_rank"), "duplicated": ident["duplicated"],
                 "blind": ident["blind"], "redundancy": None if chk.get("redundancy") is None else chk["redundancy"]["text"]}
        if chk.get("urdf"):                     # a URDF arm: also over random configurations (issue 23 item 7)
            entry["configurations"] = _urdf_ranks(path, cfg)
        if chk["name"] in BUILTIN:
            entry.update(BUILTIN[chk["name"]](MechanismModel(path), cfg))
        entry["seconds"] = time.perf_counter() - t0
        rows[chk["name"]] = entry
    return StudyResult({"mechanisms": rows, "seed": cfg["seed"]})


def render(result: StudyResult) -> Report:
    """The table of mechanisms, the URDF arms, the 5-bar's certified errors and the comparisons.

    Returns
    -------
    evotol.reporting.html.Report
        The HTML report.
    """
    m = result.summary["mechanisms"]
    rep = Report("Mechanisms from description files",
                 "every robots/mechanisms/*.toml: sources generated, FD agreement, equality with the hand-written model")
    rows = [[name, e["file"], e["n_sources"], e.get("rank", "-"), "-" if e.get("pinocchio_rank") is None else e["pinocchio_rank"],
             e["fd_rel_error"], e["closure_residual"], "-" if e["builtin_rel_diff"] is None else e["builtin_rel_diff"], e["seconds"]]
            for name, e in m.items()]
    rep.table(rows, ["mechanism", "file", "sources", "rank (workspace)", "Pinocchio rank", "FD rel. error", "closure residual",
                     "vs hand-written (rel.)", "s"])
    for name, e in m.items():
        if e.get("redundancy"):
            rep.text(e["redundancy"])
    arms = {name: e["configurations"] for name, e in m.items() if "configurations" in e}
    if arms:
        rep.heading("URDF arms over random configurations inside the joint limits")
        rep.table([[name, c["n_configurations"], c["n_sources"], c["rank"], c["pinocchio_rank"], c["combined_rank"],
                    c["rank_with_tip"], c["pinocchio_rank_with_tip"], c["fk_vs_pinocchio"], c["fd_rel_error"]] for name, c in arms.items()],
                  ["arm", "configurations", "sources", "rank", "Pinocchio rank", "both", "rank + tip", "Pinocchio + tip",
                   "FK vs Pinocchio (m)", "FD rel. error"], digits=3)
    if "5-bar" in m:
        e = m["5-bar"]
        rep.heading("5-bar at (0, 70) mm, the thesis's clearances (certified)")
        rep.table([["p_max (mm)", e["p_max_mm"], e["p_upper_mm"]], ["r_max (rad)", e["r_max_rad"], e["r_upper_rad"]]],
                  ["", "attained", "certified bound"], digits=6)
        c = e["clearance_map"]
        rep.text(f"Certified clearance map on {c['poses']} poses: {c['seconds_description']:.2f} s from the description, "
                 f"{c['seconds_hand_written']:.2f} s from robots/fivebar/ (ratio {c['ratio']:.2f}).")
    for name, e in m.items():
        if "builtin" in e:
            rep.heading(f"{name}: compared with the hand-written model")
            rep.table([[k, v] for k, v in e["builtin"].items()], ["quantity", "value"], digits=3)
    return rep


STUDY = Study(name="mechanisms", title="Mechanisms from description files: FD agreement and equality with the hand-written models",
              compute=compute, render=render, config={"seed": 0, "n_poses": 20, "map_grid": 11, "n_configurations": 200},
              quick={"n_poses": 8, "map_grid": 5, "n_configurations": 40}, seed_paper="Deng 2012 Ch. II, IV, VI (5-bar, IRSBot-2)")

"""IRSBot-2 dimension synthesis (Deng 2012, Sec. VII.2, Tab. VII.1, Figs. VII.9-VII.16).

Design variables l1, l2, a1, a2, p on the three levels of Tab. VII.1 (3^5 = 243 designs), the
other parameters fixed at Tab. VI.4 (b = d = 50 mm, alpha_d = pi/6, beta = pi/4, e = 0). Each
design gets three objectives:

* ``area_mm2`` -- the area of the largest axis-aligned rectangle (the thesis's "cuboid-shaped
  sub-workspace") of the x-z plane in which the robot is assembled in its working mode and free
  of Type 1 and Type 2 singularities, found by workspace discretisation (Sec. VII.2.1, [BPC10]);
* ``p_max_mm`` and ``r_max_deg`` -- the maximum positional and rotational error of the platform
  due to the clearances of the distal modules and the parallelograms (114-variable model of
  Ch. V-VI), the largest over the rectangle's right-down corner, centre and left-up corner
  (Fig. VII.10), computed by the certified engine of :mod:`evotol.robots.clearance`.

Geometry (the equivalent planar mechanism, Sec. II.2.1, working mode elbows out, assembly mode
distal links forming a V) and the sub-workspace search are :meth:`evotol.robots.irsbot2.IRSBot2.planar_legs`
and :func:`evotol.robots.irsbot2.singularity_free_rectangle`: a grid point below the base is kept when
both singularity sines exceed ``sin(margin)`` in magnitude (default margin 2 deg: the
sub-workspace stays off the singular loci, where the clearance errors grow without bound).
"""
from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from evotol import design as doe
from evotol.design import Factor, Objective
from evotol._runtime.executor import scheduler_of, worker_count
from evotol.design.filtering import DesignStudy, Preset
from evotol.core.pareto import non_dominated
from evotol.studies import Study, StudyResult
from evotol.studies._design_report import parcoords_counts, parcoords_section
from evotol.robots.irsbot2 import IRSBot2, singularity_free_rectangle
from evotol.units import MM


#: Tab. VI.4 (fixed parameters of the dimension synthesis), SI units
TAB_VI_4 = {"b": 50 * MM, "d": 50 * MM, "alpha_0": 0.0, "alpha_d": math.pi / 6, "beta": math.pi / 4, "e": 0.0}
#: Tab. VII.1: three levels of l1, l2, a1, a2, p (mm)
TAB_VII_1 = {"l1": (50.0, 100.0, 200.0), "l2": (50.0, 100.0, 200.0), "a1": (10.0, 30.0, 50.0),
             "a2": (5.0, 15.0, 30.0), "p": (15.0, 25.0, 40.0)}
#: Tab. VII.2: the thesis's two good designs (mm)
TAB_VII_2 = ((200.0, 100.0, 50.0, 15.0, 15.0), (200.0, 100.0, 50.0, 5.0, 15.0))


def design_robot(l1: float, l2: float, a1: float, a2: float, p: float) -> IRSBot2:
    """The IRSBot-2 of a design (m): Tab. VI.4's fixed parameters with the five design variables.

    Parameters
    ----------
    l1 : float
        Proximal crank length ``A_iB_i``, m.
    l2 : float
        Length of each distal link ``E_jiF_ji``, m.
    a1 : float
        Length ``E_iE_ji`` (elbow to a distal link's upper joint), m.
    a2 : float
        Length of the platform-side counterpart (``H_hi`` to ``F_ji``), m.
    p : float
        Horizontal offset ``H_hi P`` of the platform point, m.

    Returns
    -------
    evotol.robots.irsbot2.IRSBot2
        The robot with the fixed parameters of Tab. VI.4.

    Raises
    ------
    ValidationError
        If the dimensions are invalid (see :class:`evotol.robots.irsbot2.IRSBot2`), e.g. ``l2`` too
        short for the equivalent link to exist.
    """
    return IRSBot2.thesis("VI.4", l1=l1, l2=l2, a1=a1, a2=a2, p=p)


# --------------------------------------------------------------------------- study
NAME = "deng2012-dimsynth"
DESIGN_VARS = ("l1", "l2", "a1", "a2", "p")
#: Sec. VII.2.2: clearances of every joint (distal modules and parallelograms)
CLEARANCE = {"b_xy": 0.1 * MM, "b_z": 0.1 * MM, "beta_xy": 0.01}
BETA_Z_ACTIVE, BETA_Z_PASSIVE = 0.001, 0.2
#: Sec. VII.2.2 text: ranges over the thesis's 243 designs
THESIS_RANGES = {"p_max_mm": (7.3, 30.6), "r_max_deg": (5.8, 24.3)}


def factors(continuous: bool = False) -> list[Factor]:
    """l1, l2, a1, a2, p (mm) on the levels of Tab. VII.1 (or their continuous span).

    Parameters
    ----------
    continuous : bool, optional
        Continuous factors on [min, max] of the levels (for NSGA-II) instead of the three levels.

    Returns
    -------
    list of evotol.design.Factor
        Factors ``l1_mm``, ``l2_mm``, ``a1_mm``, ``a2_mm``, ``p_mm`` (values in mm, ``si_scale``
        1e-3).
    """
    out = []
    for k, lv in TAB_VII_1.items():
        if continuous:
            out.append(Factor(f"{k}_mm", low=min(lv), high=max(lv), si_scale=MM, label=f"{k} (mm)", group="dimension"))
        else:
            out.append(Factor(f"{k}_mm", lv, si_scale=MM, label=f"{k} (mm)", group="dimension"))
    return out


def presets() -> list[Preset]:
    """The filters of Figs. VII.12-VII.16.

    Returns
    -------
    list of evotol.design.filtering.Preset
        Five filters on ``area_mm2`` (mm²), ``p_max_mm`` (mm) and ``r_max_deg`` (deg).
    """
    return [Preset("f_a ≥ 4e4 mm²", {"area_mm2": (4e4, None)}, "Fig. VII.12"),
            Preset("f_a ≤ 3e3 mm²", {"area_mm2": (None, 3e3)}, "Fig. VII.13"),
            Preset("f_p ≤ 10 mm", {"p_max_mm": (None, 10.0)}, "Fig. VII.14"),
            Preset("f_r ≤ 8°", {"r_max_deg": (None, 8.0)}, "Fig. VII.15"),
            Preset("f_a ≥ 3e4, f_p ≤ 15, f_r ≤ 8", {"area_mm2": (3e4, None), "p_max_mm": (None, 15.0),
                                                    "r_max_deg": (None, 8.0)}, "Fig. VII.16")]


def clearance_bounds():
    """Sec. VII.2.2: Δb_xy = Δb_z = 0.1 mm, Δβ_xy = 0.01 rad on every joint; Δβ_z "very small" on the
    actuated joints (0.001 rad, Tab. VI.7) and "relatively higher" on the passive ones (0.2 rad,
    Tab. VI.3). Returns (distal, actuated, passive) ClearanceBounds.

    Returns
    -------
    distal, actuated, passive : evotol.robots.clearance.ClearanceBounds
        Bounds (Δβ_xy, Δβ_z in rad; Δb_xy, Δb_z in m) of the distal-module joints, the actuated
        joints (Δβ_z = 0.001 rad) and the passive parallelogram joints (Δβ_z = 0.2 rad).
    """
    from evotol.robots.clearance import ClearanceBounds

    b, bz, bxy = CLEARANCE["b_xy"], CLEARANCE["b_z"], CLEARANCE["beta_xy"]
    return (ClearanceBounds(bxy, BETA_Z_PASSIVE, b, bz), ClearanceBounds(bxy, BETA_Z_ACTIVE, b, bz),
            ClearanceBounds(bxy, BETA_Z_PASSIVE, b, bz))


def engine_mechanism(robot: IRSBot2):
    """A design's IRSBot-2 with the clearances of Sec. VII.2.2 in the distal modules and the
    parallelograms (Ch. V-VI, 114 variables).

    Parameters
    ----------
    robot : evotol.robots.irsbot2.IRSBot2
        The design (e.g. from :func:`design_robot`).

    Returns
    -------
    ClearanceMechanism
        The robot's clearance mechanism with the bounds of :func:`clearance_bounds`.
    """
    distal, actuated, passive = clearance_bounds()
    return robot.clearance_mechanism(parallelograms=True, distal=distal, actuated=actuated, passive=passive)


def engine_pose_errors(robot: IRSBot2, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Certified maximum positional (m) and rotational (rad) error at ``points`` (k, 2) [x, z] (m).

    Parameters
    ----------
    robot : evotol.robots.irsbot2.IRSBot2
        The design.
    points : (k, 2) ndarray
        Platform positions [x, z], m.

    Returns
    -------
    p_max : (k,) ndarray
        Maximum positional error, m.
    r_max : (k,) ndarray
        Maximum rotational error, rad.
    """
    from evotol.robots.clearance import max_pose_error

    res = max_pose_error(engine_mechanism(robot), points)
    return np.asarray(res.p_max), np.asarray(res.r_max)


def engine_pose_errors_batch(robots: list, points: list) -> list[tuple[np.ndarray, np.ndarray]]:
    """:func:`engine_pose_errors` for many designs in one engine call
    (:func:`evotol.robots.clearance.stacked.max_pose_error_stacked`: the designs share joints and chains).

    Parameters
    ----------
    robots : list of evotol.robots.irsbot2.IRSBot2
        The designs.
    points : list of (k_i, 2) array_like
        ``points[i]``: platform positions [x, z] of ``robots[i]``, m.

    Returns
    -------
    list of (ndarray, ndarray)
        Per design, ``(p_max (k_i,) in m, r_max (k_i,) in rad)``.
    """
    from evotol.robots.clearance.stacked import max_pose_error_stacked

    return max_pose_error_stacked([engine_mechanism(r) for r in robots], points)


@dataclass(frozen=True)
class IRSBot2DesignEvaluator:
    """Objectives of IRSBot-2 designs (rows with ``l1_mm, l2_mm, a1_mm, a2_mm, p_mm``).

    n_grid: points per side of the workspace discretisation; margin_deg: distance kept from the
    singular loci (module doc); pose_errors: ``(IRSBot2, points) -> (p (m), r (rad))``,
    the certified engine by default (tests plug in closed forms).
    Returns ``area_mm2, p_max_mm, r_max_deg``, the rectangle ``x0_mm, x1_mm, z0_mm, z1_mm``, the
    errors at the three points of Fig. VII.10 (``p_rd_mm, p_c_mm, p_lu_mm``, ``r_rd_deg`` ...).
    A design without a singularity-free rectangle (zero area) gets NaN errors and
    ``feasible = False``.

    Parameters
    ----------
    n_grid : int, optional
        Points per side of the workspace discretisation (default 161).
    margin_deg : float, optional
        Distance kept from the singular loci, deg (default 2).
    pose_errors : callable or None, optional
        ``pose_errors(robot, points) -> (p, r)`` with ``points`` (3, 2) m, ``p`` in m and ``r``
        in rad; ``None`` (default) uses the certified engine in one stacked call
        (:func:`engine_pose_errors_batch`).
    """

    n_grid: int = 161
    margin_deg: float = 2.0
    pose_errors: Callable | None = None

    def __call__(self, X: pd.DataFrame) -> pd.DataFrame:
        rows, robots, points = [], [], []
        for rec in X[[f"{k}_mm" for k in DESIGN_VARS]].to_numpy(float):
            robot = design_robot(*(rec * MM))
            w = singularity_free_rectangle(robot, n=self.n_grid, margin_deg=self.margin_deg)
            rows.append({"area_mm2": w.area / MM ** 2, "x0_mm": w.x[0] / MM, "x1_mm": w.x[1] / MM,
                         "z0_mm": w.z[0] / MM, "z1_mm": w.z[1] / MM})
            if w.area > 0:
                robots.append((len(rows) - 1, robot))
                points.append(w.points)
        if self.pose_errors is None:
            errs = engine_pose_errors_batch([r for _, r in robots], points)
        else:
            errs = [self.pose_errors(r, pt) for (_, r), pt in zip(robots, points)]
        nan = dict(p_max_mm=np.nan, r_max_deg=np.nan, p_rd_mm=np.nan, p_c_mm=np.nan, p_lu_mm=np.nan,
                   r_rd_deg=np.nan, r_c_deg=np.nan, r_lu_deg=np.nan, feasible=False)
        for row in rows:
            row.update(nan)
        for (i, _), (p, r) in zip(robots, errs):
            p, r = np.asarray(p, float) / MM, np.degrees(np.asarray(r, float))
            rows[i].update(p_max_mm=float(p.max()), r_max_deg=float(r.max()), p_rd_mm=p[0], p_c_mm=p[1],
                           p_lu_mm=p[2], r_rd_deg=r[0], r_c_deg=r[1], r_lu_deg=r[2], feasible=True)
        return pd.DataFrame(rows)


OBJECTIVES = ("area_mm2", "p_max_mm", "r_max_deg")


def _kept_levels(r, name):
    return r.ranges[name].get("levels") or []


def _findings(study: DesignStudy, pres: dict) -> tuple[list[str], dict]:
    """The thesis's statements on Figs. VII.12-VII.16, re-derived from our entries."""
    lines, facts = [], {}
    df = study.entries[study.entries["feasible"]]
    me_a = study.main_effects("area_mm2", log=False, among=df).set_index("input")
    me_p = study.main_effects("p_max_mm", among=df).set_index("input")
    me_r = study.main_effects("r_max_deg", among=df).set_index("input")
    facts["main_effects"] = {"area_mm2": me_a["effect"].to_dict(), "p_max_decades": me_p["effect"].to_dict(),
                             "r_max_decades": me_r["effect"].to_dict()}
    fmt = lambda lv: "{" + ", ".join(f"{v:g}" for v in lv) + "}"
    for name, var, thesis in (("f_a ≥ 4e4 mm²", ("l1_mm", "l2_mm"), "l1 = l2 = 200 mm"),
                              ("f_a ≤ 3e3 mm²", ("l1_mm",), "l1 = 50 mm"),
                              ("f_p ≤ 10 mm", ("l2_mm",), "l2 = 50 mm"),
                              ("f_r ≤ 8°", ("l1_mm", "l2_mm", "a1_mm", "a2_mm", "p_mm"), "no single parameter")):
        r = pres[name]
        kept = {v: _kept_levels(r, v) for v in var}
        facts[name] = {"count": r.count, "kept_levels": kept}
        if r.count == 0:
            lines.append(f"{name} ({pres[name].query if hasattr(pres[name], 'query') else ''}): no design is kept "
                         f"(thesis: {thesis}).")
            continue
        lines.append(f"{name}: {r.count} designs kept; " + "; ".join(f"{v.split('_')[0]} ∈ {fmt(kept[v])}" for v in var)
                     + f" (thesis: {thesis}).")
    top_a = me_a.index[0]
    top_p = me_p.index[0]
    top_r = me_r.index[0]
    facts.update(area_driver=top_a, p_driver=top_p, r_driver=top_r)
    lines.append(f"Largest main effects: on the area {top_a.split('_')[0]} ({me_a.loc[top_a, 'effect']:.3g} mm²), "
                 f"on p_max {top_p.split('_')[0]} ({me_p.loc[top_p, 'effect']:.2f} decades), on r_max "
                 f"{top_r.split('_')[0]} ({me_r.loc[top_r, 'effect']:.2f} decades).")
    return lines, facts


CONFIG = {"seed": 0, "n_grid": 161, "n_designs": None, "pop_size": 16, "n_gen": 6, "workers": None,
          "scheduler": None, "progress": True, "pose_errors": None}
#: quick: 8 random designs on a coarser grid, a tiny NSGA-II
QUICK = {"n_grid": 81, "n_designs": 8, "pop_size": 4, "n_gen": 2}
_COLS = [f"{k}_mm" for k in DESIGN_VARS] + list(OBJECTIVES)


def compute(config: dict) -> StudyResult:
    """Evaluate the 243 designs of Tab. VII.1 (``n_designs``: a random subset), find the grid's
    Pareto designs and knees, run NSGA-II on continuous dimensions. ``pose_errors`` replaces the
    certified engine (tests plug in closed forms); ``out_dir`` holds the resumable chunk store.

    Parameters
    ----------
    config : dict
        Study config: ``seed``, ``quick``, ``n_grid`` (workspace grid per side), ``n_designs``
        (random subset size or ``None`` for all 243), ``pop_size`` and ``n_gen`` (NSGA-II),
        ``workers``, ``scheduler`` (Dask address or ``None``), ``progress`` (bool),
        ``pose_errors`` (see :class:`IRSBot2DesignEvaluator`) and, set by the framework,
        ``out_dir`` (no chunk store without it).

    Returns
    -------
    StudyResult
        ``summary`` (presets, findings, objective ranges in mm², mm and deg, the thesis's
        designs, grid Pareto designs and knees, NSGA-II knees, timing in s) and the tables
        ``entries`` (every evaluated design with the columns of :class:`IRSBot2DesignEvaluator`)
        and ``pareto`` (the NSGA-II front).
    """
    t0 = time.perf_counter()
    quick, seed, workers = config["quick"], config["seed"], config["workers"]
    scheduler = scheduler_of(config["scheduler"])   # `evotol reproduce` on a cluster
    ev = IRSBot2DesignEvaluator(n_grid=config["n_grid"], pose_errors=config["pose_errors"])
    f = factors()
    entries = doe.random_subset(f, config["n_designs"], seed=seed) if config["n_designs"] else doe.full_factorial(f)
    store = Path(config["out_dir"]) / f"{NAME}_store{'_quick' if quick else ''}" if config.get("out_dir") else None
    log = doe.EvaluationLog()
    if scheduler is None and worker_count(workers) > 1:
        # the pools' workers fork with the clearance kernels loaded here: one compile (fresh install)
        # or cache load, not one per worker (issue 43)
        from evotol.robots.clearance.support import warm_up

        warm_up()
    df = doe.evaluate(entries, ev, store=store, workers=workers, scheduler=scheduler, progress=config["progress"],
                      log=log, chunk_size=4 if quick else None, description="IRSBot-2 designs")
    # always evaluate the thesis's two good designs (Tab. VII.2) -- they are grid designs
    thesis = doe.evaluate(pd.DataFrame([dict(zip([x.name for x in f], d)) for d in TAB_VII_2]), ev,
                          workers=1, progress=False)
    study = DesignStudy(df, objectives=list(OBJECTIVES), presets=presets(), name=NAME)
    pres = study.preset_results()
    findings, facts = _findings(study, pres)
    good = pres["f_a ≥ 3e4, f_p ≤ 15, f_r ≤ 8"].kept

    # Pareto designs of the grid (max area, min p_max, min r_max) -- threshold-free "good designs"
    ok = df[df["feasible"]].reset_index(drop=True)
    F = np.column_stack([-ok["area_mm2"], ok["p_max_mm"], ok["r_max_deg"]])
    grid_front = ok.iloc[non_dominated(F)]
    in_front = [bool(((grid_front[[x.name for x in f]].to_numpy() == np.array(d)).all(1)).any()) for d in TAB_VII_2]
    Fg = np.column_stack([-grid_front["area_mm2"], grid_front["p_max_mm"], grid_front["r_max_deg"]])
    grid_knees = grid_front.iloc[doe.knee_points(Fg, log=[False, True, True])] if len(grid_front) else grid_front
    cols = _COLS
    fig16 = pres["f_a ≥ 3e4, f_p ≤ 15, f_r ≤ 8"]
    d2s = lambda d: "(" + ", ".join(f"{v:g}" for v in d) + ")"
    findings.append(
        f"Fig. VII.16's filter (f_a ≥ 3e4 mm², f_p ≤ 15 mm, f_r ≤ 8°) keeps {fig16.count} of our designs "
        f"(thesis: 2, Tab. VII.2). The thesis's designs {' and '.join(d2s(d) for d in TAB_VII_2)} give here "
        + "; ".join(f"area {t['area_mm2']:.3g} mm², p_max {t['p_max_mm']:.3g} mm, r_max {t['r_max_deg']:.3g}°"
                    for _, t in thesis.iterrows())
        + f"; {'both are' if all(in_front) else ('one is' if any(in_front) else 'neither is')} on the Pareto front "
        f"of our 243 designs ({len(grid_front)} non-dominated designs).")
    relaxed = study.filter("area_mm2 >= 3e4 and p_max_mm <= 15")
    facts["fig16_without_r"] = relaxed.to_dict()
    if relaxed.count:
        findings.append(
            f"Without its r_max bound, Fig. VII.16's filter keeps {relaxed.count} designs: "
            + "; ".join(f"{v.split('_')[0]} ∈ {{{', '.join(f'{x:g}' for x in relaxed.ranges[v]['levels'])}}}"
                        for v in study.inputs)
            + f" (their r_max is {relaxed.objective_ranges['r_max_deg']['min']:.3g}-"
              f"{relaxed.objective_ranges['r_max_deg']['max']:.3g}°; the smallest r_max of any design with "
              f"f_a ≥ 3e4 mm² is {ok.loc[ok['area_mm2'] >= 3e4, 'r_max_deg'].min():.3g}°).")
    where_p = ok[["p_rd_mm", "p_c_mm", "p_lu_mm"]].to_numpy().argmax(1)
    where_r = ok[["r_rd_deg", "r_c_deg", "r_lu_deg"]].to_numpy().argmax(1)
    names = ("right-down corner", "centre", "left-up corner")
    facts["p_max_at"] = {n: int((where_p == i).sum()) for i, n in enumerate(names)}
    facts["r_max_at"] = {n: int((where_r == i).sum()) for i, n in enumerate(names)}
    findings.append("Where the maximum occurs among the three points of Fig. VII.10: p_max at the "
                    + ", ".join(f"{n} for {int((where_p == i).sum())}" for i, n in enumerate(names))
                    + " designs; r_max at the " + ", ".join(f"{n} for {int((where_r == i).sum())}" for i, n in enumerate(names))
                    + " (thesis, Sec. VIII.1: the rotational error is large at the centre).")
    findings.append("Knees of our grid's Pareto front (best compromises, no thresholds): "
                    + "; ".join(f"{d2s(r[[x.name for x in f]].to_numpy())} -> {r['area_mm2']:.3g} mm², "
                                f"{r['p_max_mm']:.3g} mm, {r['r_max_deg']:.3g}°" for _, r in grid_knees.iterrows()) + ".")

    # NSGA-II on continuous dimensions: area vs p_max vs r_max
    t1 = time.perf_counter()
    front = doe.nsga2(factors(continuous=True), ev,
                       [Objective("area_mm2", -1), Objective("p_max_mm", 1, log=True), Objective("r_max_deg", 1, log=True)],
                       pop_size=config["pop_size"], n_gen=config["n_gen"], seed=seed,
                       initial=grid_front if len(grid_front) else None,
                       workers=1 if quick else (workers or os.cpu_count() or 1), scheduler=scheduler)
    t_nsga = time.perf_counter() - t1
    pareto = front.table
    knees = pareto[pareto["knee"]]

    rng = study.objective_ranges(among=ok)
    findings.append(f"Ranges over our designs: p_max [{rng['p_max_mm']['min']:.3g}, {rng['p_max_mm']['max']:.3g}] mm "
                    f"(thesis [7.3, 30.6]), r_max [{rng['r_max_deg']['min']:.3g}, {rng['r_max_deg']['max']:.3g}]° "
                    f"(thesis [5.8, 24.3]), area [{rng['area_mm2']['min']:.3g}, {rng['area_mm2']['max']:.3g}] mm².")
    summary = {
        "study": NAME, "quick": quick, "seed": seed, "n_designs": len(df), "n_feasible": int(df["feasible"].sum()),
        "fixed_parameters_SI": TAB_VI_4,
        "clearance_SI": {**CLEARANCE, "beta_z_active": BETA_Z_ACTIVE, "beta_z_passive": BETA_Z_PASSIVE}, "n_grid": ev.n_grid, "margin_deg": ev.margin_deg,
        "objective_ranges": {k: [v["min"], v["max"]] for k, v in rng.items()}, "thesis_ranges": THESIS_RANGES,
        "presets": {k: {"count": v.count, "ranges": v.ranges, "query": v.resolved_query} for k, v in pres.items()},
        **parcoords_counts(study, pareto, _axes(f)),
        "good_designs": good[cols].to_dict(orient="records"),
        "grid_pareto_designs": grid_front[cols].to_dict(orient="records"),
        "grid_knees": grid_knees[cols].to_dict(orient="records"),
        "thesis_designs": [{"design_mm": list(d), "area_mm2": t["area_mm2"], "p_max_mm": t["p_max_mm"],
                            "r_max_deg": t["r_max_deg"], "on_grid_pareto_front": fr}
                           for d, (_, t), fr in zip(TAB_VII_2, thesis.iterrows(), in_front)],
        "findings": findings, "facts": facts,
        "evaluation": {"seconds": log.seconds, "backend": log.backend, "chunks_resumed": len(log.chunks_resumed)},
        "nsga2": {"n_pareto": len(pareto), "n_evaluations": pareto.attrs["evotol"]["n_evaluations"], "seconds": t_nsga,
                  "knees": knees[cols].to_dict(orient="records")},
        "files": {"entries_parquet": f"{NAME}_entries.parquet", "entries_csv": f"{NAME}_entries.csv",
                  "pareto_parquet": f"{NAME}_pareto.parquet"},
        "seconds": time.perf_counter() - t0,
    }
    return StudyResult(summary, {"entries": df, "pareto": pareto})


def _axes(f):
    from evotol.reporting.parcoords import Axis

    return [Axis(x.name, x.label) for x in f] + [Axis("area_mm2", "area (mm²)"), Axis("p_max_mm", "p_max (mm)", True),
                                                  Axis("r_max_deg", "r_max (deg)", True)]


def render(result: StudyResult):
    """Findings, Tab. VII.2 in our model, the parallel coordinates with the presets of Figs.
    VII.12-VII.16, ranges vs the thesis, the grid's Pareto designs and the NSGA-II knees.

    Parameters
    ----------
    result : StudyResult
        Output of :func:`compute`: its summary and the tables ``entries`` and ``pareto``.

    Returns
    -------
    evotol.reporting.html.Report
        The HTML report.
    """
    from evotol.reporting.html import Report
    from evotol.reporting.parcoords import format_tick

    s, df, pareto = result.summary, result.tables["entries"], result.tables["pareto"]
    f = factors()
    labels = [x.label for x in f] + ["area (mm²)", "p_max (mm)", "r_max (deg)"]
    study = DesignStudy(df, objectives=list(OBJECTIVES), presets=presets(), name=NAME)
    rng = {k: {"min": v[0], "max": v[1]} for k, v in s["objective_ranges"].items()}
    ev = s["evaluation"]
    rep = Report("IRSBot-2 dimension synthesis (Deng 2012, Sec. VII.2.2)",
                 f"{len(df)} designs ({'quick sample' if s['quick'] else 'Tab. VII.1 full factorial 3^5'}); fixed parameters "
                 f"Tab. VI.4; clearances Δb = 0.1 mm, Δβ_xy = 0.01 rad in the distal modules and parallelograms; "
                 f"evaluated in {ev['seconds']:.1f} s ({ev['backend']})")
    rep.heading("Findings (computed from the entries below)")
    rep.html("<ul>" + "".join(f"<li>{x}</li>" for x in s["findings"]) + "</ul>")
    good = {tuple(g[f"{k}_mm"] for k in DESIGN_VARS) for g in s["good_designs"]}
    rows = [[", ".join(f"{v:g}" for v in t["design_mm"]), t["area_mm2"], t["p_max_mm"], t["r_max_deg"],
             "yes" if tuple(t["design_mm"]) in good else "no", "yes" if t["on_grid_pareto_front"] else "no"]
            for t in s["thesis_designs"]]
    rep.heading("The thesis's good designs (Tab. VII.2) in our model")
    rep.table(rows, ["(l1, l2, a1, a2, p) mm", "area (mm²)", "p_max (mm)", "r_max (deg)", "kept by Fig. VII.16 filter",
                     "on our grid's Pareto front"])
    parcoords_section(rep, study, pareto, _axes(f),
                      "One line per design (level grid), NSGA-II Pareto designs on continuous dimensions in orange, "
                      "knees in red. Presets apply the filters of Figs. VII.12-VII.16.", "Presets (Figs. VII.12-VII.16)")
    rep.heading("Objective ranges vs the thesis")
    rep.table([[c, f"[{format_tick(rng[c]['min'])}, {format_tick(rng[c]['max'])}]",
                f"[{THESIS_RANGES[c][0]:g}, {THESIS_RANGES[c][1]:g}]" if c in THESIS_RANGES else "–"] for c in OBJECTIVES],
              ["objective", "ours", "thesis (Sec. VII.2.2)"])
    rep.heading("Pareto designs of the level grid and NSGA-II knees")
    rep.table([[d[c] for c in _COLS] for d in s["grid_pareto_designs"]], labels, digits=4)
    ns = s["nsga2"]
    rep.text(f"NSGA-II: {ns['n_pareto']} Pareto designs from {ns['n_evaluations']} evaluations ({ns['seconds']:.1f} s); knees:")
    rep.table([[d[c] for c in _COLS] for d in ns["knees"]], labels, digits=4)
    rep.text(f"Workspace: the largest axis-aligned rectangle of x-z points (grid {s['n_grid']} x {s['n_grid']} over the reach) "
             f"below the base in the elbows-out working mode, with the distal links forming a V and "
             f"|sin| of the Type 1 and Type 2 singularity angles ≥ sin {s['margin_deg']:g}°. Pose errors at its right-down "
             f"corner, centre and left-up corner (Fig. VII.10), largest taken.", note=True)
    return rep


STUDY = Study(name=NAME, title="IRSBot-2 dimension synthesis on parallel coordinates + NSGA-II (Deng 2012 Sec. VII.2)",
              compute=compute, render=render, config=CONFIG, quick=QUICK, seed_paper="004 Deng 2012 (thesis), Ch. VII")

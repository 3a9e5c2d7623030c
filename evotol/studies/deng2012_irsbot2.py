"""Study ``deng2012-irsbot2``: maximum pose error of the IRSBot-2 due to joint clearances (Deng 2012, Ch. VI).

* Maps (Figs. VI.1/VI.3): Tabs. VI.1-VI.2 geometry, clearances in the distal module only
  (Tab. VI.3, 78 variables) and in distal module + parallelograms (Tabs. VI.7-VI.9, 114
  variables), on a 41 x 41 grid of a square centred on the z axis and crossed by the parallel
  singularity (the thesis's square is not given in its text; ours is ``evotol.robots.irsbot2.MAP_WORKSPACE``).
  The thesis reports ten days of computation for the distal map; every value here is a certified
  global maximum (gap <= 0.1 %).
* 5-point comparison (Figs. VI.4-VI.5): Tabs. VI.4-VI.5 geometry (beta = pi/4), distal joints with
  beta_z = 0.4 rad (Tab. VI.6), parallelogram joints Tabs. VI.7-VI.9, at the four corners and the
  centre of the largest rectangle of the workspace. The thesis does not state the rectangle's
  criterion; we take the largest rectangle symmetric about x = 0 in which the robot is at least
  ``margin`` away from both singularity types (``|sin(psi1 - psi2)|`` and ``min |sin(q_i - psi_i)|``),
  :func:`evotol.robots.irsbot2.centred_singularity_free_rectangle`.
"""
from __future__ import annotations

import time

import numpy as np

from evotol._runtime.executor import scheduler_of
from evotol.reporting.html import Report
from evotol.studies import Study, StudyResult
from evotol.units import MM



def _maps_figure(title, x_mm, z_mm, P, R, sing):
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    fig = make_subplots(rows=1, cols=2, subplot_titles=("maximum positional error (mm)", "maximum rotational error (rad)"),
                        horizontal_spacing=0.12)
    def rng(Z):   # a constant map (e.g. an open leg's rotation) must not show round-off as colour
        Z = np.asarray(Z, float)
        lo, hi = np.nanmin(Z), np.nanmax(Z)
        return dict(zmin=lo * (1 - 1e-3), zmax=hi * (1 + 1e-3)) if hi - lo <= 1e-9 * max(abs(hi), 1e-300) else {}

    fig.add_trace(go.Heatmap(x=x_mm, y=z_mm, z=P, colorscale="Viridis", **rng(P), colorbar=dict(x=0.44, title="mm"),
                             hovertemplate="x=%{x:.1f} mm<br>z=%{y:.1f} mm<br>p_max=%{z:.4g} mm<extra></extra>"), 1, 1)
    fig.add_trace(go.Heatmap(x=x_mm, y=z_mm, z=R, colorscale="Cividis", **rng(R), colorbar=dict(x=1.0, title="rad"),
                             hovertemplate="x=%{x:.1f} mm<br>z=%{y:.1f} mm<br>r_max=%{z:.4g} rad<extra></extra>"), 1, 2)
    xs, zs, S = sing
    for col in (1, 2):
        fig.add_trace(go.Contour(x=xs, y=zs, z=S, contours=dict(start=0, end=0, size=1, coloring="none"),
                                 line=dict(color="red", width=2, dash="dash"), showscale=False, name="parallel singularity",
                                 showlegend=col == 1, hoverinfo="skip"), 1, col)
    fig.update_layout(title=title, height=470, legend=dict(orientation="h", y=-0.18))
    for col in (1, 2):
        fig.update_xaxes(title_text="x (mm)", row=1, col=col)
        fig.update_yaxes(title_text="z (mm)", row=1, col=col, scaleanchor=f"x{'' if col == 1 else 2}")
    return fig


CONFIG = {"seed": 0, "n_grid": 41, "workers": None, "scheduler": None, "margin": 0.2, "rectangle_step": 1e-3,
          "n_starts": 6}
QUICK = {"n_grid": 7, "rectangle_step": 2e-3, "n_starts": 1}


def compute(config: dict) -> StudyResult:
    """The two error maps, the five points of the largest rectangle and the multistart baseline.

    Parameters
    ----------
    config : dict
        Study config: ``n_grid`` (points per axis of the map grid; 41), ``seed``, ``quick``,
        ``workers`` and ``scheduler`` (parallel map evaluation; a Dask address or ``None``),
        ``margin`` (smallest allowed magnitude of the singularity sines, dimensionless),
        ``rectangle_step`` (search step of the largest rectangle, m) and ``n_starts``
        (multistart starts of the baseline).

    Returns
    -------
    StudyResult
        ``summary`` only: grid ``x``, ``z`` (mm); per clearance case (``distal``,
        ``distal_parallelograms``) the maps ``p_max``, ``p_upper`` (mm) and ``r_max``,
        ``r_upper`` (rad) as ``(n_grid, n_grid)`` nested lists (row = z index); the geometries
        (SI), the singularity data, the five points (mm, rad), the multistart baseline, the
        mirror-reuse check, ``figures`` and ``seconds`` (s).
    """
    from evotol.robots.clearance import ClearanceBounds, max_pose_error, multistart_max_pose_error
    from evotol.robots.clearance.symmetry import grid_max_pose_error_mirrored
    from evotol.robots.irsbot2 import MAP_WORKSPACE, IRSBot2, centred_singularity_free_rectangle, mirror_joint_map

    t_start = time.perf_counter()
    n, quick, seed, margin, workers = config["n_grid"], config["quick"], config["seed"], config["margin"], config["workers"]
    # `evotol reproduce --scheduler ADDRESS` passes the Dask address in the config (or the environment)
    scheduler = scheduler_of(config["scheduler"])
    W = MAP_WORKSPACE
    x = np.linspace(W.low[0], W.high[0], n)
    z = np.linspace(W.low[1], W.high[1], n)
    X, Z = np.meshgrid(x, z)                    # row = z index, column = x index
    poses = np.stack([X.ravel(), Z.ravel()], 1)
    robot = IRSBot2.thesis("VI.1")
    cases = {"distal": robot.clearance_mechanism(), "distal_parallelograms": robot.clearance_mechanism(parallelograms=True)}
    results, mirror = {}, {}
    for name, mech in cases.items():
        # the square is symmetric about x = 0: solve x <= 0, reuse the mirror half once the mirror
        # symmetry of the description is proven pose pair by pose pair (issue 13)
        results[name], mirror[name] = grid_max_pose_error_mirrored(
            mech, poses, mirror_joint_map(mech), np.diag([-1.0, 1.0, 1.0]), np.array([-1.0, 1.0]),
            workers=workers, scheduler=scheduler)
    xs = np.linspace(W.low[0], W.high[0], 121)
    zs = np.linspace(W.low[1], W.high[1], 121)
    XS, ZS = np.meshgrid(xs, zs)
    S = robot.parallel_singularity(np.stack([XS.ravel(), ZS.ravel()], 1)).reshape(XS.shape)
    sing_grid = np.abs(robot.parallel_singularity(poses))

    def as_map(a, scale=1.0):
        return (np.asarray(a) * scale).reshape(n, n)

    # --- 5-point comparison (Figs. VI.4-VI.5) ---------------------------------------------------
    robot4 = IRSBot2.thesis("VI.4")
    rect = centred_singularity_free_rectangle(robot4, margin=margin, step=config["rectangle_step"])
    hw, z1, z2 = rect["half_width"], rect["z_low"], rect["z_high"]
    pts = np.array([[-hw, z2], [hw, z2], [0.0, (z1 + z2) / 2], [-hw, z1], [hw, z1]])
    labels = ["upper left", "upper right", "centre", "lower left", "lower right"]
    distal_b = ClearanceBounds(0.01, 0.4, 0.1 * MM, 0.1 * MM)                 # Tab. VI.6
    five = {
        "distal": max_pose_error(robot4.clearance_mechanism(distal=distal_b), pts),
        "distal_parallelograms": max_pose_error(robot4.clearance_mechanism(parallelograms=True, distal=distal_b), pts),
    }

    # --- the thesis's method on one point ------------------------------------------------------
    n_starts = config["n_starts"]
    base_pose = poses[[len(poses) // 2]]
    ms = {k: multistart_max_pose_error(cases[k], base_pose, n_starts=n_starts, seed=seed) for k in cases}
    ours = {k: max_pose_error(cases[k], base_pose) for k in cases}

    def pack(res):
        return {"p_max": as_map(res.p_max, 1e3).tolist(), "r_max": as_map(res.r_max).tolist(),
                "p_upper": as_map(res.p_upper, 1e3).tolist(), "r_upper": as_map(res.r_upper).tolist(),
                "gap_max": float(res.gap.max()), "seconds": res.seconds, "n_variables": None}

    data = {"x": (x / MM).tolist(), "z": (z / MM).tolist(), "grid": n, "quick": quick,
            "geometry_maps": {k: getattr(robot, k) for k in ("b", "d", "alpha_d", "beta", "e", "l1", "l2", "a1", "a2", "p")},
            "geometry_five_points": {k: getattr(robot4, k) for k in ("b", "d", "alpha_d", "beta", "e", "l1", "l2", "a1", "a2", "p")}}
    for k, res in results.items():
        data[k] = pack(res)
        pm = cases[k].pose_maps(poses[:1])[0]
        data[k]["n_variables"] = pm.n_rows - pm.n_loops
    data["gap_max"] = float(max(max(r.gap.max() for r in results.values()), max(r.gap.max() for r in five.values())))
    data["map_seconds"] = {k: r.seconds for k, r in results.items()}
    data["singularity"] = {"measure": "sin(psi1 - psi2)", "min_abs_on_grid": float(sing_grid.min()),
                           "p_max_at_most_singular_grid_point_mm": float(results["distal"].p_max[np.argmin(sing_grid)] / MM),
                           "most_singular_grid_point_mm": (poses[np.argmin(sing_grid)] / MM).tolist()}
    data["five_points"] = {
        "rectangle_mm": {"x": [-hw / MM, hw / MM], "z": [z1 / MM, z2 / MM], "area_mm2": rect["area"] / MM ** 2,
                         "criterion": f"|sin(psi1-psi2)| >= {margin} and min|sin(q_i-psi_i)| >= {margin}"},
        "points_mm": (pts / MM).tolist(), "labels": labels,
        **{k: {"p_max_mm": (r.p_max / MM).tolist(), "p_upper_mm": (r.p_upper / MM).tolist(), "r_max_rad": r.r_max.tolist(),
               "r_upper_rad": r.r_upper.tolist()} for k, r in five.items()}}
    data["multistart_baseline"] = {k: {"pose_mm": (base_pose[0] / MM).tolist(), "n_starts": n_starts, "n_variables": ms[k].n_variables,
                                       "multistart_p_mm": ms[k].p_max[0] / MM, "multistart_r": ms[k].r_max[0],
                                       "p_max_mm": ours[k].p_max[0] / MM, "p_upper_mm": ours[k].p_upper[0] / MM,
                                       "r_max": ours[k].r_max[0], "r_upper": ours[k].r_upper[0],
                                       "seconds_multistart": ms[k].seconds, "seconds_ours": ours[k].seconds} for k in cases}
    data["mirror_reuse"] = mirror
    # independent check of the reuse: solve a few mirrored poses directly and compare
    check = np.flatnonzero(poses[:, 0] > 0)[:: max(1, int(np.sum(poses[:, 0] > 0)) // 6)]
    direct = {k: max_pose_error(cases[k], poses[check]) for k in cases}
    data["symmetry"] = {k: {"p_max_relative_difference": float(np.max(np.abs(results[k].p_max[check] - d.p_max) / d.p_max)),
                            "r_max_relative_difference": float(np.max(np.abs(results[k].r_max[check] - d.r_max) / d.r_max)),
                            "checked_poses": int(len(check)),
                            "brackets_overlap": bool(np.all(results[k].p_max[check] <= d.p_upper * (1 + 1e-12))
                                                     and np.all(d.p_max <= results[k].p_upper[check] * (1 + 1e-12))
                                                     and np.all(results[k].r_max[check] <= d.r_upper * (1 + 1e-12))
                                                     and np.all(d.r_max <= results[k].r_upper[check] * (1 + 1e-12)))}
                        for k, d in direct.items()}

    data["figures"] = {"margin": margin, "singularity_contour": {"x_mm": (xs / MM).tolist(), "z_mm": (zs / MM).tolist(),
                                                                  "sin_psi1_minus_psi2": S.tolist()},
                       "min_max": {k: {"p_max_mm": [float(r.p_max.min() / MM), float(r.p_max.max() / MM)],
                                       "r_max_rad": [float(r.r_max.min()), float(r.r_max.max())]} for k, r in results.items()}}
    data["seconds"] = time.perf_counter() - t_start
    return StudyResult(data)


def render(result: StudyResult) -> Report:
    """Figs. VI.1/VI.3 maps with the singular locus, the five points of Figs. VI.4-VI.5, the baseline.

    Returns
    -------
    evotol.reporting.html.Report
        The HTML report.
    """
    import plotly.graph_objects as go

    data = result.summary
    fg = data["figures"]
    margin, mm = fg["margin"], fg["min_max"]
    x_mm, z_mm = np.asarray(data["x"]), np.asarray(data["z"])
    sc = fg["singularity_contour"]
    sing = (np.asarray(sc["x_mm"]), np.asarray(sc["z_mm"]), np.asarray(sc["sin_psi1_minus_psi2"], float))
    n = data["grid"]
    fp = data["five_points"]
    labels, pts_mm = fp["labels"], np.asarray(fp["points_mm"])
    hw_mm, (z1_mm, z2_mm) = fp["rectangle_mm"]["x"][1], fp["rectangle_mm"]["z"]
    rep = Report("deng2012-irsbot2: IRSBot-2, maximum pose error due to joint clearances",
                 "Deng 2012 (seed 004), Ch. II, V-VI: Tabs. II.1-II.2, VI.1-VI.9, Figs. VI.1-VI.5")
    rep.text(f"Certified global maximum positional and rotational errors of the IRSBot-2 on a {n} x {n} grid of "
             f"x in [{x_mm[0]:.0f}, {x_mm[-1]:.0f}] mm, z in [{z_mm[0]:.0f}, {z_mm[-1]:.0f}] mm "
             f"(Tabs. VI.1-VI.2: b = d = l1 = l2 = 50, a1 = 30, a2 = 15, p = 25 mm, alpha_d = beta = pi/6, elbows out). "
             f"Largest relative gap between attained value and certified bound: {data['gap_max']:.2e}. Map times: "
             + ", ".join(f"{k} {v:.1f} s ({data[k]['n_variables']} variables)" for k, v in data["map_seconds"].items())
             + ". The thesis reports ten days for the distal-module map with 200-start local optimisation.")
    rep.text("The thesis's text does not give the square of Figs. VI.1-VI.3; we use a square centred on the z axis "
             "that, like the thesis's (Fig. VI.2), is crossed by the parallel singularity (red dashed line). Its DH "
             "tables and equations needed corrections before the loops closed (see docs/clearance.md): row 28 of "
             "Tab. II.2 (alpha sign), eq. II.1 (cos^2), eq. II.8 (leg-2 terms).", note=True)
    titles = {"distal": "Clearances in the distal module (Figs. VI.1 and VI.3; Tab. VI.3)",
              "distal_parallelograms": "Clearances in the distal module and the parallelograms (Tabs. VI.7-VI.9)"}
    for k in titles:
        d = data[k]
        rep.heading(titles[k])
        rep.figure(_maps_figure(titles[k], x_mm, z_mm, np.asarray(d["p_max"], float), np.asarray(d["r_max"], float), sing))
        rep.table([[*mm[k]["p_max_mm"], *mm[k]["r_max_rad"], d["gap_max"], d["seconds"], d["n_variables"],
                    data["symmetry"][k]["p_max_relative_difference"], data["symmetry"][k]["r_max_relative_difference"]]],
                  header=["p_max min (mm)", "p_max max (mm)", "r_max min (rad)", "r_max max (rad)", "largest gap", "seconds",
                          "variables (thesis v)", "mirror reuse vs direct p (rel.)", "mirror reuse vs direct r (rel.)"])
        mr = data["mirror_reuse"][k]
        rep.text(f"Mirror symmetry x -> -x (leg 1 <-> leg 2) proven at each of the {mr['n_reused']} pose pairs from the "
                 f"description's per-pose maps (largest residuals {mr['max_map_residual']:.1e} / "
                 f"{mr['max_consistency_residual']:.1e}; robots/clearance/symmetry.py): {mr['n_solved']} of "
                 f"{mr['n_poses']} poses solved, the mirror half reused with its maximisers mapped. "
                 f"{data['symmetry'][k]['checked_poses']} reused poses solved again directly agree to the relative "
                 f"differences in the table (brackets overlap: {data['symmetry'][k]['brackets_overlap']}).", note=True)
    surf = go.Figure(go.Surface(x=x_mm, y=z_mm, z=np.asarray(data["distal"]["p_max"], float), colorscale="Viridis"))
    surf.update_layout(title="Distal module: p_max surface (perspective view of Fig. VI.1a)", height=520,
                       scene=dict(xaxis_title="x (mm)", yaxis_title="z (mm)", zaxis_title="p_max (mm)"))
    rep.figure(surf)

    rep.heading("Five points of the largest rectangle (Figs. VI.4-VI.5; Tabs. VI.4-VI.9)")
    rep.text(f"beta = pi/4, distal beta_z = 0.4 rad, actuated joints beta_z = 0.001 rad, passive parallelogram joints "
             f"0.2 rad (the captions of Tabs. VI.8 and VI.9 are swapped in the thesis). Rectangle: x in +-{hw_mm:.1f} mm, "
             f"z in [{z1_mm:.1f}, {z2_mm:.1f}] mm, the largest symmetric rectangle with both singularity measures "
             f">= {margin} (our criterion; the thesis does not state its own).")
    five = {k: fp[k] for k in ("distal", "distal_parallelograms")}
    rows = []
    for i, lab in enumerate(labels):
        rows.append([lab, f"({pts_mm[i, 0]:.1f}, {pts_mm[i, 1]:.1f})", five["distal"]["p_max_mm"][i],
                     five["distal_parallelograms"]["p_max_mm"][i], five["distal"]["r_max_rad"][i],
                     five["distal_parallelograms"]["r_max_rad"][i]])
    rep.table(rows, header=["point", "(x, z) mm", "p_max distal (mm)", "p_max + parallelograms (mm)", "r_max distal (rad)",
                            "r_max + parallelograms (rad)"])
    bar = go.Figure()
    for k, nm in (("distal", "distal module"), ("distal_parallelograms", "distal + parallelograms")):
        bar.add_trace(go.Bar(x=labels, y=five[k]["p_max_mm"], name=f"p_max, {nm}"))
    bar.update_layout(barmode="group", title="Maximum positional error at the five points (mm)", height=380)
    rep.figure(bar)
    bar2 = go.Figure()
    for k, nm in (("distal", "distal module"), ("distal_parallelograms", "distal + parallelograms")):
        bar2.add_trace(go.Bar(x=labels, y=five[k]["r_max_rad"], name=f"r_max, {nm}"))
    bar2.update_layout(barmode="group", title="Maximum rotational error at the five points (rad)", height=380)
    rep.figure(bar2)

    rep.heading("The thesis's method on one point")
    brows = []
    for k, v in data["multistart_baseline"].items():
        brows.append([k, v["n_variables"], v["multistart_p_mm"], v["p_max_mm"], v["p_upper_mm"], v["multistart_r"], v["r_max"],
                      v["r_upper"], v["seconds_multistart"], v["seconds_ours"]])
    b0 = data["multistart_baseline"]["distal"]
    rep.text(f"QR elimination + SLSQP from {b0['n_starts']} random starts (thesis: fmincon, up to 200 starts) at "
             f"({b0['pose_mm'][0]:.1f}, {b0['pose_mm'][1]:.1f}) mm.")
    rep.table(brows, header=["case", "variables", "multistart p (mm)", "p_max (mm)", "p_upper (mm)", "multistart r (rad)",
                             "r_max (rad)", "r_upper (rad)", "multistart s", "certified s"])
    rep.text(f"Total study time {data['seconds']:.1f} s.")
    return rep


STUDY = Study(name="deng2012-irsbot2", title="IRSBot-2: certified maximum pose error due to joint clearances (Deng 2012 Ch. VI)",
              compute=compute, render=render, config=CONFIG, quick=QUICK,
              seed_paper="004_fe1111236e25a595 (Deng 2012, Ch. II, V-VI)")

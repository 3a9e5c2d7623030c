"""The figures of the Lara-Molina et al. 2019 study (:mod:`evotol.studies.laramolina2019_5r`), drawn
from its JSON summary alone: workspace with the usable region and the MIC, zoom on the clouds,
LCI map, LHS-vs-MC convergence, Pareto front and the allocation's grid check."""
from __future__ import annotations

import numpy as np

from evotol.robots.planar5r import uncertainty as U

POSE_LABELS = tuple("abcdefghi")


def circle(cx, cy, r, n=181):
    a = np.linspace(0, 2 * np.pi, n)
    return cx + r * np.cos(a), cy + r * np.sin(a)


def plot_arrays(p: dict) -> dict:
    """A case's figure data (``summary["figures"][case]``) as numpy arrays."""
    f = lambda k: np.asarray(p[k], float)
    return {"x": f("x"), "y": f("y"), "usable": np.asarray(p["usable"], bool), "lci": f("lci"),
            "type1_circles": p["type1_circles"], "locus": f("type2_locus").reshape(-1, 2),
            "cloud": f("cloud"), "cloud_ok": np.asarray(p["cloud_ok"], bool), "poses": f("poses")}


def workspace_figure(case: str, res: dict, p: dict):
    import plotly.graph_objects as go

    poses = p["poses"]
    fig = go.Figure()
    fig.add_trace(go.Heatmap(x=p["x"], y=p["y"], z=np.where(p["usable"], 1.0, np.nan), showscale=False, hoverinfo="skip",
                             colorscale=[[0, "#cfe8cf"], [1, "#cfe8cf"]], name="usable workspace"))
    for c in p["type1_circles"]:
        x, y = circle(c["cx"], 0.0, c["radius"], 361)
        fig.add_trace(go.Scatter(x=x, y=y, mode="lines", line=dict(color="#888", width=1, dash="dot"),
                                 name=f"type I {c['name']}", legendgroup="t1"))
    L = p["locus"]
    if len(L):
        fig.add_trace(go.Scatter(x=L[:, 0], y=L[:, 1], mode="markers", marker=dict(size=2, color="#c0392b"),
                                 name="type II singular locus"))
    x, y = circle(0.0, res["mic_center_y"], res["mic_radius"])
    fig.add_trace(go.Scatter(x=x, y=y, mode="lines", line=dict(color="#1f4e9c", width=2), name=f"MIC ({res['mic_equation']})"))
    k = 0.2 * res["mic_radius"] / U.PAPER_CIRCLE
    cx, cy = [], []
    for i in range(len(poses)):
        x, y = circle(poses[i, 0], poses[i, 1], k * U.PAPER_CIRCLE, 61)
        cx += list(x) + [None]
        cy += list(y) + [None]
    fig.add_trace(go.Scatter(x=cx, y=cy, mode="lines", line=dict(color="#2b8a3e", width=1), name="0.005 circles (magnified)"))
    cl, ok = p["cloud"], p["cloud_ok"]
    px = (poses[:, None, 0] + k * cl[..., 0])[ok]
    py = (poses[:, None, 1] + k * cl[..., 1])[ok]
    fig.add_trace(go.Scatter(x=px, y=py, mode="markers", marker=dict(size=2, color="#333"), name="sampled end-effector"))
    fig.add_trace(go.Scatter(x=poses[:, 0], y=poses[:, 1], mode="markers+text", text=list(POSE_LABELS),
                             textposition="top right", marker=dict(size=5, color="#e67700"), name="poses a-i"))
    X, Y = np.meshgrid(p["x"], p["y"])
    xs, ys = X[p["usable"]], Y[p["usable"]]
    pad = 0.08 * max(np.ptp(xs), np.ptp(ys))
    fig.update_layout(title=f"Case {case}: usable workspace, singular loci, MIC and Monte Carlo clouds "
                            f"(deviations magnified x{k:.3g}; circles = 0.005)",
                      xaxis=dict(title="x (non-dimensional)", range=[xs.min() - pad, xs.max() + pad]),
                      yaxis=dict(title="y", scaleanchor="x", range=[ys.min() - pad, ys.max() + pad]),
                      height=620, legend=dict(font=dict(size=10)), plot_bgcolor="white")
    return fig


def zoom_figure(case: str, res: dict, p: dict):
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    st = res["poses"]
    fig = make_subplots(rows=3, cols=3, subplot_titles=[
        f"{lab}: LCI {st['lci'][i]:.2f}, P(out) {st['p_exceed'][i]:.3f}" for i, lab in enumerate(POSE_LABELS)],
        horizontal_spacing=0.06, vertical_spacing=0.09)
    cl, ok = p["cloud"], p["cloud_ok"]
    lim = max(1.1 * U.PAPER_CIRCLE, float(np.max(np.abs(cl[ok]))) * 1.05) if ok.any() else 1.1 * U.PAPER_CIRCLE
    cx, cy = circle(0, 0, U.PAPER_CIRCLE)
    for i in range(9):
        r, c = divmod(i, 3)
        fig.add_trace(go.Scatter(x=cl[i, ok[i], 0], y=cl[i, ok[i], 1], mode="markers", marker=dict(size=2, color="#333"),
                                 showlegend=False), row=r + 1, col=c + 1)
        fig.add_trace(go.Scatter(x=cx, y=cy, mode="lines", line=dict(color="#2b8a3e"), showlegend=False), row=r + 1, col=c + 1)
        fig.update_xaxes(range=[-lim, lim], row=r + 1, col=c + 1)
        fig.update_yaxes(range=[-lim, lim], row=r + 1, col=c + 1, scaleanchor=f"x{i + 1 if i else ''}")
    fig.update_layout(title=f"Case {case}: zoom of poses a-i, deviation (dx, dy) from the nominal pose "
                            f"(non-dimensional) inside the 0.005 circle", height=1000)
    return fig


def lci_figure(case: str, res: dict, p: dict):
    import plotly.graph_objects as go

    poses = p["poses"]
    fig = go.Figure(go.Heatmap(x=p["x"], y=p["y"], z=p["lci"], colorscale="Viridis", zmin=0, zmax=1,
                               colorbar=dict(title="LCI")))
    x, y = circle(0.0, res["mic_center_y"], res["mic_radius"])
    fig.add_trace(go.Scatter(x=x, y=y, mode="lines", line=dict(color="white", width=2), name="MIC"))
    fig.add_trace(go.Scatter(x=poses[:, 0], y=poses[:, 1], mode="markers+text", text=list(POSE_LABELS),
                             textposition="top right", textfont=dict(color="white"), marker=dict(size=5, color="#e67700"),
                             name="poses"))
    X, Y = np.meshgrid(p["x"], p["y"])
    xs, ys = X[p["usable"]], Y[p["usable"]]
    fig.update_layout(title=f"Case {case}: LCI = 1/cond(J) over the usable workspace (max {res['lci_max']:.3f})",
                      xaxis=dict(title="x", range=[xs.min(), xs.max()]),
                      yaxis=dict(title="y", scaleanchor="x", range=[ys.min(), ys.max()]), height=560, showlegend=False)
    return fig


def convergence_figure(conv: dict):
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    keys = list(conv["variance_ratio"])
    titles = {"mean_dx": "mean of dx (error / rms deviation)", "rms_dev": "rms deviation (relative error)",
              "p_exceed_q90": "P(|dp| > q90) (relative error)"}
    fig = make_subplots(rows=1, cols=len(keys), subplot_titles=[titles[k] for k in keys])
    for j, k in enumerate(keys):
        for m, color in (("mc", "#c0392b"), ("lhs", "#1f4e9c")):
            fig.add_trace(go.Scatter(x=conv["sizes"], y=conv[m][k], mode="lines+markers", line=dict(color=color),
                                     name=m.upper(), showlegend=j == 0), row=1, col=j + 1)
        fig.update_xaxes(type="log", title="samples N", row=1, col=j + 1)
        fig.update_yaxes(type="log", row=1, col=j + 1)
    fig.update_layout(title=f"LHS vs plain MC: RMS estimation error over {conv['n_rep']} replications (case b, 9 poses)",
                      height=420)
    return fig


def pareto_figure(alloc: dict):
    import plotly.graph_objects as go

    par = alloc["pareto"]
    hover = [f"r_cA {a * 1e6:.1f} um, r_cB {b * 1e6:.1f} um, dtheta {np.rad2deg(t):.4f} deg"
             for a, b, t in zip(par["clearance_A"], par["clearance_B"], par["theta"])]
    fig = go.Figure(go.Scatter(x=par["p_exceed"], y=par["cost"], mode="markers+lines", text=hover, name="NSGA-II front"))
    fig.add_trace(go.Scatter(x=[max(alloc["p_exceed_optimiser"])], y=[alloc["cost"]], mode="markers",
                             marker=dict(size=12, symbol="star", color="#e67700"), name="GA optimum, calibrated"))
    fig.add_vline(x=alloc["p_max"], line=dict(dash="dash", color="#888"))
    fig.update_layout(title=f"Case {alloc['case']}: cost vs max over MIW poses of P(|dp| > {alloc['radius'] * 1e3:.2g} mm) "
                            f"(common sample of {alloc['n_samples']} LHS rows)",
                      xaxis=dict(title="max_pose P_exceed", type="log"), yaxis=dict(title="cost"), height=460)
    return fig


def grid_figure(alloc: dict):
    import plotly.graph_objects as go

    g = alloc["grid"]
    rc = np.array(g["clearance"]) * 1e6
    dt = np.rad2deg(np.array(g["theta"]))
    fig = go.Figure(go.Heatmap(x=rc, y=dt, z=np.log10(np.maximum(np.array(g["p_exceed_max"]), 1e-4)),
                               colorscale="RdYlGn_r", colorbar=dict(title="log10 P")))
    fig.add_trace(go.Contour(x=rc, y=dt, z=np.array(g["cost"]), contours=dict(coloring="lines", showlabels=True),
                             line=dict(color="black", width=1), showscale=False, name="cost"))
    t = alloc["tolerances"]
    fig.add_trace(go.Scatter(x=[t["clearance_A"] * 1e6, t["clearance_B"] * 1e6], y=[np.rad2deg(t["theta"])] * 2,
                             mode="markers+text", text=["GA r_cA", "GA r_cB"], textposition="top center",
                             marker=dict(size=10, symbol="star", color="#1f4e9c"), name="GA optimum"))
    fig.update_layout(title=f"Case {alloc['case']}: max_pose P_exceed with r_cA = r_cB (colour) and cost (lines)",
                      xaxis=dict(title="radial clearance r_c (um)", type="log"),
                      yaxis=dict(title="actuator error std (deg)", type="log"), height=480)
    return fig

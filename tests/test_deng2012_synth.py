"""IRSBot-2 dimension-synthesis geometry and the synthesis pipelines (Deng 2012 Ch. II, VII).

Checks the equivalent planar mechanism against the thesis's closed forms (eqs. II.1, II.3-II.8,
II.36-II.38), the largest-rectangle search against brute force, and the study pipeline with a
closed-form stand-in for the clearance engine (the engine itself is exercised in
tests/test_deng2012_synth_engine.py).
"""
from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pandas as pd
import pytest

from evotol.studies import deng2012_dimsynth as ds
from evotol.studies import deng2012_tolsynth as ts
from evotol.robots.geometry import largest_centred_rectangle, largest_rectangle, largest_rectangle_reference
from evotol.robots.irsbot2 import IRSBot2, singularity_free_rectangle
from evotol.units import MM

TAB_VI_5 = dict(l1=50 * MM, l2=50 * MM, a1=30 * MM, a2=15 * MM, p=25 * MM)


def robot(**kw):
    return ds.design_robot(**{**TAB_VI_5, **kw})


def test_l2eq_verified_form_eq_II_1():
    """The distal link spans (a1 - a2) cos(beta) across the elbow plane (eqs. II.16-II.17), so
    |(l2eq cos psi, (a1 - a2) cos beta, -l2eq sin psi)| = l2 -- the printed eq. II.1 (cos beta not
    squared) violates it."""
    l2, a1, a2, beta = 0.1, 0.05, 0.015, math.pi / 4
    verified = IRSBot2.thesis("VI.4", l2=l2, a1=a1, a2=a2, beta=beta).l2eq
    printed = IRSBot2.thesis("VI.4", l2=l2, a1=a1, a2=a2, beta=beta, l2eq_variant="printed").l2eq
    for psi in (0.3, 1.2, 2.5):
        v = np.array([verified * math.cos(psi), (a1 - a2) * math.cos(beta), -verified * math.sin(psi)])
        assert np.linalg.norm(v) == pytest.approx(l2, rel=1e-14)
    assert abs(np.hypot(printed, (a1 - a2) * math.cos(beta)) - l2) > 1e-4


def test_planar_inverse_geometry_closes_the_loops_eqs_II_3_II_4():
    r = robot()
    x = np.linspace(-0.04, 0.04, 9)
    z = np.linspace(-0.085, -0.045, 9)
    X, Z = np.meshgrid(x, z)
    g = r.planar_legs(X, Z)
    assert g["reachable"].all()
    sb = r.a1 * math.sin(r.beta)
    # eq. II.3 (leg 1) and II.4 (leg 2), closed with the returned q_i and psi_i
    x1 = -r.b + r.l1 * np.cos(g["q1"]) + sb + r.l2eq * np.cos(g["psi1"]) + r.p
    z1 = -r.l1 * np.sin(g["q1"]) - r.e - r.l2eq * np.sin(g["psi1"])
    x2 = r.b + r.l1 * np.cos(g["q2"]) - sb + r.l2eq * np.cos(g["psi2"]) - r.p
    z2 = -r.l1 * np.sin(g["q2"]) - r.e - r.l2eq * np.sin(g["psi2"])
    for a, b in ((x1, X), (z1, Z), (x2, X), (z2, Z)):
        np.testing.assert_allclose(a, b, atol=1e-12)
    # elbows outward: leg 1's elbow left of its base point, leg 2's right (for P straight below)
    g0 = r.planar_legs(0.0, -0.07)
    assert g0["E1"][0] < -r.base_x and g0["E2"][0] > r.base_x


def test_actuated_angle_matches_closed_form_eq_II_5():
    """q1 = 2 atan((-B1 ± sqrt(B1² + A1² - C1²)) / (C1 - A1)) -- ours is one of the two roots."""
    r = robot()
    for x, z in ((0.0, -0.07), (0.03, -0.08), (-0.02, -0.06)):
        g = r.planar_legs(x, z)
        u = x + r.b - r.p - r.a1 * math.sin(r.beta)
        A, B = -2 * r.l1 * u, 2 * r.l1 * (z + r.e)
        C = u ** 2 + (z + r.e) ** 2 + r.l1 ** 2 - r.l2eq ** 2
        roots = [2 * math.atan((-B + s * math.sqrt(B * B + A * A - C * C)) / (C - A)) for s in (1, -1)]
        d = [abs((float(g["q1"]) - q + math.pi) % (2 * math.pi) - math.pi) for q in roots]
        assert min(d) < 1e-10


def test_type2_measure_is_det_A_of_eq_II_38():
    """det A = (2 l2eq)² (cos psi1 sin psi2 - sin psi1 cos psi2) = -(2 l2eq)² sin(psi1 - psi2)."""
    r = robot()
    X, Z = np.meshgrid(np.linspace(-0.05, 0.05, 7), np.linspace(-0.09, -0.03, 7))
    g = r.planar_legs(X, Z)
    L = r.l2eq
    detA = (2 * L * np.cos(g["psi1"])) * (2 * L * np.sin(g["psi2"])) - (2 * L * np.sin(g["psi1"])) * (2 * L * np.cos(g["psi2"]))
    ok = g["reachable"]
    np.testing.assert_allclose(detA[ok], -(2 * L) ** 2 * g["sin_t2"][ok], atol=1e-15)


def _largest_by_brute_force(m, centre=None) -> int:
    """Largest all-True rectangle (cell spans) by trying every one; ``centre``: only the rectangles
    symmetric about that column."""
    best = 0
    for r0, r1 in itertools.combinations_with_replacement(range(m.shape[0]), 2):
        for c0, c1 in itertools.combinations_with_replacement(range(m.shape[1]), 2):
            if (centre is None or c0 + c1 == 2 * centre) and m[r0:r1 + 1, c0:c1 + 1].all():
                best = max(best, (r1 - r0) * (c1 - c0))
    return best


@pytest.mark.parametrize("centre", [None, 5])
def test_largest_rectangle_matches_brute_force(centre):
    """evotol.robots.geometry: the histogram algorithm (and its centred reduction) against every rectangle."""
    rng = np.random.default_rng(3)
    for _ in range(30):
        m = rng.random((8, 11)) < 0.8
        if centre is None:
            area, r0, r1, c0, c1 = largest_rectangle(m)
        else:
            area, r0, r1, half = largest_centred_rectangle(m, centre)
            c0, c1 = centre - half, centre + half
        assert area == _largest_by_brute_force(m, centre)
        if area:
            assert m[r0:r1 + 1, c0:c1 + 1].all() and (r1 - r0) * (c1 - c0) == area


def test_compiled_largest_rectangle_is_the_python_one_result_for_result():
    """The numba kernel (issue 43) returns what the Python histogram stack returns -- area, rows and
    columns, ties included -- on random masks of every density and shape, empty ones, and the
    IRSBot-2's own singularity-free masks."""
    rng = np.random.default_rng(7)
    masks = [rng.random(tuple(rng.integers(1, 25, 2))) < rng.uniform(0.2, 1.0) for _ in range(400)]
    masks += [np.zeros((0, 5), bool), np.zeros((4, 0), bool), np.ones((1, 1), bool), np.ones((6, 9), bool)]
    r = robot()
    for n in (41, 81):
        reach = r.l1 + r.l2
        X, Z = np.meshgrid(np.linspace(-reach, reach, n), np.linspace(-reach - r.e, -r.e, n))
        g = r.planar_legs(X, Z)
        s = math.sin(math.radians(2.0))
        masks.append(g["reachable"] & (g["sin_t2"] <= -s) & (np.abs(g["sin_t1_1"]) >= s) & (np.abs(g["sin_t1_2"]) >= s))
    for m in masks:
        assert largest_rectangle(m) == largest_rectangle_reference(m), m.shape
    assert sum(largest_rectangle(m)[0] > 0 for m in masks[-2:]) == 2        # the robot's masks have a rectangle


def test_largest_rectangle_without_numba_is_the_python_one(hide_numba):
    """numba missing: the search falls back to the Python histogram stack, same results."""
    from evotol.robots import geometry

    hide_numba(geometry._compiled)
    assert geometry._compiled() is None
    m = np.random.default_rng(1).random((30, 40)) < 0.9
    assert largest_rectangle(m) == largest_rectangle_reference(m) and largest_rectangle(m)[0] > 0


def test_sub_workspace_is_symmetric_singularity_free_and_grows_with_the_links():
    r = robot()
    w = singularity_free_rectangle(r, n=121)
    assert w.area > 0
    assert w.x[0] == pytest.approx(-w.x[1], abs=w.step)                # the robot is symmetric in x
    # every grid point of the rectangle is reachable and off the singular loci
    xs = np.linspace(*w.x, 15)
    zs = np.linspace(*w.z, 15)
    X, Z = np.meshgrid(xs, zs)
    g = r.planar_legs(X, Z)
    s = math.sin(math.radians(2.0))
    assert g["reachable"].all() and (g["sin_t2"] <= -s + 1e-9).all()
    assert (np.abs(g["sin_t1_1"]) >= s - 1e-9).all() and (np.abs(g["sin_t1_2"]) >= s - 1e-9).all()
    # Fig. VII.10: right-down corner, centre, left-up corner
    np.testing.assert_allclose(w.points, [[w.x[1], w.z[0]], [0.0, (w.z[0] + w.z[1]) / 2], [w.x[0], w.z[1]]], atol=1e-12)
    # longer links, larger sub-workspace (Fig. VII.12: l1 = l2 = 200 mm give the largest)
    big = singularity_free_rectangle(robot(l1=0.2, l2=0.2), n=121)
    assert big.area > 4 * w.area


def serial_standin(robot, points):
    """Closed-form stand-in for the engine: 6 joint plays of 0.1 mm plus a 0.01 rad tilt times the
    lever arm to the base (a serial-chain bound), and r = 4 x 0.01 rad."""
    lever = np.hypot(points[:, 0], points[:, 1])
    return 6 * 0.1 * MM + 0.01 * lever, np.full(len(points), 0.04)


def test_dimsynth_pipeline_with_a_closed_form_standin(tmp_path):
    ds.STUDY.run(tmp_path, quick=True, workers=1, pose_errors=serial_standin, progress=False)
    saved = json.loads((tmp_path / "deng2012-dimsynth.json").read_text())
    df = pd.read_parquet(tmp_path / saved["files"]["entries_parquet"])
    assert len(df) == 8 and df["entry"].is_unique
    for name, res in saved["presets"].items():
        assert res["count"] == len(df.query(res["query"]))
        assert saved["presets_shown_in_report"][name] == res["count"] + sum(
            1 for _ in pd.read_parquet(tmp_path / saved["files"]["pareto_parquet"]).query(res["query"]).index)
    # the objectives are the maximum over the three points of Fig. VII.10
    ok = df[df["feasible"]]
    np.testing.assert_allclose(ok["p_max_mm"], ok[["p_rd_mm", "p_c_mm", "p_lu_mm"]].max(axis=1))
    lever = np.hypot(ok[["x1_mm", "x0_mm"]].abs().max(axis=1), ok[["z0_mm", "z1_mm"]].abs().max(axis=1))
    assert (ok["p_max_mm"] <= 0.6 + 0.01 * lever + 1e-9).all()
    from evotol.reporting.html import plotlyjs_name
    page = (tmp_path / "deng2012-dimsynth.html").read_text()
    assert f'src="{plotlyjs_name()}"' in page and (tmp_path / plotlyjs_name()).stat().st_size > 1e6


def test_tolsynth_factors_and_presets_follow_sec_VII_1_2():
    f = ts.factors()
    assert [x.levels for x in f[:5]] == [(1e-4, 1e-3, 1e-2, 1e-1)] * 5
    assert [x.levels for x in f[5:]] == [(1e-3, 1e-1)] * 5
    assert [p.figure for p in ts.presets()] == [f"Fig. VII.{k}" for k in range(3, 9)]
    # eq. III.2: Δβ_xy = Δb_xy / h on every joint; Δβ_z 0 on A, B (actuated), 0.2 rad on C, D, E
    ev = ts.FiveBarToleranceEvaluator(h_mm=10.0)
    X = pd.DataFrame({x.name: [x.levels[-1]] for x in f})
    B = ev.bounds(X)
    np.testing.assert_allclose(B[0, :, 0], 0.1 * MM / (10 * MM))
    assert sorted(B[0, :, 1].tolist()) == [0.0, 0.0, 0.2, 0.2, 0.2]

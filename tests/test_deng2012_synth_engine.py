"""The synthesis studies on the certified clearance engine (Deng 2012 Sec. VII.1.2, Fig. VII.2).

* the extreme entries of the 5-bar factorial bracket the thesis's ranges [0.0038, 1.41] mm and
  [0.0024, 1.38] deg (the thesis's 1000 entries are a subset of the factorial), and with
  h = 10 mm the largest rotational error matches the thesis's 1.38 deg within 1 %;
* enlarging any one clearance never lowers the maximum error (the feasible set grows), and ten
  times every clearance gives ten times the maximum (the first-order model is linear);
* our certified maximum is never below the thesis's own multistart method, equals it on the
  rotation and is 2.7 times its position maximum at one entry (the multistart stops at a local one);
* the quick study writes JSON whose preset counts equal a pandas query of the written entries.
"""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from evotol import design as doe  # noqa: E402
from evotol.studies import deng2012_tolsynth as ts  # noqa: E402
from evotol.units import MM, numbers_without_unit  # noqa: E402


def entry(xy, z):
    """One entry with all Δb_xy = xy and all Δb_z = z (mm); scalars or per-joint lists."""
    xy = np.broadcast_to(xy, 5)
    z = np.broadcast_to(z, 5)
    return {**{f"db_xy_{j}_mm": v for j, v in zip(ts.JOINTS, xy)}, **{f"db_z_{j}_mm": v for j, v in zip(ts.JOINTS, z)}}


@pytest.fixture(scope="module")
def ev():
    return ts.FiveBarToleranceEvaluator()


def test_extreme_entries_bracket_the_thesis_ranges_fig_VII_2(ev):
    X = pd.DataFrame([entry(1e-4, 1e-3), entry(1e-1, 1e-1)])
    out = ev(X)
    lo, hi = out.iloc[0], out.iloc[1]
    assert lo["p_max_mm"] <= ts.THESIS_RANGES["p_max_mm"][0] and hi["p_max_mm"] >= ts.THESIS_RANGES["p_max_mm"][1]
    assert lo["r_max_deg"] <= ts.THESIS_RANGES["r_max_deg"][0] and hi["r_max_deg"] >= ts.THESIS_RANGES["r_max_deg"][1]
    assert hi["r_max_deg"] == pytest.approx(1.38, rel=0.01)            # h = 10 mm
    # certificate: attained <= certified bound, gap <= 0.1 %
    assert (out["p_upper_mm"] >= out["p_max_mm"]).all() and (out["p_upper_mm"] <= out["p_max_mm"] * 1.001).all()
    assert (out["r_upper_deg"] <= out["r_max_deg"] * 1.001).all()


def test_maximum_error_grows_with_every_clearance(ev):
    rng = np.random.default_rng(0)
    f = ts.factors()
    base = doe.random_subset(f, 12, seed=5).drop(columns="entry").reset_index(drop=True)
    rows = []
    for _, r in base.iterrows():
        k = rng.integers(len(f))
        fac = f[k]
        lv = fac.levels.index(r[fac.name])
        if lv + 1 < len(fac.levels):
            up = r.copy()
            up[fac.name] = fac.levels[lv + 1]
            rows += [r, up]
    X = pd.DataFrame(rows).reset_index(drop=True)
    out = ev(X)
    small, big = out.iloc[0::2].reset_index(drop=True), out.iloc[1::2].reset_index(drop=True)
    assert (big["p_max_mm"] >= small["p_max_mm"] * (1 - 1e-3)).all()
    assert (big["r_max_deg"] >= small["r_max_deg"] * (1 - 1e-3)).all()
    # and the number: the first-order feasible set scales with the clearances (Deng 2012 eqs.
    # III.24-III.26 are linear in the error screws), so ten times every clearance gives exactly ten
    # times both maxima -- equal within the certificate's 0.1 % gap (measured: 1 + 8e-8)
    base_rows = X.iloc[0::2].reset_index(drop=True)
    ten = ev(base_rows * 10.0)
    for col in ("p_max_mm", "r_max_deg"):
        np.testing.assert_allclose(ten[col].to_numpy(), 10.0 * small[col].to_numpy(), rtol=1e-3)


def test_never_below_the_thesis_multistart_method(ev):
    from evotol.robots.clearance import multistart_max_pose_error

    X = pd.DataFrame([entry([0.1, 1e-3, 0.01, 1e-4, 0.1], [0.1, 1e-3, 1e-3, 0.1, 1e-3])])
    ours = ev(X).iloc[0]
    model = ev._model()
    ms = multistart_max_pose_error(model.mech, model.poses, ev.bounds(X)[0], n_starts=4, seed=1)
    assert ours["p_max_mm"] >= ms.p_max[0] / MM * (1 - 1e-6)
    assert ours["r_max_deg"] >= np.degrees(ms.r_max[0]) * (1 - 1e-6)
    # the numbers: on the rotation both methods find the same maximum (0.66495 deg, to 1e-6); on the
    # position the thesis's 4 local solves stop at 0.119 mm, a local maximum 2.7 times below the
    # certified 0.3224 mm (our attained value is an assembled configuration, so the multistart is
    # the one that misses)
    assert ours["r_max_deg"] == pytest.approx(np.degrees(ms.r_max[0]), rel=1e-6)
    assert ours["p_upper_mm"] <= ours["p_max_mm"] * (1 + 1e-3)
    assert ms.p_max[0] / MM < 0.5 * ours["p_max_mm"]


def test_quick_study_writes_json_entries_and_report(tmp_path):
    s = ts.STUDY.run(tmp_path, quick=True, workers=1, progress=False)
    saved = json.loads((tmp_path / f"{ts.NAME}.json").read_text())
    assert numbers_without_unit(saved, saved["units"]) == []  # docs/units.md (issue 15)
    df = pd.read_parquet(tmp_path / saved["files"]["entries_parquet"])
    # 256 distinct factorial entries, each evaluated once
    assert len(df) == 256 and df["entry"].is_unique and s["n_entries"] == 256
    assert set(saved["presets"]) == {p.name for p in ts.presets()}
    for name, res in saved["presets"].items():
        kept = df.query(res["query"])
        assert res["count"] == len(kept)
        for c, rg in res["ranges"].items():
            if len(kept):
                assert rg["levels"] == sorted(kept[c].unique().tolist())
    assert saved["certificate_gap_max"] <= 1e-3
    assert any("Δb_z" in line for line in saved["findings"])
    html = (tmp_path / f"{ts.NAME}.html").read_text()
    assert "Fig. VII.5" in html and 'id="pc-count-n"' in html
    # render() reads only the written JSON and tables: redrawing from them gives the same page
    from evotol.studies import StudyResult

    tables = {k: pd.read_parquet(tmp_path / f"{ts.NAME}_{k}.parquet") for k in ("entries", "pareto")}
    assert ts.STUDY.render(StudyResult(saved, tables)).render() == html
    # resuming: a second run reuses every chunk
    s2 = ts.STUDY.run(tmp_path, quick=True, workers=1, progress=False)
    assert s2["evaluation"]["chunks_resumed"] == s2["evaluation"]["chunks"]


# --------------------------------------------------------------------------- IRSBot-2 (Sec. VII.2.2)
def test_planar_geometry_agrees_with_the_inverse_geometry():
    """Two independent inverse geometries of one model: IRSBot2.planar_legs (circle intersection)
    and IRSBot2.inverse_geometry (eqs. II.5-II.8)."""
    from evotol.studies import deng2012_dimsynth as ds
    from evotol.robots.irsbot2 import singularity_free_rectangle

    rng = np.random.default_rng(1)
    for d in [(50, 50, 30, 15, 25), (200, 100, 50, 15, 15), (100, 200, 10, 30, 40)]:
        robot = ds.design_robot(*(np.array(d) * MM))
        w = singularity_free_rectangle(robot, n=81)
        P = np.column_stack([rng.uniform(*w.x, 20), rng.uniform(*w.z, 20)])
        g, h = robot.planar_legs(P[:, 0], P[:, 1]), robot.inverse_geometry(P)
        for k in ("q1", "q2", "psi1", "psi2"):
            np.testing.assert_allclose(np.angle(np.exp(1j * (g[k] - h[k]))), 0, atol=1e-12)
        np.testing.assert_allclose(g["sin_t2"], robot.parallel_singularity(P), atol=1e-12)


def test_batched_engine_call_equals_one_call_per_design():
    from evotol.studies import deng2012_dimsynth as ds
    from evotol.robots.irsbot2 import singularity_free_rectangle

    robots = [ds.design_robot(*(np.array(d) * MM)) for d in [(50, 50, 30, 15, 25), (200, 100, 50, 5, 15)]]
    pts = [singularity_free_rectangle(r, n=81).points for r in robots]
    batch = ds.engine_pose_errors_batch(robots, pts)
    for r, pt, (pb, rb) in zip(robots, pts, batch):
        p1, r1 = ds.engine_pose_errors(r, pt)
        np.testing.assert_allclose(pb, p1, rtol=2e-3)        # both within the 0.1 % certificate
        np.testing.assert_allclose(rb, r1, rtol=2e-3)
    # clearances in the parallelograms add error sources (Sec. VI.3): distal-only is never larger
    from evotol.robots.clearance import max_pose_error

    distal, _, _ = ds.clearance_bounds()
    distal_only = max_pose_error(robots[0].clearance_mechanism(parallelograms=False, distal=distal), pts[0])
    assert (distal_only.p_max <= batch[0][0] * (1 + 2e-3)).all()


def test_quick_dimsynth_on_the_engine(tmp_path):
    from evotol.studies import deng2012_dimsynth as ds

    ds.STUDY.run(tmp_path, quick=True, workers=1, progress=False)
    saved = json.loads((tmp_path / f"{ds.NAME}.json").read_text())
    assert numbers_without_unit(saved, saved["units"]) == []  # docs/units.md (issue 15)
    df = pd.read_parquet(tmp_path / saved["files"]["entries_parquet"])
    assert len(df) == 8 and df["feasible"].all() and df["entry"].is_unique
    for name, res in saved["presets"].items():
        assert res["count"] == len(df.query(res["query"]))
    # the same order of magnitude as the thesis's ranges (mm, deg)
    assert 1 < saved["objective_ranges"]["p_max_mm"][0] and saved["objective_ranges"]["p_max_mm"][1] < 100
    assert 1 < saved["objective_ranges"]["r_max_deg"][0] and saved["objective_ranges"]["r_max_deg"][1] < 60
    assert len(saved["thesis_designs"]) == 2


def test_thesis_range_endpoints_are_values_of_our_factorial(ev):
    """Fig. VII.2's endpoints are taken by specific entries of ours: p_max 0.0038 mm (Δb_xy,E = 1e-3,
    others 1e-4; the second smallest value, reached when a sample misses the 8 entries below it),
    p_max 1.41 mm (all Δb_xy = 0.1, Δb_z = 0.1 on A, C, E), r_max 0.0024° (Δb_xy,B = 1e-3, others
    1e-4) and r_max 1.38° (all Δb_xy = 0.1)."""
    X = pd.DataFrame([entry([1e-4, 1e-4, 1e-4, 1e-4, 1e-3], 1e-3),
                      entry(0.1, [0.1, 0.1, 1e-3, 1e-3, 0.1]),
                      entry([1e-4, 1e-4, 1e-3, 1e-4, 1e-4], 1e-3)])
    out = ev(X)
    assert out.loc[0, "p_max_mm"] == pytest.approx(0.0038, rel=0.01)
    assert out.loc[1, "p_max_mm"] == pytest.approx(1.41, rel=0.001)
    assert out.loc[2, "r_max_deg"] == pytest.approx(0.0024, rel=0.03)


def test_thesis_endpoints_probability_of_missing_the_extremes():
    """P(a 1000-of-N sample misses k given entries) = prod_{i<k} (N - 1000 - i) / (N - i)."""
    N = 32768
    v = np.r_[np.full(8, 0.0034), np.full(24, 0.0038), np.linspace(0.01, 1.3, N - 32 - 1), 1.38]
    df = pd.DataFrame({"p_max_mm": v, "r_max_deg": v})
    e = ts.thesis_endpoints(df)["p_max_mm_min"]
    assert e["ours_nearest"] == pytest.approx(0.0038) and e["n_entries_beyond"] == 8 and e["rank_from_the_end"] == 2
    assert e["probability_sample_misses_those_beyond"] == pytest.approx((1 - 1000 / N) ** 8, rel=1e-3)

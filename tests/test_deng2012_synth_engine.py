"""The synthesis studies on the certified clearance engine (Deng 2012 Sec. VII.1.2, Fig. VII.2).

* the extreme entries of the 5-bar factorial bracket the thesis's ranges [0.0038, 1.41] mm and
  [0.0024, 1.38] deg (the thesis's 1000 entries are a subset of the factorial), and with
  h = 10 mm the largest rotational error matches the thesis's 1.38 deg within 1 %;
* enlarging any one clearance never lowers the maximum error (the feasible set grows);
* our certified maximum is never below the thesis's own multistart method;
* the quick study writes JSON whose preset counts equal a pandas query of the written entries.
"""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("robots.fivebar", reason="the 5-bar clearance engine (issue 6) is not in this checkout")

from evotol import doe  # noqa: E402
from evotol.studies import deng2012_tolsynth as ts  # noqa: E402

MM = 1e-3


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


def test_never_below_the_thesis_multistart_method(ev):
    from robots.clearance import multistart_max_pose_error

    X = pd.DataFrame([entry([0.1, 1e-3, 0.01, 1e-4, 0.1], [0.1, 1e-3, 1e-3, 0.1, 1e-3])])
    ours = ev(X).iloc[0]
    model = ev._model()
    ms = multistart_max_pose_error(model.mech, model.poses, ev.bounds(X)[0], n_starts=6, seed=1)
    assert ours["p_max_mm"] >= ms.p_max[0] / MM * (1 - 1e-6)
    assert ours["r_max_deg"] >= np.degrees(ms.r_max[0]) * (1 - 1e-6)


def test_quick_study_writes_json_entries_and_report(tmp_path):
    s = ts.run(tmp_path, quick=True, workers=1, progress=False)
    saved = json.loads((tmp_path / f"{ts.NAME}.json").read_text())
    df = pd.read_parquet(tmp_path / saved["files"]["entries_parquet"])
    assert len(df) == 256 and saved["seconds"] > 0 and s["n_entries"] == 256
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
    # resuming: a second run reuses every chunk
    s2 = ts.run(tmp_path, quick=True, workers=1, progress=False)
    assert s2["evaluation"]["chunks_resumed"] == s2["evaluation"]["chunks"]

"""Filtering evaluated entries (evotol.design.filtering, ``evotol filter``; Deng 2012 Figs. VII.3-VII.8).

Counts are checked against numpy masks of the same data; kept level sets against the closed
form of a serial chain (see tests/test_doe.py): with p = sqrt((Σ Δb_xy)² + (Σ Δb_z)²) a filter
p <= c keeps exactly the level combinations that satisfy it.
"""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from evotol import design as doe
from evotol.cli import main
from evotol.errors import ValidationError
from evotol.design.filtering import DesignStudy, Preset, main_effects, resolve_query


def thesis_factors(n_joints: int):
    """Δb_xy on the 4 levels and Δb_z on the 2 levels of Deng 2012 Sec. VII.1.2 (mm)."""
    xy = [doe.Factor(f"db_xy_{j}_mm", (1e-4, 1e-3, 1e-2, 1e-1), log=True, si_scale=1e-3) for j in "ABCDE"[:n_joints]]
    z = [doe.Factor(f"db_z_{j}_mm", (1e-3, 1e-1), log=True, si_scale=1e-3) for j in "ABCDE"[:n_joints]]
    return xy + z


class SerialChainClearance:
    """p_max (mm) = sqrt((Σ Δb_xy)² + (Σ Δb_z)²): translational clearances of a serial chain."""

    def __call__(self, X):
        xy = X[[c for c in X if c.startswith("db_xy")]].to_numpy().sum(1)
        z = X[[c for c in X if c.startswith("db_z")]].to_numpy().sum(1)
        return pd.DataFrame({"p_max_mm": np.hypot(xy, z), "p_xy_mm": xy})


@pytest.fixture(scope="module")
def study():
    E = doe.full_factorial(thesis_factors(3))
    df = doe.evaluate(E, SerialChainClearance(), workers=1, progress=False)
    df["r_max_deg"] = np.degrees(df["p_xy_mm"] / 10.0)      # a second objective in deg
    df.attrs["evotol"]["objectives"] = ["p_max_mm", "p_xy_mm", "r_max_deg"]
    return DesignStudy(df, presets=[Preset("p_max <= 0.05 mm", {"p_max_mm": (None, 0.05)}, "Fig. VII.4"),
                                    Preset("p_max >= 0.1 mm", {"p_max_mm": (0.1, None)}, "Fig. VII.3")])


def test_filter_counts_match_numpy_masks(study):
    df = study.entries
    r = study.filter("p_max <= 0.05 and r_max_deg <= 0.05")
    mask = (df["p_max_mm"] <= 0.05) & (df["r_max_deg"] <= 0.05)
    assert r.count == int(mask.sum()) and r.total == len(df) == 512
    assert r.resolved_query == "p_max_mm <= 0.05 and r_max_deg <= 0.05"
    assert r.kept["entry"].tolist() == df.loc[mask, "entry"].tolist()
    assert study.filter("p_max >= 0.1 mm").count == int((df["p_max_mm"] >= 0.1).sum())


def test_kept_levels_are_what_the_closed_form_allows(study):
    """p <= 0.05 mm needs every Δb_xy < 0.1 and every Δb_z = 1e-3 (3 x 0.1 > 0.05)."""
    r = study.filter("p_max <= 0.05")
    for j in "ABC":
        assert r.ranges[f"db_xy_{j}_mm"]["levels"] == [1e-4, 1e-3, 1e-2]
        assert r.ranges[f"db_z_{j}_mm"]["levels"] == [1e-3]
    # the kept objective range is inside the filter
    assert r.objective_ranges["p_max_mm"]["max"] <= 0.05
    json.dumps(r.to_dict())                     # JSON-ready


def test_resolve_query_units_and_errors():
    cols = ["p_max_mm", "r_max_deg", "db_xy_A_mm", "area_mm2"]
    assert resolve_query("p_max <= 0.05 and r_max <= 1", cols) == "p_max_mm <= 0.05 and r_max_deg <= 1"
    assert resolve_query("area >= 4e4", cols) == "area_mm2 >= 4e4"
    assert resolve_query("db_xy_A_mm == 0.1", cols) == "db_xy_A_mm == 0.1"
    assert resolve_query("p_max_mm < 1e-2 or not (r_max_deg > 0.5)", cols) == "p_max_mm < 1e-2 or not (r_max_deg > 0.5)"
    with pytest.raises(ValidationError, match="a column of the entries"):
        resolve_query("q_max <= 1", cols)
    with pytest.raises(ValidationError, match="ambiguous"):
        resolve_query("p <= 1", ["p_mm", "p_deg"])


def test_bad_query_is_a_validation_error(study):
    with pytest.raises(ValidationError, match="query"):
        study.filter("p_max_mm <=")


def test_main_effects_of_an_additive_log_model():
    """log10 y = Σ c_j log10 x_j on a full factorial: main effect_j = c_j x (decades of x_j)."""
    f = [doe.Factor("a", (1e-3, 1e-2, 1e-1)), doe.Factor("b", (1e-3, 1e-1)), doe.Factor("c", (1.0, 10.0))]
    E = doe.full_factorial(f)
    E["y"] = E["a"] ** 1.0 * E["b"] ** 0.25 * E["c"] ** 0.0
    me = main_effects(E, ["a", "b", "c"], "y").set_index("input")
    np.testing.assert_allclose(me.loc["a", "effect"], 2.0, rtol=1e-12)
    np.testing.assert_allclose(me.loc["b", "effect"], 0.5, rtol=1e-12)
    np.testing.assert_allclose(me.loc["c", "effect"], 0.0, atol=1e-12)
    assert list(me.index) == ["a", "b", "c"]


def test_cli_filter_prints_counts_and_ranges(tmp_path, study, capsys):
    paths = study.save(tmp_path / "entries")
    out_json, out_csv = tmp_path / "kept.json", tmp_path / "kept.csv"
    code = main(["filter", str(paths["parquet"]), "p_max <= 0.05 and r_max_deg <= 0.05",
                 "--summary", str(out_json), "--out", str(out_csv)])
    text = capsys.readouterr().out
    expected = study.filter("p_max <= 0.05 and r_max_deg <= 0.05")
    assert code == 0
    assert f"{expected.count} of 512 entries kept" in text
    assert "db_z_A_mm" in text and "levels 0.001" in text
    summary = json.loads(out_json.read_text())
    assert summary["count"] == expected.count and summary["ranges"]["db_z_A_mm"]["levels"] == [0.001]
    assert len(pd.read_csv(out_csv)) == expected.count


def test_cli_filter_on_a_csv_needs_or_infers_columns(tmp_path, study, capsys):
    paths = study.save(tmp_path / "entries")
    code = main(["filter", str(paths["csv"]), "p_max_mm >= 0.1", "--objectives", "p_max_mm,p_xy_mm,r_max_deg",
                 "--show", "0"])
    assert code == 0
    assert f"{study.filter('p_max_mm >= 0.1').count} of 512" in capsys.readouterr().out
    assert main(["filter", str(tmp_path / "missing.parquet"), "p_max <= 1"]) == 2


def test_cli_filter_writes_a_report_of_the_kept_entries(tmp_path, study):
    paths = study.save(tmp_path / "entries")
    out = tmp_path / "kept.html"
    assert main(["filter", str(paths["parquet"]), "p_max <= 0.05", "--html", str(out), "--show", "0"]) == 0
    html = out.read_text()
    n = study.filter("p_max <= 0.05").count
    assert f'<span id="pc-count-n">{n}</span> of {n} entries kept' in html


def test_cli_filter_keeping_nothing_says_so_and_writes_no_report(tmp_path, study, capsys):
    paths = study.save(tmp_path / "entries")
    out = tmp_path / "none.html"
    assert main(["filter", str(paths["parquet"]), "p_max_mm < 0", "--html", str(out)]) == 0
    text = capsys.readouterr()
    assert "0 of 512 entries kept (no entry satisfies the query" in text.out
    assert "no report written" in text.err and not out.exists()      # a message: standard error


def test_main_effects_without_inputs_is_a_validation_error():
    """main_effects with no input column (or one not in the entries) is a one-line ValidationError
    naming ``inputs``, not a KeyError from sorting an empty table."""
    E = pd.DataFrame({"a": [1.0, 2.0], "y": [1.0, 10.0]})
    with pytest.raises(ValidationError) as ei:
        main_effects(E, [], "y")
    assert str(ei.value) == "inputs = []: expected one or more columns of ['a', 'y']"
    with pytest.raises(ValidationError, match=r"inputs = \['b'\]"):
        main_effects(E, ["b"], "y")


def test_main_effects_quartiles_drop_bins_left_empty_by_ties():
    """Continuous inputs, quartile bins: 30 ties at 0 make the first two quantile edges coincide;
    the two empty bins are dropped (levels 0 and 8, means 3/32 and 8, no NaN, no numpy warning).
    Without ties the four bins are unchanged: x = y = 0..19 gives medians and means 2, 7, 12, 17."""
    import warnings

    x = np.r_[np.zeros(30), np.arange(1.0, 14.0)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        me = main_effects(pd.DataFrame({"x": x, "y": x}), ["x"], "y", log=False).iloc[0]
    assert me["levels"] == [0.0, 8.0]
    np.testing.assert_allclose(me["level_means"], [3 / 32, 8.0], rtol=1e-15)
    np.testing.assert_allclose(me["effect"], 8.0 - 3 / 32, rtol=1e-15)

    x = np.arange(20.0)
    me = main_effects(pd.DataFrame({"x": x, "y": x}), ["x"], "y", log=False).iloc[0]
    assert me["levels"] == [2.0, 7.0, 12.0, 17.0] and me["level_means"] == [2.0, 7.0, 12.0, 17.0]
    assert me["effect"] == 15.0


def test_cli_filter_json_is_a_flag_and_the_old_file_form_still_works(tmp_path, study, capsys):
    """``--json`` prints the summary as JSON on stdout (as on describe and check-*; issue 40), its
    count the one pandas' own query gives on the saved table; ``--json FILE`` (the old form) still
    writes FILE, with a deprecation message on stderr."""
    paths = study.save(tmp_path / "entries")
    direct = len(pd.read_parquet(paths["parquet"]).query("p_max_mm <= 0.05 and r_max_deg <= 0.05"))
    assert main(["filter", str(paths["parquet"]), "p_max <= 0.05 and r_max_deg <= 0.05", "--json"]) == 0
    out = capsys.readouterr()
    printed = json.loads(out.out)                 # stdout is the JSON alone
    assert printed["count"] == direct and printed["total"] == 512 and out.err == ""
    old = tmp_path / "old.json"
    assert main(["filter", str(paths["parquet"]), "p_max <= 0.05 and r_max_deg <= 0.05", "--json", str(old)]) == 0
    out = capsys.readouterr()
    assert "deprecated" in out.err and f"--summary {old}" in out.err
    assert json.loads(old.read_text())["count"] == direct and "entries kept" in out.out
    assert main(["filter", str(paths["parquet"]), "p_max <= 0.05", "--json", "kept.csv"]) == 2
    assert "--json" in capsys.readouterr().err

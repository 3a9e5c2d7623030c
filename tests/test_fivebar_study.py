"""Study deng2012-5bar (quick run): JSON keys of the issue, thesis statements of Sec. IV.3-IV.4."""
import json

import numpy as np
import pytest


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    from evotol.studies import get

    out = tmp_path_factory.mktemp("d5")
    data = get("deng2012-5bar").run(out, quick=True, seed=0)
    return out, data


def test_json_has_the_issue_keys_and_shapes(study):
    out, data = study
    saved = json.loads((out / "deng2012-5bar.json").read_text())
    n = len(saved["x"])
    assert n == len(saved["y"]) == saved["grid"]
    for key in ("x", "y", "p_max", "r_max", "leg1", "leg2", "redundant", "gap_max", "seconds"):
        assert key in saved
    for block in (saved, saved["leg1"], saved["leg2"], saved["redundant"]):
        for k in ("p_max", "r_max"):
            arr = np.array(block[k], float)
            assert arr.shape == (n, n) and np.all(np.isfinite(arr))      # values on the singularity, no NaN
    assert saved["gap_max"] <= 1e-3
    assert saved["x"][0] == -20 and saved["y"][-1] == 70                  # mm


def test_rows_are_y_and_columns_are_x(study):
    """Row index = y, column = x: the map is symmetric in columns (x -> -x), not in rows."""
    _, data = study
    R = np.array(data["r_max"])
    assert np.allclose(R, R[:, ::-1], rtol=1e-6)
    assert not np.allclose(R, R[::-1, :], rtol=1e-2)


def test_thesis_statements_sec_IV4(study):
    """Figs. IV.10, IV.12, IV.14: constant rotational maxima 0.02, 0.03, 0.02 rad; the positional
    map is only nearly symmetric (joint E belongs to leg 2); sampling falls short."""
    _, data = study
    tc = data["thesis_claims"]
    assert np.allclose(tc["leg1_r_max_constant_rad"], 0.02, rtol=1e-9)
    assert np.allclose(tc["leg2_r_max_constant_rad"], 0.03, rtol=1e-9)
    assert np.allclose(tc["redundant_r_max_rad"], 0.02, rtol=1e-6)
    sym = data["symmetry"]
    assert sym["r_max_relative_difference"] < 1e-6 and 1e-3 < sym["p_max_relative_difference"] < 0.1
    assert sym["p_asymmetry_certified_points"] > 0
    assert data["monte_carlo"]["worst_ratio"] < 0.95
    sing = data["singularity"]
    assert sing["most_singular_grid_point_mm"] == [0.0, 50.0] and np.isfinite(sing["p_max_at_most_singular_grid_point_mm"])


def test_never_below_multistart_and_html_offline(study):
    out, data = study
    for pt in data["multistart_baseline"]["points"]:
        assert pt["p_upper_mm"] >= pt["multistart_p_mm"] * (1 - 1e-9)
        assert pt["p_max_mm"] >= pt["multistart_p_mm"] * (1 - 1e-3)
    html = (out / "deng2012-5bar.html").read_text()
    assert "<script src=\"http" not in html and "parallel singularity" in html


def test_report_is_drawn_from_the_json_alone(study):
    """render() reads only the written JSON: redrawing from it gives the same page, byte for byte."""
    from evotol.studies import StudyResult, get

    out, _ = study
    d = json.loads((out / "deng2012-5bar.json").read_text())
    assert get("deng2012-5bar").render(StudyResult(d)).render() == (out / "deng2012-5bar.html").read_text()


def test_every_number_in_the_json_has_a_unit(study):
    """docs/units.md: the file's ``units`` block resolves the unit of every number (issue 15)."""
    from evotol.units import numbers_without_unit

    data = study[1]
    assert data["units"]["keys"] and numbers_without_unit(data, data["units"]) == []

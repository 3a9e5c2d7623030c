"""The yao2013 study end to end (quick run): JSON keys of the issue, paper numbers, HTML offline."""
import json

import pytest

from evotol.cli import main


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("yao")
    assert main(["reproduce", "yao2013", "--out", str(out), "--quick"]) == 0
    return out, json.loads((out / "yao2013.json").read_text())


def test_json_has_the_issue_keys(study):
    _, d = study
    assert d["paper_table1_cost"] == pytest.approx(2.18, abs=0.01)
    assert d["paper_table2_cost"] == pytest.approx(4.24, abs=0.01)
    for variant in ("paper", "verified"):
        v = d["variants"][variant]
        assert v["accuracy_measure"] == "rss"
        # the certified optimum is no dearer than the GA or the sensitivity rule on the same problem
        assert 0 < v["optimum_cost"] <= min(v["ga_cost"], v["sensitivity_cost"]) * (1 + 1e-9)
        for k in ("ga", "sensitivity", "optimum"):
            assert len(v["tolerances"][k]) == 12
            # the three allocations meet the RSS requirement (Yao 2013: 0.05 mm)
            assert v[k]["rss_error"] <= 5e-5 * (1 + 1e-9)
        for k in ("paper_table1", "paper_table2", "ga", "sensitivity", "optimum"):
            # worst case (sum of |contributions|) >= RSS (their root sum of squares), same tolerances
            assert v[k]["worst_case_error"] >= v[k]["rss_error"] > 0
            assert 0 <= v[k]["mc_max_exceed_rate"] <= 1
        assert v["ga_cost"] <= v["optimum_cost"] * 1.005


def test_paper_comparison_under_the_paper_model(study):
    """Sensitivity (collective lengths, the rule behind Table 2) over the GA: the paper's 1.94
    (Table 2 / Table 1 = 4.2391 / 2.1837) is reproduced to 1 % against the paper's own GA design
    (measured 4.2053 / 2.1846 = 1.925: the rule's cost is Table 2's to 0.8 %, Table 1's cost
    recomputed to 0.04 %). Against evotol's GA the ratio is 2.094, not 1.94: that GA reaches the
    certified optimum (2.0086), which the paper's Table 1 exceeds by 8.8 %; the ratio is the rule
    over the optimum to 0.1 %."""
    _, d = study
    v = d["variants"]["paper"]
    sens, table1 = v["sensitivity_collective_lengths_cost"], v["paper_table1"]["cost"]
    assert sens == pytest.approx(4.2391, rel=0.01)
    assert table1 == pytest.approx(2.1837, rel=1e-3)
    assert sens / table1 == pytest.approx(4.2391 / 2.1837, rel=0.01)
    assert v["ga_over_optimum"] < 1e-3
    assert v["sensitivity_collective_over_ga"] == pytest.approx(sens / v["optimum_cost"], rel=1e-3)
    assert table1 / v["optimum_cost"] == pytest.approx(1.088, abs=1e-3)
    # the paper's Table 1 sits on the RSS boundary of its own model (within 2 %)
    assert v["paper_table1"]["rss_error"] == pytest.approx(5e-5, rel=0.02)
    # and does not hold under the verified model
    assert d["variants"]["verified"]["paper_table1"]["rss_error"] > 2 * 5e-5


def test_html_is_offline_and_indexed(study):
    out, d = study
    html = (out / "yao2013.html").read_text()
    # the page carries the computed costs of both variants, as the JSON has them (to 6 digits for the
    # optimum and the GA, 4 for the sensitivity rule), not a rounded or stale copy
    for variant in ("paper", "verified"):
        v = d["variants"][variant]
        for key, digits in (("optimum_cost", 6), ("ga_cost", 6), ("sensitivity_cost", 4)):
            assert f"{v[key]:.{digits}g}" in html, (variant, key, v[key])
    assert "<script src=\"http" not in html and "Plotly" in html   # plotly.js beside it, no CDN
    assert "Convergence" in html and "exceed rate" in html
    assert "yao2013.html" in (out / "index.html").read_text()


def test_html_states_errors_in_micrometres(study):
    """The "what holds" table and its note give the errors in µm, as a drawing of a 50 µm
    requirement would (they printed 5.0720e-05 m): the JSON's SI value / 1e-6, to 4 digits."""
    out, d = study
    html = (out / "yao2013.html").read_text()
    assert "max RSS error (µm)" in html and "holds 50 µm (RSS)" in html and "(m)" not in html
    for variant in ("paper", "verified"):
        c = d["variants"][variant]["paper_table1"]
        assert f"{c['rss_error'] / 1e-6:.4g}" in html and f"{c['worst_case_error'] / 1e-6:.4g}" in html
    p1 = d["variants"]["paper"]["paper_table1"]["rss_error"]
    assert f"Table 1 has max RSS error {p1 / 1e-6:.2f} µm" in html


def test_report_is_drawn_from_the_json_alone(study):
    """render() reads only the written JSON: redrawing from it gives the same page, byte for byte."""
    from evotol.studies import StudyResult, get

    out, d = study
    assert get("yao2013").render(StudyResult(d)).render() == (out / "yao2013.html").read_text()


def test_every_number_in_the_json_has_a_unit(study):
    """docs/units.md: the file's ``units`` block resolves the unit of every number (issue 15)."""
    from evotol.units import numbers_without_unit

    data = study[1]
    assert data["units"]["keys"] and numbers_without_unit(data, data["units"]) == []

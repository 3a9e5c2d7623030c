"""Issue 25 item 4: the allocated tolerance table as a drawing carries it, as CSV and as an Excel
workbook (pandas + openpyxl), from evotol run and from evotol export."""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from evotol.cli import main
from evotol.reporting.export import chosen_method, tolerance_table
from evotol.studyfile import run_study_file

STUDIES = Path(__file__).resolve().parents[1] / "reports" / "studies"
CONTRIB = "contribution to the position error at the worst pose (%)"


@pytest.fixture(scope="module")
def specs(tmp_path_factory):
    """Asymmetric legs, shared variables and a fixed bought-in joint (R1), in mm."""
    d = tmp_path_factory.mktemp("export")
    text = (STUDIES / "ucr3_tolerance_specs.toml").read_text().replace("refine = { grid = 4 }", "")
    text = text[:text.index("[methods]")] + ('[methods]\nsensitivity = {}\noptimum = {}\n[verify]\nn_samples = 20\n'
                                             '[report]\nunits = "mm"\n')
    (d / "s.toml").write_text(text)
    run_study_file(d / "s.toml", out=d)
    return d, json.loads((d / "ucr3_tolerance_specs.json").read_text())


def test_run_writes_the_drawing_table_in_display_units(specs):
    """The CSV/Excel table: tolerances and deviations in mm, the fixed joint, each source's cost
    share recomputed here from the study file's cost models (exponential 1.9/0.5 for lengths,
    1.1/0.6 otherwise, scale 1e-5 m, at the half-width (minus + plus)/2·t) over the allocation's
    total cost, and the contributions; the workbook holds the same numbers."""
    d, data = specs
    assert data["exports"] == {"csv": "ucr3_tolerance_specs_tolerances.csv", "xlsx": "ucr3_tolerance_specs_tolerances.xlsx"}
    assert chosen_method(data) == "optimum"
    csv = pd.read_csv(d / data["exports"]["csv"], keep_default_na=False)
    r = data["results"]["optimum"]
    src = {s["name"]: s for s in data["sources"]}
    for _, row in csv.iterrows():
        s, t = src[row["source"]], r["tolerances"][row["source"]]
        assert row["unit"] == "mm"                                          # [report] units = "mm"
        assert row["± tolerance"] == pytest.approx(t * 1e3 * (s["minus"] + s["plus"]) / 2, rel=1e-12)
        assert row["lower deviation"] == pytest.approx((s["offset"] - s["minus"] * t) * 1e3, rel=1e-12, abs=1e-15)
        assert row["upper deviation"] == pytest.approx((s["offset"] + s["plus"] * t) * 1e3, rel=1e-12, abs=1e-15)
    legs = csv.set_index("source").loc["l1"]
    # "20 +0.01/-0.03" style: +0.5 t / -1.5 t around a 2 µm shift
    t = r["tolerances"]["l1"]
    assert legs["upper deviation"] == pytest.approx((2e-6 + 0.5 * t) * 1e3) and legs["lower deviation"] == pytest.approx((2e-6 - 1.5 * t) * 1e3)
    assert csv.set_index("source").loc["R1", "process"] == "fixed (bought in)"
    assert csv.set_index("source").loc["R1", "cost share (%)"] == 0
    # every share from the study file's cost models (not the shares' own sum, which is 100 by construction)
    from evotol.cost_models import ExponentialCost

    length, joint = ExponentialCost(1.9, 0.5, scale=1e-5), ExponentialCost(1.1, 0.6, scale=1e-5)
    cost = {n: 0.0 if s["fixed"] else float((length if s["group"] == "length" else joint).cost(
        (s["minus"] + s["plus"]) / 2 * r["tolerances"][n])) for n, s in src.items()}
    assert sum(cost.values()) == pytest.approx(r["cost"], rel=1e-12)
    shares = csv.set_index("source")["cost share (%)"]
    assert shares.to_dict() == pytest.approx({n: 100 * c / r["cost"] for n, c in cost.items()}, rel=1e-12, abs=1e-12)
    assert len(set(np.round(shares.to_numpy(), 6))) >= 5            # shares differ: not an equal split
    c = r["contributions"]["position"]
    assert csv.set_index("source").loc[c["source"], CONTRIB].to_numpy() == pytest.approx(c["percent"], rel=1e-12)
    # the workbook: an about sheet, then every method (the chosen one first), the same numbers
    book = pd.read_excel(d / data["exports"]["xlsx"], sheet_name=None)
    assert list(book) == ["about", "optimum", "sensitivity"]
    assert book["optimum"]["± tolerance"].to_numpy() == pytest.approx(csv["± tolerance"].to_numpy(), rel=1e-15)
    about = dict(zip(book["about"]["item"], book["about"]["value"]))
    assert about["length unit"] == "mm" and about["requirement: position"] == "0.05000 mm"
    page = (d / "ucr3_tolerance_specs.html").read_text()
    assert 'href="ucr3_tolerance_specs_tolerances.xlsx"' in page


def test_export_command_writes_csv_or_excel_and_names_bad_input(specs, tmp_path, capsys):
    d, data = specs
    out = tmp_path / "sens.csv"
    assert main(["export", str(d / "ucr3_tolerance_specs.json"), "--method", "sensitivity", "--out", str(out)]) == 0
    got = pd.read_csv(out, keep_default_na=False)
    want = tolerance_table(data, "sensitivity")
    assert list(got["source"]) == list(want["source"])
    assert got["± tolerance"].to_numpy() == pytest.approx(want["± tolerance"].to_numpy(), rel=1e-12)
    assert main(["export", str(d / "ucr3_tolerance_specs.json"), "--out", str(tmp_path / "t.pdf")]) == 2
    assert "export file" in capsys.readouterr().err
    assert main(["export", str(d / "ucr3_tolerance_specs.json"), "--method", "gaa", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "method" in err and "gaa" in err and "sensitivity" in err      # names the field, the value, the choices


def test_nominal_is_the_assembly_dimension(tmp_path):
    text = (STUDIES / "clutch_assembly.toml").read_text()
    text = text[:text.index("[methods]")] + '[methods]\noptimum = {}\n[verify]\nn_samples = 20\n[report]\nunits = "mm"\n'
    (tmp_path / "c.toml").write_text(text)
    run_study_file(tmp_path / "c.toml", out=tmp_path)
    data = json.loads((tmp_path / "clutch_assembly.json").read_text())
    table = tolerance_table(data).set_index("source")
    assert table["nominal"].to_numpy() == pytest.approx(np.array([27.645, 11.43, 50.8]), rel=1e-12)
    assert list(table["group"]) == ["hub", "roller", "ring"]


@pytest.fixture(scope="module")
def puma(tmp_path_factory):
    """The PUMA 560 per-axis study (d6 = 0: the wrist's alpha4..6, theta4..6 cannot move frame 6's
    origin), 50 Monte Carlo samples; run with RuntimeWarnings as errors (issue 33: none leak)."""
    import warnings

    d = tmp_path_factory.mktemp("puma")
    text = (STUDIES / "puma560_axes.toml").read_text().replace("n_samples = 500", "n_samples = 50")
    (d / "s.toml").write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        run_study_file(d / "s.toml", out=d)
    return d, json.loads((d / "puma560_axes.json").read_text())


def test_sources_without_effect_are_marked_in_the_export_with_their_cost(puma):
    """Issue 33 item 7: the CSV's effect column is "none" exactly for the sources the summary flags,
    and the about sheet states what they cost: recomputed here from the study file's cost model
    (exponential a0 = 1.9, a1 = 0.5, scale 1e-5 m) at their allocated tolerance."""
    d, data = puma
    csv = pd.read_csv(d / data["exports"]["csv"], keep_default_na=False).set_index("source")
    flagged = {s["name"] for s in data["sources"] if s.get("no_effect")}
    assert flagged == {"alpha4", "alpha5", "alpha6", "theta4", "theta5", "theta6"}
    assert set(csv.index[csv["effect"] == "none"]) == flagged
    assert set(csv["effect"]) == {"none", ""}
    about = pd.read_excel(d / data["exports"]["xlsx"], sheet_name="about").set_index("item")["value"]
    for m, r in data["results"].items():
        own = sum(1.9 * np.exp(-0.5 * r["tolerances"][n] / 1e-5) for n in flagged)
        total = sum(1.9 * np.exp(-0.5 * t / 1e-5) for t in r["tolerances"].values())
        text = about[f"no effect on the requirement, method {m}"]
        assert text.startswith("alpha4, theta4, alpha5, theta5, alpha6, theta6 (effect 'none'): together cost ")
        shown, of = re.search(r"together cost (\S+) of the allocation's (\S+) \(", text).groups()
        assert float(shown) == pytest.approx(own, rel=1e-5) and float(of) == pytest.approx(total, rel=1e-5)


def test_round_off_shows_as_zero_in_every_table(puma):
    """Issue 33 item 7: this study's contributions hold round-off (d4's share of the error at the
    worst pose is ~4e-15 %; the wrist angles' ~1e-15 %): the CSV, the page's contribution tables and
    the formatting helper all show 0, never 4e-15; a real small value (0.2 um) is kept."""
    from evotol.units.display import number

    d, data = puma
    csv = pd.read_csv(d / data["exports"]["csv"], keep_default_na=False).set_index("source")
    c = data["results"]["optimum"]["contributions"]["position"]
    noise = [(s, p) for s, p in zip(c["source"], c["percent"]) if 0 < abs(p) < 1e-9]
    assert noise                                       # the study does produce round-off
    for s, _ in noise:
        assert csv.loc[s, CONTRIB] == 0.0
    page = (d / "puma560_axes.html").read_text()
    assert not re.search(r"<td>-?[0-9.]+e-1[0-9]</td>", page)          # e.g. <td>7.0474e-15</td> before
    assert "<td>alpha5</td><td>angle (no effect on the requirement)</td>" in page
    assert number(-1.115e-14) == "0" and number(2e-7) == "2.000e-07" and number(-3e-4) == "-0.0003000"

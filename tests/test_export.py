"""Issue 25 item 4: the allocated tolerance table as a drawing carries it, as CSV and as an Excel
workbook (pandas + openpyxl), from evotol run and from evotol export."""
from __future__ import annotations

import json
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
    from cost_models import ExponentialCost

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

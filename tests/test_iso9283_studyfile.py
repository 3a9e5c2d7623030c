"""ISO 9283 in a study file (issue 44): ``[requirement] iso9283`` and ``[iso9283]`` read and checked before any
work, and the study JSON's ``iso9283`` block (reports/studies/iso9283_example.toml, docs/iso9283.md).

References: the ISO poses recomputed here from the cube's corners; one-line refusals naming the field.
"""
import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from evotol.errors import ValidationError
from evotol.studyfile.iso9283 import quantity, read_iso9283
from evotol.studyfile.problem import load_problem

EXAMPLE = Path(__file__).resolve().parents[1] / "reports" / "studies" / "iso9283_example.toml"


def example(**iso_changes) -> dict:
    spec = tomllib.loads(EXAMPLE.read_text())
    spec["iso9283"].update(iso_changes)
    return spec


@pytest.fixture(scope="module")
def problem():
    return load_problem(example())


def refusal(spec, problem, field):
    with pytest.raises(ValidationError) as e:
        read_iso9283(spec, problem)
    assert e.value.field == field and "\n" not in str(e.value)
    return str(e.value)


def test_quantities_with_units():
    assert quantity("0.5 mm", "x") == pytest.approx(5e-4)
    assert quantity("10*um", "x") == pytest.approx(1e-5)
    assert quantity("1 arcmin", "x") == pytest.approx(np.pi / 10800)
    with pytest.raises(ValidationError, match="unit"):
        quantity("3 furlongs", "x")


def test_a_cube_outside_the_workspace_is_refused(problem):
    refusal(example(cube={"centre": ["400*mm", 0, "300*mm"], "edge": "300 mm"}), problem, "iso9283.cube")


def test_rp_without_random_sources_is_refused(problem):
    spec = example()
    del spec["iso9283"]["random"]
    spec["iso9283"]["allocate"] = False
    refusal(spec, problem, "requirement.iso9283.RP")


def test_ap_below_the_noise_floor_is_refused(problem):
    spec = example()
    spec["requirement"]["iso9283"] = {"AP": "0.01 mm", "RP": "0.05 mm"}
    assert "noise floor" in refusal(spec, problem, "requirement.iso9283.AP")


def test_too_few_calibration_configurations_are_refused(problem):
    refusal(example(calibrate={"configurations": 5}), problem, "iso9283.calibrate")


def test_unknown_keys_and_kinds_are_refused(problem):
    assert "yield" in refusal(example(yeild=0.9), problem, "iso9283.yeild")      # the nearest valid key
    spec = example()
    spec["iso9283"]["random"]["wobble"] = {"tolerance": "1 um"}
    refusal(spec, problem, "iso9283.random")


def test_the_study_json_carries_the_iso_block(tmp_path, capsys):
    from evotol.studyfile.run import run_study_file
    text = EXAMPLE.read_text().replace("allocate = true", "allocate = false").replace(
        "robots = 200", "robots = 20").replace("robots = 100", "robots = 10").replace('n_samples = 300', 'n_samples = 50').replace(
        'RP = "0.05 mm"', 'RP = "0.08 mm"')        # the catalogue sources alone give 0.056 mm
    f = tmp_path / "iso.toml"
    f.write_text(text)
    run_study_file(f, out=tmp_path)
    block = json.loads((tmp_path / "iso9283_example.json").read_text())["iso9283"]
    c, h = np.array(block["cube"]["centre"]), block["cube"]["edge"] / 2
    C1, C2, C3, C4 = (c + h * np.array(s) for s in ([-1, -1, -1], [1, -1, -1], [1, 1, 1], [-1, 1, 1]))
    want = [c, C1 + 0.1 * (C3 - C1), C2 + 0.1 * (C4 - C2), C3 + 0.1 * (C1 - C3), C4 + 0.1 * (C2 - C4)]
    assert [p["name"] for p in block["poses"]] == ["P1", "P2", "P3", "P4", "P5"]
    for p, w in zip(block["poses"], want):
        assert p["position"] == pytest.approx(w, abs=1e-12)
        assert set(p["AP_quantile"]) == {"yield", "predicted", "simulated", "interval"}
        assert set(p["AP"]) >= {"predicted", "simulated", "interval"} and set(p["RP"]) >= {"predicted", "simulated", "interval"}
        lo, hi = p["RP"]["interval"]
        assert lo <= p["RP"]["simulated"] <= hi
        assert p["AP"]["simulated"] <= p["AP"]["bound"] + p["RP"]["predicted"]
    assert len(block["random_sources"]) == 18 and block["systematic_from"] == "optimum"
    assert sum(block["what_each_source_buys"]["RP"].values()) <= 1 + 1e-9
    for p in block["calibrated"]["poses"]:
        assert p["RP_after_mean"] == pytest.approx(p["RP_before_mean"], rel=1e-3)
    page = (tmp_path / "iso9283_example.html").read_text()
    assert "ISO 9283 pose accuracy and repeatability" in page and "id='iso9283'" in page
    # the terminal states the block too: each figure's verdict on its model, each pose, the calibrated AP
    from evotol.cli import _print_results
    from evotol.units.display import DisplayUnits
    summary = json.loads((tmp_path / "iso9283_example.json").read_text())
    capsys.readouterr()
    _print_results(summary)
    out = capsys.readouterr().out
    u = DisplayUnits(**summary["display_units"])
    assert "[evotol] ISO 9283" in out
    for fig, v in block["verdict"].items():
        assert f"{fig} <= {u.format(v['requirement'], 'm')}: {v['verdict']} ({u.format(v['predicted'], 'm')}, {v['model']}" in out
    for p in block["poses"]:
        assert f"{p['name']}: AP {u.format(p['AP']['predicted'], 'm')} predicted, {u.format(p['AP']['simulated'], 'm')} simulated" in out
    assert "calibrated (10 simulated robots" in out and "RP unchanged" in out

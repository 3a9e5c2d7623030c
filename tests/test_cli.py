"""Command line: user study files (evotol run), listing, and clear errors for bad input."""
import json
import shutil
from pathlib import Path

import pytest

from evotol.cli import main

EXAMPLE = Path(__file__).resolve().parents[1] / "reports" / "studies" / "ucr3_example.toml"


def test_run_example_study_file(tmp_path, capsys):
    text = EXAMPLE.read_text().replace("grid = [5, 5, 3]", "grid = [3, 3, 2]").replace("n_gen = 60", "n_gen = 15")
    f = tmp_path / "s.toml"
    f.write_text(text)
    assert main(["run", str(f), "--out", str(tmp_path)]) == 0
    d = json.loads((tmp_path / "ucr3_example.json").read_text())
    assert d["results"]["optimum"]["feasible"]
    assert d["results"]["ga"]["cost"] <= d["results"]["optimum"]["cost"] * 1.01
    assert d["results"]["optimum"]["tolerances"]["R1"] == pytest.approx(2e-5)   # locked
    # the terminal answers "what did I get": one line per method with its cost and largest error in
    # the study's display units (the UCR3 shows no length in mm: µm, issue 25), and NSGA-II's
    # cheapest feasible point and knee
    out = capsys.readouterr().out
    assert "position (µm)" in out and d["display_units"] == {"length": "µm", "angle": "deg"}
    lines = {ln.split()[0]: ln.split() for ln in out.splitlines() if ln.startswith("  ")}
    for name, r in d["results"].items():
        assert float(lines[name][1]) == pytest.approx(r["cost"], rel=1e-5)
        assert float(lines[name][2]) == pytest.approx(r["max_position_error"] * 1e6, rel=1e-3)
    knee = next(ln.split() for ln in out.splitlines() if ln.startswith("  nsga2 knee"))
    front = d["pareto_front"]
    i = d["nsga2"]["knee"]["row"]
    assert float(knee[2]) == pytest.approx(front["cost"][i], rel=1e-5)
    assert float(knee[3]) == pytest.approx(front["position_error"][i] * 1e6, rel=1e-3)
    if "cheapest_feasible" in d["nsga2"]:
        assert any(ln.startswith("  nsga2 cheapest feasible") for ln in out.splitlines())
    # the report loads the plotly.js written once beside it (issue 11 item 7), no inlined 4.8 MB copy
    from evotol.reporting.html import plotlyjs_name
    page = (tmp_path / "ucr3_example.html").read_text()
    assert f'src="{plotlyjs_name()}"' in page and len(page) < 1_000_000
    assert (tmp_path / plotlyjs_name()).stat().st_size > 1_000_000


@pytest.mark.parametrize("edit,message", [
    (("measure = \"rss\"", "measure = \"maximum\""), "requirement.measure"),
    (("model = \"ucr3\"", "model = \"hexapod\""), "robot.model"),
    (("[sources.R1]", "[sources.R9]"), "sources.R9"),
    (("a1 = 0.5", "a1 = -0.5"), "exponential.a1"),
])
def test_bad_study_files_get_named_errors(tmp_path, capsys, edit, message):
    f = tmp_path / "bad.toml"
    f.write_text(EXAMPLE.read_text().replace(*edit))
    assert main(["run", str(f)]) == 2
    assert message in capsys.readouterr().err


def test_unknown_study_and_list(capsys):
    assert main(["reproduce", "nope", "--out", "/tmp/evotol-nope"]) == 2
    assert "one of" in capsys.readouterr().err
    assert main(["list"]) == 0
    assert "yao2013" in capsys.readouterr().out

"""What the shop can hold (issue 41 item 1): ``[shop] floors`` are lower bounds of the allocation,
named by feature (``"bore position"``), callout kind, group or source; a requirement the floors make
out of reach names the floored sources and the remedies; a zone below the measurability limit is a
warning naming it. The UR5 callout study on a 2x2x2 grid; the floors checked against the values
written in the test (⌀10 µm = 1e-5 m)."""
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest

from evotol.allocators import allocate_optimum
from evotol.core.plausibility import PlausibilityWarning, result_warnings
from evotol.core.shop import apply_shop, floors_of, unmeasurable
from evotol.errors import InfeasibleError, ValidationError
from evotol.studyfile import load_problem

STUDY = Path(__file__).resolve().parents[1] / "reports" / "studies" / "ur5_callouts_shop.toml"


def _problem(**shop):
    spec = tomllib.loads(STUDY.read_text())
    spec["poses"] = {"grid": 2}
    spec["shop"] = {**spec["shop"], **shop}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlausibilityWarning)
        return spec, apply_shop(spec, load_problem(spec, STUDY.parent))


def test_floors_are_lower_bounds_and_the_optimum_respects_them():
    spec, p = _problem()
    pos = [j for j, n in enumerate(p.names) if ".position." in n]
    axial = [j for j, n in enumerate(p.names) if n.endswith(".axial")]
    assert len(pos) == 12 and len(axial) == 6
    assert np.all(p.lower[pos] == pytest.approx(1e-5)) and np.all(p.lower[axial] == pytest.approx(2e-5))
    offsets = [j for j, n in enumerate(p.names) if n.endswith("_joint")]
    assert np.all(p.lower[offsets] == pytest.approx(1e-6))           # the study's own range, no floor
    r = allocate_optimum(p)
    assert r.feasible and np.all(r.t[pos] >= 1e-5 * (1 - 1e-9)) and np.all(r.t[axial] >= 2e-5 * (1 - 1e-9))
    assert set(p.shop_floors) == {p.names[j] for j in pos + axial}


def test_floors_out_of_reach_name_the_sources_and_the_remedies():
    spec = tomllib.loads(STUDY.read_text())
    spec["poses"] = {"grid": 2}
    spec["shop"]["floors"]["bore position"] = "30 um"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlausibilityWarning)
        p = load_problem(spec, STUDY.parent)
    with pytest.raises(InfeasibleError) as e:
        apply_shop(spec, p)
    msg = str(e.value)
    assert "with the shop's floors (bore position >= 30 µm, shoulder face >= 20 µm)" in msg
    assert "sources at a floor: elbow_joint.axial, elbow_joint.position" in msg
    assert "calibration" in msg and f"a requirement of at least {e.value.smallest_error:.6g} m" in msg
    assert e.value.smallest_error > 5e-4 and "\n" not in msg


def test_floor_keys_by_source_callout_group_and_feature():
    _, p = _problem()
    src = p.error_model.sources
    by_feature = floors_of(src, {"bore position": "10 um"})
    by_group = floors_of(src, {"position": "0.01 mm"})
    assert by_feature.keys() == by_group.keys() and all(v == pytest.approx(1e-5) for v, _ in by_group.values())
    one = floors_of(src, {"elbow_joint.position": "5*um", "position": "10 um"})     # the most specific wins
    assert one["elbow_joint.position.end1"][0] == pytest.approx(5e-6)
    assert one["wrist_1_joint.position.end2"][0] == pytest.approx(1e-5)
    with pytest.raises(ValidationError) as e:
        floors_of(src, {"bore positon": "10 um"})
    assert "shop.floors.bore positon" in str(e.value)
    with pytest.raises(ValidationError) as e:
        floors_of(src, {"shoulder_pan_joint": "10 um"})       # an angle source given a length
    assert "shop.floors.shoulder_pan_joint" in str(e.value) and "angle" in str(e.value)


def test_a_zone_below_the_measurability_limit_is_named():
    _, p = _problem(measurable="12 um")
    assert p.measurable["m"] == pytest.approx(1.2e-5)
    r = allocate_optimum(p)
    lines = result_warnings(p, r)
    named = sorted(line.split(":")[0] for line in lines if "below what can be measured (12 µm" in line)
    want = sorted({n.rpartition(".")[0] for n, t in zip(p.names, r.t) if ".position." in n and t < 1.2e-5})
    assert named == want and len(want) >= 1
    assert unmeasurable(p, r.t, {"m": 1e-6}) == []          # every zone at least ⌀10 µm: measurable at 1 µm


def test_a_feasible_design_names_the_sources_at_their_floor(tmp_path, capsys):
    """Issue 41: when feasible, the terminal and the page say which sources sit at their floor. The
    list is checked against the allocated tolerances compared here with the floors this test states
    (⌀10 µm bores, 20 µm faces): exactly the callouts whose every member is within 1e-6 of its floor."""
    from evotol.cli import main
    text = STUDY.read_text().replace("grid = [3, 3, 3]", "grid = [2, 2, 2]")
    text = text.replace('ga = { pop_size = 80, n_gen = 150 }', '').replace("n_samples = 300", "n_samples = 20")
    f = tmp_path / "shop.toml"
    f.write_text(text)
    assert main(["run", str(f), "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    import json
    d = json.loads((tmp_path / "ur5_callouts_shop.json").read_text())
    r = d["results"]["optimum"]
    assert r["feasible"]
    floor = {"position": 1e-5, "axial": 2e-5}
    by_callout = {}
    for name, t in r["tolerances"].items():
        kind = next((k for k in floor if f".{k}" in name), None)
        if kind:
            callout = name.split(f".{kind}")[0] + f".{kind}"
            by_callout.setdefault(callout, []).append(abs(t - floor[kind]) <= 1e-6 * floor[kind])
    expected = [c for c, at in by_callout.items() if all(at)]
    assert expected and [row["source"] for row in r["at_floor"]] == expected
    line = next(x for x in out.splitlines() if "sit at their [shop] floor" in x)
    assert line.strip().startswith("optimum:") and all(c in line for c in expected) and "bore position >= 10 µm" in line
    html = (tmp_path / "ur5_callouts_shop.html").read_text()
    import html as html_module
    assert html_module.escape(line.strip() + ".", quote=False) in html

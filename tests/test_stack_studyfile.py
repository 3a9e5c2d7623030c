"""A stack written in a study file ([stack], evotol.studyfile.stack_table) and assemblies named
``module:function`` beside the study file (issue 34 item 1)."""
from __future__ import annotations

import html
import json
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from evotol.errors import ValidationError
from evotol.measures.stack_analysis import Stack, StackDimension, StackModel, analyse_stack
from evotol.reporting.stack_report import terminal_rows
from evotol.studyfile import load_problem, run_study_file
from evotol.studyfile.stack_table import stack_from_table
from evotol.units import numbers_without_unit

ROOT = Path(__file__).resolve().parents[1]
MOTOR = ROOT / "reports" / "studies" / "motor_stack.toml"
DATA = ROOT / "evotol" / "studies" / "data" / "motor_assembly_handbook.json"
INCH = 0.0254


def data_stack() -> Stack:
    d = json.loads(DATA.read_text())
    return Stack(tuple(StackDimension(x["name"], x["nominal"] * INCH, x["plus"] * INCH, -x["minus"] * INCH,
                                      x["direction"], "normal", x.get("same_part_as")) for x in d["dimensions"]),
                 "gap", 0.0, 0.12 * INCH)


def test_motor_stack_file_gives_the_data_files_figures(motor_stack_run):
    """The [stack] file (inch, one-sided and unequal tolerances) gives the figures of the stack
    built from the data file in Python (SI), and the handbook's worst case −0.034/+0.157 in."""
    out, s = motor_stack_run
    data = json.loads((out / "motor_stack.json").read_text())
    assert numbers_without_unit(data, data["units"]) == []       # docs/units.md
    ref = analyse_stack(data_stack(), {"rss": StackModel(), "six_sigma": StackModel(2.0, 0.25)}).to_dict()
    st = data["stack"]
    for key in ("nominal", "mean"):
        assert st[key] == pytest.approx(ref[key], rel=1e-12)
    for key in ("worst_case", "rss", "mrss"):
        assert st[key]["limits"] == pytest.approx(ref[key]["limits"], rel=1e-12)
    assert st["models"]["six_sigma"]["cpk"] == pytest.approx(ref["models"]["six_sigma"]["cpk"], rel=1e-12)
    assert [round(v / INCH, 3) for v in st["worst_case"]["limits"]] == [-0.034, 0.157]
    assert s["stack"]["gap"] == "gap" and data["display"] == {"unit": "in", "precision": 0.0001}


def test_terminal_and_page_show_the_same_cells(motor_stack_run):
    """One truth: every cell of the terminal's gap table is in the page's gap table, same row."""
    _, s = motor_stack_run
    page = Path(s["html"]).read_text()
    table = page[re.search(r"id=['\"]gap['\"]", page).start():]
    table = table[:table.index("</table>")]
    html_rows = [[html.unescape(c) for c in re.findall(r"<td>(.*?)</td>", r)] for r in table.split("<tr>")[2:]]
    rows, _ = terminal_rows(s)
    # six figures (nominal, mean, worst case, RSS, modified RSS, specification): the page's gap
    # table has exactly these rows and the terminal's first six rows are the same cells
    assert len(html_rows) == 6 and len(rows) >= 6
    for trow, hrow in zip(rows[:6], html_rows, strict=True):
        assert trow == hrow[:len(trow)]
    # and the cells are the hand formulas on the data file (inch; Drake 1999 ch. 9): zone centre
    # c = nominal + (plus - minus)/2, half-zone h = (plus + minus)/2, worst case Σa·c ± Σ|a|h,
    # RSS Σa·c ± sqrt(Σh²), modified RSS with C_f = 1 + 0.5 (T_wc - T_rss) / (T_rss (sqrt(n) - 1))
    d = json.loads(DATA.read_text())["dimensions"]
    a = np.array([x["direction"] for x in d], float)
    nom = np.array([x["nominal"] for x in d])
    plus, minus = np.array([x["plus"] for x in d]), np.array([x["minus"] for x in d])
    c, h = a @ (nom + (plus - minus) / 2), (plus + minus) / 2
    wc, rss = np.abs(a) @ h, np.sqrt(h @ h)
    cf = 1 + 0.5 * (wc - rss) / (rss * (np.sqrt(len(h)) - 1))
    # columns: label, gap, lower limit, upper limit, half-width, verdict (issue 41: gaps are not limits)
    hand = [(1, [a @ nom]), (1, [c]), (2, [c - wc, c + wc, wc]), (2, [c - rss, c + rss, rss]),
            (2, [c - cf * rss, c + cf * rss, cf * rss]), (2, [0.0, 0.12, 0.06])]
    for (col, want), hrow in zip(hand, html_rows, strict=True):
        assert [float(v) for v in hrow[col:col + len(want)]] == pytest.approx(want, abs=5.1e-5)   # 4 decimals shown
    assert f"C_f = {cf:.4f}" in page


def test_the_stack_reads_as_a_verdict(tmp_path):
    """Issue 41 item 4: each stacking model passes or fails against LSL/USL, judged here from the
    printed limits (worst case -0.0340 .. 0.1570 in against 0 .. 0.12 in: below and above; RSS and
    modified RSS inside); a design whose worst case sits on a limit passes; the nominal and mean gap
    are values, not lower limits; the specification's half-width is (USL − LSL)/2, not a ± about the mean."""
    s = run_study_file(MOTOR, out=tmp_path)
    rows, header = terminal_rows(s)
    assert header[1:6] == ["gap (in)", "lower limit (in)", "upper limit (in)", "half-width (upper − lower)/2 (in)",
                           "against LSL/USL"]
    by = {r[0]: r for r in rows}
    assert by["nominal gap (Σ a·nominal)"][1:3] == ["0.0640", ""] and by["mean gap (Σ a·zone centre)"][2] == ""
    lsl, usl = 0.0, 0.12
    for name in ("worst case", "RSS", "modified RSS"):
        lo, hi = float(by[name][2]), float(by[name][3])
        want = [w for w, bad in (("below LSL", lo < lsl), ("above USL", hi > usl)) if bad]
        assert by[name][5] == ("fail: " + " and ".join(want) if want else "pass"), name
    assert by["worst case"][5] == "fail: below LSL and above USL" and by["RSS"][5] == "pass"
    assert by["specification (LSL, USL)"][4] == f"{(usl - lsl) / 2:.4f}"
    opt = next(r for r in rows if r[0].startswith("optimum: cost"))
    assert (opt[2], opt[3]) == ("0.0000", "0.1200") and opt[5].startswith("pass")       # on the limits: pass


def test_units_mm_and_inch_give_the_same_stack(motor_stack_run):
    """The same stack written in mm (values × 25.4) gives the same SI figures."""
    spec = tomllib.loads(MOTOR.read_text())
    st = spec["stack"]
    st["unit"] = "mm"
    for k in ("lower_limit", "upper_limit"):
        st[k] *= 25.4
    for d in st["dimensions"].values():
        for k in ("nominal", "upper", "lower", "tolerance"):
            if k in d:
                d[k] *= 25.4
    st.pop("precision")
    stack_mm, models, display = stack_from_table(st)
    assert display["unit"] == "mm"
    a = analyse_stack(stack_mm, models).to_dict()
    b = motor_stack_run[1]["stack"]
    assert a["worst_case"]["limits"] == pytest.approx(b["worst_case"]["limits"], rel=1e-9)
    assert a["mrss"]["limits"] == pytest.approx(b["mrss"]["limits"], rel=1e-9)


def _write(tmp_path, stack_toml: str) -> Path:
    p = tmp_path / "bad.toml"
    p.write_text('name = "bad"\n[stack]\nunit = "mm"\nlower_limit = 0.0\nupper_limit = 1.0\n' + stack_toml)
    return p


GOOD = "[stack.dimensions.a]\nnominal = 10.0\nupper = 0.1\nlower = -0.2\ndirection = 1\n"


@pytest.mark.parametrize("text, field", [
    ("[stack.dimensions.a]\nnominal = 10.0\nupper = -0.1\nlower = 0.2\n", "stack.dimensions.a.lower"),
    ("[stack.dimensions.a]\nnominal = 10.0\ntolerance = 0.1\nupper = 0.1\n", "stack.dimensions.a.tolerance"),
    ("[stack.dimensions.a]\nnominal = 10.0\nupper = 0.1\n", "stack.dimensions.a.lower"),
    ("[stack.dimensions.a]\nnominal = 10.0\ntolerance = 0.1\ndirection = 2\n", "stack.dimensions.a.direction"),
    ("[stack.dimensions.a]\nnominal = 10.0\ntolerance = 0.1\ndistribution = \"lognormal\"\n", "stack.dimensions.a.distribution"),
    ("[stack.dimensions.a]\nnominl = 10.0\ntolerance = 0.1\n", "stack.dimensions.a.nominl"),
    ("[stack.models]\nsix = { cp = 2.0, k = 1.5 }\n" + GOOD, "stack.models.six.k"),
    (GOOD.replace("direction = 1", "same_part_as = \"z\""), "stack.dimensions.a.same_part_as"),
    ("[stack.models]\nsix = { cp = 2.0, k = 0.25 }\n" + GOOD.replace("direction = 1", "distribution = \"uniform\""),
     "model.shift_model"),
])
def test_bad_stack_tables_are_refused_before_any_work(tmp_path, text, field):
    """One-line ValidationError naming the field; nothing is written."""
    with pytest.raises(ValidationError) as e:
        run_study_file(_write(tmp_path, text), out=tmp_path / "out")
    assert e.value.field == field
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_bad_unit_and_inverted_limits(tmp_path):
    """An unknown length unit and LSL >= USL name their field, in the file's unit."""
    p = tmp_path / "u.toml"
    p.write_text('[stack]\nunit = "furlong"\n' + GOOD)
    with pytest.raises(ValidationError, match="stack.unit"):
        run_study_file(p, out=tmp_path)
    p.write_text('[stack]\nunit = "mm"\nlower_limit = 2.0\nupper_limit = 1.0\n' + GOOD)
    with pytest.raises(ValidationError, match=r"stack.lower_limit = 2.0: expected < upper_limit \(1.0\)"):
        run_study_file(p, out=tmp_path)


def test_module_function_assembly_beside_the_study_file(tmp_path):
    """``assembly = "module:function"`` with ``module.py`` next to the study file resolves without
    PYTHONPATH; the sensitivities are the function's (∂gap/∂a = 1, ∂gap/∂b = −2)."""
    mod = "h34_gap_beside_study"
    (tmp_path / f"{mod}.py").write_text("def gap(a, b):\n    return a - 2 * b\n")
    spec = {"robot": {"assembly": f"{mod}:gap", "nominal": {"a": 0.05, "b": 0.01}, "limits": {"gap": 1e-4}},
            "cost": {"default": {"model": "power", "a0": 1.0, "a1": 1.0, "scale": 1e-3}}}
    problem = load_problem(spec, base_dir=tmp_path)
    assert np.allclose(problem.model.gradient, [[1.0, -2.0]])
    with pytest.raises(ValidationError, match="beside the study file"):
        load_problem({**spec, "robot": {**spec["robot"], "assembly": "h34_not_there:gap"}}, base_dir=tmp_path)

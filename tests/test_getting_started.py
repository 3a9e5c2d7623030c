"""docs/getting_started.md's Python call runs as written and gives the closed-form optimum of its
stack (Lagrange: t_i proportional to |a_i|^(-1/2), cost (sum sqrt|a_i|)^2 * 1e-3 / 1e-4)."""
from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

PAGE = Path(__file__).resolve().parents[1] / "docs" / "getting_started.md"


def test_the_first_python_call_runs_and_meets_the_closed_form(capsys):
    code = re.search(r"```python\n(.*?)```", PAGE.read_text(encoding="utf-8"), re.S).group(1)
    names: dict = {}
    exec(compile(code, str(PAGE), "exec"), names)
    closed_form = (1 + math.sqrt(2) + math.sqrt(0.5)) ** 2 * 1e-3 / 1e-4
    assert names["best"].cost == pytest.approx(closed_form, rel=1e-6) and closed_form == pytest.approx(97.426, abs=1e-3)
    out = capsys.readouterr().out
    assert out.startswith("AllocationResult(method='optimum', cost=97.4264, feasible=True")
    assert names["mc"].max_exceed_rate() == 0.0


def test_the_page_names_the_schema_and_the_tutorials_in_order():
    text = PAGE.read_text(encoding="utf-8")
    assert "docs/study.schema.json" in text and "evotol schema" in text
    assert text.index("tutorial_1_3rrr.md") < text.index("tutorial_2_3rpr.md")
    docs = PAGE.parent
    assert (docs / "tutorial_1_3rrr.md").read_text(encoding="utf-8").startswith("# Tutorial 1:")
    assert (docs / "tutorial_2_3rpr.md").read_text(encoding="utf-8").startswith("# Tutorial 2:")

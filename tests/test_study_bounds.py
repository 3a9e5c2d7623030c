"""Issue 15: tolerance bounds per group or source in study files ([bounds."U joint"], [bounds.l1])."""
from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from evotol.studyfile import load_problem

EXAMPLE = Path(__file__).resolve().parents[1] / "reports" / "studies" / "ucr3_example.toml"


def _spec(extra: str) -> dict:
    text = EXAMPLE.read_text().replace("grid = [5, 5, 3]", "grid = [2, 2, 2]")
    return tomllib.loads(text + extra)


def test_bounds_by_group_and_source_with_precedence():
    spec = _spec('\n[bounds."U joint"]\nupper = 5e-5\n[bounds."R joint"]\nlower = 3e-6\nupper = 1e-4\n'
                 '[bounds.l1]\nlower = 2e-6\n')
    spec["sources"]["R2"] = {"upper": 9e-5}                      # [sources.NAME] wins over the group
    P = load_problem(spec)
    lo, hi = dict(zip(P.names, P.lower)), dict(zip(P.names, P.upper))
    assert hi["U1a"] == hi["U3b"] == 5e-5 and lo["U1a"] == 1e-6     # group upper, global lower
    assert lo["R3"] == 3e-6 and hi["R3"] == 1e-4                    # group table
    assert hi["R2"] == 9e-5 and lo["R2"] == 3e-6                    # source override, then group
    assert lo["l1"] == 2e-6 and hi["l1"] == 2e-4 and lo["l2"] == 1e-6   # source table, then global


def test_without_sub_tables_the_global_bounds_apply_as_before():
    P = load_problem(_spec(""))
    assert set(P.upper) == {2e-4} and set(P.lower[P.free]) == {1e-6}

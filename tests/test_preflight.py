"""Refusals before work (issue 34 item 6): every method's options are checked against the problem
before the first method runs -- the RSS optimum of asymmetric intervals is refused before the
sensitivity rule (listed first) runs, and nothing is written."""
from __future__ import annotations

import pytest

import evotol.studyfile
from evotol.errors import ValidationError
from evotol.studyfile import run_study_file

STUDY = '''name = "pre"
seed = 0
[requirement]
measure = "rss"
[robot]
assembly = "h34_pre_gap:gap"
nominal = { a = 0.05, b = 0.02 }
limits = { gap = 1e-4 }
[bounds]
lower = 1e-6
upper = 1e-3
[cost.default]
model = "power"
a0 = 1.0
a1 = 1.0
scale = 1e-3
[sources.a]
minus = 1.0
plus = 0.0
[methods]
sensitivity = {}
METHOD
[verify]
n_samples = 20
'''


def _never(*a, **k):
    raise AssertionError("a method ran before every method was checked")


@pytest.mark.parametrize("method, field", [("optimum = {}", "methods.optimum: requirement.measure"),
                                           ("ga = { pop_size = 2 }", "methods.ga: pop_size"),
                                           ("ga = { operators = \"fancy\" }", "methods.ga: operators")])
def test_refused_before_the_first_method(tmp_path, monkeypatch, method, field):
    (tmp_path / "h34_pre_gap.py").write_text("def gap(a, b):\n    return a - b\n")
    (tmp_path / "pre.toml").write_text(STUDY.replace("METHOD", method))
    monkeypatch.setattr(evotol.studyfile, "METHODS", {m: _never for m in evotol.studyfile.METHODS})
    with pytest.raises(ValidationError) as e:
        run_study_file(tmp_path / "pre.toml", out=tmp_path / "out")
    assert e.value.field == field
    assert not (tmp_path / "out" / "pre.json").exists()


def test_the_allocator_raises_the_same_refusal():
    """The preflight check is the allocator's own: allocate_optimum refuses RSS with asymmetric
    intervals with the same field and message."""
    import numpy as np
    from evotol.cost_models.power import PowerCost
    from evotol.allocators import allocate_optimum
    from evotol.allocators.preflight import check_methods
    from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
    from evotol.robots.assembly import LinearStack

    robot = LinearStack({"a": 1.0, "b": -1.0}, {"gap": 1e-4})
    tol = {"a": Tolerance(PowerCost(1.0, 1.0, scale=1e-3), 1e-6, 1e-3, minus=1.0, plus=0.0),
           "b": Tolerance(PowerCost(1.0, 1.0, scale=1e-3), 1e-6, 1e-3)}
    p = ToleranceProblem(robot, tol, Requirement(position=1.0, measure="rss"), np.zeros((1, 1)))
    with pytest.raises(ValidationError) as direct:
        allocate_optimum(p)
    with pytest.raises(ValidationError) as pre:
        check_methods(p, {"optimum": {}})
    assert pre.value.field == f"methods.optimum: {direct.value.field}" and pre.value.expected == direct.value.expected

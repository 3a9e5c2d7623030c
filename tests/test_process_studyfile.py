"""Process selection from a study file ([processes.<dimension>], evotol/studyfile/processes.py): the
shipped clutch file against the Python API, both TOML spellings, quality loss in an ordinary study,
bad input named."""
import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from evotol.allocators import allocate_optimum
from evotol.allocators.process import allocate_process_optimum
from evotol.errors import ValidationError
from evotol.studyfile import load_process_problem, run_process_study
from evotol.core.quality_loss import with_quality_loss
from evotol.studies import choi2000_clutch as choi
from evotol.studyfile import load_problem, run_study_file

STUDIES = Path(__file__).resolve().parents[1] / "reports" / "studies"
CLUTCH = STUDIES / "clutch_processes.toml"


def _spec():
    return tomllib.loads(CLUTCH.read_text())


def test_shipped_clutch_file_gives_the_python_api_optimum(tmp_path):
    """The file's A = 100 optimum equals allocate_process_optimum on the choi2000 problem built in Python
    (35.16608: the published Choi 2000 A = 100 allocation recomputed), and the JSON splits machining + loss."""
    spec = _spec()
    spec["methods"] = {"optimum": {}, "ga": {"pop_size": 30, "n_gen": 30}, "baselines": {}, "nsga2": {"pop_size": 20, "n_gen": 10}}
    run_process_study(spec, CLUTCH, tmp_path, 0)     # the file with a smaller GA/NSGA-II budget
    data = json.loads((tmp_path / "clutch_processes.json").read_text())
    py = allocate_process_optimum(choi.problem(choi.load(), 101.6, "rss", 100.0))
    opt = data["results"]["optimum"]
    assert opt["cost"] == pytest.approx(py.cost, rel=1e-9)
    assert opt["processes"] == py.processes
    assert opt["machining_cost"] + opt["quality_loss"] == pytest.approx(opt["cost"], rel=1e-12)
    assert opt["quality_loss"] == pytest.approx(9.1627, rel=1e-4)
    for m, r in data["results"].items():
        if r["feasible"]:
            assert r["cost"] >= opt["cost"] * (1 - 1e-9), m
    assert len(data["pareto_front"]["cost"]) > 0
    from evotol.units import numbers_without_unit
    assert numbers_without_unit(data, data["units"]) == []     # docs/units.md


def test_shipped_file_runs_through_evotol_run(tmp_path):
    """``evotol run`` dispatches a file with [processes.*] to process selection (default methods)."""
    spec = _spec()
    spec.pop("methods")
    spec["quality_loss"] = 0.0
    summary = run_process_study(spec, CLUTCH, tmp_path, 0)
    assert set(summary["results"]) == {"optimum", "ga", "baseline sensitivity", "baseline lagrange"}
    # A = 0: the machining-cost optimum of the Choi clutch, 24.46243 (choi2000-clutch study)
    assert summary["results"]["optimum"]["cost"] == pytest.approx(24.46242558, rel=1e-8)
    assert run_study_file.__module__ == "evotol.studyfile.run"


def test_both_spellings_build_the_same_problem():
    spec = _spec()
    as_tables = dict(spec)
    as_tables["processes"] = {src: {p["name"]: {k: v for k, v in p.items() if k != "name"} for p in plist}
                              for src, plist in spec["processes"].items()}
    a = load_process_problem(spec)
    b = load_process_problem(as_tables)
    assert a.describe() == b.describe()
    assert np.allclose(a.loss_coefficients, b.loss_coefficients) and a.loss_coefficients.any()


@pytest.mark.parametrize("edit, field", [
    (lambda s: s["processes"]["X1"][0].update(lowr=1e-5), "processes.X1[0].lowr"),
    (lambda s: s["processes"].update(X9=[]), "processes.X9"),
    (lambda s: s["processes"]["X2"][0].pop("cost"), "processes.X2[0].cost"),
    (lambda s: s["processes"]["X2"][1].update(lower="fine"), "processes.X2[1].lower"),
    (lambda s: s["processes"]["X3"][0]["cost"].update(model="nope"), "processes.X3[0].cost"),
    (lambda s: s.update(cost={"default": {}}), "cost"),
    (lambda s: s["processes"].pop("X4"), "processes"),
    (lambda s: s.update(quality_loss=-1.0), "quality_loss"),
])
def test_bad_process_tables_are_named(edit, field):
    spec = _spec()
    edit(spec)
    with pytest.raises(ValidationError) as exc:
        load_process_problem(spec)
    assert exc.value.field.startswith(field)


def test_quality_loss_in_an_ordinary_study_file():
    """quality_loss = A in a study without processes: load_problem returns the problem with the loss
    term, whose optimum equals with_quality_loss on the plain problem."""
    spec = tomllib.loads((STUDIES / "clutch_assembly.toml").read_text())
    spec["requirement"]["measure"] = "rss"
    plain = load_problem(spec)
    spec["quality_loss"] = 50.0
    lossy = load_problem(spec)
    r = allocate_optimum(lossy)
    assert r.cost == pytest.approx(allocate_optimum(with_quality_loss(plain, 50.0)).cost, rel=1e-9)
    assert r.cost > allocate_optimum(plain).cost


def test_nonlinear_limit_method_in_a_process_study_file(tmp_path):
    """methods.nonlinear_limit on the clutch file switched to the worst-case limit: the JSON shows the
    first-order optimum's proven nonlinear worst case above the limit and the held design on it."""
    spec = _spec()
    spec["requirement"]["measure"] = "worst_case"
    spec["methods"] = {"optimum": {}, "nonlinear_limit": {}}
    summary = run_process_study(spec, CLUTCH, tmp_path, 0)
    nl = summary["nonlinear_limit"]
    assert nl["linear_optimum_nonlinear_worst_case_over_limit"] > 1.2
    assert 1 - 1e-6 <= nl["nonlinear_worst_case_over_limit"] <= 1 + 1e-9
    held, opt = summary["results"]["nonlinear limit"], summary["results"]["optimum"]
    assert held["cost"] - opt["cost"] == pytest.approx(nl["cost_difference"], rel=1e-12) and nl["cost_difference"] > 0
    from evotol.units import numbers_without_unit
    assert numbers_without_unit(summary, summary["units"]) == []

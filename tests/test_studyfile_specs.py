"""Study files with tolerance specifications (issue 10 item 7): the example files run and state
what they say; unknown keys are errors naming the key and the nearest valid one."""
import tomllib
from pathlib import Path

import numpy as np
import pytest

from evotol.errors import ValidationError
from evotol.studyfile import load_problem

EXAMPLES = Path(__file__).resolve().parent.parent / "reports" / "studies"


def _spec(name):
    return tomllib.loads((EXAMPLES / name).read_text())


def test_tolerance_specs_example_builds_the_stated_problem():
    P = load_problem(_spec("ucr3_tolerance_specs.toml"))
    assert P.shared == {"legs": ("l1", "l2", "l3"), "u_base": ("U1a", "U2a", "U3a")}
    assert P.n_variables == 12 - 4 - 1          # two groups of three -> 2 variables, R1 fixed
    t = P.full(np.full(P.n_variables, 1e-5)[None])[0]
    np.testing.assert_allclose(P.intervals(t)[0], [2e-6 - 1.5e-5, 2e-6 + 0.5e-5])
    assert P.tolerances["R1"].is_fixed and t[P.names.index("R1")] == 5e-6
    assert P.source_costs(t)[P.names.index("R1")] == 0


def test_tolerance_specs_example_runs_with_refinement(tmp_path):
    from evotol.studyfile import run_study_file

    text = (EXAMPLES / "ucr3_tolerance_specs.toml").read_text()
    text = text.replace("sensitivity = {}\n", "").replace("ga = { pop_size = 30, n_gen = 30 }\n", "")
    text = text.replace("n_samples = 200", "n_samples = 50")
    f = tmp_path / "s.toml"
    f.write_text(text)
    out = run_study_file(f, out=tmp_path)
    r = out["results"]["optimum"]
    assert r["feasible"] and r["refinement"]["holds"] and r["refinement"]["rounds"] >= 1
    assert r["shared"]["legs"] == ["l1", "l2", "l3"]


@pytest.mark.parametrize("mutate, field, nearest", [
    (lambda s: s.update(requirment=s.pop("requirement")), "requirment", "requirement"),
    (lambda s: s["bounds"].update(lowr=1e-6), "bounds.lowr", "lower"),
    (lambda s: s["sources"]["l1"].update(ofset=1e-6), "sources.l1.ofset", "offset"),
    (lambda s: s["poses"].update(refien=True), "poses.refien", "refine"),
    (lambda s: s["requirement"].update(measur="rss"), "requirement.measur", "measure"),
    (lambda s: s["sources"].update(l_1={"offset": 1e-6}), "sources.l_1", "l1"),
])
def test_unknown_study_key_names_it_and_the_nearest_valid_key(mutate, field, nearest):
    spec = _spec("ucr3_tolerance_specs.toml")
    mutate(spec)
    with pytest.raises(ValidationError) as exc:
        load_problem(spec)
    assert exc.value.field == field
    assert f"did you mean {nearest!r}" in str(exc.value)


@pytest.mark.parametrize("mutate, field", [
    (lambda s: s["shared"].update(legs=["l1", "l9"]), "shared.legs"),
    (lambda s: s["shared"].update(more=["l1"]), "shared.more"),
    (lambda s: s.update(seed=1.5), "seed"),
    (lambda s: s["sources"]["R1"].update(lower=1e-6), "sources.R1.lower"),
    (lambda s: s["sources"]["l1"].update(offset=1e-4, contains_nominal=True), "tolerances['l1'].offset"),
    (lambda s: s["sources"].update(U1b={"offset": 1e-6}), "tolerances['U1b'].offset"),
])
def test_bad_tolerance_specs_in_a_study_file(mutate, field):
    spec = _spec("ucr3_tolerance_specs.toml")
    mutate(spec)
    with pytest.raises(ValidationError) as exc:
        load_problem(spec)
    assert exc.value.field == field


def test_shared_per_variable_example_counts_the_group_once():
    P = load_problem(_spec("ucr3_shared_per_variable.toml"))
    assert P.n_variables == 4 and P.shared_cost == "variable"
    t = np.full(12, 1e-5)
    assert P.cost(t) == pytest.approx(4 * float(P.tolerances["l1"].cost.cost(1e-5)))

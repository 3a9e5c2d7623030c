"""The process-selection studies (quick runs): files, the JSON keys issue 14 asks for, and the
exact optimum agreeing with full enumeration / never beaten by the GA or the baselines."""
import json

import pytest

from evotol import studies

KEYS = ("published", "optimum_cost", "ga_cost", "ga_over_optimum", "n_nodes", "seconds")


@pytest.mark.parametrize("name", ["chase1990-clutch", "process-stack"])
def test_process_study_writes_html_and_json_with_the_issue_keys(tmp_path, name):
    summary = studies.get(name).run(tmp_path, quick=True)
    assert (tmp_path / f"{name}.html").exists()
    data = json.loads((tmp_path / f"{name}.json").read_text())
    from evotol.units import numbers_without_unit

    assert numbers_without_unit(data, data["units"]) == []  # docs/units.md (issue 15)
    for k in KEYS:
        assert k in data
    for case in data["cases"].values():
        opt = case["optimum_cost"]
        assert case["optimum"]["feasible"]
        assert case["ga_cost"] >= opt * (1 - 1e-9)
        for b in case["baselines"].values():
            if b["feasible"]:
                assert b["cost"] >= opt * (1 - 1e-9)
        if "enumeration" in case:
            assert case["enumeration"]["same_optimum"]
            assert case["n_convex_solves"] <= case["enumeration"]["n_convex_solves"]
    assert summary["optimum_cost"] == pytest.approx(data["optimum_cost"])

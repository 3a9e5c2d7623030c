"""The study protocol (evotol/studies/__init__.py): configs, and files written in one place."""
import json

import pandas as pd
import pytest

from evotol import studies
from evotol.errors import ValidationError
from evotol.reporting import Report
from evotol.studies import Study, StudyResult, reproduce


def _compute(config):
    n = config["n"]
    table = pd.DataFrame({"entry": range(n), "p_max_mm": [0.5 * i for i in range(n)]})
    return StudyResult({"n": n, "seed": config["seed"], "sum_p_max_mm": float(table["p_max_mm"].sum())},
                       {"entries": table})


def _render(result):
    rep = Report("toy study")
    rep.text(f"sum of p_max: {result.summary['sum_p_max_mm']:.2f} mm over {len(result.tables['entries'])} entries")
    return rep


TOY = Study(name="toy", title="toy", compute=_compute, render=_render, config={"seed": 0, "n": 5}, quick={"n": 3})


def test_config_is_default_then_quick_then_overrides():
    assert TOY.make_config() == {"seed": 0, "n": 5, "quick": False}
    assert TOY.make_config(quick=True) == {"seed": 0, "n": 3, "quick": True}
    assert TOY.make_config(quick=True, seed=7, n=4) == {"seed": 7, "n": 4, "quick": True}


def test_unknown_config_key_is_named():
    with pytest.raises(ValidationError, match="toy config.*n_gen"):
        TOY.make_config(n_gen=3)


def test_reproduce_writes_html_json_and_tables(tmp_path):
    summary = TOY.run(tmp_path, quick=True, seed=3)
    # 0 + 0.5 + 1.0 over the quick run's three entries
    assert summary["sum_p_max_mm"] == 1.5 and summary["seed"] == 3
    on_disk = json.loads((tmp_path / "toy.json").read_text())
    assert on_disk["sum_p_max_mm"] == 1.5 and "seconds" in on_disk   # set by reproduce when compute does not
    assert pd.read_parquet(tmp_path / "toy_entries.parquet")["p_max_mm"].tolist() == [0.0, 0.5, 1.0]
    assert pd.read_csv(tmp_path / "toy_entries.csv")["entry"].tolist() == [0, 1, 2]
    assert "sum of p_max: 1.50 mm over 3 entries" in (tmp_path / "toy.html").read_text()


def test_reproduce_passes_out_dir_to_compute(tmp_path):
    seen = {}

    def compute(config):
        seen.update(config)
        return StudyResult({})

    study = Study(name="t", title="t", compute=compute, render=lambda r: Report("t"), config={"seed": 0})
    reproduce(study, tmp_path, study.make_config())
    assert seen["out_dir"] == str(tmp_path)


def test_every_study_declares_the_protocol():
    for name, study in studies.available().items():
        assert study.seed_paper and study.title, name
        assert callable(study.compute) and callable(study.render), name
        assert "seed" in study.config, name
        assert set(study.quick) <= set(study.config), (name, sorted(set(study.quick) - set(study.config)))


@pytest.mark.parametrize("name", ["all", "no-such-study"])
def test_get_unknown_name_offers_only_names_get_accepts(name):
    """``studies.get`` refuses a name that is not a study, ``'all'`` included (only the CLI's
    ``reproduce all`` takes it), and its one-line message lists the study names -- without
    offering ``'all'``, which ``get`` does not accept."""
    with pytest.raises(ValidationError) as exc:
        studies.get(name)
    assert exc.value.field == "study" and exc.value.value == name
    assert exc.value.expected == f"one of {sorted(studies.available())}"
    assert "'all'" not in exc.value.expected and "yao2013" in exc.value.expected

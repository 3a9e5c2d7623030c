"""The JSON Schema of the study file (issue 40): generated from the reader's key tables, shipped as
docs/study.schema.json (kept up to date), printed by ``evotol schema``; every shipped study file
validates, and a misspelt key is refused by the schema exactly where the reader refuses it."""
from __future__ import annotations

import json
import tomllib
from pathlib import Path

import jsonschema
import pytest

from evotol.cli import main
from evotol.errors import ValidationError
from evotol.studyfile.keys import check_study_keys
from evotol.studyfile.schema import schema_text, study_schema

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "docs" / "study.schema.json"
STUDIES = sorted((ROOT / "reports" / "studies").glob("*.toml"))


@pytest.fixture(scope="module")
def validator():
    schema = study_schema()
    jsonschema.Draft202012Validator.check_schema(schema)          # a valid draft 2020-12 schema
    return jsonschema.Draft202012Validator(schema)


def test_shipped_schema_is_up_to_date_and_the_command_prints_it(capsys):
    assert SHIPPED.read_text(encoding="utf-8") == schema_text(), \
        "docs/study.schema.json is stale: python -m evotol.cli schema > docs/study.schema.json"
    assert main(["schema"]) == 0
    assert json.loads(capsys.readouterr().out) == json.loads(SHIPPED.read_text(encoding="utf-8"))


@pytest.mark.parametrize("path", STUDIES, ids=[p.stem for p in STUDIES])
def test_every_shipped_study_file_validates(validator, path):
    errors = [f"{list(e.path)}: {e.message}" for e in validator.iter_errors(tomllib.loads(path.read_text()))]
    assert not errors, errors


@pytest.mark.parametrize("edit, where", [
    (lambda d: d.update(requirment=d.pop("requirement")), "requirment"),                 # top level
    (lambda d: d["poses"].update(gird=d["poses"].pop("grid")), "gird"),                  # [poses]
    (lambda d: d["requirement"].update(postion=1e-4), "postion"),                         # [requirement]
    (lambda d: d.setdefault("sources", {}).update(l1={"lowr": 1e-6}), "lowr"),            # [sources.NAME]
    (lambda d: d.update(seed=-1), "seed"),
])
def test_a_misspelt_key_is_refused_by_schema_and_reader_alike(validator, edit, where):
    spec = tomllib.loads((ROOT / "reports" / "studies" / "ucr3_example.toml").read_text())
    check_study_keys(spec)                                    # the file as shipped: accepted by both
    edit(spec)
    errors = list(validator.iter_errors(spec))
    assert errors and any(where in e.message or where in map(str, e.path) for e in errors), [e.message for e in errors]
    with pytest.raises(ValidationError):
        check_study_keys(spec)


def test_method_tables_take_the_allocators_keywords(validator):
    spec = {"methods": {"ga": {"pop_size": 60, "n_gen": 60, "rng": 3}, "optimum": {}}}
    assert not list(validator.iter_errors(spec))
    spec["methods"]["ga"]["pop_sise"] = 60                    # the reader's example typo (docs/errors.md)
    assert [e.message for e in validator.iter_errors(spec)] == ["Additional properties are not allowed ('pop_sise' was unexpected)"]

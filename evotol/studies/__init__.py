"""Reproducible studies: data plus a picture, discovered automatically.

A study is a :class:`Study` value in a module of this package (``STUDY = Study(...)``). It has
two pure functions:

* ``compute(config) -> StudyResult`` -- the physics and statistics, returning plain data: a
  JSON-ready ``summary`` (numbers, lists, strings; it is what ``NAME.json`` holds) and, for the
  design studies, named entry ``tables`` (pandas DataFrames, written as CSV and Parquet);
* ``render(result) -> Report`` -- the HTML report, drawn from that data alone (it never computes
  physics, so a report can be redrawn from the JSON and tables it was written with).

``config`` is a plain dict: the study's default ``config``, updated by ``quick`` for a small run
(``--quick``; used by tests) and by the caller's overrides (``seed``, ``workers``, ...). The
framework adds ``out_dir`` (where the resumable design studies keep their chunk store).

Files are written in one place, :func:`write_outputs`: ``OUT/NAME.html``, ``OUT/NAME.json`` and
``OUT/NAME_<table>.csv`` / ``.parquet`` for every table. :func:`reproduce` (behind
``evotol reproduce NAME --out DIR`` and ``Study.run``) and ``evotol run STUDY.toml``
(:mod:`evotol.studyfile`) both go through it. :func:`reproduce` renders the report from the
summary read back from the written JSON: a page shows nothing its JSON does not hold.
"""
from __future__ import annotations

import importlib
import json
import pkgutil
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

from evotol.doe import save_entries
from evotol.errors import ValidationError
from evotol.reporting.html import write_json


@dataclass
class StudyResult:
    """What a study computes: a JSON-ready ``summary`` and named entry ``tables`` (DataFrames)."""

    summary: dict
    tables: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Study:
    """A reproducible study: name, title, seed paper, configs and the compute/render pair."""

    name: str
    title: str
    compute: Callable[[dict], StudyResult]
    render: Callable[[StudyResult], Any]
    config: Mapping[str, Any]
    quick: Mapping[str, Any] = field(default_factory=dict)
    seed_paper: str = ""

    def make_config(self, quick: bool = False, **overrides) -> dict:
        """The full-run config, updated by the quick config (``quick=True``) and then ``overrides``."""
        cfg = dict(self.config)
        if quick:
            cfg.update(self.quick)
        cfg["quick"] = bool(quick)
        unknown = sorted(set(overrides) - set(cfg) - {"out_dir"})
        if unknown:
            raise ValidationError(f"{self.name} config", unknown, f"keys among {sorted(cfg)}")
        cfg.update(overrides)
        return cfg

    def units_block(self) -> dict:
        """The ``units`` block written into ``NAME.json`` (docs/units.md): the common keys and
        rules plus this study's own keys (``evotol/studies/_units.py``)."""
        from evotol.studies._units import study_units
        from evotol.units import make_units_block
        return make_units_block(**study_units(self.name))

    def run(self, out_dir, quick: bool = False, seed: int = 0, **overrides) -> dict:
        """Compute, render and write the study into ``out_dir``; returns the JSON summary."""
        return reproduce(self, out_dir, self.make_config(quick, seed=seed, **overrides)).summary


def reproduce(study: Study, out_dir, config: dict) -> StudyResult:
    """Run ``study`` with ``config`` and write its report, JSON and tables into ``out_dir``.

    ``summary["seconds"]`` is set here when the study did not time itself (wall time of
    ``compute``). The report is rendered from the summary *as written to JSON* (read back), so
    a page can only show what its JSON holds. Returns the result with that summary.
    """
    out_dir = Path(out_dir)
    config = {**config, "out_dir": str(out_dir)}
    t0 = time.perf_counter()
    result = study.compute(config)
    result.summary.setdefault("seconds", time.perf_counter() - t0)
    result.summary.setdefault("units", study.units_block())
    paths = write_outputs(study.name, out_dir, result)
    result = StudyResult(json.loads(paths["json"].read_text(encoding="utf-8")), result.tables)
    study.render(result).write(paths["html"])
    return result


def write_outputs(name: str, out_dir, result: StudyResult, report=None) -> dict[str, Path]:
    """The one writer of study files: ``NAME_<table>.csv``/``.parquet`` for every table,
    ``NAME.json`` and, given a ``report``, ``NAME.html``. Returns the paths by kind (``json``,
    ``html`` -- also when no report was given --, ``<table>_parquet``, ``<table>_csv``)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = {}
    for key, table in result.tables.items():
        for kind, path in save_entries(table, out_dir / f"{name}_{key}").items():
            paths[f"{key}_{kind}"] = path
    paths["json"] = write_json(out_dir / f"{name}.json", result.summary)
    paths["html"] = report.write(out_dir / f"{name}.html") if report is not None else out_dir / f"{name}.html"
    return paths


def available() -> dict[str, Study]:
    """All studies, by name, in name order."""
    found = {}
    for info in pkgutil.iter_modules(__path__):
        if info.name.startswith("_"):
            continue
        mod = importlib.import_module(f"{__name__}.{info.name}")
        study = getattr(mod, "STUDY", None)
        if isinstance(study, Study):
            found[study.name] = study
    return dict(sorted(found.items()))


def get(name: str) -> Study:
    studies = available()
    if name not in studies:
        raise ValidationError("study", name, f"one of {sorted(studies)} or 'all'")
    return studies[name]

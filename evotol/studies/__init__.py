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

Files are written in one place, :func:`reproduce`: ``OUT/NAME.html``, ``OUT/NAME.json`` and
``OUT/NAME_<table>.csv`` / ``.parquet`` for every table. ``evotol reproduce NAME --out DIR`` and
``Study.run`` both go through it.
"""
from __future__ import annotations

import importlib
import pkgutil
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

from evotol.errors import ValidationError


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
    compute: Callable[[dict], StudyResult] | None = None
    render: Callable[[StudyResult], Any] | None = None
    config: Mapping[str, Any] = field(default_factory=dict)
    quick: Mapping[str, Any] = field(default_factory=dict)
    seed_paper: str = ""
    #: transition only: a study not yet split into compute/render writes its own files
    legacy_run: Callable[..., dict] | None = None

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

    def run(self, out_dir, quick: bool = False, seed: int = 0, **overrides) -> dict:
        """Compute, render and write the study into ``out_dir``; returns the JSON summary."""
        if self.legacy_run is not None:
            return self.legacy_run(out_dir, quick=quick, seed=seed, **overrides)
        return reproduce(self, out_dir, self.make_config(quick, seed=seed, **overrides)).summary


def reproduce(study: Study, out_dir, config: dict) -> StudyResult:
    """Run ``study`` with ``config`` and write its report, JSON and tables into ``out_dir``.

    The one place where study files are written. ``summary["seconds"]`` is set here when the
    study did not time itself (wall time of ``compute``).
    """
    from evotol.doe import save_entries
    from evotol.reporting.html import write_json

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    config = {**config, "out_dir": str(out_dir)}
    t0 = time.perf_counter()
    result = study.compute(config)
    result.summary.setdefault("seconds", time.perf_counter() - t0)
    for key, table in result.tables.items():
        save_entries(table, out_dir / f"{study.name}_{key}")
    study.render(result).write(out_dir / f"{study.name}.html")
    write_json(out_dir / f"{study.name}.json", result.summary)
    return result


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

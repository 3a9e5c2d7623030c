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

The parameters several definitions of this package share are described once, here.

Parameters
----------
result : StudyResult
    Output of the study module's ``compute`` (its summary).
"""
from __future__ import annotations

import importlib
import json
import pkgutil
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

from evotol._runtime.output_paths import check_output_name, path_inside
from evotol._runtime.output_set import claim_outputs
from evotol.design import save_entries
from evotol.errors import ValidationError
from evotol.reporting.html import write_json


@dataclass
class StudyResult:
    """What a study computes: a JSON-ready ``summary`` and named entry ``tables`` (DataFrames).

    Parameters
    ----------
    summary : dict
        JSON-ready numbers, lists and strings; written as ``NAME.json``. Quantities carry the
        units named by the study's ``units`` block (docs/units.md).
    tables : dict of str to pandas.DataFrame, optional
        Named entry tables, each written as ``NAME_<key>.csv`` and ``.parquet``. Empty by
        default (studies without design tables).
    """

    summary: dict
    tables: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Study:
    """A reproducible study: name, title, seed paper, configs and the compute/render pair.

    Parameters
    ----------
    name : str
        Short name; the stem of the output files (``NAME.html``, ``NAME.json``) and the name
        ``evotol reproduce NAME`` takes.
    title : str
        Human-readable title of the report.
    compute : callable
        ``compute(config) -> StudyResult``: the physics and statistics, from the config dict.
    render : callable
        ``render(result) -> Report``: the HTML report, drawn from the :class:`StudyResult` alone.
    config : mapping
        Default config of a full run (plain keys to values).
    quick : mapping, optional
        Keys that override ``config`` for a small run (``--quick``; used by tests). Empty by
        default.
    seed_paper : str, optional
        Citation of the paper the study reproduces; empty when there is none.
    """

    name: str
    title: str
    compute: Callable[[dict], StudyResult]
    render: Callable[[StudyResult], Any]
    config: Mapping[str, Any]
    quick: Mapping[str, Any] = field(default_factory=dict)
    seed_paper: str = ""

    def make_config(self, quick: bool = False, **overrides) -> dict:
        """The full-run config, updated by the quick config (``quick=True``) and then ``overrides``.

        Parameters
        ----------
        quick : bool, optional
            Apply the study's ``quick`` config (small run). The result's ``"quick"`` key is set
            to this flag.
        **overrides
            Config keys to set last; each must be a key of the config (or ``out_dir``).

        Returns
        -------
        dict
            The merged config.

        Raises
        ------
        ValidationError
            If an override names a key the config does not have (other than ``out_dir``).
        """
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
        rules plus this study's own keys (``evotol/studies/_summary_key_units.py``).

        Returns
        -------
        dict
            The units block, as made by :func:`evotol.units.make_units_block`.
        """
        from evotol.studies._summary_key_units import study_units
        from evotol.units import make_units_block
        return make_units_block(**study_units(self.name))

    def run(self, out_dir, quick: bool = False, seed: int = 0, force: bool = False, **overrides) -> dict:
        """Compute, render and write the study into ``out_dir``; returns the JSON summary.

        Parameters
        ----------
        out_dir : str or path-like
            Folder to write ``NAME.html``, ``NAME.json`` and the table files into (created if
            missing).
        quick : bool, optional
            Small run with the study's ``quick`` config.
        seed : int, optional
            Random seed, passed as the ``seed`` config key.
        force : bool, optional
            Overwrite another study's files of the same name in ``out_dir`` (:func:`reproduce`).
        **overrides
            Further config keys (see :meth:`make_config`).

        Returns
        -------
        dict
            The summary as written to ``NAME.json`` (read back).

        Raises
        ------
        ValidationError
            If an override is not a config key (from :meth:`make_config`), or another study's
            files or writer hold ``out_dir`` (:func:`reproduce`).
        """
        return reproduce(self, out_dir, self.make_config(quick, seed=seed, **overrides), force=force).summary


def reproduce(study: Study, out_dir, config: dict, force: bool = False) -> StudyResult:
    """Run ``study`` with ``config`` and write its report, JSON and tables into ``out_dir``.

    ``summary["seconds"]`` is set here when the study did not time itself (wall time of
    ``compute``). The report is rendered from the summary *as written to JSON* (read back), so
    a page can only show what its JSON holds. Returns the result with that summary.

    Parameters
    ----------
    study : Study
        The study to run.
    out_dir : str or path-like
        Folder for the outputs (created if missing); also passed to ``compute`` as the config
        key ``out_dir``.
    config : dict
        The full config (usually from :meth:`Study.make_config`).
    force : bool, optional
        Overwrite the files of another study of the same name (a study file's) in ``out_dir``.

    Returns
    -------
    StudyResult
        The summary read back from ``NAME.json`` (with ``seconds`` and ``units`` filled in when
        the study did not set them) and the computed tables.

    Raises
    ------
    ValidationError
        Before any work: another process is writing this study into ``out_dir``, its files
        there belong to a study file, or a quick run (``config["quick"]``) would replace a full
        run's files without ``force`` (:func:`evotol._runtime.output_set.claim_outputs`).
    """
    out_dir = Path(out_dir)
    config = {**config, "out_dir": str(out_dir)}
    with claim_outputs(out_dir, study.name, f"seed study {study.name}", force=force,   # one writer (issue 42)
                       quick=bool(config.get("quick"))):                                 # no quick over full
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
    ``html`` -- also when no report was given --, ``<table>_parquet``, ``<table>_csv``).

    Parameters
    ----------
    name : str
        Study name; the stem of every file name.
    out_dir : str or path-like
        Output folder (created if missing).
    result : StudyResult
        The summary (written as JSON) and tables (written as CSV and Parquet).
    report : Report, optional
        The HTML report to write as ``NAME.html``; ``None`` writes no HTML.

    Returns
    -------
    dict of str to pathlib.Path
        The paths by kind: ``json``, ``html`` and ``<table>_parquet``, ``<table>_csv`` per table.

    Raises
    ------
    ValidationError
        ``name`` (or a table's name) is not a file name, or a file would land outside ``out_dir``
        (:func:`evotol._runtime.output_paths.check_output_name`, ``path_inside``).
    evotol.errors.WriteFailed
        The system refused a write (disk full, read-only); every file is written atomically, so the
        earlier file of that name is kept whole.
    """
    check_output_name(name)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = {}
    for key, table in result.tables.items():
        check_output_name(f"{name}_{key}", "table name")
        for kind, path in save_entries(table, path_inside(out_dir, f"{name}_{key}")).items():
            paths[f"{key}_{kind}"] = path
    paths["json"] = write_json(path_inside(out_dir, f"{name}.json"), result.summary)
    html = path_inside(out_dir, f"{name}.html")
    paths["html"] = report.write(html) if report is not None else html
    return paths


def available() -> dict[str, Study]:
    """All studies, by name, in name order.

    Returns
    -------
    dict of str to Study
        Every ``STUDY`` of a public module of this package, keyed by its name, sorted by name.
    """
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
    """The study called ``name``.

    Parameters
    ----------
    name : str
        Study name, as listed by :func:`available`.

    Returns
    -------
    Study
        The study.

    Raises
    ------
    ValidationError
        If no study has that name.
    """
    studies = available()
    if name not in studies:
        raise ValidationError("study", name, f"one of {sorted(studies)}")
    return studies[name]

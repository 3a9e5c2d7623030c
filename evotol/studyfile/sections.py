"""The optional sections of a robot study, registered once (issue 39 item 2).

A capability a study may have beyond its methods -- drawing callouts, a calibration, the ISO 9283
figures -- is a :class:`Section`: whether the study has it (read from the composed problem, never
from ``getattr``), the block it adds to the summary from the results of the study's one step loop
(a summary never allocates: what a section compares with ran as a step,
:mod:`evotol.studyfile.comparisons`), and the files it exports beside the page. The runner
(:func:`evotol.studyfile.run.run_study_file`) walks :data:`SECTIONS` in order; a new capability is
one more entry here, with its checks where its part is composed (``docs/architecture.md``).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from evotol._runtime.output_paths import path_inside
from evotol.calibration.summary import add_to_study as add_calibration
from evotol.reporting.callout_drawing import write_callout_exports
from evotol.studyfile.callouts import callout_summary, callout_warnings
from evotol.studyfile.iso9283 import iso9283_block


@dataclass
class StudyRun:
    """What a section reads: the study's problem and what its steps produced.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The study's problem (``problem.model`` the composed error model).
    results : dict
        Method name -> allocation result.
    compared : dict
        Comparison step name -> its result (``"callouts: exact"``, ``"uncalibrated"``, ...).
    seed : int
        The study's seed.
    stopped : bool
        A Ctrl-C stopped a step: sections that need every step's result add nothing.
    iso : object or None
        The ISO 9283 reading of the study file (:func:`evotol.studyfile.iso9283.read_iso9283`).
    """

    problem: object
    results: dict
    compared: dict
    seed: int
    stopped: bool
    iso: object = None


@dataclass(frozen=True)
class Section:
    """One optional section of a robot study.

    Parameters
    ----------
    name : str
        The summary's key for the section.
    present : callable
        ``present(run) -> bool``: the study has this capability.
    summarise : callable
        ``summarise(summary, run)``: adds the section's block (and warnings) to the summary.
    export : callable or None
        ``export(summary, out, name)``: writes the section's files beside the page.
    """

    name: str
    present: Callable[[StudyRun], bool]
    summarise: Callable[[dict, StudyRun], None]
    export: Callable[[dict, Path, str], None] | None = None


def _calibration(summary: dict, run: StudyRun) -> None:
    if "uncalibrated" in run.compared:      # what calibration buys (docs/calibration.md)
        add_calibration(summary, run.problem, run.results, run.seed, uncalibrated=run.compared["uncalibrated"])


def _iso9283(summary: dict, run: StudyRun) -> None:
    if not run.stopped:
        summary["iso9283"] = iso9283_block(run.iso, run.problem, run.results, run.seed)


def _callouts(summary: dict, run: StudyRun) -> None:
    if run.stopped:
        return
    callouts = run.problem.model.part_of("callouts")     # exact zones vs boxes (issue 35), both solved in the loop
    side = {z: run.compared.get(f"callouts: {z}", run.results.get("optimum") if callouts.zones == z else None)
            for z in ("exact", "boxes")}
    if None not in side.values():
        summary["callouts"] = callout_summary(run.problem, side["exact"], side["boxes"])
    summary["warnings"] = [*summary["warnings"], *callout_warnings(run.problem)]


def _callout_files(summary: dict, out: Path, name: str) -> None:
    if summary.get("callouts") and "exports" in summary:    # the drawing callouts: a CSV, two sheets of the workbook
        summary["exports"]["drawing"] = f"{name}_drawing.csv"
        write_callout_exports(summary, path_inside(out, f"{name}_drawing.csv"), path_inside(out, summary["exports"]["xlsx"]))


#: the sections, in the order their blocks are added and their files written
SECTIONS = (
    Section("calibration", lambda run: run.problem.calibration is not None, _calibration),
    Section("iso9283", lambda run: run.iso is not None, _iso9283),
    Section("callouts", lambda run: run.problem.model.part_of("callouts") is not None, _callouts, _callout_files),
)

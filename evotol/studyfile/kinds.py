"""One pipeline for every kind of study file (issue 39 item 2, docs/architecture.md).

A study file is one of a few kinds -- a robot or mechanism study (with or without every tolerance
given), a ``[stack]``, a ``[processes]`` selection -- and each kind is a :class:`StudyKind`:
whether a file is of that kind (``present``) and how to turn it into an :class:`Outcome`
(``run``: read and check everything, build the problem, run the methods, checks and comparisons as
named steps, summarise). What every kind shares happens here, once:

* the output set is claimed before (:func:`evotol.studyfile.run.run_study_file`);
* one Ctrl-C handler and one :class:`evotol.studyfile.steps.StepLog` for the whole run: every kind
  runs its work through :func:`evotol.studyfile.steps.run_steps`, so a Ctrl-C stops the running
  step and what ran is written, marked ``interrupted`` (:func:`run_kind`);
* the summary's ``study_file``, ``interrupted`` and ``interruption`` keys, the page rendered from
  the summary and stated first on the page, the JSON/HTML pair written atomically, then the kind's other files (drawing table,
  sections' exports) (:func:`finish`).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from evotol._runtime.interrupt import CtrlC
from evotol.studies import StudyResult, write_outputs
from evotol.studyfile.steps import StepLog


@dataclass
class Study:
    """What every kind's ``run`` gets: the file, where it writes, and the run's Ctrl-C and step log.

    Parameters
    ----------
    spec : dict
        The parsed study file.
    path : Path
        The study file (relative files are read from its folder).
    out : Path
        The output folder (claimed).
    name : str
        The study's name (checked: never a path).
    seed : int
        The run's seed.
    t0 : float
        ``time.perf_counter()`` at the start of the run (s).
    log : StepLog
        The steps stopped and skipped by a Ctrl-C.
    ctrl_c : evotol._runtime.interrupt.CtrlC or None
        The run's Ctrl-C handler (set by :func:`run_kind`).
    """

    spec: dict
    path: Path
    out: Path
    name: str
    seed: int
    t0: float
    log: StepLog
    ctrl_c: CtrlC | None = None

    def seconds(self) -> float:
        """Wall time since the run started (s).

        Returns
        -------
        float
            Seconds.
        """
        return time.perf_counter() - self.t0


@dataclass
class Outcome:
    """What a kind's run hands to the one writer.

    Parameters
    ----------
    summary : dict
        The JSON-ready summary (SI).
    render : callable
        ``render(summary) -> evotol.reporting.Report``: the page, made after the run's
        ``interrupted`` keys are in the summary.
    exports : list of callable
        ``export(summary, out, name)``: files written beside the page, after it.
    """

    summary: dict
    render: Callable
    exports: list = field(default_factory=list)


@dataclass(frozen=True)
class StudyKind:
    """A kind of study file: ``present(spec)`` says whether a file is one; ``run(study)`` gives its Outcome.

    Parameters
    ----------
    name : str
        The kind's name (``"processes"``, ``"stack"``, ``"robot"``).
    present : callable
        ``present(spec) -> bool`` from the parsed file alone.
    run : callable
        ``run(study) -> Outcome``.
    """

    name: str
    present: Callable
    run: Callable


def finish(study: Study, outcome: Outcome) -> dict:
    """Write a kind's outcome the one way every study is written (module docstring).

    Parameters
    ----------
    study : Study
        The run.
    outcome : Outcome
        What the kind made.

    Returns
    -------
    dict
        The summary written, with ``study_file``, ``interrupted`` (and ``interruption`` when a step
        was stopped), ``html`` and ``json``.
    """
    summary = outcome.summary
    summary["study_file"] = str(Path(study.path).resolve())     # every kind's, here only
    summary["interrupted"] = bool(study.log.stopped)
    if study.log.stopped:
        summary["interruption"] = study.log.interruption()
    report = outcome.render(summary)
    if study.log.stopped:       # every kind's page says so first (the JSON: ``interruption``)
        what = summary["interruption"]
        report.lead(f"Interrupted (Ctrl-C): stopped {', '.join(what['stopped'])}"
                    + (f"; not run: {', '.join(what['skipped'])}" if what["skipped"] else "")
                    + ". The results below are what was computed until then; a GA or NSGA-II that was "
                      "stopped reports its best design so far.")
    paths = write_outputs(study.name, study.out, StudyResult(summary), report)
    for export in outcome.exports:
        export(summary, study.out, study.name)
    summary.update(html=str(paths["html"]), json=str(paths["json"]))
    return summary


def run_kind(run: Callable, spec: dict, path, out, name: str, seed: int, t0: float | None = None,
             keep_going: bool = False) -> dict:
    """Run one kind's ``run`` under the study's one Ctrl-C handler and write its outcome.

    Parameters
    ----------
    run : callable
        ``run(study) -> Outcome`` (a :class:`StudyKind`'s).
    spec, path, out, name, seed
        As :class:`Study`.
    t0 : float, optional
        Start time (default: now).
    keep_going : bool, optional
        After a Ctrl-C, still run the remaining steps.

    Returns
    -------
    dict
        The summary written (:func:`finish`).
    """
    study = Study(spec, Path(path), Path(out), name, seed, time.perf_counter() if t0 is None else t0,
                  StepLog(keep_going))
    with CtrlC() as ctrl_c:
        study.ctrl_c = ctrl_c
        outcome = run(study)
    return finish(study, outcome)

"""Several studies at once: ``evotol reproduce all --jobs 2`` (issue 13).

Each seed study runs as its own ``evotol reproduce NAME`` process -- exactly what a user can run
by hand, with the same seed and options, so the results are those of a run one study at a time
(the test compares the JSON files number by number). ``jobs`` studies run at the same time,
the longest expected first (:func:`longest_first`: this machine's last runs, else the project's), so the single-process
parts of one study (a GA, a Newton sweep, the report) overlap with another study's work: a
study's grid and design evaluations still use every core, so two studies at once share the
cores rather than add processes of their own.

A study's output (its progress lines, warnings, a traceback) goes to ``OUT/logs/NAME.log``;
this process prints one line when a study starts, ends or fails (with the last lines of its log).
Ctrl-C stops every running study (each gets one SIGINT: a GA inside returns its best design so
far and the study still writes its files, as in a run of that study alone); the studies not
started are named.
"""
from __future__ import annotations

import functools
import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from evotol._runtime.interrupt import CtrlC
from evotol._runtime.orphans import end_with_parent
from evotol._runtime.progress import EXPECTED_SECONDS, last_run_seconds

#: exit code of a study process stopped by Ctrl-C (``evotol reproduce``)
INTERRUPTED = 130


@dataclass
class JobsOutcome:
    """What :func:`reproduce_concurrently` did: summaries (read back from the JSON files) of the
    studies that completed, wall seconds per study, the failed ones, and on Ctrl-C the studies
    that were running (``stopped``, with ``written`` those that still wrote their files) and those
    never started (``not_run``).

    Parameters
    ----------
    summaries : dict, optional
        Study name -> its JSON summary (``OUT/NAME.json``, read back), for the studies that
        completed (and those stopped that still wrote their files).
    seconds : dict, optional
        Study name -> wall time of its process, s.
    failed : list of str, optional
        Studies whose process ended with a non-zero exit code.
    stopped : list of str, optional
        Studies running when Ctrl-C came.
    written : list of str, optional
        Those of ``stopped`` that still wrote their JSON file.
    not_run : list of str, optional
        Studies not started when Ctrl-C came.
    """

    summaries: dict = field(default_factory=dict)
    seconds: dict = field(default_factory=dict)
    failed: list = field(default_factory=list)
    stopped: list = field(default_factory=list)
    written: list = field(default_factory=list)
    not_run: list = field(default_factory=list)

    @property
    def interrupted(self) -> bool:
        """True when Ctrl-C stopped the run (a study was stopped or never started)."""
        return bool(self.stopped or self.not_run)


def longest_first(names, out=None, quick: bool = False) -> list[str]:
    """Names ordered by expected run time, longest first (unknown ones last, order kept).

    When every study has a complete run of the same kind in ``out``, their times on this machine
    order them (:func:`evotol._runtime.progress.last_run_seconds`); otherwise the full-run times of
    the project's machine do (:data:`evotol._runtime.progress.EXPECTED_SECONDS`), never a mix of
    the two.

    Parameters
    ----------
    names : iterable of str
        Seed study names.
    out : str or Path or None, optional
        The output folder (its manifests hold the last runs' times).
    quick : bool, optional
        Whether the runs to come are ``--quick`` ones.

    Returns
    -------
    list of str
        The names sorted by expected seconds, descending (stable sort).
    """
    names = list(names)
    last = {n: last_run_seconds(out, n, quick) for n in names}
    if names and all(s is not None for s in last.values()):
        return sorted(names, key=lambda n: -last[n])
    return sorted(names, key=lambda n: -EXPECTED_SECONDS.get(n, 0))


def _command(name: str, out: Path, *, seed: int, quick: bool, scheduler: str | None, force: bool = False) -> list[str]:
    cmd = [sys.executable, "-m", "evotol.cli", "reproduce", name, "--out", str(out), "--seed", str(seed)]
    if force:
        cmd.append("--force")
    if quick:
        cmd.append("--quick")
    if scheduler:
        cmd += ["--scheduler", scheduler]
    return cmd


def _tail(path: Path, n: int = 20) -> str:
    try:
        return "\n".join(path.read_text(encoding="utf-8", errors="replace").splitlines()[-n:])
    except OSError:
        return "(no log)"


def _written_since(out: Path, name: str, t0: float) -> bool:
    # t0 is wall-clock time.time() (the clock of st_mtime), not time.perf_counter()
    p = out / f"{name}.json"
    return p.exists() and p.stat().st_mtime >= t0


def reproduce_concurrently(names, out, *, jobs: int = 2, seed: int = 0, quick: bool = False,
                           scheduler: str | None = None, titles: dict | None = None,
                           poll: float = 0.2, report_every: float = 30.0, stream=None, force: bool = False) -> JobsOutcome:
    """Run the studies ``names`` into ``out``, ``jobs`` at a time (see the module docstring).

    Parameters
    ----------
    names : iterable of str
        Seed study names, each run as ``evotol reproduce NAME`` (longest expected first).
    out : str or Path
        The output folder: each study's ``NAME.json`` and ``NAME.html``, and ``logs/NAME.log``
        (created).
    jobs : int, optional
        Studies running at the same time (default 2).
    seed : int, optional
        ``--seed`` of every study (default 0).
    quick : bool, optional
        Pass ``--quick`` (shorter runs).
    scheduler : str, optional
        Dask scheduler address passed as ``--scheduler`` (default: none, local processes).
    titles : dict, optional
        Study name -> title shown in its "started" line.
    poll : float, optional
        Seconds between checks of the running processes (default 0.2).
    report_every : float, optional
        Seconds between "running: ..." lines (default 30).
    stream : file, optional
        Where the progress lines go (default ``sys.stderr``: progress and messages on standard
        error, results on standard output).
    force : bool, optional
        Pass ``--force`` to each study (overwrite a study file's outputs of the same name).

    Returns
    -------
    JobsOutcome
        What ran, how long, what failed and, on Ctrl-C, what was stopped or not run. Ctrl-C does
        not propagate: each running study gets one SIGINT and is waited for (killed after 60 s).
    """
    stream = stream or sys.stderr
    out = Path(out)
    logs = out / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    queue = longest_first(names, out, quick)
    titles = titles or {}
    res = JobsOutcome()
    running: dict[str, tuple[subprocess.Popen, float, object]] = {}
    started: dict[str, float] = {}      # wall-clock start (time.time()), compared with the JSON's mtime
    env = dict(os.environ)
    # children must import this evotol (an editable install or the source tree the caller runs)
    root = str(Path(__file__).resolve().parents[1])
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    print(f"[evotol] reproducing {len(queue)} studies, {jobs} at a time, longest first; each study's "
          f"output: {logs}/NAME.log", file=stream, flush=True)
    last_report = time.perf_counter()
    try:
        # Ctrl-C raises here even when this process was started with SIGINT ignored (as by `nohup`
        # or `cmd &` in a script), as in the one-at-a-time path
        with CtrlC():
            while queue or running:
                while queue and len(running) < jobs:
                    name = queue.pop(0)
                    log = open(logs / f"{name}.log", "w", encoding="utf-8")
                    started[name] = time.time()
                    # own session: a terminal Ctrl-C reaches only this process, which forwards one
                    # SIGINT to each study (a second one would abort a GA's clean stop)
                    proc = subprocess.Popen(_command(name, out, seed=seed, quick=quick, scheduler=scheduler, force=force),
                                            stdout=log, stderr=subprocess.STDOUT, env=env, start_new_session=True,
                                            preexec_fn=functools.partial(end_with_parent, os.getpid()))   # issue 42
                    running[name] = (proc, time.perf_counter(), log)
                    print(f"[evotol] started {name}" + (f": {titles[name]}" if name in titles else ""), file=stream, flush=True)
                for name in list(running):
                    proc, t0, log = running[name]
                    code = proc.poll()
                    if code is None:
                        continue
                    log.close()
                    del running[name]
                    res.seconds[name] = time.perf_counter() - t0
                    if code == 0:
                        res.summaries[name] = json.loads((out / f"{name}.json").read_text(encoding="utf-8"))
                        print(f"[evotol] {name} done in {res.seconds[name]:.1f} s -> {out / (name + '.html')}", file=stream, flush=True)
                    else:
                        res.failed.append(name)
                        print(f"[evotol] {name} failed (exit code {code}); last lines of {logs / (name + '.log')}:\n"
                              f"{_tail(logs / (name + '.log'))}", file=sys.stderr, flush=True)
                if running and time.perf_counter() - last_report >= report_every:
                    last_report = time.perf_counter()
                    now = time.perf_counter()
                    print("[evotol] running: " + ", ".join(f"{n} ({now - t0:.0f} s)" for n, (_, t0, _) in running.items()),
                          file=stream, flush=True)
                time.sleep(poll)
    except KeyboardInterrupt:
        for name, (proc, t0, log) in running.items():
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
        for name, (proc, t0, log) in running.items():
            try:
                proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            log.close()
            res.seconds[name] = time.perf_counter() - t0
            res.stopped.append(name)
            if _written_since(out, name, started[name]):
                res.written.append(name)
                res.summaries[name] = json.loads((out / f"{name}.json").read_text(encoding="utf-8"))
        res.not_run = list(queue)
    return res

"""Progress a log file can show: periodic lines while a study runs, when no terminal is attached.

:func:`progress_bar` is the one progress display of the long methods (GA, NSGA-II, Monte Carlo):
a tqdm bar on a terminal; with ``progress=True`` and no terminal (``evotol run ... > log``), a
line every ``every`` seconds with the count, the elapsed time and the time left -- the same tqdm
object, so callers only ``update()`` (issue 27 item 5).

Progress bars (tqdm) switch themselves off when stdout is not a terminal, so ``evotol reproduce
yao2013 > log`` used to print nothing for 28 s (issue 15). :class:`Heartbeat` prints one line
every ``every`` seconds -- elapsed time and the expected time of a full run -- from a daemon
thread, only when the stream is not a terminal, and stops when the study ends.

``EXPECTED_SECONDS``: full-run times of the seed studies measured on the project's 2-core
machine, each study alone (2026-11-23; the engine studies after the compiled Newton iteration of
issue 13's fourth session, with the numba cache warm; `evotol reproduce all` runs two at a time,
longest first, so these also set its order); ``--quick`` runs are much shorter. They are a
guide, not a promise: the machine and its load change them (the same code took 2-3 times as
long on a slower machine of the same name, 2026-12-02). So the heartbeat prefers what this
machine took: :func:`last_run_seconds`, the last complete run of the study in the same output
folder, read from its manifest (``started``, ``finished``; :mod:`evotol._runtime.output_set`).
"""
from __future__ import annotations

import logging
import sys
import threading
import time

from tqdm.auto import tqdm

logger = logging.getLogger(__name__)

EXPECTED_SECONDS = {
    "brahmia2023-delta": 42, "chase1990-clutch": 5, "deng2012-5bar": 21, "deng2012-clearalloc": 9,
    "deng2012-dimsynth": 35, "drake1999-motor": 1, "deng2012-irsbot2": 56, "deng2012-tolsynth": 17, "laramolina2019-5r": 33,
    "mechanisms": 8, "process-stack": 4, "yao2013": 30,
}


def last_run_seconds(out, name: str, quick: bool = False) -> float | None:
    """Wall seconds of the last complete run of ``name`` in ``out``, with the same ``--quick``.

    Read from the output set's manifest (``finished - started``), so call it before a new run
    claims the folder (the claim rewrites the manifest as incomplete).

    Parameters
    ----------
    out : str or Path or None
        The output folder (None: unknown).
    name : str
        The output set's (study's) name.
    quick : bool, optional
        Whether the run to come is a ``--quick`` one; only a run of the same kind counts.

    Returns
    -------
    float or None
        Seconds (s), or None when no complete run of that kind is recorded there.
    """
    if out is None:
        return None
    from evotol._runtime.output_set import read_manifest

    m = read_manifest(out, name)
    try:
        seconds = float(m["finished"]) - float(m["started"])
    except (KeyError, TypeError, ValueError):
        return None
    ok = m.get("complete") is True and bool(m.get("quick", False)) == bool(quick) and 0.0 < seconds < 1e6
    return seconds if ok else None


def run_hint(name: str, out=None, quick: bool = False) -> str:
    """What the heartbeat says about the length of a run: this machine's last run if known, else
    :data:`EXPECTED_SECONDS` (a full run on the project's machine), else ``""``.

    Parameters
    ----------
    name : str
        The study's name.
    out : str or Path or None, optional
        The output folder the run writes to (its last run there is read from the manifest).
    quick : bool, optional
        Whether this is a ``--quick`` run.

    Returns
    -------
    str
        e.g. ``"its last run in this folder took 2.7 min"`` or ``"a full run takes about 56 s on
        the project's 2-core machine"``, or ``""``.
    """
    last = last_run_seconds(out, name, quick)
    if last is not None:
        return f"its last {'quick ' if quick else ''}run in this folder took {_seconds(last)}"
    hint = expected(name)
    return f"a full run takes {hint} on the project's 2-core machine" if hint else ""


def expected(name: str) -> str:
    """'about 21 s' / 'about 3 min' for a seed study, '' when unknown.

    Parameters
    ----------
    name : str
        The seed study's name, a key of ``EXPECTED_SECONDS``.

    Returns
    -------
    str
        The expected full-run time in words (seconds below 100 s, else minutes), or ``""``.
    """
    s = EXPECTED_SECONDS.get(name)
    if s is None:
        return ""
    return f"about {s:.0f} s" if s < 100 else f"about {s / 60:.0f} min"


class Heartbeat:
    """``with Heartbeat("yao2013"): study.run(...)`` -- a line every ``every`` s on a non-terminal.

    ``bar=True``: on a terminal, a tqdm line with the elapsed time instead (shown after 2 s,
    redrawn every second, on ``bar_stream``, default stderr) -- for a method of unknown length,
    such as the exact optimum's cutting planes in ``evotol run`` (issue 27 item 5).

    Parameters
    ----------
    name : str
        What runs, named in each line; a seed study's name also gives the expected time
        (:func:`run_hint`).
    every : float, optional
        Seconds between lines (default 10).
    stream : file, optional
        Where the lines go (default: the ``evotol`` log at INFO level, which the command shows on
        standard error); lines only when it (stderr by default) is not a terminal.
    force : bool, optional
        Print the lines even on a terminal.
    bar : bool, optional
        On a terminal (and without ``force``), show the elapsed-time tqdm line instead.
    bar_stream : file, optional
        Where that line goes (default: ``sys.stderr``); shown only when it is a terminal.
    out : str or Path or None, optional
        The output folder of the run: the lines give the last run's time there when it is
        recorded (:func:`run_hint`), read when the heartbeat is made.
    quick : bool, optional
        Whether the run is a ``--quick`` one (only a last run of the same kind is quoted).
    """

    def __init__(self, name: str, every: float = 10.0, stream=None, force: bool = False, bar: bool = False,
                 bar_stream=None, out=None, quick: bool = False):
        self.name, self.every = name, float(every)
        self.hint = run_hint(name, out, quick)     # read now: the run about to start rewrites the manifest
        self.stream = stream
        isatty = getattr(sys.stderr if stream is None else stream, "isatty", lambda: False)
        self.active = force or not isatty()
        self.bar_stream = sys.stderr if bar_stream is None else bar_stream
        self.bar = bar and not self.active and getattr(self.bar_stream, "isatty", lambda: False)()
        self._stop = threading.Event()
        self._thread = None

    def _spin(self) -> None:
        with tqdm(total=None, desc=self.name, bar_format="{desc}: running for {elapsed}", leave=False, delay=2.0,
                  file=self.bar_stream) as bar:
            while not self._stop.wait(1.0):
                bar.refresh()

    def _beat(self) -> None:
        t0 = time.perf_counter()
        while not self._stop.wait(self.every):
            elapsed = time.perf_counter() - t0
            line = f"{self.name}: running for {elapsed:.0f} s" + (f" ({self.hint})" if self.hint else "")
            if self.stream is None:
                logger.info(line)
            else:
                print(f"[evotol] {line}", file=self.stream, flush=True)

    def __enter__(self) -> "Heartbeat":
        if self.active or self.bar:
            self._thread = threading.Thread(target=self._beat if self.active else self._spin, name=f"heartbeat-{self.name}",
                                            daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc) -> bool:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=1.0)
        return False


#: one line of :func:`progress_bar` off a terminal
LINE_FORMAT = "{desc}: {n_fmt}/{total_fmt} {unit} ({percentage:.0f} %), {elapsed} elapsed, about {remaining} left{postfix}"


def _seconds(s: float) -> str:
    return f"{s:.0f} s" if s < 100 else f"{s / 60:.1f} min"


class _Estimate:
    """After the second step, one line: the method's size and its time estimated from the first two
    (``GA: 60 generations × 60 designs × 75 poses; about 45 s (the first 1 gen: 0.9 s, the next 1: 0.6 s)``),
    when the estimate is at least ``delay`` s and work remains (a short run says nothing). The rate is the
    second step's: the first carries the method's one-off set-up (a compiled kernel loaded, caches
    filled), which made a 103 823-pose Monte Carlo announce 12.4 min for a run of 23 s."""

    size = ""
    _first: tuple | None = None      # (steps, seconds) of the first update
    _estimated = False               # the estimate line was said

    def update(self, n=1):
        if n and not self.disable and self.total and self._first is not None and self.n == self._first[0]:
            first, took = self._first                                   # the second step: state the estimate
            now = self._time()
            total = took + (now - self.start_t - took) / n * (self.total - first)
            if total >= self.delay and first + n < self.total:
                self._estimated = True
                self.say(f"{self.desc}: {self.size + '; ' if self.size else ''}about {_seconds(total)} "
                         f"(the first {first} {self.unit}: {took:.2g} s, the next {n}: {now - self.start_t - took:.2g} s)")
        if self.n == 0 and n and not self.disable and self.total:      # the first step: remember its time
            self._first = (n, self._time() - self.start_t)
        return super().update(n)

    def say(self, text: str) -> None:
        self.write(text, file=self.fp)


class _Bar(_Estimate, tqdm):
    """A tqdm bar with the estimate line."""


class _Lines(_Estimate, tqdm):
    """A tqdm that prints a new line at each display (at most every ``mininterval`` s) instead of
    redrawing one with carriage returns: readable in a log file."""

    def say(self, text: str) -> None:
        self.fp.write(f"[evotol] {text}\n")
        self.fp.flush()

    def display(self, msg=None, pos=None, force: bool = False):
        if msg == "" or not self.n:       # clearing a bar, or nothing done yet: nothing to say in a log
            return False
        now = self._time()                # set_postfix() refreshes at every step: at most a line per interval
        if not force and now - getattr(self, "_said", getattr(self, "start_t", now)) < self.mininterval:
            return True
        self._said = now
        self.say(self.__str__() if msg is None else msg)
        return True

    def close(self):
        elapsed = self._time() - getattr(self, "start_t", self._time())
        if not self.disable and self.n and elapsed >= self.delay:     # how far it got, in how long
            post = f", {self.postfix}" if self.postfix else ""
            size = f"{self.size}; " if self.size and not self._estimated else ""   # the size not said yet
            self.say(f"{self.desc}: {size}{self.n}/{self.total} {self.unit} in {_seconds(elapsed)}{post}")
        super().close()


def progress_bar(total: int, desc: str, unit: str, progress: bool | None = None, size: str = "", stream=None,
                 every: float = 10.0, delay: float = 2.0) -> tqdm:
    """The progress display of a long method (see the module docstring).

    Parameters
    ----------
    total : int
        Steps of the method (generations, poses).
    desc, unit : str
        What runs (``"GA"``) and what a step is (``"gen"``).
    progress : bool or None
        None: a bar on a terminal, nothing otherwise; True: a bar on a terminal, a line every
        ``every`` s otherwise; False: nothing. Nothing either when the ``evotol`` logger's level is
        set above INFO (``evotol -q``).
    size : str
        The method's size, stated with the time estimate after the first step
        (``"60 generations x 60 designs x 75 poses"``).
    stream : file, optional
        Where to write (default: stderr, whose ``isatty()`` decides).
    every : float
        Seconds between lines off a terminal (the first after ``every`` s).
    delay : float
        Seconds before a bar appears, and the shortest estimate that is stated.

    Returns
    -------
    tqdm
        Call ``update(n)``, ``set_postfix(...)``, ``close()`` (or use it as a context manager).
    """
    stream = sys.stderr if stream is None else stream
    tty = getattr(stream, "isatty", lambda: False)()
    quiet = logging.getLogger("evotol").level > logging.INFO     # ``evotol -q`` (or a user's setLevel): no progress
    if progress is False or (progress is None and not tty) or quiet:
        return tqdm(total=total, disable=True)
    if tty:
        bar = _Bar(total=total, desc=desc, unit=unit, leave=False, delay=delay, file=stream)
    else:
        bar = _Lines(total=total, desc=desc, unit=unit, file=stream, mininterval=every, delay=every, miniters=1,
                     bar_format=LINE_FORMAT, leave=False)
        bar.delay = delay                 # the estimate's threshold (the first line waits ``every`` s)
    bar.size = size
    return bar

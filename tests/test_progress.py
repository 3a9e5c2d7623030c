"""Issue 15: `reproduce` prints progress lines when stdout is not a terminal; `list` gives run times."""
from __future__ import annotations

import io
import time

from evotol import studies
from evotol.cli import main
from evotol._runtime.progress import EXPECTED_SECONDS, Heartbeat


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_heartbeat_prints_lines_to_a_log_but_not_to_a_terminal():
    log, tty = io.StringIO(), _Terminal()
    with Heartbeat("yao2013", every=0.02, stream=log), Heartbeat("yao2013", every=0.02, stream=tty):
        deadline = time.monotonic() + 10
        while "running for" not in log.getvalue() and time.monotonic() < deadline:
            time.sleep(0.01)
    lines = log.getvalue().splitlines()
    assert lines and lines[0].startswith("[evotol] yao2013: running for") and f"about {EXPECTED_SECONDS['yao2013']} s" in lines[0]
    assert tty.getvalue() == ""


def test_list_prints_expected_time_of_every_study(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert set(EXPECTED_SECONDS) <= set(studies.available())
    for name in EXPECTED_SECONDS:
        line = next(l for l in out.splitlines() if l.startswith(name + " "))
        assert "about " in line, line


# --- issue 27 item 5: the long methods' progress, a bar on a terminal and lines in a log ---------
def test_progress_bar_prints_size_estimate_and_lines_to_a_log():
    from evotol._runtime.progress import progress_bar

    log = io.StringIO()
    with progress_bar(5, "GA", "gen", True, size="5 generations × 8 designs × 3 poses", stream=log, every=0.0, delay=0.0) as bar:
        for _ in range(5):
            time.sleep(0.01)
            bar.update(1)
            bar.set_postfix(best="1.5")
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue() and all(line.startswith("[evotol] GA: ") for line in lines), lines
    estimate = [line for line in lines if "; about " in line]
    second = next(i for i, line in enumerate(lines) if line.startswith("[evotol] GA: 2/5 gen"))
    assert len(estimate) == 1 and 0 < lines.index(estimate[0]) < second, lines      # once, at the second step
    assert estimate[0].startswith("[evotol] GA: 5 generations × 8 designs × 3 poses; about ")
    assert "(the first 1 gen: " in estimate[0] and ", the next 1: " in estimate[0]
    assert any(line.startswith("[evotol] GA: 3/5 gen (60 %)") for line in lines), lines
    assert lines[-1].startswith("[evotol] GA: 5/5 gen in ") and lines[-1].endswith("best=1.5"), lines
    # rate limit: set_postfix refreshes at every step, the log gets at most a line per interval
    slow = io.StringIO()
    with progress_bar(50, "GA", "gen", True, stream=slow, every=60.0, delay=0.0) as bar:
        for _ in range(50):
            bar.update(1)
            bar.set_postfix(best="1")
    assert len(slow.getvalue().splitlines()) <= 2, slow.getvalue()


def test_the_estimate_takes_its_rate_from_the_second_step_not_the_set_up_of_the_first():
    """The first step carries a method's one-off set-up (a 103 823-pose Monte Carlo: 0.46 s for its first
    64 poses, 12 ms for each next 64; the first step's rate announced 12.4 min for a 23 s run). On a
    made-up clock: first step 10 s, second 0.5 s, 100 steps -> 10 + 99 x 0.5 = 59.5 s."""
    from evotol._runtime.progress import progress_bar

    log, clock = io.StringIO(), [0.0]
    bar = progress_bar(100, "Monte Carlo", "pose", True, size="100 poses", stream=log, every=1e9, delay=0.0)
    bar._time, bar.start_t = (lambda: clock[0]), 0.0
    clock[0] = 10.0
    bar.update(1)
    assert log.getvalue() == ""                                   # no estimate from the set-up alone
    clock[0] = 10.5
    bar.update(1)
    assert log.getvalue() == "[evotol] Monte Carlo: 100 poses; about 60 s (the first 1 pose: 10 s, the next 1: 0.5 s)\n"
    bar.update(1)
    assert log.getvalue().count("about") == 1                     # said once
    bar.close()
    two = io.StringIO()                                           # done at the second step: nothing to estimate
    with progress_bar(2, "GA", "gen", True, stream=two, every=1e9, delay=0.0) as short:
        short.update(1)
        short.update(1)
    assert "about" not in two.getvalue(), two.getvalue()
    one = io.StringIO()                                           # one step: the size is said when it ends
    with progress_bar(8, "Monte Carlo", "pose", True, size="8 poses × 20 samples", stream=one, every=1e9,
                      delay=0.0) as single:
        single.update(8)
    assert one.getvalue().startswith("[evotol] Monte Carlo: 8 poses × 20 samples; 8/8 pose in "), one.getvalue()


def test_progress_bar_default_is_a_bar_on_a_terminal_and_silent_in_a_log():
    from evotol._runtime.progress import progress_bar

    log, tty = io.StringIO(), _Terminal()
    for stream, progress in ((log, None), (tty, False), (log, False)):
        with progress_bar(3, "GA", "gen", progress, stream=stream, every=0.0, delay=0.0) as bar:
            bar.update(3)
        assert stream.getvalue() == "", (stream, progress)
    with progress_bar(3, "GA", "gen", None, stream=tty, delay=0.0) as bar:
        bar.update(3)
    assert "\r" in tty.getvalue() and "GA" in tty.getvalue()          # tqdm's redrawn bar


def test_run_shows_the_size_and_progress_of_every_long_method_in_a_log(tmp_path, capsys, monkeypatch):
    """`evotol run` turns progress on: GA, NSGA-II and Monte Carlo state their size and time
    estimate and print lines (here with the intervals set to 0 so an 8-pose study shows them)."""
    import functools

    import evotol.allocators.ga as ga
    import evotol.allocators.nsga_driver as nsga
    import evotol.verification.montecarlo as mc
    from evotol._runtime.progress import progress_bar
    from tests.fast_study import fast_study

    for module in (ga, nsga, mc):
        monkeypatch.setattr(module, "progress_bar", functools.partial(progress_bar, every=0.0, delay=0.0))
    f = fast_study(tmp_path, ("sensitivity = {}\n", "sensitivity = {}\nga = { pop_size = 8, n_gen = 3 }\n"
                                                    "nsga2 = { pop_size = 8, n_gen = 3 }\n"))
    assert main(["run", str(f), "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    for line in ("[evotol] GA: 3 generations × 8 designs × 8 poses; about ", "[evotol] GA: 3/3 gen in ",
                 "[evotol] NSGA-II: 3 generations × 8 designs × 8 poses; about ", "[evotol] NSGA-II: 3/3 gen in ",
                 "[evotol] Monte Carlo: 8 poses × 20 samples"):
        assert line in err, (line, err)


def test_run_prints_lines_for_a_method_without_a_bar(tmp_path, capsys, monkeypatch):
    """The exact optimum has no bar: off a terminal, `evotol run` prints the Heartbeat's line
    every interval while it runs (here 0.01 s, with a solve made to last 0.1 s)."""
    import functools

    import evotol.studyfile.run as sf
    from evotol._runtime.progress import Heartbeat
    from tests.fast_study import fast_study

    monkeypatch.setattr(sf, "Heartbeat", functools.partial(Heartbeat, every=0.01))
    slow = sf.METHODS["sensitivity"]

    def sensitivity(problem, **kw):
        time.sleep(0.1)
        return slow(problem, **kw)

    monkeypatch.setitem(sf.METHODS, "sensitivity", sensitivity)
    assert main(["run", str(fast_study(tmp_path)), "--out", str(tmp_path)]) == 0
    out = capsys.readouterr()       # progress on standard error, results alone on standard output (issue 40)
    assert "[evotol] sensitivity: running for " in out.err and "running for" not in out.out
    assert main(["run", str(fast_study(tmp_path)), "--out", str(tmp_path), "--force", "-q"]) == 0
    assert "running for" not in capsys.readouterr().err        # -q: no progress


def test_heartbeat_bar_on_a_terminal_shows_the_elapsed_time():
    """A method of unknown length (the exact optimum) gets a tqdm line on a terminal: after its
    2 s delay it reads 'optimum: running for 00:02'; off a terminal the lines of the log instead."""
    out, err = _Terminal(), _Terminal()
    with Heartbeat("optimum", stream=out, bar=True, bar_stream=err):
        time.sleep(3.2)
    assert "optimum: running for 00:0" in err.getvalue() and "\r" in err.getvalue()
    assert out.getvalue() == ""
    log, err2 = io.StringIO(), _Terminal()
    with Heartbeat("optimum", every=0.02, stream=log, bar=True, bar_stream=err2):
        time.sleep(0.1)
    assert "[evotol] optimum: running for" in log.getvalue() and err2.getvalue() == ""


# --- issue 43: the expected time is this machine's last run when the folder records one -----------
def test_heartbeat_quotes_the_last_run_in_the_folder_else_the_projects_machine(tmp_path):
    from evotol._runtime.output_set import read_manifest
    from evotol._runtime.progress import last_run_seconds, run_hint

    assert last_run_seconds(tmp_path, "drake1999-motor", quick=True) is None
    assert run_hint("drake1999-motor", tmp_path, quick=True) == (
        f"a full run takes about {EXPECTED_SECONDS['drake1999-motor']} s on the project's 2-core machine")
    studies.get("drake1999-motor").run(tmp_path, quick=True)
    m = read_manifest(tmp_path, "drake1999-motor")
    took = m["finished"] - m["started"]
    assert m["complete"] is True and m["quick"] is True and took > 0
    assert last_run_seconds(tmp_path, "drake1999-motor", quick=True) == took
    assert last_run_seconds(tmp_path, "drake1999-motor", quick=False) is None     # a quick run is not a full one
    beat = Heartbeat("drake1999-motor", out=tmp_path, quick=True)
    assert beat.hint == f"its last quick run in this folder took {took:.0f} s"
    # read when made: the run that follows rewrites the manifest as incomplete, the hint stays
    (tmp_path / "drake1999-motor.manifest.json").write_text('{"complete": false, "started": 1.0}')
    assert beat.hint.startswith("its last quick run") and last_run_seconds(tmp_path, "drake1999-motor", quick=True) is None
    log = io.StringIO()
    with Heartbeat("drake1999-motor", every=0.02, stream=log, out=tmp_path, quick=True):
        deadline = time.monotonic() + 10
        while "running for" not in log.getvalue() and time.monotonic() < deadline:
            time.sleep(0.01)
    assert "(a full run takes about" in log.getvalue().splitlines()[0]


def test_reproduce_all_orders_by_this_machines_last_runs_only_when_every_study_has_one(tmp_path):
    import json

    from evotol.cli.parallel_studies import longest_first

    names = ["drake1999-motor", "yao2013", "process-stack"]
    table = longest_first(names)
    assert table == sorted(names, key=lambda n: -EXPECTED_SECONDS[n])
    took = {"drake1999-motor": 50.0, "yao2013": 5.0, "process-stack": 20.0}    # this machine, unlike the table
    for n, s in list(took.items())[:2]:
        (tmp_path / f"{n}.manifest.json").write_text(json.dumps({"complete": True, "quick": False, "started": 100.0,
                                                                 "finished": 100.0 + s}))
    assert longest_first(names, tmp_path) == table                    # one study unknown: no mix, the table
    (tmp_path / "process-stack.manifest.json").write_text(json.dumps({"complete": True, "quick": False,
                                                                      "started": 100.0, "finished": 120.0}))
    assert longest_first(names, tmp_path) == ["drake1999-motor", "process-stack", "yao2013"]
    assert longest_first(names, tmp_path, quick=True) == table        # those were full runs

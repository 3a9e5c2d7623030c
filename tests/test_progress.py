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
    assert lines[0].startswith("[evotol] GA: 5 generations × 8 designs × 3 poses; about ")
    assert "from the first 1 gen" in lines[0]
    assert any(line.startswith("[evotol] GA: 3/5 gen (60 %)") for line in lines), lines
    assert lines[-1].startswith("[evotol] GA: 5/5 gen in ") and lines[-1].endswith("best=1.5"), lines
    # rate limit: set_postfix refreshes at every step, the log gets at most a line per interval
    slow = io.StringIO()
    with progress_bar(50, "GA", "gen", True, stream=slow, every=60.0, delay=0.0) as bar:
        for _ in range(50):
            bar.update(1)
            bar.set_postfix(best="1")
    assert len(slow.getvalue().splitlines()) <= 2, slow.getvalue()


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
                                                    "nsga2 = { pop_size = 8, n_gen = 2 }\n"))
    assert main(["run", str(f), "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    for line in ("[evotol] GA: 3 generations × 8 designs × 8 poses; about ", "[evotol] GA: 3/3 gen in ",
                 "[evotol] NSGA-II: 2 generations × 8 designs × 8 poses; about ", "[evotol] NSGA-II: 2/2 gen in ",
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

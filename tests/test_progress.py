"""Issue 15: `reproduce` prints progress lines when stdout is not a terminal; `list` gives run times."""
from __future__ import annotations

import io
import time

from evotol import studies
from evotol.cli import main
from evotol.progress import EXPECTED_SECONDS, Heartbeat


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

"""The per-study time table printed at the end of ``evotol reproduce all`` (issue 13), through the
command itself (``evotol.cli.main``) on two stand-in studies, one of which fails."""
import re

from evotol import studies
from evotol.cli import main
from evotol.errors import EvotolError


class _StandIn:
    """What ``evotol reproduce`` reads of a study: name, title, seed paper, config and ``run``."""

    seed_paper = ""
    config = {}

    def __init__(self, name, fails=False):
        self.name, self.title, self.fails = name, f"stand-in {name}", fails

    def run(self, out, quick=False, seed=0):
        if self.fails:
            raise EvotolError("planned failure")
        return {"seconds": 0.0}


def test_time_table_lists_every_study_its_seconds_and_the_total(capsys, monkeypatch, tmp_path):
    fake = {"deng2012-5bar": _StandIn("deng2012-5bar"), "yao2013": _StandIn("yao2013", fails=True)}
    monkeypatch.setattr(studies, "available", lambda: dict(fake))
    monkeypatch.setattr(studies, "get", lambda name: fake[name])
    assert main(["reproduce", "all", "--jobs", "1", "--out", str(tmp_path)]) == 1       # one study failed
    out = capsys.readouterr().out.splitlines()
    start = next(i for i, line in enumerate(out) if line.startswith("[evotol] run times (load average "))
    number = r"\d+\.\d"                                   # seconds to one decimal
    assert re.fullmatch(rf"  deng2012-5bar +{number} s", out[start + 1]), out[start + 1]
    assert re.fullmatch(rf"  yao2013 +{number} s  \(failed\)", out[start + 2]), out[start + 2]
    assert re.fullmatch(rf"  total +{number} s", out[start + 3]), out[start + 3]
    # the columns line up: every number ends in the same column
    assert len({len(line.split(" s")[0]) for line in out[start + 1:start + 4]}) == 1

"""The per-study time table printed at the end of ``evotol reproduce all`` (issue 13)."""
from evotol.cli import _print_time_table


def test_time_table_lists_every_study_its_seconds_and_the_total(capsys):
    _print_time_table({"deng2012-5bar": 12.25, "yao2013": 3.0}, ["yao2013"], 15.5)
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("[evotol] run times (load average ")
    assert out[1].split() == ["deng2012-5bar", "12.2", "s"]        # 12.25 rounds to one decimal
    assert out[2].split() == ["yao2013", "3.0", "s", "(failed)"]
    assert out[3].split() == ["total", "15.5", "s"]

"""Every public function and class of the front door (``evotol.__all__``) that a user calls carries
numpydoc ``Parameters`` and ``Raises`` sections (a plain value checked later: ``Raises`` on its
``validate``), and every function a ``Returns`` section (issue 26 item 6). The site built from them
(``docs/``) is checked by CI with ``sphinx -W``."""
from __future__ import annotations

import inspect
import re
import subprocess
import sys
from pathlib import Path

import pytest

import evotol

SECTION = "^ *{}\n *-{{3,}}$"

#: front-door names that are not called with arguments (errors, protocols, result records)
NOT_CALLED = {"EvotolError", "ValidationError", "KinematicsError", "ConvergenceError", "InfeasibleError",
              "RobotErrorModel", "Evaluation", "AllocationResult", "MonteCarloResult", "ParetoFront",
              "ProcessResult"}
#: plain values checked later: their ``validate`` (or the problem that holds them) raises
PLAIN_VALUES = {"Tolerance", "Requirement", "Process", "Distribution"}


def _sections(obj) -> set[str]:
    doc = inspect.getdoc(obj) or ""
    return {s for s in ("Parameters", "Returns", "Raises") if re.search(SECTION.format(s), doc, re.M)}


@pytest.mark.parametrize("name", [n for n in evotol.__all__ if n not in NOT_CALLED])
def test_front_door_numpydoc_sections(name):
    obj = getattr(evotol, name)
    need = {"Parameters", "Returns"} if inspect.isfunction(obj) else {"Parameters"}
    missing = need - _sections(obj)
    raises = obj.validate if name in PLAIN_VALUES and hasattr(obj, "validate") else obj
    if name not in PLAIN_VALUES or raises is not obj:
        missing |= {"Raises"} - _sections(raises)
    assert not missing, f"evotol.{name} ({obj.__module__}) lacks numpydoc section(s) {sorted(missing)}"


def test_section_pattern_finds_a_section_and_misses_prose():
    """The check itself: a numpydoc header is found, the word in running text is not."""
    def with_section():
        """Do.

        Parameters
        ----------
        x : float
            Length (m).
        """

    def prose():
        """Parameters are described in the module docstring; Returns nothing."""

    assert _sections(with_section) == {"Parameters"}
    assert _sections(prose) == set()


def test_site_builds_with_warnings_as_errors(tmp_path):
    """The docs/ pages and the API reference build with ``sphinx -W`` (as ``.ci/run`` does), so a
    docstring that is not valid reStructuredText (``|x|`` is a substitution) fails here, before it
    reaches main. Skipped without the ``docs`` extra; the dummy builder parses every page and
    docstring but writes no HTML."""
    pytest.importorskip("sphinx")
    pytest.importorskip("numpydoc")
    pytest.importorskip("myst_parser")
    docs = Path(__file__).resolve().parents[1] / "docs"
    run = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "dummy", str(docs),
                          str(tmp_path / "site")], capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-4000:]

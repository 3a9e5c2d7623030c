"""The front door is typed (issue 40): evotol ships ``py.typed``, and mypy accepts a user's script
that imports the names of ``evotol.__all__`` and calls them (tests/typing/front_door.py) while it
rejects a wrong call; the script also runs."""
from __future__ import annotations

import ast
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import evotol

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "tests" / "typing" / "front_door.py"


@pytest.fixture(scope="module")
def installed_layout(tmp_path_factory) -> Path:
    """evotol laid out as a wheel installs it (evotol/, evotol/robots/, evotol/cost_models/): mypy reads
    files, and a checkout keeps robots/ and cost_models/ beside evotol/ (setup.py maps them), which
    neither mypy nor an editable install's import hook can show it."""
    root = tmp_path_factory.mktemp("layout")
    keep = shutil.ignore_patterns("__pycache__", "*.pyc", "*.so", "urdf", "mechanisms", "data", "*.js")
    shutil.copytree(ROOT / "evotol", root / "evotol", ignore=keep)
    for name in ("robots", "cost_models"):
        shutil.copytree(ROOT / name, root / "evotol" / name, ignore=keep)
    return root


def _mypy(layout: Path, *files: Path) -> subprocess.CompletedProcess:
    pytest.importorskip("mypy", reason="mypy is in the test extra: pip install -e '.[test]'")
    return subprocess.run([sys.executable, "-m", "mypy", "--no-incremental", "--config-file", str(ROOT / "pyproject.toml"),
                           *map(str, files)], cwd=layout, capture_output=True, text=True, timeout=600)


def test_type_checking_names_are_the_front_door():
    """The ``if TYPE_CHECKING:`` imports of evotol/__init__.py (what mypy reads) name exactly
    ``evotol.__all__``, each from the module the lazy table names."""
    tree = ast.parse((ROOT / "evotol" / "__init__.py").read_text(encoding="utf-8"))
    block = next(n for n in tree.body if isinstance(n, ast.If) and getattr(n.test, "id", "") == "TYPE_CHECKING")
    typed = {a.asname or a.name: node.module for node in block.body for a in node.names}
    assert typed == dict(evotol._WHERE)


# Slow (~11 s in a full run) because its check is strong: mypy reads all of evotol (one run for both files).
def test_mypy_accepts_the_front_door_and_rejects_a_wrong_call(tmp_path, installed_layout):
    """One mypy run over both files (it checks evotol once, not twice; issue 43): every error it reports
    is in the wrong call's file -- none in the front-door script nor in evotol -- and the wrong call's
    two errors are there."""
    wrong = tmp_path / "wrong.py"
    wrong.write_text("from evotol import allocate_optimum, AllocationResult\n"
                     "x: int = allocate_optimum(None)\n")
    done = _mypy(installed_layout, SCRIPT, wrong)
    assert done.returncode == 1, done.stdout + done.stderr
    errors = [line for line in done.stdout.splitlines() if ": error:" in line]
    assert errors and all(line.startswith(str(wrong) + ":") for line in errors), done.stdout
    assert "Found 2 errors in 1 file (checked 2 source files)" in done.stdout, done.stdout
    assert 'Argument 1 to "allocate_optimum" has incompatible type "None"' in done.stdout, done.stdout
    assert 'Incompatible types in assignment (expression has type "AllocationResult"' in done.stdout, done.stdout


def test_the_front_door_script_runs():
    sys.path.insert(0, str(SCRIPT.parent))
    try:
        import front_door
    finally:
        sys.path.remove(str(SCRIPT.parent))
    problem, best, mc = front_door.study()
    assert best.feasible and mc.n_samples == 100 and front_door.refused() == "rng"

"""Conformance checks hold under ``python -O`` (issue 26 item 4): they raise the named error
:class:`evotol.errors.CheckFailed` instead of asserting, so stripping asserts strips nothing. Each
case runs in a subprocess started with ``-O`` and must fail on a broken plugin: a robot whose
sensitivities are all NaN, a cost model that rises with t, a measure whose errors fall as t grows."""
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

PRELUDE = '''
import numpy as np
from evotol.errors import CheckFailed
assert False, "asserts are not stripped: this is not python -O"
'''

CASES = {
    "robot with NaN sensitivities": '''
from evotol.robots.base import RobotErrorModel, SourceSpec, Workspace
from evotol.robots.checks import check_robot

class NaNRobot(RobotErrorModel):
    name = "nan"
    sources = (SourceSpec("a", 1, "m", "length"),)
    workspace = Workspace(("x",), (0.0,), (1.0,), ("m",))

    def sensitivity(self, poses):
        return np.full((len(self.check_poses(poses)), 6, 1), np.nan)

check_robot(NaNRobot())
''',
    "cost model rising with t": '''
from evotol.cost_models import CallableCost
from evotol.cost_models.checks import check_cost_model

check_cost_model(CallableCost(lambda t: 1.0 + 1e4 * t, lambda t: 1e4 + 0 * t, name="rising"), 1e-6, 1e-4)
''',
    "measure falling with t": '''
from evotol.core.measure_checks import check_measure
from evotol.measures.builtin.worst_case import WorstCaseMeasure

class Falling(WorstCaseMeasure):
    name = "falling"

    def evaluate(self, problem, T, top_only=False):
        ev = super().evaluate(problem, T, top_only)
        ev.position = 1e-12 / ev.position
        return ev

check_measure(Falling())
''',
}


@pytest.fixture(scope="module")
def optimised_run():
    """One ``python -O`` process runs every case, each in its own namespace, and prints one line per case
    (its first line: ``CheckFailed: ...``, ``passed`` or the unexpected error); a case's test reads its
    line. One process instead of one per case (issue 43): evotol is imported once (the file alone: 10.9 s -> 5.9 s)."""
    code = PRELUDE + "import traceback\n"
    for i, case in enumerate(sorted(CASES)):
        code += f"try:\n    exec(compile({CASES[case]!r}, {case!r}, 'exec'), {{'np': np, 'CheckFailed': CheckFailed}})\n" + f'''
except CheckFailed as exc:
    print({i}, "CheckFailed:", str(exc).splitlines()[0])
except Exception:
    print({i}, "raised:", traceback.format_exc().replace("\\n", " | "))
else:
    print({i}, "passed")
'''
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-O", "-c", code], env=env, capture_output=True, text=True, timeout=300)
    lines = dict(line.split(" ", 1) for line in out.stdout.splitlines() if line.split(" ", 1)[0].isdigit())
    return out, {case: lines.get(str(i), "") for i, case in enumerate(sorted(CASES))}


@pytest.mark.parametrize("case", sorted(CASES))
def test_check_fails_under_python_O(case, optimised_run):
    out, lines = optimised_run
    assert out.returncode == 0, out.stderr
    assert lines[case].startswith("CheckFailed:"), out.stdout

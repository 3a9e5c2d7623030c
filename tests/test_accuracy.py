"""Measures as plugins (issue 26 item 1): every registered measure passes the conformance checks
(monotone in t, equal to its brute force on a small problem, vectorised equal to a loop); each
check can fail; a measure from outside the package plugs in through the entry-point group
``evotol.measures`` and is selected by ``Requirement(measure=...)``."""
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from evotol.measures import Evaluation, available, get, names
from evotol.measures.protocol import ComponentErrors, evaluation_of, violation
from evotol.core.measure_checks import CHECKS, check_measure, measure_checks, small_problem
from evotol.measures.builtin.worst_case import WorstCaseMeasure
from evotol.errors import CheckFailed, ValidationError
from evotol.core.problem import Requirement

ROOT = Path(__file__).resolve().parents[1]
MEASURES = sorted(available())


def test_builtin_measures_registered():
    assert names()[:4] == ("worst_case", "rss", "mc_quantile", "yield")


@pytest.mark.parametrize("name, check", [(m, c.__name__) for m in MEASURES for c in CHECKS])
def test_registered_measure(name, check):
    """Every registered measure (built-ins and entry points), every check."""
    dict(measure_checks(get(name)))[check]()


def test_worst_case_equals_vertex_search_and_rss_closed_form():
    """The two exact measures on the checks' small problem against independent computations:
    worst case = the largest |J e| over the 16 vertices of the tolerance box; RSS =
    sqrt(Σ_j (t_j |J_:,j|)²) (1-D sources: the singular value is the column norm)."""
    P = small_problem()
    t = np.array([3e-5, 5e-5, 7e-5, 9e-5])
    ev = P.evaluate(t, "worst_case")
    corners = np.array(np.meshgrid(*[[-1, 1]] * 4)).reshape(4, -1).T * t
    J = P.jacobian[:, 0:3]
    exact = np.max(np.linalg.norm(np.einsum("pik,sk->psi", J, corners), axis=2), axis=1)
    np.testing.assert_allclose(ev.position[0], exact, rtol=1e-12)
    assert np.all(ev.position_bound[0] >= exact)
    rss = np.sqrt(np.sum((t * np.linalg.norm(J, axis=1)) ** 2, axis=1))
    np.testing.assert_allclose(P.evaluate(t, "rss").position[0], rss, rtol=1e-12)


class _Broken(WorstCaseMeasure):
    """A worst case broken in one way at a time (to show each check can fail)."""

    def __init__(self, how):
        self.how, self.name = how, f"broken-{how}"

    def evaluate(self, problem, T, top_only=False):
        ev = super().evaluate(problem, T, top_only)
        if self.how == "decreasing":       # error falls as t grows
            ev.position = 1e-3 / np.sum(T, axis=1, keepdims=True) * np.ones_like(ev.position) * 1e-8
        elif self.how == "biased":         # 1 % too small: not the brute force
            ev.position = 0.99 * ev.position
        elif self.how == "batch":          # depends on the other designs of the batch
            ev.position = ev.position * (1 + 0.01 * (T.shape[0] - 1))
        elif self.how == "violation":      # a violation that ignores the bound
            ev.violation = ev.violation + 1
        return ev


@pytest.mark.parametrize("how, failing", [("decreasing", "check_monotone_in_t"),
                                          ("biased", "check_equals_brute_force"),
                                          ("batch", "check_vectorised"),
                                          ("violation", "check_returns_evaluation")])
def test_each_check_can_fail(how, failing):
    checks = dict(measure_checks(_Broken(how)))
    with pytest.raises(CheckFailed):
        checks[failing]()
    with pytest.raises(CheckFailed, match=failing):
        check_measure(_Broken(how))


def test_unknown_measure_names_the_nearest():
    with pytest.raises(ValidationError, match=r"requirement.measure = 'worst_cas'.*did you mean 'worst_case'"):
        Requirement(position=1e-3, measure="worst_cas").validate()


def test_evaluation_of_fills_only_the_given_components():
    v = np.array([[1.0, 2.0]])
    ev = evaluation_of({"position": ComponentErrors(v, 2 * v)}, np.array([0.5]))
    assert isinstance(ev, Evaluation) and ev.orientation is None and ev.position_bound[0, 1] == 4.0
    P = small_problem()     # position bound 2e-4 m: violation = max / bound − 1
    assert violation(P, {"position": ComponentErrors(np.array([[1e-4, 3e-4]]))})[0] == pytest.approx(0.5)


PLUGIN = '''
"""A measure from outside evotol: the triangle-inequality bound Σ_j t_j ‖B_j‖₂ per pose."""
import numpy as np

from evotol.measures.protocol import COMPONENTS, ComponentErrors, Measure, evaluation_of, violation


class Triangle(Measure):
    name = "triangle"

    def evaluate(self, problem, T, top_only=False):
        parts = {}
        for c in COMPONENTS:
            val = T @ problem.sensitivities[c].T
            parts[c] = ComponentErrors(val, val)
        return evaluation_of(parts, violation(problem, parts))

    def brute_force(self, problem, t):
        return {c: np.array([sum(t[j] * np.linalg.svd(B[p], compute_uv=False)[0]
                                 for j, B in enumerate(problem.blocks[c])) for p in range(problem.n_poses)])
                for c in COMPONENTS}


TRIANGLE = Triangle()
'''

SCRIPT = '''
import numpy as np
from evotol.measures import names
from evotol.core.measure_checks import check_measure, small_problem
from evotol.measures.registry import get

P = small_problem().with_requirement(measure="triangle")
t = np.array([3e-5, 5e-5, 7e-5, 9e-5])
tri = P.evaluate(t).position[0]
J = P.jacobian[:, 0:3]
closed = np.sum(t * np.linalg.norm(J, axis=1), axis=1)     # 1-D sources: |B_j| = column norm
wc = P.evaluate(t, "worst_case").position_bound[0]
check_measure(get("triangle"))
print("triangle" in names(), np.max(np.abs(tri - closed) / closed), bool(np.all(tri >= wc * (1 - 1e-12))))
'''


def test_measure_from_outside_the_package(tmp_path):
    """A distribution installed beside evotol (a dist-info with an ``evotol.measures`` entry point)
    adds the measure ``triangle``: registered, selected by the requirement, passing the checks,
    equal to its closed form and never below the worst case's proven bound."""
    (tmp_path / "toy_measure.py").write_text(PLUGIN)
    info = tmp_path / "toy_measure-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: toy-measure\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[evotol.measures]\ntriangle = toy_measure:TRIANGLE\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]))
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(SCRIPT)], env=env, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    registered, rel, above = out.stdout.split()
    assert registered == "True" and float(rel) < 1e-12 and above == "True"

"""The one NSGA-II driver (evotol/allocators/nsga_driver.py, issue 32 item 5): every front
(tolerances, design studies, process selection) runs through ``run_nsga2``; its callback, progress
display and Ctrl-C handling are checked here on a two-objective toy problem (Schaffer's
``f1 = x², f2 = (x − 2)²``, whose Pareto set is ``0 <= x <= 2``)."""
import numpy as np
import pytest
from pymoo.core.callback import Callback
from pymoo.core.problem import Problem

from evotol.allocators.nsga_driver import run_nsga2


class _Schaffer(Problem):
    def __init__(self):
        super().__init__(n_var=1, n_obj=2, xl=-10.0, xu=10.0)

    def _evaluate(self, X, out, *args, **kwargs):
        out["F"] = np.column_stack([X[:, 0] ** 2, (X[:, 0] - 2) ** 2])


class _Count(Callback):
    def __init__(self, stop_at=None):
        super().__init__()
        self.generations, self.stop_at = [], stop_at

    def notify(self, algo):
        self.generations.append(algo.n_iter)
        if self.stop_at is not None and algo.n_iter >= self.stop_at:
            raise KeyboardInterrupt


def test_driver_runs_n_gen_generations_with_the_callers_callback_and_a_progress_display():
    """The caller's callback sees every generation once; the progress display changes no number
    (same seed, same front with the bar on or off); the front lies in the Pareto set [0, 2]."""
    seen = _Count()
    with_bar = run_nsga2(_Schaffer(), pop_size=12, n_gen=6, seed=3, callback=seen, progress=True, size="toy")
    without = run_nsga2(_Schaffer(), pop_size=12, n_gen=6, seed=3)
    assert seen.generations == [1, 2, 3, 4, 5, 6]
    np.testing.assert_array_equal(with_bar.pop.get("X"), without.pop.get("X"))
    X = with_bar.opt.get("X")[:, 0]
    assert np.all((X > -0.05) & (X < 2.05)), X


def test_ctrl_c_keeps_the_population_only_when_interruptible():
    stopped = run_nsga2(_Schaffer(), pop_size=8, n_gen=50, seed=0, callback=_Count(stop_at=3), interruptible=True)
    assert stopped.n_iter == 3 and len(stopped.pop) == 8
    with pytest.raises(KeyboardInterrupt):
        run_nsga2(_Schaffer(), pop_size=8, n_gen=50, seed=0, callback=_Count(stop_at=3))


def test_every_front_runs_through_the_one_driver():
    """The tolerance front, the design front and the process front import the same function, and no
    other module of evotol builds pymoo's NSGA2 (a second driver would)."""
    from pathlib import Path

    from evotol.allocators import nsga
    from evotol.allocators.process import front
    from evotol.design import nsga as design_nsga

    assert nsga.run_nsga2 is design_nsga.run_nsga2 is front.run_nsga2 is run_nsga2
    root = Path(__file__).resolve().parents[1] / "evotol"
    builders = sorted(str(p.relative_to(root)) for p in root.rglob("*.py") if "NSGA2(" in p.read_text())
    assert builders == ["allocators/nsga_driver.py"], builders

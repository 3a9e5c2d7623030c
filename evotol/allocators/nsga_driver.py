"""The one NSGA-II driver of evotol: pymoo's ``NSGA2``, its termination, its loop and its hooks.

Every Pareto front evotol computes runs through :func:`run_nsga2`: the tolerance front
(:func:`evotol.allocators.allocate_nsga2`), the design-study front (:func:`evotol.design.nsga2`),
the process-selection front (:func:`evotol.allocators.process.process_front`) and the ISO 9283 front of cost
against AP (:func:`evotol.allocators.iso9283_front.allocate_iso9283_front`). Each brings its
own pymoo ``Problem`` (what a decision vector means, what the objectives are) and, when it needs
per-generation work (lazy constraint checks, a history), a pymoo ``Callback``; the driver owns the
rest: the algorithm's settings (duplicates eliminated), the ``n_gen`` termination, pymoo's
``while has_next(): next()`` loop, the progress display (:func:`evotol._runtime.progress.progress_bar`,
advanced by a callback of its own) and what Ctrl-C does.
"""
from __future__ import annotations

from pymoo.algorithms.moo.nsga2 import NSGA2
from pymoo.core.callback import Callback
from pymoo.core.problem import Problem
from pymoo.termination import get_termination

from evotol._runtime.progress import progress_bar


class _Callbacks(Callback):
    """The caller's callback, then one step of the progress bar, after every generation."""

    def __init__(self, callback: Callback | None, bar):
        super().__init__()
        self.callback, self.bar = callback, bar

    def notify(self, algo):
        if self.callback is not None:
            self.callback(algo)
        self.bar.update(1)


def run_nsga2(problem: Problem, *, pop_size: int, n_gen: int, seed: int, sampling=None, callback=None,
              progress: bool | None = False, size: str = "", verbose: bool = False,
              interruptible: bool = False, repair=None) -> NSGA2:
    """Run pymoo's ``NSGA2`` (duplicates eliminated) for ``n_gen`` generations on a pymoo ``problem``;
    return the algorithm (``algo.pop``, ``algo.opt``).

    Parameters
    ----------
    problem : pymoo.core.problem.Problem
        The pymoo problem (decision vectors and objectives in its own units).
    pop_size : int
        Population size.
    n_gen : int
        Number of generations.
    seed : int
        Seed of the run.
    sampling : numpy.ndarray or None
        Initial population (array of decision vectors, (pop_size, n_var)) or None (pymoo's
        random sampling).
    callback : pymoo.core.callback.Callback or None
        Called after every generation (lazy constraint checks, a history) -- pymoo's hook, so the
        loop itself stays pymoo's ``while has_next(): next()``.
    progress : bool or None, default False
        The progress display over generations (:func:`~evotol._runtime.progress.progress_bar`):
        None a bar on a terminal only, True also periodic lines off a terminal, False nothing.
    size : str
        The run's size, stated with the time estimate (``"60 generations × 60 designs"``).
    verbose : bool
        pymoo's per-generation printout.
    interruptible : bool
        If True, Ctrl-C ends the run early and keeps the population reached so far; otherwise
        the ``KeyboardInterrupt`` propagates.
    repair : pymoo.core.repair.Repair or None
        pymoo's repair, applied to every design before it is evaluated (the initial population and every
        offspring); None: none.

    Returns
    -------
    pymoo.algorithms.moo.nsga2.NSGA2
        The algorithm after the run: ``algo.pop`` (last population), ``algo.opt`` (its front).
    """
    kw = {**({} if sampling is None else {"sampling": sampling}), **({} if repair is None else {"repair": repair})}
    algo = NSGA2(pop_size=pop_size, eliminate_duplicates=True, **kw)
    with progress_bar(n_gen, "NSGA-II", "gen", progress, size=size) as bar:
        algo.setup(problem, termination=get_termination("n_gen", int(n_gen)), seed=seed, verbose=verbose,
                   callback=_Callbacks(callback, bar))
        try:
            while algo.has_next():
                algo.next()
        except KeyboardInterrupt:
            if not interruptible:
                raise
    return algo

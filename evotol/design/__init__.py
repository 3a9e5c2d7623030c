"""Design-of-experiments entries for design studies, and their chunked, resumable evaluation.

Deng (2012), Sec. VII.1.1 and Fig. VII.1: a design study evaluates many **entries** -- one value
per design variable (a tolerance level, a link length) -- and draws every entry as one line on
parallel coordinates. One module per job:

* :mod:`~evotol.design.factors` -- :class:`Factor`: one design variable, discrete ``levels`` or a
  continuous ``[low, high]``, optionally log-scaled; the shared column names;
* :mod:`~evotol.design.designs` -- :func:`full_factorial`, :func:`random_subset`,
  :func:`latin_hypercube`;
* :mod:`~evotol.design.evaluation` -- :func:`evaluate`: a picklable evaluator over chunks of entries
  on the one executor (:mod:`evotol._runtime.executor`: local processes or Dask, resumable store);
* :mod:`~evotol.design.nsga` -- :func:`nsga2`: NSGA-II over the factors' continuous ranges with the
  same evaluator, returning the Pareto entries and their knee points (:func:`evotol.core.pareto.knee_points`);
* :mod:`~evotol.design.files` -- :func:`save_entries` / :func:`load_entries` (CSV + Parquet; the
  factor definitions travel in the Parquet metadata so ``evotol filter`` knows the inputs).
"""
from evotol.design.designs import factorial_entries, full_factorial, latin_hypercube, n_factorial, random_subset
from evotol.design.evaluation import EvaluationLog, Evaluator, evaluate
from evotol.design.factors import ENTRY, ERROR, FEASIBLE, SOURCE, Factor, factors_of
from evotol.design.files import load_entries, save_entries
from evotol.design.nsga import Objective, nsga2
from evotol.core.pareto import knee_points

__all__ = ["Factor", "factors_of", "ENTRY", "ERROR", "FEASIBLE", "SOURCE",
           "n_factorial", "factorial_entries", "full_factorial", "random_subset", "latin_hypercube",
           "Evaluator", "EvaluationLog", "evaluate", "save_entries", "load_entries",
           "Objective", "nsga2", "knee_points"]

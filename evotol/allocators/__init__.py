"""Allocation methods and what each returns.

On a :class:`evotol.core.problem.ToleranceProblem` (an :class:`evotol.core.result.AllocationResult`, unless said):

* :func:`allocate_sensitivity` – the equal-effect rule the literature compares against;
* :func:`allocate_optimum` – exact optimum of the convex problem, with a certificate;
* :func:`allocate_ga` – single-objective GA (pymoo) with the penalty fitness of Yao 2013 eq. 15;
* :func:`allocate_nsga2` – cost vs. accuracy Pareto front (pymoo NSGA-II): a :class:`ParetoFront`;
* :func:`allocate_monotone` – best design + proven lower bound of a monotone, non-convex problem
  (joint clearances; polyblock outer approximation);
* :mod:`evotol.allocators.baselines` – equal tolerance, proportional scaling, Lagrange closed forms.

On a :class:`evotol.allocators.process.ProcessProblem` (process *and* tolerance per source; a
:class:`evotol.allocators.process.ProcessResult`, unless said):

* :func:`allocate_process_optimum` – exact (branch and bound or enumeration), certified;
* :func:`allocate_process_ga` – GA over process choices and tolerances;
* :func:`allocate_process_baselines` – a dict of the textbook rules on the cheapest feasible processes;
* :func:`process_front` – NSGA-II cost vs. error or vs. yield: a :class:`ParetoFront`.

Every allocator has one shape: ``allocate_x(problem, *, budget=None, seed=..., **options)`` -- the
problem first, everything else by keyword (``seed`` where the method is random; ``budget`` selects
*best accuracy at a budget*, and is refused with a one-line error by the methods that have no such
mode: NSGA-II, whose front spans every budget, and the polyblock bracket). What *feasible* means in
every result is one rule, :mod:`evotol.measures.feasibility`.

The parameters several definitions of this package share are described once, here.

Parameters
----------
problem : ToleranceProblem
    The problem (tolerances in SI: m or rad).
t : numpy.ndarray, (n_sources,)
    The design (m or rad).
"""
from evotol.allocators.baselines import allocate_equal, allocate_lagrange, allocate_proportional
from evotol.allocators.ga import allocate_ga
from evotol.allocators.monotone import allocate_monotone
from evotol.allocators.nsga import ParetoFront, allocate_nsga2
from evotol.allocators.optimum import allocate_optimum
from evotol.allocators.process import (Process, ProcessProblem, ProcessResult, allocate_process_baselines,
                                       allocate_process_ga, allocate_process_optimum, process_front)
from evotol.allocators.sensitivity import aggregated_sensitivity, allocate_sensitivity

__all__ = ["allocate_sensitivity", "allocate_optimum", "allocate_ga", "allocate_nsga2", "allocate_monotone", "ParetoFront",
           "allocate_equal", "allocate_proportional", "allocate_lagrange", "aggregated_sensitivity",
           "Process", "ProcessProblem", "ProcessResult", "allocate_process_optimum", "allocate_process_ga",
           "allocate_process_baselines", "process_front"]

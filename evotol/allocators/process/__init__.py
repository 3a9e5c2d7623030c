"""Process selection: choose a manufacturing process *and* a tolerance for every source.

Each source ``j`` has a list of candidate processes ``p`` (turning, grinding, honing...), each a
cost model ``c_p(t)``, a feasible tolerance range ``[lo_p, hi_p]`` and an optional fixed (set-up)
cost ``F_p``. A design picks one process per source and a tolerance inside that process's range:

    min_{p, t}  Σ_j [F_{p_j} + c_{p_j}(t_j)]   s.t.  the accuracy requirement,  lo_{p_j} <= t_j <= hi_{p_j}

(Chase, Greenwood, Loosli & Hauglund 1990; Loosli 1987, ADCATS report 87-4). Conventions:

* **a range clips the cost curve**: outside ``[lo_p, hi_p]`` a process cannot hold (below) or is
  not used for (above) the tolerance, so a design outside every range of a source is infeasible;
  inside it the cost is the curve's value (no extrapolation);
* **worst case vs. RSS** is the problem's ``Requirement.measure``: arithmetic stack
  ``Σ|S_j| t_j <= L`` or statistical stack ``sqrt(Σ (S_j t_j)²) <= L``;
* a process that costs more than another process of the same source everywhere on its range
  while the other's range covers it can never be chosen: evotol reports it as inconsistent data
  (usually a unit slip) unless ``check_dominance=False``.

Process selection is a layer over :class:`evotol.core.problem.ToleranceProblem`: a *process choice*
turns the problem into an ordinary convex allocation problem (:meth:`ProcessProblem.subproblem`),
which :func:`evotol.allocators.optimum.allocate_optimum` solves with a certificate. Methods:

* :func:`allocate_process_optimum` — exact: **branch and bound** over process choices (depth-first,
  children in order of their bound) or full enumeration. Node bound: the Lagrange dual
  ``q(λ) = Σ_j min_{p∈P_j} min_{t∈[lo_p,hi_p]} [F_p + c_p(t) + w_j t + v_j t²] − Σλ − Σμ``
  with ``w = Aᵀλ, v = Bᵀμ`` over the constraint rows (:mod:`evotol.measures.constraints`), sources already
  fixed taking their process only. Weak duality makes ``q(λ)`` a lower bound of every completion
  of the node for **any** ``λ, μ >= 0`` (no convexity needed); we take the best over a log-spaced
  family ``s·λ̂`` along the KKT multipliers ``λ̂`` of every leaf solved so far. A node whose
  tightest design (every tolerance at its smallest possible value) violates the rows is pruned as
  infeasible. Leaves are solved with ``allocate_optimum``. The result reports nodes, convex solves
  and the certificate (incumbent, smallest pruned bound, leaf duality gap).
* :func:`allocate_process_ga` — pymoo GA over one real gene per source, ``z_j ∈ [0, P_j)``:
  process ``⌊z_j⌋``, tolerance ``lo·(hi/lo)^{frac(z_j)}`` (log-uniform inside the range). One gene
  per source keeps the standard SBX / polynomial-mutation operators and a vectorised evaluation;
  crossing an integer moves to a neighbouring process. A boundary repair scales each design's
  tolerances onto the constraint boundary inside its processes' ranges (as ``allocate_ga`` does)
  and writes the genes back (Lamarckian).
* :func:`process_front` — NSGA-II, cost vs. normalised error (``max error / bound``).
* :func:`allocate_process_baselines` — the textbook route: cheapest feasible process per source
  (:func:`cheapest_feasible_processes`), then the sensitivity rule or the Lagrange closed form.

Modules: :mod:`~evotol.allocators.process.candidates` (Process),
:mod:`~evotol.allocators.process.problem` (ProcessProblem, assembly_problem),
:mod:`~evotol.allocators.process.result` (ProcessResult), :mod:`~evotol.allocators.process.branch_and_bound`,
:mod:`~evotol.allocators.process.baselines`, :mod:`~evotol.allocators.process.ga`,
:mod:`~evotol.allocators.process.front`.
"""
from __future__ import annotations

from evotol.allocators.process.baselines import allocate_process_baselines, cheapest_feasible_processes
from evotol.allocators.process.branch_and_bound import allocate_process_optimum
from evotol.allocators.process.front import FRONT_OBJECTIVES, process_front
from evotol.allocators.process.ga import allocate_process_ga
from evotol.allocators.process.candidates import Process
from evotol.allocators.process.problem import ProcessProblem, assembly_problem
from evotol.allocators.process.result import FEAS_TOL, ProcessResult

__all__ = ["Process", "ProcessProblem", "ProcessResult", "assembly_problem", "allocate_process_optimum",
           "allocate_process_ga", "allocate_process_baselines", "cheapest_feasible_processes", "process_front",
           "FRONT_OBJECTIVES", "FEAS_TOL"]

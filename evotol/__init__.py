"""evotol: cost-optimal tolerance allocation for robots and mechanisms.

One front door: every name a user needs is importable from ``evotol``::

    from evotol import ToleranceProblem, Tolerance, Requirement, allocate_optimum, allocate_ga, verify

The names are loaded on first use (PEP 562 module ``__getattr__``), so ``import evotol`` and
``evotol --help`` do not import NumPy, SciPy, pymoo or Pinocchio. The table below is the one place
that says where each name lives; ``tests/test_front_door.py`` imports every one of them.
"""
from __future__ import annotations

import importlib

__version__ = "0.1.0"

#: public name -> module that defines (or re-exports) it
_WHERE = {
    # the problem
    "Tolerance": "evotol.core.problem",
    "Requirement": "evotol.core.problem",
    "ToleranceProblem": "evotol.core.problem",
    "Evaluation": "evotol.core.problem",
    # allocators
    "allocate_sensitivity": "evotol.allocators",
    "allocate_optimum": "evotol.allocators",
    "allocate_ga": "evotol.allocators",
    "allocate_nsga2": "evotol.allocators",
    "allocate_monotone": "evotol.allocators",
    "allocate_equal": "evotol.allocators",
    "allocate_proportional": "evotol.allocators",
    "allocate_lagrange": "evotol.allocators",
    # process selection
    "Process": "evotol.allocators",
    "ProcessProblem": "evotol.allocators",
    "ProcessResult": "evotol.allocators",
    "allocate_process_optimum": "evotol.allocators",
    "allocate_process_ga": "evotol.allocators",
    "allocate_process_baselines": "evotol.allocators",
    "process_front": "evotol.allocators",
    "assembly_problem": "evotol.allocators.process",
    # sources beyond intervals
    "Distribution": "evotol.measures.statistical.distributions",
    "ClearanceClass": "evotol.measures.clearances",
    "ClearanceSources": "evotol.measures.clearances",
    # results and verification
    "AllocationResult": "evotol.core.result",
    "ParetoFront": "evotol.allocators",
    "verify": "evotol.verification.montecarlo",
    "MonteCarloResult": "evotol.verification.montecarlo",
    # errors
    "EvotolError": "evotol.errors",
    "ValidationError": "evotol.errors",
    "KinematicsError": "evotol.errors",
    "ConvergenceError": "evotol.errors",
    "InfeasibleError": "evotol.errors",
    # mechanisms and assemblies
    "MechanismModel": "evotol.robots.mechanism.model",
    "AssemblyFunction": "evotol.robots.assembly",
    "LinearStack": "evotol.robots.assembly",
    "RobotErrorModel": "evotol.robots.base",
}

__all__ = sorted(_WHERE)


def __getattr__(name: str):
    try:
        module = _WHERE[name]
    except KeyError:
        raise AttributeError(f"module 'evotol' has no attribute {name!r}") from None
    # no caching in the module's globals: import_module returns the already-imported module, so a
    # repeated access costs one dict lookup more, and no module state is rewritten
    return getattr(importlib.import_module(module), name)


def __dir__():
    return sorted(set(globals()) | set(_WHERE))

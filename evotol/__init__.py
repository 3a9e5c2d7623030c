"""evotol: cost-optimal tolerance allocation for robots and mechanisms.

One front door: every name a user needs is importable from ``evotol``::

    from evotol import ToleranceProblem, Tolerance, Requirement, allocate_optimum, allocate_ga, verify

The names are loaded on first use (PEP 562 module ``__getattr__``), so ``import evotol`` and
``evotol --help`` do not import NumPy, SciPy, pymoo or Pinocchio. The table below is the one place
that says where each name lives; ``tests/test_front_door.py`` imports every one of them.
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
from pathlib import Path

#: sub-packages kept in the repository's own top-level folders (the design card's ``robots/``,
#: ``cost_models/``); an installed evotol holds them inside its folder (setup.py maps them)
_MAPPED = ("robots", "cost_models")


class _SourceTreeFinder(importlib.abc.MetaPathFinder):
    """``evotol.robots`` / ``evotol.cost_models`` from a checkout's ``robots/`` and ``cost_models/`` when
    evotol is imported from the source tree itself (the repository root on ``sys.path``), as an
    editable install does through setup.py's mapping."""

    def __init__(self, root: Path):
        self.root = root

    def find_spec(self, fullname, path=None, target=None):
        head, _, name = fullname.partition(".")
        if head != __name__ or name not in _MAPPED:
            return None
        folder = self.root / name
        return importlib.util.spec_from_file_location(fullname, folder / "__init__.py",
                                                      submodule_search_locations=[str(folder)])


_HERE = Path(__file__).resolve().parent
if not (_HERE / "robots").is_dir() and (_HERE.parent / "robots" / "__init__.py").is_file() \
        and (_HERE.parent / "pyproject.toml").is_file():
    sys.meta_path.insert(0, _SourceTreeFinder(_HERE.parent))     # before an editable install of another checkout
from typing import TYPE_CHECKING

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
    "MechanismModel": "evotol.robots.mechanism.model.error_model",
    "AssemblyFunction": "evotol.robots.assembly",
    "LinearStack": "evotol.robots.assembly",
    "RobotErrorModel": "evotol.robots.base",
}

__all__ = sorted(_WHERE)

if TYPE_CHECKING:          # what mypy and editors read: the same names, imported eagerly (issue 40)
    from evotol.allocators import (ParetoFront as ParetoFront, Process as Process,
        ProcessProblem as ProcessProblem, ProcessResult as ProcessResult, allocate_equal as allocate_equal,
        allocate_ga as allocate_ga, allocate_lagrange as allocate_lagrange,
        allocate_monotone as allocate_monotone, allocate_nsga2 as allocate_nsga2,
        allocate_optimum as allocate_optimum, allocate_process_baselines as allocate_process_baselines,
        allocate_process_ga as allocate_process_ga, allocate_process_optimum as allocate_process_optimum,
        allocate_proportional as allocate_proportional, allocate_sensitivity as allocate_sensitivity,
        process_front as process_front)
    from evotol.allocators.process import assembly_problem as assembly_problem
    from evotol.core.problem import (Evaluation as Evaluation, Requirement as Requirement,
        Tolerance as Tolerance, ToleranceProblem as ToleranceProblem)
    from evotol.core.result import AllocationResult as AllocationResult
    from evotol.errors import (ConvergenceError as ConvergenceError, EvotolError as EvotolError,
        InfeasibleError as InfeasibleError, KinematicsError as KinematicsError,
        ValidationError as ValidationError)
    from evotol.measures.clearances import (ClearanceClass as ClearanceClass,
        ClearanceSources as ClearanceSources)
    from evotol.measures.statistical.distributions import Distribution as Distribution
    from evotol.verification.montecarlo import MonteCarloResult as MonteCarloResult, verify as verify
    from evotol.robots.assembly import AssemblyFunction as AssemblyFunction, LinearStack as LinearStack
    from evotol.robots.base import RobotErrorModel as RobotErrorModel
    from evotol.robots.mechanism.model.error_model import MechanismModel as MechanismModel


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

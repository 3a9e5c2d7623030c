"""Every method of a study checked against its problem before the first one runs (issue 34 item 6):
a refusal that would come after minutes of another method's work (the RSS optimum of asymmetric
intervals, a GA setting out of range, the sensitivity rule on clearances) comes first, in one line
naming the method.

Each check is the allocator's own (the same function the allocator calls), so the refusal and its
message are the allocator's.
"""
from __future__ import annotations

from evotol.allocators.ga import check_ga_options
from evotol.allocators.monotone import check_monotone_options
from evotol.allocators.optimum import check_optimum
from evotol.allocators.sensitivity import check_sensitivity
from evotol.core.problem import ToleranceProblem
from evotol.errors import ValidationError


def _check_sensitivity(problem: ToleranceProblem, **kw) -> None:
    check_sensitivity(problem)


def _check_ga(problem: ToleranceProblem, operators: str = "pymoo", pop_size: int = 100, n_gen: int = 200,
              seed: int = 0, **kw) -> None:
    check_ga_options(operators=operators, pop_size=pop_size, n_gen=n_gen, seed=seed)


def _check_optimum(problem: ToleranceProblem, budget=None, refine=False, **kw) -> None:
    check_optimum(problem, budget=budget, refine=refine)


def _check_monotone(problem: ToleranceProblem, max_evaluations=4000, rel_gap=1e-2, batch=16, **kw) -> None:
    check_monotone_options(max_evaluations=max_evaluations, rel_gap=rel_gap, batch=batch)


#: method name -> its check (keyword arguments: the method's table)
CHECKS = {"optimum": _check_optimum, "sensitivity": _check_sensitivity, "ga": _check_ga, "monotone": _check_monotone}


def check_methods(problem: ToleranceProblem, methods: dict) -> None:
    """Check every method's options against the problem, before any method runs.

    Parameters
    ----------
    problem : ToleranceProblem
        The study's problem.
    methods : dict
        Method name -> its keyword arguments (a study file's ``[methods]`` table).

    Raises
    ------
    evotol.errors.ValidationError
        The first refusal, its field prefixed by ``methods.NAME`` (e.g. ``methods.optimum:
        requirement.measure = 'rss': expected 'worst_case' for the exact optimum of asymmetric
        intervals ...``).
    """
    for m, kw in methods.items():
        check = CHECKS.get(m)
        if check is None:
            continue
        try:
            check(problem, **dict(kw))
        except ValidationError as exc:
            raise ValidationError(f"methods.{m}: {exc.field}", exc.value, exc.expected) from None

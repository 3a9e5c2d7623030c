"""A linear stack with process selection (Loosli 1987 / Chase et al. 1990 style): the axial gap of a
shaft-housing chain (housing − shoulder − spacer − bearing − spacer − circlip) within ±0.10 mm,
each of the six dimensions made by one of four processes (mill, turn, grind, hone: 4096
combinations), worst-case and RSS. Branch and bound is compared with the number of convex solves
full enumeration needs (every combination whose tightest design can hold the gap). See
``docs/process_selection.md``.
"""
from __future__ import annotations

import itertools

import numpy as np

from evotol.studies import Study, StudyResult
from evotol.studies._process_benchmarks import render_cases, run_case, stack_problem, summarise

CONFIG = {"seed": 0, "pop_size": 60, "n_gen": 100, "n_mc": 100_000}
QUICK = {"pop_size": 30, "n_gen": 30, "n_mc": 5_000}
CASES = {"worst_case": "gap within ±0.10 mm, worst case", "rss": "gap within ±0.10 mm, RSS (t = 3σ)"}
PUBLISHED = {"source": "B. G. Loosli, 'Manufacturing tolerance cost minimization using discrete optimization for alternate "
                       "process selection', ADCATS report 87-4, BYU 1987; Chase, Greenwood, Loosli & Hauglund 1990",
             "tables": None,
             "note": "only the reports' abstracts were retrievable in this session; the stack here is evotol's own, with "
                     "the illustrative process catalogue, so no published cost can be recomputed"}


def enumeration_solves(pp) -> int:
    """Convex solves full enumeration needs: combinations whose tightest design holds the requirement.

    Parameters
    ----------
    pp : evotol.allocators.process.ProcessProblem
        The process-selection problem.

    Returns
    -------
    int
        Number of process combinations whose tightest design (every tolerance at its process's
        lower limit) has normalised error <= 1.
    """
    combos = np.array(list(itertools.product(*[range(k) for k in pp.n_processes])))
    T = pp.lo[np.arange(pp.n_sources), combos]
    return int(np.sum(pp.normalised_error(T) <= 1 + 1e-9))


def compute(config: dict) -> StudyResult:
    """Solve the stack under both limits of ``CASES`` (worst case and RSS).

    Parameters
    ----------
    config : dict
        Study config: ``seed``, ``pop_size`` and ``n_gen`` (GA and NSGA-II), ``n_mc`` (nonlinear
        Monte Carlo samples).

    Returns
    -------
    StudyResult
        ``summary`` only: the published-source note, the worst-case case's headline costs (cost
        units, arbitrary) and per case the optimum, GA, baselines, fronts, Monte Carlo and
        ``enumeration_convex_solves``; tolerances in mm.
    """
    cases = {}
    for m in CASES:
        pp = stack_problem(m)
        case = run_case(pp, config, enumerate_all=False)
        case["enumeration_convex_solves"] = enumeration_solves(pp)
        cases[m] = case
    return StudyResult(summarise(cases, PUBLISHED, "worst_case"))


def render(result: StudyResult):
    """The HTML report of the study, from its summary.

    Returns
    -------
    evotol.reporting.html.Report
        The HTML report.
    """
    return render_cases("Linear stack with process selection", "Shaft-housing axial gap, six dimensions × four processes; "
                        "process data: evotol's illustrative catalogue.", result.summary, CASES)


STUDY = Study(name="process-stack", title="Linear stack: exact process selection vs. GA vs. baselines",
              compute=compute, render=render, config=CONFIG, quick=QUICK,
              seed_paper="Loosli 1987 (ADCATS 87-4); Chase, Greenwood, Loosli & Hauglund 1990")

"""Chase, Greenwood, Loosli & Hauglund 1990 / Chase handbook §14.7: the one-way clutch with process selection.

The contact angle φ = arccos((a + c)/(e − c)) of hub width a, roller radius c and ring radius e
must stay within ±2° of its nominal 7.018°, under the worst-case (arithmetic) and the statistical
(RSS) stack. Each dimension can be made by three processes (``_process_benchmarks.CATALOGUE``,
evotol's illustrative data). The study reports the exact optimum (branch and bound, checked by full
enumeration of the 27 combinations), the GA, the sensitivity-rule and Lagrange baselines on the
cheapest feasible processes, an NSGA-II cost/error front and a nonlinear Monte Carlo at the optimum.
See ``docs/process_selection.md``.
"""
from __future__ import annotations

from evotol.studies import Study, StudyResult
from evotol.studies._process_benchmarks import CLUTCH_PUBLISHED, clutch_problem, render_cases, run_case, summarise

CONFIG = {"seed": 0, "pop_size": 60, "n_gen": 100, "n_mc": 100_000}
QUICK = {"pop_size": 30, "n_gen": 30, "n_mc": 5_000}
CASES = {"worst_case": "worst-case limit |Δφ| <= 2° (arithmetic stack)",
         "rss": "statistical limit: RSS of the dimensions' effects <= 2° (t = 3σ)"}


def compute(config: dict) -> StudyResult:
    """Solve the clutch under both limits of ``CASES`` (worst case and RSS).

    Parameters
    ----------
    config : dict
        Study config: ``seed``, ``pop_size`` and ``n_gen`` (GA and NSGA-II), ``n_mc`` (nonlinear
        Monte Carlo samples).

    Returns
    -------
    StudyResult
        ``summary`` only: the published data, the worst-case case's headline costs (cost units,
        arbitrary) and per case the optimum (with its enumeration check), GA, baselines, fronts
        and Monte Carlo; tolerances in mm.
    """
    cases = {m: run_case(clutch_problem(m), config, enumerate_all=True) for m in CASES}
    return StudyResult(summarise(cases, CLUTCH_PUBLISHED, "worst_case"))


def render(result: StudyResult):
    """The HTML report of the study, from its summary.

    Returns
    -------
    evotol.reporting.html.Report
        The HTML report.
    """
    return render_cases("One-way clutch: process selection and tolerance allocation",
                        "Chase handbook §14.7 / Chase, Greenwood, Loosli & Hauglund 1990; contact angle "
                        "φ = arccos((a + c)/(e − c)), φ0 = 7.018°, limit ±2°. Process data: evotol's illustrative catalogue.",
                        result.summary, CASES)


STUDY = Study(name="chase1990-clutch", title="One-way clutch: exact process selection vs. GA vs. baselines",
              compute=compute, render=render, config=CONFIG, quick=QUICK,
              seed_paper="Chase, Greenwood, Loosli & Hauglund 1990 (Manufacturing Review 3(1)); Chase, D&T Handbook ch. 14")

"""The comparisons a study's sections ask for, run as ordinary methods inside the study's loop (issue 39).

A study with drawing callouts compares its exact zones with the independent-box rule
(:func:`evotol.studyfile.callouts.zone_comparison`); a calibrated study compares with the uncalibrated
robot (:func:`evotol.calibration.summary.calibration_summary`). Both are certified optima of another
problem. They run in the study's method loop -- under its Ctrl-C, its progress lines and its
keep-going rule -- and the summaries only read their results: a summary never allocates.
"""
from __future__ import annotations

from evotol.allocators import allocate_optimum
from evotol.studyfile.callouts import twin_problem
from evotol.studyfile.methods import method_options
from evotol.studyfile.poses import refine_option


def comparison_runs(spec: dict, problem, methods: dict) -> dict:
    """The comparison runs of a study: name -> (problem, keywords of :func:`allocate_optimum`).

    Parameters
    ----------
    spec : dict
        The parsed study file.
    problem : evotol.core.problem.ToleranceProblem
        The study's problem.
    methods : dict
        The study's methods (name -> keywords), as :func:`evotol.studyfile.methods.study_methods` gives them.

    Returns
    -------
    dict
        ``"callouts: exact"`` and ``"callouts: boxes"`` for a robot with callouts (the study's own zone
        model only when its optimum did not run with the same options); ``"uncalibrated"`` for a
        calibrated problem.
    """
    runs = {}
    callouts = problem.model.part_of("callouts")
    if callouts is not None:
        refine = refine_option(spec)
        opts = {"refine": refine} if refine else {}
        # the study's own optimum is its zone model's side of the comparison when it ran with these options
        own = "optimum" in methods and method_options(spec, "optimum", methods["optimum"]) == opts
        for zones in ("exact", "boxes"):
            if not (own and callouts.zones == zones):
                runs[f"callouts: {zones}"] = (problem if callouts.zones == zones else twin_problem(problem, zones), opts)
    if problem.calibration is not None:
        runs["uncalibrated"] = (problem.uncalibrated, {})
    return runs


def run_comparison(run) -> object:
    """Solve one comparison run: the certified optimum of its problem.

    Parameters
    ----------
    run : tuple
        ``(problem, keywords)`` from :func:`comparison_runs`.

    Returns
    -------
    evotol.core.result.AllocationResult
        The optimum.
    """
    problem, kw = run
    return allocate_optimum(problem, **kw)

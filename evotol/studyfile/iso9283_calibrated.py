"""The study's methods on the random sources inside ``[calibration]`` (issue 44, docs/iso9283.md).

With ``[calibration]`` and ``[iso9283] allocate = true`` the random sources are variables of the calibrated budget
and their least-cost design is :func:`evotol.calibration.random_allocation.least_cost`'s (the block's
``calibrated_budget.random_allocation``). A ``ga``, ``sensitivity``, ``equal``, ``lagrange`` or ``monotone`` among the study's
methods then allocates them in the same budget too (:mod:`evotol.calibration.random_rules`), beside its ordinary
run on the systematic sources, each judged by the budget's own check; the block's
``calibrated_budget.methods`` holds them.
"""
from __future__ import annotations

from evotol.calibration.random_rules import CALIBRATED_RULES, calibrated_design
from evotol.studyfile.methods import monotone_options, study_methods

#: the GA's settings the calibrated GA takes (the ordinary run takes the whole table)
GA_KEYS = ("pop_size", "n_gen", "seed")
def calibrated_methods(spec: dict, problem) -> dict:
    """The study's methods that also allocate the random sources in the calibrated budget, with their settings.

    Parameters
    ----------
    spec : dict
        The study file as read (its ``[methods]``).
    problem : evotol.core.problem.ToleranceProblem
        The study's problem (calibrated, when ``[calibration]`` is given).

    Returns
    -------
    dict
        Method -> settings (the GA's ``pop_size``, ``n_gen``, ``seed``; the bracket's
        :func:`evotol.studyfile.methods.monotone_options`;
        ``{}`` for a rule), in the study's order;
        empty without ``[calibration]`` or when the random sources are not allocated.
    """
    info = getattr(problem, "calibration", None)
    if info is None or info.random_budget is None:
        return {}
    methods = study_methods(spec, problem)
    return {m: ({k: int(v) for k, v in methods[m].items() if k in GA_KEYS} if m == "ga" else
                monotone_options(methods) if m == "monotone" else {})
            for m in methods if m in CALIBRATED_RULES}


def calibrated_allocations(iso, info, seed: int) -> dict:
    """Each wanted method's random tolerances in the calibrated budget (``calibrated_budget.methods``).

    Parameters
    ----------
    iso : evotol.studyfile.iso9283.IsoStudy
        The request (``calibrated``: method -> settings, :func:`calibrated_methods`).
    info : evotol.calibration.problem.CalibrationInfo
        The calibrated problem's ``calibration`` (its budget and least-cost design).
    seed : int
        The study's seed (the GA's unless it sets its own).

    Returns
    -------
    dict
        Method -> :func:`evotol.calibration.random_rules.calibrated_design`'s result.
    """
    names = [s.name for s in info.random.sources]
    return {m: calibrated_design(info.random_budget, m, info.random_allocation, names, seed, ga=opts if m == "ga" else None,
                                 monotone=opts if m == "monotone" else None)
            for m, opts in iso.calibrated.items()}


def calibrated_scope(names, methods: dict) -> dict:
    """What each of the study's methods allocated of the random sources inside ``[calibration]``: the block's
    key of its design in the calibrated budget, or None where it allocated the systematic sources alone.

    Parameters
    ----------
    names : iterable of str
        The methods that ran, in the study's order.
    methods : dict
        ``calibrated_budget.methods``.

    Returns
    -------
    dict
        Method name -> key (``optimum``: the least-cost design, ``calibrated_budget.random_allocation``).
    """
    return {n: "calibrated_budget.random_allocation" if n == "optimum" else
            (f"calibrated_budget.methods.{n}" if n in methods else None) for n in names}


def calibrated_budget(info) -> dict:
    """What the random sources take of a calibrated requirement (SI; docs/calibration.md, issue 44 item 4).

    Parameters
    ----------
    info : evotol.calibration.problem.CalibrationInfo
        The calibrated problem's ``calibration``.

    Returns
    -------
    dict
        ``requirement``, ``noise_only`` (the noise's quantile alone), ``random_identification`` (what the
        random sources add to it through the fit), ``random_worst_case`` (their largest effect at a task pose),
        ``second_order``, ``remainder``, ``geometric_bound`` (left for the systematic residual), all m, and
        ``random_allocation`` (cost, tolerances, whether the requirement binds) when they are allocated.
    """
    pos = info.noise.get("position", {})
    keys = ("noise_only", "random_identification", "random_worst_case", "second_order", "remainder", "geometric_bound")
    return {"requirement": pos.get("bound"), **{k: pos.get(k) for k in keys},
            "random_allocation": info.random_allocation,
            "meaning": "calibrated requirement = systematic residual (geometric_bound) + quantile of the fit's error "
                       "(noise_only + random_identification) + the random sources' worst case at a pose + second order"}


def calibrated_block(iso, info, results, seed: int) -> dict:
    """The ISO block's parts inside ``[calibration]``: ``calibrated_budget`` (:func:`calibrated_budget`, with
    ``methods``: :func:`calibrated_allocations`) and, when the random sources are allocated, ``methods``
    (:func:`calibrated_scope`).

    Parameters
    ----------
    iso, info, seed
        As :func:`calibrated_allocations`.
    results : dict
        The study's results (method -> result): which methods ran.

    Returns
    -------
    dict
    """
    out = {"calibrated_budget": calibrated_budget(info)}
    if iso.calibrated:
        out["calibrated_budget"]["methods"] = calibrated_allocations(iso, info, seed)
    if info.random_budget is not None:
        out["methods"] = calibrated_scope(results, out["calibrated_budget"].get("methods", {}))
    return out

"""The study's other methods beside ``[iso9283] allocate = true`` (issue 44 item 3, docs/iso9283.md).

With ``[requirement] iso9283`` and ``allocate = true`` (without ``[calibration]``) the ISO block's allocation of
systematic and random sources together is the certified optimum (:func:`evotol.allocators.iso9283.allocate_iso9283`).
A ``ga`` among the study's methods then allocates them too (:func:`evotol.allocators.iso9283_ga.allocate_iso9283_ga`,
judged by the optimum's own check), beside its ordinary run on the position requirement; ``nsga2``, whose front
knows neither the random sources nor AP/RP, is refused in one line before any work, and so are GA settings
and orientation figures the ISO GA does not take. A ``sensitivity`` among the methods allocates them by the
equal-effect rule too (:func:`evotol.allocators.iso9283_sensitivity.allocate_iso9283_sensitivity`), so that
the optimum shows what the rule costs.
"""
from __future__ import annotations

from evotol.allocators.ga import check_ga_options
from evotol.allocators.iso9283_ga import allocate_iso9283_ga
from evotol.allocators.iso9283_sensitivity import allocate_iso9283_sensitivity
from evotol.errors import ValidationError
from evotol.studyfile.methods import study_methods

#: the GA's settings the ISO GA takes (pymoo's operators; ``progress`` is the ordinary run's bar)
ISO_GA_KEYS = ("pop_size", "n_gen", "seed", "progress")


def iso_ga_options(spec: dict, problem, orientation: dict) -> dict | None:
    """The GA's settings when the GA allocates the random sources to AP/RP too; None when it does not.

    Parameters
    ----------
    spec : dict
        The study file.
    problem : evotol.core.problem.ToleranceProblem
        The study's problem (its default methods, whether anything is free).
    orientation : dict
        The orientation figures required (``APa`` .. ``RPc``).

    Returns
    -------
    dict or None
        ``pop_size``, ``n_gen`` and, if given, ``seed``.

    Raises
    ------
    evotol.errors.ValidationError
        One line: ``nsga2`` among the methods; a GA setting other than ``pop_size``, ``n_gen``, ``seed``; an
        orientation figure beside the GA.
    """
    table, req = spec.get("iso9283") or {}, spec.get("requirement", {}).get("iso9283")
    if not table.get("allocate") or not req or "calibration" in spec or not problem.free.any():
        return None
    methods = study_methods(spec, problem)
    if "nsga2" in methods:
        raise ValidationError("methods.nsga2", methods["nsga2"], "no nsga2 beside [iso9283] allocate = true: its front "
                              "trades cost against the position requirement and knows neither the random sources nor "
                              "AP/RP (the optimum and the ga allocate both; docs/iso9283.md)")
    if "ga" not in methods:
        return None
    ga = dict(methods["ga"])
    other = [k for k in ga if k not in ISO_GA_KEYS]
    if other:
        raise ValidationError(f"methods.ga.{other[0]}", ga[other[0]], "only pop_size, n_gen and seed beside [iso9283] "
                              "allocate = true (the ga then allocates the random sources to AP/RP too, pymoo's operators)")
    if orientation:
        k = next(iter(orientation))
        raise ValidationError(f"requirement.iso9283.{k}", req[k], "no orientation figure beside [methods] ga and "
                              "[iso9283] allocate = true: the ga allocates to AP and RP only (the optimum takes them: list "
                              "[methods] without ga)")
    check_ga_options(**{k: v for k, v in ga.items() if k in ("pop_size", "n_gen", "seed")})
    return {"pop_size": int(ga.get("pop_size", 100)), "n_gen": int(ga.get("n_gen", 200)),
            **({"seed": int(ga["seed"])} if "seed" in ga else {})}


def judged_design(iso, result: dict, optimum: dict) -> dict:
    """What the ISO block states of any allocator's design beside the optimum (SI): ``cost``, ``gap_to_optimum``
    (cost / optimum's − 1), ``feasible`` (:func:`evotol.allocators.iso9283.iso_check`), ``systematic`` and
    ``random`` (name -> tolerance), ``AP_bound``, ``RP_sampled``, ``RP_fresh_draws`` (per pose, m).

    Parameters
    ----------
    iso : evotol.studyfile.iso9283.IsoStudy
        The request (source names).
    result : dict
        The allocator's result (``cost``, ``feasible``, ``systematic``, ``random``, ``AP_bound``, ``RP``, ``RP_fresh``).
    optimum : dict
        :func:`evotol.allocators.iso9283.allocate_iso9283`'s result.

    Returns
    -------
    dict
    """
    return {"cost": result["cost"], "gap_to_optimum": result["cost"] / optimum["cost"] - 1, "feasible": result["feasible"],
            "systematic": dict(zip(iso.robot.source_names, result["systematic"].tolist())),
            "random": {s.name: float(t) for s, t in zip(iso.sources, result["random"])},
            "AP_bound": result["AP_bound"].tolist(), "RP_sampled": result["RP"].tolist(),
            "RP_fresh_draws": result["RP_fresh"].tolist()}


def ga_allocation(iso, problem, optimum: dict, seed: int) -> dict:
    """The ISO block's ``allocation_ga``: the GA on systematic and random sources together (SI).

    Parameters
    ----------
    iso : evotol.studyfile.iso9283.IsoStudy
        The request, with ``ga`` its GA settings (:func:`iso_ga_options`).
    problem : evotol.core.problem.ToleranceProblem
        The study's problem (bounds, cost models, which tolerances are free).
    optimum : dict
        :func:`evotol.allocators.iso9283.allocate_iso9283`'s result, for the gap.
    seed : int
        The study's seed (the GA's unless it sets its own; the RP draws are the optimum's).

    Returns
    -------
    dict
        ``cost``, ``gap_to_optimum`` (cost / optimum's − 1), ``feasible``, ``pop_size``, ``n_gen``,
        ``evaluations``, ``systematic`` and ``random`` (name -> tolerance), ``AP_bound``, ``RP_sampled``,
        ``RP_fresh_draws`` (per pose, m), ``meaning``.
    """
    tols = problem.tolerances
    opts = {**iso.ga, "seed": iso.ga.get("seed", seed)}
    ga = allocate_iso9283_ga(iso.robot, iso.positions, [tols[n].cost for n in iso.robot.source_names],
                             [problem.lower, problem.upper], problem.free, iso.sources, iso.costs, [iso.lower, iso.upper],
                             iso.AP, iso.RP, pop_size=opts["pop_size"], n_gen=opts["n_gen"], seed=opts["seed"],
                             draw_seed=seed)
    return {**judged_design(iso, ga, optimum),
            "pop_size": opts["pop_size"], "n_gen": opts["n_gen"], "seed": opts["seed"], "evaluations": ga["evaluations"],
            "meaning": "the study's ga on the systematic and random sources together (pymoo GA in log space, designs moved "
                       "onto the AP/RP boundary), judged by the optimum's check: feasible if the proven AP bound meets AP "
                       "and the RP on the optimum's fixed draws meets RP. The optimum aims its attained AP at AP cos δ, "
                       "the ga its proven bound at AP: a gap below 0 (at most about 0.4 %) is that margin, not a better design"}


def iso_sensitivity_wanted(spec: dict, problem, orientation: dict) -> bool:
    """Whether the study's ``sensitivity`` also allocates the random sources to AP/RP (the equal-effect rule).

    Parameters
    ----------
    spec, problem, orientation
        As :func:`iso_ga_options`.

    Returns
    -------
    bool
        True with ``sensitivity`` among the methods, ``[requirement] iso9283``, ``allocate = true`` and no
        ``[calibration]``.

    Raises
    ------
    evotol.errors.ValidationError
        One line: an orientation figure beside it (the rule shares AP and RP only).
    """
    table, req = spec.get("iso9283") or {}, spec.get("requirement", {}).get("iso9283")
    if not table.get("allocate") or not req or "calibration" in spec or not problem.free.any():
        return False
    if "sensitivity" not in study_methods(spec, problem):
        return False
    if orientation:
        k = next(iter(orientation))
        raise ValidationError(f"requirement.iso9283.{k}", req[k], "no orientation figure beside [methods] sensitivity and "
                              "[iso9283] allocate = true: the equal-effect rule shares AP and RP only (the optimum takes "
                              "them: list [methods] without sensitivity)")
    return True


def sensitivity_allocation(iso, problem, optimum: dict, seed: int) -> dict:
    """The ISO block's ``allocation_sensitivity``: the equal-effect rule on systematic and random sources (SI).

    Parameters
    ----------
    iso, problem, optimum, seed
        As :func:`ga_allocation` (the RP draws are the optimum's).

    Returns
    -------
    dict
        ``cost``, ``gap_to_optimum``, ``feasible``, ``systematic`` and ``random`` (name -> tolerance),
        ``AP_bound``, ``RP_sampled``, ``RP_fresh_draws`` (per pose, m), ``meaning``.
    """
    tols = problem.tolerances
    s = allocate_iso9283_sensitivity(iso.robot, iso.positions, [tols[n].cost for n in iso.robot.source_names],
                                     [problem.lower, problem.upper], problem.free, iso.sources, iso.costs,
                                     [iso.lower, iso.upper], iso.AP, iso.RP, seed=seed)
    return {**judged_design(iso, s, optimum),
            "meaning": "the equal-effect rule (each source the same share of AP by its largest effect per unit tolerance, "
                       "each random source the same root-sum-square share of RP), scaled onto the AP/RP boundary and "
                       "judged by the optimum's check: feasible if the proven AP bound meets AP and the RP on the "
                       "optimum's fixed draws meets RP; it ignores cost, the gap is what the optimum saves"}

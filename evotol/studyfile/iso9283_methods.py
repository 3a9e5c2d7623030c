"""The study's other methods beside ``[iso9283] allocate = true`` (issue 44 item 3, docs/iso9283.md).

With ``[requirement] iso9283`` and ``allocate = true`` (without ``[calibration]``) the ISO block's allocation of
systematic and random sources together is the certified optimum (:func:`evotol.allocators.iso9283.allocate_iso9283`).
A ``ga`` among the study's methods then allocates them too (:func:`evotol.allocators.iso9283_ga.allocate_iso9283_ga`,
judged by the optimum's own check), beside its ordinary run on the position requirement. An ``nsga2`` among them
runs its ordinary front on the position requirement and, beside it, the front of cost against AP on systematic and
random sources with every point holding RP (:func:`evotol.allocators.iso9283_front.allocate_iso9283_front`), judged
against the exact frontier of certified optima. Settings and orientation figures the ISO GA or front does not take,
and an ``nsga2`` beside ``[calibration]``, are refused in one line before any work.
A ``sensitivity``, ``equal`` or ``lagrange`` among the methods allocates them by its rule too: the equal-effect
rule (:func:`evotol.allocators.iso9283_sensitivity.allocate_iso9283_sensitivity`), equal tolerances and the Lagrange
closed form (:mod:`evotol.allocators.iso9283_baselines`), so that the optimum shows what each rule costs. A
``monotone`` among them brackets the least cost by polyblocks
(:func:`evotol.allocators.iso9283_monotone.allocate_iso9283_monotone`), its bracket stated beside the optimum.
"""
from __future__ import annotations

from evotol.allocators.ga import check_ga_options
from evotol.allocators.iso9283_front import allocate_iso9283_front
from evotol.allocators.iso9283_baselines import allocate_iso9283_equal, allocate_iso9283_lagrange
from evotol.allocators.iso9283_ga import allocate_iso9283_ga
from evotol.allocators.iso9283_monotone import allocate_iso9283_monotone
from evotol.allocators.iso9283_sensitivity import allocate_iso9283_sensitivity
from evotol.errors import ValidationError
from evotol.studyfile.methods import monotone_options, study_methods

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
        One line: a GA setting other than ``pop_size``, ``n_gen``, ``seed``; an orientation figure beside the GA.
    """
    req, methods = _beside_allocation(spec, problem)
    if "ga" not in methods or "calibration" in spec:
        return None
    return _iso_settings("ga", methods["ga"], req, orientation,
                         "the ga then allocates the random sources to AP/RP too", "the ga allocates to AP and RP only")


def _beside_allocation(spec: dict, problem) -> tuple[dict, dict]:
    """``[requirement] iso9283`` and the study's methods when ``[iso9283] allocate = true`` has a requirement and
    free tolerances (the methods may then allocate to AP/RP too); else ``({}, {})``."""
    table, req = spec.get("iso9283") or {}, spec.get("requirement", {}).get("iso9283")
    if not table.get("allocate") or not req or not problem.free.any():
        return {}, {}
    return req, study_methods(spec, problem)


def _iso_settings(method: str, table: dict, req: dict, orientation: dict, then: str, only: str) -> dict:
    """``pop_size``, ``n_gen``, ``seed`` of a method that also allocates to AP/RP; anything else refused in one line."""
    other = [k for k in table if k not in ISO_GA_KEYS]
    if other:
        raise ValidationError(f"methods.{method}.{other[0]}", table[other[0]], "only pop_size, n_gen and seed beside "
                              f"[iso9283] allocate = true ({then}, pymoo's operators)")
    if orientation:
        k = next(iter(orientation))
        raise ValidationError(f"requirement.iso9283.{k}", req[k], f"no orientation figure beside [methods] {method} and "
                              f"[iso9283] allocate = true: {only} (the optimum takes them: list [methods] without {method})")
    try:
        check_ga_options(**{k: v for k, v in table.items() if k in ("pop_size", "n_gen", "seed")})
    except ValidationError as e:
        raise ValidationError(f"methods.{method}.{e.field}", e.value, e.expected) from None
    return {"pop_size": int(table.get("pop_size", 100)), "n_gen": int(table.get("n_gen", 200)),
            **({"seed": int(table["seed"])} if "seed" in table else {})}


def allocator_args(iso, problem) -> tuple:
    """The ISO allocators' common arguments, from the study (SI): robot, poses, the systematic cost models and
    bounds, which systematic tolerances are free, the random sources with their cost models and bounds, AP, RP
    (:func:`evotol.allocators.iso9283.allocate_iso9283`).

    Parameters
    ----------
    iso : evotol.studyfile.iso9283.IsoStudy
        The request.
    problem : evotol.core.problem.ToleranceProblem
        The study's problem: its cost models, bounds and free tolerances.

    Returns
    -------
    tuple
    """
    tols = problem.tolerances
    return (iso.robot, iso.positions, [tols[n].cost for n in iso.robot.source_names], [problem.lower, problem.upper],
            problem.free, iso.sources, iso.costs, [iso.lower, iso.upper], iso.AP, iso.RP)


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
    opts = {**iso.ga, "seed": iso.ga.get("seed", seed)}
    ga = allocate_iso9283_ga(*allocator_args(iso, problem), pop_size=opts["pop_size"], n_gen=opts["n_gen"],
                             seed=opts["seed"], draw_seed=seed)
    return {**judged_design(iso, ga, optimum),
            "pop_size": opts["pop_size"], "n_gen": opts["n_gen"], "seed": opts["seed"], "evaluations": ga["evaluations"],
            "meaning": "the study's ga on the systematic and random sources together (pymoo GA in log space, designs moved "
                       "onto the AP/RP boundary), judged by the optimum's check: feasible if the proven AP bound meets AP "
                       "and the RP on the optimum's fixed draws meets RP. The optimum aims its attained AP at AP cos δ, "
                       "the ga its proven bound at AP: a gap below 0 (at most about 0.4 %) is that margin, not a better design"}


def iso_front_options(spec: dict, problem, orientation: dict) -> dict | None:
    """The ``nsga2`` settings when it also runs the ISO front (cost against AP, RP held); None when it does not.

    Parameters
    ----------
    spec, problem, orientation
        As :func:`iso_ga_options`.

    Returns
    -------
    dict or None
        ``pop_size``, ``n_gen`` (defaults 100, 200, as the ordinary front) and, if given, ``seed``.

    Raises
    ------
    evotol.errors.ValidationError
        One line: ``nsga2`` beside ``[calibration]``; a setting other than ``pop_size``, ``n_gen``, ``seed``; a
        ``pop_size`` below 4 or ``n_gen`` below 1; an orientation figure.
    """
    req, methods = _beside_allocation(spec, problem)
    if "nsga2" not in methods:
        return None
    refuse_front_beside_calibration(spec, methods)
    return _iso_settings("nsga2", methods["nsga2"], req, orientation, "the nsga2 then also runs the ISO front",
                         "the ISO front trades cost against AP with RP held only")


def refuse_front_beside_calibration(spec: dict, methods: dict) -> None:
    """Refuse an ``nsga2`` beside ``[calibration]`` and ``[iso9283] allocate = true`` with ``[requirement] iso9283``
    in one line (the ISO front does not take a calibrated budget); read from the file alone, before any work.

    Parameters
    ----------
    spec : dict
        The study file as read.
    methods : dict
        Its ``[methods]`` table (method -> settings).

    Raises
    ------
    evotol.errors.ValidationError
        That pair.
    """
    table = spec.get("iso9283") if isinstance(spec.get("iso9283"), dict) else {}
    if "calibration" in spec and "nsga2" in methods and table.get("allocate") \
            and (spec.get("requirement") or {}).get("iso9283"):
        raise ValidationError("methods.nsga2", methods["nsga2"], "no nsga2 beside [calibration] and [iso9283] allocate = "
                              "true: the ISO front (cost against AP, RP held) does not take a calibrated budget yet (list "
                              "[methods] without nsga2; docs/iso9283.md)")


def front_allocation(iso, problem, optimum: dict, seed: int) -> dict:
    """The ISO block's ``front_nsga2``: cost against AP on systematic and random sources, RP held (SI).

    Parameters
    ----------
    iso : evotol.studyfile.iso9283.IsoStudy
        The request, with ``front`` its settings (:func:`iso_front_options`).
    problem
        As :func:`ga_allocation`.
    optimum : dict
        :func:`evotol.allocators.iso9283.allocate_iso9283`'s result at the requirement, shown beside the front.
    seed : int
        The study's seed (the front's unless it sets its own; the RP draws are the optimum's).

    Returns
    -------
    dict
        ``points`` (each ``cost``, ``AP_bound``, ``AP_attained``, ``RP``, ``RP_fresh_draws``, ``gap``,
        ``systematic`` and ``random`` name -> tolerance), ``exact_frontier`` (each ``AP``, ``cost``, ``AP_bound``,
        ``feasible``), ``gap_method``, ``judged``, ``kept``, ``pop_size``, ``n_gen``, ``seed``, ``evaluations``,
        ``optimum`` (its ``cost`` and ``AP_bound``), ``requirement``, ``meaning``.
    """
    opts = {**iso.front, "seed": iso.front.get("seed", seed)}
    f = allocate_iso9283_front(*allocator_args(iso, problem), pop_size=opts["pop_size"], n_gen=opts["n_gen"],
                               seed=opts["seed"], draw_seed=seed)
    names = iso.robot.source_names
    points = [{"cost": p["cost"], "AP_bound": p["AP_bound"], "AP_attained": p["AP_attained"], "RP": p["RP"],
               "RP_fresh_draws": p["RP_fresh"], "gap": p["gap"],
               "systematic": {n: float(t) for n, t, fr in zip(names, p["systematic"], problem.free) if fr},
               "random": {s.name: float(t) for s, t in zip(iso.sources, p["random"])}} for p in f["points"]]
    return {"points": points, "judged": f["judged"], "kept": f["kept"], "pop_size": opts["pop_size"],
            "n_gen": opts["n_gen"], "seed": opts["seed"], "evaluations": f["evaluations"],
            "exact_frontier": [{k: v for k, v in lv.items() if k != "tolerances"} for lv in f["exact_frontier"]],
            "optimum": {"cost": optimum["cost"], "AP_bound": float(max(optimum["AP_bound"]))},
            "requirement": {"AP": iso.AP, "RP": iso.RP},
            "gap_method": "cost / exact frontier - 1, the frontier interpolated linearly in (log AP, log cost) between "
                          "its levels",
            "meaning": "NSGA-II (pymoo, log tolerances) on the systematic and random sources together: cost against AP "
                       "(its proven first-order worst-case bound, the largest over the five poses), every point holding "
                       "RP on the optimum's fixed draws (aimed like the optimum, 1.5 % below). Every point re-judged by "
                       "the optimum's check and kept only if its RP meets the requirement, and only if no cheaper kept "
                       "point has a smaller AP. The exact frontier: the certified optimum (AP convex; RP sampled) at "
                       "each level, the proven AP bound <= level. It aims its attained AP at level cos δ, a front point "
                       "its bound at the level: a gap below 0 (at most about 0.4 %) is that margin, not a better design"}


#: the study's rules that also allocate the random sources to AP/RP: method -> (allocator, what its design means)
ISO_RULES = {
    "sensitivity": (allocate_iso9283_sensitivity,
                    "the equal-effect rule (each source the same share of AP by its largest effect per unit tolerance, "
                    "each random source the same root-sum-square share of RP), scaled onto the AP/RP boundary"),
    "equal": (allocate_iso9283_equal,
              "equal tolerances (every tolerance the same value in SI, m or rad, clipped to its bounds: the largest "
              "whose proven AP bound meets AP and whose RP meets the optimum's aim, 1.5 % below RP)"),
    "lagrange": (allocate_iso9283_lagrange,
                 "the Lagrange closed form (least cost on the AP worst-case stack-up of the largest effects per unit "
                 "tolerance and the RP root-sum-square stack-up of each random source's RP alone), scaled onto the "
                 "AP/RP boundary"),
    "monotone": (allocate_iso9283_monotone,
                 "the polyblock bracket (Tuy 2000) of the least cost, started from the cheapest of the Lagrange, "
                 "equal-effect and equal designs, at most 10 s (stop says what ended it): the design is the bracket's upper end, lower_bound its "
                 "lower end (proven where RP on the fixed draws never decreases as a tolerance grows; it can dip by about "
                 "2 %, docs/iso9283.md), gap their distance relative to the design's cost"),
}

#: what the ``monotone`` rule adds to its allocation: the bracket
BRACKET_KEYS = ("lower_bound", "gap", "rounds", "vertices", "evaluations", "converged", "stop", "incumbent", "improved")


def iso_rules_wanted(spec: dict, problem, orientation: dict) -> tuple[str, ...]:
    """Which of the study's ``sensitivity``, ``equal``, ``lagrange``, ``monotone`` also allocate the random sources to
    AP/RP.

    Parameters
    ----------
    spec, problem, orientation
        The study file, its problem and the orientation figures required, as :func:`iso_ga_options` reads them.

    Returns
    -------
    tuple of str
        The rules among the methods, with ``[requirement] iso9283``, ``allocate = true`` and no
        ``[calibration]`` (there each allocates them in the calibrated budget instead:
        :mod:`evotol.studyfile.iso9283_calibrated`); else empty.

    Raises
    ------
    evotol.errors.ValidationError
        One line: an orientation figure beside one of them (the rules share AP and RP only).
    """
    req, methods = _beside_allocation(spec, problem)
    if "calibration" in spec:
        return ()
    rules = tuple(r for r in ISO_RULES if r in methods)
    if rules and orientation:
        k = next(iter(orientation))
        raise ValidationError(f"requirement.iso9283.{k}", req[k], f"no orientation figure beside [methods] {rules[0]} "
                              f"and [iso9283] allocate = true: the {rules[0]} rule shares AP and RP only (the optimum "
                              f"takes them: list [methods] without {', '.join(rules)})")
    return rules


def rule_allocation(iso, problem, optimum: dict, seed: int, rule: str) -> dict:
    """The ISO block's ``allocation_<rule>``: the rule on systematic and random sources (SI).

    Parameters
    ----------
    iso, problem, optimum, seed
        As :func:`ga_allocation` (the RP draws are the optimum's).
    rule : str
        ``sensitivity``, ``equal``, ``lagrange`` or ``monotone`` (:data:`ISO_RULES`).

    Returns
    -------
    dict
        ``cost``, ``gap_to_optimum``, ``feasible``, ``systematic`` and ``random`` (name -> tolerance),
        ``AP_bound``, ``RP_sampled``, ``RP_fresh_draws`` (per pose, m), ``meaning``; for ``monotone`` also its
        bracket (:data:`BRACKET_KEYS`).
    """
    allocate, what = ISO_RULES[rule]
    res = allocate(*allocator_args(iso, problem), seed=seed, **(iso.monotone if rule == "monotone" else {}))
    return {**judged_design(iso, res, optimum), **{k: res[k] for k in BRACKET_KEYS if k in res},
            "meaning": what + " and judged by the optimum's check: feasible if the proven AP bound meets AP and the RP "
                              "on the optimum's fixed draws meets RP; the gap is what the optimum saves"}


def study_method_options(spec: dict, problem, orientation: dict) -> dict:
    """Which of the study's methods also allocate the random sources to AP/RP, checked before any work.

    Parameters
    ----------
    spec, problem, orientation
        Read and checked as :func:`iso_ga_options` reads them.

    Returns
    -------
    dict
        ``ga`` (:func:`iso_ga_options`), ``rules`` (:func:`iso_rules_wanted`), ``monotone`` (the ISO bracket's
        settings, :func:`evotol.studyfile.methods.monotone_options`), ``front``
        (:func:`iso_front_options`): the :class:`evotol.studyfile.iso9283.IsoStudy` fields.
    """
    rules = iso_rules_wanted(spec, problem, orientation)
    return {"ga": iso_ga_options(spec, problem, orientation), "rules": rules,
            "monotone": monotone_options(study_methods(spec, problem)) if "monotone" in rules else {},
            "front": iso_front_options(spec, problem, orientation)}


def method_allocations(iso, problem, optimum: dict, seed: int) -> dict:
    """The ISO block's allocations by the study's other methods, each judged by the optimum's check.

    Parameters
    ----------
    iso, problem, optimum, seed
        As :func:`ga_allocation`.

    Returns
    -------
    dict
        ``allocation_ga``, ``allocation_sensitivity``, ``allocation_equal``, ``allocation_lagrange``,
        ``allocation_monotone``, ``front_nsga2``: the ones the study asks for.
    """
    out = {}
    if iso.ga is not None:
        out["allocation_ga"] = ga_allocation(iso, problem, optimum, seed)
    for rule in iso.rules:
        out[f"allocation_{rule}"] = rule_allocation(iso, problem, optimum, seed, rule)
    if iso.front is not None:
        out["front_nsga2"] = front_allocation(iso, problem, optimum, seed)
    return out


#: the study's methods that also allocate the random sources to AP/RP beside ``allocate = true``, and where
#: the block states it
ISO_ALLOCATIONS = {"optimum": "allocation", "ga": "allocation_ga", **{r: f"allocation_{r}" for r in ISO_RULES},
                   "nsga2": "front_nsga2"}


def methods_scope(names, block: dict) -> dict:
    """What each of the study's methods allocated beside ``[iso9283] allocate = true``: the ISO block's key of
    its allocation to AP/RP, or None where it allocated the systematic sources alone, to the position
    requirement (inside ``[calibration]``: :func:`evotol.studyfile.iso9283_calibrated.calibrated_scope`).

    Parameters
    ----------
    names : iterable of str
        The study's methods that ran.
    block : dict
        The ISO block, its allocations written.

    Returns
    -------
    dict
        Method name -> key in the block, or None.
    """
    return {n: ISO_ALLOCATIONS[n] if ISO_ALLOCATIONS.get(n) in block else None for n in names}

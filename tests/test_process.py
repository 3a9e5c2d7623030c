"""Process selection (evotol/allocators/process/): branch and bound against full enumeration
and an independent grid search, the dual bound, the GA and baselines, bad input."""
import itertools

import numpy as np
import pytest
from scipy.stats import norm

from evotol.cost_models import PowerCost, ReciprocalCost
from evotol.allocators.process import (Process, ProcessProblem, allocate_process_baselines, allocate_process_ga,
                                       allocate_process_optimum, assembly_problem, cheapest_feasible_processes,
                                       process_front)
from evotol.errors import InfeasibleError, ValidationError
from evotol.core.problem import Requirement
from evotol.studies._process_benchmarks import clutch_problem, process, stack_problem
from evotol.units import MM
from evotol.robots.assembly import LinearStack


@pytest.fixture(scope="module")
def clutch_wc():
    pp = clutch_problem("worst_case")
    return pp, allocate_process_optimum(pp, method="enumerate")


@pytest.mark.parametrize("measure", ["worst_case", "rss"])
def test_branch_and_bound_finds_the_enumeration_optimum_with_fewer_solves(measure):
    pp = stack_problem(measure, n_dims=4, names=("turn", "grind", "hone"))
    enum = allocate_process_optimum(pp, method="enumerate")
    bb = allocate_process_optimum(pp)
    assert bb.cost == pytest.approx(enum.cost, rel=1e-9)
    assert bb.processes == enum.processes
    assert bb.feasible and enum.feasible
    assert bb.n_convex_solves < enum.n_convex_solves
    assert enum.n_combinations == 3 ** 4


def test_clutch_optimum_against_independent_grid_search(clutch_wc):
    """Worst case: Σ s_j t_j <= L is one linear row; for every process combination eliminate t_e
    on the active row and scan (t_a, t_c) on a 400 × 400 log grid: never below the optimum, and
    within 0.1 % of it."""
    pp, opt = clutch_wc
    s = np.abs(pp.robot.gradient[0]) / pp.robot.limits[0]
    best = np.inf
    for choice in itertools.product(*[range(k) for k in pp.n_processes]):
        P = [pp.processes[n][k] for n, k in zip(pp.names, choice)]
        ta, tc = np.meshgrid(np.geomspace(P[0].lower, P[0].upper, 400), np.geomspace(P[1].lower, P[1].upper, 400))
        te = np.minimum((1 - s[0] * ta - s[1] * tc) / s[2], P[2].upper)
        ok = te >= P[2].lower
        if ok.any():
            cost = P[0].total(ta) + P[1].total(tc) + P[2].total(np.where(ok, te, P[2].lower))
            best = min(best, float(np.min(cost[ok])))
    assert opt.cost <= best * (1 + 1e-9)
    assert best <= opt.cost * 1.001


def test_node_bound_at_the_root_is_a_lower_bound(clutch_wc):
    pp, opt = clutch_wc
    bb = allocate_process_optimum(pp)
    assert bb.cost == pytest.approx(opt.cost, rel=1e-9)
    assert bb.certificate["leaf_gap"] < 1e-6
    if bb.certificate["smallest_pruned_bound"] is not None:
        assert bb.certificate["smallest_pruned_bound"] >= opt.cost * (1 - 1e-7)


def test_ga_finds_a_feasible_design_within_five_percent_and_never_below_the_optimum(clutch_wc):
    pp, opt = clutch_wc
    ga = allocate_process_ga(pp, pop_size=40, n_gen=40, seed=1)
    assert ga.feasible
    assert opt.cost * (1 - 1e-9) <= ga.cost <= 1.05 * opt.cost


def test_baselines_are_feasible_processes_and_cost_at_least_the_optimum(clutch_wc):
    pp, opt = clutch_wc
    ch = cheapest_feasible_processes(pp)
    assert pp.normalised_error(pp.lo[np.arange(pp.n_sources), ch])[0] <= 1
    for r in allocate_process_baselines(pp).values():
        if r.feasible:
            assert r.cost >= opt.cost * (1 - 1e-9)
    lag = allocate_process_baselines(pp)["lagrange"]
    assert lag.feasible
    # the numbers of the Lagrange closed form (Chase 1990 eq. for the worst-case stack): on its
    # processes, inside their ranges, the design sits on the limit (sum s_j t_j = 1) with equal
    # marginal cost per unit of stack, dC_j/dt_j / s_j (central differences of the cost models)
    s = np.abs(pp.robot.gradient[0]) / pp.robot.limits[0]
    procs = [next(p for p in pp.processes[n] if p.name == lag.processes[n]) for n in pp.names]
    t = np.array([lag.tolerances[n] for n in pp.names])
    assert all(p.lower < tj < p.upper for p, tj in zip(procs, t))
    assert s @ t == pytest.approx(1.0, rel=1e-9)
    marginal = [(p.total(tj * (1 + 1e-6)) - p.total(tj * (1 - 1e-6))) / (2e-6 * tj) / sj for p, tj, sj in zip(procs, t, s)]
    np.testing.assert_allclose(marginal, marginal[0], rtol=1e-6)
    assert lag.cost == pytest.approx(sum(p.total(tj) for p, tj in zip(procs, t)), rel=1e-12)


def test_nsga_front_feasible_points_cost_at_least_the_optimum(clutch_wc):
    pp, opt = clutch_wc
    front = process_front(pp, pop_size=30, n_gen=30, seed=0)
    df = front.table
    feas = df[df.normalised_error <= 1]
    assert len(feas) > 0
    assert feas.cost.min() >= opt.cost * (1 - 1e-9)
    assert front.cheapest_feasible()["cost"] == feas.cost.min()
    assert np.all(np.diff(df.cost) >= 0)


def _stack():
    return LinearStack({"x1": 1.0, "x2": -1.0}, {"gap": 1e-4})


def _pp(processes, **kw):
    return ProcessProblem(_stack(), processes, Requirement(position=1.0), _stack().response_poses, **kw)


GOOD = [process("turn"), process("grind")]


@pytest.mark.parametrize("processes, field_part", [
    ({"x1": [], "x2": GOOD}, "processes['x1']"),
    ({"x1": GOOD}, "processes"),
    ({"x1": GOOD, "x2": GOOD, "x3": GOOD}, "processes['x3']"),
    ({"x1": GOOD, "x2": ["grind"]}, "processes['x2'] entry"),
    ({"x1": GOOD, "x2": [process("turn"), process("turn")]}, "processes['x2'] name"),
    ({"x1": GOOD, "x2": [Process("lap", PowerCost(1.0, 1.0, scale=MM), 2e-5, 1e-5)]}, "processes['x2']['lap']"),
    ({"x1": GOOD, "x2": [Process("lap", PowerCost(1.0, 1.0, scale=MM), 1e-6, 1e-5, fixed_cost=-1.0)]},
     "processes['x2']['lap'].fixed_cost"),
    # a rough process that costs more than the fine one over all of its range: a unit slip
    ({"x1": GOOD, "x2": [Process("fine", ReciprocalCost(1.0, 0.01, scale=MM), 1e-6, 1e-4),
                         Process("rough", ReciprocalCost(1.0, 0.01, scale=1e-2), 2e-5, 8e-5)]},
     "processes['x2']['rough']"),
])
def test_bad_process_input_names_source_and_process(processes, field_part):
    with pytest.raises(ValidationError) as err:
        _pp(processes)
    assert field_part in err.value.field


def test_dominated_process_accepted_when_check_is_off():
    pp = _pp({"x1": GOOD, "x2": [Process("fine", ReciprocalCost(1.0, 0.01, scale=MM), 1e-6, 1e-4),
                                 Process("rough", ReciprocalCost(1.0, 0.01, scale=1e-2), 2e-5, 8e-5)]},
             check_dominance=False)
    r = allocate_process_optimum(pp)
    assert r.processes["x2"] == "fine"


def test_no_process_fine_enough_is_an_infeasible_error():
    """Every source at its finest process's lower limit misses the gap: InfeasibleError from every
    allocator, naming the smallest achievable error ((0.05 + 0.02) mm / 1 µm = 70 × the limit)."""
    stack = LinearStack({"x1": 1.0, "x2": -1.0}, {"gap": 1e-6})
    pp = assembly_problem(stack, processes={"x1": [process("mill")], "x2": [process("mill"), process("turn")]})
    for fn in (allocate_process_optimum, allocate_process_baselines, cheapest_feasible_processes):
        with pytest.raises(InfeasibleError, match="no process choice can hold") as exc:
            fn(pp)
        assert exc.value.smallest_error == pytest.approx(70.0, rel=1e-6)


def test_judge_recomputes_a_design_cost_and_constraint(clutch_wc):
    """A 'published' design: the optimum's processes with every tolerance 10 % looser costs less
    (cost curves fall with t) and violates the worst-case limit by 10 % (the stack is linear in t)."""
    pp, opt = clutch_wc
    j = pp.judge(opt.processes, opt.tolerances)
    assert j["cost"] == pytest.approx(opt.cost, rel=1e-12) and j["holds_requirement"]
    loose = pp.judge(opt.processes, {n: 1.1 * v for n, v in opt.tolerances.items()})
    assert loose["cost"] < opt.cost
    assert loose["normalised_error"] == pytest.approx(1.1 * j["normalised_error"], rel=1e-9)
    assert not loose["holds_requirement"]
    far = pp.judge(opt.processes, {n: 10 * v for n, v in opt.tolerances.items()})
    assert far["outside_process_range"]


def test_loose_requirement_is_proved_without_enumerating():
    """Limit so loose that every source takes its cheapest process at its loosest tolerance: the
    λ = 0 dual bound (cheapest cost per source) proves it; enumeration would solve all 81."""
    pp = stack_problem("worst_case", n_dims=4, limit=10e-3, names=("turn", "grind", "hone"))
    bb = allocate_process_optimum(pp)
    cheapest = sum(min(float(p.total(p.upper)) for p in pp.processes[n]) for n in pp.names)
    assert bb.cost == pytest.approx(cheapest, rel=1e-12)
    assert bb.n_convex_solves <= 2


def test_assembly_yield_is_the_normal_closed_form():
    """First-order yield of the statistical machinery vs. 2Φ(−L/σ) with σ² = Σ (∂y/∂x_j · t_j/3)²
    (normal, t = 3σ); at the RSS optimum the stack is exactly 3σ, yield 0.9973."""
    pp = clutch_problem("rss")
    rng = np.random.default_rng(1)
    T = np.exp(rng.uniform(np.log(pp.lo.min(1)), np.log(np.nanmax(pp.hi, 1)), size=(20, pp.n_sources)))
    J = pp.robot.sensitivity(pp.robot.response_poses)[0, 2, :]      # d(Δφ/L)/dx_j
    sigma = np.sqrt(((T * J / 3) ** 2).sum(1))
    assert pp.assembly_yield(T) == pytest.approx(1 - 2 * norm.sf(1 / sigma), rel=1e-9, abs=1e-12)
    opt = allocate_process_optimum(pp)
    t = [[opt.tolerances[n] for n in pp.names]]
    assert pp.assembly_yield(t)[0] == pytest.approx(2 * norm.cdf(3) - 1, rel=1e-9)
    # uniform sources in ±t: variance t²/3 instead of t²/9, σ √3 times larger:
    # moment-matched yield 2Φ(√3) − 1 at the same t
    assert pp.assembly_yield(t, pp.yield_model("uniform"))[0] == pytest.approx(2 * norm.cdf(np.sqrt(3)) - 1, rel=1e-9)
    # the 3-D quadrature of evotol.measures.statistical agrees to its accuracy on this rank-one covariance
    q = pp.yield_model().evaluate(T, 0.9973).miss["position"][:, 0]
    assert 1 - q == pytest.approx(pp.assembly_yield(T), abs=1e-4)


def test_cost_vs_yield_front_trades_cost_for_yield(clutch_wc):
    """Along the NSGA-II front cost rises with yield; a worst-case-feasible design (the
    worst-case optimum) has yield 1 − tiny, and no front point reaching that yield is cheaper
    than the exact optimum of the RSS problem at the same 3σ yield."""
    pp, opt = clutch_wc
    front = process_front(pp, objective="yield", pop_size=30, n_gen=30, seed=0)
    df = front.table
    assert {"cost", "yield", "miss_probability"} <= set(df.columns)
    assert np.all(np.diff(df.cost) >= 0) and np.all(np.diff(df["yield"]) >= -1e-12)
    assert pp.assembly_yield([[opt.tolerances[n] for n in pp.names]])[0] > 1 - 1e-5
    rss_opt = allocate_process_optimum(clutch_problem("rss"))
    best = front.cheapest_feasible()     # miss probability <= 2Φ(−3): yield of a 3σ design
    assert best["yield"] >= 2 * norm.cdf(3) - 1 - 1e-12
    assert rss_opt.cost * (1 - 1e-9) <= best["cost"] <= 1.10 * rss_opt.cost


def test_front_and_yield_bad_input_are_validation_errors(clutch_wc):
    pp, _ = clutch_wc
    with pytest.raises(ValidationError, match="objective"):
        process_front(pp, objective="cost")
    with pytest.raises(ValidationError, match="distribution"):
        pp.yield_model(3.0)


def test_ga_and_front_problems_pickle(clutch_wc):
    """Module-level pymoo problems (parallel evaluation and checkpointing need them picklable).

    Kept on the private classes: the pymoo problems are internal to allocate_process_ga and
    process_front, and no public call hands them out or pickles them."""
    import pickle

    from evotol.allocators.process.front import _ProcessFrontProblem
    from evotol.allocators.process.ga import _ProcessGAProblem

    pp, _ = clutch_wc
    for prob in (_ProcessGAProblem(pp), _ProcessFrontProblem(pp, "yield", pp.yield_model())):
        back = pickle.loads(pickle.dumps(prob))
        X = np.full((1, pp.n_sources), 0.5)
        assert np.allclose(back.evaluate(X), prob.evaluate(X))


def shaft_washer_bracket(play_mm=0.12, offset_mm=0.08, measure="worst_case"):
    """Five dimensions (bracket, shaft shoulder, two washers, circlip), two responses sharing them
    (axial play and an offset), 4·3·2·2·1 = 48 process combinations."""
    st = LinearStack({"play": {"bracket": 1.0, "shaft": -1.0, "washer1": -1.0, "washer2": -1.0, "circlip": -1.0},
                      "offset": {"bracket": 0.5, "shaft": -1.0, "washer1": -1.0, "circlip": -0.5}},
                     {"play": play_mm * MM, "offset": offset_mm * MM}, name="shaft/washer/bracket")
    procs = {"bracket": [process(p, 1.6) for p in ("mill", "turn", "grind", "hone")],
             "shaft": [process(p, 1.0) for p in ("turn", "grind", "hone")],
             "washer1": [process(p, 0.4) for p in ("turn", "grind")],
             "washer2": [process(p, 0.4) for p in ("turn", "grind")],
             "circlip": [process("grind", 0.3)]}
    return assembly_problem(st, processes=procs, measure=measure)


def _check_baselines_against_enumeration(pp):
    enum = allocate_process_optimum(pp, method="enumerate")
    base = allocate_process_baselines(pp)
    assert set(base) == {"sensitivity", "lagrange"}
    for key, r in base.items():
        t = np.array([r.tolerances[n] for n in pp.names])
        ne = float(pp.normalised_error(t[None])[0])
        assert r.normalised_error == pytest.approx(ne, rel=1e-12)
        assert r.feasible == bool(ne <= 1 + 1e-7 and pp.in_ranges(pp.choice_index(r.processes), t)[0])
        if r.feasible:
            assert r.cost >= enum.cost * (1 - 1e-9), key
    assert base["lagrange"].feasible             # sized on a conservative stack, or scaled onto the limit
    return enum, base


def test_baselines_on_the_feasible_shaft_washer_bracket_problem():
    """Worst case, 48 combinations: the Lagrange baseline used to raise 'expected a bound the lower
    tolerance limits can hold' (its one-stack model, aggregated over the two responses, cannot hold
    the limit on the cheapest processes the exact limit allows). Now both baselines return designs,
    the Lagrange one feasible, none below the optimum that enumeration finds (17.42336 here)."""
    pp = shaft_washer_bracket()
    assert pp.n_combinations == 48
    enum, base = _check_baselines_against_enumeration(pp)
    assert allocate_process_optimum(pp).cost == pytest.approx(enum.cost, rel=1e-9)
    assert enum.cost == pytest.approx(17.42336, abs=5e-6)


@pytest.mark.parametrize("seed", range(4))
def test_baselines_on_random_feasible_process_problems(seed):
    """Random stacks (5 dimensions, 1-3 responses, 1-4 processes each, worst case or RSS, random
    limits): when enumeration finds a feasible choice the baselines return designs (Lagrange
    feasible, none below the optimum); when it finds none every allocator raises InfeasibleError."""
    rng = np.random.default_rng(seed)
    names = [f"d{j}" for j in range(5)]
    cat = ("mill", "turn", "grind", "hone")
    n_feasible = n_infeasible = 0
    for _ in range(4):
        K = int(rng.integers(1, 4))
        A = rng.choice([-1.0, 1.0], size=(K, 5)) * rng.uniform(0.5, 2.0, size=(K, 5))
        st = LinearStack({f"r{k}": {n: float(A[k, j]) for j, n in enumerate(names)} for k in range(K)},
                         {f"r{k}": float(rng.uniform(0.02, 0.4)) * MM for k in range(K)})
        procs = {n: [process(p, float(rng.uniform(0.3, 2.0))) for p in
                     sorted(rng.choice(cat, size=int(rng.integers(1, 4)), replace=False), key=cat.index)] for n in names}
        pp = assembly_problem(st, processes=procs, measure=str(rng.choice(["worst_case", "rss"])))
        tight = pp.lo[np.arange(5)[None], np.array(list(itertools.product(*[range(k) for k in pp.n_processes])))]
        if np.any(pp.normalised_error(tight) <= 1):
            _check_baselines_against_enumeration(pp)
            n_feasible += 1
        else:
            for fn in (allocate_process_optimum, allocate_process_baselines):
                with pytest.raises(InfeasibleError):
                    fn(pp)
            n_infeasible += 1
    assert n_feasible >= 1


def test_process_allocators_have_the_one_shape_and_refuse_a_budget(clutch_wc):
    """(problem, *, budget=None, ...) keyword-only; a budget is a one-line ValidationError; a
    ToleranceProblem instead of a ProcessProblem is named."""
    import inspect

    from evotol.allocators.process import process_front

    pp, _ = clutch_wc
    for fn in (allocate_process_optimum, allocate_process_ga, allocate_process_baselines, process_front):
        params = list(inspect.signature(fn).parameters.values())
        assert params[0].name == "problem"
        assert all(p.kind is inspect.Parameter.KEYWORD_ONLY for p in params[1:])
        assert inspect.signature(fn).parameters["budget"].default is None
        with pytest.raises(ValidationError, match="budget"):
            fn(pp, budget=10.0)
        with pytest.raises(ValidationError, match="ProcessProblem"):
            fn(pp.base)


@pytest.mark.parametrize("measure", ["yield", "mc_quantile"])
def test_process_optimum_and_ga_name_a_measure_without_constraint_rows(measure):
    """allocate_process_optimum / allocate_process_ga on a statistical measure: a one-line
    ValidationError naming requirement.measure, its value and the measures expected (worst_case,
    rss), from evotol.measures.constraints.ConstraintRows -- not a plain ValueError."""
    pp = stack_problem(measure)
    for fn in (allocate_process_optimum, allocate_process_ga):
        with pytest.raises(ValidationError) as err:
            fn(pp)
        assert err.value.field == "requirement.measure" and err.value.value == measure
        assert "'worst_case' or 'rss'" in err.value.expected


def test_feasible_means_within_feas_tol_of_the_limit(clutch_wc):
    """A process result is called feasible when its normalised stack error is <= 1 + FEAS_TOL
    (1e-9), the slack branch and bound and the baselines use -- not 1 + 1e-7 as before, which
    called a design 5e-8 over the limit feasible. The certified optimum itself is inside it.
    ``pp.judge`` (public) applies the same rule to a given design; ``_result`` is kept because it is
    the one place a ProcessResult's ``feasible`` is set, and no public call builds a result from a
    given design."""
    from evotol.allocators.process import FEAS_TOL
    from evotol.allocators.process.result import _result

    pp, opt = clutch_wc
    assert FEAS_TOL == 1e-9 and opt.feasible and opt.normalised_error <= 1 + FEAS_TOL
    choice = pp.choice_index(opt.processes)
    t = np.array([opt.tolerances[n] for n in pp.names])
    over = _result(pp, "probe", choice, t * (1 + 5e-8) / opt.normalised_error, 0.0)
    assert over.normalised_error == pytest.approx(1 + 5e-8, abs=1e-12) and not over.feasible
    at = _result(pp, "probe", choice, t * (1 + 0.5e-9) / opt.normalised_error, 0.0)
    assert at.feasible
    for r in (over, at, opt):
        assert pp.judge(r.processes, r.tolerances)["holds_requirement"] == r.feasible

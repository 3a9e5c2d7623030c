"""Monte Carlo verification: sampling rules (Yao 2013 eq. 12), reproducibility, linear vs nonlinear."""
import numpy as np
import pytest

import evotol.cost_models as cm
from evotol.allocators import allocate_optimum
from evotol.errors import ValidationError
from evotol.measures.statistical.distributions import draw as _draw, uniforms as _uniforms
from evotol.verification.montecarlo import verify
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from evotol.studies.yao2013 import yao2013_problem
from tests.toy_robot import ToyRobot


def test_eq12_disk_samples_have_uniform_direction_and_radius():
    U = _uniforms(20000, 3, "lhs", 0)
    z_int, z_disk = _draw(U, [1, 2], ["uniform", "uniform"], "uniform")
    r = np.linalg.norm(z_disk, axis=1)
    assert r.max() <= 1 and abs(r.mean() - 0.5) < 0.01          # radius ~ U(0, 1)
    ang = np.arctan2(z_disk[:, 1], z_disk[:, 0])
    hist = np.histogram(ang, bins=8, range=(-np.pi, np.pi))[0]
    assert hist.min() > 0.9 * hist.mean()                        # direction ~ U(0, 2π)
    assert np.abs(z_int).max() <= 1 and abs(np.var(z_int) - 1 / 3) < 0.01
    z_area = _draw(U, [1, 2], ["uniform", "uniform"], "area")[1]
    assert abs(np.mean(np.linalg.norm(z_area, axis=1)) - 2 / 3) < 0.01  # uniform over the disk area
    z_norm = _draw(U, [1, 2], ["truncated_normal", "truncated_normal"], "uniform")[0]
    assert np.abs(z_norm).max() <= 1 and abs(np.std(z_norm) - 1 / 3) < 0.02


def test_worst_case_feasible_design_never_exceeds_and_sampling_falls_short():
    r = ToyRobot()
    tol = {s.name: Tolerance(cm.ExponentialCost(1, 1, scale=1e-3), 1e-5, 1e-2) for s in r.sources}
    P = ToleranceProblem(r, tol, Requirement(position=1e-3, measure="worst_case"), [[0.0], [0.5], [1.0]])
    opt = allocate_optimum(P)
    for method in ("lhs", "mc"):
        mc = verify(P, opt.t, 2000, method=method, seed=1)
        assert mc.max_exceed_rate() == 0.0
        assert 0.3 < mc.max_error_over_worst_case["position"] < 1.0
    a, b = verify(P, opt.t, 500, seed=5), verify(P, opt.t, 500, seed=5)
    np.testing.assert_array_equal(a.max_error["position"], b.max_error["position"])
    with pytest.raises(ValidationError, match="method"):
        verify(P, opt.t, 10, method="sobol")
    with pytest.raises(ValidationError, match="n_samples"):
        verify(P, opt.t, 0)


def test_3ucr_paper_table1_exceed_rate_and_linearisation():
    """Yao 2013 Sec. 5: under the paper's model Table 1 exceeds 5e-5 m in under 10 % of the
    samples at every pose; the verified model's linearisation error is tiny."""
    P = yao2013_problem("paper", "rss", grid=(3, 3, 2))
    from evotol.studies.yao2013 import PAPER_TABLE1
    mc = verify(P, PAPER_TABLE1, 1000, seed=0, nonlinear=False)
    assert mc.max_exceed_rate() < 0.10
    V = yao2013_problem("verified", "rss", grid=(2, 2, 2))
    mcv = verify(V, PAPER_TABLE1, 300, seed=0, nonlinear=True)
    assert mcv.linearisation_error < 1e-3
    np.testing.assert_allclose(mcv.nonlinear_exceed_rate["position"], mcv.exceed_rate["position"], atol=0.02)


class _UnassembledToy(ToyRobot):
    """Linear toy with a nonlinear model that cannot assemble a sample whose source s0 error is
    positive: raises by default, a NaN row with ``failures="nan"`` (as evotol.robots.planar5r)."""

    def pose_error(self, poses, errors, failures="raise"):
        out = np.einsum("pij,psj->psi", self.sensitivity(poses), errors)
        bad = errors[..., 0] > 0
        if failures == "raise" and bad.any():
            raise RuntimeError("cannot be assembled")
        out[bad] = np.nan
        return out


def test_verify_nonlinear_counts_an_unassembled_sample_as_a_miss():
    """verify_nonlinear (verify(model="nonlinear")) samples through pose_error_nan: a sample that
    cannot be assembled is a miss, as in verify(): the exceed rate is the fraction of samples with
    e0 > 0 (every assembled sample is far inside the 1 mm bound), the same as verify()'s nonlinear
    exceed rate on the same law; mc_max and mc_q999 are inf (misses are infinite errors), not NaN."""
    from evotol.verification.nonlinear import uniform_interval_samples, verify_nonlinear

    r = _UnassembledToy(dims=(1, 1))
    tol = {s.name: Tolerance(cm.ExponentialCost(1, 1, scale=1e-3), 1e-6, 1e-3) for s in r.sources}
    P = ToleranceProblem(r, tol, Requirement(position=1e-3), [[0.0], [0.5]])
    t = np.full(2, 1e-5)
    chk = verify(P, t, 200, seed=3, model="nonlinear")
    miss = np.mean(uniform_interval_samples(P, t, 200, 3)[:, 0] > 0)
    assert 0.4 < miss < 0.6
    assert chk.mc_exceed_rate["position"] == pytest.approx(miss, abs=1e-12)
    assert chk.mc_max["position"] == np.inf and chk.mc_q999["position"] == np.inf
    lin = verify(P, t, 2000, seed=3)
    np.testing.assert_allclose(lin.nonlinear_exceed_rate["position"], 0.5, atol=0.03)
    # a robot returning NaN by itself (no failures keyword) is read the same way
    class _NoKeyword(_UnassembledToy):
        def pose_error(self, poses, errors):
            return super().pose_error(poses, errors, failures="nan")

    P2 = ToleranceProblem(_NoKeyword(dims=(1, 1)), tol, Requirement(position=1e-3), [[0.0], [0.5]])
    chk2 = verify_nonlinear(P2, t, n_samples=200, seed=3)
    assert chk2.mc_exceed_rate == chk.mc_exceed_rate and chk2.mc_q999["position"] == np.inf


class _MissesAbove(ToyRobot):
    """Linear toy (one source, one pose) whose nonlinear model cannot assemble a sample with
    |e0| > ``cut``: the misses are then exactly the samples of largest error."""

    cut = np.inf

    def pose_error(self, poses, errors):
        out = np.einsum("pij,psj->psi", self.sensitivity(poses), errors)
        out[np.abs(errors[..., 0]) > self.cut] = np.nan
        return out


def test_verify_nonlinear_quantile_puts_a_few_misses_above_every_error():
    """With fewer misses than the 0.1 % tail, mc_q999 is the quantile with the misses placed above
    every assembled error (finite, the value without misses), and mc_max is inf; one miss more and
    the quantile reaches them (inf). 2001 samples: the 0.999 quantile is the third-largest error.
    Through verify_nonlinear and its public sampler (uniform_interval_samples, same seed)."""
    from evotol.verification.nonlinear import uniform_interval_samples, verify_nonlinear

    robot = _MissesAbove(dims=(1,))
    tol = {"s0": Tolerance(cm.ExponentialCost(1, 1, scale=1e-3), 1e-6, 1e-3)}
    P = ToleranceProblem(robot, tol, Requirement(position=1e-3), [[0.5]])
    t = np.array([1e-5])
    a = np.sort(np.abs(uniform_interval_samples(P, t, 2001, 4)[:, 0]))
    whole = verify_nonlinear(P, t, n_samples=2001, seed=4)
    gain = np.linalg.norm(robot.sensitivity(P.poses)[0, :3, 0])
    assert gain > 0 and a[-4] < a[-3] < a[-2]
    assert whole.mc_q999["position"] == pytest.approx(gain * a[-3], rel=1e-12)      # no miss: the plain quantile
    assert whole.mc_max["position"] == pytest.approx(gain * a[-1], rel=1e-12)
    robot.cut = 0.5 * (a[-3] + a[-2])                       # the 2 largest errors are misses
    two = verify_nonlinear(P, t, n_samples=2001, seed=4)
    assert two.mc_q999["position"] == whole.mc_q999["position"] and two.mc_max["position"] == np.inf
    robot.cut = 0.5 * (a[-4] + a[-3])                       # the 3 largest: the quantile reaches a miss
    three = verify_nonlinear(P, t, n_samples=2001, seed=4)
    assert three.mc_q999["position"] == np.inf


def test_verify_nonlinear_does_not_depend_on_its_chunks_and_refuses_a_bad_one():
    """Every statistic of the nonlinear check (the quantile over every pose-sample included) is the
    same whether the poses go to pose_error one at a time, 3 at a time or all at once (7 poses; the
    default chunk is 64), with misses among them; a chunk that is not a positive integer is refused by
    name, by verify_nonlinear, by verify(model="nonlinear") and by verify."""
    from evotol.verification.nonlinear import verify_nonlinear

    r = _UnassembledToy(dims=(1, 1))
    tol = {s.name: Tolerance(cm.ExponentialCost(1, 1, scale=1e-3), 1e-6, 1e-3) for s in r.sources}
    P = ToleranceProblem(r, tol, Requirement(position=1e-3), np.linspace(0.0, 0.9, 7)[:, None])
    t = np.full(2, 1e-5)
    runs = [verify_nonlinear(P, t, n_samples=301, seed=5, chunk_poses=c).to_dict() for c in (64, 1, 3, 7)]
    for d in runs:
        d.pop("seconds")
    assert runs[0]["max_exceed_rate"] > 0 and all(d == runs[0] for d in runs[1:])
    for bad in (0, 2.5, "4", None):
        with pytest.raises(ValidationError, match="chunk_poses"):
            verify_nonlinear(P, t, n_samples=10, chunk_poses=bad)
        with pytest.raises(ValidationError, match="chunk_poses"):
            verify(P, t, 10, model="nonlinear", chunk_poses=bad)
        with pytest.raises(ValidationError, match="chunk_poses"):
            verify(P, t, 10, chunk_poses=bad)


class _LinearToy(ToyRobot):
    """ToyRobot whose nonlinear model is its linear one."""

    def pose_error(self, poses, errors):
        return np.einsum("pij,psj->psi", self.sensitivity(poses), errors)


def _asymmetric_yield_problem():
    r = _LinearToy(dims=(1, 1, 1), planar=True)
    c = cm.ExponentialCost(1, 1, scale=1e-3)
    tol = {"s0": Tolerance(cost=c, lower=1e-6, upper=1e-2, distribution="normal", offset=1e-4, minus=0.5, plus=1.5),
           "s1": Tolerance(cost=c, lower=1e-6, upper=1e-2, distribution="normal"),
           "s2": Tolerance(cost=c, lower=1e-6, upper=1e-2, distribution="normal")}
    return ToleranceProblem(r, tol, Requirement(position=6e-4, measure="yield", probability=0.99, model="nonlinear"),
                            [[0.0], [0.6]])


def test_calibrate_scale_samples_asymmetric_intervals_as_the_yield_measure():
    """calibrate_scale on an offset/asymmetric interval (offset 0.1 mm, minus 0.5, plus 1.5): at the
    returned factor the one-sided 95 % Clopper-Pearson upper bound of the miss probability on the
    same samples *with the interval shift* is within 1 − p = 1 %, and 3 % more is not (sampled as
    centred ±t the factor was 2.26 and its bound 12 %)."""
    from scipy.stats import beta

    from evotol.verification.montecarlo import calibrate_scale
    from evotol.measures.statistical import SampledYield

    P = _asymmetric_yield_problem()
    cal = calibrate_scale(P, np.full(3, 2e-4), 2000, seed=11)
    assert cal["certified"]
    model = SampledYield(P.model, P.poses, P.distributions, dict(P.components), 2000, 11,
                         shift=(P.shape.rho, P.shape.kappa, P.shape.offset))

    def upper(T):
        k = np.rint((1 - model.evaluate(T[None], 0.99).probability[0]) * 2000)
        return np.max(beta.ppf(0.95, k + 1, 2000 - k))

    assert upper(cal["tolerances"]) <= 0.01 < upper(cal["tolerances"] * 1.03)
    assert cal["scale"] == pytest.approx(1.436, abs=0.01)


def test_calibrate_scale_refuses_a_zero_free_tolerance():
    """A zero tolerance on a free source cannot be scaled into its bounds: a ValidationError naming
    the source, not a scale of inf and NaN tolerances."""
    from evotol.verification.montecarlo import calibrate_scale

    with pytest.raises(ValidationError, match=r"tolerances\['s0'\] = 0\.0: expected a positive tolerance"):
        calibrate_scale(_asymmetric_yield_problem(), [0.0, 2e-4, 2e-4], 100)


def test_calibrate_scale_refuses_a_problem_without_a_free_source():
    """With every source locked there is no tolerance to scale: a one-line ValidationError naming
    ``tolerances`` ("all locked"), not numpy's "zero-size array to reduction operation maximum"
    ValueError. ToleranceProblem itself refuses all-locked sources, so the problem's locked values
    are set after construction (a shallow copy, as the with_* methods make)."""
    import copy

    from evotol.verification.montecarlo import calibrate_scale

    P = copy.copy(_asymmetric_yield_problem())
    P.locked_values = np.full(3, 2e-4)
    with pytest.raises(ValidationError) as exc:
        calibrate_scale(P, np.full(3, 2e-4), 100)
    assert exc.value.field == "tolerances" and exc.value.value == "all locked"
    assert str(exc.value) == "tolerances = 'all locked': expected at least one free source for calibrate_scale to scale"


@pytest.mark.parametrize("field, value, expected", [
    ("confidence", 1.5, "a probability in (0, 1)"),
    ("confidence", "95%", "a probability in (0, 1)"),
    ("iters", 0, "a positive integer (bisection steps)"),
    ("iters", 2.5, "a positive integer (bisection steps)"),
    ("n_samples", True, "an integer >= 10"),
])
def test_calibrate_scale_checks_confidence_iters_and_samples_first(field, value, expected):
    """``confidence`` 1.5 made scipy's beta quantile NaN, so no scale was ever certified; text
    failed inside the first sampled check; ``iters`` 0 returned the lower-bound scale without a
    search and 2.5 raised a TypeError from ``range``. Each is refused before any sampling in one
    line naming the argument (``n_samples=True``, a bool, is refused as before)."""
    from evotol.verification.montecarlo import calibrate_scale

    kw = {"n_samples": 100, field: value}
    with pytest.raises(ValidationError) as exc:
        calibrate_scale(_asymmetric_yield_problem(), np.full(3, 2e-4), **kw)
    assert str(exc.value) == f"{field} = {value!r}: expected {expected}"


def _same(a, b) -> bool:
    """Equal to the last bit (NaN equal to NaN), through dicts, sequences and arrays."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple, np.ndarray)) or isinstance(b, (list, tuple, np.ndarray)):
        return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=np.asarray(a).dtype.kind == "f")
    if isinstance(a, float) and isinstance(b, float) and np.isnan(a) and np.isnan(b):
        return True
    return a == b


def _timeless(d):
    """``d`` without its wall times (``seconds``, at any depth)."""
    return {k: _timeless(v) for k, v in d.items() if k != "seconds"} if isinstance(d, dict) else d


def _fields(res) -> dict:
    d = _timeless(res.to_dict())
    return {**d, "exceed": res.exceed_rate, "max": res.max_error, "q95": res.quantile_95,
            "exceed_nl": res.nonlinear_exceed_rate, "yield_linear": res.yield_linear, "yield_nonlinear": res.yield_nonlinear}


def _clearance_problem():
    from evotol.measures.clearances import ClearanceSources, thesis_classes
    from evotol.robots.mechanism.model.error_model import MechanismModel, resolve_description

    robot = MechanismModel(resolve_description("fivebar"))
    mech = robot.clearance_mechanism()
    cl = ClearanceSources(mech, thesis_classes([j.name for j in mech.joints], h=0.01))
    names = list(robot.source_names) + list(cl.names)
    tols = {n: Tolerance(cm.ReciprocalCost(1.0, 1.0, scale=1e-6), lower=1e-7, upper=1e-4) for n in names}
    return ToleranceProblem(robot, tols, Requirement(position=1e-4), robot.workspace.grid([3, 3]), clearances=cl)


@pytest.mark.parametrize("case", ["ucr3 nonlinear", "ucr3 paper, normal, mc", "toy 600 poses (compiled hypercubes)",
                                  "toy yield", "5-bar with clearances", "UR5 calibrated (simulated per design)"])
def test_verify_designs_equals_verify_of_each_design_bit_for_bit(case):
    """verify_designs draws each chunk's unit samples once for all designs: every result equals verify of
    that design alone (per-pose arrays, the yield verdict, the linearisation error, the worst-case ratio), on
    a nonlinear model with disk sources, with one given distribution and plain sampling, on the compiled
    hypercube path (>= 500 poses), with a yield requirement, with clearance sources (whose states are
    drawn per chunk, per design) and on a calibrated robot (each design's calibration simulated)."""
    from evotol.studies.yao2013 import PAPER_TABLE1, PAPER_TABLE2
    from evotol.verification.montecarlo import verify_designs

    kw = dict(n_samples=200, seed=3)
    if case.startswith("ucr3"):
        P = yao2013_problem("verified" if "nonlinear" in case else "paper", "rss", grid=(2, 2, 2))
        designs = [PAPER_TABLE1, PAPER_TABLE2, np.asarray(PAPER_TABLE1) * 0.5]
        if "normal" in case:
            kw.update(method="mc", distribution="normal", nonlinear=False)
    elif case.startswith("UR5 calibrated"):          # each design's own simulated calibration (part_checks)
        from tests.test_combinations import build

        P = build("calibration")
        designs = [P.upper, np.sqrt(P.lower * P.upper), np.minimum(P.lower * 30, P.upper)]
        kw["n_samples"] = 60
    elif case == "5-bar with clearances":
        P = _clearance_problem()
        designs = [P.upper, P.upper * 0.3, np.sqrt(P.lower * P.upper)]
    else:
        r = ToyRobot()
        req = Requirement(position=1e-3, measure="yield", probability=0.99) if "yield" in case else Requirement(position=1e-3)
        tol = {s.name: Tolerance(cm.ExponentialCost(1, 1, scale=1e-3), 1e-5, 1e-2) for s in r.sources}
        P = ToleranceProblem(r, tol, req, np.linspace(0, 1, 600 if "600" in case else 5)[:, None])
        designs = [np.full(P.n_sources, 2e-4), np.full(P.n_sources, 5e-4), np.linspace(1e-4, 6e-4, P.n_sources)]
        kw["chunk_poses"] = 128
    together = verify_designs(P, designs, **kw)
    assert len(together) == len(designs)
    for t, res in zip(designs, together):
        alone = verify(P, t, **kw)
        assert _same(_fields(res), _fields(alone))
        assert res.part_checks.keys() == alone.part_checks.keys()
    assert not _same(_fields(together[0])["max"], _fields(together[1])["max"])     # designs not mixed up
    with pytest.raises(ValidationError, match="designs"):
        verify_designs(P, [], **kw)

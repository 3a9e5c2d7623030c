"""The Monte Carlo verification's sampling and the worst case's coefficients of many poses, made fast
without changing a number (issue 43 item 4): checked against SciPy's Latin hypercube class and against
the stored support coefficients, element by element."""
import numpy as np
import pytest
from scipy.stats import qmc

from evotol.measures.linear import support_coefficients
from evotol.measures.linear.support import IntervalShape
from evotol.measures.linear.support_grid import LazySupport, support_grid, support_rows
from evotol.measures.statistical.distributions import latin_hypercube


@pytest.mark.parametrize("n, d", [(100, 36), (1, 5), (7, 3), (300, 54)])
def test_latin_hypercube_draws_what_scipys_class_draws(n, d):
    for seed in range(20):
        def child():         # a fresh Generator of the same stream each time (spawning changes its seed sequence)
            return np.random.default_rng(np.random.SeedSequence(seed).spawn(3)[2])
        ref = qmc.LatinHypercube(d=d, seed=child()).random(n)
        got = latin_hypercube(n, d, child())
        assert np.array_equal(got, ref)
        assert np.array_equal(latin_hypercube(n, d, seed), qmc.LatinHypercube(d=d, seed=seed).random(n))
        strata = np.sort(np.floor(got * n), axis=0)             # one value in each of the n strata, per column
        assert np.array_equal(strata, np.tile(np.arange(n)[:, None], (1, d)))


def test_verify_streams_are_each_poses_own_spawned_child():
    """The verification draws pose p's samples from SeedSequence(seed).spawn(P)[p] (its docstring):
    the child made directly from the spawn key is that child."""
    root = np.random.SeedSequence(11)
    kids = np.random.SeedSequence(11).spawn(6)
    for p, kid in enumerate(kids):
        direct = np.random.SeedSequence(root.entropy, spawn_key=(p,))
        assert np.array_equal(direct.generate_state(8), kid.generate_state(8))


def _blocks(rng, n_poses, dims):
    return [rng.normal(size=(n_poses, 3, k)) for k in dims]


@pytest.mark.parametrize("mixed", [False, True])
@pytest.mark.parametrize("shaped", [False, True])
def test_lazy_support_gives_the_stored_coefficients_products_and_rows(shaped, mixed):
    rng = np.random.default_rng(4)
    dims = [1, 1, 2, 1, 3, 1, 1] if mixed else [1] * 6
    blocks = _blocks(rng, 53, dims)
    D = rng.normal(size=(40, 3))
    D /= np.linalg.norm(D, axis=1, keepdims=True)
    n = len(dims)
    shape = None
    if shaped:
        line = np.array([k == 1 for k in dims])
        shape = IntervalShape(np.where(line, rng.uniform(0.5, 1.5, n), 1.0), np.where(line, rng.uniform(-0.4, 0.4, n), 0.0),
                              np.where(line, rng.uniform(-1e-4, 1e-4, n), 0.0))
    c = support_coefficients(blocks, D, shape)
    lazy = LazySupport(blocks, D, shape)
    assert lazy.shape == c.shape
    assert np.array_equal(np.asarray(lazy), c)
    T = rng.uniform(1e-5, 1e-3, size=(3, n))
    const = rng.normal(size=(53, 40))
    own = np.einsum("pdj,nj->npd", c, T) + const[None]            # written out: sum over sources
    import evotol.measures.linear.support_grid as sg
    step = sg.STEP_BYTES
    try:
        sg.STEP_BYTES = 8 * 40 * n * 4                              # four poses a step: several steps and a short last one
        got = support_grid((lazy, D, 0.1, const), T)
        pp, dd = rng.integers(0, 53, 30), rng.integers(0, 40, 30)
        rows = support_rows(lazy, pp, dd)
    finally:
        sg.STEP_BYTES = step
    assert np.allclose(got, own, rtol=1e-13, atol=0)
    assert np.array_equal(support_grid((c, D, 0.1, const), T), got)    # stored or not: the same products
    assert np.array_equal(rows, c[pp, dd, :])


@pytest.mark.parametrize("method", ["lhs", "mc"])
def test_pose_uniforms_are_the_spawned_childs_draws(method):
    from evotol.measures.statistical.distributions import uniforms
    from evotol.verification.montecarlo import pose_uniforms

    kids = np.random.SeedSequence(5).spawn(9)
    for p in (0, 3, 8):
        ref = uniforms(40, 7, method, np.random.default_rng(kids[p]))
        assert np.array_equal(pose_uniforms(np.random.SeedSequence(5), p, 40, 7, method), ref)


def test_compiled_latin_hypercubes_are_the_numpy_draws():
    from evotol.measures.statistical.lhs_compiled import latin_hypercubes
    from evotol.verification.montecarlo import pose_uniforms

    root = np.random.SeedSequence(13)
    for n, d, poses in [(100, 36, range(40)), (1, 3, [5]), (7, 5, [0, 9, 2]), (300, 54, [1, 77])]:
        got = latin_hypercubes(root, poses, n, d)
        if got is None:
            pytest.skip("numba is not available (EVOTOL_NO_NUMBA or not installed): the NumPy path serves")
        ref = np.stack([pose_uniforms(root, p, n, d, "lhs") for p in poses])
        assert np.array_equal(got, ref)


def test_compiled_pcg64_draws_are_numpys_raw_draws():
    """pcg64_kernel's 128-bit step and XSL-RR output against ``PCG64.random_raw`` (NumPy's C generator):
    seeded as the poses' generators and from plain integers, 10 000 draws each, and the state it leaves
    draws on as NumPy's does."""
    pytest.importorskip("numba")
    from evotol.measures.statistical import pcg64_kernel as K

    gens = [np.random.PCG64(np.random.SeedSequence(7, spawn_key=(p, 0))) for p in (0, 1, 99_999)]
    gens += [np.random.PCG64(s) for s in (0, 1, 2 ** 63, 12345678901234567890)]
    for g in gens:
        st = K.generator_states([g])[0].copy()
        assert np.array_equal(K.raw_draws(st, 10_000), g.random_raw(10_000))
        assert np.array_equal(K.raw_draws(st, 5), g.random_raw(5))


def test_compiled_hypercube_takes_the_kept_half_of_numpys_last_32_bit_draw_first():
    """A generator whose last 32-bit draw left its high half kept (``has_uint32``): the shuffle's first
    bounded draw is that half, as in NumPy's ``pcg64_next32``."""
    pytest.importorskip("numba")
    from evotol.measures.statistical import pcg64_kernel as K
    from evotol.measures.statistical.distributions import latin_hypercube_from

    a, b = np.random.PCG64(3), np.random.PCG64(3)
    np.random.Generator(a).integers(0, 7, size=3)                  # three 32-bit draws: a high half kept
    np.random.Generator(b).integers(0, 7, size=3)
    states = K.generator_states([a])
    assert states[0, 4] == 1                                        # a kept half, to be used first
    out = np.empty((1, 9, 4))
    K.latin_hypercube_kernel(states, 9, 4, out)
    assert np.array_equal(out[0], latin_hypercube_from(9, 4, np.random.Generator(b)))


def test_a_verification_draws_the_same_samples_compiled_or_not(monkeypatch):
    """verify() switches to the compiled hypercubes from lhs_compiled.MIN_POSES poses: forced on a small
    study, every rate, maximum and yield is the same to the last bit."""
    import evotol.verification.montecarlo as mc
    from tests.test_combinations import STUDIES, ur5
    from evotol.studyfile.problem import load_problem

    p = load_problem(ur5(), base_dir=STUDIES)
    t = np.sqrt(p.lower * p.upper)
    ref = mc.verify(p, t, n_samples=64, seed=4)
    monkeypatch.setattr(mc, "LHS_MIN_POSES", 0)
    got = mc.verify(p, t, n_samples=64, seed=4)
    for name in ("exceed_rate", "max_error", "quantile_95", "nonlinear_exceed_rate"):
        a, b = getattr(ref, name), getattr(got, name)
        assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
    assert np.array_equal(ref.yield_linear, got.yield_linear) and np.array_equal(ref.yield_nonlinear, got.yield_nonlinear)
    assert ref.nonlinear_exceed_rate and ref.yield_nonlinear is not None          # the nonlinear model was sampled too

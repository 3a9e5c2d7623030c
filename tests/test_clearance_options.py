"""The clearance engine's settings are one frozen value passed down (issue 26 item 2): a worker
process computes with the options its task carries, not with module state; the work done comes
back with the result (``n_newton``), not through a global counter."""
import dataclasses

import numpy as np
import pytest

from evotol.errors import ValidationError
from evotol.robots.clearance import ClearanceEvaluator, MaxPoseError, max_pose_error
from evotol.robots.clearance.options import DEFAULT, LEGACY, NUMPY, EngineOptions


def test_options_are_frozen_and_validated():
    with pytest.raises(dataclasses.FrozenInstanceError):
        DEFAULT.growth = 8.0
    with pytest.raises(ValidationError, match="EngineOptions.patch_bound"):
        EngineOptions(patch_bound="loose")
    with pytest.raises(ValidationError, match="EngineOptions.growth"):
        EngineOptions(growth=1.0)
    assert (LEGACY.patch_bound, LEGACY.interpolate, LEGACY.predictor, LEGACY.growth) == ("legacy", 0, "legacy", 8.0)
    assert NUMPY.kernel is False and dataclasses.replace(NUMPY, kernel=None) == DEFAULT


def test_workers_compute_with_the_options_their_task_carries():
    """5-bar, 12 bound sets at (0, 70) mm in chunks of 4 on two worker processes with the legacy
    settings: bit-identical to the same chunks solved with the same settings in this process
    (brackets and Newton work), and a different amount of work than the default settings -- the
    workers did not fall back to them."""
    from evotol.robots.fivebar import FiveBar

    mech = FiveBar().clearance_mechanism()
    rng = np.random.default_rng(2)
    b = mech.thesis_bounds(b_xy=rng.uniform(1e-6, 1e-4, (12, 5)), b_z=rng.uniform(1e-6, 1e-4, (12, 5)))
    legacy = ClearanceEvaluator(mech, [[0.0, 0.07]], options=LEGACY)
    par = legacy.evaluate(b, workers=2, chunk_size=4)
    one = MaxPoseError.concat([legacy.evaluate(b[i:i + 4]) for i in range(0, 12, 4)])
    new = MaxPoseError.concat([ClearanceEvaluator(mech, [[0.0, 0.07]]).evaluate(b[i:i + 4]) for i in range(0, 12, 4)])
    for f in ("p_max", "p_upper", "r_max", "r_upper"):
        np.testing.assert_array_equal(getattr(par, f), getattr(one, f))
    assert par.n_newton == one.n_newton > 0 and par.n_solves == one.n_solves
    assert new.n_newton != one.n_newton
    for a, c in ((new, one), (one, new)):      # both certified: the brackets overlap
        assert np.all(a.p_max <= c.p_upper * (1 + 1e-12)) and np.all(a.r_max <= c.r_upper * (1 + 1e-12))


def test_work_is_returned_and_summed_over_chunks():
    from evotol.robots.fivebar import FiveBar

    mech = FiveBar().clearance_mechanism()
    poses = [[0.0, 0.07], [0.01, 0.06], [-0.01, 0.05]]
    parts = [max_pose_error(mech, [p]) for p in poses]
    whole = MaxPoseError.concat(parts)
    assert whole.n_newton == sum(p.n_newton for p in parts) and all(p.n_newton > 0 for p in parts)
    np.testing.assert_array_equal(whole.p_max, np.concatenate([p.p_max for p in parts]))


def test_concat_keeps_the_values_of_extra_sources():
    """Chunks of the 5-bar's combined clearance + geometric worst case (``extra`` sources) keep the
    extra sources' values at the maximisers when concatenated (they were dropped: None), equal to
    the same poses solved at once; mixing a part with extras and one without is refused."""
    from evotol.robots.fivebar import FiveBar, combined_max_pose_error

    poses = [[0.0, 0.07], [0.01, 0.06], [-0.01, 0.05]]
    geo = {"L1": 2e-5, "L2": 1e-5}
    parts = [combined_max_pose_error(FiveBar(), [p], geometric=geo) for p in poses]
    whole = MaxPoseError.concat(parts)
    at_once = combined_max_pose_error(FiveBar(), poses, geometric=geo)
    assert whole.p_extra.shape == at_once.p_extra.shape == (3, at_once.p_extra.shape[1])
    np.testing.assert_allclose(whole.p_extra, at_once.p_extra, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(whole.r_extra, at_once.r_extra, rtol=1e-9, atol=1e-15)
    assert np.abs(whole.p_extra).max() > 0
    mech = FiveBar().clearance_mechanism()
    with pytest.raises(ValidationError, match=r"parts\[1\]\.p_extra = 'None'"):
        MaxPoseError.concat([parts[0], max_pose_error(mech, [poses[1]])])

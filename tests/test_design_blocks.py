"""Worst case of many designs evaluated in blocks of designs (issue 43 item 4: memory that grows with what
is kept). The (designs, poses, directions) grid of a GA population over thousands of poses used to be
built at once (80 designs x 3 375 poses x 600 directions: 1.3 GB). Blocked, every design's value,
bound, worst direction and contributions equal the one-block evaluation; the only coupling between
designs is the ascent's common stopping test, so values and bounds agree to round-off and the worst
directions to the ascent's own precision."""
from __future__ import annotations

import numpy as np
import pytest

import evotol.measures.linear.stackup as stackup
from evotol.measures import linear as measures


def _blocks(rng, n_poses=40):
    dims = [1, 1, 3, 1, 2, 1, 3]
    return [rng.standard_normal((n_poses, 3, d)) for d in dims]


@pytest.mark.parametrize("kind", ["plain", "asymmetric", "top_only"])
def test_blocks_of_designs_equal_one_block(kind, monkeypatch):
    rng = np.random.default_rng(3)
    blocks = _blocks(rng)
    n = len(blocks)
    T = rng.uniform(1e-5, 1e-4, (11, n))
    shape = None
    if kind == "asymmetric":
        shape = measures.IntervalShape(rho=np.full(n, 1.0), kappa=np.array([0.5, -0.5, 0, 0.3, 0, 0, 0]),
                                       offset=np.array([0, 2e-6, 0, 0, 0, -1e-6, 0]))
    D, delta = measures.directions_for(np.concatenate(blocks, axis=2), 200, full_sphere=shape is not None)
    c = measures.support_coefficients(blocks, D, shape)
    coef = (c, D, delta) if shape is None else (c, D, delta, measures.support_constant(blocks, D, shape))
    kw = dict(coefficients=coef, shape=shape, top_only=kind == "top_only")
    whole = stackup.worst_case(blocks, T, **kw)
    per_design = 8 * c.shape[0] * max(c.shape[1], 4 * sum(B.shape[2] for B in blocks))
    assert T.shape[0] * per_design <= stackup.DESIGN_BLOCK_BYTES          # one block by default here
    seen = []
    real = stackup.worst_case

    def spy(*a, **k):
        seen.append(np.atleast_2d(a[1]).shape[0])
        return real(*a, **k)

    monkeypatch.setattr(stackup, "DESIGN_BLOCK_BYTES", 3 * per_design)     # blocks of 3 designs: 3+3+3+2
    monkeypatch.setattr(stackup, "worst_case", spy)
    blocked = spy(blocks, T, **kw)
    assert seen == [11, 3, 3, 3, 2]
    if kind == "top_only":      # the poses refined are those that may hold some design's maximum: with other
        # designs in the block, other poses keep their grid value (a lower estimate); the maxima are the same
        exact = stackup.worst_case(blocks, T, coefficients=coef)
        assert np.allclose(blocked.value.max(axis=1), whole.value.max(axis=1), rtol=1e-12)
        assert np.allclose(blocked.value.max(axis=1), exact.value.max(axis=1), rtol=1e-12)
        assert np.all(blocked.value <= exact.value * (1 + 1e-12))
        return
    # value and bound to round-off; the worst direction and the shares along it to 1e-6: h is stationary at
    # u*, so the ascent's stop at |Δh| <= 1e-14 h fixes u* only to about sqrt(1e-14) (measured 3.6e-7)
    for f, tol in (("value", 1e-12), ("bound", 1e-12), ("direction", 1e-6), ("contributions", 1e-6)):
        a, b = getattr(whole, f), getattr(blocked, f)
        assert a.shape == b.shape and np.allclose(a, b, rtol=tol, atol=tol * np.abs(a).max()), f
    # one design is one block whatever the budget
    monkeypatch.setattr(stackup, "DESIGN_BLOCK_BYTES", 1)
    one = spy(blocks, T[4], **kw)
    assert np.allclose(one.value, whole.value[4], rtol=1e-12)

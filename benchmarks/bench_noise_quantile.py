"""Benchmark of the noise quantile (issue 43; evotol/calibration/noise_share.py): ``norm_quantile`` against the
same quadrature written with ``scipy.stats.norm`` (the formulation before 2026-12-01), on the same seeded
covariances, in one run. Every calibrated budget's check evaluates it at each task pose (the UR5 ISO-calibrated
problem spent 24.7 of 47.5 s in it under cProfile before the change).

Prints the two times, their ratio, and whether the quantiles are bit-identical (they must be: the same
formulas without scipy.stats' per-call argument checks); then the check "quantile <= limit" the calibrated
budget asks, by the solved quantile and by ``norm_within`` (one evaluation of the distribution), their times and
whether they agree.

Run: ``python benchmarks/bench_noise_quantile.py``
"""
from __future__ import annotations

import os
import time

import numpy as np
from scipy.optimize import brentq
from scipy.stats import norm

from evotol.calibration import noise_share as ns


def _over_reference(L):
    L = np.asarray(L, float)[:, None]
    bounded = L <= ns.CUT
    s = np.pi / 2 * ns._S
    z = np.where(bounded, L * np.sin(s), ns.CUT * ns._S)
    w = np.where(bounded, L * np.cos(s) * np.pi / 2 * ns._W, ns.CUT * ns._W)
    return z, w


def _cdf_reference(x, lam):
    last = lambda rest: 2 * norm.cdf(np.sqrt(np.maximum(rest, 0.0) / lam[-1])) - 1    # noqa: E731
    if len(lam) == 1:
        return float(last(x))
    z1, w1 = _over_reference([np.sqrt(x / lam[0])])
    r1 = x - lam[0] * z1[0] ** 2
    if len(lam) == 2:
        return float(np.sum(w1[0] * norm.pdf(z1[0]) * last(r1)))
    z2, w2 = _over_reference(np.sqrt(np.maximum(r1, 0.0) / lam[1]))
    inner = np.sum(w2 * norm.pdf(z2) * last(r1[:, None] - lam[1] * z2 ** 2), axis=1)
    return float(np.sum(w1[0] * norm.pdf(z1[0]) * inner))


def quantile_reference(C, p):
    """:func:`evotol.calibration.noise_share.norm_quantile` as it was written with scipy.stats.norm."""
    lams = np.linalg.eigvalsh(C)
    out = np.zeros(len(lams))
    for i, lam in enumerate(lams):
        top = lam.max(initial=0.0)
        lam = np.sort(lam[lam > 1e-12 * top] / top)[::-1]
        hi = len(lam) * norm.ppf(0.5 + p / 2) ** 2 * 1.01
        out[i] = np.sqrt(top * brentq(lambda x: _cdf_reference(x, lam) - p, 0.0, hi, xtol=1e-13, rtol=1e-12))
    return out


def main() -> None:
    print(f"load average {os.getloadavg()[0]:.2f}")
    rng = np.random.default_rng(2026)
    A = rng.normal(size=(100, 3, 3)) * rng.uniform(0.1, 1.0, (100, 3, 1))
    C = A @ A.transpose(0, 2, 1) * 1e-10
    p = ns.level_of(3.0)
    t0 = time.perf_counter()
    ref = quantile_reference(C, p)
    t_ref = time.perf_counter() - t0
    t0 = time.perf_counter()
    new = ns.norm_quantile(C, p)
    t_new = time.perf_counter() - t0
    print(f"100 covariances: scipy.stats form {t_ref:.2f} s, norm_quantile {t_new:.2f} s, "
          f"ratio {t_new / t_ref:.3f}; bit-identical: {np.array_equal(ref, new)}")
    # the check "every quantile <= its limit", as the calibrated budget asks it: solved quantiles against one
    # evaluation of the distribution per covariance (norm_within), at limits 1 % and 1e-9 either side of them
    agree, t_q, t_w = 0, 0.0, 0.0
    for f in (0.99, 1 - 1e-9, 1 + 1e-9, 1.01):
        for i in range(len(C)):
            t0 = time.perf_counter()
            by_q = bool(ns.norm_quantile(C[i:i + 1], p)[0] <= new[i] * f)
            t_q += time.perf_counter() - t0
            t0 = time.perf_counter()
            by_w = ns.norm_within(C[i:i + 1], p, new[i] * f)
            t_w += time.perf_counter() - t0
            agree += by_q == by_w
    print(f"400 checks 'quantile <= limit': solved quantiles {t_q:.2f} s, norm_within {t_w:.2f} s, ratio "
          f"{t_w / t_q:.3f}; the same verdict in {agree} of 400")


if __name__ == "__main__":
    main()

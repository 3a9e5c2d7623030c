"""The perturbed 5R's end-effector over poses x samples in one compiled pass (issue 43).

:func:`evotol.robots.planar5r.kinematics.perturbed.perturbed_position` followed by
:func:`~evotol.robots.planar5r.kinematics.position.circle_intersection` is about thirty NumPy passes
over a (poses, samples) array, most of them reading the stacked errors (poses, samples, 16) through
strided views (cProfile: 30 of the 59 s of ``laramolina2019-5r``; fused, the study ran 7-13 s faster
alone). :func:`perturbed_position_stacked` keeps the
trigonometry in NumPy (the same ``np.cos``/``np.sin`` calls on the same values as the NumPy code)
and does the rest -- the crank points, the coupler radii and the circle intersection of
Lara-Molina et al. 2019, Sec. 2.5 -- in one numba loop with every operation of the NumPy code in the
same order (IEEE ``+ - * /`` and ``sqrt``: the same results to the last bit; ``tests/test_planar5r_model.py``
compares them with ``array_equal``). Without numba it is the NumPy code itself.

Error columns (m, rad) in the order of ``Planar5R.COLUMN_PARAMETERS``: ``dA1B1 dA2B2 dB1P dB2P dOA1
dOA2 dth1 dth2 cA1x cA1y cA2x cA2y cB1x cB1y cB2x cB2y``.
"""
from __future__ import annotations

import functools

import numpy as np


def _fused(c, s, E, cd1, sd1, cd2, sd2, r1, r2, r3, assembly, px, py, h2):
    """Kernel body (compiled by :func:`_compiled`): per pose p and sample i, the expressions of
    ``perturbed_position`` (chains 1 and 2, ``side`` -1 and +1) and ``circle_intersection``,
    operation by operation; writes ``px``, ``py``, ``h2`` (poses, samples)."""
    n_p, n_s = E.shape[0], E.shape[1]
    for p in range(n_p):
        ca, sa, cb, sb = c[p, 0], s[p, 0], c[p, 1], s[p, 1]
        for i in range(n_s):
            e = E[p, i]
            c1 = ca * cd1[p, i] - sa * sd1[p, i]
            s1 = sa * cd1[p, i] + ca * sd1[p, i]
            crank = r1 + e[0]
            b1x = -1.0 * (r3 + e[4]) + e[8] + e[12] + crank * c1
            b1y = e[9] + e[13] + crank * s1
            rho1 = r2 + e[2]
            c2 = cb * cd2[p, i] - sb * sd2[p, i]
            s2 = sb * cd2[p, i] + cb * sd2[p, i]
            crank = r1 + e[1]
            b2x = 1.0 * (r3 + e[5]) + e[10] + e[14] + crank * c2
            b2y = e[11] + e[15] + crank * s2
            rho2 = r2 + e[3]
            dx, dy = b2x - b1x, b2y - b1y
            d2 = dx * dx + dy * dy
            r1s = rho1 * rho1
            a = 0.5 + 0.5 * (r1s - rho2 * rho2) / d2
            h = r1s / d2 - a * a
            k = assembly * np.sqrt(h if (h >= 0.0 or h != h) else 0.0)     # np.maximum(h, 0): NaN kept
            px[p, i] = b1x + a * dx - k * dy
            py[p, i] = b1y + a * dy + k * dx
            h2[p, i] = h


@functools.lru_cache(maxsize=1)
def _compiled():
    """The compiled :func:`_fused` (numba, cached on disk; NumPy's error model: a zero distance gives
    inf/NaN as in NumPy), or None without numba."""
    from evotol._runtime.numba_cache import njit

    try:
        return njit(cache=True, error_model="numpy")(_fused)      # imports numba
    except ImportError:
        return None


def perturbed_position_stacked(theta, r1: float, r2: float, r3: float, errors, assembly: float = 1.0):
    """:func:`~evotol.robots.planar5r.kinematics.perturbed.perturbed_position` at poses x samples for
    stacked errors, in one compiled pass (module docstring); the same ``px, py, h2``.

    Parameters
    ----------
    theta : (n_poses, 2) array_like
        Nominal crank angles per pose, rad.
    r1, r2, r3 : float
        Crank, coupler and half-base lengths (the length unit of the errors).
    errors : (n_poses, n_samples, 16) array_like
        Stacked source errors per pose and sample, columns as in the module docstring.
    assembly : float, optional
        The assembly sign (+1 or -1, default +1).

    Returns
    -------
    px, py : (n_poses, n_samples) ndarray
        Perturbed end-effector position, length unit.
    h2 : (n_poses, n_samples) ndarray
        ``(h / d)^2`` of the circle intersection, dimensionless (``< 0``: no assembly).
    """
    from evotol.robots.planar5r.kinematics.perturbed import ERROR_PARAMETERS, perturbed_position

    theta = np.asarray(theta, float)
    E = np.asarray(errors, float)
    kernel = _compiled()
    if kernel is None:
        return perturbed_position(theta[:, None, :], r1, r2, r3, {k: E[..., j] for j, k in enumerate(ERROR_PARAMETERS)},
                                  assembly)
    c, s = np.cos(theta), np.sin(theta)           # E as it is: a broadcast view stays one (no copy per pose)
    trig = [f(E[..., col]) for col in (6, 7) for f in (np.cos, np.sin)]
    px, py, h2 = (np.empty(E.shape[:2]) for _ in range(3))
    kernel(c, s, E, *trig, float(r1), float(r2), float(r3), float(assembly), px, py, h2)
    return px, py, h2

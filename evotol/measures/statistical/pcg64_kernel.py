"""NumPy's PCG64 bit generator and the per-pose Latin hypercubes drawn from it, compiled and cached
(issue 43): the draws of :func:`evotol.measures.statistical.distributions.latin_hypercube_from`,
array for array.

PCG64 (O'Neill 2014, "PCG: a family of simple fast space-efficient statistically good algorithms for
random number generation", the XSL-RR 128/64 member; NumPy's ``numpy/random/src/pcg64/pcg64.h``) keeps
a 128-bit state ``s`` and increment ``c``; each 64-bit draw first steps ``s <- s M + c (mod 2^128)``
with ``M = 0x2360ED051FC65DA44385DF649FCCF645``, then outputs ``rotr64(hi(s) ^ lo(s), s >> 122)``. A
double is ``(x >> 11) 2^-53``; a 32-bit draw takes the low half of a 64-bit draw and keeps the high
half for the next one (``has_uint32``/``uinteger``), as NumPy's ``pcg64_next32`` does. The 128-bit
arithmetic is written with two 64-bit halves (the product's high half from four 32 x 32-bit products).

The shuffle is NumPy's Fisher-Yates of ``Generator.permuted`` (``random_interval``: the smallest bit mask
covering the bound, 32-bit draws rejected above it). A kernel that called NumPy's C functions through
``ctypes`` could not be cached by numba (a second of compilation in every process, so a verification
used it only from 20 000 poses on); this one is, and a verification uses it from
:data:`evotol.measures.statistical.lhs_compiled.MIN_POSES` poses on. ``tests/test_montecarlo_sampling.py``
compares both the raw draws with ``PCG64.random_raw`` and the hypercubes with the NumPy path.
"""
from __future__ import annotations

import numpy as np

from evotol._runtime.numba_cache import njit

_MUL_HI = np.uint64(0x2360ED051FC65DA4)
_MUL_LO = np.uint64(0x4385DF649FCCF645)
_M32 = np.uint64(0xFFFFFFFF)


def generator_states(generators) -> np.ndarray:
    """(K, 6) uint64 rows ``[state hi, state lo, inc hi, inc lo, has_uint32, uinteger]`` of PCG64 generators.

    Parameters
    ----------
    generators : sequence of numpy.random.PCG64
        The generators (their state is read, not advanced).

    Returns
    -------
    ndarray of uint64, shape (K, 6)
        The states, in the kernel's layout.
    """
    out = np.empty((len(generators), 6), np.uint64)
    mask = (1 << 64) - 1
    for k, g in enumerate(generators):
        st = g.state
        s, c = st["state"]["state"], st["state"]["inc"]
        out[k] = (s >> 64, s & mask, c >> 64, c & mask, st["has_uint32"], st["uinteger"])
    return out


@njit(cache=True, inline="always")
def _mulhi64(a, b):
    """The high 64 bits of the 128-bit product of uint64 a and b."""
    a0, a1, b0, b1 = a & _M32, a >> np.uint64(32), b & _M32, b >> np.uint64(32)
    p00, p01, p10, p11 = a0 * b0, a0 * b1, a1 * b0, a1 * b1
    mid = (p00 >> np.uint64(32)) + (p01 & _M32) + (p10 & _M32)
    return p11 + (p01 >> np.uint64(32)) + (p10 >> np.uint64(32)) + (mid >> np.uint64(32))


@njit(cache=True, inline="always")
def _step(sh, sl, ch, cl):
    """The state after one step, ``s M + c (mod 2^128)``, and that step's XSL-RR output: (sh, sl, x)."""
    lo = sl * _MUL_LO
    hi = _mulhi64(sl, _MUL_LO) + sh * _MUL_LO + sl * _MUL_HI
    nl = lo + cl
    nh = hi + ch + (np.uint64(1) if nl < cl else np.uint64(0))
    rot = nh >> np.uint64(58)
    x = nh ^ nl
    return nh, nl, (x >> rot) | (x << ((np.uint64(64) - rot) & np.uint64(63)))


@njit(cache=True)
def raw_draws(st, n):
    """``n`` 64-bit draws of the generator row ``st`` (advanced in place; ``PCG64.random_raw(n)``, for the tests)."""
    out = np.empty(n, np.uint64)
    sh, sl = st[0], st[1]
    for i in range(n):
        sh, sl, out[i] = _step(sh, sl, st[2], st[3])
    st[0], st[1] = sh, sl
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def latin_hypercube_kernel(states, n, d, out):
    """Each generator row ``states[k]``'s (n, d) Latin hypercube into ``out[k]``: ``n d`` doubles, then per
    column a Fisher-Yates shuffle of 1..n, then ``(pi(i) - u) / n`` (``latin_hypercube_from``'s draws). The
    state is held in local variables (a row read and written at every draw took twice the time)."""
    perm = np.empty(n, np.int64)
    for k in range(states.shape[0]):
        sh, sl, ch, cl, has32, kept = states[k, 0], states[k, 1], states[k, 2], states[k, 3], states[k, 4], states[k, 5]
        for i in range(n):
            for j in range(d):
                sh, sl, x = _step(sh, sl, ch, cl)
                out[k, i, j] = np.float64(x >> np.uint64(11)) * (1.0 / 9007199254740992.0)
        for j in range(d):
            for i in range(n):
                perm[i] = i + 1
            for i in range(n - 1, 0, -1):
                mask = np.uint64(i)
                mask |= mask >> np.uint64(1)
                mask |= mask >> np.uint64(2)
                mask |= mask >> np.uint64(4)
                mask |= mask >> np.uint64(8)
                mask |= mask >> np.uint64(16)
                while True:
                    if has32 != np.uint64(0):          # NumPy's pcg64_next32: the kept high half first
                        has32, v = np.uint64(0), kept
                    else:
                        sh, sl, x = _step(sh, sl, ch, cl)
                        has32, kept, v = np.uint64(1), x >> np.uint64(32), x & _M32
                    v &= mask
                    if v <= np.uint64(i):
                        break
                t = perm[i]
                perm[i] = perm[v]
                perm[v] = t
            for i in range(n):
                out[k, i, j] = (perm[i] - out[k, i, j]) / n
        states[k, 0], states[k, 1], states[k, 4], states[k, 5] = sh, sl, has32, kept

"""The Latin hypercubes of many poses in one compiled pass, draw for draw those of
:func:`evotol.verification.montecarlo.pose_uniforms` (issue 43 item 4: a Monte Carlo verification of
10^5 poses spent 0.2 ms a pose drawing its uniforms, most of it in NumPy's per-call overhead).

Pose p's hypercube is drawn from the PCG64 generator of ``SeedSequence(entropy, spawn_key=(p, 0))`` (the
child SciPy's ``LatinHypercube`` spawns from the pose's stream): ``n d`` doubles, then for each column
a Fisher-Yates shuffle of 1..n with NumPy's bounded integers (``random_interval``: the smallest bit mask
above the bound, 32-bit draws rejected above it), then ``(π(i) − u) / n``. The kernel calls NumPy's own
C functions of the generators (their ``ctypes`` interface), so the draws are NumPy's. A kernel that calls
ctypes pointers cannot be cached by numba: it is compiled once a process (about a second), so
:func:`evotol.verification.montecarlo.verify` uses it only from :data:`MIN_POSES` poses on.
``tests/test_montecarlo_sampling.py`` compares it with the NumPy path, array for array.
"""
from __future__ import annotations

import ctypes
import os

import numpy as np

#: poses from which a verification draws its hypercubes here (below, the compile would not pay)
MIN_POSES = 20_000

_STATE: dict = {}


def _capsule_pointer():
    get = ctypes.pythonapi.PyCapsule_GetPointer
    get.restype, get.argtypes = ctypes.c_void_p, [ctypes.py_object, ctypes.c_char_p]
    return get


def _compile():
    """The kernel, compiled on first use (None when numba is missing or ``EVOTOL_NO_NUMBA`` is set)."""
    if "kernel" in _STATE:
        return _STATE["kernel"]
    _STATE["kernel"] = None
    if os.environ.get("EVOTOL_NO_NUMBA", "").lower() in ("1", "true", "yes"):
        return None
    try:
        import numba
    except ImportError:          # pragma: no cover - numba is a dependency
        return None
    ref = np.random.PCG64(0).ctypes         # NumPy's C functions of every PCG64 (the same pointers for all)
    next_double, next_uint32 = ref.next_double, ref.next_uint32

    @numba.njit(cache=False, error_model="numpy")
    def kernel(states, n, d, out):
        perm = np.empty(n, np.int64)
        for k in range(states.shape[0]):
            st = states[k]
            for i in range(n):
                for j in range(d):
                    out[k, i, j] = next_double(st)
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
                        v = np.uint64(next_uint32(st)) & mask
                        if v <= np.uint64(i):
                            break
                    t = perm[i]
                    perm[i] = perm[v]
                    perm[v] = t
                for i in range(n):
                    out[k, i, j] = (perm[i] - out[k, i, j]) / n

    _STATE["kernel"] = kernel
    _STATE["pointer"] = _capsule_pointer()
    return kernel


def pose_lhs_generator(root: np.random.SeedSequence, p: int) -> np.random.PCG64:
    """The bit generator of pose ``p``'s Latin hypercube: ``SeedSequence(entropy, spawn_key=(p, 0))``,
    the child SciPy's class spawns from the pose's stream ``root.spawn(P)[p]`` (both paths draw from it).

    Parameters
    ----------
    root, p
        As :func:`evotol.verification.montecarlo.pose_uniforms`.

    Returns
    -------
    numpy.random.PCG64
        A new generator, nothing drawn from it yet.
    """
    return np.random.PCG64(np.random.SeedSequence(root.entropy, spawn_key=(p, 0)))


def latin_hypercubes(root: np.random.SeedSequence, poses, n: int, d: int) -> np.ndarray | None:
    """The (n, d) Latin hypercube of each pose in ``poses``, or None when the kernel is not available.

    Parameters
    ----------
    root : numpy.random.SeedSequence
        The run's seed sequence.
    poses : array_like of int
        The poses' indices.
    n, d : int
        Samples and columns of each hypercube.

    Returns
    -------
    ndarray, shape (len(poses), n, d) or None
        ``pose_uniforms(root, p, n, d, "lhs")`` for each p, stacked.
    """
    kernel = _compile() if n < 2 ** 32 else None          # (NumPy draws 64-bit integers from 2^32 samples on)
    if kernel is None:
        return None
    get = _STATE["pointer"]
    gens = [pose_lhs_generator(root, int(p)) for p in poses]
    # a bitgen_t starts with its state's address (numpy/random/bitgen.h)
    states = np.array([ctypes.c_void_p.from_address(get(g.capsule, b"BitGenerator")).value for g in gens], np.uint64)
    out = np.empty((len(gens), int(n), int(d)))
    kernel(states, int(n), int(d), out)
    return out

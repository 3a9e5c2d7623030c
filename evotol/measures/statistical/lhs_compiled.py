"""The Latin hypercubes of many poses in one compiled pass, draw for draw those of
:func:`evotol.verification.montecarlo.pose_uniforms` (issue 43 item 4: a Monte Carlo verification of
10^5 poses spent 0.2 ms a pose drawing its uniforms, most of it in NumPy's per-call overhead).

Pose p's hypercube is drawn from the PCG64 generator of ``SeedSequence(entropy, spawn_key=(p, 0))`` (the
child SciPy's ``LatinHypercube`` spawns from the pose's stream): ``n d`` doubles, then for each column
a Fisher-Yates shuffle of 1..n with NumPy's bounded integers (``random_interval``: the smallest bit mask
above the bound, 32-bit draws rejected above it), then ``(π(i) − u) / n``. The generators are NumPy's,
seeded by NumPy; their draws are made by :mod:`evotol.measures.statistical.pcg64_kernel` (PCG64 compiled
and cached by numba). :func:`evotol.verification.montecarlo.verify` uses it from :data:`MIN_POSES`
poses on. ``tests/test_montecarlo_sampling.py`` compares it with the NumPy path, array for array.
"""
from __future__ import annotations

import functools
import os

import numpy as np

#: poses from which a verification draws its hypercubes here: the NumPy path costs about 0.9 ms a pose
#: (100 samples x 36 columns), loading numba and the cached kernel about 0.5-1.5 s once per process
MIN_POSES = 500

@functools.lru_cache(maxsize=1)
def _kernel():
    """The kernel module (None when numba is missing or ``EVOTOL_NO_NUMBA`` is set), imported on first use."""
    if os.environ.get("EVOTOL_NO_NUMBA", "").lower() in ("1", "true", "yes"):
        return None
    try:
        from evotol.measures.statistical import pcg64_kernel
    except ImportError:          # pragma: no cover - numba is a dependency
        return None
    return pcg64_kernel


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
    kernel = _kernel() if n < 2 ** 32 else None          # (NumPy draws 64-bit integers from 2^32 samples on)
    if kernel is None:
        return None
    states = kernel.generator_states([pose_lhs_generator(root, int(p)) for p in poses])
    out = np.empty((len(states), int(n), int(d)))
    kernel.latin_hypercube_kernel(states, int(n), int(d), out)
    return out

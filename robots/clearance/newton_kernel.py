"""One barrier-Newton iteration of the support-function solver, compiled per problem (numba).

:func:`evotol.robots.clearance.support.solve_support` minimises, for every problem of a batch, the
reduced log barrier ``F(mu) = sum_c q_c - log(1 + q_c)``, ``q_c = sqrt(1 + tau^2 ||y_c||^2)``,
``y = a + B mu`` (its module docstring has the derivation). One iteration is

1. the barrier pieces per cone (disk pair or interval row): ``t_c = (1 + q_c) / tau``,
   ``sigma_c = y_c / t_c`` (gradient part), the row weights ``w`` and the disk rank-one terms;
2. the gradient ``g = tau B^T sigma`` and the Hessian ``H = B^T W B - sum_disks G_c G_c^T``
   (``G_c = c_c y_c^T B_c``), assembled group by group over the loop map's block sparsity;
3. the Newton step ``d = -H^{-1} g`` (Cholesky; LU with partial pivoting if round-off makes
   ``H`` indefinite), the decrement ``lambda^2 = -g^T d`` and ``B d``;
4. the backtracking line search on ``F`` (steps 1, .5, .25, .12, never shorter than the damped
   step ``1 / (1 + lambda)`` that self-concordance guarantees; only when ``lambda > 0.25``; a trial
   not longer than the damped step is not evaluated, the damped step is taken: the same step);
5. the update of ``mu`` and ``y`` and, optionally, the certified dual value ``sum_c ||y_c||``.

At a centred point two more compiled steps run on the centred problems only: the feasible
primal point (barrier point projected onto the loop equations and scaled into the cones: the
certified lower bound, :func:`project_centred`) and the path predictor (:func:`predict_centred`).
The kernels read ``B``, ``a`` and ``pinv(B^T B)`` of the original problems through the working
set's index, so nothing of size ``K x R x m`` is copied when the working set shrinks; the Newton
iteration reads each column group's block of ``B`` from one contiguous array
(:func:`group_blocks`, built once per solve).

The kernel bodies, plain Python loops, are in :mod:`evotol.robots.clearance.newton_kernel_bodies`; this
module lays out the column groups for them (:func:`group_arrays`, :func:`group_blocks`), compiles
them and calls them (:func:`newton_iterate`, :func:`project_centred`, :func:`predict_centred`).

The NumPy version (``solve_support(..., kernel=False)``, ``EngineOptions(kernel=False)``) does this
with batched array operations (some twenty temporaries of the batch's size per iteration);
compiled, one problem's iteration stays in the first-level cache, several times faster on the
IRSBot-2 problems (``benchmarks/bench_clearance.py``). Both agree to round-off.

numba is a dependency of evotol, imported on the first compiled iteration. The first use on a
fresh install compiles the kernel (about 6 s) into numba's on-disk cache (``__pycache__`` beside
this file, or numba's user-wide cache directory; where neither can be written, a temporary folder,
:mod:`evotol._runtime.numba_cache`); later processes load it in about 0.5 s. If numba
cannot be imported or fails to compile, a ``RuntimeWarning`` says so once and the solver uses the
NumPy iteration (same results up to round-off); ``EVOTOL_NO_NUMBA=1`` asks for that explicitly.

The parameters several definitions of this module share are described once, here.

Parameters
----------
rows : (k,) int array_like
    Original problem of each working problem.
cidx : (n,) int array_like
    Working indices of the centred problems.
B : (K, R, m) ndarray
    Scaled loop maps of the original problems.
"""
from __future__ import annotations

import functools
import importlib.util
import logging
import os
import types
import warnings

import numpy as np

from evotol.robots.clearance.newton_kernel_bodies import (_chol_factor, _chol_solve, _newton_iterate_py, _predict_centred_py,
                                                   _project_centred_py)

logger = logging.getLogger(__name__)

#: False when numba is missing or EVOTOL_NO_NUMBA is set (NumPy iteration); :func:`_kernel` is None
#: also when numba fails to compile
AVAILABLE = (os.environ.get("EVOTOL_NO_NUMBA", "").lower() not in ("1", "true", "yes")
             and importlib.util.find_spec("numba") is not None)

#: steps of the backtracking line search (the compiled kernels and newton_numpy)
LINE_SEARCH = np.array([1.0, 0.5, 0.25, 0.12])


def group_arrays(grows, nd: int):
    """Flat description of the column groups for the kernel: per group the disk-cone range
    ``[d0, d1)``, the interval-row range ``[i0, i1)`` (rows of the permuted problem), its
    columns ``cols[off[g]:off[g+1]]`` and the offset ``boff[g]`` of its block in
    :func:`group_blocks`.

    Parameters
    ----------
    grows : sequence of tuple
        Per group ``(disk-row slice, interval-row slice, columns, disk-cone slice)`` of the
        permuted problem (as built in :func:`evotol.robots.clearance.support.solve_support`).
    nd : int
        Number of disk cones (not used by the layout).

    Returns
    -------
    gd : (G, 2) int64 ndarray
        Disk-cone range ``[d0, d1)`` of each group.
    gi : (G, 2) int64 ndarray
        Interval-row range ``[i0, i1)`` of each group.
    cols : (sum s_g,) int64 ndarray
        The groups' loop columns, concatenated.
    off : (G + 1,) int64 ndarray
        Offsets of each group's columns in ``cols``.
    boff : (G + 1,) int64 ndarray
        Offsets of each group's block in the rows of :func:`group_blocks`.
    """
    gd = np.array([(s.start, s.stop) for *_, s in grows], np.int64).reshape(-1, 2)
    gi = np.array([(ir.start, ir.stop) for _, ir, _, _ in grows], np.int64).reshape(-1, 2)
    cols = [np.asarray(c, np.int64) for _, _, c, _ in grows]
    off = np.concatenate([[0], np.cumsum([len(c) for c in cols])]).astype(np.int64)
    sizes = [(2 * (d1 - d0) + (i1 - i0)) * len(c) for (d0, d1), (i0, i1), c in zip(gd, gi, cols)]
    boff = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    return gd, gi, np.concatenate(cols) if cols else np.zeros(0, np.int64), off, boff


def group_blocks(B, grows):
    """Each group's rows x columns of ``B`` (K, R, m), flattened side by side: (K, sum nr_g s_g),
    the layout :func:`_newton_iterate_py` reads with :func:`group_arrays`' offsets. One group over
    all rows and columns in order (the IRSBot-2 distal module) is ``B`` itself: a view, no copy.

    Parameters
    ----------
    B : (K, R, m) ndarray
        Scaled loop maps of the permuted problems.
    grows : sequence of tuple
        Per group ``(disk-row slice, interval-row slice, columns, disk-cone slice)``.

    Returns
    -------
    (K, sum nr_g s_g) ndarray
        C-contiguous; each group's ``(nr_g, s_g)`` block (disk rows, then interval rows, by its
        columns) flattened, groups side by side.
    """
    if len(grows) == 1:
        dr, ir, cols, _ = grows[0]
        if (dr.start == 0 and ir.start == dr.stop and ir.stop == B.shape[1]
                and np.array_equal(cols, np.arange(B.shape[2])) and B.flags.c_contiguous):
            return B.reshape(len(B), -1)
    K = len(B)
    sizes = [(dr.stop - dr.start + ir.stop - ir.start) * len(cols) for dr, ir, cols, _ in grows]
    out = np.empty((K, sum(sizes)))
    o = 0
    for (dr, ir, cols, _), n in zip(grows, sizes):
        n2 = dr.stop - dr.start
        block = out[:, o:o + n].reshape(K, n2 + ir.stop - ir.start, len(cols))
        # each run of consecutive columns is copied as a slice (a fancy index costs twice as much)
        for run in np.split(np.arange(len(cols)), np.nonzero(np.diff(cols) != 1)[0] + 1):
            if run.size:
                c0, c1, r0, r1 = cols[run[0]], cols[run[-1]] + 1, run[0], run[-1] + 1
                block[:, :n2, r0:r1] = B[:, dr, c0:c1]
                block[:, n2:, r0:r1] = B[:, ir, c0:c1]
        o += n
    return out


def _say_if_compiling(dispatcher) -> None:
    """One log line (INFO; standard error under the ``evotol`` command) when numba's on-disk cache has
    no copy of the kernels yet (a fresh install): the first solve then pauses ~10 s to compile them,
    and should not look hung."""
    try:
        index = dispatcher._cache._cache_file._index_path      # numba internals; silent if they change
    except AttributeError:
        return
    if not os.path.exists(index):
        logger.info("compiling the clearance engine's Newton kernels with numba (once per install, "
                    "about 10 s; cached in %s)", os.path.dirname(index))


def _bound(fn, **names):
    """``fn`` calling ``names`` (the compiled helpers) through a copy of its globals: numba resolves
    a kernel's calls there, and this module's own names stay the Python functions."""
    out = types.FunctionType(fn.__code__, dict(fn.__globals__, **names), fn.__name__, fn.__defaults__, fn.__closure__)
    out.__qualname__, out.__module__ = fn.__qualname__, fn.__module__
    return out


def _kernel():
    """The compiled kernels (loaded once per process), or None: switched off or numba unusable."""
    return _compiled() if AVAILABLE else None


@functools.lru_cache(maxsize=1)
def _compiled():
    try:
        from evotol._runtime.numba_cache import njit     # cache=True that falls back (issue 42)

        # a read-only install caches in a temporary folder instead of dropping to the NumPy iteration (issue 43)
        jit = njit(cache=True, nogil=True, error_model="numpy")
        helpers = {"_chol_factor": jit(_chol_factor), "_chol_solve": jit(_chol_solve)}
        compiled = tuple(jit(_bound(f, **helpers)) for f in (_newton_iterate_py, _project_centred_py, _predict_centred_py))
        _say_if_compiling(compiled[0])
        return compiled
    except Exception as exc:        # pragma: no cover - depends on the platform
        warnings.warn(f"evotol.robots.clearance.newton_kernel: numba unavailable ({exc!r}); the clearance engine "
                      "uses its NumPy iteration (same results, slower)", RuntimeWarning, stacklevel=3)
        return None


def newton_iterate(Y, mu, GB, rows, tau, nd, groups, want_dual: bool):
    """Run one iteration on every working problem ``i`` (original problem ``rows[i]``: its group
    blocks are ``GB[rows[i]]``, :func:`group_blocks`); see :func:`_newton_iterate_py`. Returns
    ``(H, lam2, dual, fail)``; ``groups`` is :func:`group_arrays`'s output.

    Parameters
    ----------
    Y : (k, R) ndarray
        Dual vectors ``y = a + B mu`` of the working problems (writeable C-contiguous float64;
        updated in place).
    mu : (k, m) ndarray
        Dual points (writeable C-contiguous float64; updated in place).
    GB : (K, sum nr_g s_g) ndarray
        Group blocks of ``B`` of the original problems (:func:`group_blocks`).
    tau : (k,) ndarray
        Barrier parameters.
    groups : tuple
        Output of :func:`group_arrays`.
    want_dual : bool
        Also compute the dual value after the step.

    Returns
    -------
    H : (k, m, m) ndarray
        Hessians at the start points (for the path predictor).
    lam2 : (k,) ndarray
        Squared Newton decrements (0 where ``H`` is singular).
    dual : (k,) ndarray
        ``sum_c ||y_c||`` after the step (undefined unless ``want_dual``).
    fail : (k,) int64 ndarray
        1 where ``H`` is exactly singular (no step taken), else 0.

    Raises
    ------
    ValueError
        ``Y`` or ``mu`` not a writeable C-contiguous float64 array.
    """
    for name, x in (("Y", Y), ("mu", mu)):     # updated in place
        if not (x.flags.c_contiguous and x.flags.writeable and x.dtype == np.float64):
            raise ValueError(f"newton_iterate: {name} must be a writeable C-contiguous float64 array")
    k, m = mu.shape
    H = np.empty((k, m, m))
    lam2 = np.empty(k)
    dual = np.empty(k)
    fail = np.zeros(k, np.int64)
    gd, gi, gcols, goff, boff = groups
    _kernel()[0](Y, mu, np.ascontiguousarray(GB, dtype=np.float64), np.asarray(rows, np.int64),
                 np.ascontiguousarray(tau, float), int(nd), gd, gi, gcols, goff, boff, LINE_SEARCH,
                 bool(want_dual), H, lam2, dual, fail)
    return H, lam2, dual, fail


def project_centred(cidx, rows, Y, a, B, gram_inv, tau, nd):
    """Feasible points of the centred working problems ``cidx`` (original problems ``rows[cidx]``
    of ``a``, ``B``, ``gram_inv``; see :func:`_project_centred_py`); returns ``(s0, s, lower)``.

    Parameters
    ----------
    Y : (k, R) ndarray
        Dual vectors of the working problems.
    a : (K, R) ndarray
        Scaled linear terms of the original problems.
    gram_inv : (K, m, m) ndarray
        ``pinv(B^T B)`` of the original problems.
    tau : (k,) ndarray
        Barrier parameters of the working problems.

    Returns
    -------
    s0 : (n, R) ndarray
        Barrier points ``y_c / t_c``.
    s : (n, R) ndarray
        Feasible scaled screws (loop residual removed, scaled into the unit cones).
    lower : (n,) ndarray
        ``a^T s``: lower bounds of the support values.
    """
    n, R = len(cidx), Y.shape[1]
    s0, s, lo = np.empty((n, R)), np.empty((n, R)), np.empty(n)
    _kernel()[1](np.asarray(cidx, np.int64), np.asarray(rows, np.int64), Y, a, B, gram_inv, tau, int(nd), s0, s, lo)
    return s0, s, lo


def predict_centred(cidx, rows, Y, mu, B, H, told, tnew, cand, nd):
    """The path predictor on the centred working problems ``cidx`` (``B`` of the original
    problems ``rows[cidx]``), in place on Y and mu (see :func:`_predict_centred_py`).

    Parameters
    ----------
    Y : (k, R) ndarray
        Dual vectors of the working problems (updated in place).
    mu : (k, m) ndarray
        Dual points of the working problems (updated in place).
    H : (k, m, m) ndarray
        Hessians of the working problems (from :func:`newton_iterate`).
    told : (n,) ndarray
        Barrier parameters at the centred points.
    tnew : (n,) ndarray
        New barrier parameters.
    cand : (n, c) ndarray
        Candidate scales of the predictor step (the one with the lowest barrier is taken).
    """
    _kernel()[2](np.asarray(cidx, np.int64), np.asarray(rows, np.int64), Y, mu, B, H, np.ascontiguousarray(told, float),
                 np.ascontiguousarray(tnew, float), np.ascontiguousarray(cand, float), int(nd))


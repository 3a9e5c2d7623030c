"""Grid studies on all local cores, or on a Dask cluster when given a scheduler address.

The poses are cut into fixed-size chunks (``chunk_size``, independent of the number of workers),
each chunk is solved by :func:`evotol.robots.clearance.max_pose_error` in a worker, and the chunks are
put back in order. Because the chunks do not depend on where they run, a local run and a Dask
run return identical arrays.

The chunks run on evotol's one executor (:func:`evotol._runtime.executor.parallel_map`):

* default: local processes, ``workers`` of them (default: the number of CPUs; ``workers=1``
  runs in this process);
* ``scheduler="tcp://host:8786"`` (or an ``inproc://`` address, or a ``distributed.Client``):
  the chunks are submitted to that Dask cluster (the existing Dask engine, no home-made cluster).
"""
from __future__ import annotations

import time

import numpy as np

from evotol.errors import ValidationError
from evotol._runtime.executor import parallel_map
from evotol.robots.clearance.maxerror import MaxPoseError, max_pose_error
from evotol.robots.clearance.model import ClearanceMechanism
from evotol.robots.clearance.options import DEFAULT, EngineOptions
from evotol.robots.clearance.support import warm_up


def _solve_chunk(args):
    mech, poses, bounds, tol, options = args
    return max_pose_error(mech, poses, bounds, tol=tol, options=options)


def grid_max_pose_error(mech: ClearanceMechanism, poses, bounds=None, *, tol: float = 1e-3, chunk_size: int = 256,
                        workers: int | None = None, scheduler=None, options: EngineOptions = DEFAULT) -> MaxPoseError:
    """:func:`max_pose_error` over many poses, chunked and run in parallel (see module doc).

    bounds: None, (n_joints, 4) or (n, n_joints, 4); options: the engine's settings, sent to every
    worker with its chunk. ``seconds`` of the result is the wall time.

    Parameters
    ----------
    poses : (n, d) array_like
        Poses in the mechanism's pose coordinates (m).
    bounds : array_like or None, optional
        None (default: the joints' own bounds), ``(n_joints, 4)`` or ``(n, n_joints, 4)``; columns
        ``[beta_xy (rad), beta_z (rad), b_xy (m), b_z (m)]``.
    chunk_size : int, optional
        Poses per chunk (default 256).
    workers : int or None, optional
        Local processes (default None: the number of CPUs; 1: in this process).
    scheduler : str or distributed.Client or None, optional
        Dask scheduler address or client (default None: local processes).

    Returns
    -------
    MaxPoseError
        One case per pose, in order (``seconds``: wall time).

    Raises
    ------
    ValidationError
        ``chunk_size < 1``, or bounds rejected by :func:`max_pose_error`.
    """
    t0 = time.perf_counter()
    poses = np.atleast_2d(np.asarray(poses, float))
    n = len(poses)
    if chunk_size < 1:
        raise ValidationError("chunk_size", chunk_size, "a positive number of poses")
    b = mech.default_bounds() if bounds is None else np.asarray(bounds, float)
    starts = range(0, n, chunk_size)
    per_pose = b.ndim == 3
    items = [(mech, poses[s:s + chunk_size], b[s:s + chunk_size] if per_pose else b, tol, options) for s in starts]
    warm_up()     # compile the solver's kernels once here, not once per worker (fresh install)
    parts = parallel_map(_solve_chunk, items, workers=workers, scheduler=scheduler)
    out = MaxPoseError.concat(parts)
    out.seconds = time.perf_counter() - t0
    return out

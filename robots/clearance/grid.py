"""Grid studies on all local cores, or on a Dask cluster when given a scheduler address.

The poses are cut into fixed-size chunks (``chunk_size``, independent of the number of workers),
each chunk is solved by :func:`robots.clearance.max_pose_error` in a worker, and the chunks are
put back in order. Because the chunks do not depend on where they run, a local run and a Dask
run return identical arrays.

* default: ``concurrent.futures.ProcessPoolExecutor`` with ``workers`` processes (default: the
  number of CPUs; ``workers=1`` runs in this process);
* ``scheduler="tcp://host:8786"`` (or an ``inproc://`` address, or a ``distributed.Client``):
  the chunks are submitted with ``Client.map`` and gathered (the existing Dask engine, no
  home-made cluster).
"""
from __future__ import annotations

import os
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Callable, Sequence

import numpy as np

from evotol.errors import ValidationError
from robots.clearance.maxerror import MaxPoseError, max_pose_error
from robots.clearance.model import ClearanceMechanism


def parallel_map(fn: Callable, items: Sequence, *, workers: int | None = None, scheduler=None) -> list:
    """``[fn(x) for x in items]`` on local processes or on a Dask cluster; order preserved.

    fn must be picklable (a module-level function or a ``functools.partial`` of one)."""
    items = list(items)
    if scheduler is not None:
        try:
            from distributed import Client
        except ImportError as exc:  # pragma: no cover - dask is a declared optional dependency
            raise ValidationError("scheduler", scheduler, "dask[distributed] installed (pip install evotol[dask])") from exc
        if isinstance(scheduler, Client):
            client, own = scheduler, False
        else:
            client, own = Client(scheduler), True
        try:
            futures = client.map(fn, items, pure=False)
            return client.gather(futures)
        finally:
            if own:
                client.close()
    n = (os.cpu_count() or 1) if workers is None else int(workers)
    if n < 1:
        raise ValidationError("workers", workers, "a positive number of processes")
    if n == 1 or len(items) <= 1:
        return [fn(x) for x in items]
    with ProcessPoolExecutor(max_workers=min(n, len(items))) as pool:
        return list(pool.map(fn, items))


def _solve_chunk(args):
    mech, poses, bounds, tol = args
    return max_pose_error(mech, poses, bounds, tol=tol)


def concat_results(parts: Sequence[MaxPoseError]) -> MaxPoseError:
    cat = {f: np.concatenate([getattr(p, f) for p in parts]) for f in
           ("p_max", "p_upper", "r_max", "r_upper", "p_screws", "r_screws", "p_twist", "r_twist")}
    return MaxPoseError(**cat, joint_names=parts[0].joint_names, n_solves=sum(p.n_solves for p in parts),
                        seconds=sum(p.seconds for p in parts))


def grid_max_pose_error(mech: ClearanceMechanism, poses, bounds=None, *, tol: float = 1e-3, chunk_size: int = 256,
                        workers: int | None = None, scheduler=None) -> MaxPoseError:
    """:func:`max_pose_error` over many poses, chunked and run in parallel (see module doc).

    bounds: None, (n_joints, 4) or (n, n_joints, 4). ``seconds`` of the result is the wall time."""
    t0 = time.perf_counter()
    poses = np.atleast_2d(np.asarray(poses, float))
    n = len(poses)
    if chunk_size < 1:
        raise ValidationError("chunk_size", chunk_size, "a positive number of poses")
    b = mech.default_bounds() if bounds is None else np.asarray(bounds, float)
    starts = range(0, n, chunk_size)
    per_pose = b.ndim == 3
    items = [(mech, poses[s:s + chunk_size], b[s:s + chunk_size] if per_pose else b, tol) for s in starts]
    parts = parallel_map(_solve_chunk, items, workers=workers, scheduler=scheduler)
    out = concat_results(parts)
    out.seconds = time.perf_counter() - t0
    return out

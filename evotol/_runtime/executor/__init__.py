"""One parallel executor for every chunked computation in evotol (design studies, clearance grids).

* :func:`run_chunks` -- call ``fn(*common, item)`` for every item on local processes
  (``concurrent.futures``) or on a Dask cluster, handing each finished result to a callback as
  it arrives (progress bars, saving chunks); an interrupt (Ctrl-C) or a failing chunk stops the
  running workers at once and keeps what finished;
* :func:`parallel_map` -- the same, returning ``[fn(*common, x) for x in items]`` in order;
* :class:`ChunkStore` -- finished DataFrame chunks as Parquet files in a folder with a manifest,
  so that an interrupted run resumes with only the missing chunks.

This package sits below the robots and the problem layer (it imports nothing of evotol but
:mod:`evotol.errors`), so ``robots/clearance`` and ``evotol.design`` share it.
"""
from evotol._runtime.executor.backends import parallel_map, run_chunks, scheduler_of, worker_count
from evotol._runtime.executor.store import ChunkStore

__all__ = ["run_chunks", "parallel_map", "scheduler_of", "worker_count", "ChunkStore"]

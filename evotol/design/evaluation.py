"""Chunked, resumable evaluation of design entries (:func:`evaluate`).

An *evaluator* is a picklable callable ``DataFrame -> DataFrame`` computing the objectives of a
whole chunk of entries in one vectorised call (STYLE.md "pymoo"). The chunks run on the one
executor of :mod:`evotol._runtime.executor` (local processes, or a Dask cluster with
``scheduler="tcp://..."``), a tqdm bar counts entries done, and every finished chunk is saved in
a :class:`~evotol._runtime.executor.ChunkStore`: started again on the same entries, only the missing
chunks run (an interrupted study resumes).
"""
from __future__ import annotations

import hashlib
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Mapping

import numpy as np
import pandas as pd

from evotol.design.factors import ERROR, FEASIBLE
from evotol.errors import EvotolError, SchedulerLost, ValidationError
from evotol._runtime.executor import ChunkStore, run_chunks, worker_count

#: an entry evaluator: a DataFrame of factor columns in, one row per entry of objective columns out
Evaluator = Callable[[pd.DataFrame], pd.DataFrame]


def _evaluate_chunk(evaluator: Evaluator, inputs: pd.DataFrame) -> pd.DataFrame:
    """Run the evaluator on one chunk; isolate entries that raise an EvotolError.

    Returns the evaluator's output columns plus ``feasible`` and ``error`` (the message of an
    entry that could not be evaluated, e.g. a pose out of reach; its objectives are NaN and
    ``feasible`` is False -- the failure is recorded, never silent), whatever the chunk size: when
    the whole chunk raises, each entry is re-run alone. A malformed evaluator output (not a
    DataFrame or dict of arrays with one row per entry) is a programming error: its
    ValidationError propagates.
    """
    if len(inputs) == 1:
        out = _evaluate_entry(evaluator, inputs)
    else:
        try:
            raw = evaluator(inputs)
        except EvotolError:
            out = pd.concat([_evaluate_entry(evaluator, inputs.iloc[i:i + 1]) for i in range(len(inputs))],
                            ignore_index=True)
        else:
            out = _as_frame(raw, len(inputs))
            out[ERROR] = ""
    out.index = inputs.index
    objectives = [c for c in out.columns if c not in (FEASIBLE, ERROR)]
    finite = np.all(np.isfinite(out[objectives].to_numpy(dtype=float)), axis=1) if objectives else np.ones(len(out), bool)
    if FEASIBLE in out:
        out[FEASIBLE] = out[FEASIBLE].fillna(False).astype(bool) & finite
    else:
        out[FEASIBLE] = finite & (out[ERROR] == "")
    return out


def _evaluate_entry(evaluator: Evaluator, entry: pd.DataFrame) -> pd.DataFrame:
    """One entry (a 1-row frame): its output row with ``error`` empty, or only ``error`` when it raised."""
    try:
        raw = evaluator(entry)
    except EvotolError as exc:
        return pd.DataFrame({ERROR: [f"{type(exc).__name__}: {exc}"]})
    out = _as_frame(raw, 1)
    out[ERROR] = ""
    return out


def _as_frame(out, n: int) -> pd.DataFrame:
    if isinstance(out, Mapping):
        out = pd.DataFrame({k: np.asarray(v) for k, v in out.items()})
    if not isinstance(out, pd.DataFrame) or len(out) != n:
        got = f"DataFrame with {len(out)} rows" if isinstance(out, pd.DataFrame) else type(out).__name__
        raise ValidationError("evaluator output", got, f"a DataFrame (or dict of arrays) with {n} rows")
    return out.reset_index(drop=True)


def _fingerprint(entries: pd.DataFrame, evaluator) -> str:
    h = hashlib.sha1()
    h.update(pd.util.hash_pandas_object(entries, index=False).to_numpy().tobytes())
    h.update(",".join(map(str, entries.columns)).encode())
    key = getattr(evaluator, "cache_key", None)
    h.update(str(key() if callable(key) else (key if key is not None else repr(evaluator))).encode())
    return h.hexdigest()


@dataclass
class EvaluationLog:
    """What :func:`evaluate` did: chunks evaluated now, chunks reused from the store, time.

    Pass one to :func:`evaluate` (``log=``) and read it afterwards; the defaults are an empty log.

    Parameters
    ----------
    n_entries : int, default 0
        Number of entries evaluated (rows of ``entries``).
    n_chunks : int, default 0
        Number of chunks the entries were split into.
    chunks_evaluated : list of int
        Indices of the chunks run by this call, in the order they finished.
    chunks_resumed : list of int
        Indices of the chunks read back from the store (sorted).
    seconds : float, default 0.0
        Wall-clock time of the call (s).
    backend : str, default ""
        Where the chunks ran (``"in-process"``, ``"2 local processes"``, ``"dask ..."``), or
        ``"store"`` when every chunk was resumed.
    """

    n_entries: int = 0
    n_chunks: int = 0
    chunks_evaluated: list[int] = field(default_factory=list)
    chunks_resumed: list[int] = field(default_factory=list)
    seconds: float = 0.0
    backend: str = ""


def evaluate(entries: pd.DataFrame, evaluator: Evaluator, *, store: str | Path | None = None,
             chunk_size: int | None = None, workers: int | None = None, scheduler: str | None = None,
             progress: bool = True, description: str = "entries", log: EvaluationLog | None = None
             ) -> pd.DataFrame:
    """Evaluate every entry; returns inputs + objectives + ``feasible`` + ``error`` columns.

    An entry whose evaluation raises an :class:`~evotol.errors.EvotolError` (e.g. a pose out of
    reach) is re-run alone and recorded with its message in ``error``, NaN objectives and
    ``feasible`` False; an entry with a non-finite objective is infeasible too.

    Parameters
    ----------
    entries : pandas.DataFrame
        A DataFrame from :func:`~evotol.design.designs.full_factorial` & co. (any columns; all go to
        the evaluator), non-empty.
    evaluator : callable
        Picklable ``DataFrame -> DataFrame`` (or dict of arrays) computing one chunk in one
        vectorised call, one output row per input row, with column names other than the
        inputs'; an optional ``feasible`` column is combined with the finiteness check. An
        optional ``cache_key`` attribute/method identifies its settings for resuming.
    store : str or Path, optional
        Folder for finished chunks (``chunk_00012.parquet``) and a manifest; on a later call
        with the same entries and evaluator only the missing chunks run (resume after an
        interruption); a store holding another study's chunks is cleared first. None: nothing
        is stored.
    chunk_size : int, optional
        Entries per chunk (default: about 8 chunks per worker, at most 2048).
    workers : int, optional
        Local processes (default: all cores; 1 = in this process, no pickling).
    scheduler : str, optional
        Address of a Dask scheduler (``"tcp://host:8786"``); chunks then run on that cluster
        (dask.distributed) instead of local processes.
    progress : bool, default True
        Show a tqdm bar counting entries done.
    description : str, default "entries"
        Label of the progress bar.
    log : EvaluationLog, optional
        An :class:`EvaluationLog` to fill (which chunks ran, which were resumed, time, backend).

    Returns
    -------
    pandas.DataFrame
        The entries (index reset) with the evaluator's columns, ``feasible`` (bool) and
        ``error`` (str, empty when evaluated) appended; ``attrs`` are the entries' with
        ``attrs["evotol"]["objectives"]`` listing the evaluator's output columns.

    Raises
    ------
    ValidationError
        ``entries`` is not a non-empty DataFrame, ``evaluator`` is not callable, ``chunk_size``
        or ``workers`` is not a positive integer, or the evaluator's columns repeat input column
        names, or the evaluator's output is not a DataFrame or dict of arrays with one row per
        entry (a programming error, raised, not recorded in ``error``).
    evotol.errors.SchedulerLost
        The Dask ``scheduler`` did not answer or was lost: names the number of chunks written and
        verified in ``store``, which a rerun resumes (``docs/reliability.md``).
    """
    from tqdm.auto import tqdm

    if not isinstance(entries, pd.DataFrame) or len(entries) == 0:
        raise ValidationError("entries", type(entries).__name__, "a non-empty DataFrame")
    if not callable(evaluator):
        raise ValidationError("evaluator", evaluator, "a callable DataFrame -> DataFrame")
    t0 = time.perf_counter()
    n = len(entries)
    workers = worker_count(workers)
    if chunk_size is None:
        chunk_size = max(1, min(2048, math.ceil(n / (8 * workers))))
    if not (isinstance(chunk_size, (int, np.integer)) and chunk_size >= 1):
        raise ValidationError("chunk_size", chunk_size, "a positive integer")
    entries = entries.reset_index(drop=True)
    bounds = [(s, min(s + chunk_size, n)) for s in range(0, n, chunk_size)]
    log = log if log is not None else EvaluationLog()
    log.n_entries, log.n_chunks = n, len(bounds)

    results: dict[int, pd.DataFrame] = {}
    chunks = None
    if store is not None:
        chunks = ChunkStore(store, key=_fingerprint(entries, evaluator), n_entries=n, chunk_size=int(chunk_size))
        results = chunks.open()
        log.chunks_resumed = sorted(results)
    todo = [i for i in range(len(bounds)) if i not in results]

    def _done(k: int, out: pd.DataFrame) -> None:
        i = todo[k]
        results[i] = out
        log.chunks_evaluated.append(i)
        if chunks is not None:
            chunks.save(i, out)
        bar.update(len(out))

    initial = sum(len(r) for r in results.values())
    with tqdm(total=n, initial=initial, unit="entry", desc=description, disable=not progress,
              dynamic_ncols=True, mininterval=0.5) as bar:
        if not todo:
            log.backend = "store"
        else:
            try:
                log.backend = run_chunks(_evaluate_chunk, [entries.iloc[bounds[i][0]:bounds[i][1]] for i in todo],
                                         _done, common=(evaluator,), workers=workers, scheduler=scheduler)
            except SchedulerLost as lost:     # the chunks saved so far are verified in the store's manifest
                kept = len(chunks.chunks) if chunks is not None else 0
                raise SchedulerLost(lost.address, lost.reason, kept, None if store is None else str(store)) from lost

    out = pd.concat([results[i] for i in range(len(bounds))], ignore_index=True)
    out.index = entries.index
    overlap = [c for c in out.columns if c in entries.columns]
    if overlap:
        raise ValidationError("evaluator output columns", overlap, "names different from the input columns")
    df = pd.concat([entries, out], axis=1)
    df.attrs = dict(entries.attrs)
    meta = df.attrs.setdefault("evotol", {})
    meta["objectives"] = [c for c in out.columns if c not in (FEASIBLE, ERROR)]
    log.seconds = time.perf_counter() - t0
    return df



"""Design-of-experiments entries for design studies, and their chunked, resumable evaluation.

Deng (2012), Sec. VII.1.1 and Fig. VII.1: a design study evaluates many **entries** -- one value
per design variable (a tolerance level, a link length) -- and draws every entry as one line on
parallel coordinates. This module makes the entries and evaluates them:

* :class:`Factor` -- one design variable: discrete ``levels`` or a continuous ``[low, high]``,
  optionally log-scaled (tolerances spanning decades);
* :func:`full_factorial`, :func:`random_subset` (the thesis's 1000 of 32 768 entries, seeded) and
  :func:`latin_hypercube` (continuous ranges, log-uniform where ``log=True``) -- each returns a
  pandas DataFrame with an ``entry`` id column and one column per factor;
* :func:`evaluate` -- runs an *evaluator* (a picklable callable ``DataFrame -> DataFrame`` that
  computes the objectives of a whole chunk of entries in one vectorised call, STYLE.md "pymoo")
  on local cores (default) or on a Dask cluster (``scheduler="tcp://..."``), shows a tqdm
  progress bar, saves every finished chunk as Parquet in ``store`` and, when started again on the
  same entries, evaluates only the chunks that are missing (an interrupted study resumes);
* :func:`nsga2` -- NSGA-II (pymoo) over the factors' continuous ranges with the same evaluator,
  returning the Pareto entries and their knee points (issue "beyond the levels");
* :func:`save_entries` / :func:`load_entries` -- CSV + Parquet; the factor definitions travel in
  the Parquet metadata so ``evotol filter`` knows which columns are inputs.

Column values are in the unit their name says (``db_xy_A_mm`` in mm); ``Factor.si_scale``
converts them to SI for the physics.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np
import pandas as pd

from evotol.errors import EvotolError, ValidationError

#: columns the evaluation adds besides the evaluator's objectives
FEASIBLE, ERROR, ENTRY, SOURCE = "feasible", "error", "entry", "source"


@dataclass(frozen=True)
class Factor:
    """One design variable of a study.

    name: column name in the entries table; says its unit when not SI (``"db_xy_A_mm"``).
    levels: the discrete levels (full factorial / random subset); empty for a continuous factor.
    low, high: the continuous range (Latin hypercube, NSGA-II); defaults to the levels' span.
    log: sample and draw on a log scale (tolerances spanning decades).
    label: axis label for reports (``"Δb_xy A (mm)"``); defaults to ``name``.
    si_scale: SI value = column value * si_scale (1e-3 for mm, pi/180 for deg).
    group: family used by reports and findings (``"radial clearance"``, ``"link length"``).
    """

    name: str
    levels: tuple[float, ...] = ()
    low: float | None = None
    high: float | None = None
    log: bool = False
    label: str = ""
    si_scale: float = 1.0
    group: str = ""

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise ValidationError("Factor.name", self.name, "a Python identifier (it becomes a query column)")
        levels = tuple(float(v) for v in self.levels)
        object.__setattr__(self, "levels", levels)
        if levels:
            if len(set(levels)) != len(levels) or not all(np.isfinite(levels)):
                raise ValidationError(f"Factor({self.name!r}).levels", levels, "distinct finite values")
            object.__setattr__(self, "levels", tuple(sorted(levels)))
            if self.low is None:
                object.__setattr__(self, "low", min(levels))
            if self.high is None:
                object.__setattr__(self, "high", max(levels))
        if self.low is None or self.high is None:
            raise ValidationError(f"Factor({self.name!r})", (self.low, self.high), "levels or a [low, high] range")
        lo, hi = float(self.low), float(self.high)
        object.__setattr__(self, "low", lo)
        object.__setattr__(self, "high", hi)
        if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
            raise ValidationError(f"Factor({self.name!r}) range", (lo, hi), "finite low <= high")
        if self.log and lo <= 0:
            raise ValidationError(f"Factor({self.name!r}).low", lo, "a positive value on a log-scaled factor")
        if not (self.si_scale > 0):
            raise ValidationError(f"Factor({self.name!r}).si_scale", self.si_scale, "a positive number")
        if not self.label:
            object.__setattr__(self, "label", self.name)

    @property
    def is_discrete(self) -> bool:
        return bool(self.levels)

    def to_unit(self, u: np.ndarray) -> np.ndarray:
        """Map u in [0, 1] to the factor's range (log-uniform when ``log``); continuous."""
        u = np.asarray(u, dtype=float)
        if self.log:
            a, b = math.log10(self.low), math.log10(self.high)
            return 10.0 ** (a + u * (b - a))
        return self.low + u * (self.high - self.low)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["levels"] = list(self.levels)
        return d

    @classmethod
    def from_dict(cls, d: Mapping) -> "Factor":
        return cls(**{**d, "levels": tuple(d.get("levels", ()))})


def _check_factors(factors: Sequence[Factor]) -> tuple[Factor, ...]:
    factors = tuple(factors)
    if not factors or not all(isinstance(f, Factor) for f in factors):
        raise ValidationError("factors", factors, "a non-empty sequence of Factor")
    names = [f.name for f in factors]
    if len(set(names)) != len(names):
        raise ValidationError("factor names", names, "unique names")
    reserved = {FEASIBLE, ERROR, ENTRY, SOURCE}
    if reserved & set(names):
        raise ValidationError("factor names", sorted(reserved & set(names)), f"names other than {sorted(reserved)}")
    return factors


def _attach(df: pd.DataFrame, factors: Sequence[Factor], design: str, **extra) -> pd.DataFrame:
    df.attrs["evotol"] = {"factors": [f.to_dict() for f in factors], "design": design, **extra}
    return df


def factors_of(df: pd.DataFrame) -> tuple[Factor, ...]:
    """The factors stored with an entries table (empty when it carries none, e.g. a plain CSV)."""
    meta = df.attrs.get("evotol", {})
    return tuple(Factor.from_dict(d) for d in meta.get("factors", ()))


# --- designs ---------------------------------------------------------------------------------
def n_factorial(factors: Sequence[Factor]) -> int:
    """Number of entries of the full factorial (product of the level counts)."""
    factors = _check_factors(factors)
    missing = [f.name for f in factors if not f.is_discrete]
    if missing:
        raise ValidationError("factors without levels", missing, "levels on every factor of a factorial design")
    return int(np.prod([len(f.levels) for f in factors], dtype=np.int64))


def factorial_entries(factors: Sequence[Factor], ids) -> pd.DataFrame:
    """Entries of the full factorial with the given ids (mixed radix, last factor fastest)."""
    factors = _check_factors(factors)
    total = n_factorial(factors)
    ids = np.asarray(ids, dtype=np.int64)
    if ids.size and (ids.min() < 0 or ids.max() >= total):
        raise ValidationError("entry ids", (int(ids.min()), int(ids.max())), f"ids in [0, {total - 1}]")
    cols, rest = {}, ids.copy()
    for f in reversed(factors):
        k = len(f.levels)
        cols[f.name] = np.asarray(f.levels)[rest % k]
        rest //= k
    df = pd.DataFrame({ENTRY: ids, **{f.name: cols[f.name] for f in factors}})
    return df


def full_factorial(factors: Sequence[Factor]) -> pd.DataFrame:
    """All combinations of the factors' levels (Deng 2012 Sec. VII.1.2: 4^5 * 2^5 = 32 768)."""
    factors = _check_factors(factors)
    df = factorial_entries(factors, np.arange(n_factorial(factors)))
    return _attach(df, factors, "full factorial")


def random_subset(factors: Sequence[Factor], n: int, seed: int = 0) -> pd.DataFrame:
    """``n`` distinct entries of the full factorial drawn uniformly without replacement.

    The thesis plots "1000 entries" of its 32 768-entry factorial (Fig. VII.2); the subset is
    reproducible from ``seed`` and its ids are the factorial ids, so it can be joined with (or
    read out of) an evaluated full factorial.
    """
    factors = _check_factors(factors)
    total = n_factorial(factors)
    if not (isinstance(n, (int, np.integer)) and 1 <= n <= total):
        raise ValidationError("random_subset n", n, f"an integer in [1, {total}]")
    ids = np.sort(np.random.default_rng(seed).choice(total, size=int(n), replace=False))
    return _attach(factorial_entries(factors, ids), factors, "random subset", n=int(n), seed=seed)


def latin_hypercube(factors: Sequence[Factor], n: int, seed: int = 0) -> pd.DataFrame:
    """``n`` Latin-hypercube entries (scipy.stats.qmc) over the factors' ranges.

    Continuous factors are sampled uniformly in their range (log-uniformly when ``log``);
    discrete factors take ``levels[floor(u * n_levels)]``, i.e. each level in equal share.
    """
    from scipy.stats import qmc

    factors = _check_factors(factors)
    if not (isinstance(n, (int, np.integer)) and n >= 1):
        raise ValidationError("latin_hypercube n", n, "a positive integer")
    u = qmc.LatinHypercube(d=len(factors), seed=seed).random(int(n))
    cols = {}
    for j, f in enumerate(factors):
        if f.is_discrete:
            k = len(f.levels)
            cols[f.name] = np.asarray(f.levels)[np.minimum((u[:, j] * k).astype(int), k - 1)]
        else:
            cols[f.name] = f.to_unit(u[:, j])
    df = pd.DataFrame({ENTRY: np.arange(int(n), dtype=np.int64), **cols})
    return _attach(df, factors, "latin hypercube", n=int(n), seed=seed)


# --- evaluation ------------------------------------------------------------------------------
Evaluator = Callable[[pd.DataFrame], pd.DataFrame]


def _evaluate_chunk(evaluator: Evaluator, inputs: pd.DataFrame) -> pd.DataFrame:
    """Run the evaluator on one chunk; isolate entries that raise an EvotolError.

    Returns the evaluator's output columns plus ``feasible`` and ``error`` (the message of an
    entry that could not be evaluated, e.g. a pose out of reach; its objectives are NaN and
    ``feasible`` is False -- the failure is recorded, never silent).
    """
    try:
        out = _as_frame(evaluator(inputs), len(inputs))
        out[ERROR] = ""
    except EvotolError:
        if len(inputs) == 1:
            raise
        rows = []
        for i in range(len(inputs)):
            try:
                r = _as_frame(evaluator(inputs.iloc[i:i + 1]), 1)
                r[ERROR] = ""
            except EvotolError as exc:
                r = pd.DataFrame({ERROR: [f"{type(exc).__name__}: {exc}"]})
            rows.append(r)
        out = pd.concat(rows, ignore_index=True)
    out.index = inputs.index
    objectives = [c for c in out.columns if c not in (FEASIBLE, ERROR)]
    finite = np.all(np.isfinite(out[objectives].to_numpy(dtype=float)), axis=1) if objectives else np.ones(len(out), bool)
    if FEASIBLE in out:
        out[FEASIBLE] = out[FEASIBLE].fillna(False).astype(bool) & finite
    else:
        out[FEASIBLE] = finite & (out[ERROR] == "")
    return out


def _as_frame(out, n: int) -> pd.DataFrame:
    if isinstance(out, Mapping):
        out = pd.DataFrame({k: np.asarray(v) for k, v in out.items()})
    if not isinstance(out, pd.DataFrame) or len(out) != n:
        raise ValidationError("evaluator output", type(out).__name__, f"a DataFrame (or dict of arrays) with {n} rows")
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
    """What :func:`evaluate` did: chunks evaluated now, chunks reused from the store, time."""

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

    entries: a DataFrame from :func:`full_factorial` & co. (any columns; all go to the evaluator).
    evaluator: picklable ``DataFrame -> DataFrame`` computing one chunk in one vectorised call;
        an optional ``cache_key`` attribute/method identifies its settings for resuming.
    store: folder for finished chunks (``chunk_00012.parquet``) and a manifest; on a later call
        with the same entries and evaluator only the missing chunks run (resume after an
        interruption); a store holding another study's chunks is cleared first.
    chunk_size: entries per chunk (default: about 8 chunks per worker, at most 2048).
    workers: local processes (default: all cores; 1 = in this process, no pickling).
    scheduler: address of a Dask scheduler (``"tcp://host:8786"``); chunks then run on that
        cluster (dask.distributed) instead of local processes.
    progress: show a tqdm bar counting entries done.
    log: an :class:`EvaluationLog` to fill (which chunks ran, which were resumed, time, backend).
    """
    from tqdm.auto import tqdm

    if not isinstance(entries, pd.DataFrame) or len(entries) == 0:
        raise ValidationError("entries", type(entries).__name__, "a non-empty DataFrame")
    if not callable(evaluator):
        raise ValidationError("evaluator", evaluator, "a callable DataFrame -> DataFrame")
    t0 = time.perf_counter()
    n = len(entries)
    workers = int(workers) if workers is not None else (os.cpu_count() or 1)
    if workers < 1:
        raise ValidationError("workers", workers, "a positive integer")
    if chunk_size is None:
        chunk_size = max(1, min(2048, math.ceil(n / (8 * workers))))
    if not (isinstance(chunk_size, (int, np.integer)) and chunk_size >= 1):
        raise ValidationError("chunk_size", chunk_size, "a positive integer")
    entries = entries.reset_index(drop=True)
    bounds = [(s, min(s + chunk_size, n)) for s in range(0, n, chunk_size)]
    log = log if log is not None else EvaluationLog()
    log.n_entries, log.n_chunks = n, len(bounds)

    results: dict[int, pd.DataFrame] = {}
    store_path = Path(store) if store is not None else None
    if store_path is not None:
        results = _open_store(store_path, _fingerprint(entries, evaluator), n, chunk_size)
        log.chunks_resumed = sorted(results)
    todo = [i for i in range(len(bounds)) if i not in results]

    def _done(i: int, out: pd.DataFrame) -> None:
        results[i] = out
        log.chunks_evaluated.append(i)
        if store_path is not None:
            tmp = store_path / f".chunk_{i:05d}.parquet.tmp"
            out.to_parquet(tmp)
            os.replace(tmp, store_path / f"chunk_{i:05d}.parquet")
        bar.update(len(out))

    initial = sum(len(r) for r in results.values())
    with tqdm(total=n, initial=initial, unit="entry", desc=description, disable=not progress,
              dynamic_ncols=True, mininterval=0.5) as bar:
        if not todo:
            log.backend = "store"
        elif scheduler is not None:
            log.backend = f"dask {scheduler}"
            _run_dask(scheduler, evaluator, entries, bounds, todo, _done)
        elif workers == 1 or len(todo) == 1:
            log.backend = "in-process"
            for i in todo:
                s, e = bounds[i]
                _done(i, _evaluate_chunk(evaluator, entries.iloc[s:e]))
        else:
            log.backend = f"{min(workers, len(todo))} local processes"
            _run_processes(min(workers, len(todo)), evaluator, entries, bounds, todo, _done)

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


def _open_store(path: Path, key: str, n: int, chunk_size: int) -> dict[int, pd.DataFrame]:
    path.mkdir(parents=True, exist_ok=True)
    manifest = path / "manifest.json"
    meta = {"key": key, "n_entries": n, "chunk_size": int(chunk_size)}
    if manifest.exists():
        try:
            old = json.loads(manifest.read_text())
        except (OSError, ValueError):
            old = {}
        if old == meta:
            found = {}
            for f in sorted(path.glob("chunk_*.parquet")):
                try:
                    found[int(f.stem.split("_")[1])] = pd.read_parquet(f)
                except (OSError, ValueError):     # a chunk cut short by a kill: evaluate again
                    f.unlink(missing_ok=True)
            return found
    # another study (or other settings) used this folder: its chunks do not belong to us
    for f in list(path.glob("chunk_*.parquet")) + list(path.glob(".chunk_*.tmp")):
        f.unlink()
    manifest.write_text(json.dumps(meta))
    return {}


def _run_processes(workers, evaluator, entries, bounds, todo, done) -> None:
    pool = ProcessPoolExecutor(max_workers=workers)
    pending = {pool.submit(_evaluate_chunk, evaluator, entries.iloc[bounds[i][0]:bounds[i][1]]): i for i in todo}
    try:
        while pending:
            finished, _ = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                done(pending.pop(fut), fut.result())
    except BaseException:
        # interrupted (Ctrl-C) or a chunk failed: the finished chunks are saved; stop the running
        # ones now instead of waiting for them (they are evaluated again on resume)
        for fut in pending:
            fut.cancel()
        for proc in list(getattr(pool, "_processes", {}).values()):
            proc.terminate()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


def _run_dask(scheduler, evaluator, entries, bounds, todo, done) -> None:
    try:
        from distributed import Client, as_completed
    except ImportError as exc:   # pragma: no cover - dask is an optional dependency
        raise ValidationError("scheduler", scheduler, "dask[distributed] installed (pip install evotol[dask])") from exc
    client = Client(scheduler, set_as_default=False)
    try:
        ev = client.scatter(evaluator, broadcast=True)
        futures = {client.submit(_evaluate_chunk, ev, entries.iloc[bounds[i][0]:bounds[i][1]], pure=False): i
                   for i in todo}
        try:
            for fut in as_completed(list(futures), loop=client.loop):
                done(futures[fut], fut.result())
        except BaseException:
            client.cancel(list(futures))
            raise
    finally:
        client.close()


# --- storage ---------------------------------------------------------------------------------
def save_entries(df: pd.DataFrame, stem: str | Path) -> dict[str, Path]:
    """Write ``stem.parquet`` (with the factor metadata) and ``stem.csv``; returns both paths."""
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    pq, csv = stem.with_suffix(".parquet"), stem.with_suffix(".csv")
    df.to_parquet(pq, index=False)
    df.to_csv(csv, index=False)
    return {"parquet": pq, "csv": csv}


def load_entries(path: str | Path) -> pd.DataFrame:
    """Read entries from Parquet (with metadata) or CSV."""
    path = Path(path)
    if not path.exists():
        raise ValidationError("entries file", str(path), "an existing .parquet or .csv file")
    if path.suffix.lower() in (".parquet", ".pq"):
        return pd.read_parquet(path)
    if path.suffix.lower() == ".csv":
        df = pd.read_csv(path)
        if ERROR in df:
            df[ERROR] = df[ERROR].astype(object).where(df[ERROR].notna(), "").astype(str)
        return df
    raise ValidationError("entries file", str(path), "a .parquet or .csv file")


# --- NSGA-II beyond the levels ---------------------------------------------------------------
@dataclass(frozen=True)
class Objective:
    """An objective column and whether it is minimised (``sense=+1``) or maximised (``-1``)."""

    column: str
    sense: int = 1
    log: bool = False     # compare/normalise in log10 (values spanning decades)

    def __post_init__(self):
        if self.sense not in (1, -1):
            raise ValidationError(f"Objective({self.column!r}).sense", self.sense, "+1 (minimise) or -1 (maximise)")


def knee_points(F: np.ndarray, log: Sequence[bool] | None = None) -> np.ndarray:
    """Indices of the knee points of a Pareto front ``F`` (n, m), all objectives minimised.

    Two definitions, both returned (deduplicated): the entry nearest to the ideal point after
    normalising every objective to [0, 1] over the front (log10 first where ``log``), and the
    high trade-off points of pymoo's ``HighTradeoffPoints`` (Rachmawati & Srinivasan 2009).
    """
    F = np.asarray(F, dtype=float)
    if F.ndim != 2 or len(F) == 0:
        return np.zeros(0, dtype=int)
    G = F.copy()
    for j, lg in enumerate(log or [False] * F.shape[1]):
        if lg:
            G[:, j] = np.log10(np.maximum(G[:, j], 1e-300))
    span = G.max(0) - G.min(0)
    N = (G - G.min(0)) / np.where(span > 0, span, 1.0)
    knees = {int(np.argmin(np.linalg.norm(N, axis=1)))}
    if len(F) >= 4:
        try:
            from pymoo.mcdm.high_tradeoff import HighTradeoffPoints

            ht = HighTradeoffPoints().do(N)
            if ht is not None:
                knees.update(int(i) for i in np.atleast_1d(ht))
        except (ValueError, IndexError, np.linalg.LinAlgError):   # degenerate fronts
            pass
    return np.array(sorted(knees), dtype=int)


def nsga2(factors: Sequence[Factor], evaluator: Evaluator, objectives: Sequence[Objective], *,
          pop_size: int = 64, n_gen: int = 40, seed: int = 0, constraint: str | None = None,
          initial: pd.DataFrame | None = None, progress: bool = False, workers: int = 1,
          scheduler: str | None = None) -> pd.DataFrame:
    """NSGA-II (pymoo) on the factors' continuous ranges; returns the final Pareto entries.

    Decision variables are the factors in [0, 1] mapped by :meth:`Factor.to_unit` (log-uniform
    where ``log``: a tolerance from 1e-4 to 1e-1 mm is searched per decade, not per mm). Each
    generation's whole population is one evaluator call (``workers`` > 1 or ``scheduler``: split
    into one chunk per worker, run by :func:`evaluate`). ``constraint`` is a column of the
    evaluator output that must be <= 0 for a feasible entry (besides ``feasible``). ``initial``
    seeds the population with known entries (e.g. the best grid entries).

    Returns a DataFrame of the non-dominated feasible entries with ``source = "NSGA-II"`` and a
    boolean ``knee`` column (:func:`knee_points`), sorted by the first objective.
    """
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.problem import Problem
    from pymoo.optimize import minimize
    from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

    factors = _check_factors(factors)
    objectives = tuple(objectives)
    if not objectives:
        raise ValidationError("objectives", objectives, "at least one Objective")
    seen: list[pd.DataFrame] = []

    def to_frame(U: np.ndarray) -> pd.DataFrame:
        return pd.DataFrame({f.name: f.to_unit(U[:, j]) for j, f in enumerate(factors)})

    class _DesignProblem(Problem):
        def __init__(self):
            super().__init__(n_var=len(factors), n_obj=len(objectives),
                             n_ieq_constr=1, xl=0.0, xu=1.0)

        def _evaluate(self, U, out, *args, **kwargs):
            X = to_frame(U)
            if workers > 1 or scheduler is not None:
                Y = evaluate(X, evaluator, workers=workers, scheduler=scheduler, progress=False,
                             chunk_size=max(1, math.ceil(len(X) / max(workers, 1))))
                Y = Y.drop(columns=list(X.columns))
            else:
                Y = _evaluate_chunk(evaluator, X)
            seen.append(pd.concat([X, Y], axis=1))
            F = np.column_stack([o.sense * Y[o.column].to_numpy(dtype=float) for o in objectives])
            bad = ~Y[FEASIBLE].to_numpy(bool)
            F[bad] = 0.0     # ranked by the constraint violation below, never by F
            G = np.where(bad, 1.0, -1.0)
            if constraint is not None:
                G = np.maximum(G, Y[constraint].to_numpy(dtype=float))
            out["F"], out["G"] = F, G[:, None]

    kw = {}
    if initial is not None and len(initial):
        U0 = np.column_stack([_from_unit(f, initial[f.name].to_numpy(float)) for f in factors])
        rng = np.random.default_rng(seed)
        fill = rng.random((max(0, pop_size - len(U0)), len(factors)))
        kw["sampling"] = np.vstack([U0[:pop_size], fill])
    algo = NSGA2(pop_size=pop_size, **kw)
    minimize(_DesignProblem(), algo, ("n_gen", int(n_gen)), seed=seed, verbose=progress)
    allx = pd.concat(seen, ignore_index=True)
    ok = allx[allx[FEASIBLE]].reset_index(drop=True)
    if constraint is not None:
        ok = ok[ok[constraint] <= 0].reset_index(drop=True)
    if ok.empty:
        raise EvotolError("NSGA-II found no feasible entry")
    F = np.column_stack([o.sense * ok[o.column].to_numpy(float) for o in objectives])
    front = NonDominatedSorting().do(F, only_non_dominated_front=True)
    # every entry NSGA-II evaluated is a candidate: the archive's front is never worse than the
    # final population's
    pareto = ok.iloc[front].drop_duplicates(subset=[f.name for f in factors]).reset_index(drop=True)
    Fp = np.column_stack([o.sense * pareto[o.column].to_numpy(float) for o in objectives])
    knee = np.zeros(len(pareto), bool)
    knee[knee_points(Fp, [o.log for o in objectives])] = True
    pareto[SOURCE] = "NSGA-II"
    pareto["knee"] = knee
    pareto = pareto.sort_values(objectives[0].column, ascending=objectives[0].sense > 0).reset_index(drop=True)
    pareto.attrs["evotol"] = {"factors": [f.to_dict() for f in factors], "design": "NSGA-II",
                              "pop_size": pop_size, "n_gen": n_gen, "seed": seed,
                              "n_evaluations": int(len(allx))}
    return pareto


def _from_unit(f: Factor, x: np.ndarray) -> np.ndarray:
    x = np.clip(np.asarray(x, dtype=float), f.low, f.high)
    if f.high == f.low:
        return np.zeros_like(x)
    if f.log:
        return (np.log10(x) - math.log10(f.low)) / (math.log10(f.high) - math.log10(f.low))
    return (x - f.low) / (f.high - f.low)

"""Issue 42: a lost Dask scheduler (docs/reliability.md) -- killed in the middle of a design
evaluation, or not answering at the start -- ends in one line naming its address and the chunks a
rerun resumes; the chunks finished before are kept, and the rerun's numbers equal an uninterrupted
run's and ``sin(x) * exp(x / 50)`` computed here. A real ``distributed.LocalCluster`` (in this
process, ``processes=False``) whose scheduler is closed, and a scheduler in a process of its own that
is SIGKILLed; skipped without dask.distributed.
"""
from __future__ import annotations

import dataclasses
import json
import logging
import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from evotol import design as doe
from evotol._runtime.executor import ChunkStore
from evotol._runtime.executor.backends import SCHEDULER_ENV
from evotol.errors import SchedulerLost
from evotol.reporting.html import Report
from evotol.studies import StudyResult
from tests.test_study_outputs import _run

distributed = pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[1]
N, SIZE = 40, 4                         # 10 chunks of 4 entries
X = np.linspace(0.0, 3.0, N)
_ORIGINAL_SAVE = ChunkStore.save


class _Wave:
    """y = sin(x) exp(x/50): float work whose bits a different chunking or order would not change."""
    cache_key = "sin(x)*exp(x/50)"

    def __call__(self, entries: pd.DataFrame) -> pd.DataFrame:
        x = entries["x"].to_numpy()
        return pd.DataFrame({"y": np.sin(x) * np.exp(x / 50)})


def _expected() -> np.ndarray:
    return np.array([np.sin(x) * np.exp(x / 50) for x in X])      # entry by entry, not by evotol


@pytest.fixture
def cluster():
    # the scheduler's and worker's own log lines come from this process only because the test runs
    # them here; a real scheduler logs in its own process. The client's lines (our side) stay on.
    quiet = [logging.getLogger(n) for n in ("distributed.scheduler", "distributed.worker", "distributed.core",
                                             "distributed.worker.state_machine", "distributed.comm")]
    levels = [q.level for q in quiet]
    for q in quiet:
        q.setLevel(logging.CRITICAL)
    import dask

    # a worker whose scheduler is gone tries to reach it for the connect timeout before it closes
    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}), \
            distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp",
                                     host="127.0.0.1", dashboard_address=None) as c:
        yield c
    for q, level in zip(quiet, levels):
        q.setLevel(level)


#: a scheduler and one worker in one process of their own, printing the scheduler's address
REMOTE = """
import asyncio
from distributed import Scheduler, Worker

async def main():
    async with Scheduler(host="127.0.0.1", port=0, dashboard_address=None) as s, Worker(s.address, nthreads=1):
        print(s.address, flush=True)
        await s.finished()

asyncio.run(main())
"""


@pytest.fixture
def remote():
    """A scheduler (and its worker) in another process, as on a cluster; SIGKILLed by the test."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}           # the worker unpickles tests.test_faults_dask._Wave
    proc = subprocess.Popen([sys.executable, "-c", REMOTE], cwd=ROOT, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True)
    try:
        proc.address = proc.stdout.readline().strip()
        yield proc
    finally:
        proc.kill()
        proc.wait()


def _lose_scheduler_after(monkeypatch, lose, k: int) -> list:
    """Lose the scheduler (``lose()``) as soon as the k-th chunk is saved (chunk written, then lost)."""
    saved, save = [], ChunkStore.save

    def save_then_lose(self, index, chunk):
        save(self, index, chunk)
        saved.append(index)
        if len(saved) == k:
            lose()

    monkeypatch.setattr(ChunkStore, "save", save_then_lose)
    return saved


def _free_address() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp://127.0.0.1:{s.getsockname()[1]}"


def test_a_lost_scheduler_keeps_its_chunks_and_the_rerun_resumes_them(tmp_path, monkeypatch, cluster):
    E = pd.DataFrame({"x": X})
    store = tmp_path / "store"
    saved = _lose_scheduler_after(monkeypatch, lambda: cluster.sync(cluster.scheduler.close), 3)
    address = cluster.scheduler_address
    with pytest.raises(SchedulerLost) as lost:
        doe.evaluate(E, _Wave(), store=store, chunk_size=SIZE, scheduler=address, progress=False)
    n = lost.value.resumable
    message = str(lost.value)
    assert message.count("\n") == 0 and f"the Dask scheduler at {address} was lost" in message, message
    assert message.endswith(f"a rerun resumes {n} chunks") and str(store) in message, message
    manifest = json.loads((store / "manifest.json").read_text(encoding="utf-8"))
    on_disk = sorted(int(p.stem.split("_")[1]) for p in store.glob("chunk_*.parquet"))
    assert n == len(saved) >= 3 and on_disk == sorted(saved) == sorted(map(int, manifest["chunks"])), (n, saved)
    monkeypatch.undo()
    log = doe.EvaluationLog()
    again = doe.evaluate(E, _Wave(), store=store, chunk_size=SIZE, workers=1, progress=False, log=log)
    assert log.chunks_resumed == on_disk and sorted(log.chunks_evaluated) == sorted(set(range(10)) - set(on_disk))
    whole = doe.evaluate(E, _Wave(), store=tmp_path / "whole", chunk_size=SIZE, workers=1, progress=False)
    assert again.equals(whole)                                       # bit for bit, every column
    assert np.array_equal(again["y"].to_numpy(), _expected())


def test_a_scheduler_that_does_not_answer_at_the_start(tmp_path):
    """Nothing listens at the address: one line within distributed's connect timeout (set to 1 s
    here), naming the chunks an earlier run left verified (7 of 10 here)."""
    import dask

    E = pd.DataFrame({"x": X})
    store = tmp_path / "store"
    doe.evaluate(E, _Wave(), store=store, chunk_size=SIZE, workers=1, progress=False)
    for i in (2, 5, 9):
        (store / f"chunk_{i:05d}.parquet").unlink()
    address = _free_address()
    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        with pytest.raises(SchedulerLost, match="no answer at the start") as lost:
            doe.evaluate(E, _Wave(), store=store, chunk_size=SIZE, scheduler=address, progress=False)
    assert lost.value.resumable == 7 and str(lost.value).endswith("a rerun resumes 7 chunks")
    assert f"the Dask scheduler at {address} was lost" in str(lost.value)


def test_evotol_reproduce_says_it_in_one_line_and_the_rerun_is_identical(tmp_path, capfd, monkeypatch, remote):
    """`evotol reproduce NAME --scheduler ADDR` with the scheduler's process SIGKILLed after 4
    chunks: exit 3, one line, no traceback (distributed's client logs its failed reconnection with
    tracebacks unless evotol drops them); the rerun without a scheduler resumes those chunks and writes the JSON an
    uninterrupted run writes. ``capfd``: distributed's log handlers write to file descriptor 2."""
    import evotol.studies as studies
    from evotol._runtime.executor import scheduler_of

    def compute(config):
        log = doe.EvaluationLog()
        df = doe.evaluate(pd.DataFrame({"x": X}), _Wave(), store=f"{config['out_dir']}/wave_store", chunk_size=SIZE,
                          workers=1, scheduler=scheduler_of(config["scheduler"]), progress=False, log=log)
        return StudyResult({"y": df["y"].tolist(), "resumed": len(log.chunks_resumed), "seconds": 0.0})

    real = studies.get("deng2012-tolsynth")           # a seed study's name and config, a light compute
    fake = dataclasses.replace(real, compute=compute, render=lambda result: Report("wave", "a page"))
    monkeypatch.setattr(studies, "get", lambda name: fake)
    monkeypatch.setattr(studies, "available", lambda: {fake.name: fake})
    monkeypatch.delenv(SCHEDULER_ENV, raising=False)   # `reproduce --scheduler` sets it; restored after
    _lose_scheduler_after(monkeypatch, lambda: (remote.send_signal(signal.SIGKILL), remote.wait()), 4)
    out, address = tmp_path / "out", remote.address
    said = logging.Handler(logging.WARNING)                  # what distributed's client logs in this process
    said.emit = lambda record: lines.append(record)
    lines: list = []
    logging.getLogger("distributed.client").addHandler(said)
    try:
        code, err = _run(["reproduce", fake.name, "-q", "--scheduler", address, "--out", str(out)], capfd)
    finally:
        logging.getLogger("distributed.client").removeHandler(said)
    assert not lines, [r.getMessage() or repr(r.exc_info) for r in lines]
    assert code == 3 and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert err.startswith(f"evotol: error: the Dask scheduler at {address} was lost (the connection closed after")
    n = int(err.split("a rerun resumes ")[1].split()[0])
    assert n == len(list((out / "wave_store").glob("chunk_*.parquet"))) >= 4 and not (out / f"{fake.name}.lock").exists()
    monkeypatch.setattr(ChunkStore, "save", _ORIGINAL_SAVE)
    monkeypatch.delenv(SCHEDULER_ENV, raising=False)
    assert _run(["reproduce", fake.name, "-q", "--out", str(out)], capfd)[0] == 0
    assert _run(["reproduce", fake.name, "-q", "--out", str(tmp_path / "whole")], capfd)[0] == 0
    rerun = json.loads((out / f"{fake.name}.json").read_text(encoding="utf-8"))
    whole = json.loads((tmp_path / "whole" / f"{fake.name}.json").read_text(encoding="utf-8"))
    assert rerun["resumed"] == n and whole["resumed"] == 0
    assert {k: v for k, v in rerun.items() if k != "resumed"} == {k: v for k, v in whole.items() if k != "resumed"}
    assert np.array_equal(np.array(rerun["y"]), _expected())



def test_reproduce_with_a_scheduler_leaves_the_environment_as_it_found_it(monkeypatch, tmp_path):
    """`evotol reproduce --scheduler ADDR` sets EVOTOL_DASK_SCHEDULER for its own studies only: a second command
    in the same process once connected to the first one's (closed) scheduler -- six study tests failed so when
    a test of this file ran first in their worker."""
    import evotol.cli.argument_types as argument_types
    from evotol.cli import main, scheduler_in_environment

    seen = []
    monkeypatch.setattr(argument_types, "check_scheduler_answers", lambda address: seen.append(address))
    monkeypatch.delenv(SCHEDULER_ENV, raising=False)
    assert main(["reproduce", "drake1999-motor", "--out", str(tmp_path), "--scheduler", "tcp://127.0.0.1:9", "-q"]) == 0
    assert seen == ["tcp://127.0.0.1:9"] and SCHEDULER_ENV not in os.environ
    monkeypatch.setenv(SCHEDULER_ENV, "tcp://elsewhere:8786")          # a user's own setting comes back
    with scheduler_in_environment("tcp://127.0.0.1:9"):
        assert os.environ[SCHEDULER_ENV] == "tcp://127.0.0.1:9"
    assert os.environ[SCHEDULER_ENV] == "tcp://elsewhere:8786"

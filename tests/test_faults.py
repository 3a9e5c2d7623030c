"""Issue 42: nothing lost, nothing corrupt, nothing outside ``--out`` (docs/reliability.md).

Each test plays one fault -- a name that is a path, a kill at the k-th file of a run, SIGKILL of a
writer, two writers at once, a damaged chunk, a full disk, a read-only folder, a cache numba cannot
write, a killed parent of pool workers -- and checks what is left in the folder against what an
uninterrupted run writes (computed here, in the test) or against the earlier files' bytes.
"""
from __future__ import annotations

import errno
import json
import logging
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import evotol._runtime.atomic_files as atomic
from evotol import design as doe
from evotol._runtime.atomic_files import pid_alive
from evotol._runtime.output_paths import path_inside
from evotol._runtime.output_set import claim_outputs, read_manifest
from evotol.errors import ValidationError, WriteFailed
from evotol.reporting.html import Report
from evotol.studies import StudyResult, write_outputs
from tests.fast_study import fast_study
from tests.test_study_outputs import _run

ROOT = Path(__file__).resolve().parents[1]
ESCAPES = ["../escaped", "/tmp/x", "a/b", "..", "CON", "nul.txt", "", "a\\b", "tab\there"]


def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _no_seconds(obj):
    """A summary without its wall-clock times (the only values two identical runs may differ in)."""
    if isinstance(obj, dict):
        return {k: _no_seconds(v) for k, v in obj.items() if k != "seconds"}
    if isinstance(obj, list):
        return [_no_seconds(v) for v in obj]
    return obj


# --- 1. names are never paths -------------------------------------------------------------------

@pytest.mark.parametrize("name", ESCAPES)
def test_a_study_name_that_is_a_path_is_refused_before_any_work(tmp_path, capsys, monkeypatch, name):
    import evotol.studyfile.run as run

    monkeypatch.setattr(run, "load_problem", lambda *a, **k: pytest.fail("work started"))
    study = fast_study(tmp_path / "s", ('name = "ucr3_example"', f"name = {json.dumps(name)}"))
    out = tmp_path / "box" / "out"
    t0 = time.time() - 1
    code, err = _run(["run", str(study), "--out", str(out)], capsys)
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert err.startswith(f"evotol: error: name = {name!r}: expected a"), err
    assert _tree(tmp_path / "box") == {}
    assert not any(p.stat().st_mtime >= t0 for p in Path("/tmp").glob("x*"))   # '/tmp/x': nothing written there
    assert sorted(p.name for p in tmp_path.iterdir()) == ["box", "s"]       # nothing beside --out either


@pytest.mark.parametrize("name", ESCAPES)
def test_the_python_writer_refuses_the_same_names(tmp_path, name):
    with pytest.raises(ValidationError, match="^name = "):
        write_outputs(name, tmp_path / "out", StudyResult({"a": 1}))
    with pytest.raises(ValidationError, match="^name = "):
        with claim_outputs(tmp_path / "out", name, "test"):
            pytest.fail("claimed")
    assert _tree(tmp_path) == {}


def test_every_written_path_is_proven_inside_out(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "link").symlink_to(tmp_path)              # a link that leads out of --out
    for bad in ("../x.json", "/tmp/x.json", "link/x.json", "."):
        with pytest.raises(ValidationError, match="expected a file inside --out"):
            path_inside(out, bad)
    assert path_inside(out, "a.json") == out / "a.json"


# --- 2. atomic outputs: a kill at the k-th file ---------------------------------------------------

def _result(v: float) -> tuple[StudyResult, Report]:
    table = pd.DataFrame({"x": np.arange(500) * v, "label": ["±µ"] * 500})
    rep = Report(f"run {v}", "a page")
    return StudyResult({"value": v, "text": "±0.1 µm"}, {"entries": table}), rep


@pytest.mark.parametrize("k", range(4))
def test_a_kill_at_the_kth_file_keeps_every_file_whole(tmp_path, monkeypatch, k):
    """Files: entries .parquet, .csv, .json, .html. Killed (KeyboardInterrupt) as the k-th is about
    to be renamed into place: files before k are the new run's, from k on the old run's, byte for
    byte; no temporary file or lock is left; the rerun of the same owner is accepted and writes what
    an uninterrupted run writes."""
    out = tmp_path / "out"
    with claim_outputs(out, "s", "study file A"):
        write_outputs("s", out, *_result(1.0)[:1], report=_result(1.0)[1])
    old = _tree(out)
    ref = tmp_path / "ref"
    with claim_outputs(ref, "s", "study file A"):
        write_outputs("s", ref, *_result(2.0)[:1], report=_result(2.0)[1])
    new = _tree(ref)
    calls, replace = [], os.replace

    def dying_replace(src, dst):
        if Path(dst).name in ("s.manifest.json", "s.lock"):
            return replace(src, dst)
        calls.append(Path(dst).name)
        if len(calls) == k + 1:
            raise KeyboardInterrupt
        return replace(src, dst)

    monkeypatch.setattr(atomic.os, "replace", dying_replace)
    with pytest.raises(KeyboardInterrupt):
        with claim_outputs(out, "s", "study file A"):
            write_outputs("s", out, *_result(2.0)[:1], report=_result(2.0)[1])
    monkeypatch.setattr(atomic.os, "replace", replace)
    left = _tree(out)
    assert not [n for n in left if n.startswith(".") or n.endswith(".lock")], sorted(left)
    done = calls[:k]
    for n in left:
        if n in ("s.manifest.json",):
            continue
        assert left[n] == (new[n] if n in done else old[n]), (k, n)
    assert read_manifest(out, "s")["complete"] is False          # the folder says: a run did not finish
    with claim_outputs(out, "s", "study file A"):                 # its own owner: accepted
        write_outputs("s", out, *_result(2.0)[:1], report=_result(2.0)[1])
    again = _tree(out)
    assert {n: b for n, b in again.items() if "manifest" not in n} == {n: b for n, b in new.items() if "manifest" not in n}
    m = read_manifest(out, "s")
    assert m["complete"] and set(m["files"]) == {"s.json", "s.html", "s_entries.csv", "s_entries.parquet"}
    import hashlib
    assert all(hashlib.sha256(again[n]).hexdigest() == h for n, h in m["files"].items())


# --- 3. one writer per output set ---------------------------------------------------------------

def _child(code: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-c", textwrap.dedent(code)], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, text=True)


HOLDER = """
    import sys, time
    from pathlib import Path
    from evotol._runtime.atomic_files import atomic_path
    from evotol._runtime.output_set import claim_outputs
    with claim_outputs(Path(sys.argv[1]), "s", "study file A"):
        with atomic_path(Path(sys.argv[1]) / "s.json") as tmp:
            tmp.write_text("{\\"half\\": ", encoding="utf-8")
            print("writing", flush=True)
            time.sleep(60)
"""


def _holder(out: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-c", textwrap.dedent(HOLDER), str(out)], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "writing"
    return proc


def test_sigkill_mid_write_then_rerun_and_a_second_writer(tmp_path, capsys):
    """A writer killed with SIGKILL in the middle of NAME.json: the earlier NAME.json is intact, its
    lock is stale and its temporary file is removed by the next writer, which is recognised as the
    same owner (the old false 'written by another study' is gone); while it lived, a second writer
    was refused in one line naming its pid."""
    out = tmp_path / "out"
    with claim_outputs(out, "s", "study file A"):                  # an earlier, complete run of A
        atomic.write_text(out / "s.json", '{"good": 1}')
    proc = _holder(out)
    try:
        with pytest.raises(ValidationError, match=f"process {proc.pid} on .* holds s.lock"):
            with claim_outputs(out, "s", "study file B"):
                pytest.fail("two writers")
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    assert (out / "s.json").read_text(encoding="utf-8") == '{"good": 1}'
    assert [p.name for p in out.glob(".s.json.*.tmp*")] and (out / "s.lock").exists()   # what a kill leaves
    with pytest.raises(ValidationError, match="written by the study file A"):
        with claim_outputs(out, "s", "study file B"):          # not its files: still refused, by name
            pass
    with claim_outputs(out, "s", "study file A"):              # stale lock taken over, temp removed
        assert not list(out.glob(".s.json.*"))
    assert not (out / "s.lock").exists()


def test_two_study_files_with_one_name_at_once(tmp_path, capsys):
    """`evotol run` while another process writes the same output set: exit 2, one line, no work."""
    out = tmp_path / "out"
    proc = _holder(out)
    try:
        code, err = _run(["run", str(fast_study(tmp_path / "b", ('name = "ucr3_example"', 'name = "s"'))),
                          "--out", str(out)], capsys)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    assert code == 2 and len(err.strip().splitlines()) == 1 and f"process {proc.pid}" in err, err


def test_reproduce_refuses_a_study_files_outputs(tmp_path, capsys):
    out = tmp_path / "out"
    with claim_outputs(out, "yao2013", "study file /a/study.toml"):
        write_outputs("yao2013", out, StudyResult({"mine": 1}))
    code, err = _run(["reproduce", "yao2013", "--quick", "--out", str(out)], capsys)
    assert code == 1 and "written by the study file /a/study.toml" in err and "--force" in err, err
    assert json.loads((out / "yao2013.json").read_text(encoding="utf-8")) == {"mine": 1}


def test_reproduce_quick_over_a_full_run_is_refused_and_a_full_run_replaces_a_quick_one(tmp_path, capsys, monkeypatch):
    """`reproduce NAME --quick` over the files of NAME's full run: refused before any work, one line
    naming --out, the full run and --force, the files unchanged; with --force it replaces them. A full
    run over a quick run's files replaces them. A folder written before manifests recorded the flag is
    judged by NAME.json's ``quick``."""
    import dataclasses

    import evotol.studies as studies

    runs = []

    def compute(config):
        runs.append(config["quick"])
        return StudyResult({"quick": config["quick"], "n": 16 if config["quick"] else 32768, "seconds": 0.0})

    fake = dataclasses.replace(studies.get("yao2013"), compute=compute, render=lambda result: Report("r", "a page"))
    monkeypatch.setattr(studies, "get", lambda name: fake)
    monkeypatch.setattr(studies, "available", lambda: {fake.name: fake})
    out = tmp_path / "out"
    reproduce = ["reproduce", "yao2013", "-q", "--out", str(out)]

    def files():
        return {n: b for n, b in _tree(out).items() if n != "index.html"}      # the index is every run's

    def n_written():
        return json.loads((out / "yao2013.json").read_text(encoding="utf-8"))["n"]

    assert _run(reproduce, capsys)[0] == 0 and runs == [False] and n_written() == 32768
    full = files()
    for manifest in (True, False):                  # as written today; a folder from before the flag
        if not manifest:
            (out / "yao2013.manifest.json").unlink()
            full = files()
        code, err = _run(reproduce + ["--quick"], capsys)
        assert code == 1 and runs == [False] and files() == full, (code, err)   # no work, nothing changed
        lines = err.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in err, err
        for words in (f"--out = '{out}'", "a full run's", "--force", "--quick"):
            assert words in lines[0], (words, lines[0])
    assert _run(reproduce + ["--quick", "--force"], capsys)[0] == 0 and runs == [False, True] and n_written() == 16
    assert _run(reproduce + ["--quick"], capsys)[0] == 0 and n_written() == 16     # quick over quick
    assert _run(reproduce, capsys)[0] == 0 and runs == [False, True, True, False] and n_written() == 32768
    assert read_manifest(out, "yao2013")["quick"] is False


# --- 4. checked chunks ----------------------------------------------------------------------------

class _Square:
    cache_key = "x**2"          # the store's fingerprint (evotol.design.evaluation._fingerprint)

    def __call__(self, X: pd.DataFrame) -> pd.DataFrame:
        return pd.DataFrame({"y": X["x"].to_numpy() ** 2})


def test_a_damaged_chunk_is_evaluated_again_with_one_line(tmp_path, caplog):
    """A bit flip, a chunk swapped for another, a short chunk and a garbage chunk: each fails its
    manifest check (SHA-256, range, rows), is evaluated again with one warning, and the entries equal
    x**2 computed here; the intact chunks are reused."""
    E = pd.DataFrame({"x": np.arange(40.0)})
    kw = dict(store=tmp_path, workers=1, chunk_size=8, progress=False)
    doe.evaluate(E, _Square(), **kw)
    c = {i: tmp_path / f"chunk_{i:05d}.parquet" for i in range(5)}
    raw = bytearray(c[1].read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    c[1].write_bytes(bytes(raw))                                   # bit flip
    c[2].write_bytes(c[0].read_bytes())                            # swapped
    pd.DataFrame({"y": [4.0, 9.0]}).to_parquet(c[3])               # short, still Parquet
    c[4].write_bytes(b"PAR1 not really")                           # unreadable
    log = doe.EvaluationLog()
    with caplog.at_level(logging.WARNING, logger="evotol"):
        df = doe.evaluate(E, _Square(), log=log, **kw)
    assert np.array_equal(df["y"].to_numpy(), np.arange(40.0) ** 2)
    assert log.chunks_resumed == [0] and sorted(log.chunks_evaluated) == [1, 2, 3, 4]
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 4 and all("failed its check" in m and "evaluated again" in m for m in lines), lines
    assert all("SHA-256 differs" in m for m in lines)             # each changed file fails its checksum first
    log2 = doe.EvaluationLog()
    doe.evaluate(E, _Square(), log=log2, **kw)                     # all five verified now
    assert log2.chunks_resumed == [0, 1, 2, 3, 4]
    # a short chunk whose manifest entry was rewritten to match its checksum (an older store): the
    # row count and the entry range still catch it
    manifest = json.loads((tmp_path / "manifest.json").read_text(encoding="utf-8"))
    pd.DataFrame({"y": [4.0, 9.0]}).to_parquet(c[3])
    manifest["chunks"]["3"]["sha256"] = atomic.sha256_of(c[3])
    manifest["chunks"]["2"]["start"] = 0                              # and a range that is not chunk 2's
    (tmp_path / "manifest.json").write_text(json.dumps(manifest), encoding="utf-8")
    caplog.clear()
    log3 = doe.EvaluationLog()
    with caplog.at_level(logging.WARNING, logger="evotol"):
        df = doe.evaluate(E, _Square(), log=log3, **kw)
    assert np.array_equal(df["y"].to_numpy(), np.arange(40.0) ** 2) and sorted(log3.chunks_evaluated) == [2, 3]
    lines = sorted(r.getMessage() for r in caplog.records)
    assert "entry range 0..24 is not chunk 2's 16..24" in lines[0] and "2 rows, the manifest says 8" in lines[1], lines


def test_two_writers_of_one_chunk_store_use_their_own_temporary_names(tmp_path):
    names = {atomic.temporary_name(tmp_path / "chunk_00001.parquet") for _ in range(100)}
    assert len(names) == 100 and all(f".{os.getpid()}-" in n.name for n in names)


# --- 5. faults: a full disk, a read-only folder, an unwritable numba cache, orphaned workers ---

@pytest.mark.parametrize("code_, words", [(errno.ENOSPC, "disk full"), (errno.EROFS, "read-only file system")])
def test_a_refused_write_is_one_line_and_keeps_the_earlier_files(tmp_path, capsys, monkeypatch, code_, words):
    study = fast_study(tmp_path / "s")
    out = tmp_path / "out"
    assert _run(["run", str(study), "--out", str(out)], capsys)[0] == 0
    before = _tree(out)
    fsync = os.fsync

    def full(fd):
        raise OSError(code_, os.strerror(code_))

    monkeypatch.setattr(atomic.os, "fsync", full)                  # the data does not reach the disk
    code, err = _run(["run", str(study), "--out", str(out)], capsys)
    monkeypatch.setattr(atomic.os, "fsync", fsync)
    assert code == 3 and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert err.startswith("evotol: error: cannot write ") and words in err and "untouched" in err
    after = _tree(out)
    assert {n: b for n, b in after.items() if "manifest" not in n} == {n: b for n, b in before.items() if "manifest" not in n}
    assert not [n for n in after if n.startswith(".") or n.endswith(".lock")]
    if code_ != errno.ENOSPC:
        return
    assert _run(["run", str(study), "--out", str(out)], capsys)[0] == 0     # the same study, once the disk has room
    a = json.loads((out / "ucr3_example.json").read_text(encoding="utf-8"))
    b = json.loads(before["ucr3_example.json"])
    assert _no_seconds(a) == _no_seconds(b)


def test_write_failed_names_the_file():
    with pytest.raises(WriteFailed, match="cannot write /x/a.json: disk full"):
        raise atomic.refused(OSError(errno.ENOSPC, "No space left on device"), "/x/a.json")


NO_LOCATOR = """
    import sys
    from numba.core import caching
    caching.CacheImpl._locator_classes = {locators}
    import numpy as np
    from evotol.robots.mechanism.kinematics import serial_kernels as k
    out = np.zeros((4, 4))
    k._mul(2 * np.eye(4), np.eye(4), out)         # rigid product, last row (0, 0, 0, 1): trace 2+2+2+1
    print(type(k.sensitivity._cache).__name__, out.trace())
"""


@pytest.mark.parametrize("locators, cache", [("[]", "NullCache"), ("[caching.UserProvidedCacheLocator]", "FunctionCache")])
def test_serial_kernels_import_when_numba_cannot_cache(locators, cache):
    """No cache folder numba can write (a read-only install and home): the kernels still import and
    run, caching in a temporary folder when one can be made, else without a cache; one line says so."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"} | {"PYTHONPATH": str(ROOT)}
    r = subprocess.run([sys.executable, "-c", textwrap.dedent(NO_LOCATOR.format(locators=locators))], cwd=ROOT,
                       env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == [cache, "7.0"]
    assert r.stderr.count("[evotol] numba cannot write its cache") == 1 and "NUMBA_CACHE_DIR" in r.stderr



NO_LOCATOR_CLEARANCE = """
    from numba.core import caching
    caching.CacheImpl._locator_classes = {locators}
    from evotol.robots.clearance import newton_kernel as nk
    compiled = nk._compiled()
    print(compiled is not None and type(compiled[0]._cache).__name__)
"""


@pytest.mark.parametrize("locators, cache", [("[]", "NullCache"), ("[caching.UserProvidedCacheLocator]", "FunctionCache")])
def test_clearance_kernel_compiles_when_numba_cannot_cache(locators, cache):
    """The same for the clearance engine's Newton kernels (issue 43): compiled (cached in a temporary
    folder, else without a cache), not dropped to the NumPy iteration; one line says so."""
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "EVOTOL_NO_NUMBA")} | {"PYTHONPATH": str(ROOT)}
    r = subprocess.run([sys.executable, "-W", "error::RuntimeWarning", "-c",
                        textwrap.dedent(NO_LOCATOR_CLEARANCE.format(locators=locators))], cwd=ROOT,
                       env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == [cache]
    assert r.stderr.count("[evotol] numba cannot write its cache") == 1 and "NUMBA_CACHE_DIR" in r.stderr

POOL = """
    import os, time
    from evotol._runtime.executor import run_chunks
    def work(x):
        # one write() of under PIPE_BUF bytes: the two workers' lines cannot interleave
        # (print() writes the number and the newline separately; CI once read "\\n")
        os.write(1, f"{os.getpid()}\\n".encode())
        time.sleep(60)
    run_chunks(work, [1, 2], lambda i, r: None, workers=2)
"""


def test_pool_workers_end_with_their_killed_parent():
    proc = _child(POOL)
    workers = [int(proc.stdout.readline()) for _ in range(2)]
    assert all(pid_alive(p) for p in workers)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    t0 = time.perf_counter()
    while any(pid_alive(p) for p in workers) and time.perf_counter() - t0 < 10:
        time.sleep(0.05)
    assert not any(pid_alive(p) for p in workers), workers

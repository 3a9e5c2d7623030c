"""One writer per output set, and a manifest written last (issue 42).

An **output set** is the files one study writes into one folder: ``NAME.json``, ``NAME.html``,
tables and exports, all named from ``NAME``. :func:`claim_outputs` is held around a whole run
(``evotol run``, ``evotol reproduce``, :func:`evotol.studies.reproduce`) and, before any work:

1. checks ``NAME`` is a file name and not a path (:func:`~evotol._runtime.output_paths.check_output_name`);
2. takes the lock ``NAME.lock`` (created with ``O_CREAT | O_EXCL``, holding the pid, the host and
   the owner); a lock whose process has ended on this host is stale and taken over; a live one is a
   one-line :class:`~evotol.errors.ValidationError`. It is removed on every exit Python sees;
3. refuses another owner's files (:func:`~evotol._runtime.output_paths.check_not_overwriting`);
4. refuses a seed study's ``--quick`` run over the files of its full run (:func:`holds_full_run`;
   ``--force`` replaces them); a full run replaces a quick run's files;
5. removes temporary files left by killed writers, and records the owner in ``NAME.manifest.json``
   (``"complete": false``, keeping the earlier run's file hashes) before the first file is written,
   so that a run killed at any moment is recognised as the same owner's on the rerun.

When the block ends normally the manifest is rewritten, last, with the SHA-256 of every file the run
wrote (``"complete": true``). A file whose hash differs from the manifest's was written by a run
that did not finish.
"""
from __future__ import annotations

import json
import os
import socket
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from evotol._runtime.atomic_files import pid_alive, recording, refused, remove_stale_temporaries, write_text
from evotol._runtime.output_paths import check_not_overwriting, check_output_name, path_inside
from evotol.errors import ValidationError


def manifest_path(out, name: str) -> Path:
    """``out / NAME.manifest.json``, the output set's manifest.

    Parameters
    ----------
    out : str or Path
        The output folder.
    name : str
        The output set's name.

    Returns
    -------
    Path
        The manifest's path.
    """
    return Path(out) / f"{name}.manifest.json"


def read_manifest(out, name: str) -> dict:
    """The output set's manifest, or ``{}`` when missing or unreadable.

    Parameters
    ----------
    out : str or Path
        The output folder.
    name : str
        The output set's name.

    Returns
    -------
    dict
        ``owner``, ``complete``, ``files`` (name -> SHA-256), ``pid``, ``host``, ``started``.
    """
    try:
        data = json.loads(manifest_path(out, name).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _take_lock(lock: Path, owner: str) -> None:
    """Create ``lock`` exclusively; take over a stale one (its process ended on this host)."""
    host = socket.gethostname()
    record = json.dumps({"pid": os.getpid(), "host": host, "owner": owner, "since": time.time()})
    for _ in range(3):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            pass
        except OSError as exc:          # a read-only folder, a full disk: one line (WriteFailed)
            failed = refused(exc, lock)
            if failed is None:
                raise
            raise failed from None
        else:
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                f.write(record)
            return
        try:
            held = json.loads(lock.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            held = {}
        try:
            young = time.time() - lock.stat().st_mtime < 5
        except FileNotFoundError:       # its writer just finished
            continue
        if not held and young:          # being written this instant
            time.sleep(0.2)
            continue
        pid, where = int(held.get("pid", -1)), held.get("host")
        if not held or (where == host and pid != os.getpid() and not pid_alive(pid)):
            lock.unlink(missing_ok=True)    # stale: its writer ended (killed) on this machine
            continue
        raise ValidationError("--out", str(lock.parent),
                              f"a folder no other evotol is writing {lock.stem}'s files into: process {pid} on "
                              f"{where} ({held.get('owner')}) holds {lock.name}; wait for it, or delete "
                              f"{lock.name} if that process no longer runs") from None
    raise ValidationError("--out", str(lock.parent), f"a lock file {lock.name} that can be taken (it keeps changing)")


def holds_full_run(out, name: str, manifest: dict) -> bool:
    """Whether ``out/NAME.*`` are the files of a full (not ``--quick``) run of a seed study.

    The manifest records ``quick`` for the files it vouches for (kept through an interrupted run's
    manifest); a folder written before manifests recorded it is judged by ``NAME.json``'s
    ``quick`` key, when the study writes one. Unknown: False.

    Parameters
    ----------
    out : str or Path
        The output folder.
    name : str
        The output set's name.
    manifest : dict
        The folder's manifest for ``name`` (:func:`read_manifest`).

    Returns
    -------
    bool
        True when the files there are known to be a full run's.
    """
    if "quick" in manifest:
        return manifest["quick"] is False and bool(manifest.get("files"))
    try:
        summary = json.loads((Path(out) / f"{name}.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(summary, dict) and summary.get("quick") is False


@contextmanager
def claim_outputs(out, name: str, owner: str, *, force: bool = False, study_file=None,
                  field: str = "name", quick: bool | None = None) -> Iterator[dict]:
    """Hold the output set ``out/NAME.*`` for one run: lock, ownership, manifest (module docstring).

    Parameters
    ----------
    out : str or Path
        The output folder (created when missing).
    name : str
        The output set's name (the study's ``name``).
    owner : str
        Who writes: ``"study file /abs/path.toml"`` or ``"seed study NAME"``.
    force : bool, optional
        Overwrite another owner's files (``--force``).
    study_file : str or Path, optional
        The study file, for the overwrite check of files without a manifest (their JSON's
        ``study_file``).
    field : str, optional
        The field named when ``name`` is not a file name (default ``"name"``).
    quick : bool, optional
        A seed study's ``--quick`` flag, recorded in the manifest; a quick run over a full run's
        files (:func:`holds_full_run`) is refused unless ``force`` (default None: not a seed
        study, nothing recorded or checked).

    Yields
    ------
    dict
        The files written so far (resolved path -> SHA-256).

    Raises
    ------
    ValidationError
        ``name`` is not a file name, another live process holds the lock, the files belong to
        another owner, or a quick run would replace a full run's files.
    """
    check_output_name(name, field)
    out = Path(out)
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    lock = path_inside(out, f"{name}.lock")
    _take_lock(lock, owner)
    had_manifest = manifest_path(out, name).exists()
    written = {}
    try:
        earlier = read_manifest(out, name)
        check_not_overwriting(out, name, study_file, force, owner=owner, manifest=earlier)
        if quick and not force and holds_full_run(out, name, earlier):
            raise ValidationError("--out", str(out), f"a folder without a full run of {name}: its files there "
                                  f"({name}.json, {name}.html, ...) are a full run's, which this --quick run would "
                                  "replace; pass --force to replace them, or give another --out")
        remove_stale_temporaries(out)
        base = {"name": name, "owner": owner, "pid": os.getpid(), "host": socket.gethostname(), "started": time.time()}
        files = earlier.get("files", {}) if earlier.get("owner") == owner else {}
        kept = {"quick": earlier["quick"]} if files and "quick" in earlier else {}    # what `files` are
        write_text(manifest_path(out, name), json.dumps({**base, **kept, "complete": False, "files": files},
                                                        indent=1), record=False)
        with recording() as written:
            yield written
        root = out.resolve()
        vouched = {str(Path(p).relative_to(root)): h for p, h in sorted(written.items())
                   if Path(p).parent == root}
        mine = {"quick": bool(quick)} if quick is not None else {}
        write_text(manifest_path(out, name), json.dumps({**base, **mine, "complete": True, "finished": time.time(),
                                                         "files": vouched}, indent=1), record=False)
    except BaseException:
        if not written:        # refused before any file (bad input, ...): leave the folder as it was
            if not had_manifest:
                manifest_path(out, name).unlink(missing_ok=True)
            lock.unlink(missing_ok=True)
            if created and not any(out.iterdir()):
                out.rmdir()
        raise
    finally:
        lock.unlink(missing_ok=True)

"""Atomic output files: every output evotol writes appears whole or not at all (issue 42).

A file is written to a temporary name in its own folder (``.NAME.<pid>-<random>.tmp<suffix>``,
unique per process and per call), flushed to disk and renamed over the target with
:func:`os.replace`, which POSIX and Windows make atomic within one file system. A kill, a full disk
or an exception during the write leaves the previous file untouched; the temporary file is removed
on every exit path Python sees (an exception, Ctrl-C, ``SystemExit``), and a temporary file of a
process that was killed outright (SIGKILL) is removed by the next writer of the folder
(:func:`remove_stale_temporaries`).

Inside :func:`recording`, every file written here is recorded (path and SHA-256), so the output
set can write a manifest of the files it vouches for (:mod:`evotol._runtime.output_set`).

A refused write (``ENOSPC``, ``EROFS``, ``EACCES``, ``EDQUOT``) becomes one
:class:`~evotol.errors.WriteFailed` naming the file and the reason.
"""
from __future__ import annotations

import contextvars
import errno
import hashlib
import os
import re
import secrets
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from evotol.errors import WriteFailed

#: the files written in the current output set: {resolved path: sha256}, or None outside one
_RECORD: contextvars.ContextVar[dict | None] = contextvars.ContextVar("evotol_written_files", default=None)

_TEMP = re.compile(r"^\..+\.(\d+)-[0-9a-f]{8}\.tmp")

_REASONS = {errno.ENOSPC: "disk full", errno.EROFS: "read-only file system", errno.EACCES: "permission denied",
            errno.EPERM: "permission denied", getattr(errno, "EDQUOT", -1): "disk quota exceeded"}


def temporary_name(path: Path) -> Path:
    """A fresh temporary name beside ``path``, unique per process and call: ``.NAME.<pid>-<8 hex>.tmp<suffix>``
    (the suffix kept, so writers that choose a format by it -- openpyxl -- still accept it).

    Parameters
    ----------
    path : Path
        The file to be written.

    Returns
    -------
    Path
        A name in the same folder that no other process or call uses.
    """
    return path.with_name(f".{path.name}.{os.getpid()}-{secrets.token_hex(4)}.tmp{path.suffix}")


def _fsync_folder(folder: Path) -> None:
    """Make the rename itself durable (POSIX); a folder cannot be opened on Windows: skipped there."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def refused(exc: OSError, path) -> WriteFailed | None:
    """The one-line error for a write the system refused, or None for another ``OSError``.

    Parameters
    ----------
    exc : OSError
        The error raised by the write.
    path : str or Path
        The file being written.

    Returns
    -------
    WriteFailed or None
        Naming the file, the reason (disk full, read-only, permission, quota) and that the earlier
        file is kept.
    """
    reason = _REASONS.get(exc.errno)
    if reason is None:
        return None
    return WriteFailed(str(path), f"{reason} ({exc.strerror or exc}); the earlier file, if any, is untouched "
                                  "and no partial file is left")


def sha256_of(path) -> str:
    """The SHA-256 of a file's bytes, as 64 hex digits.

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    str
        ``hashlib.sha256(bytes).hexdigest()``.
    """
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


@contextmanager
def atomic_path(path, *, keep_existing: bool = False, record: bool = True) -> Iterator[Path]:
    """Yield a temporary path to write ``path`` through; on a normal exit it replaces ``path``.

    Parameters
    ----------
    path : str or Path
        The file to write (its folder is created).
    keep_existing : bool, optional
        Start the temporary file as a copy of ``path`` (writers that append, e.g. a workbook's
        sheets).
    record : bool, optional
        Record the file in the current output set's manifest (default True; the shared plotly.js
        bundle and chunk stores keep their own records).

    Yields
    ------
    Path
        The temporary file (same folder and suffix); the caller writes it completely.

    Raises
    ------
    WriteFailed
        The system refused the write (disk full, read-only, permission, quota).
    """
    path = Path(path)
    tmp = temporary_name(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if keep_existing and path.exists():
            tmp.write_bytes(path.read_bytes())
        yield tmp
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)       # the data is on disk before the name points at it
        finally:
            os.close(fd)
        os.replace(tmp, path)
    except OSError as exc:
        failed = refused(exc, path)
        if failed is None:
            raise
        raise failed from None
    finally:
        if tmp.exists():
            tmp.unlink(missing_ok=True)
    _fsync_folder(path.parent)
    written = _RECORD.get()
    if record and written is not None:
        written[str(path.resolve())] = sha256_of(path)


def write_text(path, text: str, *, record: bool = True) -> Path:
    """Write ``text`` as UTF-8 to ``path`` atomically (:func:`atomic_path`).

    Parameters
    ----------
    path : str or Path
        The file.
    text : str
        Its content.
    record : bool, optional
        Record it in the current output set's manifest (default True).

    Returns
    -------
    Path
        ``path``.
    """
    return write_bytes(path, text.encode("utf-8"), record=record)


def write_bytes(path, data: bytes, *, record: bool = True) -> Path:
    """Write ``data`` to ``path`` atomically (:func:`atomic_path`).

    Parameters
    ----------
    path : str or Path
        The file.
    data : bytes
        Its content.
    record : bool, optional
        Record it in the current output set's manifest (default True).

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    with atomic_path(path, record=record) as tmp:
        with open(tmp, "wb") as f:
            f.write(data)
    return path


@contextmanager
def recording() -> Iterator[dict]:
    """Record every file written by :func:`atomic_path` while the block runs.

    Yields
    ------
    dict of str to str
        Resolved path -> SHA-256, filled as files are written.
    """
    written: dict = {}
    token = _RECORD.set(written)
    try:
        yield written
    finally:
        _RECORD.reset(token)


def pid_alive(pid: int) -> bool:
    """Whether the process ``pid`` of this machine still runs (a zombie counts as ended on Linux).

    Parameters
    ----------
    pid : int
        The process id.

    Returns
    -------
    bool
        False once the process has ended.
    """
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:     # another user's process: alive
        return True
    except OSError:             # Windows: os.kill(pid, 0) is not a probe
        return True
    try:                        # a zombie (killed, parent not yet waited) has ended its work
        with open(f"/proc/{pid}/stat", encoding="utf-8") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return True


def remove_stale_temporaries(folder) -> list[Path]:
    """Remove the temporary files that a process killed outright left in ``folder`` (its pid ended).

    Parameters
    ----------
    folder : str or Path
        The output folder.

    Returns
    -------
    list of Path
        The files removed.
    """
    gone = []
    folder = Path(folder)
    if not folder.is_dir():
        return gone
    for f in folder.iterdir():
        m = _TEMP.match(f.name)
        if m and int(m.group(1)) != os.getpid() and not pid_alive(int(m.group(1))):
            f.unlink(missing_ok=True)
            gone.append(f)
    return gone

"""Check where results will go *before* any computation starts.

A run that computes for minutes and then cannot write its report loses all of it (issue 15:
``evotol run study.toml --out /proc/x`` died with a traceback after 8 s). ``run``,
``reproduce`` and ``filter --html`` call these checks at the command-line boundary, so a bad
location is a one-line :class:`~evotol.errors.ValidationError` naming the option and the path.
"""
from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

from evotol.errors import ValidationError


def _probe_writable(folder: Path, field: str, shown) -> None:
    """Create and delete a small file in ``folder``: the only test that ``os.access`` cannot fool
    (read-only mounts, /proc, ACLs)."""
    try:
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".evotol-write-test-"):
            pass
    except OSError as exc:
        raise ValidationError(field, shown, f"a writable folder ({exc.strerror or exc})") from None


def output_folder(path, field: str = "--out", shown=None) -> Path:
    """Make sure ``path`` is a folder evotol can write into; create it (and parents) if missing.

    Raises ValidationError naming ``field`` and ``path`` when ``path`` is an existing file, cannot
    be created, or is not writable. Returns the folder as a Path.

    Parameters
    ----------
    path : str or Path
        The folder (``~`` expanded).
    field : str, optional
        The option named in the error (default ``"--out"``).
    shown : str, optional
        The path as named in the error (default: ``str(path)``).

    Returns
    -------
    Path
        The folder, existing and writable.

    Raises
    ------
    ValidationError
        ``path`` is empty, an existing file, cannot be created, or a test file cannot be written
        in it.
    """
    shown = str(path) if shown is None else shown
    if not str(path).strip():
        raise ValidationError(field, shown, "a folder path")
    p = Path(path).expanduser()
    if p.exists() and not p.is_dir():
        raise ValidationError(field, shown, "a folder, not an existing file")
    if not p.exists():
        try:
            p.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ValidationError(field, shown, f"a folder that can be created ({exc.strerror or exc})") from None
    _probe_writable(p, field, shown)
    return p


def output_file(path, field: str) -> Path:
    """Make sure the file ``path`` can be written: not a folder, its folder exists or can be
    created and is writable. Creates the folder; does not create the file.

    Parameters
    ----------
    path : str or Path
        The file to write (``~`` expanded).
    field : str
        The option named in the error (e.g. ``"--html"``).

    Returns
    -------
    Path
        The file's path.

    Raises
    ------
    ValidationError
        ``path`` is empty, a folder (or ends with a separator), an existing read-only file, or its
        folder cannot be created or written (:func:`output_folder`).
    """
    shown = str(path)
    if not shown.strip():
        raise ValidationError(field, shown, "a file path")
    p = Path(path).expanduser()
    if p.is_dir() or shown.endswith(os.sep):
        raise ValidationError(field, shown, "a file name, not a folder")
    if p.exists() and not os.access(p, os.W_OK):
        raise ValidationError(field, shown, "a writable file (the existing file is read-only)")
    output_folder(p.parent, field=field, shown=shown)   # Path("kept.html").parent is Path(".")
    return p


def input_file(path, field: str, expected: str = "an existing file") -> Path:
    """An existing, readable regular file (not a folder).

    Parameters
    ----------
    path : str or Path
        The file to read (``~`` expanded).
    field : str
        The option or argument named in the error.
    expected : str, optional
        What the file should be, in words (default ``"an existing file"``).

    Returns
    -------
    Path
        The file's path.

    Raises
    ------
    ValidationError
        ``path`` does not exist, is a folder, or cannot be read.
    """
    shown = str(path)
    p = Path(path).expanduser()
    if not p.exists():
        raise ValidationError(field, shown, f"{expected} (no such file)")
    if p.is_dir():
        raise ValidationError(field, shown, f"{expected}, not a folder")
    if not os.access(p, os.R_OK):
        raise ValidationError(field, shown, f"{expected} that can be read (permission denied)")
    return p


def check_not_overwriting(out: Path, name: str, study_file, force: bool = False) -> None:
    """Refuse to overwrite another study's files in ``out`` (issue 27 item 4).

    ``evotol run`` writes ``NAME.json`` and ``NAME.html``; its JSON records ``study_file``, the
    resolved path of the study file that wrote them. The same study file may write again (an
    edited and re-run study keeps its place); files recorded by another study file, or without
    that record (a seed study's, an earlier evotol's), are refused unless ``force``.

    Parameters
    ----------
    out : Path
        The output folder.
    name : str
        The study's ``name`` (the files' stem).
    study_file : str or Path
        The study file about to write.
    force : bool
        Overwrite on purpose (``evotol run --force``).

    Raises
    ------
    ValidationError
        Naming ``--out``, the files there and the study file that wrote them.
    """
    existing = [p for p in (Path(out) / f"{name}.json", Path(out) / f"{name}.html") if p.exists()]
    if force or not existing:
        return
    owner = None
    try:
        owner = json.loads((Path(out) / f"{name}.json").read_text(encoding="utf-8")).get("study_file")
    except (OSError, ValueError, AttributeError):
        pass
    if owner is not None and owner == str(Path(study_file).resolve()):
        return
    who = f"by the study file {owner}" if owner else "by another study (no study file recorded)"
    raise ValidationError("--out", str(out), f"a folder without another study's files: {' and '.join(p.name for p in existing)} "
                                             f"there were written {who}; pass --force to overwrite them, or give this study "
                                             f"another name (name = {name!r}) or another --out")

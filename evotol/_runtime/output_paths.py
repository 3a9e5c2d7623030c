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


#: names Windows reserves for devices, with or without an extension (``CON``, ``nul.txt``, ``COM1``)
_RESERVED = {"CON", "PRN", "AUX", "NUL", *(f"COM{i}" for i in range(1, 10)), *(f"LPT{i}" for i in range(1, 10))}


def check_output_name(name, field: str = "name") -> str:
    """Make sure ``name`` can only be a file name: the stem of a study's files, never a path.

    A study file is input from anyone; ``name = "../escaped"`` must not write beside ``--out``
    (issue 42).

    Parameters
    ----------
    name : str
        The name (e.g. a study file's ``name``).
    field : str, optional
        The field named in the error (default ``"name"``).

    Returns
    -------
    str
        ``name``.

    Raises
    ------
    ValidationError
        ``name`` is not a string, is empty, starts with ``.`` (``..``, hidden files), holds a path separator (``/``,
        ``\\``), a drive colon, a control character, starts or ends with a space or ends with a dot,
        or is a name Windows reserves (``CON``, ``NUL``, ``COM1``, ...).

    Examples
    --------
    >>> from evotol._runtime.output_paths import check_output_name
    >>> check_output_name("ucr3_example")
    'ucr3_example'
    >>> check_output_name("../escaped")
    Traceback (most recent call last):
        ...
    evotol.errors.ValidationError: name = '../escaped': expected a file name, not a path (no '/', '\\', ':' or '..'; not starting with '.')
    """
    expected = "a file name, not a path (no '/', '\\', ':' or '..'; not starting with '.')"
    if not isinstance(name, str) or not name.strip():
        raise ValidationError(field, name, "a non-empty file name")
    if name.startswith(".") or any(c in name for c in "/\\:") or ".." in name:
        raise ValidationError(field, name, expected)
    if any(ord(c) < 32 or ord(c) == 127 for c in name) or name != name.strip() or name.endswith("."):
        raise ValidationError(field, name, "a file name without control characters, outer spaces or a final dot")
    if name.split(".")[0].upper() in _RESERVED:
        raise ValidationError(field, name, "a file name that is not a device name reserved by Windows "
                                           "(CON, PRN, AUX, NUL, COM1-9, LPT1-9)")
    return name


def path_inside(out, filename) -> Path:
    """``out / filename``, proven to stay inside ``out`` once links and ``..`` are resolved.

    Parameters
    ----------
    out : str or Path
        The output folder.
    filename : str or Path
        A file name (or a relative path) inside ``out``.

    Returns
    -------
    Path
        ``Path(out) / filename``.

    Raises
    ------
    ValidationError
        The resolved path lies outside the resolved ``out`` (an absolute ``filename``, ``..``, or
        a link pointing elsewhere).
    """
    root = Path(out).resolve()
    target = (Path(out) / filename).resolve()
    if target == root or not target.is_relative_to(root):
        raise ValidationError("output file", str(filename), f"a file inside --out {str(out)!r} (it resolves to {target})")
    return Path(out) / filename


def check_not_overwriting(out: Path, name: str, study_file, force: bool = False, *, owner: str | None = None,
                          manifest: dict | None = None) -> None:
    """Refuse to overwrite another owner's files in ``out`` (issue 27 item 4, issue 42).

    The owner of ``NAME.*`` is the one recorded in ``NAME.manifest.json``
    (:mod:`evotol._runtime.output_set`: written before the first file, so a killed run is still
    its owner's), else, for folders written before manifests existed, the ``study_file`` of
    ``NAME.json`` (a seed study's JSON records none). The same owner may write again; another
    owner's files are refused unless ``force``.

    Parameters
    ----------
    out : Path
        The output folder.
    name : str
        The study's ``name`` (the files' stem).
    study_file : str or Path or None
        The study file about to write (None: a seed study).
    force : bool
        Overwrite on purpose (``evotol run --force``, ``evotol reproduce --force``).
    owner : str, optional
        Who writes (default: ``"study file <resolved study_file>"``).
    manifest : dict, optional
        The folder's manifest for ``name`` (default: none).

    Raises
    ------
    ValidationError
        Naming ``--out``, the files there and who wrote them.
    """
    study_file = str(Path(study_file).resolve()) if study_file is not None else None
    owner = owner or f"study file {study_file}"
    names = (f"{name}.json", f"{name}.html", f"{name}.manifest.json")
    existing = [Path(out) / n for n in names if (Path(out) / n).exists()]
    if force or not existing:
        return
    if manifest and manifest.get("owner"):
        if manifest["owner"] == owner:
            return
        who = f"by the {manifest['owner']}"
    else:
        recorded = None
        try:
            recorded = json.loads((Path(out) / f"{name}.json").read_text(encoding="utf-8")).get("study_file")
        except (OSError, ValueError, AttributeError):
            pass
        if recorded == study_file and (recorded is not None or owner.startswith("seed study")):
            return      # the same study file; or a seed study's files (no study file), rewritten by reproduce
        who = f"by the study file {recorded}" if recorded else "by another study (no study file recorded)"
    shown = [p.name for p in existing if not p.name.endswith(".manifest.json")] or [existing[0].name]
    raise ValidationError("--out", str(out), f"a folder without another study's files: {' and '.join(shown)} "
                                             f"there were written {who}; pass --force to overwrite them, or give this study "
                                             f"another name (name = {name!r}) or another --out")

"""Finding a mechanism description file: by path, or by the name of one shipped with evotol.

The shipped descriptions are ``robots/mechanisms/*.toml`` (:data:`SHIPPED`): ``"fivebar"`` names
``robots/mechanisms/fivebar.toml``. A study file's ``[robot] mechanism = ...``, ``evotol describe``
and ``evotol check-mechanism`` find their description here.
"""
from __future__ import annotations

from pathlib import Path

from evotol.errors import ValidationError

#: directory of the shipped mechanism descriptions (``robots/mechanisms/``)
SHIPPED = Path(__file__).resolve().parents[2] / "mechanisms"


def resolve_description(name, base_dir=None) -> Path:
    """A description file by path (relative to ``base_dir``, then to the working directory) or by
    the name of a shipped one (``"fivebar"`` -> ``robots/mechanisms/fivebar.toml``).

    Parameters
    ----------
    name : str or Path
        A file path, or the name of a shipped description (with or without ``.toml``).
    base_dir : str or Path or None, optional
        Directory a relative path is tried against first (e.g. the study file's directory).

    Returns
    -------
    Path
        The first existing file among ``base_dir / name``, ``name``, the shipped ``name`` and
        ``name.toml``.

    Raises
    ------
    evotol.errors.ValidationError
        No such file; the message lists the shipped descriptions.
    """
    p = Path(str(name))
    for cand in ([Path(base_dir) / p] if base_dir and not p.is_absolute() else []) + [p, SHIPPED / p, SHIPPED / f"{p}.toml"]:
        if cand.is_file():
            return cand
    shipped = sorted(f.stem for f in SHIPPED.glob("*.toml"))
    raise ValidationError("robot.mechanism", str(name), f"a description file (TOML) or a shipped one: {shipped}")

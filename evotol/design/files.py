"""Entries tables on disk: CSV for people, Parquet (with the factor metadata) for ``evotol filter``."""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from evotol._runtime.atomic_files import atomic_path
from evotol.design.factors import ERROR
from evotol.errors import ValidationError


def save_entries(df: pd.DataFrame, stem: str | Path) -> dict[str, Path]:
    """Write ``stem.parquet`` (with the factor metadata) and ``stem.csv``; returns both paths.

    Parameters
    ----------
    df : pandas.DataFrame
        The entries table (its ``attrs`` travel in the Parquet metadata; the index is not
        written).
    stem : str or Path
        Path without suffix (any suffix is replaced); missing parent folders are created.

    Returns
    -------
    dict of str to Path
        ``{"parquet": <stem>.parquet, "csv": <stem>.csv}``.
    """
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    pq, csv = stem.with_suffix(".parquet"), stem.with_suffix(".csv")
    with atomic_path(pq) as tmp:
        df.to_parquet(tmp, index=False)
    with atomic_path(csv) as tmp:
        df.to_csv(tmp, index=False, encoding="utf-8")
    return {"parquet": pq, "csv": csv}


def load_entries(path: str | Path) -> pd.DataFrame:
    """Read entries from Parquet (with metadata) or CSV.

    Parameters
    ----------
    path : str or Path
        A ``.parquet`` / ``.pq`` file (factor metadata restored in ``df.attrs``) or a ``.csv``
        file (no metadata; a missing ``error`` is read back as the empty string).

    Returns
    -------
    pandas.DataFrame
        The entries table.

    Raises
    ------
    ValidationError
        The file does not exist or has another suffix.
    """
    path = Path(path)
    if not path.exists():
        raise ValidationError("entries file", str(path), "an existing .parquet or .csv file")
    if path.suffix.lower() in (".parquet", ".pq"):
        return pd.read_parquet(path)
    if path.suffix.lower() == ".csv":
        df = pd.read_csv(path, encoding="utf-8")
        if ERROR in df:
            df[ERROR] = df[ERROR].astype(object).where(df[ERROR].notna(), "").astype(str)
        return df
    raise ValidationError("entries file", str(path), "a .parquet or .csv file")


"""Entries tables on disk: CSV for people, Parquet (with the factor metadata) for ``evotol filter``."""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from evotol.doe.factors import ERROR
from evotol.errors import ValidationError


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


"""A folder of finished chunks (Parquet) with a manifest: what makes a long evaluation resumable."""
from __future__ import annotations

import json
import os
from pathlib import Path

import pandas as pd


class ChunkStore:
    """Finished DataFrame chunks ``chunk_00012.parquet`` in ``path``, keyed by a manifest.

    The manifest records what the chunks belong to (``key``: a fingerprint of the inputs and the
    evaluator, the number of entries, the chunk size). Opening the store with the same manifest
    returns the chunks already there (an interrupted run resumes with the missing ones); with
    another manifest the old chunks belong to another study and are removed first.

    Parameters
    ----------
    path : str or Path
        The folder of the chunks and of ``manifest.json`` (created by :meth:`open`).
    **manifest
        JSON-serialisable values recording what the chunks belong to (e.g. ``key``, the number
        of entries, the chunk size); compared with the stored manifest after a JSON round trip.
    """

    def __init__(self, path: str | Path, **manifest):
        self.path = Path(path)
        self.manifest = dict(manifest)

    def open(self) -> dict[int, pd.DataFrame]:
        """The chunks finished by an earlier run with the same manifest, by chunk index.

        Creates the folder; with another (or no readable) manifest, removes the old chunks and
        writes this one. A chunk that cannot be read (cut short by a kill) is deleted.

        Returns
        -------
        dict of int to pandas.DataFrame
            Chunk index -> the finished chunk; empty for a new or another study.
        """
        path = self.path
        path.mkdir(parents=True, exist_ok=True)
        manifest = path / "manifest.json"
        if manifest.exists():
            try:
                old = json.loads(manifest.read_text())
            except (OSError, ValueError):
                old = {}
            if old == self.manifest:
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
        manifest.write_text(json.dumps(self.manifest))
        return {}

    def save(self, index: int, chunk: pd.DataFrame) -> None:
        """Write one finished chunk atomically (a kill mid-write leaves no half chunk behind).

        Parameters
        ----------
        index : int
            The chunk's index (the file ``chunk_{index:05d}.parquet``).
        chunk : pandas.DataFrame
            The finished chunk.
        """
        tmp = self.path / f".chunk_{index:05d}.parquet.tmp"
        chunk.to_parquet(tmp)
        os.replace(tmp, self.path / f"chunk_{index:05d}.parquet")

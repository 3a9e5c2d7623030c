"""A folder of finished chunks (Parquet) with a manifest: what makes a long evaluation resumable.

Every chunk is checked before it is used again (issue 42): the manifest records, per chunk, the
entry range it holds (``start``, ``stop``, from the manifest's ``n_entries`` and ``chunk_size``),
its row count and the SHA-256 of its file. A chunk that fails any of them -- unreadable, cut short,
a bit flipped, swapped for another chunk, or not in the manifest -- is removed and evaluated again,
with one warning line (logger ``evotol``); nothing unverified is used.
"""
from __future__ import annotations

import json
import logging
from pathlib import Path

import pandas as pd

from evotol._runtime.atomic_files import atomic_path, remove_stale_temporaries, sha256_of, write_text

log = logging.getLogger("evotol")


class ChunkStore:
    """Finished DataFrame chunks ``chunk_00012.parquet`` in ``path``, keyed by a manifest.

    The manifest records what the chunks belong to (``key``: a fingerprint of the inputs and the
    evaluator, the number of entries, the chunk size) and, under ``chunks``, each finished
    chunk's entry range, row count and SHA-256 (module docstring). Opening the store with the same
    manifest returns the chunks already there that pass those checks (an interrupted run resumes
    with the missing ones); with another manifest the old chunks belong to another study and are
    removed first.

    Parameters
    ----------
    path : str or Path
        The folder of the chunks and of ``manifest.json`` (created by :meth:`open`).
    **manifest
        JSON-serialisable values recording what the chunks belong to (e.g. ``key``, the number
        of entries ``n_entries``, the chunk size ``chunk_size``); compared with the stored
        manifest after a JSON round trip.
    """

    def __init__(self, path: str | Path, **manifest):
        self.path = Path(path)
        self.manifest = dict(manifest)
        self.chunks: dict[str, dict] = {}

    def _range(self, index: int) -> tuple[int, int] | None:
        n, size = self.manifest.get("n_entries"), self.manifest.get("chunk_size")
        if n is None or size is None:
            return None
        return index * int(size), min((index + 1) * int(size), int(n))

    def _checked(self, f: Path, records: dict) -> pd.DataFrame | None:
        """The chunk in ``f`` if it passes every check, else None with the one-line reason logged."""
        index = int(f.stem.split("_")[1])
        rec = records.get(str(index))
        expected = self._range(index)
        why = None
        if not isinstance(rec, dict):
            why = "not in the manifest"
        elif expected is not None and [rec.get("start"), rec.get("stop")] != list(expected):
            why = f"its entry range {rec.get('start')}..{rec.get('stop')} is not chunk {index}'s {expected[0]}..{expected[1]}"
        elif sha256_of(f) != rec.get("sha256"):
            why = "its SHA-256 differs from the manifest's (changed or swapped)"
        df = None
        if why is None:
            try:
                df = pd.read_parquet(f)
            except Exception as exc:    # pyarrow raises its own kinds for a damaged file
                why = f"unreadable ({type(exc).__name__})"
        if why is None and len(df) != rec.get("rows"):
            why = f"{len(df)} rows, the manifest says {rec.get('rows')}"
        if why is None and expected is not None and len(df) != expected[1] - expected[0]:
            why = f"{len(df)} rows, chunk {index} holds {expected[1] - expected[0]} entries"
        if why is None:
            return df
        log.warning("evotol: chunk %s of %s failed its check (%s): evaluated again", f.name, self.path, why)
        f.unlink(missing_ok=True)
        return None

    def open(self) -> dict[int, pd.DataFrame]:
        """The chunks finished by an earlier run with the same manifest that pass their checks, by
        chunk index.

        Creates the folder; with another (or no readable) manifest, removes the old chunks and
        writes this one. A chunk that fails its checks (class docstring) is deleted, with a
        warning.

        Returns
        -------
        dict of int to pandas.DataFrame
            Chunk index -> the finished chunk; empty for a new or another study.
        """
        path = self.path
        path.mkdir(parents=True, exist_ok=True)
        remove_stale_temporaries(path)          # left by a writer killed outright (its pid ended)
        manifest = path / "manifest.json"
        if manifest.exists():
            try:
                old = json.loads(manifest.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                old = {}
            records = old.pop("chunks", {}) if isinstance(old, dict) else {}
            if old == self.manifest and isinstance(records, dict):
                found = {}
                for f in sorted(path.glob("chunk_*.parquet")):
                    df = self._checked(f, records)
                    if df is not None:
                        found[int(f.stem.split("_")[1])] = df
                        self.chunks[str(int(f.stem.split("_")[1]))] = records[str(int(f.stem.split("_")[1]))]
                self._write_manifest()
                return found
        # another study (or other settings) used this folder: its chunks do not belong to us
        for f in list(path.glob("chunk_*.parquet")) + list(path.glob(".chunk_*.tmp*")):
            f.unlink(missing_ok=True)
        self.chunks = {}
        self._write_manifest()
        return {}

    def _write_manifest(self) -> None:
        write_text(self.path / "manifest.json", json.dumps({**self.manifest, "chunks": self.chunks}), record=False)

    def save(self, index: int, chunk: pd.DataFrame) -> None:
        """Write one finished chunk atomically (a kill mid-write leaves no half chunk behind) and
        record its range, row count and SHA-256 in the manifest.

        Parameters
        ----------
        index : int
            The chunk's index (the file ``chunk_{index:05d}.parquet``).
        chunk : pandas.DataFrame
            The finished chunk.
        """
        f = self.path / f"chunk_{index:05d}.parquet"
        with atomic_path(f, record=False) as tmp:     # a name unique to this process and call
            chunk.to_parquet(tmp)
        rec = {"rows": len(chunk), "sha256": sha256_of(f)}
        span = self._range(index)
        if span is not None:
            rec.update(start=span[0], stop=span[1])
        self.chunks[str(index)] = rec
        self._write_manifest()

"""Filter evaluated design entries the way Deng (2012, Figs. VII.3-VII.8, VII.12-VII.16) does.

A :class:`DesignStudy` holds an evaluated entries table (:mod:`evotol.doe`), which columns are
inputs (factors) and which are objectives, and named :class:`Preset` filters. ``study.filter(
"p_max <= 0.05")`` returns a :class:`FilterResult`: how many entries are kept and the range (and
for levelled factors the set of levels) each input keeps -- what the thesis reads off its
filtered parallel-coordinate figures ("Δb_z can be either 1e-3 or 1e-1 mm").

Queries are pandas ``DataFrame.query`` expressions. A bare objective name resolves to the one
column that carries it with a unit suffix (``p_max`` -> ``p_max_mm``), so the thesis's
``p_max <= 0.05`` reads in the unit of the table; the resolved query is reported.

:func:`main_effects` summarises how much each input moves an objective (mean of log10 objective
per level, averaged over all other inputs): the data behind the report's findings.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import pandas as pd

from evotol.doe import ENTRY, ERROR, FEASIBLE, SOURCE, Factor, factors_of, load_entries, save_entries
from evotol.errors import ValidationError

#: unit suffixes a bare name may resolve to, in order of preference
UNIT_SUFFIXES = ("mm", "deg", "mm2", "um", "m", "rad", "m2", "cost")
_NAME = re.compile(r"(?<![\w.@'\"`])([A-Za-z_]\w*)(?![\w'\"`(])")
_KEYWORDS = {"and", "or", "not", "in", "True", "False", "None", "inf", "nan"}


@dataclass(frozen=True)
class Preset:
    """A named filter: per-column closed bounds ``{column: (low or None, high or None)}``.

    figure: where it comes from (``"Deng 2012 Fig. VII.4"``). Bounds map one-to-one to the axis
    constraint ranges of the parallel-coordinate report.
    """

    name: str
    bounds: Mapping[str, tuple[float | None, float | None]]
    figure: str = ""

    def __post_init__(self):
        if not self.bounds:
            raise ValidationError(f"Preset({self.name!r}).bounds", self.bounds, "at least one column bound")
        for col, b in self.bounds.items():
            if len(b) != 2 or (b[0] is None and b[1] is None):
                raise ValidationError(f"Preset({self.name!r}) bound on {col}", b, "(low, high) with at least one number")
            if b[0] is not None and b[1] is not None and b[0] > b[1]:
                raise ValidationError(f"Preset({self.name!r}) bound on {col}", b, "low <= high")

    @property
    def query(self) -> str:
        parts = []
        for col, (lo, hi) in self.bounds.items():
            if lo is not None:
                parts.append(f"{col} >= {lo!r}")
            if hi is not None:
                parts.append(f"{col} <= {hi!r}")
        return " and ".join(parts)

    def to_dict(self) -> dict:
        return {"name": self.name, "query": self.query, "figure": self.figure,
                "bounds": {k: list(v) for k, v in self.bounds.items()}}


@dataclass
class FilterResult:
    """Entries kept by a query, with the range each input keeps."""

    query: str
    resolved_query: str
    count: int
    total: int
    kept: pd.DataFrame
    ranges: dict = field(default_factory=dict)
    objective_ranges: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """JSON-ready summary: ``{query, count, total, ranges, objective_ranges}``."""
        return {"query": self.resolved_query, "count": self.count, "total": self.total,
                "ranges": self.ranges, "objective_ranges": self.objective_ranges}

    def describe(self) -> str:
        """Plain-text summary, one line per input (what ``evotol filter`` prints)."""
        lines = [f"{self.resolved_query}: {self.count} of {self.total} entries kept"]
        if not self.count:
            return lines[0] + " (no entry satisfies the query; no ranges to report)"
        for name, r in self.ranges.items():
            if r.get("levels") is not None:
                lines.append(f"  {name:24s} levels {', '.join(f'{v:g}' for v in r['levels'])}")
            elif r["min"] is not None:
                lines.append(f"  {name:24s} [{r['min']:.6g}, {r['max']:.6g}]")
        for name, r in self.objective_ranges.items():
            if r["min"] is not None:
                lines.append(f"  {name:24s} [{r['min']:.6g}, {r['max']:.6g}] (objective)")
        return "\n".join(lines)


def resolve_query(query: str, columns: Sequence[str]) -> str:
    """Replace bare names by their unit-suffixed column (``p_max`` -> ``p_max_mm``).

    A name that is a column stays; a name with exactly one ``name_<unit>`` column
    (:data:`UNIT_SUFFIXES`) is replaced; an ambiguous or unknown name raises ValidationError.
    """
    if not isinstance(query, str) or not query.strip():
        raise ValidationError("query", query, "a non-empty pandas query such as 'p_max_mm <= 0.05'")
    cols = set(map(str, columns))

    def sub(m: re.Match) -> str:
        name = m.group(1)
        if name in cols or name in _KEYWORDS or name.startswith("@"):
            return name
        cands = [f"{name}_{u}" for u in UNIT_SUFFIXES if f"{name}_{u}" in cols]
        if len(cands) == 1:
            return cands[0]
        if len(cands) > 1:
            raise ValidationError("query name", name, f"one of the columns {cands} (ambiguous unit)")
        raise ValidationError("query name", name, f"a column of the entries: {sorted(cols)}")

    # names inside quoted strings are left alone
    pieces = re.split(r"('(?:[^']*)'|\"(?:[^\"]*)\")", query)
    return "".join(p if i % 2 else _NAME.sub(sub, p) for i, p in enumerate(pieces))


def _ranges(df: pd.DataFrame, columns: Sequence[str], factors: Mapping[str, Factor]) -> dict:
    out = {}
    for c in columns:
        vals = pd.to_numeric(df[c], errors="coerce").to_numpy(float) if len(df) else np.zeros(0)
        vals = vals[np.isfinite(vals)]
        r = {"min": float(vals.min()) if vals.size else None, "max": float(vals.max()) if vals.size else None}
        f = factors.get(c)
        if f is not None and f.is_discrete:
            r["levels"] = sorted(float(v) for v in np.unique(vals))
        out[c] = r
    return out


class DesignStudy:
    """An evaluated design study: entries, inputs, objectives and named presets.

    entries: DataFrame from :func:`evotol.doe.evaluate` (or loaded with :meth:`load`).
    inputs: factor columns (default: the factors stored in the entries' metadata, else every
        numeric column that is not an objective or bookkeeping column).
    objectives: objective columns (default: from the metadata, else ``--objectives``-less CSVs
        use the numeric columns that are not inputs).
    """

    def __init__(self, entries: pd.DataFrame, *, inputs: Sequence[str] | None = None,
                 objectives: Sequence[str] | None = None, presets: Sequence[Preset] = (),
                 name: str = ""):
        if not isinstance(entries, pd.DataFrame):
            raise ValidationError("entries", type(entries).__name__, "a pandas DataFrame")
        self.entries, self.name = entries, name
        meta = entries.attrs.get("evotol", {})
        self.factors = {f.name: f for f in factors_of(entries)}
        bookkeeping = {ENTRY, ERROR, FEASIBLE, SOURCE, "knee"}
        numeric = [c for c in entries.columns if c not in bookkeeping and pd.api.types.is_numeric_dtype(entries[c])]
        if inputs is None:
            inputs = [f for f in self.factors if f in entries] or None
        if objectives is None:
            objectives = [c for c in meta.get("objectives", []) if c in entries] or None
        if inputs is None and objectives is None:
            raise ValidationError("inputs/objectives", None, "the entries' metadata or explicit input and objective columns")
        if inputs is None:
            inputs = [c for c in numeric if c not in objectives]
        if objectives is None:
            objectives = [c for c in numeric if c not in inputs]
        for c in list(inputs) + list(objectives):
            if c not in entries:
                raise ValidationError("column", c, f"a column of the entries: {list(entries.columns)}")
        self.inputs, self.objectives = list(inputs), list(objectives)
        self.presets = {p.name: p for p in presets}

    # --- construction ---------------------------------------------------------------------
    @classmethod
    def load(cls, path: str | Path, **kw) -> "DesignStudy":
        return cls(load_entries(path), **kw)

    def save(self, stem: str | Path) -> dict[str, Path]:
        return save_entries(self.entries, stem)

    def __len__(self) -> int:
        return len(self.entries)

    def __repr__(self) -> str:
        return (f"DesignStudy({self.name!r}, {len(self)} entries, inputs={self.inputs}, "
                f"objectives={self.objectives}, presets={list(self.presets)})")

    # --- filtering ------------------------------------------------------------------------
    def filter(self, query: str | Preset, among: pd.DataFrame | None = None) -> FilterResult:
        """Entries satisfying ``query`` (a pandas query string, a Preset, or a preset's name)."""
        df = self.entries if among is None else among
        if isinstance(query, str) and query in self.presets:
            query = self.presets[query]
        text = query.query if isinstance(query, Preset) else query
        resolved = resolve_query(text, list(df.columns))
        try:
            kept = df.query(resolved, engine="python")
        except Exception as exc:   # pandas raises many types for a malformed expression
            raise ValidationError("query", text, f"a valid pandas query over {list(df.columns)} ({exc})") from None
        return FilterResult(query=text, resolved_query=resolved, count=int(len(kept)), total=int(len(df)),
                            kept=kept, ranges=_ranges(kept, self.inputs, self.factors),
                            objective_ranges=_ranges(kept, self.objectives, {}))

    def preset_results(self, among: pd.DataFrame | None = None) -> dict[str, FilterResult]:
        return {name: self.filter(p, among) for name, p in self.presets.items()}

    def objective_ranges(self, among: pd.DataFrame | None = None) -> dict:
        df = self.entries if among is None else among
        return _ranges(df, self.objectives, {})

    def main_effects(self, objective: str, log: bool = True, among: pd.DataFrame | None = None) -> pd.DataFrame:
        return main_effects(self.entries if among is None else among, self.inputs, objective, log=log)


def main_effects(df: pd.DataFrame, inputs: Sequence[str], objective: str, log: bool = True) -> pd.DataFrame:
    """Main effect of each input on an objective: per level, the mean of (log10) objective.

    Returns one row per input with ``effect`` = largest minus smallest level mean (in decades
    when ``log``), ``low_level_mean`` and ``high_level_mean`` (at the input's smallest and
    largest level) and ``levels``. On a full factorial this is the classical main effect (every
    level is averaged over all combinations of the other inputs); on samples it is an estimate.
    Continuous inputs are binned into quartiles.
    """
    if objective not in df:
        raise ValidationError("objective", objective, f"a column of {list(df.columns)}")
    y = df[objective].to_numpy(float)
    ok = np.isfinite(y) & ((y > 0) if log else True)
    y = np.log10(y[ok]) if log else y[ok]
    rows = []
    for c in inputs:
        x = df[c].to_numpy(float)[ok]
        levels = np.unique(x)
        if len(levels) > 12:
            q = np.quantile(x, [0, .25, .5, .75, 1])
            keys = np.clip(np.searchsorted(q, x, side="right") - 1, 0, 3)
            levels = np.array([np.median(x[keys == k]) for k in range(4)])
        else:
            keys = np.searchsorted(levels, x)
        means = np.array([y[keys == k].mean() for k in range(len(levels))])
        rows.append({"input": c, "effect": float(means.max() - means.min()),
                     "low_level_mean": float(means[0]), "high_level_mean": float(means[-1]),
                     "levels": [float(v) for v in levels], "level_means": [float(m) for m in means]})
    return pd.DataFrame(rows).sort_values("effect", ascending=False).reset_index(drop=True)

"""Filter evaluated design entries the way Deng (2012, Figs. VII.3-VII.8, VII.12-VII.16) does.

A :class:`DesignStudy` holds an evaluated entries table (:mod:`evotol.design`), which columns are
inputs (factors) and which are objectives, and named :class:`Preset` filters. ``study.filter(
"p_max <= 0.05")`` returns a :class:`FilterResult`: how many entries are kept and the range (and
for levelled factors the set of levels) each input keeps -- what the thesis reads off its
filtered parallel-coordinate figures ("Δb_z can be either 1e-3 or 1e-1 mm").

Queries are pandas ``DataFrame.query`` expressions. A bare objective name resolves to the one
column that carries it with a unit suffix (``p_max`` -> ``p_max_mm``), so the thesis's
``p_max <= 0.05`` reads in the unit of the table; the resolved query is reported.

:func:`main_effects` summarises how much each input moves an objective (mean of log10 objective
per level, averaged over all other inputs): the data behind the report's findings.

The parameters several definitions of this module share are described once, here.

Parameters
----------
among : pandas.DataFrame, optional
    Entries to use instead of the study's.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import pandas as pd

from evotol.design import ENTRY, ERROR, FEASIBLE, SOURCE, Factor, factors_of, load_entries, save_entries
from evotol.errors import ValidationError

#: unit suffixes a bare name may resolve to, in order of preference
UNIT_SUFFIXES = ("mm", "deg", "mm2", "um", "m", "rad", "m2", "cost")
_NAME = re.compile(r"(?<![\w.@'\"`])([A-Za-z_]\w*)(?![\w'\"`(])")
_KEYWORDS = {"and", "or", "not", "in", "True", "False", "None", "inf", "nan"}


@dataclass(frozen=True)
class Preset:
    """A named filter: per-column closed bounds ``{column: (low or None, high or None)}``.

    Bounds map one-to-one to the axis constraint ranges of the parallel-coordinate report.

    Parameters
    ----------
    name : str
        The preset's name (``evotol filter --preset NAME``).
    bounds : mapping of str to (float or None, float or None)
        Column -> closed ``(low, high)`` bounds in the column's unit (its suffix, e.g. mm for
        ``p_max_mm``); None leaves that side open.
    figure : str, optional
        Where it comes from (``"Deng 2012 Fig. VII.4"``).

    Raises
    ------
    ValidationError
        No bound at all, a bound that is not a pair with at least one number, or ``low > high``.
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
        """The bounds as a pandas query, ``col >= low and col <= high and ...`` (str)."""
        parts = []
        for col, (lo, hi) in self.bounds.items():
            if lo is not None:
                parts.append(f"{col} >= {lo!r}")
            if hi is not None:
                parts.append(f"{col} <= {hi!r}")
        return " and ".join(parts)

    def to_dict(self) -> dict:
        """JSON form of the preset.

        Returns
        -------
        dict
            ``name``, ``query`` (:attr:`query`), ``figure`` and ``bounds`` (column ->
            ``[low, high]``, None for an open side).
        """
        return {"name": self.name, "query": self.query, "figure": self.figure,
                "bounds": {k: list(v) for k, v in self.bounds.items()}}


@dataclass
class FilterResult:
    """Entries kept by a query, with the range each input keeps.

    Parameters
    ----------
    query : str
        The query as given (a preset's query for a preset).
    resolved_query : str
        The query run, bare names replaced by their unit-suffixed columns (:func:`resolve_query`).
    count : int
        Entries kept.
    total : int
        Entries filtered.
    kept : pandas.DataFrame
        The kept entries.
    ranges : dict, optional
        Input column -> ``{"min", "max"}`` over the kept entries (the column's unit; None when
        nothing is kept), plus ``levels`` (list of float) for a levelled factor.
    objective_ranges : dict, optional
        Objective column -> ``{"min", "max"}`` over the kept entries.
    """

    query: str
    resolved_query: str
    count: int
    total: int
    kept: pd.DataFrame
    ranges: dict = field(default_factory=dict)
    objective_ranges: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """JSON-ready summary: ``{query, count, total, ranges, objective_ranges}``.

        Returns
        -------
        dict
            ``query`` (the resolved query), ``count``, ``total``, ``ranges``, ``objective_ranges``.
        """
        return {"query": self.resolved_query, "count": self.count, "total": self.total,
                "ranges": self.ranges, "objective_ranges": self.objective_ranges}

    def describe(self) -> str:
        """Plain-text summary, one line per input (what ``evotol filter`` prints).

        Returns
        -------
        str
            The query and the count kept, then each input's levels or ``[min, max]`` and each
            objective's ``[min, max]``; one line only when nothing is kept.
        """
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
    Python keywords, ``@variables`` and names inside quoted strings are left alone.

    Parameters
    ----------
    query : str
        A pandas ``DataFrame.query`` expression.
    columns : sequence of str
        The columns of the entries.

    Returns
    -------
    str
        The query with bare names replaced.

    Raises
    ------
    ValidationError
        ``query`` is not a non-empty string, or a name is neither a column nor the stem of exactly
        one unit-suffixed column.
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

    Parameters
    ----------
    entries : pandas.DataFrame
        DataFrame from :func:`evotol.design.evaluate` (or loaded with :meth:`load`).
    inputs : sequence of str, optional
        Factor columns (default: the factors stored in the entries' metadata, else every numeric
        column that is not an objective or bookkeeping column).
    objectives : sequence of str, optional
        Objective columns (default: from the metadata, else ``--objectives``-less CSVs use the
        numeric columns that are not inputs).
    presets : sequence of Preset, optional
        Named filters, kept by name in ``self.presets``.
    name : str, optional
        The study's name (shown in its repr).

    Raises
    ------
    ValidationError
        ``entries`` is not a DataFrame; neither the metadata nor the arguments give inputs or
        objectives; or a named column is not in ``entries``.
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
        """A study of the entries saved in a file (:func:`evotol.design.load_entries`).

        Parameters
        ----------
        path : str or Path
            A ``.parquet`` file (with the factor metadata) or a ``.csv`` file.
        **kw
            ``inputs``, ``objectives``, ``presets``, ``name`` of :class:`DesignStudy`.

        Returns
        -------
        DesignStudy
            The study of the loaded entries.

        Raises
        ------
        ValidationError
            The file does not exist or is neither Parquet nor CSV, or as :class:`DesignStudy`.
        """
        return cls(load_entries(path), **kw)

    def save(self, stem: str | Path) -> dict[str, Path]:
        """Write the entries to ``stem.parquet`` (with the factor metadata) and ``stem.csv``.

        Parameters
        ----------
        stem : str or Path
            The files' path without suffix (its folder is created).

        Returns
        -------
        dict of str to Path
            ``{"parquet": path, "csv": path}``.
        """
        return save_entries(self.entries, stem)

    def __len__(self) -> int:
        return len(self.entries)

    def __repr__(self) -> str:
        return (f"DesignStudy({self.name!r}, {len(self)} entries, inputs={self.inputs}, "
                f"objectives={self.objectives}, presets={list(self.presets)})")

    # --- filtering ------------------------------------------------------------------------
    def filter(self, query: str | Preset, among: pd.DataFrame | None = None) -> FilterResult:
        """Entries satisfying ``query`` (a pandas query string, a Preset, or a preset's name).

        Parameters
        ----------
        query : str or Preset
            A pandas query (bare objective names resolved by :func:`resolve_query`, values in
            the columns' units), a preset, or the name of one of the study's presets.
        among : pandas.DataFrame, optional
            Entries to filter instead of the study's (e.g. a previous result's ``kept``).

        Returns
        -------
        FilterResult
            The kept entries and the ranges of the inputs and objectives over them.

        Raises
        ------
        ValidationError
            An unknown or ambiguous name (:func:`resolve_query`), or a query pandas cannot
            evaluate.
        """
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
        """Every preset's :meth:`filter` result.

        Parameters
        ----------
        among : pandas.DataFrame, optional
            Entries to filter instead of the study's.

        Returns
        -------
        dict of str to FilterResult
            Preset name -> its result.
        """
        return {name: self.filter(p, among) for name, p in self.presets.items()}

    def objective_ranges(self, among: pd.DataFrame | None = None) -> dict:
        """Range of every objective over the entries (unfiltered).

        Returns
        -------
        dict
            Objective column -> ``{"min", "max"}`` of its finite values (the column's unit; None
            when there are none).
        """
        df = self.entries if among is None else among
        return _ranges(df, self.objectives, {})

    def main_effects(self, objective: str, log: bool = True, among: pd.DataFrame | None = None) -> pd.DataFrame:
        """Main effect of each of the study's inputs on ``objective`` (:func:`main_effects`).

        Parameters
        ----------
        objective : str
            An objective column.
        log : bool, optional
            Average log10 of the objective (default True: effects in decades).

        Returns
        -------
        pandas.DataFrame
            As :func:`main_effects`.

        Raises
        ------
        ValidationError
            ``objective`` or an input is not a column (of ``among``, if given), or the study
            has no inputs.
        """
        return main_effects(self.entries if among is None else among, self.inputs, objective, log=log)


def main_effects(df: pd.DataFrame, inputs: Sequence[str], objective: str, log: bool = True) -> pd.DataFrame:
    """Main effect of each input on an objective: per level, the mean of (log10) objective.

    Returns one row per input with ``effect`` = largest minus smallest level mean (in decades
    when ``log``), ``low_level_mean`` and ``high_level_mean`` (at the input's smallest and
    largest level) and ``levels``. On a full factorial this is the classical main effect (every
    level is averaged over all combinations of the other inputs); on samples it is an estimate.
    Continuous inputs (more than 12 distinct values) are binned into quartiles, each level
    then the bin's median; a bin left empty by tied values (quantile edges that coincide) is
    dropped, so such an input has fewer than four levels. With ``log``, entries whose objective
    is not positive are left out.

    Parameters
    ----------
    df : pandas.DataFrame
        The evaluated entries.
    inputs : sequence of str
        Input (factor) columns.
    objective : str
        The objective column.
    log : bool, optional
        Average log10 of the objective (default True); otherwise the objective itself, in its
        column's unit.

    Returns
    -------
    pandas.DataFrame
        One row per input, largest ``effect`` first: ``input``, ``effect`` (decades with
        ``log``, else the objective's unit), ``low_level_mean``, ``high_level_mean``, ``levels``
        (the inputs' unit) and ``level_means``.

    Raises
    ------
    ValidationError
        ``objective`` is not a column of ``df``, or ``inputs`` is empty or names a column
        that is not in ``df``.
    """
    if objective not in df:
        raise ValidationError("objective", objective, f"a column of {list(df.columns)}")
    if len(inputs) == 0 or any(c not in df for c in inputs):
        raise ValidationError("inputs", list(inputs), f"one or more columns of {list(df.columns)}")
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
            present = np.unique(keys)  # heavy ties can leave a quartile bin empty: it has no level
            keys = np.searchsorted(present, keys)
            levels = np.array([np.median(x[keys == k]) for k in range(len(present))])
        else:
            keys = np.searchsorted(levels, x)
        means = np.array([y[keys == k].mean() for k in range(len(levels))])
        rows.append({"input": c, "effect": float(means.max() - means.min()),
                     "low_level_mean": float(means[0]), "high_level_mean": float(means[-1]),
                     "levels": [float(v) for v in levels], "level_means": [float(m) for m in means]})
    return pd.DataFrame(rows).sort_values("effect", ascending=False).reset_index(drop=True)

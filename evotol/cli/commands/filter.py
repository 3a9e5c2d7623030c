"""``evotol filter ENTRIES.parquet "p_max <= 0.05 and r_max_deg <= 0.05"``.

Prints how many entries the query keeps and the range (levels) each input keeps -- the reading
Deng (2012) takes off Figs. VII.3-VII.8 -- (or, with ``--json``, that summary as JSON, as ``--json``
does on every command) and optionally writes the kept entries (CSV/Parquet), the JSON summary to a
file (``--summary``), or a parallel-coordinate HTML of the kept entries.
"""
from __future__ import annotations

import logging
from pathlib import Path

from evotol._runtime.atomic_files import atomic_path
logger = logging.getLogger(__name__)


def register(subparsers) -> None:
    """Add the ``filter`` sub-command to the ``evotol`` parser.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        What ``ArgumentParser.add_subparsers()`` returned; the new parser's ``func`` default
        is :func:`cmd_filter`.
    """
    p = subparsers.add_parser(
        "filter", help="filter evaluated design entries with a query; print counts and kept input ranges",
        description="Filter an entries table written by a design study (Parquet or CSV). The query is a "
                    "pandas expression over its columns; a bare objective name resolves to its "
                    "unit-suffixed column (p_max -> p_max_mm).")
    p.add_argument("entries", help="entries file (.parquet with evotol metadata, or .csv)")
    p.add_argument("query", help='e.g. "p_max <= 0.05 and r_max_deg <= 0.05"')
    p.add_argument("--inputs", default=None, help="comma-separated input columns (CSV files without metadata)")
    p.add_argument("--objectives", default=None, help="comma-separated objective columns (CSV files without metadata)")
    p.add_argument("--out", default=None, help="write the kept entries to this .csv or .parquet file")
    p.add_argument("--json", nargs="?", const=True, default=False,
                   help="print the summary (query, count, total, ranges) as JSON instead of the table")
    p.add_argument("--summary", default=None, metavar="FILE",
                   help="write the summary (query, count, total, ranges) to this JSON file")
    p.add_argument("--html", default=None, help="write a parallel-coordinate report of the kept entries")
    p.add_argument("--show", type=int, default=10, help="print the first N kept entries (default 10)")
    p.set_defaults(func=cmd_filter)


def cmd_filter(args) -> int:
    """Run ``evotol filter ENTRIES QUERY`` (module docstring).

    Parameters
    ----------
    args : argparse.Namespace
        ``entries`` (file), ``query`` (pandas expression, values in the columns' units),
        ``inputs`` / ``objectives`` (comma-separated columns or None), ``json`` (True: print the
        summary as JSON; a file name: the old form of ``--summary``, deprecated), ``out``,
        ``summary``, ``html`` (output files or None) and ``show`` (kept entries to print).

    Returns
    -------
    int
        Exit status 0 (also when the query keeps no entry).

    Raises
    ------
    ValidationError
        An unreadable entries file or unwritable output (checked before loading), entries
        without evotol metadata and no ``--inputs``/``--objectives``, or a bad query
        (:meth:`evotol.design.filtering.DesignStudy.filter`).
    """
    import pandas as pd

    from evotol.errors import ValidationError
    from evotol.design.filtering import DesignStudy, load_entries
    from evotol._runtime.output_paths import input_file, output_file
    from evotol.reporting.html import write_json

    input_file(args.entries, "entries", "an entries file (.parquet or .csv)")
    _old_json_form(args)
    for flag in ("out", "summary", "html"):              # before loading and filtering (issue 15)
        if getattr(args, flag):
            output_file(getattr(args, flag), f"--{flag}")
    split = (lambda s: [c.strip() for c in s.split(",") if c.strip()] if s else None)
    entries = load_entries(args.entries)
    try:
        study = DesignStudy(entries, inputs=split(args.inputs), objectives=split(args.objectives),
                            name=Path(args.entries).stem)
    except ValidationError as exc:
        if exc.field != "inputs/objectives":
            raise
        raise ValidationError("--inputs/--objectives", None,
                              f"the input and/or objective columns of {args.entries}, which carries no evotol "
                              f"metadata: pass --inputs a,b and/or --objectives c,d (its columns: "
                              f"{', '.join(map(str, entries.columns))})") from None
    res = study.filter(args.query)
    summary = {"entries": str(args.entries), **res.to_dict()}
    if args.json:
        from evotol.reporting.html import json_text
        print(json_text(summary))
    else:
        print(res.describe())
    if args.show and res.count and not args.json:
        with pd.option_context("display.width", 200, "display.max_columns", 40):
            print(res.kept[[c for c in ["entry", *study.inputs, *study.objectives] if c in res.kept]].head(args.show).to_string(index=False))
    if args.out:
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(out) as tmp:          # whole or not at all (issue 42)
            (res.kept.to_parquet(tmp, index=False) if out.suffix == ".parquet"
             else res.kept.to_csv(tmp, index=False, encoding="utf-8"))
        logger.info("kept entries -> %s", out)
    if args.summary:
        write_json(args.summary, summary)
        logger.info("summary -> %s", args.summary)
    if args.html and not res.count:
        logger.warning("no report written to %s: the query keeps no entry", args.html)
    elif args.html:
        from evotol.reporting.html import Report
        from evotol.reporting.parcoords import add_parcoords

        rep = Report(f"Filtered entries: {res.resolved_query}", f"{res.count} of {res.total} entries of {args.entries}")
        add_parcoords(rep, study, among=res.kept)
        logger.info("report -> %s", rep.write(args.html))
    return 0


def _old_json_form(args) -> None:
    """``--json FILE`` (before issue 40) still writes the summary to FILE, with a deprecation
    message: ``--json`` now means "print JSON" on every command, and ``--summary FILE`` writes it."""
    from evotol.errors import ValidationError

    if args.json is True or args.json is False:
        return
    if not str(args.json).endswith(".json"):
        raise ValidationError("--json", args.json, "no value (--json prints the summary as JSON); "
                                                   "--summary FILE writes it to a file")
    if args.summary:
        raise ValidationError("--json", args.json, "no value when --summary is given")
    logger.warning("'--json FILE' is deprecated and will be removed: use '--summary %s' (--json alone prints "
                   "the summary as JSON)", args.json)
    args.summary, args.json = args.json, False

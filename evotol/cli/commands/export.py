"""``evotol export STUDY.json``: the allocated tolerance table as a drawing carries it (CSV or Excel).

Reads the JSON that ``evotol run`` wrote and writes, per source, the name, group, nominal (where
known), the tolerance ± in the study's display units and the limit deviations, the process, the
source's share of the cost and its contribution at the worst pose (evotol/reporting/export.py).
An ``.xlsx`` file holds an ``about`` sheet and one sheet per method; a ``.csv`` file one method
(default: the certified optimum, else the cheapest method that meets the requirement).
"""
from __future__ import annotations


def register(subparsers) -> None:
    """Add the ``export`` sub-command to the ``evotol`` parser.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        What ``ArgumentParser.add_subparsers()`` returned; the new parser's ``func`` default
        is :func:`cmd_export`.
    """
    p = subparsers.add_parser("export", help="write a user study's tolerance table as CSV or Excel (drawing units)",
                              description=__doc__.split("\n\n", 1)[1])
    p.add_argument("study_json", help="the NAME.json that 'evotol run' wrote")
    p.add_argument("--method", default=None, help="the allocation to export (default: optimum, else the cheapest "
                                                  "feasible method; an .xlsx file otherwise holds every method)")
    p.add_argument("--out", default=None, help="output file ending in .csv or .xlsx (default: NAME_tolerances.xlsx "
                                               "beside the JSON)")
    p.set_defaults(func=cmd_export)


def cmd_export(args) -> int:
    """Run ``evotol export STUDY.json`` (module docstring).

    Parameters
    ----------
    args : argparse.Namespace
        ``study_json`` (the JSON ``evotol run`` wrote), ``method`` (or None) and ``out`` (a
        ``.csv`` or ``.xlsx`` file, or None: ``NAME_tolerances.xlsx`` beside the JSON).

    Returns
    -------
    int
        Exit status 0.

    Raises
    ------
    ValidationError
        The JSON file is missing, unreadable or not valid JSON, or not a user study's summary
        (no ``display_units`` or ``sources``); and what the table writer refuses (an unknown
        method or file type).
    """
    import json
    from pathlib import Path

    from evotol.errors import ValidationError
    from evotol._runtime.output_paths import input_file
    from evotol.reporting.export import write_tolerance_table

    path = input_file(args.study_json, "study JSON", "the NAME.json written by 'evotol run'")
    try:
        summary = json.loads(Path(path).read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValidationError("study JSON", str(path), f"a JSON file ({exc})") from None
    if not isinstance(summary, dict) or "display_units" not in summary or "sources" not in summary:
        raise ValidationError("study JSON", str(path), "the JSON of a user study written by 'evotol run' "
                                                       "(with display_units and sources)")
    out = Path(args.out) if args.out else Path(path).with_name(f"{summary['name']}_tolerances.xlsx")
    written = write_tolerance_table(summary, out, args.method)
    if summary.get("callouts") and written.suffix.lower() == ".xlsx":     # drawing callouts: two more sheets (issue 35)
        from evotol.reporting.callout_drawing import write_callout_exports

        write_callout_exports(summary, written.with_name(f"{summary['name']}_drawing.csv"), written)
    print(f"[evotol] wrote {written}")
    return 0

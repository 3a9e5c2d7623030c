"""``evotol schema``: print the JSON Schema of the study file (``evotol.studyfile.schema``).

Editors that read JSON Schema for TOML complete and check a study file's keys with it; the same
schema ships as ``docs/study.schema.json``.
"""
from __future__ import annotations


def register(subparsers) -> None:
    """Add the ``schema`` sub-command to the ``evotol`` parser.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        What ``ArgumentParser.add_subparsers()`` returned; the new parser's ``func`` default
        is :func:`cmd_schema`.
    """
    p = subparsers.add_parser("schema", help="print the JSON Schema of the study file (for editors)",
                              description="Print the JSON Schema of the study file on standard output, "
                                          "generated from the keys evotol's reader accepts. Save it and point "
                                          "your editor at it (docs/getting_started.md).")
    p.add_argument("--json", action="store_true", help="print it as JSON (the only form; accepted for symmetry)")
    p.set_defaults(func=cmd_schema)


def cmd_schema(args) -> int:
    """Run ``evotol schema``: the schema as JSON (indent 2) on standard output.

    Parameters
    ----------
    args : argparse.Namespace
        No options are read.

    Returns
    -------
    int
        Exit status 0.
    """
    from evotol.studyfile.schema import schema_text

    print(schema_text(), end="")
    return 0

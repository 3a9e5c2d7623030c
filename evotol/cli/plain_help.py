"""Help texts in plain words: the sub-commands take their descriptions from module docstrings,
which carry reStructuredText markup (````code````, ``:func:`name```), issue numbers and source paths
for the developers. :func:`plain` turns such text into what a terminal user reads, and
:func:`plain_parser` applies it to every description and option help of a parser (issue 40).
"""
from __future__ import annotations

import argparse
import re

_ROLE = re.compile(r":[a-z]+:`~?([^`]+)`")                 # :func:`evotol.x.y` -> evotol.x.y
_CODE = re.compile(r"``([^`]+)``")                         # ``evotol run`` -> 'evotol run'
_ISSUE = re.compile(r"\s*\((?:see |as in )?issues? \d+[^()]*\)|,? (?:see )?issues? \d+(?: item \d+)?")
_SOURCE = re.compile(r"\s*\((?:see )?[\w./]+\.py\)")      # (evotol/reporting/export.py)


def plain(text: str | None) -> str | None:
    """``text`` without reStructuredText markup, issue numbers or source-file paths.

    Parameters
    ----------
    text : str or None
        A description or help text (None and argparse's ``SUPPRESS`` pass through).

    Returns
    -------
    str or None
        The text a terminal user reads: code in single quotes, cross-references as their names.

    Examples
    --------
    >>> plain("a study file is named as such (issue 27); see ``evotol describe ur5``")
    "a study file is named as such; see 'evotol describe ur5'"
    """
    if not text or text == argparse.SUPPRESS:
        return text
    text = _ROLE.sub(lambda m: m.group(1), text)
    text = _ISSUE.sub("", text)
    text = _SOURCE.sub("", text)
    return _CODE.sub(lambda m: f"'{m.group(1)}'", text)


def plain_parser(parser: argparse.ArgumentParser) -> None:
    """Apply :func:`plain` to ``parser``'s description and every option's help, and to its
    sub-commands' in turn.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The parser, changed in place.
    """
    parser.description = plain(parser.description)
    parser.epilog = plain(parser.epilog)
    for action in parser._actions:
        action.help = plain(action.help)
        if isinstance(action, argparse._SubParsersAction):
            for choice in action._choices_actions:
                choice.help = plain(choice.help)
            for sub in set(action.choices.values()):
                plain_parser(sub)

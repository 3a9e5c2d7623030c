"""Check keyword arguments taken from a study file against a function's signature, with a
"did you mean" for typos (``pop_sise`` -> ``pop_size``), before anything runs.

Python's own ``TypeError: got an unexpected keyword argument`` arrives only when the function is
called -- after the earlier methods of a study have computed -- and names neither the table nor
the valid keys (issue 15).

The parameters several definitions of this module share are described once, here.

Parameters
----------
valid : iterable of str
    The names accepted.
"""
from __future__ import annotations

import difflib
import fnmatch
import inspect
from typing import Callable, Iterable, Mapping

from evotol.errors import ValidationError


def nearest(name: str, valid: Iterable[str]) -> str | None:
    """The valid name closest to ``name`` (difflib ratio >= 0.6), or None.

    Parameters
    ----------
    name : str
        The name given (a possible typo).

    Returns
    -------
    str or None
        The closest valid name, or None when none is close enough.
    """
    close = difflib.get_close_matches(str(name), list(valid), n=1, cutoff=0.6)
    return close[0] if close else None


def did_you_mean(name: str, valid: Iterable[str]) -> str:
    """``" (did you mean 'x'?)"`` when a valid name is close to ``name``, else ``""``.

    Parameters
    ----------
    name : str
        The name given.

    Returns
    -------
    str
        The suffix to append to an error message (with its leading space), or ``""``.
    """
    guess = nearest(name, valid)
    return f" (did you mean {guess!r}?)" if guess else ""


def unknown_key_message(key: str, valid: Iterable[str]) -> str:
    """'a key among [...]' with '(did you mean ...?)' when one is close.

    Parameters
    ----------
    key : str
        The unknown key.
    valid : iterable of str
        The keys accepted (listed sorted).

    Returns
    -------
    str
        The ``expected`` text of a :class:`~evotol.errors.ValidationError`.
    """
    valid = sorted(valid)
    return f"a key among {valid}" + did_you_mean(key, valid)


def check_table_keys(table, valid: Iterable[str], where: str) -> None:
    """The one check that a table's keys are known.

    Parameters
    ----------
    table : mapping
        A table of a study file or description (TOML).
    valid : iterable of str
        The keys it may have.
    where : str
        Its place, named in the error (``""`` at the top level).

    Raises
    ------
    ValidationError
        ``table`` is not a table, or ``where.KEY = VALUE: expected a key among [...] (did you mean
        'x'?)`` for its first unknown key.
    """
    valid = list(valid)
    if not isinstance(table, Mapping):
        raise ValidationError(where, table, f"a table with keys among {sorted(valid)}")
    for k in table:
        if k not in valid:
            raise ValidationError(f"{where}.{k}" if where else k, table[k], unknown_key_message(k, valid))


def keywords_of(func: Callable, exclude: Iterable[str] = ()) -> list[str] | None:
    """Keyword names ``func`` accepts (None if it takes ``**kwargs``: anything goes).

    Parameters
    ----------
    func : callable
        The function whose signature is read.
    exclude : iterable of str, optional
        Names to leave out (those evotol sets itself).

    Returns
    -------
    list of str or None
        The positional-or-keyword and keyword-only parameter names in signature order, less
        ``exclude``; None when ``func`` takes ``**kwargs``.
    """
    params = inspect.signature(func).parameters.values()
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params):
        return None
    skip = set(exclude)
    return [p.name for p in params
            if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
            and p.name not in skip]


def check_keywords(func: Callable, kwargs: Mapping, field: str, exclude: Iterable[str] = ()) -> None:
    """ValidationError ``field.KEY = value: expected a key among [...] (did you mean 'x'?)`` for the
    first key of ``kwargs`` that ``func`` does not accept (or that is in ``exclude``, i.e. set by
    evotol itself); also when ``kwargs`` is not a table.

    Parameters
    ----------
    func : callable
        The function the keywords will be passed to; nothing is checked when it takes ``**kwargs``.
    kwargs : mapping
        The keyword arguments from the study file.
    field : str
        The study-file table they come from, named in the error (e.g. ``"methods.ga"``).
    exclude : iterable of str, optional
        Keywords evotol sets itself, not accepted from the file.

    Raises
    ------
    ValidationError
        ``kwargs`` is not a mapping, or one of its keys is not a keyword of ``func`` (or is
        excluded).
    """
    if not isinstance(kwargs, Mapping):
        raise ValidationError(field, kwargs, "a table of keyword arguments, e.g. { pop_size = 60 }")
    valid = keywords_of(func, exclude)
    if valid is None:
        return
    for key, value in kwargs.items():
        if key not in valid:
            raise ValidationError(f"{field}.{key}", value, unknown_key_message(key, valid))


def expand_patterns(table: Mapping, valid: Iterable[str], where: str, what: str) -> dict:
    """A table whose keys may be fnmatch patterns (``"l?"``, ``"P?.shift_*"``), one entry per name.

    A name written exactly keeps its own value; a pattern gives its value to every valid name it
    matches (issue 41: one entry per source or joint is no way to write 42 of them).

    Parameters
    ----------
    table : Mapping
        Names or patterns -> values, as written.
    where : str
        The table's field in errors (``"sources"``, ``"assembly.joints"``).
    what : str
        What the names are, in errors (``"source"``, ``"joint variable"``).

    Returns
    -------
    dict
        Exact keys as written (unknown ones too: the caller refuses them), then each pattern's
        matches in the order of ``valid``.

    Raises
    ------
    evotol.errors.ValidationError
        ``<where>.<pattern>`` when a pattern matches no valid name, or when two patterns match the
        same name (its value would depend on their order).
    """
    valid = list(valid)
    out = {k: v for k, v in table.items() if not any(c in str(k) for c in "*?[")}
    claimed = {}
    for pat, v in table.items():
        if pat in out:
            continue
        hit = [n for n in valid if fnmatch.fnmatchcase(n, pat)]
        if not hit:
            raise ValidationError(f"{where}.{pat}", v, f"a pattern matching some {what}: " + unknown_key_message(pat, valid))
        for n in hit:
            if n in claimed:
                raise ValidationError(f"{where}.{pat}", v, f"patterns that do not overlap: {claimed[n]!r} already matches "
                                      f"{n} (give {n} its own entry to override both)")
            claimed[n] = pat
            out.setdefault(n, v)
    return out

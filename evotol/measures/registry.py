"""Accuracy measures by name: the built-ins and the entry-point group ``evotol.measures``.

scikit-learn's scorers (``sklearn/metrics/_scorer.py``: named scorers, ``get_scorer(name)``) are the
model. A package adds a measure without touching evotol by declaring, in its ``pyproject.toml``::

    [project.entry-points."evotol.measures"]
    my_measure = "my_package.measures:MY_MEASURE"

The entry point names a :class:`evotol.measures.protocol.Measure` instance (or a class, instantiated
without arguments) whose ``name`` equals the entry point's name. ``Requirement(measure="my_measure")``
then selects it; :func:`evotol.core.measure_checks.check_measure` proves it follows the contract.
"""
from __future__ import annotations

import importlib
from evotol._runtime.plugins import group_entry_points

from evotol.measures.protocol import Measure
from evotol.errors import ValidationError
from evotol._runtime.keyword_checks import did_you_mean

GROUP = "evotol.measures"

#: name -> "module:attribute" of the built-in measures (imported on first use)
BUILTIN = {
    "worst_case": "evotol.measures.builtin.worst_case:WORST_CASE",
    "rss": "evotol.measures.builtin.rss:RSS",
    "mc_quantile": "evotol.measures.builtin.mc_quantile:MC_QUANTILE",
    "yield": "evotol.measures.builtin.statistical_yield:YIELD",
}

_loaded: dict[str, Measure] = {}


def _instance(obj, name: str, where: str) -> Measure:
    if isinstance(obj, type):
        obj = obj()
    if not callable(getattr(obj, "evaluate", None)) or getattr(obj, "name", None) != name:
        raise ValidationError(f"measure {name!r}", where, f"a Measure (an object with evaluate() and name = {name!r})")
    return obj


def _entry_points() -> dict:
    return {ep.name: ep for ep in group_entry_points(GROUP)}


def names() -> tuple[str, ...]:
    """Names of every registered measure: the built-ins, then the entry points.

    Returns
    -------
    tuple of str
        The built-in names, then the other entry-point names sorted.
    """
    return tuple(BUILTIN) + tuple(sorted(set(_entry_points()) - set(BUILTIN)))


def get(name: str, field: str = "measure") -> Measure:
    """The measure registered as ``name``.

    Parameters
    ----------
    name : str
        A built-in measure (``worst_case``, ``rss``, ``mc_quantile``, ``yield``) or an entry
        point of the group ``evotol.measures``.
    field : str
        The field named in the error (e.g. ``"requirement.measure"``).

    Returns
    -------
    Measure
        The measure instance (loaded once, then cached).

    Raises
    ------
    ValidationError
        ``name`` is not registered (with the closest registered name), or its entry point does
        not load a measure.
    """
    if name in _loaded:
        return _loaded[name]
    if name in BUILTIN:
        mod, _, attr = BUILTIN[name].partition(":")
        measure = _instance(getattr(importlib.import_module(mod), attr), name, BUILTIN[name])
    else:
        eps = _entry_points() if isinstance(name, str) else {}
        if name not in eps:
            valid = names()
            raise ValidationError(field, name, f"one of {valid}" + did_you_mean(str(name), valid))
        measure = _instance(eps[name].load(), name, eps[name].value)
    _loaded[name] = measure
    return measure


def available() -> dict[str, Measure]:
    """Every registered measure by name (loads the entry points).

    Returns
    -------
    dict of str to Measure
        Name -> measure, in the order of :func:`names`.

    Raises
    ------
    evotol.errors.ValidationError
        An entry point that does not load a measure named as the entry point.
    """
    return {n: get(n) for n in names()}

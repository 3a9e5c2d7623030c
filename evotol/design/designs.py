"""Designs of experiments: which entries a study evaluates (Deng 2012 Sec. VII.1.2).

:func:`full_factorial`, :func:`random_subset` (the thesis's 1000 of 32 768 entries, seeded) and
:func:`latin_hypercube` (continuous ranges, log-uniform where ``log=True``) each return a pandas
DataFrame with an ``entry`` id column and one column per factor; the factor definitions travel
in ``df.attrs``.

The parameters several definitions of this module share are described once, here.

Parameters
----------
factors : sequence of Factor
    The design variables, each with discrete ``levels``.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np
import pandas as pd

from evotol.design.factors import ENTRY, Factor, _attach, _check_factors
from evotol.errors import ValidationError


def n_factorial(factors: Sequence[Factor]) -> int:
    """Number of entries of the full factorial (product of the level counts).

    Returns
    -------
    int
        The product of the numbers of levels.

    Raises
    ------
    ValidationError
        ``factors`` is empty, holds something other than a :class:`~evotol.design.factors.Factor`, or has duplicate or
        reserved names (``entry``, ``feasible``, ``error``, ``source``), or a factor has no levels.
    """
    factors = _check_factors(factors)
    missing = [f.name for f in factors if not f.is_discrete]
    if missing:
        raise ValidationError("factors without levels", missing, "levels on every factor of a factorial design")
    return int(np.prod([len(f.levels) for f in factors], dtype=np.int64))


def factorial_entries(factors: Sequence[Factor], ids) -> pd.DataFrame:
    """Entries of the full factorial with the given ids (mixed radix, last factor fastest).

    Parameters
    ----------
    ids : array_like of int
        Entry ids in ``[0, n_factorial(factors) - 1]``; id 0 has every factor at its lowest level.

    Returns
    -------
    pandas.DataFrame
        One row per id, in the order given: the ``entry`` column (the ids) and one column per
        factor (its level, in the factor's column unit). No factor metadata in ``attrs``.

    Raises
    ------
    ValidationError
        ``factors`` is empty, holds something other than a :class:`~evotol.design.factors.Factor`, or has duplicate or
        reserved names (``entry``, ``feasible``, ``error``, ``source``); a factor has no levels; or an id is out of range.
    """
    factors = _check_factors(factors)
    total = n_factorial(factors)
    ids = np.asarray(ids, dtype=np.int64)
    if ids.size and (ids.min() < 0 or ids.max() >= total):
        raise ValidationError("entry ids", (int(ids.min()), int(ids.max())), f"ids in [0, {total - 1}]")
    cols, rest = {}, ids.copy()
    for f in reversed(factors):
        k = len(f.levels)
        cols[f.name] = np.asarray(f.levels)[rest % k]
        rest //= k
    df = pd.DataFrame({ENTRY: ids, **{f.name: cols[f.name] for f in factors}})
    return df


def full_factorial(factors: Sequence[Factor]) -> pd.DataFrame:
    """All combinations of the factors' levels (Deng 2012 Sec. VII.1.2: 4^5 * 2^5 = 32 768).

    Returns
    -------
    pandas.DataFrame
        ``n_factorial(factors)`` rows, ``entry`` 0, 1, ... (see :func:`factorial_entries`), one
        column per factor (column units); ``attrs["evotol"]`` holds the factor definitions and
        ``design = "full factorial"``.

    Raises
    ------
    ValidationError
        ``factors`` is empty, holds something other than a :class:`~evotol.design.factors.Factor`, or has duplicate or
        reserved names (``entry``, ``feasible``, ``error``, ``source``), or a factor has no levels.
    """
    factors = _check_factors(factors)
    df = factorial_entries(factors, np.arange(n_factorial(factors)))
    return _attach(df, factors, "full factorial")


def random_subset(factors: Sequence[Factor], n: int, seed: int = 0) -> pd.DataFrame:
    """``n`` distinct entries of the full factorial drawn uniformly without replacement.

    The thesis plots "1000 entries" of its 32 768-entry factorial (Fig. VII.2); the subset is
    reproducible from ``seed`` and its ids are the factorial ids, so it can be joined with (or
    read out of) an evaluated full factorial.

    Parameters
    ----------
    n : int
        Number of entries, in ``[1, n_factorial(factors)]``.
    seed : int, default 0
        Seed of the random generator (``numpy.random.default_rng``).

    Returns
    -------
    pandas.DataFrame
        ``n`` rows sorted by their factorial id (``entry``), one column per factor (column
        units); ``attrs["evotol"]`` holds the factor definitions, ``design = "random subset"``,
        ``n`` and ``seed``.

    Raises
    ------
    ValidationError
        ``factors`` is empty, holds something other than a :class:`~evotol.design.factors.Factor`, or has duplicate or
        reserved names (``entry``, ``feasible``, ``error``, ``source``); a factor has no levels; or ``n`` is not an integer in range.
    """
    factors = _check_factors(factors)
    total = n_factorial(factors)
    if not (isinstance(n, (int, np.integer)) and 1 <= n <= total):
        raise ValidationError("random_subset n", n, f"an integer in [1, {total}]")
    ids = np.sort(np.random.default_rng(seed).choice(total, size=int(n), replace=False))
    return _attach(factorial_entries(factors, ids), factors, "random subset", n=int(n), seed=seed)


def latin_hypercube(factors: Sequence[Factor], n: int, seed: int = 0) -> pd.DataFrame:
    """``n`` Latin-hypercube entries (scipy.stats.qmc) over the factors' ranges.

    Continuous factors are sampled uniformly in their range (log-uniformly when ``log``);
    discrete factors take ``levels[floor(u * n_levels)]``, i.e. each level in equal share.

    Parameters
    ----------
    factors : sequence of Factor
        The design variables (continuous ranges or discrete levels).
    n : int
        Number of entries, >= 1.
    seed : int, default 0
        Seed of ``scipy.stats.qmc.LatinHypercube``.

    Returns
    -------
    pandas.DataFrame
        ``n`` rows, ``entry`` 0 to ``n - 1``, one column per factor (column units);
        ``attrs["evotol"]`` holds the factor definitions, ``design = "latin hypercube"``, ``n``
        and ``seed``.

    Raises
    ------
    ValidationError
        ``factors`` is empty, holds something other than a :class:`~evotol.design.factors.Factor`, or has duplicate or
        reserved names (``entry``, ``feasible``, ``error``, ``source``); or ``n`` is not a positive integer.
    """
    from scipy.stats import qmc

    factors = _check_factors(factors)
    if not (isinstance(n, (int, np.integer)) and n >= 1):
        raise ValidationError("latin_hypercube n", n, "a positive integer")
    u = qmc.LatinHypercube(d=len(factors), seed=seed).random(int(n))
    cols = {}
    for j, f in enumerate(factors):
        if f.is_discrete:
            k = len(f.levels)
            cols[f.name] = np.asarray(f.levels)[np.minimum((u[:, j] * k).astype(int), k - 1)]
        else:
            cols[f.name] = f.to_unit(u[:, j])
    df = pd.DataFrame({ENTRY: np.arange(int(n), dtype=np.int64), **cols})
    return _attach(df, factors, "latin hypercube", n=int(n), seed=seed)


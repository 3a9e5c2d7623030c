"""``rng=`` as SciPy takes it (SPEC 7): an integer or a ``numpy.random.Generator``, beside the
older ``seed=`` (issue 40).

evotol's randomised methods (the GA and NSGA-II through pymoo, the Monte Carlo checks through
``scipy.stats.qmc``) are reproducible from an integer seed, which each result records. A Generator
is therefore drawn from once, for the integer seed of the run: the same Generator state gives the
same run, the result names the seed it drew, and a Generator shared across calls gives each call
its own seed.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import ValidationError

#: seeds are drawn in [0, SEED_LIMIT): what pymoo and numpy's legacy seeding accept
SEED_LIMIT = 2**32


def seed_from(rng=None, seed=0) -> int:
    """The integer seed of a run given ``rng=`` (new) and ``seed=`` (old) keywords.

    Parameters
    ----------
    rng : int, numpy.random.Generator or None
        An integer in ``[0, 2**32)`` is the seed; a Generator gives one draw
        (``rng.integers(2**32)``); None leaves ``seed``.
    seed : int or numpy.random.Generator
        The older keyword (a Generator is taken as ``rng``); ignored, and required to be at its
        default 0 or None, when ``rng`` is given.

    Returns
    -------
    int
        The seed, ``0 <= seed < 2**32``.

    Raises
    ------
    ValidationError
        ``rng`` neither an integer in range nor a Generator, or both ``rng`` and a non-default
        ``seed``.

    Examples
    --------
    >>> import numpy as np
    >>> seed_from(rng=7), seed_from(seed=3), seed_from()
    (7, 3, 0)
    >>> seed_from(rng=np.random.default_rng(1)) == seed_from(rng=np.random.default_rng(1))
    True
    """
    if isinstance(seed, np.random.Generator):
        if rng is not None:
            raise ValidationError("seed", seed, "no seed when rng is given (rng replaces seed)")
        rng, seed = seed, 0
    if rng is None:
        return seed
    if seed not in (0, None):
        raise ValidationError("seed", seed, "no seed when rng is given (rng replaces seed)")
    if isinstance(rng, np.random.Generator):
        return int(rng.integers(SEED_LIMIT))
    if isinstance(rng, (int, np.integer)) and not isinstance(rng, bool) and 0 <= rng < SEED_LIMIT:
        return int(rng)
    raise ValidationError("rng", rng, "an integer in [0, 2**32) or a numpy.random.Generator")

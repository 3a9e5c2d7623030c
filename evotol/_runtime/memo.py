"""A function of an optimiser's point remembered for the last point it was asked at.

SciPy's SLSQP evaluates a constraint at a point and then, at the same point, its jacobian; when both
come from one computation (a figure and its gradient), :func:`last_point` makes it run once. The
value returned is the very object the computation returned, so the optimiser sees the same bits.
"""
from __future__ import annotations

import numpy as np


def last_point(f):
    """``f`` remembered for the last point ``x`` (compared byte for byte).

    Parameters
    ----------
    f : callable
        A pure function of a 1-D float array (SLSQP's variables); its result must not be changed in
        place by the callers.

    Returns
    -------
    callable
        ``at(x)``: ``f(x)``, computed again only when ``x`` differs from the last point.
    """
    last = [None, None]

    def at(x):
        key = np.asarray(x, float).tobytes()
        if last[0] != key:
            last[0], last[1] = key, f(x)
        return last[1]
    return at


__all__ = ["last_point"]

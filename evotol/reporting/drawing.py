"""A tolerance as a drawing states it: the zone's text in display units (``±t`` or
``+upper / −lower``), one function for the page and the terminal (issue 34: a one-sided zone
``+0 / −288.6 µm`` was shown as ``± 288.6``)."""
from __future__ import annotations

import math

from evotol.units.display import DisplayUnits, number


def zone_text(zone: dict, u: DisplayUnits, si_unit: str, dim: int = 1) -> str:
    """A tolerance zone as a drawing writes it, in display units: ``±144.3`` when it is symmetric
    about the nominal, else the two deviations ``+0 / −288.6`` (never a doubled or halved ±).

    Parameters
    ----------
    zone : dict
        ``lower`` and ``upper`` deviations from the nominal (SI, m or rad), as
        :func:`evotol.summaries.user_study.tolerance_zone` gives them.
    u : DisplayUnits
        The study's display units.
    si_unit : str
        The source's SI unit (``"m"`` or ``"rad"``).
    dim : {1, 2, 3}
        The source's dimension: a disc or ball zone (2, 3) is stated by its radius, ``r ≤ 1.554``.

    Returns
    -------
    str
        The zone's text (4 significant digits, no unit).
    """
    lo, hi = float(u.convert(zone["lower"], si_unit)), float(u.convert(zone["upper"], si_unit))
    if dim > 1:         # a disc or ball: the error vector's length within r (no sign, no axis)
        return f"r ≤ {number(hi)}"
    if abs(lo + hi) <= 1e-9 * max(abs(lo), abs(hi)):
        return f"±{number(hi)}"

    def signed(v):
        return "0" if v == 0 else f"+{number(v)}" if v > 0 else f"−{number(-v)}"
    return f"{signed(hi)} / {signed(lo)}"


def drawing_check_text(check: dict) -> str:
    """The re-check of a design rounded to the drawing precision, in one line (page and workbook).

    Parameters
    ----------
    check : dict
        One method's entry of a study summary's ``drawing`` block
        (:func:`evotol.summaries.drawing.rounded_design`).

    Returns
    -------
    str
        E.g. ``"rounded inward to 0.1 µm: normalised error 0.998, meets the requirement (cost 135.7)"``.
    """
    steps = ", ".join(f"{p:.{max(0, -math.floor(math.log10(p) + 1e-9))}f} {u}" for u, p in check["precision"].items()) \
        or "no rounding"
    if check["vanished"]:
        return f"rounded to {steps}: the zones of {', '.join(check['vanished'])} vanish; state a finer drawing precision"
    verdict = "meets the requirement" if check["meets"] else "misses the requirement"
    return (f"rounded inward to {steps} (fixed sources outward): the drawn zones give normalised error "
            f"{check['normalised_error']:.6g}, {verdict} (cost {check['cost']:.6g})")

"""A tolerance as a drawing states it: the zone's text in display units (``±t`` or
``+upper / −lower``), one function for the page and the terminal (issue 34: a one-sided zone
``+0 / −288.6 µm`` was shown as ``± 288.6``)."""
from __future__ import annotations

from evotol.units.display import DisplayUnits, number


def zone_text(zone: dict, u: DisplayUnits, si_unit: str) -> str:
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

    Returns
    -------
    str
        The zone's text (4 significant digits, no unit).
    """
    lo, hi = float(u.convert(zone["lower"], si_unit)), float(u.convert(zone["upper"], si_unit))
    if abs(lo + hi) <= 1e-9 * max(abs(lo), abs(hi)):
        return f"±{number(hi)}"

    def signed(v):
        return "0" if v == 0 else f"+{number(v)}" if v > 0 else f"−{number(-v)}"
    return f"{signed(hi)} / {signed(lo)}"

"""Which sources a feasible design holds at the shop's floors (issue 41 item 1), as the page and
the terminal state it -- one text for both, read from the JSON summary (``results.*.at_floor``,
:func:`evotol.core.shop.at_floors`). The infeasible case is an error naming them
(:func:`evotol.core.shop.check_floors_feasible`).
"""
from __future__ import annotations


def _zone(v: float, key: str, unit: str) -> str:
    """A floor as the page shows it: µm for a length, arcsec for an angle."""
    return f"{key} >= {v * 1e6:.4g} µm" if unit == "m" else f"{key} >= {v * 206264.80624709636:.4g} arcsec"


def floor_lines(summary: dict) -> list[str]:
    """One line per method whose design holds sources at their ``[shop]`` floor.

    Parameters
    ----------
    summary : dict
        A user study's JSON summary (SI); no lines without ``[shop]`` floors.

    Returns
    -------
    list of str
        E.g. ``"optimum: 6 sources sit at their [shop] floor: elbow_joint.position, ...
        (bore position >= 10 µm); a process that holds a smaller zone there would lower the cost"``.
    """
    units = {s["name"]: s.get("unit", "m") for s in summary.get("sources", [])}
    out = []
    for m, r in (summary.get("results") or {}).items():
        rows = r.get("at_floor") or []
        if not rows:
            continue
        keys = {}
        for row in rows:
            unit = next((u for n, u in units.items() if n == row["source"] or n.startswith(row["source"] + ".")), "m")
            keys.setdefault(row["key"], _zone(row["floor"], row["key"], unit))
        verdict = "the requirement is met" if r.get("feasible", True) else "the requirement is not met"
        out.append(f"{m}: {len(rows)} source{'s' if len(rows) > 1 else ''} sit{'' if len(rows) > 1 else 's'} at "
                   f"{'their' if len(rows) > 1 else 'its'} [shop] floor: {', '.join(row['source'] for row in rows)} "
                   f"({'; '.join(keys.values())}); {verdict}, and a process that holds a smaller zone there "
                   "would lower the cost")
    return out

"""Units, in one room: the SI values evotol computes in, the JSON unit convention of its files
(:mod:`.json_convention`, docs/units.md) and the display units of its tables (:mod:`.display`:
µm or mm, arcsec, mrad or deg).

Inside evotol every length is in metres and every angle in radians; a number in another unit is
converted at the edge (a study file, a report) with the factors below, never with a literal of its own.
"""
from __future__ import annotations

import math

from evotol.units.json_convention import (
    CONVENTION, COST, COUNT, KEYS, RELATIVE, SUFFIXES, make_units_block, numbers_without_unit, unit_of, units_block,
)

#: the SI units an error source or a workspace coordinate may declare (values inside are SI)
UNITS = ("m", "rad")
#: metres per millimetre
MM = 1e-3
#: metres per micrometre
UM = 1e-6
#: radians per degree
DEG = math.pi / 180

__all__ = ["UNITS", "MM", "UM", "DEG", "CONVENTION", "COST", "COUNT", "KEYS", "RELATIVE", "SUFFIXES",
           "make_units_block", "numbers_without_unit", "unit_of", "units_block"]

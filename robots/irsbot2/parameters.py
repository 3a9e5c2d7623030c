"""The IRSBot-2's thesis parameters (Deng 2012, Tabs. VI.1-VI.2 and VI.4-VI.5), SI units.

Units: metres and radians (``MM`` and ``PI`` are the unit and constant the tables are written with).
"""
from __future__ import annotations

import numpy as np
from evotol.units import MM

PI = np.pi

#: Tab. VI.1-VI.2 (used for Figs. VI.1-VI.3): b, d, alpha_d, beta, e, l1, l2, a1, a2, p
THESIS_VI1 = dict(b=50 * MM, d=50 * MM, alpha_d=PI / 6, beta=PI / 6, e=0.0, l1=50 * MM, l2=50 * MM,
                  a1=30 * MM, a2=15 * MM, p=25 * MM)
#: Tab. VI.4-VI.5 (used for Figs. VI.4-VI.5): as VI.1-VI.2 with beta = pi/4
THESIS_VI4 = dict(THESIS_VI1, beta=PI / 4)

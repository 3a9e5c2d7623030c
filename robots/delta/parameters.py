"""The 47 geometric error parameters of the Delta robot (Brahmia et al. 2023, eq. 5 / Table 2, eq. 12).

Error parameters (eq. 5 / Table 2; the 47 of eq. 12): ``Ra``, ``Rb`` and per leg ``d_i``,
``La_i``, ``Lb_i``, ``alpha1_i``, ``alpha3_i``, ``alpha5_i``, ``alpha6_i``, ``q1_i`` ... ``q7_i``,
``theta_i``, all entering the KK transforms as ``nominal + error`` exactly as in Table 2
(:mod:`evotol.robots.delta.chains`). Lengths in m, angles in rad.
"""
from __future__ import annotations

import numpy as np

LEG_PARAMETERS = ("d", "La", "Lb", "alpha1", "alpha3", "alpha5", "alpha6",
                  "q1", "q2", "q3", "q4", "q5", "q6", "q7", "theta")
LINEAR_LEG = ("d", "La", "Lb")
#: the 47 error parameters of eq. (12), in the order of Tables A1-A2.
PARAMETER_NAMES: tuple[str, ...] = ("Ra", "Rb") + tuple(f"{p}_{i}" for i in (1, 2, 3) for p in LEG_PARAMETERS)
#: the error parameters that are lengths (m): Ra, Rb and every d, La, Lb
LINEAR: tuple[str, ...] = tuple(n for n in PARAMETER_NAMES if n in ("Ra", "Rb") or n.split("_")[0] in LINEAR_LEG)
#: the error parameters that are angles (rad): the alphas, joint offsets q and theta
ANGULAR: tuple[str, ...] = tuple(n for n in PARAMETER_NAMES if n not in LINEAR)
_INDEX = {n: k for k, n in enumerate(PARAMETER_NAMES)}
# (n_params,) index arrays: column of parameter p for leg i -> _LEG_COL[p][i]
_LEG_COL = {p: np.array([_INDEX[f"{p}_{i}"] for i in (1, 2, 3)]) for p in LEG_PARAMETERS}

_DESCRIPTIONS = {
    "Ra": "base radius O0-A_i (all legs)", "Rb": "platform radius P-B_i (all legs)",
    "d": "half-width of the parallelogram bars", "La": "upper-arm length", "Lb": "rod length (both rods)",
    "alpha1": "twist of the actuated axis (KK alpha_1)", "alpha3": "twist of rod-1 upper hinge (alpha_3)",
    "alpha5": "twist of the lower-bar hinge (alpha_5)", "alpha6": "twist of rod-2 upper hinge (alpha_6)",
    "q1": "actuated joint offset", "q2": "upper-bar joint offset", "q3": "rod-1 upper hinge offset",
    "q4": "rod-1 lower hinge offset", "q5": "lower-bar joint offset", "q6": "rod-2 upper hinge offset",
    "q7": "rod-2 lower hinge offset", "theta": "angular position of the leg on the base",
}

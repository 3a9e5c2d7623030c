"""Problems of the process-selection studies and benchmarks (data only; see docs/process_selection.md).

* The **one-way (overrunning) clutch** of Chase, *Dimensioning and Tolerancing Handbook* §14.7
  (and Chase, Greenwood, Loosli & Hauglund 1990): contact angle
  ``φ = arccos((a + c)/(e − c))`` (handbook eq. 14.6) of hub width ``a``, roller radius ``c`` and
  ring radius ``e``. Nominal a = 27.645 mm, c = 11.43 mm, e = 50.8 mm give φ0 = 7.018°; these are
  the diameters 55.29 / 22.86 / 101.6 mm the GA literature quotes, halved (same geometry).
* A **linear stack** (gap of a shaft/housing/spacer chain, signs ±1) with the same process catalogue.

The process catalogue (``A + B/t^k`` with t in mm, Chase's reciprocal-power form, ranges per
process) is evotol's illustrative data, **not** the published tables: those could not be
retrieved in this session (see the doc page). Cost units are arbitrary.
"""
from __future__ import annotations

import numpy as np

from cost_models.power import PowerCost
from evotol.allocators.process import Process, ProcessProblem, assembly_problem
from robots.assembly import AssemblyFunction, LinearStack

MM = 1e-3

#: process -> (lower mm, upper mm, fixed cost A, B, k): cost = A + B / t_mm^k on [lower, upper]
CATALOGUE = {
    "mill": (0.05, 0.30, 1.0, 0.40, 1.0),
    "turn": (0.02, 0.15, 2.0, 0.12, 1.0),
    "grind": (0.005, 0.05, 4.0, 0.02, 1.0),
    "hone": (0.002, 0.012, 6.0, 0.006, 1.0),
}


def process(name: str, size_factor: float = 1.0) -> Process:
    """A catalogue process; ``size_factor`` scales its costs (bigger parts cost more)."""
    lo, hi, A, B, k = CATALOGUE[name]
    return Process(name, PowerCost(size_factor * B, k, scale=MM), lo * MM, hi * MM, size_factor * A)


def clutch_angle(a, c, e):
    """Contact angle φ (rad) of the one-way clutch, Chase handbook eq. 14.6."""
    return np.arccos((a + c) / (e - c))


CLUTCH_NOMINAL = {"a": 27.645 * MM, "c": 11.43 * MM, "e": 50.8 * MM}
#: allowed deviation of the contact angle: ±2° (evotol's choice for the benchmark)
CLUTCH_LIMIT_RAD = float(np.radians(2.0))
CLUTCH_PROCESSES = {"a": ("mill", "turn", "grind"), "c": ("turn", "grind", "hone"), "e": ("turn", "grind", "hone")}
#: published numbers retrieved in this session (Chase, D&T Handbook §14.7)
CLUTCH_PUBLISHED = {
    "source": "K. W. Chase, 'Minimum-cost tolerance allocation', Dimensioning and Tolerancing Handbook (P. Drake, ed.), "
              "McGraw-Hill 1999, ch. 14, §14.7 'One-way clutch assembly'; Chase, Greenwood, Loosli & Hauglund, "
              "Manufacturing Review 3(1), 1990",
    "assembly_function": "phi = arccos((a + c) / (e - c)), eq. 14.6",
    "rss_angle_variation_rad": 0.01159,
    "rss_angle_variation_deg": 0.664,
    "tables": None,
    "note": "only the opening of §14.7 was retrievable: the transfer function and the RSS variation of the handbook's "
            "tolerances (0.01159 rad); the nominal tolerances, cost coefficients and the allocated tables were not, "
            "so no published cost can be recomputed here",
}


def clutch_assembly() -> AssemblyFunction:
    return AssemblyFunction(clutch_angle, CLUTCH_NOMINAL, {"phi": CLUTCH_LIMIT_RAD}, name="one-way clutch",
                            groups={"a": "hub", "c": "roller", "e": "ring"})


def clutch_problem(measure: str = "worst_case") -> ProcessProblem:
    asm = clutch_assembly()
    size = {"a": 1.0, "c": 0.6, "e": 1.4}
    procs = {n: [process(p, size[n]) for p in CLUTCH_PROCESSES[n]] for n in asm.source_names}
    return assembly_problem(asm, processes=procs, measure=measure)


#: linear stack: gap = housing − (shaft shoulder + spacer + bearing + ...), dimension -> sign
STACK_SIGNS = {"housing": 1.0, "shoulder": -1.0, "spacer1": -1.0, "bearing": -1.0, "spacer2": -1.0, "circlip": -1.0}
STACK_SIZE = {"housing": 1.6, "shoulder": 1.0, "spacer1": 0.5, "bearing": 0.8, "spacer2": 0.5, "circlip": 0.4}
STACK_GAP_LIMIT = 0.10 * MM   # gap within ±0.10 mm (worst case) -- evotol's choice


def stack_problem(measure: str = "worst_case", n_dims: int | None = None, limit: float = STACK_GAP_LIMIT,
                  names=("mill", "turn", "grind", "hone")) -> ProcessProblem:
    """The linear stack; ``n_dims`` > 6 repeats spacers (for the branch-and-bound benchmark)."""
    signs, size = dict(STACK_SIGNS), dict(STACK_SIZE)
    for i in range(6, n_dims or 6):
        signs[f"spacer{i - 3}"] = -1.0
        size[f"spacer{i - 3}"] = 0.3 + 0.1 * (i % 4)
    if n_dims is not None and n_dims < 6:
        signs = dict(list(signs.items())[:n_dims])
    asm = LinearStack(signs, {"gap": limit}, name="shaft-housing stack")
    procs = {n: [process(p, size[n]) for p in names] for n in asm.source_names}
    return assembly_problem(asm, processes=procs, measure=measure)

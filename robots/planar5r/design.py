"""Design space of the planar 5R symmetrical parallel mechanism (Lara-Molina et al. 2019, Sec. 2.1).

The three link lengths ``OA_i = r3``, ``A_iB_i = r1``, ``B_iP = r2`` are non-dimensionalised by
``D = (r1_bar + r2_bar + r3_bar) / 3`` (eqs. 1-2, so ``r1 + r2 + r3 = 3``) and mapped to the
planar design-space coordinates (eqs. 5-6)::

    s = 2 r1 / sqrt(3) + r3 / sqrt(3),    t = r3.

Table 2 of the paper lists four design cases. Two of its printed entries disagree with eqs. 5-6:
case a prints ``t = 0.08`` with ``r3 = 0.80`` (eq. 6 says ``t = r3``) and case d prints
``s = 1.80`` while eq. 5 gives ``s = 1.010`` for ``r1 = 0.75, r3 = 0.25``. The link lengths are
what the paper simulates, so :data:`CASES` is built from ``r1, r2, r3``; the printed rows are kept
verbatim in :data:`TABLE2_PRINTED`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from evotol.errors import ValidationError

SQRT3 = math.sqrt(3.0)


@dataclass(frozen=True)
class Design5R:
    """Non-dimensional link lengths of a 5R symmetrical mechanism (eqs. 1-4).

    r1: crank ``A_iB_i``; r2: coupler ``B_iP``; r3: half base ``OA_i``; all divided by ``D``.
    Constraints (eqs. 2 and 4): ``r1 + r2 + r3 = 3``, ``0 < r1, r2 < 3``, ``0 <= r3 <= 1.5``.

    Parameters
    ----------
    r1 : float
        Crank ``A_iB_i`` divided by ``D``, dimensionless, in (0, 3).
    r2 : float
        Coupler ``B_iP`` divided by ``D``, dimensionless, in (0, 3).
    r3 : float
        Half base ``OA_i`` divided by ``D``, dimensionless, in [0, 1.5].

    Raises
    ------
    ValidationError
        If a length is not a finite number, violates eq. 4, or the three do not sum to 3
        (within 1e-6).
    """

    r1: float
    r2: float
    r3: float

    def __post_init__(self):
        for name in ("r1", "r2", "r3"):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValidationError(f"Design5R.{name}", v, "a finite number")
        if not (0 < self.r1 < 3):
            raise ValidationError("Design5R.r1", self.r1, "0 < r1 < 3 (eq. 4)")
        if not (0 < self.r2 < 3):
            raise ValidationError("Design5R.r2", self.r2, "0 < r2 < 3 (eq. 4)")
        if not (0 <= self.r3 <= 1.5):
            raise ValidationError("Design5R.r3", self.r3, "0 <= r3 <= 1.5 (eq. 4)")
        total = self.r1 + self.r2 + self.r3
        if abs(total - 3.0) > 1e-6:
            raise ValidationError("Design5R r1 + r2 + r3", total, "3 (eq. 2: lengths divided by D)")

    @classmethod
    def from_lengths(cls, r1_bar: float, r2_bar: float, r3_bar: float) -> "Design5R":
        """Non-dimensionalise physical lengths (any unit) by ``D`` (eq. 1).

        Parameters
        ----------
        r1_bar, r2_bar, r3_bar : float
            Physical crank, coupler and half-base lengths, in one unit (e.g. m).

        Returns
        -------
        Design5R
            The non-dimensional design (``D`` itself is not kept).

        Raises
        ------
        ValidationError
            If ``D`` is not positive or the resulting design violates eq. 4.
        """
        D = (r1_bar + r2_bar + r3_bar) / 3.0
        if not D > 0:
            raise ValidationError("link lengths", (r1_bar, r2_bar, r3_bar), "positive lengths")
        return cls(r1_bar / D, r2_bar / D, r3_bar / D)

    @classmethod
    def from_st(cls, s: float, t: float) -> "Design5R":
        """Inverse of eqs. 5-6: ``r3 = t``, ``r1 = (sqrt(3) s - t) / 2``, ``r2 = 3 - r1 - r3``.

        Parameters
        ----------
        s, t : float
            Design-space coordinates (eqs. 5-6), dimensionless.

        Returns
        -------
        Design5R
            The design at ``(s, t)``.

        Raises
        ------
        ValidationError
            If ``(s, t)`` lies outside the design space (eq. 4).
        """
        r3 = float(t)
        r1 = (SQRT3 * float(s) - r3) / 2.0
        return cls(r1, 3.0 - r1 - r3, r3)

    @property
    def s(self) -> float:
        """Design-space abscissa, eq. 5."""
        return 2.0 * self.r1 / SQRT3 + self.r3 / SQRT3

    @property
    def t(self) -> float:
        """Design-space ordinate, eq. 6."""
        return self.r3

    @property
    def mic_case(self) -> str:
        """Which closed form of the MIC applies: ``"eq21"`` if ``r1 + r3 < r2`` else ``"eq22"``."""
        return "eq21" if self.r1 + self.r3 < self.r2 else "eq22"


#: Table 2 exactly as printed (including the two entries that contradict eqs. 5-6).
TABLE2_PRINTED = {
    "a": dict(s=2.77, t=0.08, r1=2.00, r2=0.20, r3=0.80),
    "b": dict(s=1.00, t=0.80, r1=0.47, r2=1.73, r3=0.80),
    "c": dict(s=1.44, t=1.30, r1=0.60, r2=1.10, r3=1.30),
    "d": dict(s=1.80, t=0.25, r1=0.75, r2=2.00, r3=0.25),
}

#: The four design cases of Table 2, built from the printed link lengths.
CASES = {k: Design5R(v["r1"], v["r2"], v["r3"]) for k, v in TABLE2_PRINTED.items()}

#: The design of the paper's Fig. 3 (workspace illustration), r1 = 1.2, r2 = 1.0, r3 = 0.8.
FIG3_DESIGN = Design5R(1.2, 1.0, 0.8)


def get_case(case) -> Design5R:
    """A :class:`Design5R` from a case letter of Table 2 or a design itself.

    Parameters
    ----------
    case : str or Design5R
        ``"a"`` ... ``"d"`` (case-insensitive) or a design, returned as is.

    Returns
    -------
    Design5R
        The design.

    Raises
    ------
    ValidationError
        If ``case`` is neither a known letter nor a :class:`Design5R`.
    """
    if isinstance(case, Design5R):
        return case
    if isinstance(case, str) and case.lower() in CASES:
        return CASES[case.lower()]
    raise ValidationError("case", case, f"one of {sorted(CASES)} (Table 2) or a Design5R")

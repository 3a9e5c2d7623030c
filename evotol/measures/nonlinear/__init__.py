"""The worst case of a **nonlinear** response over the tolerance box, with a proof
(:mod:`.worst_case`), on outward-rounded interval arithmetic (:mod:`.interval`)."""

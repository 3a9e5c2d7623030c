"""Joint clearances as allocated tolerances: the certified worst case of geometric tolerances and
clearance bounds together (Deng 2012 Sec. VII.1 stated as an optimisation; issue 12 item 5).

This package only hands names on: the clearance classes, their set on a mechanism and the study
file's ``[clearances]`` table are in :mod:`evotol.measures.clearances.classes`; the robot with its classes
as sources and the certified worst case in :mod:`evotol.measures.clearances.certified`
(``docs/clearance_allocation.md``).
"""
from evotol.measures.clearances.certified import (ClearanceWorstCase, WithClearances, error_sources, sample_twists,
                                                  worst_case)
from evotol.measures.clearances.classes import (CLASS_KEYS, COMPONENTS, TABLE_KEYS, ClearanceClass,  # noqa: F401
                                       ClearanceSources, from_table, thesis_classes)

__all__ = ["ClearanceClass", "thesis_classes", "ClearanceSources", "from_table", "WithClearances", "error_sources",
           "ClearanceWorstCase", "worst_case", "sample_twists"]

"""The problem and the values it is built from: :mod:`.tolerance`, :mod:`.requirement`,
:mod:`.variables` (shared tolerance variables), :mod:`.distributions`, :mod:`.problem`
(``ToleranceProblem``), :mod:`.result` (``AllocationResult``), :mod:`.pareto` (the one front and knee),
:mod:`.plausibility` (probable unit slips) and :mod:`.quality_loss` (Taguchi loss as a cost term).
"""

"""The plain data a user study's report is drawn from: the JSON summary (:mod:`.user_study`), error
maps over the workspace (:mod:`.workspace_map`) and the what-if explorer's data (:mod:`.explorer_data`).

The parameters several definitions of this package share are described once, here.

Parameters
----------
problem : ToleranceProblem
    The study's problem.
"""

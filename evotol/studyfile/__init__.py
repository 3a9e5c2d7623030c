"""``evotol run STUDY.toml``: a user's own allocation study, with the same outputs as the seeds.

See ``reports/studies/ucr3_example.toml`` for every field. Units are SI (m, rad); a cost model's
``scale`` is the unit its coefficients were fitted in. Tolerance specifications
(``docs/tolerances.md``): per source ``offset``/``minus``/``plus``, ``cost_width``,
``contains_nominal``, ``fixed = t``, ``distribution`` (+ ``sigma_k``, ``mean_shift``); a
``[shared]`` table (``legs = ["l1", "l2", "l3"]``) with ``shared_cost = "part" | "variable"``;
``[poses] refine = true`` (or a table of refinement options) for the whole workspace;
``[clearances]`` joint-clearance classes allocated with the geometric sources
(``docs/clearance_allocation.md``); ``[calibration]`` a calibration plan: tolerances are allocated
on the error left after calibration (``docs/calibration.md``); ``[report] units = "mm"`` (or ``"um, arcsec"``...): the units
the report, the terminal and the drawing export show (``docs/units.md``; the JSON stays SI);
``[report] precision = 0.001`` (or ``{length = 0.001, angle = 0.1}``, in those units): the drawing step.
The outputs and the page: ``docs/user_reports.md``. A ``[stack]`` table is a tolerance stack written in
the file, no robot and no Python (:mod:`evotol.studyfile.stack_table`, ``docs/stack_analysis.md``).
Every key is checked: an unknown one is an error naming it and the nearest valid key.

This package only hands names on. The reader is split by job, each module reading its tables:

* :mod:`~evotol.studyfile.keys` -- the keys of every table, :func:`check_study_keys`;
* :mod:`~evotol.studyfile.robot` -- ``[robot]`` (a registered robot, a mechanism description, an
  assembly function);
* :mod:`~evotol.studyfile.poses` -- ``[poses]`` and its ``refine`` option;
* :mod:`~evotol.studyfile.sources` -- ``[clearances]``, ``[bounds]``, ``[cost.*]``,
  ``[sources.NAME]``: the sources and their tolerances;
* :mod:`~evotol.studyfile.requirement` -- ``[requirement]``;
* :mod:`~evotol.studyfile.problem` -- :func:`load_problem`, the problem from those parts;
* :mod:`~evotol.studyfile.methods` -- ``[methods]``: :data:`METHODS` and their checks;
* :mod:`~evotol.studyfile.run` -- :func:`run_study_file`;
* :mod:`~evotol.studyfile.processes` -- ``[processes.*]`` tables, :func:`load_process_problem`;
* :mod:`~evotol.studyfile.process_run` -- :func:`run_process_study`.

Data flows one way: ``run`` reads through ``problem`` (and ``processes`` through ``problem``);
no part calls another back.

The parameters several definitions of this package share are described once, here.

Parameters
----------
spec : dict
    The parsed study file.
problem : ToleranceProblem
    The study's problem.
robot : evotol.robots.base.RobotErrorModel
    The study's robot.
"""
from evotol.studyfile.keys import (BOUND_KEYS, GROUP_BOUND_KEYS, POSE_KEYS, REFINE_KEYS, REPORT_KEYS,
                                   REQUIREMENT_KEYS, SOURCE_KEYS, TOP_KEYS, check_study_keys)
from evotol.studyfile.methods import METHODS, REFINING_METHODS
from evotol.studyfile.poses import refine_option
from evotol.studyfile.problem import load_problem
from evotol.studyfile.process_run import run_process_study
from evotol.studyfile.processes import load_process_problem
from evotol.studyfile.run import report_units, run_study_file

__all__ = ["load_problem", "run_study_file", "check_study_keys", "report_units", "refine_option", "METHODS",
           "REFINING_METHODS", "load_process_problem", "run_process_study", "TOP_KEYS", "REPORT_KEYS", "POSE_KEYS",
           "REFINE_KEYS", "BOUND_KEYS", "SOURCE_KEYS", "REQUIREMENT_KEYS", "GROUP_BOUND_KEYS"]

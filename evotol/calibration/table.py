"""The ``[calibration]`` table of a study file (``docs/calibration.md``), read into a plan.

::

    [calibration]
    count = 40                 # or joints = [[...], ...] (rad, m) or poses = [[...], ...] (SI)
    over = "workspace"         # or "joints": a Latin hypercube over the joint limits
    measure = "position"       # or ["position", "orientation"]
    noise = "20 um"            # or { position = ["20 um", "20 um", "40 um"], orientation = "5 arcsec" }
    identify = ["*_joint"]     # name patterns, or "identifiable"
    instrument = "known"       # "unknown": register the instrument's frame and the target too
    k = 3                      # noise coverage in worst-case measures
    linear_fraction = 0.1      # second-order terms below this fraction of the requirement
    compensation_range = { "*_joint" = 0.05 }   # rad or m: the controller's largest correction
    floor = "0 mm"             # the cell's floor in the base frame (default: the mounting plane, z = 0)
    obstacles = [{ min = [0.3, -0.2, 0.0], max = [0.6, 0.2, 0.1] }]   # boxes (m) no joint or tool enters
    simulate = 200             # robots in the simulated calibration of each design (0: none)

Every key is checked before any work; the noise must carry its unit.
"""
from __future__ import annotations

from evotol.calibration.plan import CalibrationPlan
from evotol._runtime.keyword_checks import unknown_key_message
from evotol.errors import ValidationError, is_integer

KEYS = ("joints", "poses", "count", "over", "seed", "measure", "noise", "identify", "instrument", "k",
        "linear_fraction", "compensation_range", "floor", "obstacles", "simulate")


def plan_from_table(table, seed: int = 0) -> tuple[CalibrationPlan, int]:
    """The plan of a ``[calibration]`` table, and how many robots to simulate per design.

    Parameters
    ----------
    table : dict
        The parsed table (module docstring).
    seed : int
        The study's seed (the table's ``seed`` overrides it).

    Returns
    -------
    plan : evotol.calibration.plan.CalibrationPlan
        The plan (noise in SI).
    simulate : int
        Robots of the simulated calibration per design (default 200; 0: none).

    Raises
    ------
    evotol.errors.ValidationError
        Not a table, an unknown key (naming the nearest valid one), no ``noise``, a noise without
        a unit, a bad ``simulate``, and what :class:`CalibrationPlan` refuses.
    """
    if not isinstance(table, dict):
        raise ValidationError("calibration", table, "a table [calibration] (docs/calibration.md)")
    for k in table:
        if k not in KEYS:
            raise ValidationError(f"calibration.{k}", k, unknown_key_message(k, KEYS))
    if "noise" not in table:
        raise ValidationError("calibration.noise", None, "the instrument's standard deviation with its unit, e.g. '20 um'")
    simulate = table.get("simulate", 200)
    if not is_integer(simulate, 0):
        raise ValidationError("calibration.simulate", simulate, "a whole number >= 0 of simulated robots")
    kw = {k: v for k, v in table.items() if k != "simulate"}
    kw.setdefault("seed", seed)
    if not kw.get("joints") and not kw.get("poses") and "count" not in kw:
        raise ValidationError("calibration.count", None, "the calibration configurations: count = n, joints = [[...]] "
                              "or poses = [[...]]")
    return CalibrationPlan(require_units=True, **kw), int(simulate)


def calibrate_study_problem(problem, table, seed: int = 0, random=None):
    """The study's problem after its ``[calibration]`` table (``evotol run``; module docstring).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The uncalibrated problem of the study file.
    table : dict
        The ``[calibration]`` table.
    seed : int
        The study's seed.
    random : evotol.calibration.random_share.RandomPart, optional
        The study's random sources (``[iso9283.random]``), in the calibrated budget.

    Returns
    -------
    evotol.core.problem.ToleranceProblem
        :func:`evotol.calibration.problem.calibrated_problem`.

    Raises
    ------
    evotol.errors.ValidationError
        What :func:`plan_from_table` and :func:`~evotol.calibration.problem.calibrated_problem` refuse.
    """
    from evotol.calibration.problem import calibrated_problem

    plan, simulate = plan_from_table(table, seed)
    return calibrated_problem(problem, plan, simulate, random)

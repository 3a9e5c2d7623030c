"""The problem of a study file: its robot, poses, sources, tolerances and requirement read by the
modules beside this one, put together as a :class:`~evotol.core.problem.ToleranceProblem`.
"""
from __future__ import annotations

from evotol.calibration.table import calibrate_study_problem
from evotol.allocators.workspace_refinement import REFINE_REASON
from evotol.core import plausibility
from evotol.core.axis_limits import axis_requirement
from evotol.core.problem import ToleranceProblem
from evotol.core.quality_loss import with_quality_loss
from evotol.errors import ValidationError
from evotol.studyfile.callouts import callout_warnings
from evotol.studyfile.iso9283 import check_composable as check_iso_composable, random_part
from evotol.studyfile.joint_poses import drop_unreachable, joint_poses
from evotol.studyfile.keys import check_study_keys
from evotol.studyfile.poses import read_poses, refine_option
from evotol.studyfile.requirement import read_requirement
from evotol.studyfile.robot import read_robot
from evotol.studyfile.sources import read_clearances, read_tolerances
from evotol.robots.mechanism.callouts.table import expand_callout_overrides


def load_problem(spec: dict, base_dir=None) -> ToleranceProblem:
    """Build the problem from a parsed study file (dict); ``base_dir``: where relative files
    (``[robot] mechanism = "my_robot.toml"``) are looked up.

    Parameters
    ----------
    spec : dict
        The parsed study file (keys checked by :func:`evotol.studyfile.keys.check_study_keys`).
    base_dir : str or Path, optional
        Where relative files are looked up (default: the current folder).

    Returns
    -------
    ToleranceProblem
        The problem (with the Taguchi loss when ``quality_loss`` is given); tolerances and
        requirement in SI (m, rad). ``problem.robot`` is the robot the file describes, and
        ``problem.clearances`` its ``[clearances]`` classes, if any.

    Raises
    ------
    ValidationError
        An unknown key or bad value anywhere in the file: a ``[processes]`` table (read by
        :func:`evotol.studyfile.processes.load_process_problem` instead), no robot model, robot
        parameters the model does not take, a bad ``[poses]`` table, an unknown source in
        ``[sources]``, a bad ``[bounds]`` table or bound, a fixed source with a range, lock or
        cost, a source without a cost model; and what the problem's own checks refuse.
    """
    check_study_keys(spec)
    check_iso_composable(spec)              # ISO 9283 with a part it does not compose with: before any work
    if "calibration" in spec and refine_option(spec) is not False:      # before any work (issue 39)
        raise ValidationError("poses.refine", spec["poses"]["refine"], "no refine beside [calibration]: "
                              f"{REFINE_REASON} (a denser [poses] grid)")
    if "processes" in spec:
        raise ValidationError("processes", sorted(spec["processes"]), "no [processes.*] here: a process-selection study "
                              "is read by evotol.studyfile.processes.load_process_problem (evotol run does so)")
    robot, spec = read_robot(spec, base_dir)
    ps = spec.get("poses", {})
    if "joints" in ps:      # joint configurations of a serial arm, held exactly (issue 33)
        robot, poses = joint_poses(robot, ps)
    else:
        poses = read_poses(spec, robot)
    poses = drop_unreachable(robot, poses, ps)      # unreachable poses together, or dropped (issue 33)
    # [clearances]: joint-clearance classes allocated with (or, geometric = false, instead of) the
    # robot's sources (docs/clearance_allocation.md); the problem holds them beside the robot
    classes, sources = read_clearances(spec, robot)
    # [sources."J.position"] applies to both members of that callout's zone (docs/callouts.md)
    spec = {**spec, "sources": expand_callout_overrides(spec.get("sources", {}), robot)}
    tol = read_tolerances(spec, sources, robot.name if classes is None else f"{robot.name} or its clearance classes")
    # position = { x = "0.5*mm", ... }: per-axis limits (evotol/core/axis_limits.py, issue 33)
    robot, poses, req_table = axis_requirement(robot, poses, spec.get("requirement", {}), clearances=classes)
    problem = ToleranceProblem(robot, tol, read_requirement({**spec, "requirement": req_table}), poses,
                               shared=spec.get("shared"), shared_cost=spec.get("shared_cost", "part"),
                               clearances=classes, all_given=True)     # every tolerance given: analysed (issue 33)
    plausibility.warn(callout_warnings(problem))        # an orientation callout that binds (issue 35)
    if "calibration" in spec:   # a robot that will be calibrated (docs/calibration.md, evotol/calibration)
        problem = calibrate_study_problem(problem, spec["calibration"], spec.get("seed", 0),
                                          random=random_part(spec, problem.model))   # [iso9283.random] (issue 44)
    # quality_loss = A (or {response = A}): machining cost + Taguchi loss (docs/process_selection.md)
    return with_quality_loss(problem, spec["quality_loss"]) if "quality_loss" in spec else problem

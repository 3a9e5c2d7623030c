"""``[robot]``: the robot error model of a study file -- a registered robot (``model = "ucr3"`` and
its parameters), a mechanism description (``mechanism = "my_robot.toml"`` or ``urdf = ...``,
docs/mechanisms.md) or an assembly function (``assembly = "module:function"``,
docs/process_selection.md).
"""
from __future__ import annotations

from evotol.errors import ValidationError
from evotol.robots import registry
from evotol.robots.assembly import assembly_from_spec
from evotol.robots.base import RobotErrorModel
from evotol.robots.mechanism.callouts.model import with_callouts
from evotol.robots.mechanism.model.error_model import model_from_table


def read_robot(spec: dict, base_dir=None) -> tuple[RobotErrorModel, dict]:
    """The robot of a study file, and the file as the rest of the reader sees it.

    An assembly function has one pose per response: unless the file gives them, its poses are its
    ``response_poses`` and its requirement ``position = 1`` (a ratio of the limits).

    Parameters
    ----------
    base_dir : str or Path, optional
        Where a relative ``mechanism``/``urdf`` file is looked up (default: the current folder).

    Returns
    -------
    robot : evotol.robots.base.RobotErrorModel
        The robot as the user described it.
    spec : dict
        ``spec``, with an assembly's default ``[poses]`` and ``[requirement]`` filled in (a copy;
        ``spec`` itself is not changed).

    Raises
    ------
    ValidationError
        No robot model, or robot parameters the model does not take (and what a mechanism
        description or an assembly specification refuses).
    """
    rs = dict(spec.get("robot", {}))
    if "mechanism" in rs or "urdf" in rs:       # a description (robots/mechanism, docs/mechanisms.md); its
        # its [robot.assembly] table is the assembly configuration; drawing callouts on joint seats:
        # [[robot.callouts]] or the description's (docs/callouts.md, issue 35)
        robot = model_from_table({k: v for k, v in rs.items() if k not in ("callouts", "zones")}, base_dir)
        return with_callouts(robot, rs.get("callouts"), rs.get("zones", "exact"), rs.get("sources")), spec
    if "assembly" in rs:  # an assembly function (docs/process_selection.md): one pose per response
        robot = assembly_from_spec(rs, base_dir)    # 'module:function' also beside the study file
        return robot, {**spec, "poses": spec.get("poses", {"list": robot.response_poses.tolist()}),
                       "requirement": {"position": 1.0, **spec.get("requirement", {})}}
    if "model" not in rs:
        raise ValidationError("robot.model", None, "a robot name, e.g. 'ucr3', mechanism = 'my_robot.toml' "
                              "or assembly = 'module:function'")
    cls = registry.get(rs.pop("model"))
    try:
        return cls(**rs), spec
    except TypeError as exc:
        raise ValidationError("robot", rs, f"parameters accepted by {cls.__name__} ({exc})") from None

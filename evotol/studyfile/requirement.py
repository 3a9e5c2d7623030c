"""``[requirement]``: the accuracy the study asks for (:class:`evotol.core.requirement.Requirement`;
its keys are checked by :func:`evotol.studyfile.keys.check_study_keys`, its values by the class).
"""
from __future__ import annotations

from evotol.core.requirement import Requirement


def read_requirement(spec: dict) -> Requirement:
    """The requirement of a study file (SI: m, rad).

    Parameters
    ----------
    spec : dict
        The parsed study file (as :func:`evotol.studyfile.robot.read_robot` returns it: an
        assembly's default requirement filled in).

    Returns
    -------
    Requirement
        The requirement (validated when the problem is built).
    """
    # iso9283 = { AP, RP }: read by evotol.studyfile.iso9283 beside the problem
    return Requirement(**{k: v for k, v in spec.get("requirement", {}).items() if k != "iso9283"})

"""The task box of a serial arm described without one: its reach (issue 39 item 4).

A designer who gives poses as joint configurations (``[poses] joints``) or checks a chain at joint
values (``evotol check-mechanism FILE --at ...``) need not state a task box: for a description with
no loops and no ``[end_effector]`` coordinates the end-effector's x, y, z range over the cube of
half-width ``R``, the arm's reach::

    R = sum over frames of |b| + |d| + |r|   (m; a prismatic joint's variable at its larger limit),

which bounds every position the chain can place its end-effector at (each frame moves its origin by
at most the lengths of its row). The box is then only a range for reports: a task-pose grid over it
would ask for poses the arm does not reach, so the study file refuses one
(:func:`evotol.studyfile.poses.read_poses`).
"""
from __future__ import annotations

import itertools

from evotol.errors import ValidationError
from evotol.robots.mechanism.description.expressions import Expression
from evotol.robots.mechanism.description.parts import Coordinate

#: the entries of a modified-DH row that are lengths (m)
LENGTH_ENTRIES = ("b", "d", "r")


def reach(frames, parameters: dict, limits: dict) -> float:
    """The reach ``R`` of a serial chain (module docstring), m.

    Parameters
    ----------
    frames : sequence of evotol.robots.mechanism.description.parts.Frame
        The rows of the description.
    parameters : dict of str to float
        The description's ``[lengths]`` and ``[angles]`` (SI).
    limits : dict of str to (float, float)
        Joint variable -> (lower, upper), SI.

    Returns
    -------
    float
        ``R`` (m); at least 1 mm, so that the box is never empty.

    Raises
    ------
    ValidationError
        A length entry that uses a joint variable with no stated limit (a prismatic joint).
    """
    total = 0.0
    for f in frames:
        for key in LENGTH_ENTRIES:
            value = getattr(f, key, 0.0)
            if isinstance(value, (int, float)):
                total += abs(float(value))
                continue
            e = Expression.parse(value, f"frame {f.name!r}.{key}")
            free = sorted(e.names - set(parameters))
            missing = [n for n in free if n not in limits]
            if missing:
                raise ValidationError("end_effector", None, f"a table with the task coordinates: the reach of frame "
                                      f"{f.name!r} ({key} = {value!r}) needs a limit of {missing[0]} ([limits])")
            corners = itertools.product(*(limits[n] for n in free))     # a row's length is largest at a corner of its joints' limits
            total += max(abs(float(e({**parameters, **dict(zip(free, c))}))) for c in corners)
    return max(total, 1e-3)


def reach_coordinates(frames, parameters: dict, limits: dict) -> tuple[Coordinate, ...]:
    """x, y, z of the end-effector over ``[-R, R]`` (m, shown in mm), for a serial arm without a task box.

    Parameters
    ----------
    frames, parameters, limits
        As for :func:`reach`.

    Returns
    -------
    tuple of Coordinate
        Three coordinates named ``x``, ``y``, ``z``.
    """
    R = reach(frames, parameters, limits)
    return tuple(Coordinate(a, a, -R, R, "mm") for a in ("x", "y", "z"))



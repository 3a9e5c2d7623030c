"""The "Joints used at every pose" section of a study page (issue 33 item 2), from the summary's
``joints`` block (:func:`evotol.summaries.pose_joints.pose_joints`): revolute joints in degrees,
wrapped to (-180°, 180°], prismatic ones in mm."""
from __future__ import annotations

import math

#: at most this many poses are listed on the page (the JSON holds them all)
MAX_ROWS = 200


def joints_section(rep, summary: dict) -> None:
    """Add the joints table to a page when the summary has one.

    Parameters
    ----------
    rep : evotol.reporting.html.Report
        The page.
    summary : dict
        A study summary with an optional ``joints`` block (``variables``, ``units``, ``values``
        in SI, wrapped; optional ``poses``).
    """
    joints = summary.get("joints") or {}
    if not joints:
        return
    vs, units = joints["variables"], joints["units"]
    n = len(joints["values"][vs[0]])
    rep.heading("Joints used at every pose")
    rep.text("The arm's joint values at each pose" + (" (the poses are these joint configurations)"
                                                      if summary.get("workspace", {}).get("names") == vs else
                                                      ", from the inverse geometry continued from the assembly posture "
                                                      "on its branch") +
             "; revolute joints in degrees wrapped to (−180°, 180°], prismatic joints in mm."
             + (f" The first {MAX_ROWS} of {n} are shown; the JSON holds all." if n > MAX_ROWS else ""))
    rows = [[str(i)] + [_joint(joints["values"][v][i], u) for v, u in zip(vs, units)] for i in range(min(n, MAX_ROWS))]
    rep.table(rows, ["pose"] + [f"{v} ({'deg' if u == 'rad' else 'mm'})" for v, u in zip(vs, units)], table_id="joints")


def _joint(v: float, unit: str) -> str:
    x = math.degrees(v) if unit == "rad" else v * 1e3
    return f"{0.0 if abs(x) < 5e-10 else x:.4f}"

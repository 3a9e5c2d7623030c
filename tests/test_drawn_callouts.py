"""The drawing is what was checked (issue 41 item 2): the UR5 callout study's drawing table, read
back from the printed CSV text alone, re-evaluated on the nonlinear model by an independent
computation written here -- Pinocchio's forward kinematics of the URDF with each joint placement
moved by ``exp6`` of the twist the callout's zone allows (``docs/callouts.md``: the ends of the bore
axis displaced by ``d1``, ``d2`` within ⌀/2, the shoulder face within ±t/2 along the axis, the joint
zero within its drawn ±), the Jacobian by central differences of that model, the worst-case
direction by a dense search on the sphere polished by a local solve, and the vertex pushed through
the nonlinear model. The drawn values must meet the 0.5 mm requirement; the values rounded to the
nearest (what the table printed before) must not, so the check can fail.
"""
import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import minimize

import pinocchio as pin

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "reports" / "studies" / "ur5_callouts.toml"
URDF = ROOT / "robots" / "urdf" / "ur_description" / "urdf" / "ur5_robot.urdf"
ARCSEC = np.pi / (180 * 3600)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    from evotol.cli import main

    out = tmp_path_factory.mktemp("drawn")
    text = STUDY.read_text()
    text = text[:text.index("[methods]")] + "[methods]\noptimum = {}\n\n[verify]\nn_samples = 20\n"
    f = out / "ur5_callouts.toml"
    f.write_text(text)
    assert main(["run", str(f), "--out", str(out)]) == 0
    summary = json.loads((out / "ur5_callouts.json").read_text())
    return out, summary


def _printed_callouts(out):
    """{joint: {"position": (⌀ m, L m), "axial": t m}} read from the printed callout text."""
    d = pd.read_csv(out / "ur5_callouts_drawing.csv")
    zones = {}
    for _, r in d.iterrows():
        joint = r["feature"].split(" of ")[-1]
        m = re.fullmatch(r"(⌖|⌓) \| (⌀?)([0-9]+\.[0-9]) µm \| A \| B", r["callout"])   # ISO 1101 frame, 0.1 µm
        assert m is not None, r["callout"]
        kind = "position" if m.group(1) == "⌖" else "axial"
        assert (m.group(2) == "⌀") == (kind == "position")
        zones.setdefault(joint, {})[kind] = (float(m.group(3)) * 1e-6, r["length (mm)"] * 1e-3)
    return zones


def _axes():
    root = ET.parse(URDF).getroot()
    return {j.get("name"): np.array([float(v) for v in j.find("axis").get("xyz").split()])
            for j in root.findall("joint") if j.get("type") == "revolute"}


class Arm:
    """The URDF through Pinocchio with its joint placements moved by callout-zone errors."""

    def __init__(self, joints):
        self.model = pin.buildModelFromUrdf(str(URDF))
        self.data = self.model.createData()
        self.tip = self.model.getFrameId("tool0")
        self.joints = joints
        self.nominal = {j: pin.SE3(self.model.jointPlacements[self.model.getJointId(j)]) for j in joints}
        self.axes = _axes()

    def tip_position(self, q, errs):
        """errs: per joint (d1 (3,), d2 (3,), axial shift, zero offset) in m / rad."""
        for j, (d1, d2, s, dq, L) in errs.items():
            a = self.axes[j]
            s1, s2 = -L / 2, L / 2
            g = (d2 - d1) / L                      # slope of the axis: a point s·a moves by d1 + (s - s1) g
            v = d1 - s1 * g + s * a
            w = np.cross(a, g)
            jid = self.model.getJointId(j)
            self.model.jointPlacements[jid] = self.nominal[j] * pin.exp6(pin.Motion(v, w))
        qq = q.copy()
        for j, (_, _, _, dq, _) in errs.items():
            qq[self.model.joints[self.model.getJointId(j)].idx_q] += dq
        pin.framesForwardKinematics(self.model, self.data, qq)
        p = self.data.oMf[self.tip].translation.copy()
        for j in errs:
            self.model.jointPlacements[self.model.getJointId(j)] = self.nominal[j]
        return p


def _lateral(a):
    e1 = np.roll(a, 1)          # the cyclic axes across a (any orthonormal pair: the discs are round)
    return e1, np.cross(a, e1)


def _worst_nonlinear(arm, q, zones, offsets):
    """Nonlinear tip error at the first-order worst-case vertex of the drawn zones at one pose."""
    joints = arm.joints
    zero = {j: (np.zeros(3), np.zeros(3), 0.0, 0.0, zones[j]["position"][1]) for j in joints}
    p0 = arm.tip_position(q, zero)
    h = 1e-7
    blocks = []          # (radius or half-width, Jacobian columns (3, k)) per zone member
    for j in joints:
        a = arm.axes[j]
        e1, e2 = _lateral(a)
        dia, L = zones[j]["position"]

        def moved(i, step):
            d1, d2, s, dq = np.zeros(3), np.zeros(3), 0.0, 0.0
            if i < 2:
                d1 = step * (e1, e2)[i]
            elif i < 4:
                d2 = step * (e1, e2)[i - 2]
            elif i == 4:
                s = step
            else:
                dq = step
            e = dict(zero)
            e[j] = (d1, d2, s, dq, L)
            return arm.tip_position(q, e)
        cols = [(moved(i, h) - moved(i, -h)) / (2 * h) for i in range(6)]
        blocks += [(dia / 2, np.stack(cols[0:2], 1)), (dia / 2, np.stack(cols[2:4], 1)),
                   (zones[j]["axial"][0] / 2, cols[4][:, None]), (offsets[j], cols[5][:, None])]

    def support(u):
        return sum(r * np.linalg.norm(B.T @ u) for r, B in blocks)
    rng = np.random.default_rng(0)
    U = rng.normal(size=(20000, 3))
    U /= np.linalg.norm(U, axis=1, keepdims=True)
    vals = sum(r * np.linalg.norm(U @ B, axis=1) for r, B in blocks)
    u0 = U[np.argmax(vals)]
    res = minimize(lambda x: -support(x / np.linalg.norm(x)), u0, method="Nelder-Mead",
                   options={"xatol": 1e-12, "fatol": 1e-16, "maxiter": 4000})
    u = res.x / np.linalg.norm(res.x)
    linear = support(u)
    errs, k = {}, 0
    for j in joints:
        a = arm.axes[j]
        e1, e2 = _lateral(a)
        ends = []
        for r, B in blocks[k:k + 2]:
            c = B.T @ u
            e = r * c / np.linalg.norm(c)
            ends.append(e[0] * e1 + e[1] * e2)
        (ra, Ba), (rq, Bq) = blocks[k + 2], blocks[k + 3]
        errs[j] = (ends[0], ends[1], ra * np.sign((Ba.T @ u)[0]), rq * np.sign((Bq.T @ u)[0]),
                   zones[j]["position"][1])
        k += 4
    return linear, float(np.linalg.norm(arm.tip_position(q, errs) - p0))


def _worst_over_poses(summary, zones, offsets):
    joints = summary["joints"]["variables"]
    arm = Arm(joints)
    vals = summary["joints"]["values"]
    out = []
    for i in range(len(vals[joints[0]])):
        q = pin.neutral(arm.model)
        for j in joints:
            q[arm.model.joints[arm.model.getJointId(j)].idx_q] = vals[j][i]
        out.append(_worst_nonlinear(arm, q, zones, offsets))
    return np.array(out)


def test_the_printed_drawing_meets_the_requirement_on_the_nonlinear_model(run):
    out, summary = run
    zones = _printed_callouts(out)
    tol = pd.read_csv(out / "ur5_callouts_tolerances.csv")
    assert summary["display_units"]["angle"] == "arcsec"
    offsets = {r["source"]: r["drawing upper deviation"] * ARCSEC for _, r in tol.iterrows()
               if r["source"] in zones}
    w = _worst_over_poses(summary, zones, offsets)
    assert w[:, 1].max() <= 5e-4, f"drawn values give {w[:, 1].max() * 1e3:.6f} mm on the nonlinear model"
    check = summary["drawing"]["optimum"]
    assert check["meets"] and check["meets_nonlinear"]
    # the summary's nonlinear re-check agrees with this independent one
    assert check["normalised_error_nonlinear"] == pytest.approx(w[:, 1].max() / 5e-4, rel=1e-4)
    assert check["normalised_error"] == pytest.approx(w[:, 0].max() / 5e-4, rel=1e-4)

    # the values rounded to the nearest (the table before issue 41) exceed the requirement
    t = summary["results"]["optimum"]["tolerances"]
    nearest = {j: {"position": (float(f"{t[j + '.position.end1'] * 1e6:.3g}") * 1e-6, zones[j]["position"][1]),
                   "axial": (float(f"{t[j + '.axial'] * 1e6:.3g}") * 1e-6, 0.0)} for j in zones}
    wn = _worst_over_poses(summary, nearest, {j: t[j] for j in zones})
    assert wn[:, 1].max() > 5e-4


def test_the_verdict_names_both_models_when_they_differ():
    from evotol.reporting.drawing import verdict_text

    both = {"meets": True, "meets_nonlinear": False, "over_nonlinear": {"position": 7e-8}}
    assert verdict_text(both) == ("meets the requirement (first-order model); 0.070 µm over (position) "
                                  "on the nonlinear model")
    assert verdict_text({"meets": True, "meets_nonlinear": True, "over_nonlinear": {"position": -1e-6}}) \
        == "meets the requirement (first-order and nonlinear models)"
    assert verdict_text({"meets": True}) == "meets the requirement"

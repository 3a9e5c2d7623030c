"""Every URDF of example-robot-data that describes a fixed-base chain loads (issue 23 item 2).

For each ``.urdf`` file of the installed ``example-robot-data`` (a test extra): the chain from the root
to its deepest link, and to each end effector its SRDF names (``<end_effector parent_link=...>``).
Each accepted chain is checked at random configurations inside its joint limits
(:func:`evotol.robots.mechanism.urdf.check.check_urdf_chain`): forward kinematics against Pinocchio's,
every sensitivity column against central finite differences, and the default sources' span against
Pinocchio's placement regressor of the same chain (equal ranks, also together; with the tip's
placement too). The table (accepted/total, FD agreement of each) is printed (``pytest -s``).
Independent of evotol: Pinocchio's forward kinematics and regressor.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from evotol.errors import ValidationError
from evotol.robots.mechanism import MechanismModel, mechanism_from_dict
from evotol.robots.mechanism.urdf.reader import chain_joints, joint_axis



def _robots_dir() -> Path | None:
    import importlib.metadata as md

    try:
        d = Path(md.distribution("example-robot-data").locate_file("cmeel.prefix/share/example-robot-data/robots"))
    except md.PackageNotFoundError:
        return None
    return d if d.is_dir() else None


ROBOTS = _robots_dir()
FILES = sorted(ROBOTS.rglob("*.urdf")) if ROBOTS else []
BOX = {"coordinates": [{"name": "x", "axis": "x", "low": -1.0, "high": 1.0}]}


def _targets(path: Path, pin) -> list[str]:
    """The deepest link (most joints from the root) and every SRDF end effector of the package."""
    model = pin.buildModelFromUrdf(str(path))
    depth = {f.name: len(chain_joints(model, i)) for i, f in enumerate(model.frames) if f.type == pin.FrameType.BODY}
    deepest = max(depth, key=depth.get)
    out = [deepest] if depth[deepest] > 0 else []                  # a robot without joints has no chain
    pkg = path.parents[1]
    for srdf in pkg.glob("srdf/*.srdf"):
        for m in re.finditer(r"<end_effector[^>]*parent_link=\"([^\"]+)\"", srdf.read_text(errors="replace")):
            link = m.group(1)
            if depth.get(link, 0) > 0 and link not in out:
                out.append(link)
    return out


def walk() -> tuple[list[dict], int]:
    import pinocchio as pin

    from evotol.robots.mechanism.urdf.check import check_urdf_chain

    rows, n_files = [], 0
    for path in FILES:
        rel = str(path.relative_to(ROBOTS))
        try:
            targets = _targets(path, pin)
        except (RuntimeError, ValueError) as exc:                     # not a URDF Pinocchio reads
            rows.append({"file": rel, "tip": "-", "accepted": False, "reason": str(exc).splitlines()[0][:80]})
            continue
        n_files += 1
        if not targets:
            rows.append({"file": rel, "tip": "-", "accepted": False, "reason": "no joints (a single rigid body)"})
        for tip in targets:
            row = {"file": rel, "tip": tip}
            try:
                robot = MechanismModel(mechanism_from_dict({"urdf": str(path), "tip": tip, "end_effector": BOX}))
            except ValidationError as exc:
                rows.append({**row, "accepted": False, "reason": str(exc)})
                continue
            rows.append({**row, "accepted": True, **check_urdf_chain(robot, n=6, seed=0)})
    return rows, n_files


@pytest.fixture(scope="module")
def walked():
    if not FILES:
        pytest.skip("example-robot-data is not installed (pip install 'evotol[test]')")
    return walk()


def test_every_fixed_base_chain_of_example_robot_data_loads_and_agrees(walked):
    rows, n_files = walked
    acc = [r for r in rows if r["accepted"]]
    print(f"\n{len(FILES)} URDF files, {n_files} read by Pinocchio; chains accepted {len(acc)}/{len(rows)}")
    for r in rows:
        if r["accepted"]:
            print(f"  {r['file']:60s} {r['tip']:28s} joints {r['n_joints']:2d} sources {r['n_sources']:3d} "
                  f"FK {r['fk_vs_pinocchio']:.1e} FD {r['fd_rel_error']:.1e} rank {r['rank']}/{r['pinocchio_rank']}"
                  f" tip {r['rank_with_tip']}/{r['pinocchio_rank_with_tip']}")
        else:
            print(f"  {r['file']:60s} {r['tip']:28s} REFUSED: {r['reason']}")
    refused = [r for r in rows if not r["accepted"] and r["tip"] != "-"]
    assert not refused, refused[:3]                 # no fixed-base chain of the collection is refused
    assert len(acc) >= 68
    for r in acc:
        assert r["fk_vs_pinocchio"] < 1e-10, r
        assert r["fd_rel_error"] < 1e-6, r
        assert r["rank"] == r["pinocchio_rank"] == r["combined_rank"], r
        assert r["rank_with_tip"] == r["pinocchio_rank_with_tip"] == r["combined_rank_with_tip"], r


def test_walk_covers_continuous_unaligned_prismatic_and_mimic_joints():
    """The collection exercises every joint kind the loader handles (so the walk above tests them)."""
    import pinocchio as pin

    from evotol.robots.mechanism.urdf.reader import urdf_joints

    if not FILES:
        pytest.skip("example-robot-data is not installed")
    kinds, mimic = set(), 0
    for path in FILES:
        try:
            model = pin.buildModelFromUrdf(str(path))
        except (RuntimeError, ValueError):
            continue
        kinds |= {model.joints[j].shortname() for j in range(1, model.njoints)}
        mimic += sum(1 for w in urdf_joints(path).values() if w["mimic"])
    assert {"JointModelRUBZ", "JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned", "JointModelPZ"} <= kinds
    assert mimic > 0


FLOATING = """<robot name="r"><link name="world"/><link name="base"/><link name="tool"/>
<joint name="root" type="{kind}"><parent link="world"/><child link="base"/></joint>
<joint name="j1" type="revolute"><parent link="base"/><child link="tool"/><axis xyz="0 0 1"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"""


@pytest.mark.parametrize("kind", ["floating", "planar"])
def test_floating_and_planar_roots_are_refused_in_one_line(tmp_path, kind):
    p = tmp_path / "r.urdf"
    p.write_text(FLOATING.format(kind=kind))
    with pytest.raises(ValidationError, match=r"urdf joint 'root'.*floating and planar") as e:
        mechanism_from_dict({"urdf": str(p), "tip": "tool", "end_effector": BOX})
    assert "\n" not in str(e.value)


MIMIC = """<robot name="m"><link name="base"/><link name="a"/><link name="b"/><link name="tool"/>
<joint name="lead" type="revolute"><parent link="base"/><child link="a"/><origin xyz="0 0 0.1" rpy="0 0.3 0"/>
<axis xyz="0 0 -1"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
<joint name="follow" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0.3 0 0" rpy="0.2 0 0"/>
<axis xyz="0.6 0 0.8"/><mimic joint="lead" multiplier="-0.5" offset="0.1"/>
<limit lower="-0.4" upper="0.9" effort="1" velocity="1"/></joint>
<joint name="slide" type="prismatic"><parent link="b"/><child link="tool"/><origin xyz="0 0.2 0"/>
<axis xyz="0 0.6 -0.8"/><limit lower="0" upper="0.1" effort="1" velocity="1"/></joint></robot>"""


def test_mimic_joint_is_coupled_with_multiplier_and_offset_errors(tmp_path):
    """One variable for the leader and its mimic; the mimic's range carried to the leader
    ((0.9 - 0.1)/-0.5 = -1.6 .. (-0.4 - 0.1)/-0.5 = 1.0); the multiplier's column is the leader's
    value times the offset's (closed form of d(m q + o)); FK and FD agree with Pinocchio."""
    import pinocchio as pin

    from evotol.robots.mechanism.urdf.check import check_urdf_chain

    p = tmp_path / "m.urdf"
    p.write_text(MIMIC)
    mech = mechanism_from_dict({"urdf": str(p), "tip": "tool", "end_effector": BOX})
    assert "follow_offset" in mech.sources and "follow_multiplier" not in mech.sources     # on request
    robot = MechanismModel(mech, sources=list(mech.sources) + ["follow_multiplier"])
    assert robot.kin.variables == ["lead", "slide"]
    assert robot.mechanism.limits["lead"] == pytest.approx((-1.6, 1.0))
    assert {"follow_offset", "follow_multiplier", "follow.tilt_x", "slide"} <= set(robot.source_names)
    q = {"lead": np.array([0.7, -0.3]), "slide": np.array([0.05, 0.02])}
    S = robot.sensitivity_at_joints(q)
    names = list(robot.source_names)
    assert np.allclose(S[..., names.index("follow_multiplier")], q["lead"][:, None] * S[..., names.index("follow_offset")], atol=1e-15)
    assert joint_axis(pin.buildModelFromUrdf(str(p)), 2)[0] == "revolute"
    r = check_urdf_chain(robot, n=6)
    assert r["fk_vs_pinocchio"] < 1e-12 and r["fd_rel_error"] < 1e-6

"""Standard-DH descriptions (issue 33 item 5): robots/mechanism/description/standard_dh.py.

Checked against an independent forward kinematics written here from the textbook formula
``A_i = Rot(z, theta_i) Trans(z, d_i) Trans(x, a_i) Rot(x, alpha_i)`` (Spong et al., *Robot Modeling
and Control*, eq. 3.10; Corke, *Robotics, Vision and Control*, sec. 7.1.1), against Corke's published
PUMA 560 poses at qz and qn, and the PUMA 560 described in both conventions.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from evotol.errors import ValidationError
from evotol.robots.mechanism.description.reader import mechanism_from_dict
from evotol.robots.mechanism.model.error_model import MechanismModel

ROOT = Path(__file__).resolve().parents[1]
PUMA = ROOT / "robots" / "mechanisms" / "puma560.toml"
PUMA_MODIFIED = ROOT / "robots" / "mechanisms" / "puma560_modified.toml"
#: Corke's PUMA 560 standard-DH table (d, a, alpha), m and rad
TABLE = [(0.0, 0.0, np.pi / 2), (0.0, 0.4318, 0.0), (0.15005, 0.0203, -np.pi / 2), (0.4318, 0.0, np.pi / 2),
         (0.0, 0.0, -np.pi / 2), (0.0, 0.0, 0.0)]


def link(theta, d, a, alpha):
    """The textbook's standard-DH link transform A_i."""
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1.0]])


def textbook_fk(q, table=TABLE, base=np.eye(4), tool=np.eye(4)):
    T = base.copy()
    for qi, (d, a, alpha) in zip(q, table):
        T = T @ link(qi, d, a, alpha)
    return T @ tool


def end_transform(model: MechanismModel, Q: np.ndarray) -> np.ndarray:
    kin = model.kin
    st = kin.state({v: Q[:, i] for i, v in enumerate(kin.variables)}, len(Q), twists=False)
    return np.asarray(st.world[model.mechanism.end_effector])


def test_puma_forward_kinematics_equals_the_textbook_product():
    model = MechanismModel(PUMA)
    Q = np.random.default_rng(0).uniform(-np.pi, np.pi, (200, 6))
    T = end_transform(model, Q)
    ref = np.array([textbook_fk(q) for q in Q])
    assert np.abs(T - ref).max() < 1e-12


def test_puma_matches_corkes_published_poses():
    # Corke 2017 sec. 7.2.2: p560.fkine(qz) = transl(0.4521, -0.1500, 0.4318); qn: (0.5963, -0.1501, -0.0144)
    model = MechanismModel(PUMA)
    T = end_transform(model, np.radians([[0, 0, 0, 0, 0, 0], [0, 45, 180, 0, 45, 0]]))
    assert np.allclose(T[0, :3, 3], [0.4521, -0.15005, 0.4318], atol=5e-5)
    assert np.allclose(T[1, :3, 3], [0.5963, -0.1501, -0.0144], atol=5e-5)


def test_puma_both_conventions_give_the_same_arm_and_sensitivities():
    std, mod = MechanismModel(PUMA), MechanismModel(PUMA_MODIFIED)
    Q = np.random.default_rng(1).uniform(-np.pi, np.pi, (100, 6))
    assert np.abs(end_transform(std, Q) - end_transform(mod, Q)).max() < 1e-12
    # the same error, named both ways: standard a_(j-1), alpha_(j-1), d_j, theta_j = modified j.d, j.alpha, j.r, j.theta
    pairs = {**{f"a{j - 1}": f"{j}.d" for j in range(2, 7)}, **{f"alpha{j - 1}": f"{j}.alpha" for j in range(2, 7)},
             **{f"d{j}": f"{j}.r" for j in range(1, 7)}, **{f"theta{j}": f"{j}.theta" for j in range(1, 7)}}
    Ss, Sm = std.sensitivity_at_joints(Q), mod.sensitivity_at_joints(Q)
    i_s = {n: i for i, n in enumerate(std.source_names)}
    i_m = {n: i for i, n in enumerate(mod.source_names)}
    assert len(pairs) == 22
    for a, b in pairs.items():
        assert np.abs(Ss[:, :, i_s[a]] - Sm[:, :, i_m[b]]).max() < 1e-12, (a, b)


def test_sources_are_named_after_the_table():
    model = MechanismModel(PUMA)
    assert model.source_names == tuple(f"{k}{i}" for i in range(1, 7) for k in ("a", "alpha", "d", "theta"))
    # a2 moves exactly what the textbook's a2 moves: finite differences of the textbook product
    q = np.radians([10, 10, -100, -20, 30, -60])
    S = model.sensitivity_at_joints(q[None])[0]
    h = 1e-7
    for name, (row, field) in {"a2": (1, 1), "d4": (3, 0), "alpha3": (2, 2)}.items():
        up = [list(r) for r in TABLE]
        up[row][field] += h
        dp = (textbook_fk(q, up)[:3, 3] - textbook_fk(q)[:3, 3]) / h
        assert np.allclose(S[:3, model.source_names.index(name)], dp, atol=1e-6), name


def _spec(**extra):
    rows = [{"a": 0.3, "alpha": 0.0, "theta": "q1"}, {"a": 0.2, "alpha": "pi/2", "d": 0.05, "theta": "q2 - pi/2"},
            {"joint": "prismatic", "a": 0.0, "alpha": 0.0, "theta": "10*deg", "d": "q3 + 0.1"}]
    spec = {"name": "rrp", "convention": "standard", "frame": rows,
            "end_effector": {"coordinates": [{"name": "x", "axis": "x", "low": 0.1, "high": 0.3},
                                             {"name": "y", "axis": "y", "low": 0.0, "high": 0.2}]},
            "assembly": {"joints": {"q1": 0.3, "q2": 0.2, "q3": 0.05}}}
    spec.update(extra)
    return spec


def test_base_tool_offsets_and_a_prismatic_row():
    base = {"a": 0.01, "alpha": "5*deg", "d": 0.4, "theta": "30*deg"}
    tool = {"d": "120*mm", "a": 0.02, "alpha": 0.0, "theta": 0.0}
    model = MechanismModel(mechanism_from_dict(_spec(base=base, tool=tool)))
    assert {"base.d", "base.theta", "tool.d", "tool.a", "theta2", "d3"} <= set(model.source_names)
    assert "base_d" not in model.source_names
    Q = np.random.default_rng(2).uniform(-1, 1, (50, 3)) * [3, 3, 0.1]
    B = link(np.radians(30), 0.4, 0.01, np.radians(5))
    E = link(0.0, 0.12, 0.02, 0.0)
    for q, T in zip(Q, end_transform(model, Q)):
        ref = B @ link(q[0], 0.0, 0.3, 0.0) @ link(q[1] - np.pi / 2, 0.05, 0.2, np.pi / 2) \
            @ link(np.radians(10), q[2] + 0.1, 0.0, 0.0) @ E
        assert np.abs(T - ref).max() < 1e-12
    # base.d and tool.d: a translation along the base z axis / the tool's z axis
    S = model.sensitivity_at_joints(Q[:1])[0]
    assert np.allclose(S[:3, model.source_names.index("base.d")], [0, 0, 1], atol=1e-12)     # along the world z
    Tn = end_transform(model, Q[:1])[0]
    assert np.allclose(S[:3, model.source_names.index("tool.d")], (Tn[:3, :3] @ np.linalg.inv(E[:3, :3]))[:, 2], atol=1e-12)


@pytest.mark.parametrize("row, field, words", [
    ({"a": 0.3, "r": 0.1, "theta": "q1"}, "frame[0].r", "modified"),
    ({"a": 0.3, "gamma": 0.1, "theta": "q1"}, "frame[0].gamma", "modified"),
    ({"a": 0.3, "antecedent": "0", "theta": "q1"}, "frame[0].antecedent", "modified"),
    ({"a": 0.3, "theta": "2*q1"}, "frame[0].theta", "offset"),
    ({"a": 0.3, "theta": "q1 + q2"}, "frame[0].theta", "several"),
    ({"a": "L1", "theta": "q1"}, "frame[0].a", "constant"),
    ({"a": 300, "theta": "q1"}, "frame[0].a", "300*mm"),
    ({"a": 0.3, "theta": "theta1"}, "frame[0]", "q1"),
    ({"a": 0.3, "theta": "q1", "joint": "fixed"}, "frame[0].joint", "revolute"),
])
def test_bad_standard_rows_are_one_line_errors(row, field, words):
    spec = _spec()
    spec["frame"] = [row] + spec["frame"][1:]
    with pytest.raises(ValidationError) as e:
        mechanism_from_dict(spec)
    assert e.value.field == field and words in str(e.value) and "\n" not in str(e.value)


def test_bad_convention_and_tables():
    with pytest.raises(ValidationError, match="standard"):
        mechanism_from_dict(_spec(convention="craig"))
    spec = _spec(base={"b": 0.1})
    with pytest.raises(ValidationError) as e:
        mechanism_from_dict(spec)
    assert e.value.field == "base.b"
    with pytest.raises(ValidationError) as e:
        mechanism_from_dict({k: v for k, v in _spec(lengths={"L": 1.0}).items()})
    assert e.value.field == "lengths"
    mod = {k: v for k, v in _spec().items() if k != "convention"}
    mod["tool"] = {"d": 0.1}
    with pytest.raises(ValidationError) as e:
        mechanism_from_dict(mod)
    assert e.value.field == "tool"


def test_puma_with_base_and_tool_tables_as_the_docs_show_them():
    """Issue 39: the PUMA 560 with [base] and [tool] (docs/mechanisms.md, every entry non-zero here) has
    32 distinct sources -- the 24 of the rows and base.theta/d/alpha/a, tool.theta/d/alpha/a once each
    (the modified entries of the base and tool frames, whose base.d would be a_B, are not candidates) --
    passes the robot check of unique names, its forward kinematics is the textbook product B A_1 ... A_6 E, and each base and
    tool source moves what the textbook entry of that name moves (finite differences of the product)."""
    text = PUMA.read_text().replace("[end_effector]", '[base]\nd = "660*mm"\na = "10*mm"\nalpha = "3*deg"\n'
                                    'theta = "20*deg"\n[tool]\nd = "56.25*mm"\na = "5*mm"\nalpha = "-4*deg"\n'
                                    'theta = "15*deg"\n\n[end_effector]')
    import tomllib
    from types import SimpleNamespace
    from evotol.robots.checks import check_sources_declared
    model = MechanismModel(mechanism_from_dict(tomllib.loads(text)))
    ends = [f"{k}.{f}" for k in ("base", "tool") for f in ("theta", "d", "alpha", "a")]
    assert sorted(model.source_names) == sorted([f"{k}{i}" for i in range(1, 7) for k in ("a", "alpha", "d", "theta")]
                                                + ends)
    check_sources_declared(SimpleNamespace(robot=model))        # the check that named "duplicate source names"
    entries = {"base": [np.radians(20), 0.66, 0.01, np.radians(3)], "tool": [np.radians(15), 0.05625, 0.005, np.radians(-4)]}

    def fk(q, moved=None, h=0.0):
        e = {k: list(v) for k, v in entries.items()}
        if moved:
            k, f = moved.split(".")
            e[k][("theta", "d", "a", "alpha").index(f)] += h
        return textbook_fk(q, base=link(*e["base"]), tool=link(*e["tool"]))
    Q = np.random.default_rng(4).uniform(-np.pi, np.pi, (50, 6))
    assert np.abs(end_transform(model, Q) - np.array([fk(q) for q in Q])).max() < 1e-12
    S = model.sensitivity_at_joints(Q[:3])
    h = 1e-7
    for p, q in enumerate(Q[:3]):
        for name in ends:
            dp = (fk(q, name, h)[:3, 3] - fk(q, name, -h)[:3, 3]) / (2 * h)
            assert np.allclose(S[p, :3, model.source_names.index(name)], dp, atol=1e-7), name


def test_a_duplicate_source_name_error_names_only_the_duplicates():
    """evotol.robots.checks: the message lists the names that appear twice, not every source."""
    from types import SimpleNamespace
    from evotol.errors import CheckFailed
    from evotol.robots.base import SourceSpec
    from evotol.robots.checks import check_sources_declared
    sources = [SourceSpec(n, 1, "m", "length", "") for n in ("a1", "d1", "a1", "theta1", "d2", "d2")]
    with pytest.raises(CheckFailed) as e:
        check_sources_declared(SimpleNamespace(robot=SimpleNamespace(name="arm", sources=sources)))
    assert "['a1', 'd2']" in str(e.value) and "theta1" not in str(e.value)

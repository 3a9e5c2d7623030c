"""The second tutorial's robot (docs/tutorial_2_3rpr.md, robots/mechanisms/planar3rpr.toml): a planar
3-RPR with in-plane prismatic joints, checked against its closed-form inverse kinematics.

Leg i: base joint ``A_i = Rb (cos g_i, sin g_i)``, platform joint
``C_i = P + rp (cos(b_i + phi), sin(b_i + phi))`` with ``b_i = g_i + offset``; the stroke is
``l_i = |C_i - A_i|`` and the leg direction ``psi_i = atan2(C_i - A_i)``. With the actuated
strokes held, ``f_i = |C_i - A_i| - l_i = 0`` gives the first-order map ``J dX = e_l - df/dRb dRb -
df/drp drp`` with rows ``J_i = [u_i, (r_i x u_i)_z]`` (``u_i`` the unit leg direction, ``r_i = C_i - P``).
"""
from __future__ import annotations

import numpy as np
import pytest

from evotol.robots.mechanism.model.error_model import MechanismModel, resolve_description

RB, RP, OFFSET = 0.2, 0.05, np.radians(40)
G = np.radians([90.0, 210.0, 330.0])


@pytest.fixture(scope="module")
def rpr():
    return MechanismModel(resolve_description("planar3rpr"))


def closed_form(poses):
    """Strokes l (n, 3), leg angles psi (n, 3), unit directions u (n, 3, 2), arms r (n, 3, 2)."""
    x, y, phi = poses.T
    b = G[None] + OFFSET + phi[:, None]
    C = np.stack([x[:, None] + RP * np.cos(b), y[:, None] + RP * np.sin(b)], -1)
    A = RB * np.stack([np.cos(G), np.sin(G)], -1)[None]
    d = C - A
    l = np.linalg.norm(d, axis=-1)
    return l, np.arctan2(d[..., 1], d[..., 0]), d / l[..., None], C - np.stack([x, y], -1)[:, None]


def test_strokes_and_leg_angles_are_the_closed_form(rpr):
    poses = rpr.workspace.latin_hypercube(40, seed=2)
    q = rpr.joint_values(poses)
    l, psi, _, _ = closed_form(poses)
    for i in range(3):
        assert np.abs(q[f"l{i + 1}"] - l[:, i]).max() < 1e-12
        # frame A_i's x axis is at gamma + a_i: along the leg
        assert np.abs(np.angle(np.exp(1j * (G[i] + q[f"a{i + 1}"] - psi[:, i])))).max() < 1e-12


def test_sensitivity_is_the_closed_form(rpr):
    poses = rpr.workspace.latin_hypercube(40, seed=3)
    S = rpr.sensitivity(poses)[:, [0, 1, 5]]          # in-plane rows: x, y, rotation about z
    assert rpr.source_names == ("Rb", "rp", "l1", "l2", "l3")
    l, psi, u, r = closed_form(poses)
    x, y, phi = poses.T
    J = np.concatenate([u, (r[..., 0] * u[..., 1] - r[..., 1] * u[..., 0])[..., None]], -1)   # (n, 3, 3)
    radial_A = np.stack([np.cos(G), np.sin(G)], -1)[None]
    b = G[None] + OFFSET + phi[:, None]
    radial_C = np.stack([np.cos(b), np.sin(b)], -1)
    dfdRb = -np.einsum("nij,nij->ni", u, np.broadcast_to(radial_A, u.shape))
    dfdrp = np.einsum("nij,nij->ni", u, radial_C)
    rhs = np.concatenate([-dfdRb[..., None], -dfdrp[..., None], np.broadcast_to(np.eye(3), (len(poses), 3, 3))], -1)
    expect = np.linalg.solve(J, rhs)                 # (n, 3 pose rows, 5 sources)
    assert np.abs(S - expect).max() < 1e-12 * max(1.0, np.abs(expect).max())


def test_in_plane_prismatic_axis_lies_along_the_leg(rpr):
    """The tutorial's frame recipe: gamma = alpha = 90 deg puts the slider's z on the leg."""
    poses = rpr.workspace.latin_hypercube(5, seed=4)
    q = rpr.joint_values(poses)
    st = rpr.kin.state(q, len(poses), twists=False)
    _, _, u, _ = closed_form(poses)
    for i in range(3):
        z = st.world[f"L{i + 1}"][:, :3, 2]
        assert np.abs(z[:, :2] - u[:, i]).max() < 1e-12 and np.abs(z[:, 2]).max() < 1e-15


def test_check_mechanism_shows_parameters_assembly_and_pose_in_display_units(capsys):
    """Issue 27 item 1: the check prints what it understood -- Rb = 200 mm, the strokes as declared
    (165 mm) and as solved (the closed form |C_i - A_i| at the centre, 164.861 mm), and the
    end-effector at the assembly pose."""
    from evotol.cli import main

    assert main(["check-mechanism", "planar3rpr", "--poses", "4"]) == 0
    out = capsys.readouterr().out
    l, _, _, _ = closed_form(np.zeros((1, 3)))
    assert "Rb = 200 mm" in out and "rp = 50 mm" in out and "offset = 40 deg" in out
    row = next(line for line in out.splitlines() if line.split()[:1] == ["l1"])
    assert row.split()[1:] == ["165", "mm", f"{l[0, 0] * 1e3:.6g}", "mm"]
    assert "end-effector P1 at the assembly: position (0, 0, 0) mm, yaw/pitch/roll (0, 0, 0) deg" in out


def test_tutorial_study_optimum_holds_by_brute_force_over_the_box_vertices():
    """docs/tutorial_2_3rpr.md step 9: the certified optimum of reports/studies/planar3rpr.toml
    (0.5868) meets 0.1 mm exactly at its worst pose -- checked by brute force: the worst case of
    interval sources is at a vertex of the tolerance box, so the largest in-plane position error
    is max over the 2^5 sign patterns of |sum_j s_j t_j S_j| (S equal to the closed form, see above)."""
    import itertools
    import tomllib
    from pathlib import Path

    from evotol.allocators import allocate_optimum
    from evotol.studyfile import load_problem

    f = Path(__file__).resolve().parents[1] / "reports" / "studies" / "planar3rpr.toml"
    p = load_problem(tomllib.loads(f.read_text()), base_dir=f.parent)
    r = allocate_optimum(p)
    assert r.cost == pytest.approx(0.5868, abs=5e-4) and r.verdict.startswith("certified optimal")
    S = p.model.sensitivity(p.poses)[:, :2]                          # x, y rows, columns Rb rp l1 l2 l3
    t = r.t
    worst = max(np.linalg.norm(S @ (np.array(s) * t), axis=1).max() for s in itertools.product((-1, 1), repeat=5))
    assert worst == pytest.approx(1e-4, rel=1e-6)

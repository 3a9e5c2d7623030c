"""3-UCR model of Yao et al. 2013: eq. 8 closed form, loop closure, first-order models vs finite differences."""
import numpy as np
import pytest

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.checks import check_robot
from evotol.robots.ucr3 import UCR3


def eq8(alpha, beta, zc, r_B=0.14):
    """Eq. 8 as printed (with s²2α read as sin²(2α)/... as in the paper's layout)."""
    sa, ca, sb, cb = np.sin(alpha), np.cos(alpha), np.sin(beta), np.cos(beta)
    vb = 1 - cb
    X = (2 * sa * sb * zc + r_B * (vb - ca ** 2 * sb ** 2 - np.sin(2 * alpha) ** 2 * vb ** 2)) / (2 * cb)
    Y = -(2 * ca * sb * zc + r_B * sa * ca * vb * (1 - 3 * cb - 4 * ca ** 2 * vb)) / (2 * cb)
    return X, Y


def test_constraint_solution_matches_eq8():
    r = UCR3()
    P = r.workspace.latin_hypercube(50, seed=3)
    R, p = r.platform_pose(P)
    X, Y = eq8(P[:, 0], P[:, 1], P[:, 2])
    np.testing.assert_allclose(p[:, 0], X, atol=1e-12)
    np.testing.assert_allclose(p[:, 1], Y, atol=1e-12)
    # eq. 5: every revolute axis u_i is perpendicular to its leg
    s, u, l, n = r.legs(R, p)
    assert np.max(np.abs(np.einsum("nki,nki->nk", u, n))) < 1e-12


def test_verified_model_matches_finite_differences():
    rep = check_robot(UCR3(variant="verified"), rtol=1e-6)
    assert rep["fd_relative_mismatch"] < 1e-6


def test_printed_eq11_does_not_match_finite_differences():
    """The printed constraint rows of J_x omit l_i (u_i × n_i); the mismatch is O(1), not round-off."""
    with pytest.raises(AssertionError, match="finite differences"):
        check_robot(UCR3(variant="paper"))
    r = UCR3()
    P = r.workspace.grid([3, 3, 2])
    d = r.jacobian_x(P, "verified") - r.jacobian_x(P, "paper")
    R, p = r.platform_pose(P)
    s, u, l, n = r.legs(R, p)
    np.testing.assert_allclose(d[:, 3:, 3:], l[..., None] * np.cross(u, n), atol=1e-15)
    assert np.all(d[:, :3] == 0) and np.all(d[:, 3:, :3] == 0)


def test_nonlinear_model_is_exact_at_zero_and_second_order_small():
    r = UCR3()
    P = r.workspace.grid([2, 2, 2])
    E = np.random.default_rng(1).uniform(-1, 1, (len(P), 50, r.n_columns)) * 3e-5
    nl = r.pose_error(P, E)
    lin = np.einsum("pij,psj->psi", r.sensitivity(P), E)
    # first-order model error ~ |e|²/link ~ 1e-9 m at 3e-5 m errors
    assert np.max(np.abs(nl - lin)) < 1e-3 * np.max(np.abs(lin))
    assert np.max(np.abs(r.pose_error(P, np.zeros((len(P), 1, r.n_columns))))) < 1e-14


def test_pose_outside_workspace_is_reported():
    r = UCR3()
    with pytest.raises(KinematicsError, match="outside the workspace"):
        r.sensitivity([[0.0, 0.0, 0.5]])
    with pytest.raises(ValidationError, match="poses shape"):
        r.sensitivity([[0.0, 0.0]])
    with pytest.raises(ValidationError, match="finite"):
        r.sensitivity([[np.nan, 0.0, 0.3]])
    with pytest.raises(ValidationError, match="variant"):
        UCR3(variant="printed")
    with pytest.raises(ValidationError, match="r_p"):
        UCR3(r_p=-1)


def test_singular_jx_error_names_the_whole_pose():
    """Z_c = 0 puts the platform in the base plane, where J_x is singular: the KinematicsError names
    the whole offending pose (alpha, beta, Z_c), also for a single pose given as shape (3,) --
    not one number of it -- and keeps it in ``poses``."""
    r = UCR3(zc_range=(0.0, 0.305))
    for poses in ([0.05, 0.0, 0.0], [[0.0, 0.0, 0.3], [0.05, 0.0, 0.0]]):
        with pytest.raises(KinematicsError, match=r"^3-UCR: singular J_x \(cond [^)]+\) at pose \[0\.05, 0\.0, 0\.0\]$") as ei:
            r.sensitivity(poses)
        np.testing.assert_array_equal(ei.value.poses, [[0.05, 0.0, 0.0]])


@pytest.mark.parametrize("variant", ["Paper", "verifed", ""])
def test_jacobian_x_refuses_an_unknown_variant(variant):
    """A mistyped ``variant`` of ``jacobian_x`` silently gave the paper's printed eq. 11 (anything
    but 'verified' did; '' gave the robot's own): a one-line ValidationError now. None still means
    the robot's variant, and the two known ones differ at a general pose."""
    r = UCR3()
    P = r.workspace.latin_hypercube(5, seed=1)
    with pytest.raises(ValidationError) as exc:
        r.jacobian_x(P, variant)
    assert str(exc.value) == f"variant = {variant!r}: expected one of ('verified', 'paper') or None (the robot's)"
    np.testing.assert_array_equal(r.jacobian_x(P, None), r.jacobian_x(P, "verified"))
    assert np.abs(r.jacobian_x(P, "paper") - r.jacobian_x(P, "verified")).max() > 1e-3

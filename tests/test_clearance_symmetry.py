"""Issue 13: exact reuse of certified maxima across a proven mirror symmetry
(robots/clearance/symmetry.py), checked against direct solves of the mirrored poses."""
import dataclasses

import numpy as np
import pytest

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.clearance import max_pose_error
from evotol.robots.clearance.grid import grid_max_pose_error
from evotol.robots.clearance.symmetry import grid_max_pose_error_mirrored, mirror_maxima, prove_mirror
from evotol.robots.irsbot2 import IRSBot2, mirror_joint_map

X_MIRROR = np.diag([-1.0, 1.0, 1.0])


@pytest.fixture(scope="module")
def irsbot():
    return IRSBot2.thesis("VI.1")


@pytest.mark.parametrize("parallelograms", [False, True])
def test_mirrored_maxima_equal_direct_solves_and_their_screws_attain_them(irsbot, parallelograms):
    mech = irsbot.clearance_mechanism(parallelograms=parallelograms)
    rng = np.random.default_rng(3)
    P = np.column_stack([rng.uniform(-0.03, -0.001, 4), rng.uniform(-0.07, -0.01, 4)])
    M = P * [-1.0, 1.0]
    proof = prove_mirror(mech, P, M, mirror_joint_map(mech), X_MIRROR)
    assert proof["max_map_residual"] < 1e-12 and proof["max_consistency_residual"] < 1e-12
    mirrored = mirror_maxima(max_pose_error(mech, P), proof)
    direct = max_pose_error(mech, M)
    # same certified brackets (independent solves agree within the certificate)
    assert np.all(mirrored.p_max <= direct.p_upper * (1 + 1e-12)) and np.all(direct.p_max <= mirrored.p_upper * (1 + 1e-12))
    assert np.all(mirrored.r_max <= direct.r_upper * (1 + 1e-12)) and np.all(direct.r_max <= mirrored.r_upper * (1 + 1e-12))
    # the mapped maximising screws are consistent at the mirrored pose and produce the value there
    pm = mech.pose_maps(M)[0]
    s = mirrored.p_screws.reshape(len(M), -1)[:, pm.cols]
    assert np.abs(np.einsum("nrm,nr->nm", pm.B, s)).max() < 1e-12 * np.abs(s).max()
    twist = np.einsum("nir,nr->ni", pm.C_pos, s)
    np.testing.assert_allclose(np.linalg.norm(twist, axis=1), mirrored.p_max, rtol=1e-10)


def test_the_proof_fails_where_there_is_no_symmetry(irsbot):
    mech = irsbot.clearance_mechanism()
    P, M = np.array([[-0.01, -0.04]]), np.array([[0.01, -0.04]])
    with pytest.raises(KinematicsError, match="mirror symmetry fails"):     # legs not swapped
        prove_mirror(mech, P, M, list(range(len(mech.joints))), X_MIRROR)
    with pytest.raises(KinematicsError, match="mirror symmetry fails"):     # not mirror poses
        prove_mirror(mech, P, np.array([[0.012, -0.04]]), mirror_joint_map(mech), X_MIRROR)
    loose = irsbot.clearance_mechanism()                                  # one joint with a looser fit
    j0 = loose.joints[0]
    loose.joints = (dataclasses.replace(j0, bounds=dataclasses.replace(j0.bounds, b_xy=2 * j0.bounds.b_xy)), *loose.joints[1:])
    with pytest.raises(KinematicsError, match="different clearance bounds"):
        prove_mirror(loose, P, M, mirror_joint_map(loose), X_MIRROR)


def test_mirrored_grid_solves_half_and_matches_the_full_grid(irsbot):
    mech = irsbot.clearance_mechanism()
    x, z = np.linspace(-0.02, 0.02, 3), np.linspace(-0.06, -0.03, 2)
    X, Z = np.meshgrid(x, z)
    poses = np.stack([X.ravel(), Z.ravel()], 1)
    res, summary = grid_max_pose_error_mirrored(mech, poses, mirror_joint_map(mech), X_MIRROR, np.array([-1.0, 1.0]), workers=1)
    full = grid_max_pose_error(mech, poses, workers=1)
    assert summary["n_solved"] == 4 and summary["n_reused"] == 2
    assert np.all(res.p_max <= full.p_upper * (1 + 1e-12)) and np.all(full.p_max <= res.p_upper * (1 + 1e-12))
    assert np.all(res.r_max <= full.r_upper * (1 + 1e-12)) and np.all(full.r_max <= res.r_upper * (1 + 1e-12))
    # the work reported is the solved half's: the mirrored half did none (its n_newton was the
    # solved half's again, so the total counted the solved poses' Newton steps twice)
    assert 0 < res.n_newton < full.n_newton and res.n_solves < full.n_solves
    proof = prove_mirror(mech, poses[:1], poses[:1] * [-1.0, 1.0], mirror_joint_map(mech), X_MIRROR)
    mirrored = mirror_maxima(max_pose_error(mech, poses[:1]), proof)
    assert mirrored.n_newton == 0 and mirrored.n_solves == 0


def test_mirrored_grid_refuses_bounds_it_cannot_prove(irsbot):
    """The mirror proof holds for the joints' own bounds; bounds passed through to the grid (which
    the docstring asked not to give, but which were used silently: the reused half then carried the
    maxima of other bounds than those proven) are a one-line ValidationError before any solve."""
    mech = irsbot.clearance_mechanism()
    poses = np.array([[-0.01, -0.05], [0.01, -0.05]])
    b = mech.thesis_bounds(b_xy=np.full(len(mech.joints), 2e-5), b_z=np.full(len(mech.joints), 2e-5))
    with pytest.raises(ValidationError) as exc:
        grid_max_pose_error_mirrored(mech, poses, mirror_joint_map(mech), X_MIRROR, np.array([-1.0, 1.0]), bounds=b)
    assert str(exc.value).startswith("bounds = 'given': expected no bounds: the mirror proof holds for the joints' own")

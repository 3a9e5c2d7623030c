"""Planar 5R symmetrical mechanism: design space, kinematics, workspace, MIC, LCI
(Lara-Molina et al. 2019, eqs. 1-22, Table 2)."""
import numpy as np
import pytest

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.planar5r import kinematics as K
from evotol.robots.planar5r.design import CASES, FIG3_DESIGN, SQRT3, TABLE2_PRINTED, Design5R, get_case

ALL = list(CASES.items()) + [("fig3", FIG3_DESIGN)]


# --- design space, eqs. 1-6 and Table 2 --------------------------------------------------------
def test_table2_lengths_sum_to_three_eq2():
    for row in TABLE2_PRINTED.values():
        assert row["r1"] + row["r2"] + row["r3"] == pytest.approx(3.0, abs=1e-12)


def test_table2_s_t_against_eqs5_6_and_printed_typos():
    for k in "abc":
        assert CASES[k].s == pytest.approx(TABLE2_PRINTED[k]["s"], abs=0.006)
    for k in "bcd":
        assert CASES[k].t == TABLE2_PRINTED[k]["t"]
    # the two printed entries that eqs. 5-6 contradict (documented in design.py / docs)
    assert CASES["a"].t == 0.80 and TABLE2_PRINTED["a"]["t"] == 0.08
    assert CASES["d"].s == pytest.approx((2 * 0.75 + 0.25) / SQRT3) and abs(CASES["d"].s - 1.80) > 0.7


def test_design_roundtrips_and_validation():
    for _, d in ALL:
        e = Design5R.from_st(d.s, d.t)
        assert (e.r1, e.r2, e.r3) == pytest.approx((d.r1, d.r2, d.r3), abs=1e-12)
    f = Design5R.from_lengths(0.094, 0.346, 0.16)
    assert (f.r1, f.r2, f.r3) == pytest.approx((0.47, 1.73, 0.80))
    with pytest.raises(ValidationError):
        Design5R(1.0, 1.0, 0.5)           # violates eq. 2
    with pytest.raises(ValidationError):
        Design5R(0.5, 0.5, 2.0)           # violates eq. 4 (r3 <= 1.5)
    with pytest.raises(ValidationError):
        get_case("e")


# --- forward / inverse kinematics, eqs. 9-15 ---------------------------------------------------
def test_eq11_12_are_the_expanded_constraints_with_A1_at_minus_r3():
    """Independent derivation: eq. 11 = |P - B_1|^2 - r2^2 with A_1 = (-r3, 0); eq. 9 as printed
    (A_1 at +r3) is not the same polynomial."""
    rng = np.random.default_rng(1)
    r1, r2, r3 = 0.6, 1.1, 1.3
    x, y, t1, t2 = rng.normal(size=(4, 50))
    c1, s1, c2, s2 = np.cos(t1), np.sin(t1), np.cos(t2), np.sin(t2)
    eq11 = x**2 + y**2 - 2 * (r1 * c1 - r3) * x - 2 * r1 * s1 * y - 2 * r1 * r3 * c1 + r3**2 + r1**2 - r2**2
    eq12 = x**2 + y**2 - 2 * (r1 * c2 + r3) * x - 2 * r1 * s2 * y + 2 * r1 * r3 * c2 + r3**2 + r1**2 - r2**2
    np.testing.assert_allclose(eq11, (x + r3 - r1 * c1) ** 2 + (y - r1 * s1) ** 2 - r2**2, atol=1e-12)
    np.testing.assert_allclose(eq12, (x - r3 - r1 * c2) ** 2 + (y - r1 * s2) ** 2 - r2**2, atol=1e-12)
    eq9_printed = (x - r1 * c1 - r3) ** 2 + (y - r1 * s1) ** 2 - r2**2
    assert np.max(np.abs(eq9_printed - eq11)) > 0.1


@pytest.mark.parametrize("name,d", ALL)
def test_forward_of_inverse_is_identity_over_usable_workspace(name, d):
    """Forward(inverse(p)) = p to 1e-12 on a 301x301 grid of the usable workspace (LCI >= 0.01)."""
    uw = K.usable_workspace(d.r1, d.r2, d.r3, n=301)
    P = uw.points()
    th = K.inverse_kinematics(P, d.r1, d.r2, d.r3)
    lci = K.local_conditioning_index(P, d.r1, d.r2, d.r3)
    err = np.max(np.abs(K.forward_kinematics(th, d.r1, d.r2, d.r3) - P), axis=1)
    assert len(P) > 100
    assert err[lci >= 0.01].max() < 1e-12
    # towards the border (LCI -> 0) the rounding error grows like eps / LCI, as conditioning says
    assert np.all(err * lci < 1e-14)


EXTENDED = np.finfo(np.longdouble).eps < 1e-18


@pytest.mark.skipif(not EXTENDED, reason="np.longdouble is not 80-bit extended on this platform")
@pytest.mark.parametrize("name,d", ALL)
@pytest.mark.parametrize("n", [201, 301])
def test_forward_of_inverse_in_long_double_holds_1e12_on_whole_usable_workspace(name, d, n):
    """Forward(inverse(p)) = p to 1e-12 at every grid point of the usable workspace, border included.

    The kinematics keep the dtype of their input; in long double the error stays at eps_ld / LCI."""
    uw = K.usable_workspace(d.r1, d.r2, d.r3, n=n)
    P = uw.points().astype(np.longdouble)
    th = K.inverse_kinematics(P, d.r1, d.r2, d.r3)
    assert th.dtype == np.longdouble
    back = K.forward_kinematics(th, d.r1, d.r2, d.r3)
    assert back.dtype == np.longdouble
    err = np.max(np.abs(back - P), axis=1).astype(float)
    lci = K.local_conditioning_index(P.astype(float), d.r1, d.r2, d.r3)
    assert err.max() < 1e-12
    assert np.all(err * lci < 100 * np.finfo(np.longdouble).eps)
    # the float64 path is unchanged by the dtype handling
    assert K.inverse_kinematics(P.astype(float), d.r1, d.r2, d.r3).dtype == np.float64


@pytest.mark.parametrize("name,d", ALL)
def test_both_branches_satisfy_constraints_and_are_mirror_images(name, d):
    uw = K.usable_workspace(d.r1, d.r2, d.r3, n=61)
    P = uw.points()
    th = K.inverse_kinematics(P, d.r1, d.r2, d.r3)
    B = K.crank_points(th, d.r1, d.r3)
    for sigma in (1, -1):
        Q = K.forward_kinematics(th, d.r1, d.r2, d.r3, assembly=sigma)
        np.testing.assert_allclose(np.linalg.norm(Q[:, None, :] - B, axis=-1), d.r2, atol=1e-12)
        assert np.all(np.sign(K.type2_determinant(Q, th, d.r1, d.r3)) == sigma)
    # the sigma = -1 point is the reflection of the sigma = +1 point across the line B1B2
    Qm = K.forward_kinematics(th, d.r1, d.r2, d.r3, assembly=-1)
    mid = B.mean(axis=1)
    np.testing.assert_allclose(Qm + P, 2 * mid, atol=1e-10)


@pytest.mark.parametrize("mode", sorted(K.WORKING_MODES))
def test_inverse_kinematics_working_modes(mode):
    d = CASES["c"]
    P = np.array([[0.0, 0.75], [0.1, 0.8], [-0.15, 0.7]])
    th = K.inverse_kinematics(P, d.r1, d.r2, d.r3, mode)
    B = K.crank_points(th, d.r1, d.r3)
    np.testing.assert_allclose(np.linalg.norm(P[:, None, :] - B, axis=-1), d.r2, atol=1e-12)
    A = np.array([[-d.r3, 0.0], [d.r3, 0.0]])
    signs = np.sign(K.cross2(P[:, None, 0] - A[:, 0], P[:, None, 1] - A[:, 1], B[..., 0] - A[:, 0], B[..., 1] - A[:, 1]))
    assert np.all(signs == np.array(K.WORKING_MODES[mode]))


@pytest.mark.parametrize("name,d", ALL)
def test_eq13_15_closed_form_corrected_and_printed(name, d):
    """eqs. 13-15 with e = r1 (sin th1 - sin th2)/den reproduce the circle intersection where
    B_2 is right of B_1 (sigma = +1 = larger root); e as printed violates the constraints."""
    uw = K.usable_workspace(d.r1, d.r2, d.r3, n=81)
    P = uw.points()
    th = K.inverse_kinematics(P, d.r1, d.r2, d.r3)
    B = K.crank_points(th, d.r1, d.r3)
    right = (B[:, 1, 0] - B[:, 0, 0]) > 1e-3 * d.r1
    assert right.sum() > 10
    Q = K.forward_kinematics_eq15(th[right], d.r1, d.r2, d.r3, sigma=1)
    np.testing.assert_allclose(Q, P[right], atol=1e-9)
    with np.errstate(invalid="ignore"):
        Qp = K.forward_kinematics_eq15(th[right], d.r1, d.r2, d.r3, sigma=1, printed=True)
    # eq. 14 substitutes x = e y + f into eq. 11, so chain 1 always closes; chain 2 does not
    resid = np.abs(np.linalg.norm(Qp - B[right][:, 1], axis=-1) - d.r2)
    wrong = ~np.isfinite(resid) | (resid > 1e-6)     # no real root, or a point off circle 2
    assert wrong.mean() > 0.5


def test_forward_kinematics_errors_are_named():
    d = CASES["b"]
    with pytest.raises(KinematicsError, match="outside the theoretical workspace"):
        K.inverse_kinematics([[0.0, 5.0]], d.r1, d.r2, d.r3)
    with pytest.raises(KinematicsError, match="cannot be assembled"):
        K.forward_kinematics([[np.pi, 0.0]], d.r1, 0.3, d.r3)
    with pytest.raises(ValidationError):
        K.forward_kinematics([[1.0, 2.0]], d.r1, d.r2, d.r3, assembly=0)
    with pytest.raises(ValidationError):
        K.inverse_kinematics([[0.0, 1.5]], d.r1, d.r2, d.r3, working_mode="+0")


# --- Jacobians, singular loci, LCI -------------------------------------------------------------
@pytest.mark.parametrize("name,d", ALL)
def test_jacobian_matches_finite_differences(name, d):
    uw = K.usable_workspace(d.r1, d.r2, d.r3, n=61)
    P = uw.points()
    P = P[K.local_conditioning_index(P, d.r1, d.r2, d.r3) > 0.05]
    th = K.inverse_kinematics(P, d.r1, d.r2, d.r3)
    J = K.jacobian(P, th, d.r1, d.r3)
    h = 1e-6
    fd = np.stack([(K.forward_kinematics(th + h * np.eye(2)[k], d.r1, d.r2, d.r3)
                    - K.forward_kinematics(th - h * np.eye(2)[k], d.r1, d.r2, d.r3)) / (2 * h) for k in range(2)], -1)
    assert np.max(np.abs(J - fd)) < 1e-5 * np.max(np.abs(J))


def test_lci_closed_form_equals_numpy_condition_number():
    d = CASES["d"]
    uw = K.usable_workspace(d.r1, d.r2, d.r3, n=41)
    P = uw.points()
    th = K.inverse_kinematics(P, d.r1, d.r2, d.r3)
    J = K.jacobian(P, th, d.r1, d.r3)
    np.testing.assert_allclose(K.local_conditioning_index(P, d.r1, d.r2, d.r3), 1 / np.linalg.cond(J), rtol=1e-9, atol=1e-12)


def test_type2_locus_exists_exactly_when_its_conditions_hold():
    """The locus exists when |B1B2| = 2 r2 is reachable (r2 <= r1 + r3) or B1 = B2 is (r1 >= r3);
    case b (r1 = 0.47, r2 = 1.73, r3 = 0.8) has neither: no type II singularity at all."""
    for name, d in ALL:
        L = K.type2_locus(d.r1, d.r2, d.r3, n=400)
        assert (len(L) > 0) == (d.r2 <= d.r1 + d.r3 or d.r1 >= d.r3), name
    assert len(K.type2_locus(CASES["b"].r1, CASES["b"].r2, CASES["b"].r3, n=400)) == 0


@pytest.mark.parametrize("name,d", [(n, d) for n, d in ALL if n != "b"])
def test_type2_locus_is_singular(name, d):
    L = K.type2_locus(d.r1, d.r2, d.r3, n=400)
    assert len(L) > 0
    t1, t2, ok = K.inverse_kinematics_raw(L[:, 0], L[:, 1], d.r1, d.r2, d.r3)
    th = np.stack([t1, t2], -1)[ok]
    det = K.type2_determinant(L[ok], th, d.r1, d.r3)
    assert ok.any() and np.max(np.abs(det)) < 1e-9


def test_type1_circles_are_serial_singularities_eq16_19():
    d = FIG3_DESIGN
    for c in K.type1_circles(d.r1, d.r2, d.r3):
        ang = np.linspace(0.3, 2.8, 7)
        P = np.stack([c["cx"] + c["radius"] * np.cos(ang), c["radius"] * np.sin(ang)], -1)
        t1, t2, ok = K.inverse_kinematics_raw(P[:, 0], P[:, 1], d.r1, d.r2, d.r3)
        _, jq = K.jacobians(P, np.stack([t1, t2], -1), d.r1, d.r3)
        chain = 0 if c["cx"] < 0 else 1
        assert np.max(np.abs(jq[:, chain])) < 1e-6


# --- MIC, eqs. 20-22 ---------------------------------------------------------------------------
@pytest.mark.parametrize("name,d", ALL)
def test_mic_closed_form_matches_numeric_search(name, d):
    cf = K.mic_closed_form(d.r1, d.r2, d.r3)
    num = K.mic_numeric(d.r1, d.r2, d.r3)
    assert cf["equation"] == d.mic_case
    assert num["radius"] == pytest.approx(cf["radius"], abs=1e-6)
    assert num["center_y"] == pytest.approx(cf["center_y"], abs=1e-4)


def test_mic_eq22_touches_the_collinear_posture_and_outer_circles():
    """Independent derivation of eq. 22: the circle passes through (0, y_col), where
    B_1 = (-r2, y_col), P, B_2 = (r2, y_col) are aligned, and is internally tangent to eqs. 16/18."""
    for d in (CASES["a"], CASES["c"], FIG3_DESIGN):
        m = K.mic_closed_form(d.r1, d.r2, d.r3)
        assert m["center_y"] - m["radius"] == pytest.approx(m["y_col"])
        assert np.hypot(-d.r2 + d.r3, m["y_col"]) == pytest.approx(d.r1)
        assert np.hypot(d.r3, m["center_y"]) + m["radius"] == pytest.approx(d.r1 + d.r2)


@pytest.mark.parametrize("name,d", ALL)
def test_mic_disk_lies_in_usable_workspace(name, d):
    m = K.mic_closed_form(d.r1, d.r2, d.r3)
    uw = K.usable_workspace(d.r1, d.r2, d.r3, n=201)
    X, Y = np.meshgrid(uw.x, uw.y)
    inside = X**2 + (Y - m["center_y"]) ** 2 <= (0.98 * m["radius"]) ** 2
    assert inside.sum() > 0 and np.all(uw.mask[inside])


def test_lci_values_against_paper_cases_b_and_d():
    """Sec. 3.2: case b LCI ~ 0.9; Sec. 3.4: case d max(LCI) = 0.55 (measured values in docs)."""
    b, dd = CASES["b"], CASES["d"]
    mb = K.mic_closed_form(b.r1, b.r2, b.r3)
    lci_b_centre = K.local_conditioning_index([0.0, mb["center_y"]], b.r1, b.r2, b.r3)
    assert 0.9 <= lci_b_centre <= 0.95
    uw_b = K.usable_workspace(b.r1, b.r2, b.r3, n=201)
    assert np.nanpercentile(uw_b.lci, 90) == pytest.approx(0.9, abs=0.03)
    uw_d = K.usable_workspace(dd.r1, dd.r2, dd.r3, n=201)
    assert uw_d.lci_max == pytest.approx(0.55, abs=0.035)
    # the maximum is 1/sqrt(3) on the symmetry axis
    assert uw_d.lci_max == pytest.approx(1 / np.sqrt(3), abs=2e-3)


def test_inverse_kinematics_error_with_array_lengths_names_the_pose_and_its_lengths():
    """Lengths given per pose (arrays broadcast with the poses): an unreachable pose is the
    KinematicsError naming that pose and the lengths at it, not a TypeError from formatting an
    array with ``:g``; scalar lengths keep the message they had."""
    P = [[0.0, 0.5], [0.0, 5.0]]
    with pytest.raises(KinematicsError) as ei:
        K.inverse_kinematics(P, np.array([1.0, 1.2]), 1.0, np.array([0.5, 0.25]))
    assert str(ei.value) == ("5R: pose [0.0, 5.0] (x, y) is outside the theoretical workspace "
                             "(eqs. 16-19) of r1=1.2, r2=1, r3=0.25")
    assert np.array_equal(ei.value.poses, [[0.0, 5.0]])
    with pytest.raises(KinematicsError) as ei:
        K.inverse_kinematics(P, 1.0, 1.0, 0.5)
    assert str(ei.value).endswith("of r1=1, r2=1, r3=0.5")


def test_mic_closed_form_refuses_array_lengths():
    """Eqs. 21-22 are for one design: lengths given as arrays (one or several elements) are a
    ValidationError naming the length, not a TypeError from the ``:g`` formatting of eq. 22's
    KinematicsError (nor an ambiguous-truth ValueError); scalars still reach that error."""
    for r1 in (np.array([0.1]), np.array([0.1, 0.2])):
        with pytest.raises(ValidationError) as ei:
            K.mic_closed_form(r1, 0.5, 1.0)
        assert str(ei.value) == f"r1 = {r1.tolist()!r}: expected a scalar length"
    with pytest.raises(KinematicsError, match=r"eq. 22 needs r1 >= \|r2 - r3\| \(r1=0.1, r2=0.5, r3=1\)"):
        K.mic_closed_form(np.float64(0.1), np.asarray(0.5), 1.0)

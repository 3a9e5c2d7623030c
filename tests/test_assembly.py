"""Assembly-function error models (robots/assembly/): derivatives against closed forms and
central differences, the normalised-response convention, bad input."""
import warnings

import numpy as np
import pytest

from evotol.cost_models import PowerCost
from evotol.allocators.process import assembly_problem
from evotol.errors import ValidationError
from evotol.core.problem import Tolerance
from evotol.studies._process_benchmarks import CLUTCH_LIMIT_RAD, CLUTCH_NOMINAL, clutch_angle, clutch_assembly
from evotol.robots.assembly import AssemblyFunction, LinearStack, resolve
from evotol.robots.base import check_robot


def clutch_gradient_closed_form(a, c, e):
    """∂φ/∂(a, c, e) of φ = arccos((a + c)/(e − c)) (Chase handbook eq. 14.6), by hand."""
    u = (a + c) / (e - c)
    k = -1 / np.sqrt(1 - u ** 2)
    return k * np.array([1 / (e - c), (e - c + a + c) / (e - c) ** 2, -(a + c) / (e - c) ** 2])


def test_clutch_nominal_angle_and_complex_step_gradient_match_closed_form():
    asm = clutch_assembly()
    assert np.degrees(asm.y0[0]) == pytest.approx(7.0184, abs=1e-3)  # the literature's 7.0184°
    assert asm.derivative_method == "complex step"
    expected = clutch_gradient_closed_form(*[CLUTCH_NOMINAL[n] for n in "ace"])
    np.testing.assert_allclose(asm.gradient[0], expected, rtol=1e-12)


def test_clutch_passes_check_robot_nonlinear_against_first_order():
    asm = clutch_assembly()
    rep = check_robot(asm, asm.response_poses, step=1e-8)
    assert rep["fd_relative_mismatch"] < 1e-5


def test_jacobian_at_many_points_matches_central_differences():
    asm = clutch_assembly()
    rng = np.random.default_rng(0)
    P = asm.x0 * (1 + 1e-3 * rng.uniform(-1, 1, size=(50, 3)))
    np.testing.assert_allclose(asm.jacobian(P), asm.central_differences(P), rtol=1e-6)
    np.testing.assert_allclose(asm.jacobian(P)[:, 0, :], np.array([clutch_gradient_closed_form(*p) for p in P]), rtol=1e-12)
    # outside arccos's domain the complex step would return a finite, meaningless number: refused
    with pytest.raises(ValidationError, match="every response is finite"):
        asm.jacobian(asm.x0 * np.array([1.02, 1.0, 1.0]))


def test_function_that_is_not_complex_safe_falls_back_to_central_differences_with_a_note():
    def real_only(a, c, e):
        return np.real(clutch_angle(a, c, e))

    with pytest.warns(RuntimeWarning, match="central differences"):
        asm = AssemblyFunction(real_only, CLUTCH_NOMINAL, {"phi": CLUTCH_LIMIT_RAD})
    assert asm.derivative_method.startswith("central differences")
    expected = clutch_gradient_closed_form(*[CLUTCH_NOMINAL[n] for n in "ace"])
    np.testing.assert_allclose(asm.gradient[0], expected, rtol=1e-6)


def test_linear_stack_worst_case_and_rss_are_the_arithmetic_and_statistical_stacks():
    stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})
    t = np.array([1e-5, 2e-5, 4e-5])
    tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), 1e-6, 1e-4) for n in stack.source_names}
    wc = assembly_problem(stack, tol, "worst_case").evaluate(t[None]).position[0, 0]
    rss = assembly_problem(stack, tol, "rss").evaluate(t[None]).position[0, 0]
    assert wc == pytest.approx((1e-5 + 4e-5 + 2e-5) / 1e-4, rel=1e-12)
    assert rss == pytest.approx(np.sqrt(1e-10 + 16e-10 + 4e-10) / 1e-4, rel=1e-12)


def test_several_responses_each_divided_by_its_own_limit():
    def gap_and_angle(x, y):
        return x - y, np.arctan((x - y) / 0.1)

    asm = AssemblyFunction(gap_and_angle, {"x": 0.02, "y": 0.01}, {"gap": 1e-4, "angle": 1e-3})
    tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), 1e-6, 1e-4) for n in asm.source_names}
    p = assembly_problem(asm, tol, "worst_case")
    t = np.array([2e-5, 3e-5])
    err = p.evaluate(t[None]).position[0]
    d_angle = 0.1 / (0.1 ** 2 + 0.01 ** 2)           # ∂ atan(g / 0.1)/∂g at g = 0.01
    np.testing.assert_allclose(err, [(5e-5) / 1e-4, d_angle * 5e-5 / 1e-3], rtol=1e-10)
    # Monte Carlo's nonlinear model: a pure +x error moves both responses by their exact change
    e = np.zeros((2, 1, 2))
    e[:, 0, 0] = 1e-5
    out = asm.pose_error(asm.response_poses, e)
    assert out[0, 0, 2] == pytest.approx(1e-5 / 1e-4, rel=1e-9)
    assert out[1, 0, 2] == pytest.approx((np.arctan2(0.01 + 1e-5, 0.1) - np.arctan2(0.01, 0.1)) / 1e-3, rel=1e-9)


def _nan_at_nominal(a, c, e):
    return np.arccos((a + c) / (e - c) + 1.0)       # argument > 1: NaN


def _raises(a, c, e):
    raise ZeroDivisionError("hub too thin")


@pytest.mark.parametrize("make, field_part", [
    (lambda: AssemblyFunction(_nan_at_nominal, CLUTCH_NOMINAL, {"phi": 0.03}), "response 'phi' at the nominal"),
    (lambda: AssemblyFunction(_raises, CLUTCH_NOMINAL, {"phi": 0.03}), "function at the nominal"),
    (lambda: AssemblyFunction(clutch_angle, {**CLUTCH_NOMINAL, "e": float("nan")}, {"phi": 0.03}), "nominal['e']"),
    (lambda: AssemblyFunction(clutch_angle, CLUTCH_NOMINAL, {"phi": -1.0}), "limits['phi']"),
    (lambda: AssemblyFunction(clutch_angle, CLUTCH_NOMINAL, {"phi": 0.03, "gap": 1e-4}), "response shape"),
    (lambda: LinearStack({"x": float("inf")}, {"gap": 1e-4}), "sensitivities['gap']['x']"),
    (lambda: resolve("no_colon_here"), "robot.assembly"),
    (lambda: resolve("math:not_a_function"), "robot.assembly"),
])
def test_bad_assembly_input_names_the_field(make, field_part):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        with pytest.raises(ValidationError) as err:
            make()
    assert field_part in err.value.field


def test_raising_function_error_says_what_failed():
    with pytest.raises(ValidationError, match="ZeroDivisionError: hub too thin"):
        AssemblyFunction(_raises, CLUTCH_NOMINAL, {"phi": 0.03})

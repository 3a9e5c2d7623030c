"""Conformance suites over every registered robot and cost model (issue 11 item 5).

Each (plugin, check) pair is its own pytest id, like scikit-learn's ``parametrize_with_checks``;
the registries include entry points, so an installed plugin is checked here too. The second half
shows that each check can fail: broken plugins are caught, and ``check_robot`` /
``check_cost_model`` report every failing check, not only the first.
"""
from functools import lru_cache

import numpy as np
import pytest

import evotol.cost_models as cm
from evotol.cost_models.checks import cost_model_checks
from evotol.errors import KinematicsError
from evotol.robots import registry as robot_registry
from evotol.robots.base import RobotErrorModel, SourceSpec, Workspace
from evotol.robots.checks import CHECKS, check_robot, robot_checks

ROBOTS = sorted(robot_registry.available())
COST_MODELS = sorted(cm.available())
COST_CHECKS = ["check_named", "check_vectorised", "check_positive_and_monotone", "check_derivative_matches_fd",
               "check_convexity_flag", "check_pickle_round_trip", "check_dict_round_trip"]
T_RANGE = (0.5e-5, 8e-5)      # 0.5 to 8 shop units of the examples (scale 1e-5 m)


@lru_cache(maxsize=None)
def _robot_checks(name):
    return dict(robot_checks(robot_registry.available()[name](), rtol=1e-5))


@pytest.mark.parametrize("name, check", [(r, c.__name__) for r in ROBOTS for c in CHECKS])
def test_registered_robot(name, check):
    """Every registered robot (built-ins and entry points) with its default construction."""
    _robot_checks(name)[check]()


def _shipped_models():
    """Robots that are not classes of the registry: every shipped mechanism description (as
    ``mechanism = NAME`` builds it) and the process-selection studies' assemblies."""
    from evotol.studies._process_benchmarks import clutch_assembly, stack_problem
    from evotol.robots.mechanism.model.error_model import SHIPPED, MechanismModel, resolve_description

    models = {f"mechanism:{p.stem}": (lambda n=p.stem: MechanismModel(resolve_description(n)))
              for p in sorted(SHIPPED.glob("*.toml"))}
    models["assembly:clutch"] = clutch_assembly
    models["assembly:linear-stack"] = lambda: stack_problem().model
    return models


SHIPPED_MODELS = _shipped_models()


@lru_cache(maxsize=None)
def _shipped_checks(name):
    return dict(robot_checks(SHIPPED_MODELS[name](), rtol=1e-5))


@pytest.mark.parametrize("name, check", [(r, c.__name__) for r in SHIPPED_MODELS for c in CHECKS])
def test_shipped_description_and_assembly(name, check):
    """Every shipped mechanism description and assembly model passes the same checks (issue 11)."""
    _shipped_checks(name)[check]()


@pytest.mark.parametrize("name, check", [(m, c) for m in COST_MODELS for c in COST_CHECKS])
def test_registered_cost_model(name, check):
    """Every registered cost model's ``example()`` on 0.5-8 x its scale."""
    checks = dict(cost_model_checks(cm.available()[name].example(), *T_RANGE))
    checks[check]()


def test_sum_of_registered_models_round_trips():
    m = cm.SumCost(cm.ExponentialCost(1.0, 0.5, scale=1e-5), cm.ReciprocalCost(0.0, 0.5, scale=1e-5))
    rep = cm.check_cost_model(m, *T_RANGE)
    assert "check_dict_round_trip" in dict(cost_model_checks(m, *T_RANGE)) and rep["convex"] is True
    t = np.geomspace(*T_RANGE, 7)        # the sum is the sum of its terms (closed forms, x = t / 1e-5)
    x = t / 1e-5
    np.testing.assert_allclose(m.cost(t), 1.0 * np.exp(-0.5 * x) + 0.5 / x, rtol=1e-12)


# --- the checks can fail -------------------------------------------------------------------------
class _Broken(RobotErrorModel):
    """A linear robot with three planted faults: it returns NaN out of reach (no check_poses),
    its sensitivity of a pose depends on the other poses of the call (a batch mean leaks in), and
    it holds a lambda (cannot be pickled to worker processes)."""

    name = "broken"

    def __init__(self):
        self.sources = (SourceSpec("a", 1, "m"), SourceSpec("b", 2, "rad"))
        self.workspace = Workspace(("x",), (0.0,), (1.0,), ("m",))
        self.gain = lambda x: 1.0 + x

    def sensitivity(self, poses):
        x = np.atleast_2d(np.asarray(poses, float))[:, 0]
        J = np.zeros((len(x), 6, 3))
        J[:, 0, :] = (self.gain(x) + x.mean())[:, None]
        J[:, 1, 0] = np.where(x > 1.0, np.nan, 0.0)
        return J


def test_check_robot_reports_every_failure():
    with pytest.raises(AssertionError) as exc:
        check_robot(_Broken())
    msg = str(exc.value)
    for check in ("check_pose_subset_invariance", "check_pickle_round_trip", "check_out_of_reach_raises"):
        assert check in msg, msg
    assert "fails 3 check(s)" in msg


def test_out_of_reach_check_accepts_a_kinematics_error():
    class Guarded(_Broken):
        def sensitivity(self, poses):
            if np.any(np.asarray(poses) > 1.0):
                raise KinematicsError("pose out of reach")
            return super().sensitivity(poses)

    dict(robot_checks(Guarded()))["check_out_of_reach_raises"]()


def test_units_check_catches_a_non_si_workspace():
    r = _Broken()
    r.workspace = Workspace(("x",), (0.0,), (1.0,), ("mm",))
    with pytest.raises(AssertionError, match="workspace units"):
        dict(robot_checks(r))["check_units_declared"]()


def _concave(x):
    return 100.0 - x ** 2       # decreasing and concave on 0.5-8


def _rising(x):
    return 1.0 + x


def test_cost_checks_catch_a_false_convexity_flag_and_a_rising_cost():
    concave = cm.CallableCost(_concave, name="concave", scale=1e-5, convex=True)
    with pytest.raises(AssertionError, match="declares convex = True"):
        dict(cost_model_checks(concave, *T_RANGE))["check_convexity_flag"]()
    rising = cm.CallableCost(_rising, name="rising", scale=1e-5)
    with pytest.raises(AssertionError) as exc:
        cm.check_cost_model(rising, *T_RANGE)
    assert "check_positive_and_monotone" in str(exc.value)


def test_cost_checks_catch_a_wrong_derivative_and_an_unpicklable_model():
    wrong = cm.CallableCost(_concave, dfunc=lambda x: -1.0 / x, name="wrong", scale=1e-5)
    with pytest.raises(AssertionError) as exc:
        cm.check_cost_model(wrong, *T_RANGE)
    msg = str(exc.value)
    assert "check_derivative_matches_fd" in msg and "check_pickle_round_trip" in msg and "fails 2 check(s)" in msg


def test_dict_round_trip_check_catches_a_lossy_to_dict():
    class Lossy(cm.ExponentialCost):
        def to_dict(self):
            return {"model": "exponential", "a0": self.params["a0"], "a1": 2 * self.params["a1"], "scale": self.scale}

    checks = dict(cost_model_checks(Lossy(1.9, 0.5, scale=1e-5), *T_RANGE))
    # a subclass is not what the registry builds: the check is not offered for it
    assert "check_dict_round_trip" not in checks
    from evotol.cost_models.checks import check_dict_round_trip
    with pytest.raises(AssertionError, match="from_dict"):
        check_dict_round_trip(Lossy(1.9, 0.5, scale=1e-5), *T_RANGE)

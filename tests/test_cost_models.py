"""Cost–tolerance models: closed forms, derivatives vs finite differences, validation, fitting."""
import numpy as np
import pytest

import evotol.cost_models as cm
from evotol.errors import ValidationError

ALL = [cm.ExponentialCost(1.9, 0.5, scale=1e-5), cm.PowerCost(2.0, 1.3, scale=1e-5), cm.ReciprocalCost(0.2, 1.5, scale=1e-5),
       cm.ReciprocalSquareCost(0.1, 2.0, scale=1e-5), cm.ExpReciprocalCost(1.0, 0.5, 0.2, scale=1e-5),
       cm.Polynomial3Cost(10.0, -3.0, 0.3, -0.01, scale=1e-5), cm.Polynomial4Cost(12.0, -4.0, 0.6, -0.04, 0.0009, scale=1e-5),
       cm.LinearExponentialCost(0.5, -0.01, 3.0, 0.4, scale=1e-5),
       cm.SumCost(cm.ExponentialCost(1.0, 0.5, scale=1e-5), cm.ReciprocalCost(0.0, 0.5, scale=1e-5))]


def test_yao2013_eq13_table_costs():
    """Yao 2013 eq. 13 with (1.9, 0.5) for lengths and (1.1, 0.6) for joints reproduces Tables 1–2 costs."""
    L, J = cm.ExponentialCost(1.9, 0.5, scale=1e-5), cm.ExponentialCost(1.1, 0.6, scale=1e-5)
    t1 = np.array([4.94, 4.81, 4.96]), np.array([2.94, 2.93, 2.97, 2.95, 2.96, 2.94, 2.98, 2.93, 2.89])
    t2 = np.array([1.38] * 3), np.array([2.21, 2.19, 2.17, 4.29, 4.34, 4.31, 4.30, 4.37, 4.32])
    c1 = L.cost(t1[0] * 1e-5).sum() + J.cost(t1[1] * 1e-5).sum()
    c2 = L.cost(t2[0] * 1e-5).sum() + J.cost(t2[1] * 1e-5).sum()
    assert c1 == pytest.approx(2.1837, abs=2e-3)
    assert c2 == pytest.approx(4.2391, abs=2e-3)


@pytest.mark.parametrize("model", ALL, ids=lambda m: m.name)
def test_conformance_and_derivatives(model):
    """Every built-in passes check_cost_model: dcost matches central differences, cost vectorised."""
    rep = cm.check_cost_model(model, 0.5e-5, 8e-5)
    assert rep["dcost_fd_relative_error"] < 1e-5
    t = np.linspace(1e-5, 5e-5, 7)
    h = 1e-10
    d2 = (model.dcost(t + h) - model.dcost(t - h)) / (2 * h)
    np.testing.assert_allclose(model.d2cost(t), d2, rtol=1e-3, atol=1e-3 * np.max(np.abs(d2)))


def test_closed_forms():
    t = np.array([1e-5, 3e-5])
    np.testing.assert_allclose(cm.PowerCost(2.0, 1.5, scale=1e-5).cost(t), 2.0 * np.array([1, 3]) ** -1.5)
    np.testing.assert_allclose(cm.ReciprocalCost(1.0, 2.0, scale=1e-5).cost(t), 1 + 2 / np.array([1, 3]))
    np.testing.assert_allclose(cm.ReciprocalSquareCost(1.0, 2.0, scale=1e-5).cost(t), 1 + 2 / np.array([1, 9]))
    np.testing.assert_allclose(cm.ExpReciprocalCost(2.0, 1.0, 0.5, scale=1e-5).cost(t), 2 / np.array([1, 3]) * np.exp(-0.5 * np.array([1, 3])))


@pytest.mark.parametrize("cls,params,field", [
    (cm.ExponentialCost, (1.0, -0.5), "exponential.a1"),
    (cm.ExponentialCost, (-1.0, 0.5), "exponential.a0"),
    (cm.PowerCost, (1.0, 0.0), "power.a1"),
    (cm.ReciprocalCost, (1.0, -2.0), "reciprocal.a1"),
])
def test_bad_parameters_are_named(cls, params, field):
    with pytest.raises(ValidationError) as e:
        cls(*params)
    assert field in str(e.value)


def test_range_rejects_negative_or_increasing_cost():
    # reciprocal with a0 < 0 goes negative for large t
    with pytest.raises(ValidationError, match="non-negative"):
        cm.ReciprocalCost(-1.0, 1.0, scale=1e-5, t_max=5e-5)
    # a cubic that turns upward inside the range
    with pytest.raises(ValidationError, match="does not increase"):
        cm.Polynomial3Cost(10.0, -3.0, 0.35, 0.0, scale=1e-5, t_max=10e-5)
    with pytest.raises(ValidationError, match="scale"):
        cm.ExponentialCost(1, 1, scale=0)
    with pytest.raises(ValidationError, match="a real number"):
        cm.ExponentialCost("x", 1)


def test_fit_recovers_parameters_of_noise_free_data():
    t = np.linspace(0.5e-5, 8e-5, 15)
    for model in [cm.ExponentialCost(1.9, 0.5, scale=1e-5), cm.PowerCost(2.0, 1.3, scale=1e-5),
                  cm.ReciprocalSquareCost(0.1, 2.0, scale=1e-5), cm.ExpReciprocalCost(1.0, 0.5, 0.2, scale=1e-5)]:
        fit = cm.fit(model.name, t, model.cost(t), scale=1e-5)
        np.testing.assert_allclose(fit.model.p, model.p, rtol=1e-5)
        assert fit.r2 > 1 - 1e-10


def test_fit_reports_quality_on_noisy_data():
    rng = np.random.default_rng(0)
    t = np.linspace(1e-5, 1e-4, 20)
    c = 3 * np.exp(-0.4 * t / 1e-5) * (1 + 0.02 * rng.normal(size=t.size))
    good = cm.fit("index", t, c, scale=1e-5)
    bad = cm.fit("reciprocal", t, c, scale=1e-5)
    assert good.r2 > 0.99 and good.r2 > bad.r2
    assert "R²" in good.summary()
    with pytest.raises(ValidationError, match="at least"):
        cm.fit("exponential", t[:2], c[:2])
    with pytest.raises(ValidationError, match="tolerances"):
        cm.fit("exponential", -t, c)


def _shop_cost(x):
    return 5.0 / (1 + x)


def test_user_models_callable_registry_and_dict():
    # a module-level function: the model pickles to worker processes (a lambda would not)
    m = cm.CallableCost(_shop_cost, name="shop", scale=1e-5, t_min=1e-6, t_max=1e-4)
    cm.check_cost_model(m, 1e-6, 1e-4)
    assert m.cost(1e-5) == pytest.approx(2.5)
    assert cm.get("index") is cm.ExponentialCost
    built = cm.from_dict({"model": "power", "a0": 2, "a1": 1.5, "scale": 1e-3})
    assert isinstance(built, cm.PowerCost) and built.scale == 1e-3
    with pytest.raises(ValidationError, match="cost model"):
        cm.get("no-such-model")
    with pytest.raises(ValidationError, match="a callable"):
        cm.CallableCost(3.0)


@pytest.mark.parametrize("p0", [[1.0], [1, 2, 3], [float("nan"), 1.0], ["a", "b"]])
def test_fit_refuses_an_initial_guess_of_the_wrong_size_or_not_finite(p0):
    """``fit(p0=...)`` with one coefficient short (was an IndexError inside the model), too many
    (was an error about the model's *parameters*), a NaN (was scipy's 'outside of provided bounds')
    or text is refused in one line naming ``p0`` and the coefficients expected."""
    t = np.array([1, 2, 4, 8, 16]) * 1e-5
    with pytest.raises(ValidationError) as exc:
        cm.fit("reciprocal", t, 10 + 5e-4 / t, p0=p0)
    assert str(exc.value) == f"p0 = {p0!r}: expected 2 finite initial coefficients ('a0', 'a1')"
    assert cm.fit("reciprocal", t, 10 + 5e-4 / t, p0=[1, 1]).model.p == pytest.approx([10, 5e-4], rel=1e-9)


def test_reciprocal_power_is_the_one_model_behind_reciprocal_and_reciprocal_square():
    """Issue 32 item 5: ``a0 + a1/x^k`` with k = 1 and k = 2 gives the reciprocal and
    reciprocal-square models to the last bit (cost, dcost, d2cost); the old names keep their
    registry names, coefficients and ``to_dict`` round trip."""
    t = np.geomspace(1e-7, 1e-3, 50)
    for old, k in ((cm.ReciprocalCost, 1), (cm.ReciprocalSquareCost, 2)):
        a, b = old(0.3, 1.7, scale=1e-5), cm.ReciprocalPowerCost(0.3, 1.7, k, scale=1e-5)
        assert isinstance(a, cm.ReciprocalPowerCost) and a.exponent == k and a.param_names == ("a0", "a1")
        for f in ("cost", "dcost", "d2cost"):
            np.testing.assert_array_equal(getattr(a, f)(t), getattr(b, f)(t))
        assert cm.get(old.name) is old
        back = cm.from_dict(a.to_dict())
        assert type(back) is old and back.to_dict() == a.to_dict() == {"model": old.name, "a0": 0.3, "a1": 1.7, "scale": 1e-5}
    m = cm.ReciprocalPowerCost(0.3, 1.7, 1.4, scale=1e-5)
    assert cm.from_dict(m.to_dict()).to_dict() == m.to_dict() == {"model": "reciprocal_power", "a0": 0.3, "a1": 1.7,
                                                                  "k": 1.4, "scale": 1e-5}
    np.testing.assert_allclose(m.cost(t), 0.3 + 1.7 * (t / 1e-5) ** -1.4, rtol=1e-14)
    assert cm.get("negative_square") is cm.ReciprocalSquareCost
    with pytest.raises(ValidationError, match=r"reciprocal_power\.k"):
        cm.ReciprocalPowerCost(0.3, 1.7, 0.0)
    with pytest.raises(ValidationError, match=r"reciprocal_square\.a1"):
        cm.ReciprocalSquareCost(0.3, -1.0)


def test_fit_recovers_the_exponent_of_a_reciprocal_power_law():
    """The exponent is a fitted coefficient: noise-free ``0.5 + 3/x^1.7`` is recovered from the
    model's own starting guess (the best of a few exponents)."""
    t = np.linspace(0.5e-5, 8e-5, 15)
    truth = cm.ReciprocalPowerCost(0.5, 3.0, 1.7, scale=1e-5)
    fit = cm.fit("reciprocal_power", t, truth.cost(t), scale=1e-5)
    np.testing.assert_allclose(fit.model.p, truth.p, rtol=1e-6)
    assert cm.ReciprocalPowerCost.initial_guess(t, truth.cost(t), scale=1e-5)[2] in (1.5, 2.0)


class _LogCost(cm.CostModel):
    """c = a0 - a1·log x (a plugin model carrying its own starting guess)."""

    name = "log_test"
    param_names = ("a0", "a1")

    def _f(self, x):
        return self.p[0] - self.p[1] * np.log(x)

    def _df(self, x):
        return -self.p[1] / x

    @classmethod
    def _guess(cls, x, c):
        cls.guessed = True
        return np.polyfit(-np.log(x), c, 1)[::-1]


def test_starting_guesses_are_carried_by_the_model_class():
    """``fit`` asks the model class for its starting coefficients (no table of names in fit.py):
    a plugin's own ``_guess`` is used, and a model without one starts from ones."""
    t = np.linspace(1e-5, 8e-5, 12)
    c = 10.0 - 2.0 * np.log(t / 1e-5)
    _LogCost.guessed = False
    np.testing.assert_allclose(cm.fit(_LogCost, t, c, scale=1e-5).model.p, [10.0, 2.0], rtol=1e-9)
    assert _LogCost.guessed
    np.testing.assert_allclose(_LogCost.initial_guess(t, c, scale=1e-5), [10.0, 2.0], rtol=1e-9)
    assert cm.CostModel.initial_guess(t, c).tolist() == []      # no coefficients, no guess
    np.testing.assert_array_equal(cm.ExponentialCost.initial_guess(t, 3 * np.exp(-0.4 * t / 1e-5), scale=1e-5),
                                  cm.ExponentialCost.initial_guess(t / 1e-5, 3 * np.exp(-0.4 * t / 1e-5)))


def test_entry_points_are_read_once_per_sys_path(tmp_path, monkeypatch):
    """The registries' entry points are kept per ``sys.path`` (evotol/_runtime/plugins.py): the same tuple on a
    second lookup, and a plugin in a folder put on ``sys.path`` afterwards is seen (its cost model usable by name)."""
    from evotol._runtime.plugins import group_entry_points
    from evotol.cost_models import registry
    before = group_entry_points("evotol.cost_models")
    assert group_entry_points("evotol.cost_models") is before and "toy_power" not in {ep.name for ep in before}
    (tmp_path / "toy_cost.py").write_text("from evotol.cost_models import PowerCost\n\n\nclass ToyPower(PowerCost):\n"
                                          "    name = 'toy_power'\n")
    info = tmp_path / "toy_cost-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: toy-cost\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[evotol.cost_models]\ntoy_power = toy_cost:ToyPower\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "toy_power" in {ep.name for ep in group_entry_points("evotol.cost_models")}
    model = registry.from_dict({"model": "toy_power", "a0": 1.0, "a1": 1.0})
    assert type(model).__name__ == "ToyPower" and float(model.cost(0.5)) == float(cm.PowerCost(1.0, 1.0).cost(0.5))

"""The one knee definition (evotol.core.pareto): closed-form fronts."""
import numpy as np
import pandas as pd
import pytest

from evotol.allocators import ParetoFront
from evotol.errors import ValidationError
from evotol.core.pareto import ideal_point_knee, knee_points, non_dominated


def test_ideal_point_knee_of_y_equals_one_over_x():
    """y = 1/x on [0.1, 10]: normalised, (x - 0.1)^2 + (1/x - 0.1)^2 is least at x = 1 (symmetric
    under x -> 1/x), in linear and in log-log axes alike."""
    x = np.geomspace(0.1, 10, 41)
    F = np.column_stack([x, 1 / x])
    assert ideal_point_knee(F) == 20
    assert ideal_point_knee(F, log=[True, True]) == 20
    assert 20 in knee_points(F, log=[True, True])


def test_pareto_front_knee_is_the_ideal_point_knee():
    """ParetoFront.knee() uses the same definition as the design-study knees: on cost = x,
    error = 1/x it is the x = 1 row, not an end of the front."""
    x = np.geomspace(0.1, 10, 41)
    front = ParetoFront(pd.DataFrame({"cost": x, "normalised_error": 1 / x}))
    assert front.knee() == 20


def test_knee_of_an_empty_front_is_named():
    with pytest.raises(ValidationError, match="Pareto front"):
        ideal_point_knee(np.zeros((0, 2)))


def test_non_dominated_rows():
    F = np.array([[1.0, 3.0], [2.0, 2.0], [2.5, 2.5], [3.0, 1.0]])
    assert sorted(non_dominated(F)) == [0, 1, 3]

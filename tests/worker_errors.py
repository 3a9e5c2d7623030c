"""A function that raises evotol's errors, for tests that send it to a spawned worker process
(tests/test_bad_inputs.py). It lives in a module of its own so that the worker imports
``evotol.errors`` alone, not the test module and the command line behind it (issue 43)."""
from __future__ import annotations


def raise_in_worker(kind):
    """Raise the :mod:`evotol.errors` error named by ``kind`` ("validation", "kinematics" or "infeasible")."""
    from evotol.errors import InfeasibleError, KinematicsError, ValidationError

    raise {"validation": ValidationError("grid", -1, "a positive integer"),
           "kinematics": KinematicsError("pose out of reach", poses=[[0.1, 0.2]]),
           "infeasible": InfeasibleError("position <= 1e-06 m", 2e-6, 3, "tight")}[kind]

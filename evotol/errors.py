"""The one small error hierarchy of evotol (see STYLE.md, "Errors"), and the two type tests its
callers share before raising :class:`ValidationError`."""
from __future__ import annotations

import sys


class EvotolError(Exception):
    """Base class of every error evotol raises on purpose.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import EvotolError, Tolerance
    >>> try:
    ...     Tolerance(PowerCost(1.0, 1.0), lower=2e-5, upper=1e-5).validate("x1")
    ... except EvotolError as err:                              # every evotol error is one
    ...     print(type(err).__name__)
    ValidationError
    """


class ValidationError(EvotolError, ValueError):
    """Bad input: names the field, the value, and what was expected.

    The message reads ``field = value!r: expected ...``. Also a ``ValueError``.

    Parameters
    ----------
    field : str
        The name of the offending input (a keyword, a study-file key such as ``"[cost] model"``).
        Kept as ``self.field``.
    value : object
        The value given; a 0-d numpy value is shown (and kept as ``self.value``) as its Python
        scalar.
    expected : str
        What was expected, in words. Kept as ``self.expected``.

    Examples
    --------
    >>> from evotol import ValidationError
    >>> raise ValidationError("tolerance.lower", -1e-6, "a positive length (m)")
    Traceback (most recent call last):
        ...
    evotol.errors.ValidationError: tolerance.lower = -1e-06: expected a positive length (m)
    """

    def __init__(self, field: str, value, expected: str):
        if hasattr(value, "item") and getattr(value, "ndim", 1) == 0:
            value = value.item()  # print 1.0, not np.float64(1.0)
        self.field, self.value, self.expected = field, value, expected
        super().__init__(f"{field} = {value!r}: expected {expected}")

    def __reduce__(self):
        # rebuilt from the constructor's arguments, so a worker process's error reaches the parent
        # as itself (the default pickles only the message, which this __init__ cannot take)
        return type(self), (self.field, self.value, self.expected)


class KinematicsError(EvotolError):
    """A pose is out of reach of the mechanism or at a singularity.

    ``poses`` holds the offending pose(s), in the units of the robot's workspace coordinates.

    Parameters
    ----------
    message : str
        The error message.
    poses : array_like, optional
        The offending pose(s), ``(d,)`` or ``(n, d)`` in the robot's workspace coordinates (m, rad);
        kept as ``self.poses`` (default None: not known).

    Examples
    --------
    >>> from evotol import KinematicsError
    >>> from evotol.robots.ucr3 import UCR3
    >>> try:
    ...     UCR3().sensitivity([[0.0, 0.0, 1.0]])              # Z_c = 1 m: outside the workspace
    ... except KinematicsError as err:
    ...     print(err)                                          # doctest: +ELLIPSIS
    3-UCR (verified): pose [0.0, 0.0, 1.0] (alpha, beta, Zc) is outside the workspace ...
    """

    def __init__(self, message: str, poses=None):
        self.poses = poses
        super().__init__(message)

    def __reduce__(self):
        # keeps the poses across a process boundary (the default would drop them)
        return type(self), (self.args[0], self.poses)


class ConvergenceError(EvotolError):
    """A numerical solver did not reach the requested tolerance.

    Examples
    --------
    >>> from evotol import ConvergenceError, EvotolError
    >>> issubclass(ConvergenceError, EvotolError)
    True
    """


class InfeasibleError(EvotolError):
    """No allowed design meets the requirement: names the requirement, the smallest achievable
    error (every tolerance at its lower bound) and the pose where it occurs.

    Parameters
    ----------
    requirement : str
        The requirement that cannot be met, in words (e.g. ``"worst_case position error <= 0.0001 m"``).
        Kept as ``self.requirement``.
    smallest_error : float
        The error with every free tolerance at its lower bound, in the requirement's units (m or
        rad, as the error component). Kept as ``self.smallest_error``.
    pose : array_like
        The pose where that error occurs, in workspace coordinates (m, rad). Kept as ``self.pose``.
    detail : str, optional
        Extra explanation appended to the message in parentheses (default: none).

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import InfeasibleError, LinearStack, Tolerance, assembly_problem, allocate_optimum
    >>> stack = LinearStack({"x1": 1.0, "x2": 1.0}, {"gap": 1e-5})
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-5, upper=1e-4)
    ...        for n in stack.source_names}                     # even the smallest: 2e-5 > 1e-5
    >>> try:
    ...     allocate_optimum(assembly_problem(stack, tol))
    ... except InfeasibleError as err:
    ...     print(err)                                          # doctest: +ELLIPSIS
    infeasible: ... with every free tolerance at its lower bound the error is 2 at pose [0.0] ...
    """

    def __init__(self, requirement: str, smallest_error: float, pose, detail: str = ""):
        self.requirement, self.smallest_error, self.pose, self.detail = requirement, smallest_error, pose, detail
        super().__init__(f"infeasible: {requirement} cannot be met; with every free tolerance at its lower bound the "
                         f"error is {smallest_error:.6g} at pose {pose}" + (f" ({detail})" if detail else ""))

    def __reduce__(self):
        # rebuilt from the constructor's arguments (see ValidationError.__reduce__)
        return type(self), (self.requirement, self.smallest_error, self.pose, self.detail)


class CheckFailed(EvotolError, AssertionError):
    """A conformance check failed (a robot, cost model or measure breaks its contract): names the
    plugin, the check and what was measured. Raised, not asserted, so it holds under ``python -O``;
    an ``AssertionError`` too, so pytest reports it as a failed assertion."""


def _numpy(kind: str) -> tuple:
    """NumPy's abstract scalar type ``kind`` if NumPy is loaded, else none: a value cannot be a
    NumPy scalar before NumPy is imported, and importing it here would load it for
    ``evotol --help``, which stays light."""
    np = sys.modules.get("numpy")
    return (getattr(np, kind),) if np is not None else ()


def is_integer(value, minimum: int) -> bool:
    """Whether ``value`` is an integer (Python or NumPy, not a bool) of at least ``minimum``.

    Parameters
    ----------
    value : object
        The value to test (a float such as 3.0 or a string such as "3" is not an integer).
    minimum : int
        The smallest value allowed.

    Returns
    -------
    bool
        True for an integer ``>= minimum``.
    """
    return not isinstance(value, bool) and isinstance(value, (int, *_numpy("integer"))) and value >= minimum


def is_real(value) -> bool:
    """Whether ``value`` is a real number: a Python int or float or a NumPy float, not a bool
    (text such as "0.9" is not; range and finiteness are the caller's test).

    Parameters
    ----------
    value : object
        The value to test.

    Returns
    -------
    bool
        True for an int, float or NumPy floating value that is not a bool.
    """
    return not isinstance(value, bool) and isinstance(value, (int, float, *_numpy("floating")))


class WriteFailed(EvotolError):
    """The system refused to write an output (disk full, read-only folder, quota): the file named
    keeps its earlier content, and no temporary file is left (``docs/reliability.md``).

    Parameters
    ----------
    path : str
        The file that could not be written.
    reason : str
        Why, in words (the system's message and what to do).

    Examples
    --------
    >>> from evotol.errors import WriteFailed
    >>> print(WriteFailed("reports/a.json", "disk full ([Errno 28] No space left on device)"))
    cannot write reports/a.json: disk full ([Errno 28] No space left on device)
    """

    def __init__(self, path: str, reason: str):
        self.path, self.reason = path, reason
        super().__init__(f"cannot write {path}: {reason}")

    def __reduce__(self):
        return type(self), (self.path, self.reason)


class SchedulerLost(EvotolError):
    """The Dask scheduler of a run was lost (killed, or not answering at the start): the chunks
    finished before it are kept, and a rerun resumes them (``docs/reliability.md``).

    Parameters
    ----------
    address : str
        The scheduler's address (``tcp://host:port``).
    reason : str
        What was seen, in words (``"the connection closed after 3 of 16 chunks"``).
    resumable : int, optional
        The chunks written and verified in a chunk store, which a rerun resumes (default 0).
    store : str, optional
        That chunk store's folder (default None: the run stored no chunks).

    Examples
    --------
    >>> from evotol.errors import SchedulerLost
    >>> print(SchedulerLost("tcp://10.0.0.5:8786", "the connection closed", 3, "out/s_store"))
    the Dask scheduler at tcp://10.0.0.5:8786 was lost (the connection closed); the chunks finished before are in out/s_store: a rerun resumes 3 chunks
    """

    def __init__(self, address: str, reason: str, resumable: int = 0, store: str | None = None):
        self.address, self.reason, self.resumable, self.store = address, reason, int(resumable), store
        where = (f"the chunks finished before are in {store}" if store is not None
                 else "no chunk store was given, so nothing was kept")
        super().__init__(f"the Dask scheduler at {address} was lost ({reason}); {where}: "
                         f"a rerun resumes {self.resumable} chunks")

    def __reduce__(self):
        return type(self), (self.address, self.reason, self.resumable, self.store)

"""Assembly functions as error models: ordinary mechanical assemblies behind the robot protocol.

A tolerance engineer describes an assembly by its **assembly function** (Chase's "explicit
assembly function", Chase, *Dimensioning and Tolerancing Handbook* ch. 14): the responses
``y_k = f_k(x)`` (a gap, a contact angle...) as a Python function of the nominal dimensions ``x_j``.
For a linear stack the function is a vector of sensitivities: ``y = Σ_j a_j x_j``.

evotol turns that into a :class:`evotol.robots.base.RobotErrorModel`:

* **sources** are the dimensions (one ``dim = 1`` source each, error ``|δx_j| <= t_j``);
* **sensitivities** ``∂f_k/∂x_j`` at the nominal come from complex-step differentiation
  ``Im f(x + i h e_j) / h`` (exact to round-off, Squire & Trapp 1998), checked against central
  differences; a function that is not complex-safe (raises on complex input, drops the imaginary
  part or disagrees with central differences) falls back to central differences with a note in
  ``derivative_method`` and a ``RuntimeWarning``;
* **pose_error** re-evaluates ``f`` at ``x + δx``: the nonlinear model for Monte Carlo.

Convention for several responses (documented in ``docs/process_selection.md``): each response
``k`` is one "pose" of the workspace (coordinate ``response`` = 0, 1, ..., K−1) and its error is
**divided by its limit** ``L_k`` and put in row 2 of the error twist (position z, no other row is
used). The problem's requirement is then ``Requirement(position=1.0)``: *every response within its
limit*, under the worst-case (``Σ_j |∂f_k/∂x_j| t_j <= L_k``, arithmetic stack) or RSS
(``sqrt(Σ_j (∂f_k/∂x_j t_j)²) <= L_k``, statistical stack) measure. :func:`evotol.allocators.process.assembly_problem`
builds that problem. Limits are symmetric (``y_k`` within ``nominal ± L_k``), in the response's own
unit (m, rad, or anything else: only the ratio matters).

All dimensions and tolerances are SI (m) unless a source declares ``unit="rad"``.
"""
from __future__ import annotations

import warnings
from typing import Callable, Mapping

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.base import RobotErrorModel, SourceSpec, Workspace

ROW = 2  # error-twist row that carries the normalised response errors (position z)


class AssemblyFunction(RobotErrorModel):
    """Error model of an assembly given as a function of its dimensions.

    Parameters
    ----------
    function : callable
        ``f(**dims) -> y`` called with one numpy array per dimension name (same shapes, possibly
        complex), returning one array (one response) or a tuple/list of arrays (several
        responses), each of the shape of the inputs. Write it with numpy ufuncs so it is
        vectorised (and complex-safe: ``np.arccos``, ``np.sqrt``... are; ``abs`` and ``np.real``
        are not).
    nominal : Mapping[str, float]
        Dimension name -> nominal value (SI: m or rad).
    limits : Mapping[str, float]
        Response name -> allowed deviation ``L_k`` from the nominal response (the response's
        unit), in the order the function returns the responses.
    name : str
        Name of the assembly (reports, messages).
    units : Mapping[str, str] or None
        Dimension name -> ``"m"`` or ``"rad"`` (default ``"m"``).
    groups : Mapping[str, str] or None
        Dimension name -> group (part name, for reports).
    step : float
        Complex step ``h`` relative to ``max(|x_j|, 1e-3)`` (1, dimensionless).
    fd_rtol : float
        Largest relative difference between the complex-step and the central-difference
        gradients at the nominal for the complex step to be used (1, dimensionless).

    Raises
    ------
    evotol.errors.ValidationError
        A function that is not callable, an empty or non-finite ``nominal``, an empty or
        non-positive ``limits``, a ``units``/``groups`` key that is not a dimension, or
        derivatives at the nominal that are not finite.

    Warns
    -----
    RuntimeWarning
        When the function is not complex-safe and central differences are used.

    Examples
    --------
    >>> import numpy as np
    >>> from evotol import AssemblyFunction
    >>> def gap(a, b):                                          # housing a, shaft b (m)
    ...     return a - b
    >>> asm = AssemblyFunction(gap, {"a": 0.030, "b": 0.029}, {"gap": 2e-4})
    >>> asm.source_names
    ('a', 'b')
    >>> np.round(asm.sensitivity([[0]])[0, 2] * 2e-4, 9)       # d gap / d (a, b)
    array([ 1., -1.])
    """

    #: False when the nominal was not given (a linear stack of sensitivities only): reports leave it blank
    nominal_given = True

    def __init__(self, function: Callable, nominal: Mapping[str, float], limits: Mapping[str, float], *,
                 name: str = "assembly", units: Mapping[str, str] | None = None,
                 groups: Mapping[str, str] | None = None, step: float = 1e-20, fd_rtol: float = 1e-5):
        if not callable(function):
            raise ValidationError("assembly function", function, "a callable f(**dimensions) -> response(s)")
        if not isinstance(nominal, Mapping) or not nominal:
            raise ValidationError("assembly nominal", nominal, "a non-empty mapping dimension name -> nominal value (SI)")
        if not isinstance(limits, Mapping) or not limits:
            raise ValidationError("assembly limits", limits, "a non-empty mapping response name -> allowed deviation")
        self.function, self.name = function, str(name)
        self.dimension_names = tuple(str(n) for n in nominal)
        x0 = []
        for n in self.dimension_names:
            v = nominal[n]
            if not isinstance(v, (int, float, np.floating, np.integer)) or not np.isfinite(v):
                raise ValidationError(f"assembly nominal[{n!r}]", v, "a finite number (SI)")
            x0.append(float(v))
        self.x0 = np.array(x0)
        self.response_names = tuple(str(n) for n in limits)
        lim = []
        for n in self.response_names:
            v = limits[n]
            if not isinstance(v, (int, float, np.floating, np.integer)) or not (np.isfinite(v) and v > 0):
                raise ValidationError(f"assembly limits[{n!r}]", v, "a positive allowed deviation of the response")
            lim.append(float(v))
        self.limits = np.array(lim)
        units, groups = dict(units or {}), dict(groups or {})
        for d in (units, groups):
            extra = [k for k in d if k not in self.dimension_names]
            if extra:
                raise ValidationError("assembly units/groups key", extra[0], f"one of the dimensions {list(self.dimension_names)}")
        self.sources = tuple(SourceSpec(n, 1, units.get(n, "m"), groups.get(n, "dimension"), f"dimension {n}")
                             for n in self.dimension_names)
        k = len(self.response_names)
        self.workspace = Workspace(("response",), (0.0,), (float(k - 1),), ("1",))
        self.y0 = self._nominal_response()
        self.step = float(step)
        self.fd_rtol = float(fd_rtol)
        self.gradient, self.derivative_method = self._derive(self.x0[None])
        self.gradient = self.gradient[0]                        # (n_responses, n_dims)

    # --- evaluation -------------------------------------------------------------------------------
    def evaluate(self, X) -> np.ndarray:
        """Responses at dimensions X (..., n_dims) -> (..., n_responses). Real or complex.

        Parameters
        ----------
        X : (..., n_dims) array_like
            Dimension values (SI: m or rad), last axis in the order of ``dimension_names``; may
            be complex (complex-step differentiation).

        Returns
        -------
        (..., n_responses) ndarray
            The function's responses, last axis in the order of ``response_names`` (each in the
            response's own unit); complex when the input is and the function is complex-safe.

        Raises
        ------
        evotol.errors.ValidationError
            ``X`` whose last axis is not ``n_dims`` long, or a function result that is not one
            value per response and point.
        """
        X = np.asarray(X)
        if X.shape[-1] != len(self.dimension_names):
            raise ValidationError("assembly dimensions shape", X.shape, f"(..., {len(self.dimension_names)})")
        cols = np.moveaxis(X, -1, 0).copy()          # one contiguous array per dimension
        out = self.function(**{n: cols[j] for j, n in enumerate(self.dimension_names)})
        if isinstance(out, Mapping):
            out = [out[n] for n in self.response_names]
        if isinstance(out, (tuple, list)):
            out = np.stack([np.broadcast_to(np.asarray(o), X.shape[:-1]) for o in out], axis=-1)
        else:
            out = np.asarray(out)
            out = np.broadcast_to(out, X.shape[:-1])[..., None] if len(self.response_names) == 1 and out.shape != X.shape[:-1] + (1,) else out
        if out.shape != X.shape[:-1] + (len(self.response_names),):
            raise ValidationError(f"{self.name} response shape", out.shape,
                                  f"{X.shape[:-1] + (len(self.response_names),)}: one value per response {list(self.response_names)}")
        return out

    def _nominal_response(self) -> np.ndarray:
        try:
            with np.errstate(all="ignore"):
                y = np.asarray(self.evaluate(self.x0[None])[0], dtype=float)
        except ValidationError:
            raise
        except Exception as exc:  # the user's function failed: say where
            raise ValidationError(f"{self.name} function at the nominal {dict(zip(self.dimension_names, self.x0.tolist()))}",
                                  f"{type(exc).__name__}: {exc}", "a finite response for every limit") from exc
        bad = ~np.isfinite(y)
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise ValidationError(f"{self.name} response {self.response_names[k]!r} at the nominal "
                                  f"{dict(zip(self.dimension_names, self.x0.tolist()))}", float(y[k]), "a finite number")
        return y

    def _steps(self) -> np.ndarray:
        return np.maximum(np.abs(self.x0), 1e-3)

    def central_differences(self, points, rel_step: float = 1e-6) -> np.ndarray:
        """∂f_k/∂x_j at points (n, n_dims) by central differences -> (n, n_responses, n_dims).

        Parameters
        ----------
        points : (n, n_dims) or (n_dims,) array_like
            Dimension values (SI: m or rad).
        rel_step : float, optional
            Step relative to ``max(|x0_j|, 1e-3)`` of each dimension's nominal ``x0_j``
            (dimensionless; the step itself is in the dimension's unit).

        Returns
        -------
        (n, n_responses, n_dims) ndarray
            Derivatives (response unit per dimension unit); NaN or inf where the function is not
            finite (floating-point warnings are silenced).
        """
        P = np.atleast_2d(np.asarray(points, dtype=float))
        n, d = P.shape
        h = rel_step * self._steps()
        E = np.eye(d) * h
        out = np.empty((n, len(self.response_names), d))
        for sl in self._chunks(n, 2 * d * d):
            Xp = P[sl, None, :] + E[None]
            Xm = P[sl, None, :] - E[None]
            with np.errstate(all="ignore"):
                Y = self.evaluate(np.concatenate([Xp, Xm], axis=1))      # (m, 2d, K)
            out[sl] = ((Y[:, :d] - Y[:, d:]) / (2 * h)[None, :, None]).transpose(0, 2, 1)
        return out

    @staticmethod
    def _chunks(n: int, per_point: int, budget: int = 1 << 16):
        """Slices of at most ``budget / per_point`` points: keeps the temporaries in cache
        (measured 5-8x faster than one pass at 10^4 points x 20 dimensions)."""
        m = max(1, budget // max(per_point, 1))
        return [slice(i, min(i + m, n)) for i in range(0, n, m)]

    def complex_step(self, points) -> np.ndarray:
        """∂f_k/∂x_j at points (n, n_dims) by complex step -> (n, n_responses, n_dims).

        The step is ``step * max(|x0_j|, 1e-3)`` along the imaginary axis (``step`` of the
        constructor); the derivative is ``Im f(x + i h e_j) / h`` (Squire & Trapp 1998).

        Parameters
        ----------
        points : (n, n_dims) or (n_dims,) array_like
            Dimension values (SI: m or rad), real.

        Returns
        -------
        (n, n_responses, n_dims) ndarray
            Derivatives (response unit per dimension unit).

        Raises
        ------
        TypeError
            The function returned a real array for complex input (it is not complex-safe).
        """
        P = np.atleast_2d(np.asarray(points, dtype=float))
        n, d = P.shape
        h = self.step * self._steps()
        E = 1j * (np.eye(d) * h)[None]
        out = np.empty((n, len(self.response_names), d))
        for sl in self._chunks(n, d * d):
            with np.errstate(all="ignore"):
                Y = self.evaluate(P[sl, None, :] + E)                  # (m, d, K)
            if not np.iscomplexobj(Y):
                raise TypeError("the function returned a real array for complex input")
            out[sl] = (Y.imag / h[None, :, None]).transpose(0, 2, 1)
        return out

    def jacobian(self, points) -> np.ndarray:
        """∂f_k/∂x_j at points (n, n_dims), with the method chosen at construction.

        Complex step when ``derivative_method == "complex step"``, else central differences
        (default relative step).

        Parameters
        ----------
        points : (n, n_dims) or (n_dims,) array_like
            Dimension values (SI: m or rad).

        Returns
        -------
        (n, n_responses, n_dims) ndarray
            Derivatives (response unit per dimension unit).

        Raises
        ------
        evotol.errors.ValidationError
            A point where some response is not finite (outside the function's domain); names
            the first one.
        """
        P = np.atleast_2d(np.asarray(points, dtype=float))
        with np.errstate(all="ignore"):
            y = np.asarray(self.evaluate(P), dtype=float)
        bad = ~np.all(np.isfinite(y), axis=-1)
        if bad.any():  # outside the function's domain: complex step would return a finite but meaningless number
            raise ValidationError(f"{self.name} dimensions", dict(zip(self.dimension_names, P[bad][0].tolist())),
                                  "a point where every response is finite")
        if self.derivative_method == "complex step":
            return self.complex_step(P)
        return self.central_differences(P)

    def _derive(self, P):
        fd = self.central_differences(P)
        try:
            cs = self.complex_step(P)
        except Exception as exc:  # noqa: BLE001 -- any failure on complex input means "not complex-safe"
            note = f"central differences (complex step failed: {type(exc).__name__}: {exc})"
        else:
            scale = max(float(np.max(np.abs(fd))), 1e-300)
            err = float(np.max(np.abs(cs - fd))) / scale if np.all(np.isfinite(cs)) else np.inf
            if err <= max(self.fd_rtol, 1e-5):
                self.complex_step_check = err
                return cs, "complex step"
            note = f"central differences (complex step differs from central differences by {err:.3g} relative)"
        warnings.warn(f"{self.name}: {note}", RuntimeWarning, stacklevel=3)
        if not np.all(np.isfinite(fd)):
            raise ValidationError(f"{self.name} derivatives at the nominal", fd.tolist(), "finite central differences")
        self.complex_step_check = None
        return fd, note

    # --- robot protocol ------------------------------------------------------------------------
    @property
    def response_poses(self) -> np.ndarray:
        """The workspace poses, one per response: (K, 1)."""
        return np.arange(len(self.response_names), dtype=float)[:, None]

    def _response_index(self, poses) -> np.ndarray:
        P = self.check_poses(poses)
        k = np.rint(P[:, 0]).astype(int)
        if np.any(np.abs(P[:, 0] - k) > 1e-9):
            raise ValidationError(f"{self.name} pose", P[:, 0].tolist(), f"response indices 0..{len(self.response_names) - 1}")
        return k

    def sensitivity(self, poses) -> np.ndarray:
        """Normalised response gradients at the nominal: row 2 (position z) holds ``∂f_k/∂x_j / L_k``
        (1 per dimension unit, m or rad), the other rows zero; a pose is a response index ``k``
        (0 .. K-1), shape (n, 1).

        Raises
        ------
        evotol.errors.ValidationError
            A pose that is not an integer response index, or of the wrong shape.
        evotol.errors.KinematicsError
            An index outside 0 .. K-1.
        """
        k = self._response_index(poses)
        J = np.zeros((len(k), 6, len(self.dimension_names)))
        J[:, ROW, :] = self.gradient[k] / self.limits[k, None]
        return J

    def pose_error(self, poses, errors) -> np.ndarray:
        """Nonlinear response errors: ``(f_k(x0 + δx) - f_k(x0)) / L_k`` in row 2 (dimensionless; within
        ``[-1, 1]`` means within the limit), the other rows zero, NaN where the function is not
        finite. A pose is a response index ``k``; ``errors`` are the dimension errors ``δx`` (SI).

        Raises
        ------
        evotol.errors.ValidationError
            A pose that is not an integer response index, or errors whose last axis is not
            ``n_dims`` long.
        evotol.errors.KinematicsError
            An index outside 0 .. K-1.
        """
        k = self._response_index(poses)
        E = np.asarray(errors, dtype=float)
        with np.errstate(all="ignore"):
            Y = self.evaluate(self.x0 + E)                              # (n_poses, n_samples, K)
        dy = np.take_along_axis(Y, k[:, None, None], axis=2)[..., 0] - self.y0[k][:, None]
        out = np.zeros(E.shape[:2] + (6,))
        out[..., ROW] = dy / self.limits[k][:, None]
        return out

"""Interval arithmetic with outward rounding, and interval forward-mode derivatives, for numpy code.

An :class:`Interval` holds arrays ``lo <= hi`` (any broadcastable shape). Arithmetic operators and
the numpy ufuncs an assembly function is usually written with (``+ − × /``, ``negative``,
``square``, ``sqrt``, ``exp``, ``log``, ``arccos``, ``arcsin``, ``arctan``, ``sin``, ``cos``,
``absolute``, ``power`` with a constant exponent) return an enclosure of the function's range over the box: the
*natural interval extension* (Moore 1966). Every result bound is moved outwards by one ulp
(``np.nextafter``), which covers the round-off of numpy's correctly-rounded-or-better elementary
operations and functions (the libm functions used are accurate to < 1 ulp). A function outside
its domain anywhere on the box (``arccos`` of an interval leaving [−1, 1], ``sqrt`` or ``log`` of
a negative, division by an interval holding 0) gives the whole real line, which the callers treat
as "no bound on this box".

:class:`Dual` carries a value interval and the interval enclosure of its gradient with respect to
the box's variables (forward mode, the same rules): ``f(Dual.variables(lo, hi)).grad`` encloses
∂f/∂x_j over the whole box, which proves monotonicity when it excludes 0.
"""
from __future__ import annotations

import numpy as np

_INF = np.inf


def _down(x):
    return np.nextafter(x, -_INF)


def _up(x):
    return np.nextafter(x, _INF)


def _exponent(k, who: str) -> float:
    """The constant exponent of ``who ** k`` as a float; a TypeError naming it otherwise."""
    try:
        return float(k)
    except (TypeError, ValueError):
        raise TypeError(f"{who} ** k needs a real constant k, got {k!r}") from None


class Interval:
    """Arrays ``lo <= hi``; see the module docstring.

    Parameters
    ----------
    lo : array_like
        Lower ends (units of the quantity enclosed, e.g. m or rad).
    hi : array_like, optional
        Upper ends, broadcastable with ``lo``; None: the degenerate interval ``[lo, lo]``.
    """

    __array_priority__ = 1000

    def __init__(self, lo, hi=None):
        self.lo = np.asarray(lo, dtype=float)
        self.hi = np.asarray(lo if hi is None else hi, dtype=float)

    @staticmethod
    def of(x) -> "Interval":
        """``x`` as an interval: itself if it is one, else the degenerate ``[x, x]``.

        Parameters
        ----------
        x : Interval or array_like
            An interval or plain numbers.

        Returns
        -------
        Interval
            ``x`` unchanged, or ``Interval(x, x)``.
        """
        return x if isinstance(x, Interval) else Interval(x, x)

    @property
    def shape(self):
        """Broadcast shape of ``lo`` and ``hi`` (tuple of int)."""
        return np.broadcast_shapes(self.lo.shape, self.hi.shape)

    def _out(lo, hi) -> "Interval":
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        bad = np.isnan(lo) | np.isnan(hi)
        return Interval(np.where(bad, -_INF, _down(lo)), np.where(bad, _INF, _up(hi)))

    # arithmetic --------------------------------------------------------------------------------
    def __add__(self, o):
        o = Interval.of(o)
        return Interval._out(self.lo + o.lo, self.hi + o.hi)

    __radd__ = __add__

    def __neg__(self):
        return Interval(-self.hi, -self.lo)

    def __sub__(self, o):
        return self + (-Interval.of(o))

    def __rsub__(self, o):
        return Interval.of(o) + (-self)

    def __mul__(self, o):
        o = Interval.of(o)
        with np.errstate(invalid="ignore"):
            p = np.stack(np.broadcast_arrays(self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi))
        p = np.where(np.isnan(p), 0.0, p)           # 0 · inf inside a product: 0
        return Interval._out(p.min(0), p.max(0))

    __rmul__ = __mul__

    def reciprocal(self):
        """Enclosure of 1/x, rounded outwards.

        Returns
        -------
        Interval
            ``[1/hi, 1/lo]``; the whole real line where the interval holds 0.
        """
        zero = (self.lo <= 0) & (self.hi >= 0)
        with np.errstate(divide="ignore"):
            lo, hi = 1.0 / self.hi, 1.0 / self.lo
        return Interval._out(np.where(zero, -_INF, lo), np.where(zero, _INF, hi))

    def __truediv__(self, o):
        return self * Interval.of(o).reciprocal()

    def __rtruediv__(self, o):
        return Interval.of(o) * self.reciprocal()

    def square(self):
        """Enclosure of x², rounded outwards (tighter than ``x * x``: it is never negative).

        Returns
        -------
        Interval
            ``[0, max(lo², hi²)]`` where the interval holds 0, else ``[min(lo², hi²), max(lo², hi²)]``.
        """
        a, b = np.abs(self.lo), np.abs(self.hi)
        zero = (self.lo <= 0) & (self.hi >= 0)
        return Interval._out(np.where(zero, 0.0, np.minimum(a, b) ** 2), np.maximum(a, b) ** 2)

    def __pow__(self, k):
        """Enclosure of ``x ** k`` for a real constant ``k``, rounded outwards.

        An integer ``k`` is defined for every x (a negative one through :meth:`reciprocal`); a
        fractional ``k`` only for x >= 0 (``x ** 0.5`` is ``sqrt``), so an interval reaching below
        0 gives the whole real line, as ``sqrt`` of a negative does.

        Parameters
        ----------
        k : float
            The exponent, a real constant (dimensionless).

        Returns
        -------
        Interval
            The enclosure of ``x ** k`` over the interval.

        Raises
        ------
        TypeError
            ``k`` is not a real scalar (an interval exponent is not supported).
        """
        k = _exponent(k, "Interval")
        if k.is_integer():
            n = int(k)
            if n == 0:
                return Interval(np.ones(self.shape))
            if n < 0:
                return self.reciprocal() ** (-n)
            if n % 2 == 0:
                return Interval._out(self.square().lo ** (n // 2), self.square().hi ** (n // 2))
            return Interval._out(self.lo ** n, self.hi ** n)
        # a fractional power: monotone on x >= 0 (x ** k at 0 is 0 for k > 0 and +inf for k < 0)
        if k > 0:
            return self._increasing(lambda a: a ** k, 0.0)
        return self._decreasing(lambda a: a ** k, 0.0)

    # monotone functions ------------------------------------------------------------------------
    def _increasing(self, f, dom_lo=-_INF, dom_hi=_INF):
        bad = (self.lo < dom_lo) | (self.hi > dom_hi)
        with np.errstate(invalid="ignore", divide="ignore"):
            lo, hi = f(np.clip(self.lo, dom_lo, dom_hi)), f(np.clip(self.hi, dom_lo, dom_hi))
        return Interval._out(np.where(bad, -_INF, lo), np.where(bad, _INF, hi))

    def _decreasing(self, f, dom_lo=-_INF, dom_hi=_INF):
        bad = (self.lo < dom_lo) | (self.hi > dom_hi)
        with np.errstate(invalid="ignore", divide="ignore"):
            lo, hi = f(np.clip(self.hi, dom_lo, dom_hi)), f(np.clip(self.lo, dom_lo, dom_hi))
        return Interval._out(np.where(bad, -_INF, lo), np.where(bad, _INF, hi))

    def _trig(self, f, peak):
        """sin/cos: endpoints, and ±1 where the box holds a peak (peak + 2kπ for +1, + π for −1)."""
        with np.errstate(invalid="ignore"):
            a, b = f(self.lo), f(self.hi)
            lo, hi = np.minimum(a, b), np.maximum(a, b)
            kmax = np.ceil((self.lo - peak) / (2 * np.pi))
            has_max = peak + 2 * np.pi * kmax <= self.hi
            kmin = np.ceil((self.lo - peak - np.pi) / (2 * np.pi))
            has_min = peak + np.pi + 2 * np.pi * kmin <= self.hi
        return Interval._out(np.where(has_min, -1.0, lo), np.where(has_max, 1.0, hi))

    def __array_ufunc__(self, ufunc, method, *inputs, **kw):
        if method != "__call__" or kw:
            return NotImplemented
        x = [Interval.of(i) for i in inputs]
        one = {np.negative: lambda a: -a, np.square: Interval.square, np.reciprocal: Interval.reciprocal,
               np.sqrt: lambda a: a._increasing(np.sqrt, 0.0), np.exp: lambda a: a._increasing(np.exp),
               np.log: lambda a: a._increasing(np.log, 0.0), np.arcsin: lambda a: a._increasing(np.arcsin, -1.0, 1.0),
               np.arctan: lambda a: a._increasing(np.arctan), np.arccos: lambda a: a._decreasing(np.arccos, -1.0, 1.0),
               np.sin: lambda a: a._trig(np.sin, np.pi / 2), np.cos: lambda a: a._trig(np.cos, 0.0),
               np.absolute: lambda a: Interval._out(np.where((a.lo <= 0) & (a.hi >= 0), 0.0, np.minimum(abs(a.lo), abs(a.hi))),
                                                    np.maximum(abs(a.lo), abs(a.hi)))}
        two = {np.add: Interval.__add__, np.subtract: Interval.__sub__, np.multiply: Interval.__mul__,
               np.true_divide: Interval.__truediv__}
        if ufunc in one and len(x) == 1:
            return one[ufunc](x[0])
        if ufunc in two and len(x) == 2:
            return two[ufunc](x[0], x[1])
        if ufunc is np.power and len(x) == 2 and np.all(x[1].lo == x[1].hi):
            return x[0] ** float(np.ravel(x[1].lo)[0])
        return NotImplemented

    def __repr__(self):
        return f"Interval({self.lo!r}, {self.hi!r})"


class Dual:
    """Value interval and gradient-enclosure interval (last axis: variables); forward mode.

    Parameters
    ----------
    val : Interval
        Enclosure of the value over the box, shape (...).
    grad : Interval
        Enclosure of the gradient with respect to the box's variables, shape (..., n).
    """

    __array_priority__ = 1001

    def __init__(self, val: Interval, grad: Interval):
        self.val, self.grad = val, grad

    @staticmethod
    def variables(lo, hi) -> list["Dual"]:
        """One Dual per variable j over boxes ``[lo, hi]`` (arrays (..., n)).

        Parameters
        ----------
        lo : array_like, shape (..., n)
            Lower corners of the boxes (units of each variable, e.g. m or rad).
        hi : array_like, shape (..., n)
            Upper corners.

        Returns
        -------
        list of Dual
            n Duals: variable j's value interval ``[lo[..., j], hi[..., j]]`` and the unit
            gradient e_j.
        """
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        n = lo.shape[-1]
        out = []
        for j in range(n):
            g = np.zeros(lo.shape)
            g[..., j] = 1.0
            out.append(Dual(Interval(lo[..., j], hi[..., j]), Interval(g)))
        return out

    @staticmethod
    def of(x, like: "Dual") -> "Dual":
        """``x`` as a Dual: itself if it is one, else a constant (zero gradient).

        Parameters
        ----------
        x : Dual, Interval or array_like
            The value.
        like : Dual
            A Dual whose gradient shape the constant takes.

        Returns
        -------
        Dual
            ``x`` unchanged, or ``Dual(Interval.of(x), 0)``.
        """
        if isinstance(x, Dual):
            return x
        return Dual(Interval.of(x), Interval(np.zeros(like.grad.shape)))

    def _g(self, d: Interval) -> Interval:        # chain rule: f'(val) · grad
        return Interval(d.lo[..., None], d.hi[..., None]) * self.grad

    def __add__(self, o):
        o = Dual.of(o, self)
        return Dual(self.val + o.val, self.grad + o.grad)

    __radd__ = __add__

    def __neg__(self):
        return Dual(-self.val, -self.grad)

    def __sub__(self, o):
        return self + (-Dual.of(o, self))

    def __rsub__(self, o):
        return Dual.of(o, self) + (-self)

    def __mul__(self, o):
        o = Dual.of(o, self)
        return Dual(self.val * o.val, o._g(self.val) + self._g(o.val))

    __rmul__ = __mul__

    def __truediv__(self, o):
        o = Dual.of(o, self)
        r = o.val.reciprocal()
        return Dual(self.val * r, self._g(r) - o._g(self.val * r * r))

    def __rtruediv__(self, o):
        return Dual.of(o, self) / self

    def __pow__(self, k):
        """``x ** k`` for a real constant ``k``: value ``x ** k``, gradient ``k x ** (k - 1) ∇x``.

        A fractional ``k`` is kept as it is (``x ** 0.5`` is ``sqrt``); the value and gradient
        enclosures are those of :meth:`Interval.__pow__`.

        Parameters
        ----------
        k : float
            The exponent, a real constant (dimensionless).

        Returns
        -------
        Dual
            Value and gradient enclosures of ``x ** k``.

        Raises
        ------
        TypeError
            ``k`` is not a real scalar (a variable exponent is not supported).
        """
        k = _exponent(k, "Dual")
        return Dual(self.val ** k, self._g(k * self.val ** (k - 1))) if k else Dual.of(1.0, self)

    def __array_ufunc__(self, ufunc, method, *inputs, **kw):
        if method != "__call__" or kw:
            return NotImplemented
        if len(inputs) == 2:
            a, b = inputs
            ops = {np.add: lambda: a + b if isinstance(a, Dual) else b + a,
                   np.subtract: lambda: a - b if isinstance(a, Dual) else b.__rsub__(a),
                   np.multiply: lambda: a * b if isinstance(a, Dual) else b * a,
                   np.true_divide: lambda: a / b if isinstance(a, Dual) else b.__rtruediv__(a)}
            if ufunc in ops:
                return ops[ufunc]()
            if ufunc is np.power and not isinstance(b, Dual):
                return a ** b
            return NotImplemented
        u = inputs[0]
        v = u.val
        one = 1.0
        rules = {np.negative: (lambda: -v, lambda: Interval.of(-one)),
                 np.square: (lambda: v.square(), lambda: 2.0 * v),
                 np.sqrt: (lambda: np.sqrt(v), lambda: 0.5 / np.sqrt(v)),
                 np.exp: (lambda: np.exp(v), lambda: np.exp(v)),
                 np.log: (lambda: np.log(v), lambda: v.reciprocal()),
                 np.arccos: (lambda: np.arccos(v), lambda: -(1.0 / np.sqrt(1.0 - v.square()))),
                 np.arcsin: (lambda: np.arcsin(v), lambda: 1.0 / np.sqrt(1.0 - v.square())),
                 np.arctan: (lambda: np.arctan(v), lambda: 1.0 / (1.0 + v.square())),
                 np.sin: (lambda: np.sin(v), lambda: np.cos(v)),
                 np.cos: (lambda: np.cos(v), lambda: -np.sin(v)),
                 np.reciprocal: (lambda: v.reciprocal(), lambda: -(v.reciprocal().square()))}
        if ufunc not in rules:
            return NotImplemented
        f, d = rules[ufunc]
        return Dual(f(), u._g(d()))

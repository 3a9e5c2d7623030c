"""Safe arithmetic expressions for the entries of a mechanism description (DH parameters, pose targets).

An entry of a modified-DH table may be a number or a string such as ``"-L0/2"``, ``"q1 - pi"``,
``"a1*sin(beta)/tan(alpha_d)"``. The string is parsed with :mod:`ast` and only numbers, names,
``+ - * / **``, unary minus and the functions ``sin cos tan asin acos atan sqrt exp log`` are
allowed (no attribute access, no calls of anything else), so a description file cannot run code.

Constants available in every expression: ``pi`` and the units of the one unit table
(:data:`evotol.units.quantity.UNITS`: ``deg`` = pi/180 so ``"30*deg"``, ``mm`` = 1e-3 so ``"100*mm"``,
``um``, ``mrad``, ``arcsec``...; ``docs/units.md``); a value with its unit alone (``"20 um"``) is read
by the same grammar. Everything else is a name of the description: a design parameter
(``[lengths]``/``[angles]``), a joint variable or a pose coordinate.

Derivatives are taken by the complex step (Squire & Trapp 1998): ``df/dx = Im f(x + i h) / h``
with ``h = 1e-30`` -- exact to machine precision for these analytic functions, no subtraction.
"""
from __future__ import annotations

import ast
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from evotol.errors import ValidationError
from evotol.units.quantity import UNITS, is_quantity_text, parse_quantity

FUNCTIONS = {"sin": np.sin, "cos": np.cos, "tan": np.tan, "asin": np.arcsin, "acos": np.arccos,
             "atan": np.arctan, "sqrt": np.sqrt, "exp": np.exp, "log": np.log}
#: ``pi`` and the units of :data:`evotol.units.quantity.UNITS` that are names (not ``m``, ``rad``: too
#: likely a description's own names; ``in`` is a Python keyword): ``"20*um"``, ``"0.1*mrad"``
CONSTANTS = {"pi": np.pi, **{u: f for u, (_, f) in UNITS.items() if u.isidentifier() and u not in ("m", "rad", "in")}}
CONSTANTS["μm"], CONSTANTS["μrad"] = CONSTANTS["um"], CONSTANTS["urad"]   # the parser reads µ (micro sign) as μ
_ALLOWED = (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Constant, ast.Name, ast.Load, ast.Call,
            ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub, ast.UAdd)
STEP = 1e-30


@dataclass(frozen=True)
class Expression:
    """A parsed entry: ``text`` (as written), ``names`` (the names it uses, constants excluded).

    Build one with :meth:`parse` (which checks the text); calling it, ``expr(env)``, evaluates it
    with ``env`` (name -> value) plus the functions and constants. It pickles as its text.

    Parameters
    ----------
    text : str
        The expression as written (a number is kept as its ``repr``).
    names : frozenset of str
        The names it uses: design parameters, joint variables, pose coordinates (functions and
        the constants ``pi``, ``deg``, ``mm`` excluded).
    code : code object
        The compiled, ast-checked expression.
    """

    text: str
    names: frozenset
    code: object

    @classmethod
    def parse(cls, text, field: str) -> "Expression":
        """Parse and check an entry: a number or an expression string (see the module docstring).

        Parameters
        ----------
        text : str or int or float
            The entry as written, e.g. ``"-L0/2"``, ``"30*deg"`` or ``0.1`` (values in SI: m, rad).
        field : str
            Where the entry is (e.g. ``"frame.A.d"``), for the error message.

        Returns
        -------
        Expression
            The parsed entry.

        Raises
        ------
        evotol.errors.ValidationError
            Not a number or string (a bool included), a non-finite number, a syntax error, or a
            construct other than numbers, names, ``+ - * / **``, unary signs and one-argument
            calls of the allowed functions (strings, attributes, other calls...).
        """
        if isinstance(text, bool) or not isinstance(text, (str, int, float)):
            raise ValidationError(field, text, "a number or an expression string such as '-L0/2' or 'q1 - pi'")
        if isinstance(text, str) and is_quantity_text(text):      # "20 um", "0.5 mm": the one unit grammar
            text = repr(parse_quantity(text, field))
        if not isinstance(text, str):
            if not np.isfinite(text):
                raise ValidationError(field, text, "a finite number")
            text = repr(float(text))
        try:
            tree = ast.parse(text.strip(), mode="eval")
        except SyntaxError:
            raise ValidationError(field, text, "an arithmetic expression (numbers, names, + - * / **, sin cos ...)") from None
        names = set()
        for node in ast.walk(tree):
            if not isinstance(node, _ALLOWED):
                raise ValidationError(field, text, f"only numbers, names, + - * / ** and {sorted(FUNCTIONS)} "
                                                   f"(found {type(node).__name__})")
            if isinstance(node, ast.Call):
                if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS or node.keywords or len(node.args) != 1:
                    raise ValidationError(field, text, f"calls of one argument to one of {sorted(FUNCTIONS)}")
            elif isinstance(node, ast.Name) and node.id not in FUNCTIONS and node.id not in CONSTANTS:
                names.add(node.id)
            elif isinstance(node, ast.Constant) and not isinstance(node.value, (int, float)):
                raise ValidationError(field, text, "numbers, not strings")
        return cls(text, frozenset(names), compile(tree, f"<{field}>", "eval"))

    def __reduce__(self):
        # compiled code does not pickle; robots travel to worker processes and Dask, so an
        # expression is sent as its text and parsed again (evotol.robots.checks.check_pickle_round_trip)
        return (Expression.parse, (self.text, "expression"))

    @property
    def is_constant(self) -> bool:
        """True when the expression uses no name (its value is fixed)."""
        return not self.names

    def __call__(self, env: Mapping[str, object]):
        return eval(self.code, {"__builtins__": {}}, {**FUNCTIONS, **CONSTANTS, **env})  # noqa: S307 (ast-checked)

    def value_and_gradient(self, env: Mapping[str, np.ndarray], wrt) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Value and the derivatives with respect to the names in ``wrt`` that the expression uses
        (complex step, exact to rounding). Arrays broadcast over poses.

        Parameters
        ----------
        env : mapping of str to float or (n,) ndarray
            Every name the expression uses -> its value (SI: m, rad).
        wrt : iterable of str
            Names to differentiate with respect to; those the expression does not use are
            skipped.

        Returns
        -------
        value : ndarray or float
            The expression's (real) value, broadcast over ``env``'s arrays.
        gradient : dict of str to ndarray
            Name in ``wrt`` and used -> derivative of the value with respect to it (value's unit
            per the name's unit), step ``1e-30``.
        """
        val = np.real(self(env))
        grad = {}
        for name in self.names & set(wrt):
            e = dict(env)
            e[name] = np.asarray(env[name]) + 1j * STEP
            grad[name] = np.imag(self(e)) / STEP
        return val, grad

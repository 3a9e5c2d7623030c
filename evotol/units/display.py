"""Display units: tolerances and errors as a drawing states them (µm, mm or inch, arcsec, mrad or deg).

SI inside (m, rad), display units at the edges (STYLE.md): every HTML table, terminal table and
``summary()`` converts with one :class:`DisplayUnits` value; JSON files and Python values stay SI.

A study chooses its units with ``[report] units = ...`` (:func:`parse_units`): one unit
(``"mm"``), a pair (``"um, arcsec"`` or ``["mm", "deg"]``) or a table
(``{length = "mm", angle = "mrad"}``). What is not chosen comes from the mechanism's ``display``
units of its workspace coordinates (:func:`default_units`: a coordinate shown in mm puts lengths
in mm, one shown in deg puts angles in deg); failing that, lengths in µm and angles in arcsec,
the units of precision tolerances.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Sequence

from evotol.errors import ValidationError

#: display unit -> its size in SI (m or rad)
LENGTHS = {"µm": 1e-6, "mm": 1e-3, "in": 0.0254}
ANGLES = {"arcsec": math.pi / (180 * 3600), "mrad": 1e-3, "deg": math.pi / 180}
#: spellings accepted in study files
ALIASES = {"um": "µm", "micron": "µm", "microns": "µm", "μm": "µm", "inch": "in", "\"": "arcsec", "°": "deg"}
DEFAULT_LENGTH, DEFAULT_ANGLE = "µm", "arcsec"


def _canonical(unit: str) -> str:
    return ALIASES.get(unit, unit)


@dataclass(frozen=True)
class DisplayUnits:
    """The units lengths and angles are shown in.

    Parameters
    ----------
    length : str, optional
        ``"µm"`` or ``"mm"`` (default µm; aliases such as ``"um"`` accepted).
    angle : str, optional
        ``"arcsec"``, ``"mrad"`` or ``"deg"`` (default arcsec; ``"°"`` accepted).

    Raises
    ------
    ValidationError
        An unknown length or angle unit.
    """

    length: str = DEFAULT_LENGTH
    angle: str = DEFAULT_ANGLE

    def __post_init__(self):
        object.__setattr__(self, "length", _canonical(self.length))
        object.__setattr__(self, "angle", _canonical(self.angle))
        if self.length not in LENGTHS:
            raise ValidationError("report.units (length)", self.length, f"one of {sorted(LENGTHS)}")
        if self.angle not in ANGLES:
            raise ValidationError("report.units (angle)", self.angle, f"one of {sorted(ANGLES)}")

    def unit_for(self, si_unit: str) -> str:
        """Display unit of a value in ``si_unit`` (``"m"`` -> length, ``"rad"`` -> angle; anything
        else is shown as it is).

        Parameters
        ----------
        si_unit : str
            The value's SI unit: ``"m"``, ``"rad"`` or another (e.g. ``"1"``).

        Returns
        -------
        str
            The display unit: :attr:`length`, :attr:`angle`, or ``si_unit`` itself.
        """
        return self.length if si_unit == "m" else self.angle if si_unit == "rad" else si_unit

    def factor(self, si_unit: str) -> float:
        """Multiply an SI value by this to get it in :meth:`unit_for` ``(si_unit)``.

        Parameters
        ----------
        si_unit : str
            The value's SI unit (``"m"``, ``"rad"``; any other gives 1).

        Returns
        -------
        float
            Display units per SI unit, e.g. 1e6 for m -> µm, about 206265 for rad -> arcsec.
        """
        if si_unit == "m":
            return 1.0 / LENGTHS[self.length]
        if si_unit == "rad":
            return 1.0 / ANGLES[self.angle]
        return 1.0

    def convert(self, value, si_unit: str):
        """``value`` (SI, scalar or array) in the display unit of ``si_unit``.

        Parameters
        ----------
        value : float or ndarray
            The value(s) in SI (m or rad).
        si_unit : str
            Their SI unit.

        Returns
        -------
        float or ndarray
            ``value`` times :meth:`factor`, same shape, in :meth:`unit_for` ``(si_unit)``.
        """
        return value * self.factor(si_unit)

    def format(self, value, si_unit: str, digits: int = 4, sign: str = "") -> str:
        """``value`` (SI) as text in its display unit, e.g. ``"44.67 µm"``; ``sign="±"`` prefixes it.

        Parameters
        ----------
        value : float or None
            The value in SI (m or rad).
        si_unit : str
            Its SI unit.
        digits : int, optional
            Significant digits (default 4; see :func:`number`).
        sign : str, optional
            Text put before the number (default none).

        Returns
        -------
        str
            The number and its display unit; ``"–"`` for None or NaN.
        """
        if value is None or (isinstance(value, float) and math.isnan(value)):
            return "–"
        return f"{sign}{number(self.convert(float(value), si_unit), digits)} {self.unit_for(si_unit)}"

    def to_dict(self) -> dict:
        """JSON form (``{"length": "µm", "angle": "arcsec"}``), the ``display_units`` of a result file.

        Returns
        -------
        dict
            ``{"length": str, "angle": str}``.
        """
        return {"length": self.length, "angle": self.angle}


#: a displayed value smaller than this (in its display unit) is round-off and shows as 0 (issue 33:
#: no "-1.115e-14 deg" in a table); no tolerance, error or coordinate is meaningful at 1e-9 of mm, µm, deg
ROUND_OFF = 1e-9


def number(v: float, digits: int = 4) -> str:
    """A number with ``digits`` significant digits, in plain decimals from 1e-4 to 1e6; below
    :data:`ROUND_OFF` in magnitude, ``"0"``.

    Parameters
    ----------
    v : float
        The number in its display unit (mm, µm, deg, × limit, ...; it is only formatted).
    digits : int, optional
        Significant digits (default 4).

    Returns
    -------
    str
        Plain decimals when ``1e-4 <= |v| < 1e6``, scientific notation otherwise; ``"0"`` when
        ``|v| < ROUND_OFF`` (never ``"-0"``); ``"inf"``, ``"nan"`` as ``format(v, "g")`` gives them.
    """
    if not math.isfinite(v):
        return f"{v:g}"
    if abs(v) < ROUND_OFF:
        return "0"
    if 1e-4 <= abs(v) < 1e6:
        r = float(f"{v:.{digits - 1}e}")        # rounded first: 0.0999999 -> 0.1000, not 0.10000
        decimals = max(0, digits - 1 - int(math.floor(math.log10(abs(r)))))
        return f"{r:.{decimals}f}"
    return f"{v:.{digits - 1}e}"


def default_units(display_units: Sequence[str] = ()) -> DisplayUnits:
    """Units from a mechanism's workspace ``display`` units (see the module docstring).

    Parameters
    ----------
    display_units : sequence of str
        The display unit of every workspace coordinate (``Workspace.display_units``).

    Returns
    -------
    DisplayUnits
        The first length unit and the first angle unit among them; µm and arcsec otherwise.
    """
    shown = [_canonical(u) for u in display_units]
    return DisplayUnits(next((u for u in shown if u in LENGTHS), DEFAULT_LENGTH),
                        next((u for u in shown if u in ANGLES), DEFAULT_ANGLE))


def parse_units(spec, default: DisplayUnits | None = None, field: str = "report.units") -> DisplayUnits:
    """The ``[report] units`` setting of a study file.

    Parameters
    ----------
    spec : str, sequence of str, mapping or None
        ``"mm"``, ``"um, arcsec"``, ``["mm", "deg"]`` or ``{length = "mm", angle = "deg"}``;
        None keeps ``default``.
    default : DisplayUnits, optional
        What is not chosen (default: µm and arcsec).
    field : str
        Name of the setting in error messages.

    Returns
    -------
    DisplayUnits
        The units chosen, the others from ``default``.

    Raises
    ------
    ValidationError
        An unknown unit, two lengths or two angles, or a table with other keys.
    """
    default = default or DisplayUnits()
    if spec is None:
        return default
    expected = (f"length unit {sorted(LENGTHS)} and/or angle unit {sorted(ANGLES)}: \"mm\", \"um, arcsec\", "
                "[\"mm\", \"deg\"] or {length = \"mm\", angle = \"deg\"}")
    if isinstance(spec, Mapping):
        extra = sorted(set(spec) - {"length", "angle"})
        if extra:
            raise ValidationError(f"{field}.{extra[0]}", spec[extra[0]], expected)
        items = [spec[k] for k in ("length", "angle") if k in spec]
    elif isinstance(spec, str):
        items = [s.strip() for s in spec.replace(";", ",").split(",") if s.strip()]
    elif isinstance(spec, (list, tuple)):
        items = list(spec)
    else:
        raise ValidationError(field, spec, expected)
    length, angle = None, None
    for item in items:
        u = _canonical(item) if isinstance(item, str) else item
        if u in LENGTHS and length is None:
            length = u
        elif u in ANGLES and angle is None:
            angle = u
        else:
            raise ValidationError(field, spec, expected)
    if isinstance(spec, Mapping) and (("length" in spec and length is None) or ("angle" in spec and angle is None)):
        raise ValidationError(field, spec, expected)
    return DisplayUnits(length or default.length, angle or default.angle)


def problem_units(problem) -> DisplayUnits:
    """Default display units of a :class:`evotol.core.problem.ToleranceProblem` (from its robot's workspace).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem; its ``robot.workspace.display_units`` are read.

    Returns
    -------
    DisplayUnits
        As :func:`default_units` gives them.
    """
    return default_units(problem.model.workspace.display_units)


def error_unit(problem, component: str) -> str:
    """SI unit of the ``component`` error (``"m"``, ``"rad"``; ``"1"`` for an assembly function,
    whose errors are fractions of the limits, ``evotol.robots.assembly``).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem; an assembly function has the workspace units ``("1",)``.
    component : str
        ``"position"`` or ``"orientation"``.

    Returns
    -------
    str
        ``"m"`` for position, ``"rad"`` otherwise, ``"1"`` for an assembly function.
    """
    if tuple(problem.model.workspace.units) == ("1",):
        return "1"
    return "m" if component == "position" else "rad"


def pose_coordinates(workspace, pose) -> list[tuple[str, float, str]]:
    """``(name, value, unit)`` of a workspace pose in the workspace's display units.

    Parameters
    ----------
    workspace : evotol.robots.base.Workspace
        Its ``names``, ``display_scale`` and ``display_units``.
    pose : array_like, shape (dim,)
        The pose in SI (m, rad).

    Returns
    -------
    list of (str, float, str)
        Per coordinate: its name, its value times the display scale, its display unit.
    """
    return [(n, float(v) * k, u) for n, v, k, u in zip(workspace.names, pose, workspace.display_scale,
                                                      workspace.display_units)]


def pose_text(workspace, pose, digits: int = 4) -> str:
    """A workspace pose as text in its display units, e.g. ``"x = 12.5 mm, y = -3 mm"``.

    Parameters
    ----------
    workspace : evotol.robots.base.Workspace
        Its coordinate names and display units.
    pose : array_like, shape (dim,)
        The pose in SI (m, rad).
    digits : int, optional
        Significant digits (default 4).

    Returns
    -------
    str
        ``name = value unit`` per coordinate, comma-separated (no unit for ``"1"`` or ``""``).
    """
    return ", ".join(f"{n} = {number(v, digits)}" + (f" {u}" if u not in ("1", "") else "")
                     for n, v, u in pose_coordinates(workspace, pose))

"""A calibration plan: where the robot is measured, what is measured, how well, and what is identified.

Industrial arms reach their accuracy by calibration: after assembly an instrument (a laser
tracker, a CMM) measures the tool at a few dozen configurations, a least-squares fit identifies
some geometric errors, and the controller compensates them (``docs/calibration.md``). A
:class:`CalibrationPlan` states that procedure before the robot exists, so that the tolerances
calibration will absorb are not paid for twice (:mod:`evotol.calibration.model`).

Everything is SI inside (m, rad). Noise values given as text carry their unit
(``"20 um"``, ``"0.02 mm"``, ``"5 arcsec"``); a bare number in a study file is refused
(:func:`parse_noise`), in Python it is SI.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from evotol.errors import ValidationError, is_integer
from evotol.units.quantity import parse_quantity, units_of

#: measured components and the rows of the error twist they take (position m, orientation rad)
MEASURED = {"position": slice(0, 3), "orientation": slice(3, 6)}
#: units accepted for a noise standard deviation, with their size in SI
NOISE_UNITS = {"position": units_of("length"), "orientation": units_of("angle")}
OVER = ("workspace", "joints")
INSTRUMENT = ("known", "unknown")
IDENTIFIABLE = "identifiable"


def _quantity(field_name: str, text, component: str, require_unit: bool) -> float:
    """One noise value (SI) from ``"20 um"`` or, unless ``require_unit``, a number (SI)."""
    units = NOISE_UNITS[component]
    if isinstance(text, bool):
        raise ValidationError(field_name, text, f"a standard deviation with its unit, e.g. '20 um' (units {sorted(units)})")
    if isinstance(text, (int, float, np.floating, np.integer)):
        if require_unit:
            raise ValidationError(field_name, text, f"a standard deviation with its unit, e.g. '{text} um' "
                                  f"(units {sorted(units)}); a bare number has none")
        value = float(text)
    else:
        value = parse_quantity(text, field_name, "length" if component == "position" else "angle")
    if not (np.isfinite(value) and value >= 0):
        raise ValidationError(field_name, text, "a standard deviation >= 0")
    return value


def parse_noise(spec, measure=("position",), require_unit: bool = True, field_name: str = "calibration.noise") -> dict:
    """The instrument's noise per measured component: a standard deviation per axis (SI).

    Parameters
    ----------
    spec : str or mapping
        ``"20 um"`` (every position axis), or a mapping component -> a value or three values
        (``{"position": ["20 um", "20 um", "40 um"], "orientation": "5 arcsec"}``).
    measure : sequence of str
        The measured components (``"position"``, ``"orientation"``); each needs a noise.
    require_unit : bool
        Refuse bare numbers (study files); False takes them as SI (Python).
    field_name : str
        Field named in errors.

    Returns
    -------
    dict of str to ndarray (3,)
        Component -> standard deviation per axis (m or rad), base-frame axes x, y, z.

    Raises
    ------
    evotol.errors.ValidationError
        A value without a unit (when required), an unknown unit, a negative or non-finite value,
        a measured component without noise, a noise for a component not measured, or not one or
        three values.
    """
    if isinstance(spec, (str, int, float)) and not isinstance(spec, bool):
        spec = {"position": spec}
    if not isinstance(spec, Mapping):
        raise ValidationError(field_name, spec, "a value with its unit ('20 um') or a table {position = ..., orientation = ...}")
    out = {}
    for comp, v in spec.items():
        if comp not in MEASURED:
            raise ValidationError(f"{field_name}.{comp}", v, f"one of {list(MEASURED)}")
        if comp not in measure:
            raise ValidationError(f"{field_name}.{comp}", v, f"a noise only for measured components {list(measure)}")
        vals = list(v) if isinstance(v, (list, tuple, np.ndarray)) else [v]
        if len(vals) not in (1, 3):
            raise ValidationError(f"{field_name}.{comp}", v, "one value (every axis) or three (x, y, z)")
        s = [_quantity(f"{field_name}.{comp}", x, comp, require_unit) for x in vals]
        out[comp] = np.array(s * 3 if len(s) == 1 else s, float)
    for comp in measure:
        if comp not in out:
            raise ValidationError(f"{field_name}.{comp}", None, f"the instrument's standard deviation of the measured {comp}")
    return out


@dataclass(frozen=True)
class CalibrationPlan:
    """How the robot will be calibrated (module docstring; ``docs/calibration.md``).

    Exactly one of ``joints``, ``poses`` and ``count`` gives the calibration configurations.

    Parameters
    ----------
    noise : str or mapping
        The instrument's standard deviation per measured axis (:func:`parse_noise`): ``"20 um"``,
        or ``{"position": ..., "orientation": ...}``; numbers are SI (m, rad).
    identify : str or sequence of str
        The sources the fit identifies and the controller compensates: name patterns
        (``["*_joint"]``, fnmatch), or ``"identifiable"`` for a base set of every source the plan
        can see (:func:`evotol.calibration.identification.identify`).
    joints : array_like (n, n_joint_variables), optional
        Joint values of the calibration configurations (rad, m), in the order of the model's
        joint variables.
    poses : array_like (n, workspace.dim), optional
        Workspace poses of the calibration configurations (SI), solved by the inverse geometry.
    count : int, optional
        Number of configurations drawn by a Latin hypercube over ``over`` with ``seed``.
    over : {"workspace", "joints"}
        What ``count`` configurations are drawn over: the workspace box, or the joint limits
        (serial arms).
    seed : int
        Seed of the Latin hypercube.
    measure : sequence of str
        ``("position",)`` (a tracker's target) or ``("position", "orientation")`` (a 6-D
        instrument).
    instrument : {"known", "unknown"}
        ``"unknown"``: the instrument's frame in the base (6 parameters) and the target's place on
        the tool (3, or 6 with orientation measured) are identified too (registration).
    k : float
        Coverage factor of the noise in worst-case measures: the requirement keeps ``k`` sigma of
        the propagated noise (default 3).
    linear_fraction : float or str
        Calibrated sources' tolerances are bounded so that the second-order terms the linear
        identification ignores stay below this fraction of the requirement, in (0, 1) (default 0.1;
        or a percentage ``"10 %"``; :mod:`evotol.calibration.linear_range`); in Python a value above
        100 (e.g. 1e8) leaves the sources uncapped.
    compensation_range : mapping of str to float, optional
        Source pattern -> the largest correction the controller applies (m or rad); a calibrated
        source's tolerance never exceeds it.
    floor : float or str or None
        Height of the cell's floor (the mounting plane) in the base frame (m, or text with its unit,
        ``"0 mm"``); a configuration that puts a joint origin or the tool below it is not in the plan
        (:mod:`evotol.calibration.configurations`). Default 0: the mounting plane. None (``"none"``): no floor.
    obstacles : sequence of mapping, optional
        Axis-aligned boxes ``{"min": [x, y, z], "max": [x, y, z]}`` (m) in the base frame that no
        joint origin and no tool may enter.
    require_units : bool
        Refuse noise values without a unit (a study file's table); False (Python) takes numbers as SI.

    Raises
    ------
    evotol.errors.ValidationError
        Not exactly one of ``joints``, ``poses``, ``count``; a count below 1; an unknown
        ``over``, ``measure`` or ``instrument``; a bad noise (:func:`parse_noise`); ``k`` or
        ``linear_fraction`` not positive, or ``linear_fraction`` of 1 or more (in a study file;
        in Python from 1 to 100: a percentage written as a number); a negative compensation range; ``identify`` empty.
    """

    noise: object
    identify: object = IDENTIFIABLE
    joints: object = None
    poses: object = None
    count: int | None = None
    over: str = "workspace"
    seed: int = 0
    measure: tuple = ("position",)
    instrument: str = "known"
    k: float = 3.0
    linear_fraction: float = 0.1
    compensation_range: Mapping = field(default_factory=dict)
    floor: object = 0.0
    obstacles: tuple = ()
    require_units: bool = False

    def __post_init__(self):
        given = [n for n in ("joints", "poses", "count") if getattr(self, n) is not None]
        if len(given) != 1:
            raise ValidationError("calibration.configurations", given or None,
                                  "exactly one of joints = [[...]], poses = [[...]] or count = n")
        if self.count is not None and not is_integer(self.count, 1):
            raise ValidationError("calibration.count", self.count, "a positive integer")
        for name in ("joints", "poses"):
            v = getattr(self, name)
            if v is not None:
                try:
                    arr = np.atleast_2d(np.asarray(v, float))
                except (TypeError, ValueError):
                    raise ValidationError(f"calibration.{name}", v, "a list of rows of numbers (SI)") from None
                if arr.ndim != 2 or arr.size == 0 or not np.all(np.isfinite(arr)):
                    raise ValidationError(f"calibration.{name}", v, "a non-empty list of rows of finite numbers (SI)")
                object.__setattr__(self, name, arr)
        if self.over not in OVER:
            raise ValidationError("calibration.over", self.over, f"one of {OVER}")
        meas = (self.measure,) if isinstance(self.measure, str) else tuple(self.measure)
        if not meas or any(m not in MEASURED for m in meas) or "position" not in meas:
            raise ValidationError("calibration.measure", self.measure, "'position' or ['position', 'orientation']")
        object.__setattr__(self, "measure", tuple(c for c in MEASURED if c in meas))
        if self.instrument not in INSTRUMENT:
            raise ValidationError("calibration.instrument", self.instrument, f"one of {INSTRUMENT}")
        object.__setattr__(self, "noise", parse_noise(self.noise, self.measure, self.require_units))
        ident = self.identify
        if isinstance(ident, str) and ident != IDENTIFIABLE:
            ident = (ident,)
        if not isinstance(ident, str):
            ident = tuple(ident)
            if not ident or not all(isinstance(p, str) and p for p in ident):
                raise ValidationError("calibration.identify", self.identify, f"source name patterns or {IDENTIFIABLE!r}")
        object.__setattr__(self, "identify", ident)
        lf = self.linear_fraction
        if isinstance(lf, str) and lf.strip().endswith("%"):        # "10 %": the fraction written as a percentage
            try:
                object.__setattr__(self, "linear_fraction", float(lf.strip()[:-1]) / 100)
            except ValueError:
                raise ValidationError("calibration.linear_fraction", lf, "a fraction in (0, 1) or a percentage such as "
                                                                         "'10 %'") from None
        for name in ("k", "linear_fraction"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (np.isfinite(v) and v > 0):
                raise ValidationError(f"calibration.{name}", v, "a positive number")
        # a share of the requirement: 10 meant as 10 % is the slip; in Python a huge value (1e8) turns the cap off
        if self.linear_fraction >= 1 and (self.require_units or self.linear_fraction <= 100):
            hint = "" if isinstance(lf, str) else f" (if {lf:g} was meant in %, write {lf / 100:g} or '{lf:g} %')"
            raise ValidationError("calibration.linear_fraction", lf, "a fraction of the requirement in (0, 1), e.g. 0.1 "
                                  "or '10 %'" + hint)
        object.__setattr__(self, "compensation_range", {
            pat: parse_quantity(v, f"calibration.compensation_range.{pat}") if isinstance(v, str) else v
            for pat, v in dict(self.compensation_range).items()})
        for pat, v in dict(self.compensation_range).items():
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (np.isfinite(v) and v > 0):
                raise ValidationError(f"calibration.compensation_range.{pat}", v, "a positive range (m or rad)")
        fl = self.floor
        if isinstance(fl, str) and fl.strip().lower() == "none":
            fl = None
        if isinstance(fl, str):
            fl = parse_quantity(fl, "calibration.floor", "length")
        if fl is not None and (isinstance(fl, bool) or not isinstance(fl, (int, float)) or not np.isfinite(fl)):
            raise ValidationError("calibration.floor", self.floor, "a height in the base frame (m, or '0 mm'), or none")
        object.__setattr__(self, "floor", None if fl is None else float(fl))
        boxes = []
        for i, box in enumerate(self.obstacles if isinstance(self.obstacles, (list, tuple)) else [self.obstacles]):
            try:
                lo, hi = (np.asarray(box[k], float) for k in ("min", "max"))
            except (TypeError, KeyError, ValueError):
                raise ValidationError(f"calibration.obstacles[{i}]", box, "a box {min = [x, y, z], max = [x, y, z]} (m)") from None
            if lo.shape != (3,) or hi.shape != (3,) or not np.all(np.isfinite(lo) & np.isfinite(hi)) or np.any(hi <= lo):
                raise ValidationError(f"calibration.obstacles[{i}]", box, "a box {min = [x, y, z], max = [x, y, z]} (m) "
                                      "with min < max on every axis")
            boxes.append((lo, hi))
        object.__setattr__(self, "obstacles", tuple(boxes))

    @property
    def rows_per_configuration(self) -> int:
        """Measured coordinates per configuration: 3 (position) or 6 (with orientation)."""
        return 3 * len(self.measure)

    def sigma_rows(self, n: int) -> np.ndarray:
        """Standard deviation of every measured row over ``n`` configurations (m, rad), configuration-major.

        Parameters
        ----------
        n : int
            Number of calibration configurations.

        Returns
        -------
        (n * rows_per_configuration,) ndarray
            Per configuration: the position axes' sigmas, then the orientation axes'.
        """
        return np.tile(np.concatenate([self.noise[c] for c in self.measure]), n)

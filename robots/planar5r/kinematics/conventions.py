"""Conventions of the planar 5R kinematics (Lara-Molina et al. 2019, Secs. 2.3-2.4): frame, branches, inputs.

The frame and the branch signs every solver of :mod:`evotol.robots.planar5r.kinematics` uses, the
working-mode table, and the input checks they share (points, assembly mode, floating dtype).

Frame and labels (those of the paper's eqs. 11-12, 16-19): ``O`` is the midpoint of the base,
``A_1 = (-r3, 0)``, ``A_2 = (r3, 0)``; the crank ``A_iB_i`` (length ``r1``) turns by the actuated
angle ``theta_i`` measured from the x axis, ``B_i = A_i + r1 (cos theta_i, sin theta_i)``; the
couplers ``B_iP`` (length ``r2``) meet at the end-effector ``P = (x, y)``.

The printed eqs. 9-10 place ``A_1`` at ``(+r3, 0)``; their expansion, eqs. 11-12, and the
workspace circles, eqs. 16-19, place it at ``(-r3, 0)``. We follow eqs. 11-12 / 16-19.

Branches, as signs of cross products (robust, unlike a choice of root):

* **assembly mode** (forward kinematics, the paper's sigma of eq. 15):
  ``sigma = sign(cross(B_2 - B_1, P - B_1)) = sign(det J_x)``, +1 = ``P`` on the left of the
  directed line ``B_1 -> B_2``. When ``B_2`` lies to the right of ``B_1`` (the usual posture)
  this is the larger root ``y`` of eq. 14, i.e. the paper's ``sigma = +1``.
* **working mode** (inverse kinematics): ``m_i = sign(cross(P - A_i, B_i - A_i))``. The default
  ``"+-"`` (``m_1 = +1, m_2 = -1``) has both elbows ``B_i`` outside the triangle ``A_1 P A_2``;
  it is the mode in which the MIC closed forms eqs. 21-22 describe the usable workspace.

Singularities: type I (serial) where ``A_i, B_i, P`` are aligned (``J_q`` singular; the circles
of eqs. 16-19); type II (parallel) where ``B_1, B_2, P`` are aligned (``det J_x = 0``).

Everything works with lengths in any unit (non-dimensional in the paper, metres in the robot
error model); angles in radians. Arrays broadcast; nothing loops in Python.

Precision: positions and angles keep their floating dtype. ``float64`` is the default; pass
``np.longdouble`` arrays (80-bit extended on x86-64, eps = 1.1e-19) when you need the round trip
``forward(inverse(p))`` to hold near the type II border, where the forward problem amplifies the
rounding of ``theta`` by the condition number ``1 / LCI`` (docs/planar5r.md, "Round trip").
"""
from __future__ import annotations

import numpy as np

from evotol.errors import ValidationError

#: Working modes by name: the elbow signs ``(m_1, m_2)`` (see the module docstring).
WORKING_MODES = {"+-": (1, -1), "-+": (-1, 1), "++": (1, 1), "--": (-1, -1)}
#: The working mode of the paper's eqs. 21-22: both elbows outside the triangle ``A_1 P A_2``.
DEFAULT_WORKING_MODE = "+-"


def working_mode_signs(working_mode) -> tuple[int, int]:
    """Signs ``(m_1, m_2)`` of a working mode (see the module docstring).

    Returns
    -------
    tuple of int
        ``(m_1, m_2)``, each +1 or -1.

    Raises
    ------
    ValidationError
        If ``working_mode`` is neither a known string nor a pair of +1/-1.
    """
    if isinstance(working_mode, str) and working_mode in WORKING_MODES:
        return WORKING_MODES[working_mode]
    if isinstance(working_mode, (tuple, list)) and len(working_mode) == 2 and all(m in (1, -1) for m in working_mode):
        return int(working_mode[0]), int(working_mode[1])
    raise ValidationError("working_mode", working_mode, f"one of {sorted(WORKING_MODES)} or a pair of +-1")


def _check_assembly(assembly) -> int:
    if assembly not in (1, -1):
        raise ValidationError("assembly", assembly, "+1 or -1 (sigma of eq. 15)")
    return int(assembly)


def _as_points(p, field="p") -> np.ndarray:
    try:
        arr = _as_float(p)
    except (TypeError, ValueError) as exc:
        raise ValidationError(field, p, "an array (..., 2) of numbers") from exc
    if arr.ndim == 0 or arr.shape[-1] != 2:
        raise ValidationError(f"{field} shape", arr.shape, "(..., 2)")
    if not np.all(np.isfinite(arr)):
        raise ValidationError(field, arr[~np.all(np.isfinite(arr), axis=-1)][0].tolist(), "finite numbers")
    return arr


def _as_float(x) -> np.ndarray:
    """``x`` as a floating array: float64 unless it already is a wider float (long double)."""
    arr = np.asarray(x)
    return arr.astype(np.result_type(arr.dtype, np.float64), copy=False)


def _common_float(*xs) -> list[np.ndarray]:
    """``xs`` as arrays of their widest floating dtype (so that lengths given as Python floats
    are squared in long double when the poses are long double, not rounded to float64 first)."""
    arrs = [np.asarray(x) for x in xs]
    dtype = np.result_type(np.float64, *(a.dtype for a in arrs))
    return [a.astype(dtype, copy=False) for a in arrs]


def cross2(ax, ay, bx, by):
    """z component of the cross product of two planar vectors.

    Parameters
    ----------
    ax, ay, bx, by : array_like
        Components of the vectors ``a`` and ``b``, broadcastable.

    Returns
    -------
    ndarray or float
        ``ax * by - ay * bx``, in the product of their units.
    """
    return ax * by - ay * bx

"""Settings of the certified clearance engine: one frozen value passed down from the public calls
(:func:`evotol.robots.clearance.max_pose_error`, :class:`~evotol.robots.clearance.ClearanceEvaluator`, ...) to the
branch and bound (:mod:`evotol.robots.clearance.branch_bound`) and the convex solver
(:mod:`evotol.robots.clearance.support`). A worker process receives the options with its task, never
through module state (``docs/clearance.md``, issue 13 for what each setting changed).

``DEFAULT`` is the engine; ``LEGACY`` its settings before issue 13 (the agreement tests and the
benchmark compare the two); ``NUMPY`` the default with the NumPy Newton iteration instead of the
compiled one (the reference of :mod:`evotol.robots.clearance.newton_kernel`).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from evotol.errors import ValidationError

PATCH_BOUNDS = ("exact", "legacy")
PREDICTORS = ("path", "legacy")


@dataclass(frozen=True)
class EngineOptions:
    """Settings of the branch and bound over directions and of the support-function solver.

    Parameters
    ----------
    stop_below : float
        A branch-and-bound vertex certified this fraction below the best value needs no more
        precision (0.06; 0.01 before issue 13).
    n_circle0 : int
        Initial vertices on the half circle for 2-component targets (3; 6 before issue 13).
    level0 : int
        Initial subdivision of the half-sphere octants (3-component targets).
    polish_rtol0, polish_rtol : float
        Relative precision of the ascent from the initial vertices' best point, and of the final
        ascent (1e-6; the final one 1e-8 before issue 13).
    dedup_antipodes : bool
        Solve one vertex of each antipodal pair (h(-u) = h(u)); False: both (before issue 13).
    patch_bound : str
        ``"exact"``: the exact sublinearity bound of a patch; ``"legacy"``: ``min(max H / d, |X|)``.
    interpolate, interpolate_arc : int
        Sub-patches per edge of the dual-interpolation bound on triangles, and sub-arcs per arc
        (0: no interpolation bound, as before issue 13).
    centred : float
        Newton decrement (squared) below which a barrier problem counts as centred.
    growth : float
        Factor of the barrier parameter at each centring (16; 8 before the path predictor).
    predictor : str
        ``"path"``: predictor scaled by tau_old / tau_new (checked against no step);
        ``"legacy"``: the best of 1, .75, .5, .25, 0.
    kernel : bool or None
        Newton iteration compiled with numba (None: when available; True: required) or NumPy (False).

    Raises
    ------
    ValidationError
        A setting out of its range.
    """

    stop_below: float = 0.06
    n_circle0: int = 3
    level0: int = 0
    polish_rtol0: float = 1e-6
    polish_rtol: float = 1e-6
    dedup_antipodes: bool = True
    patch_bound: str = "exact"
    interpolate: int = 6
    interpolate_arc: int = 24
    centred: float = 1e-2
    growth: float = 16.0
    predictor: str = "path"
    kernel: bool | None = None

    def __post_init__(self):
        if self.patch_bound not in PATCH_BOUNDS:
            raise ValidationError("EngineOptions.patch_bound", self.patch_bound, f"one of {PATCH_BOUNDS}")
        if self.predictor not in PREDICTORS:
            raise ValidationError("EngineOptions.predictor", self.predictor, f"one of {PREDICTORS}")
        if self.kernel not in (None, True, False):
            raise ValidationError("EngineOptions.kernel", self.kernel, "None, True or False")
        for f in ("stop_below", "polish_rtol0", "polish_rtol", "centred"):
            if not 0 < getattr(self, f) < 1:
                raise ValidationError(f"EngineOptions.{f}", getattr(self, f), "a number in (0, 1)")
        if not self.growth > 1:
            raise ValidationError("EngineOptions.growth", self.growth, "a factor > 1")
        for f in ("n_circle0", "level0", "interpolate", "interpolate_arc"):
            v = getattr(self, f)
            if int(v) != v or v < (2 if f == "n_circle0" else 0):
                raise ValidationError(f"EngineOptions.{f}", v, "a whole number >= " + ("2" if f == "n_circle0" else "0"))


#: the engine's settings
DEFAULT = EngineOptions()
#: the engine's settings before issue 13 (for the agreement tests and the benchmark)
LEGACY = EngineOptions(stop_below=0.01, n_circle0=6, polish_rtol=1e-8, dedup_antipodes=False, patch_bound="legacy",
                       interpolate=0, predictor="legacy", growth=8.0)
#: the engine with the NumPy Newton iteration (the reference of the compiled one)
NUMPY = replace(DEFAULT, kernel=False)

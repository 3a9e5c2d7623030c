"""Will the study fit in memory? An estimate from the problem's sizes, checked before the first method
(issue 43 item 4): a study that would need more memory than the machine has is told so, with its
estimate, instead of swapping or being killed after minutes of work.

The worst-case measures keep, per component (position and orientation: both are evaluated for the report), the support coefficients
``c[p, d, j] = t-coefficient of source j along direction d at pose p`` (8 bytes each; with
asymmetric intervals also the offsets' part ``const[p, d]`` and twice the directions, the full
sphere). Measured on the UR5 study (36 sources, 600 directions, position and orientation) at 3 375
poses: the two caches take 1.17 GB and the peak beyond the imports was 2.2 GB, so the estimate is
twice the caches (:data:`WORKING_FACTOR`) plus the sensitivities. Above
:data:`~evotol.core.problem.tolerance_problem.COEFFICIENT_CACHE_BYTES` a component's coefficients are
not kept: a few poses' at a time are computed and multiplied by the designs
(:class:`~evotol.measures.linear.support_grid.LazySupport`); what stays is a block's grid values.
"""
from __future__ import annotations

from evotol._runtime.memory import available_bytes
from evotol.errors import ValidationError
from evotol.core.problem.tolerance_problem import COEFFICIENT_CACHE_BYTES
from evotol.measures.linear.stackup import DESIGN_BLOCK_BYTES

#: the peak over the caches: the optimum's and the feasibility check's working copies (measured 1.9 on the UR5)
WORKING_FACTOR = 2.0
#: what a study keeps per pose besides its sensitivities (results, Monte Carlo records, the page), measured on
#: the UR5 study (sensitivity, Monte Carlo of 100 samples a pose, report; coefficients computed a few poses at a
#: time, posture checked in blocks): max RSS 0.565 GB at 10 648 poses, 1.113 GB at 103 823 poses (2026-12-02):
#: 5.9 kB a pose more, the sensitivities' 1.7 kB included; rounded up (was 25 kB before those two changes)
PER_POSE_BYTES = 8_000
#: share of the available memory a study may plan to take
USABLE_SHARE = 0.9


def study_bytes(problem) -> int:
    """Estimated peak memory of a study's methods on ``problem`` (bytes; module docstring).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem whose methods are estimated (its poses, sources and directions).

    Returns
    -------
    int
        ``WORKING_FACTOR * Σ_components P D (n_src + [asymmetric]) * 8`` (when above
        ``COEFFICIENT_CACHE_BYTES``: the grid values of a block of designs and poses,
        :data:`~evotol.measures.linear.stackup.DESIGN_BLOCK_BYTES`) plus, per pose, the sensitivities and
        :data:`PER_POSE_BYTES`, with D
        the directions :func:`evotol.measures.linear.directions_for` takes for each component (fewer for a
        planar error, 1 for an error along one axis).
    """
    caches = 0
    for comp in problem.blocks:                 # position and orientation: both are evaluated for the report
        full = problem.coefficient_bytes(comp)
        caches += full if full <= COEFFICIENT_CACHE_BYTES else DESIGN_BLOCK_BYTES    # else: a block's grid values
    return int(WORKING_FACTOR * caches + problem.n_poses * (6 * problem.error_model.n_columns * 8 + PER_POSE_BYTES))


def check_memory(problem, available: int | None = None) -> None:
    """Refuse, before any work, a study whose estimate exceeds the memory available.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The study's problem, before its first method runs.
    available : int, optional
        Bytes available (default: :func:`evotol._runtime.memory.available_bytes`; unknown: no check).

    Raises
    ------
    evotol.errors.ValidationError
        One line: the number of poses, the estimate and what is available, and how many poses fit.
    """
    available = available_bytes() if available is None else available
    need = study_bytes(problem)
    if available is None or need <= USABLE_SHARE * available:
        return
    per_pose = need / max(problem.n_poses, 1)
    fit = int(USABLE_SHARE * available / per_pose)
    raise ValidationError("poses", f"{problem.n_poses} poses", f"at most about {fit} poses here: the worst-case "
                          f"measures of {problem.n_sources} sources over {problem.n_directions} directions need about "
                          f"{need / 2 ** 30:.1f} GiB ({per_pose / 1024:.0f} KiB a pose), and {available / 2 ** 30:.1f} GiB "
                          "is available; give fewer poses, or start from a few with [poses] refine = true")

"""Random feasible clearance states: the largest pose error plain Monte Carlo would report at one
pose -- it falls short of the certified worst case of :func:`evotol.robots.clearance.max_pose_error`."""
from __future__ import annotations

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.clearance.maxerror import as_bounds
from evotol.robots.clearance.model import ClearanceMechanism


def sample_max_errors(mech: ClearanceMechanism, pose, bounds=None, *, n_samples: int = 10 ** 6, seed: int = 0,
                      mode: str = "boundary", chunk: int = 100_000) -> tuple[float, float]:
    """Largest positional and rotational error reached by **random** clearance states at one pose
    -- what plain Monte Carlo verification would report (compare with :func:`max_pose_error`).

    Each sample draws every joint's screw at random in its clearance set (``mode="uniform"``:
    uniformly inside the disks and intervals; ``"boundary"``: on their boundaries, i.e. every
    clearance fully taken up in a random direction), removes the part that violates the loop
    equations (orthogonal projection onto ``B^T s = 0``) and scales back into the clearance set,
    so every sample is a feasible, consistent clearance state. Returns (p, r) in m and rad.

    Parameters
    ----------
    pose : (d,) array_like
        One pose in the mechanism's pose coordinates (m).
    bounds : array_like or None, optional
        ``(n_joints, 4)``, columns ``[beta_xy (rad), beta_z (rad), b_xy (m), b_z (m)]``; None
        (default): the joints' own bounds.
    n_samples : int, optional
        Number of random states (default ``10 ** 6``).
    seed : int, optional
        Seed of the random generator (default 0).
    mode : str, optional
        ``"boundary"`` (default) or ``"uniform"``.
    chunk : int, optional
        Samples drawn at a time (memory; default 100 000).

    Returns
    -------
    p : float
        Largest position error of the samples, m.
    r : float
        Largest orientation error of the samples, rad.

    Raises
    ------
    ValidationError
        ``mode`` not ``"uniform"`` or ``"boundary"``; bounds of a wrong shape, negative or
        non-finite.
    """
    if mode not in ("uniform", "boundary"):
        raise ValidationError("mode", mode, "'uniform' or 'boundary'")
    rng = np.random.default_rng(seed)
    maps = mech.pose_maps(np.atleast_2d(np.asarray(pose, float)))
    b = as_bounds(mech, bounds, 1)
    best = {"p": np.zeros(1), "r": np.zeros(1)}
    left = int(n_samples)
    while left > 0:
        n = min(chunk, left)
        left -= n
        tot = {"p": np.zeros(n), "r": np.zeros(n)}
        for pm in maps:
            s = pm.sample_screws(0, b, n, rng, mode)
            tot["p"] += ((s @ pm.C_pos[0].T) ** 2).sum(-1)
            tot["r"] += ((s @ pm.C_rot[0].T) ** 2).sum(-1)
        for w in ("p", "r"):
            best[w] = np.maximum(best[w], np.sqrt(tot[w].max()))
    return float(best["p"][0]), float(best["r"][0])

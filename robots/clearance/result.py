"""The result of the certified clearance engine: maximum pose errors with their certificates,
maximising screws and twists (Deng 2012 eqs. III.26-III.27; :func:`evotol.robots.clearance.max_pose_error`)."""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from evotol.errors import ValidationError


@dataclass
class MaxPoseError:
    """Global maximum pose errors of a set of cases (poses and/or clearance-bound sets).

    p_max (m), r_max (rad): values attained by the explicit screws ``p_screws``/``r_screws``
    (``(n, n_joints, 6)``, each joint's ``[dr; dt]`` in its own frame, rad and m);
    p_upper, r_upper: certified upper bounds; p_twist, r_twist: end-effector error twists
    ``[dtheta; dp]`` (base axes) produced by those screws; gap: largest relative gap per case;
    n_solves: support problems solved; n_newton: Newton iterations summed over the problems
    (the solver's work, counted per call: no global counter).

    Parameters
    ----------
    p_max : (n,) ndarray
        Largest position error attained per case, m.
    p_upper : (n,) ndarray
        Certified upper bound on the position error per case, m.
    r_max : (n,) ndarray
        Largest orientation error attained per case, rad.
    r_upper : (n,) ndarray
        Certified upper bound on the orientation error per case, rad.
    p_screws : (n, n_joints, 6) ndarray
        Joint error screws ``[dr; dt]`` (rad, m; each in its joint's frame) attaining ``p_max``.
    r_screws : (n, n_joints, 6) ndarray
        Joint error screws attaining ``r_max``.
    p_twist : (n, 6) ndarray
        End-effector error twist ``[dtheta; dp]`` (rad, m; base axes) produced by ``p_screws``.
    r_twist : (n, 6) ndarray
        End-effector error twist produced by ``r_screws``.
    joint_names : tuple of str
        Names of the joints, in the order of the screws' second axis.
    seconds : float, optional
        Wall-clock time, s (default 0).
    n_newton : int, optional
        Newton iterations summed over the support problems (default 0).
    p_extra : (n, q) ndarray or None, optional
        Values of the extra interval sources at the ``p_max`` maximiser (in their own units), or
        None without extra sources.
    r_extra : (n, q) ndarray or None, optional
        Values of the extra sources at the ``r_max`` maximiser, or None.
    """

    p_max: np.ndarray
    p_upper: np.ndarray
    r_max: np.ndarray
    r_upper: np.ndarray
    p_screws: np.ndarray
    r_screws: np.ndarray
    p_twist: np.ndarray
    r_twist: np.ndarray
    joint_names: tuple[str, ...]
    n_solves: int = 0
    seconds: float = 0.0
    n_newton: int = 0
    p_extra: np.ndarray | None = None   # (n, q) values of the extra sources at the p maximiser
    r_extra: np.ndarray | None = None

    @classmethod
    def concat(cls, parts) -> "MaxPoseError":
        """The cases of several results in order (chunks of a grid); ``n_solves``, ``n_newton``,
        ``seconds`` summed.

        Parameters
        ----------
        parts : sequence of MaxPoseError
            Results with the same joints, in case order.

        Returns
        -------
        MaxPoseError
            All cases of ``parts`` concatenated (``joint_names`` from the first part; ``p_extra``
            and ``r_extra`` concatenated too when every part has them, None when none has).

        Raises
        ------
        evotol.errors.ValidationError
            Some parts carry the values of extra sources and others do not.
        """
        cat = {f: np.concatenate([getattr(p, f) for p in parts]) for f in
               ("p_max", "p_upper", "r_max", "r_upper", "p_screws", "r_screws", "p_twist", "r_twist")}
        for f in ("p_extra", "r_extra"):
            have = [getattr(p, f) is not None for p in parts]
            if any(have) and not all(have):
                raise ValidationError(f"parts[{have.index(not have[0])}].{f}", "None" if have[0] else "present",
                                      f"{f} on every part or on none (results of one evaluation)")
            cat[f] = np.concatenate([getattr(p, f) for p in parts]) if all(have) else None
        return cls(**cat, joint_names=parts[0].joint_names, n_solves=sum(p.n_solves for p in parts),
                   seconds=sum(p.seconds for p in parts), n_newton=sum(p.n_newton for p in parts))

    def take(self, idx) -> "MaxPoseError":
        """The cases ``idx`` (index array), in that order.

        Parameters
        ----------
        idx : int array or slice
            Indices (or a boolean mask) of the cases to keep.

        Returns
        -------
        MaxPoseError
            A copy with the per-case arrays (and ``p_extra``, ``r_extra`` when present) indexed by
            ``idx``; the counters and ``seconds`` unchanged.
        """
        per_case = {f: getattr(self, f)[idx] for f in
                    ("p_max", "p_upper", "r_max", "r_upper", "p_screws", "r_screws", "p_twist", "r_twist")}
        extra = {f: None if getattr(self, f) is None else getattr(self, f)[idx] for f in ("p_extra", "r_extra")}
        return replace(self, **per_case, **extra)

    @property
    def p_gap(self) -> np.ndarray:
        """(n,) ndarray: relative gap ``(p_upper - p_max) / p_upper`` per case, dimensionless."""
        return (self.p_upper - self.p_max) / np.maximum(self.p_upper, 1e-300)

    @property
    def r_gap(self) -> np.ndarray:
        """(n,) ndarray: relative gap ``(r_upper - r_max) / r_upper`` per case, dimensionless."""
        return (self.r_upper - self.r_max) / np.maximum(self.r_upper, 1e-300)

    @property
    def gap(self) -> np.ndarray:
        """(n,) ndarray: the larger of ``p_gap`` and ``r_gap`` per case, dimensionless."""
        return np.maximum(self.p_gap, self.r_gap)

    def dominant_joints(self, i: int = 0, which: str = "p") -> list[tuple[str, float]]:
        """Joints ranked by the share of their clearance used at the maximiser of case ``i``.

        Parameters
        ----------
        i : int, optional
            Case index (default 0).
        which : str, optional
            ``"p"`` (default): the position-error maximiser ``p_screws``; anything else: the
            orientation-error maximiser ``r_screws``.

        Returns
        -------
        list of (str, float)
            ``(joint name, norm of its error screw)`` pairs, largest first. The norm mixes rad
            and m components (the Euclidean norm of the 6-vector ``[dr; dt]``).
        """
        S = (self.p_screws if which == "p" else self.r_screws)[i]
        mag = np.linalg.norm(S, axis=1)
        order = np.argsort(mag)[::-1]
        return [(self.joint_names[j], float(mag[j])) for j in order]

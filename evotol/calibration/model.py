"""The calibrated robot: the error left after calibration, as a robot error model.

:class:`CalibratedRobot` wraps an error model and a plan's :class:`~evotol.calibration.identification.Identification`.
Its first-order map at task poses is ``J M`` (``e = (J − J_K A_K⁺ A) δp``, the identification's
module docstring): a linear map of the sensitivity, so every allocator and every measure works on
it unchanged. The instrument noise, propagated through the fit to a task pose, is the covariance
``C = J_K Σ_K J_Kᵀ`` (:meth:`CalibratedRobot.noise_covariance`); it enters the requirement
(:func:`noise_allowance`):

* worst-case measures (``worst_case``, ``mc_quantile`` and the other bounds) keep the quantile ``q`` of
  the noise's norm at the level ``P(|z| ≤ k)`` (99.73 % at ``k = 3``; :mod:`evotol.calibration.noise_share`):
  the geometric error must stay below ``E − max_poses q`` (the triangle inequality), so that at a pose
  the residual meets ``E`` with at least that probability;
* ``rss`` adds it in quadrature: ``sqrt(E² − q²)``;
* ``yield`` adds ``C`` to the first-order covariance at every pose (exact for normal sources: the
  noise is normal and independent of the geometric errors).

The calibrated model has no nonlinear ``pose_error`` (the nonlinear check is the simulated
calibration, :mod:`evotol.calibration.simulation`, which draws one robot for every pose).

The parameters several definitions of this module share are described once, here.

Parameters
----------
poses : (n, workspace.dim) array_like
    Task poses (SI).
"""
from __future__ import annotations

import numpy as np

from evotol.calibration.noise_share import level_of, norm_quantile
from evotol.errors import ValidationError
from evotol.robots.base import RobotErrorModel

#: how each measure accounts for the noise: "linear" (E - k sigma), "quadrature" (sqrt(E^2 - (k sigma)^2)), "covariance"
NOISE_RULE = {"rss": "quadrature", "yield": "covariance"}


class CalibratedRobot(RobotErrorModel):
    """An error model after calibration: first-order map ``J M``, plus the propagated noise (module docstring).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The uncalibrated model (its sources, workspace, sensitivities).
    identification : evotol.calibration.identification.Identification
        What the plan identifies (``M``, ``Σ_K``).
    plan : evotol.calibration.plan.CalibrationPlan
        The plan (kept for reports and the simulated calibration).
    """

    part = "calibration"

    def __init__(self, robot: RobotErrorModel, identification, plan):
        self.base = robot
        self.identification = identification
        self.plan = plan
        self.name = robot.name
        self.sources = robot.sources
        self.workspace = robot.workspace
        #: False for a model without a nonlinear joint-space model: no linear-range bounds (set by calibrated_problem)
        self.linear_range_checked = True
        #: sources whose effect the first-order map does not show: after calibration every source acts
        #: through the second-order terms its linear-range bound limits (docs/calibration.md), so a zero
        #: column here never means "no effect on the requirement"
        self.effect_beyond_first_order = frozenset(robot.source_names)

    def sensitivity(self, poses) -> np.ndarray:
        """Post-calibration first-order map ``J M`` (n, 6, n_columns) at task poses.

        Parameters
        ----------
        poses : (n, workspace.dim) array_like
            Task poses (SI: m, rad).

        Returns
        -------
        (n, 6, n_columns) ndarray
            Error twist after compensation per unit source error (m or rad per m or rad); the
            columns of the identified sources are zero up to round-off.

        Raises
        ------
        evotol.errors.ValidationError, evotol.errors.KinematicsError
            What the uncalibrated model's ``sensitivity`` raises.
        """
        return np.asarray(self.base.sensitivity(poses), float) @ self.identification.M

    def noise_covariance(self, poses) -> np.ndarray:
        """Covariance (n, 6, 6) of the instrument noise propagated to task poses (m², rad²).

        Returns
        -------
        (n, 6, 6) ndarray
            ``J_K Σ_K J_Kᵀ``: position block (m²) rows 0-2, orientation (rad²) rows 3-5.

        Raises
        ------
        evotol.errors.ValidationError, evotol.errors.KinematicsError
            What the uncalibrated model's ``sensitivity`` raises.
        """
        J = np.asarray(self.base.sensitivity(poses), float)[:, :, self.identification.identified]
        return J @ self.identification.sigma_K @ np.swapaxes(J, 1, 2)

    def noise_cov6(self, poses) -> dict:
        """The noise covariance in the yield model's packed form: component -> (n, 6) (xx, yy, zz, xy, xz, yz).

        Returns
        -------
        dict of str to (n, 6) ndarray
            ``"position"`` (m²) and ``"orientation"`` (rad²).
        """
        C = self.noise_covariance(poses)
        pairs = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
        return {c: np.stack([C[:, o + a, o + b] for a, b in pairs], -1) for c, o in (("position", 0), ("orientation", 3))}

    def noise_sigma(self, poses) -> dict:
        """Largest standard deviation of the propagated noise per pose: component -> (n,) (m, rad).

        Returns
        -------
        dict of str to (n,) ndarray
            ``sqrt(λ_max)`` of the position (m) and orientation (rad) blocks of the covariance.
        """
        C = self.noise_covariance(poses)
        return {c: np.sqrt(np.maximum(np.linalg.eigvalsh(C[:, o:o + 3, o:o + 3])[:, -1], 0.0))
                for c, o in (("position", 0), ("orientation", 3))}

    def nonlinear_checks(self, problem, t, seed: int = 0) -> dict:
        """The base's checks and the calibration simulated on the nonlinear model (``"calibration"``).

        :func:`evotol.calibration.simulation.simulate_calibration` with ``problem.calibration.simulate``
        robots; none when that is 0 or the plan has no joint configurations (a model without a
        nonlinear joint-space model).

        Returns
        -------
        dict
            The base model's checks, and ``"calibration"``: a
            :class:`evotol.calibration.simulation.CalibrationCheck`.
        """
        from evotol.calibration.simulation import simulate_calibration    # simulation reads this module

        out = super().nonlinear_checks(problem, t, seed)
        info = problem.calibration
        if info is not None and info.simulate and info.identification.joints is not None:
            out["calibration"] = simulate_calibration(problem, t, n_samples=info.simulate, seed=seed)
        return out

    def notes(self) -> list[str]:
        """Report lines of the wrapped model plus one stating the calibration.

        Returns
        -------
        list of str
            The base model's notes and the calibration's sentence.
        """
        base = list(self.base.notes())
        idn = self.identification
        return base + [f"Calibrated: {len(idn.identified)} sources identified from {idn.n_measurements} measured "
                       f"coordinates (condition number {idn.condition:.3g}); tolerances are allocated on the error "
                       "left after compensation (docs/calibration.md)."] + (
            [] if self.linear_range_checked else
            [f"{self.name} has no nonlinear joint-space model: the identified sources' tolerances are bounded by "
             "their upper bounds only (no linear-range check, no simulated calibration)."])


def noise_allowance(robot: CalibratedRobot, poses, requirement, second_order: dict | None = None,
                    remainder: dict | None = None, random: dict | None = None) -> dict:
    """How much of the requirement the instrument noise takes, per constrained component (module docstring).

    The noise's share is the quantile ``q`` of the propagated noise's norm at the level
    ``P(|z| ≤ k)`` (99.73 % at ``k = 3``), the largest over the poses
    (:func:`evotol.calibration.noise_share.norm_quantile`): at any one pose the noise's norm stays
    below it with that probability. ``k σ_max`` is kept beside it for comparison.

    Parameters
    ----------
    robot : CalibratedRobot
        The calibrated model.
    poses : (n, dim) ndarray
        Task poses (SI).
    requirement : evotol.core.requirement.Requirement
        The user's requirement (``measure`` chooses the rule).
    second_order : dict, optional
        Component -> second-order effect of the noise-driven identified values (m, rad;
        :func:`evotol.calibration.linear_range.noise_second_order`), taken off the bound first
        under every rule.
    remainder : dict, optional
        Component -> the second-order allowance of the sources within their final upper bounds (m,
        rad; :func:`evotol.calibration.linear_range.remainder_allowance`), taken off the bound too.
    random : dict, optional
        :func:`evotol.calibration.random_share.random_terms` of the robot's random sources: their
        ``covariance`` through the identification is added to the noise's before the quantile, and their
        ``worst_case`` at the poses (the largest) is taken off the bound.

    Returns
    -------
    dict
        ``rule`` (``"linear"``, ``"quadrature"`` or ``"covariance"``), ``k``, and per constrained
        component: ``{component: {"sigma": largest propagated sigma (m or rad), "k_sigma": k sigma,
        "allowance": the noise's quantile q, "level": its probability, "second_order": the noise's
        second-order term, "remainder": the sources' second-order allowance, "bound": the user's bound,
        "geometric_bound": what is left for the tolerances, "coverage": the probability that the
        3-D noise stays inside the ball of radius q at a pose (= level)}}``; with ``random`` also
        ``"noise_only"`` (the quantile without the random sources), ``"random_identification"`` (what they
        add to it) and ``"random_worst_case"`` (their largest effect at a pose, taken off with ``d``).

    Raises
    ------
    evotol.errors.ValidationError
        The noise alone takes the whole requirement (names the component and its share).
    """
    rule = NOISE_RULE.get(requirement.measure, "linear")
    k = float(robot.plan.k)
    level = level_of(k)
    sig = robot.noise_sigma(poses)
    cov = robot.noise_covariance(poses)
    out = {"rule": rule, "k": k}
    for comp, o in (("position", 0), ("orientation", 3)):
        E = getattr(requirement, comp)
        if E is None:
            continue
        s = float(sig[comp].max())
        d = float((second_order or {}).get(comp, 0.0)) + float((remainder or {}).get(comp, 0.0))
        a = float(norm_quantile(cov[:, o:o + 3, o:o + 3], level).max(initial=0.0))
        extra = {}
        if random is not None:      # the random sources: beside the noise in the fit, and at the pose itself
            both = cov[:, o:o + 3, o:o + 3] + random["covariance"][:, o:o + 3, o:o + 3]
            a, a0 = float(norm_quantile(both, level).max(initial=0.0)), a
            w = float(random["worst_case"][comp].max())
            extra = {"noise_only": a0, "random_identification": a - a0, "random_worst_case": w}
            d += w
        if a + d >= E or (rule == "covariance" and d >= E):
            u = "m" if comp == "position" else "rad"
            raise ValidationError("calibration.noise", f"{100 * level:.2f} % quantile {a:.3g} {u} + second order"
                                  f"{' and random sources' if extra else ''} {d:.3g} {u}",
                                  f"an instrument noise whose {comp} effect after calibration stays below the requirement "
                                  f"{E:g} {u} (condition number {robot.identification.condition:.3g}: spread the "
                                  "configurations, e.g. over = 'joints', or identify fewer sources)")
        if rule == "covariance":
            geo = float(E - d)
        else:
            geo = float(E - d - a) if rule == "linear" else float(np.sqrt((E - d) ** 2 - a * a))
        out[comp] = {"sigma": s, "k_sigma": k * s, "allowance": a, "level": level,
                     "second_order": float((second_order or {}).get(comp, 0.0)),
                     "remainder": float((remainder or {}).get(comp, 0.0)), "bound": float(E), "geometric_bound": geo,
                     "coverage": level, **extra}
    return out

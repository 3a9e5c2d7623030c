"""Random sources in a calibrated robot's budget (issue 44 item 4, docs/calibration.md).

Calibration removes the identifiable systematic part of a robot's error; what changes from one cycle to
the next (lost motion, encoder quantisation, bearing play: :mod:`evotol.robots.mechanism.model.random_sources`)
it cannot remove, and it disturbs the identification beside the instrument's noise. After calibration the
error at a task pose is, to first order,

    e = J M δp  −  J_K (B⁺)_K W (ε + A_r r_cal)  +  J r,

with ``J M δp`` the systematic residual (the calibrated model), ``ε`` the instrument noise, ``r_cal`` the
random sources' column errors at the calibration visits (``A_r`` the measured rows of the map there, ``W``
the rows' weights ``1/σ``) and ``r`` their column errors at the task pose. Two terms enter the requirement:

* **through the identification** (:func:`identification_covariance`): the readings' random part has, per
  configuration ``c``, the covariance ``A_c V A_cᵀ`` (``V`` the column covariance of one visit,
  :func:`visit_covariance`; visits independent), so the identified values carry
  ``Σ_r = (B⁺)_K W diag_c(A_c V A_cᵀ) W (B⁺)_Kᵀ`` beside the noise's ``Σ_K``. Their effect at a task pose
  ``J_K (Σ_K + Σ_r) J_Kᵀ`` is taken as normal (a sum over every configuration's reading: the central limit
  theorem; the simulated calibration checks it) and its norm's quantile replaces the noise's
  (:mod:`evotol.calibration.noise_share`);
* **at the pose** (:func:`worst_case_norm`): ``max |J r|`` over the random sources' ranges, a proven bound
  (grid of directions / cos δ), taken off the requirement by the triangle inequality
  ``|e| ≤ |J M δp| + |n| + max |J r|``.

The ranges and variances of one visit, per unit tolerance ``t`` (the kinds' definitions): lost motion taken
up from either side (a calibration or a task visit comes from any direction) ``±(1 + v) t/2``, variance
``t²/4 + (v t)²/12`` (the as-built lost motion at its largest, ``b' = b``); encoder ``±t/2``, ``t²/12``; axial
play ``±t/2``, ``t²/12``; radial play a disc of radius ``t/2`` (``t²/16`` per axis).

Parameters
----------
sources : sequence of evotol.robots.mechanism.model.random_sources.RandomSource
    The random sources.
loadings : list of (n_columns, dim) ndarray
    Per source its :func:`~evotol.robots.mechanism.model.random_sources.column_loading`.
tolerances : (n_random,) array_like
    Per source its tolerance (SI).
part : RandomPart
    The random sources with their tolerances and loadings.
robot : evotol.robots.base.RobotErrorModel
    The uncalibrated model (a described mechanism: the calibration configurations are joints or poses).
identification : evotol.calibration.identification.Identification
    The plan's identification.
plan : evotol.calibration.plan.CalibrationPlan
    The plan (its measured components).
poses : (n, dim) array_like
    Task poses (SI).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.calibration.plan import MEASURED
from evotol.errors import ValidationError
from evotol.measures.iso9283.budget import joints_and_maps, lost_motion_parts, rp_unit_errors
from evotol.measures.iso9283.poses import full_poses
from evotol.measures.linear.directions import directions_for, hemisphere


@dataclass(frozen=True)
class IsoTarget:
    """ISO 9283 figures required of the calibrated robot at the test cube's poses (issue 44, docs/iso9283.md).

    Parameters
    ----------
    positions : tuple of (x, y, z)
        The ISO poses P1..P5 (m).
    AP, RP : float or None
        Required calibrated AP (worst case) and RP (m); None: not required.
    """

    positions: tuple
    AP: float | None
    RP: float | None


@dataclass(frozen=True)
class RandomPart:
    """The random sources a calibrated problem carries beside its systematic ones (SI).

    Parameters
    ----------
    sources : tuple of RandomSource
        The random sources.
    tolerances : tuple of float
        Their tolerances (SI: rad, m).
    loadings : tuple of (n_columns, dim) ndarray
        Their column loadings.
    costs, lower, upper : tuple or None
        To allocate them (:mod:`evotol.calibration.random_allocation`): per source its cost model and
        bounds (SI); None: their tolerances are given.
    iso : IsoTarget or None
        ISO 9283 AP/RP the allocation must also meet after calibration; None: none.

    Raises
    ------
    evotol.errors.ValidationError
        No source, or not one tolerance and one loading per source.
    """

    @property
    def allocated(self) -> bool:
        """The sources are variables of the calibrated allocation (costs and bounds given)."""
        return self.costs is not None

    sources: tuple
    tolerances: tuple
    loadings: tuple
    costs: tuple | None = None
    lower: tuple | None = None
    upper: tuple | None = None
    iso: IsoTarget | None = None

    def __post_init__(self):
        if not (len(self.sources) == len(self.tolerances) == len(self.loadings)) or not self.sources:
            raise ValidationError("calibration random sources", len(self.sources), "one tolerance and one loading per "
                                  "random source, at least one source")


def _unit_parts(s) -> tuple[float, float]:
    """(half-range, variance) per unit tolerance of one visit (module docstring); radial play per axis."""
    if s.kind == "backlash":
        return (1 + s.variation) / 2, 0.25 + s.variation ** 2 / 12
    if s.kind == "radial_play":
        return 0.5, 1 / 16
    return 0.5, 1 / 12


def visit_covariance(part: RandomPart) -> np.ndarray:
    """Covariance (n_columns, n_columns) of the random column errors at one visit: ``Σ_k t_k² v_k G_k G_kᵀ``.

    Returns
    -------
    (n_columns, n_columns) ndarray
        m², rad² (module docstring: the variances).
    """
    return sum(t * t * _unit_parts(s)[1] * (G @ G.T) for s, t, G in zip(part.sources, part.tolerances, part.loadings))


def identification_covariance(estimator, weights, rows: np.ndarray, part: RandomPart) -> np.ndarray:
    """``Σ_r``: covariance (n_K, n_K) of the identified values from the random sources at the readings.

    Parameters
    ----------
    estimator : (n_K, n_measurements) ndarray
        ``(B⁺)_K`` on the weighted readings (:attr:`Identification.estimator`).
    weights : (n_measurements,) ndarray
        ``1/σ`` of each measured row.
    rows : (n_configurations, rows_per_configuration, n_columns) ndarray
        The measured rows of the first-order map at each calibration configuration.

    Returns
    -------
    (n_K, n_K) ndarray
        m², rad².
    """
    V = visit_covariance(part)
    n, r, _ = rows.shape
    P = (np.asarray(estimator, float) * np.asarray(weights, float)[None]).reshape(-1, n, r)     # (n_K, n, r)
    T = np.einsum("knr,nrm->nkm", P, rows)                                                      # (n, n_K, m)
    return np.einsum("nkm,ml,njl->kj", T, V, T)


def worst_case_norm(J: np.ndarray, part: RandomPart, n_directions: int = 600) -> np.ndarray:
    """Proven bound of ``max |J r|`` at each pose over the random sources' ranges at one visit.

    ``|J r|`` is largest in some direction ``u``; the set of ``J r`` is a sum of segments (lost motion,
    encoder, axial play) and discs (radial play), so its support is ``h(u) = Σ_k t_k a_k |u·J g_k|``
    (segments, ``a_k`` the half-range) ``+ Σ_k (t_k/2) |Gᵀ Jᵀ u|`` (discs). The largest ``h`` over a grid of
    directions whose ``±`` covers the sphere within ``δ``, divided by ``cos δ``, bounds it.

    Parameters
    ----------
    J : (p, 3, n_columns) ndarray
        Position (or orientation) rows of the first-order map at the task poses.
    n_directions : int
        Hemisphere directions of the grid.

    Returns
    -------
    (p,) ndarray
        m (or rad).
    """
    D, delta = hemisphere(n_directions)
    h = np.zeros((len(J), len(D)))
    for s, t, G in zip(part.sources, part.tolerances, part.loadings):
        a = np.einsum("dk,pkm,mj->pdj", D, J, G)                                 # (p, d, dim)
        h += t * (0.5 * np.linalg.norm(a, axis=-1) if s.kind == "radial_play" else _unit_parts(s)[0] * np.abs(a[..., 0]))
    return h.max(axis=1) / np.cos(delta)


def draw_visits(part: RandomPart, n: int, rng) -> np.ndarray:
    """Random column errors (n, n_columns) of ``n`` independent visits from any side (module docstring).

    Lost motion: the as-built ``b' ~ U(0, b)`` is not drawn here; the side ``±1`` and the variation are
    (``±b/2`` at the largest ``b' = b``, the case the bounds cover).

    Parameters
    ----------
    n : int
        Visits.
    rng : numpy.random.Generator
        The generator.

    Returns
    -------
    (n, n_columns) ndarray
        m, rad.
    """
    out = 0.0
    for s, t, G in zip(part.sources, part.tolerances, part.loadings):
        if s.kind == "radial_play":
            r, phi = 0.5 * np.sqrt(rng.random(n)), rng.uniform(0, 2 * np.pi, n)
            d = np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)
        elif s.kind == "backlash":
            d = (rng.choice([-0.5, 0.5], n) + s.variation * rng.uniform(-0.5, 0.5, n))[:, None]
        else:
            d = rng.uniform(-0.5, 0.5, (n, 1))
        out = out + t * d @ G.T
    return np.asarray(out)


def random_terms(robot, identification, plan, poses, part: RandomPart) -> dict:
    """What the random sources add at the task poses of a calibrated robot (module docstring).

    Returns
    -------
    dict
        ``covariance`` (n, 6, 6): ``J_K Σ_r J_Kᵀ`` (m², rad²), to add to the noise's; ``worst_case``:
        component -> (n,) proven bound of ``max |J r|`` (m, rad); ``sigma_K`` the identified values'
        covariance ``Σ_r``.
    """
    idn = identification
    S = robot.sensitivity_at_joints(idn.joints) if idn.joints is not None else robot.sensitivity(idn.poses)
    idx = np.concatenate([np.arange(6)[MEASURED[c]] for c in plan.measure])
    sig_r = identification_covariance(idn.estimator, idn.weights, np.asarray(S, float)[:, idx, :], part)
    J = np.asarray(robot.sensitivity(poses), float)
    JK = J[:, :, idn.identified]
    return {"covariance": JK @ sig_r @ np.swapaxes(JK, 1, 2), "sigma_K": sig_r,
            "worst_case": {"position": worst_case_norm(J[:, :3], part), "orientation": worst_case_norm(J[:, 3:], part)}}


def unit_terms(robot, identification, plan, poses, part: RandomPart, n_directions: int = 600) -> dict:
    """Per random source at unit tolerance: its covariance through the identification and its support at
    the task poses (position rows), for :func:`evotol.calibration.random_allocation.allocate_random`.

    Parameters
    ----------
    n_directions : int
        Hemisphere directions of the support grid.

    Returns
    -------
    dict
        ``covariance`` (K, n, 3, 3) (m² per unit²), ``support`` (K, n, d) (m per unit), ``cos_delta``.
    """
    idn = identification
    S = robot.sensitivity_at_joints(idn.joints) if idn.joints is not None else robot.sensitivity(idn.poses)
    idx = np.concatenate([np.arange(6)[MEASURED[c]] for c in plan.measure])
    J = np.asarray(robot.sensitivity(poses), float)
    JK = J[:, :3, idn.identified]
    D, delta = hemisphere(n_directions)
    cov, sup = [], []
    for src, G in zip(part.sources, part.loadings):
        one = RandomPart((src,), (1.0,), (G,))
        sig = identification_covariance(idn.estimator, idn.weights, np.asarray(S, float)[:, idx, :], one)
        cov.append(JK @ sig @ np.swapaxes(JK, 1, 2))
        a = np.einsum("dk,pkm,mj->pdj", D, J[:, :3], G)
        sup.append(0.5 * np.linalg.norm(a, axis=-1) if src.kind == "radial_play" else _unit_parts(src)[0] * np.abs(a[..., 0]))
    return {"covariance": np.array(cov), "support": np.array(sup), "cos_delta": float(np.cos(delta))}


def iso_terms(cal, identification, plan, part: RandomPart, systematic, n_samples: int = 10000, seed: int = 0) -> dict:
    """The calibrated ISO 9283 figures at the test cube's poses as functions of the random tolerances ``τ``, for
    :func:`evotol.calibration.random_allocation.allocate_random` (docs/iso9283.md, "ISO requirements in a
    calibrated budget").

    After calibration a robot's barycentre error at an ISO pose is ``J M δ + J o(τ) + n(τ)``
    (:func:`evotol.calibration.iso9283.predict_calibrated`): the systematic residual (``δ`` in ``±t``), the lost
    motion's offset for the test's approach (a box linear in ``τ``, :func:`evotol.measures.iso9283.budget.lost_motion_parts`)
    and the fit's error, normal with covariance ``C_0 + Σ_k τ_k² C_k``. The worst case of the first two in a
    direction ``u`` is ``s_0(u) + Σ_k τ_k s_k(u)`` (linear in ``τ``): on a full-sphere grid of directions its
    maximum / cos δ is a proven bound, convex in ``τ``. RP is the random sources' own, unchanged by calibration.

    Parameters
    ----------
    cal : evotol.calibration.model.CalibratedRobot
        The calibrated model (its ``base`` the arm).
    systematic : (n_columns,) array_like
        The systematic tolerances the bound holds for (SI; their upper bounds: any design below is covered).
    n_samples : int
        Cycle draws, the same for every design (common random numbers of the RP quantile).
    seed : int
        Seed of the draws.

    Returns
    -------
    dict
        ``C0`` (p, 3, 3) and ``cov`` (K, p, 3, 3) (m², m² per unit²); ``s0`` (p, d) and ``support`` (K, p, d)
        (m, m per unit); ``cos_delta``; ``E`` (p, n, 3, K) centred unit errors for RP; ``AP``, ``RP`` (m or None).
    """
    from_positions = np.asarray(part.iso.positions, float)
    robot = cal.base
    poses = full_poses(robot, from_positions)
    _, S = joints_and_maps(robot, from_positions)
    JM = np.asarray(cal.sensitivity(poses), float)[:, :3]
    D, delta = directions_for(S[:, :3], 600, full_sphere=True)
    C, H = lost_motion_parts(robot, S, part.sources, part.loadings)                       # (p, m, K)
    JD = np.einsum("dk,pkm->pdm", D, S[:, :3])
    support = np.einsum("pdm,pmk->kpd", JD, C) + np.einsum("pdm,pmk->kpd", np.abs(JD), H)
    s0 = np.abs(np.einsum("dk,pkm->pdm", D, JM)) @ np.asarray(systematic, float)
    u = unit_terms(robot, identification, plan, poses, part)
    return {"C0": cal.noise_covariance(poses)[:, :3, :3], "cov": u["covariance"], "s0": s0, "support": support,
            "cos_delta": float(np.cos(delta)), "E": rp_unit_errors(robot, S, part.sources, n_samples, seed),
            "AP": part.iso.AP, "RP": part.iso.RP}

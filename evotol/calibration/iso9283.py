"""The ISO 9283 test of calibrated robots, simulated (issue 44 item 4, docs/iso9283.md).

Each simulated robot is calibrated as a laser-tracker calibration does it and then tested:

1. **measure** the flange position at ``n_configurations`` poses of the workspace (a Latin hypercube of
   the task box, so the cell's floor is respected as the box is), on the nonlinear model, with the
   robot's systematic errors, its lost motion taken up from a random side at each pose, its random
   sources drawn for that visit, and the instrument's noise (normal, ``noise`` m per axis);
2. **identify** the systematic errors by linear least squares on the first-order map, minimum-norm
   (``δ̂ = A⁺ y``, singular values below ``1e-8 s_max`` dropped: the unidentifiable directions stay
   unknown);
3. **compensate**: at each ISO pose the controller commands the joints ``Δq = −J_q⁺ J δ̂`` (position
   rows, minimum-norm joint change), which the model adds to the encoder columns;
4. **test**: the standard's protocol on the calibrated robot (:func:`evotol.measures.iso9283.simulate`'s
   steps), the same cycle draws as the uncalibrated test.

Calibration removes the identifiable systematic part; the random sources (repeatability) enter the
identification beside the instrument's noise, and the lost motion's fixed offset, the unidentifiable
sources and the noise stay: the calibrated AP is never 0, and RP does not change.

Parameters
----------
robot : evotol.robots.mechanism.model.error_model.MechanismModel
    The arm.
positions : (p, 3) array_like
    The ISO poses (m).
systematic : (n_columns,) array_like
    Systematic tolerances (uniform in ±t).
sources : sequence of evotol.robots.mechanism.model.random_sources.RandomSource
    The random sources.
random_t : (n_random,) array_like
    Their tolerances (SI).
"""
from __future__ import annotations

import numpy as np

from evotol.calibration.noise_share import level_of, norm_quantile
from evotol.calibration.random_share import RandomPart, random_terms
from evotol.errors import ValidationError
from evotol.measures.iso9283.budget import APPROACHES, approach_signs, joints_and_maps, lost_motion_columns
from evotol.measures.iso9283.figures import ap_worst_case, figures_of_test
from evotol.measures.iso9283.poses import full_poses
from evotol.robots.mechanism.model.random_sources import column_loading, cycle_errors, unit_draws


def _actuator_columns(robot) -> list[int]:
    names = list(robot.source_names)
    return [names.index(j) for j in robot.kin.actuated if j in names]


def simulate_calibrated(robot, positions, systematic, sources, random_t, n_robots: int = 100, n_cycles: int = 30,
                        n_configurations: int = 40, noise: float = 10e-6, seed: int = 0) -> dict:
    """ISO 9283 AP and RP of robots before and after a simulated calibration (module docstring).

    Parameters
    ----------
    n_robots : int
        Robots built within the tolerances.
    n_cycles : int
        Cycles per ISO pose.
    n_configurations : int
        Calibration poses (at least ceil(n_columns / 3)).
    noise : float
        The instrument's standard deviation per axis (m), >= 0.
    seed : int
        Seed of the draws.

    Returns
    -------
    dict
        ``AP_before``, ``AP_after``, ``RP_before``, ``RP_after`` (n_robots, p) in m; ``rank`` of the
        identification and ``n_columns``.

    Raises
    ------
    evotol.errors.ValidationError
        Too few configurations, a negative noise, or an arm whose encoder columns are not sources.
    """
    m = robot.n_columns
    if n_configurations * 3 < m or noise < 0:
        raise ValidationError("iso9283.calibration", {"configurations": n_configurations, "noise": noise},
                              f"at least {int(np.ceil(m / 3))} configurations and a noise >= 0")
    act = _actuator_columns(robot)
    if len(act) != len(robot.kin.actuated):
        raise ValidationError("iso9283.calibration", robot.kin.actuated, "every actuated joint's encoder column among "
                              "the model's sources (the compensation commands the joints)")
    rng = np.random.default_rng(seed)
    ts, t = np.asarray(systematic, float), np.asarray(random_t, float)
    loadings = column_loading(robot, sources)
    ws = robot.workspace
    idx = [list(ws.names).index(a) for a in "xyz"]
    cal = ws.latin_hypercube(n_configurations, seed=seed)[:, idx]
    qc, Sc = joints_and_maps(robot, cal)
    A = Sc[:, :3].reshape(-1, m)                                             # (3N, m)
    U, s, Vt = np.linalg.svd(A, full_matrices=False)
    keep = s > 1e-8 * s[0]
    A_pinv = (Vt[keep].T / s[keep]) @ U[:, keep].T
    P = np.asarray(positions, float)
    qp, Sp = joints_and_maps(robot, P)
    Jq = Sp[:, :3][:, :, act]                                                # (p, 3, n_act)
    delta = ts * rng.uniform(-1, 1, (n_robots, m))
    share = rng.random((n_robots, m))
    # calibration measurements: lost motion from a random side per visit, a cycle's random draw, noise
    side = rng.choice([-1.0, 1.0], (n_configurations, n_robots, len(act)))
    lm_unit = lost_motion_columns(sources, loadings, t, [dict(zip(robot.kin.actuated, -np.ones(len(act))))])[0][0] \
        if len(sources) else np.zeros(m)
    off = np.zeros((n_configurations, n_robots, m))
    off[:, :, act] = side * (share * lm_unit)[:, act][None]
    rand = cycle_errors(loadings, t, unit_draws(sources, n_configurations * n_robots, rng)).reshape(
        n_configurations, n_robots, m) if len(sources) else 0.0
    y = robot.pose_error_at_joints(qc, delta[None] + off + rand)[..., :3]   # (N, R, 3)
    y = y + noise * rng.standard_normal(y.shape)
    dhat = (A_pinv @ y.transpose(0, 2, 1).reshape(-1, n_robots)).T          # (R, m)
    dq = -np.einsum("pak,pkm,rm->rpa", np.linalg.pinv(Jq), Sp[:, :3], dhat)  # (R, p, n_act)
    lm, free = lost_motion_columns(sources, loadings, t, approach_signs(robot, Sp, APPROACHES["-z"])) \
        if len(sources) else (np.zeros((len(P), m)), np.zeros((len(P), m)))
    fixed = delta[None] + share[None] * lm[:, None] + share[None] * np.abs(free[:, None]) * rng.uniform(-1, 1, (len(P), n_robots, m))
    cyc = cycle_errors(loadings, t, unit_draws(sources, len(P) * n_robots * n_cycles, rng)).reshape(
        len(P), n_robots * n_cycles, m) if len(sources) else 0.0
    out = {}
    for label, corr in (("before", 0.0), ("after", 1.0)):
        f = fixed.copy()
        f[:, :, act] += corr * dq.transpose(1, 0, 2)
        e = robot.pose_error_at_joints(qp, f.repeat(n_cycles, axis=1) + cyc)[..., :3]
        fig = figures_of_test(e.reshape(len(P), n_robots, n_cycles, 3) + P[:, None, None], P[:, None])
        out[f"AP_{label}"], out[f"RP_{label}"] = fig["AP"].T, fig["RP"].T
    out.update(rank=int(keep.sum()), n_columns=m)
    return out


def predict_calibrated(problem, positions, systematic, sources, random_t) -> dict:
    """Predicted ISO 9283 AP of a robot calibrated by the study's plan (``[calibration]``), first order.

    After the plan's calibration a robot's barycentre error at an ISO pose is ``J M δ + J o + n``: the
    systematic residual (``M`` the plan's post-calibration map, ``δ`` in ``±t``), the lost motion's fixed
    offset ``o`` for the test's approach (not identified: the calibration takes it up from any side), and
    the identification's error ``n`` -- the tracker's noise and the random sources at the calibration
    visits (:mod:`evotol.calibration.random_share`), normal. AP is bounded by the worst case of the first two
    (:func:`evotol.measures.iso9283.figures.ap_worst_case` over the stacked zonotope, proven) plus the quantile
    of ``|n|`` at the plan's level; RP is the random sources' and does not change.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The calibrated problem (``problem.calibration``).

    Returns
    -------
    dict
        Per position (p,): ``AP_systematic`` (worst case of ``J M δ + J o``, attained), ``AP_bound`` (its proven
        bound), ``noise_quantile`` (of ``|n|``), ``AP`` (``AP_bound + noise_quantile``), all m; ``level``.
    """
    info = problem.calibration
    cal, robot = problem.model, problem.model.base
    P = np.asarray(positions, float)
    poses = full_poses(robot, P)
    q, S = joints_and_maps(robot, P)
    JM = np.asarray(cal.sensitivity(poses), float)[:, :3]
    loadings, t = column_loading(robot, sources), np.asarray(random_t, float)
    m = robot.n_columns
    if len(sources):
        lm, free = lost_motion_columns(sources, loadings, t, approach_signs(robot, S, APPROACHES["-z"]))
    else:
        lm, free = np.zeros((len(P), m)), np.zeros((len(P), m))
    ts = np.asarray(systematic, float)
    J = np.concatenate([JM, S[:, :3]], axis=2)
    val, bound = np.empty(len(P)), np.empty(len(P))
    for i in range(len(P)):
        a, b = ap_worst_case(J[i:i + 1], np.concatenate([np.zeros(m), lm[i] / 2]),
                             np.concatenate([ts, np.abs(lm[i]) / 2 + np.abs(free[i])]))
        val[i], bound[i] = a[0], b[0]
    C = cal.noise_covariance(poses)[:, :3, :3]
    if info.random is not None:
        part = RandomPart(tuple(sources), tuple(t), tuple(loadings))
        C = C + random_terms(robot, info.identification, info.plan, poses, part)["covariance"][:, :3, :3]
    level = level_of(info.plan.k)
    nq = norm_quantile(C, level)
    return {"AP_systematic": val, "AP_bound": bound, "noise_quantile": nq, "AP": bound + nq, "level": level}

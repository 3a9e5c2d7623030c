"""How large a calibrated source may be: the identification's linear range and the controller's range.

After calibration an identified source has no first-order effect (its column of ``J M`` is zero),
so the first-order model would let its tolerance grow without bound. It may not: the allocation
is certified on the first-order model, which holds only while the terms it ignores are small.

Second-order terms. The post-calibration error of a robot with source errors ``x`` at a task pose is
``g(x)``: the nonlinear model's readings at the calibration configurations, the linear fit
``x̂_K = (B⁺)_K y`` (:mod:`evotol.calibration.identification`), and the controller's compensation of
``x̂_K`` (:mod:`evotol.calibration.compensation`), the true model's error after it. Its first-order
part is ``J M x``; what the first-order model ignores is ``½ Σ_jk H_jk x_j x_k + O(|x|³)``. The
second-order terms come from every source, not only the identified ones: a source the fit absorbs
into an identified one (a shift read as a joint offset) makes the identified value, and the
correction the controller applies, large -- its second-order effect is what limits it. ``H_jk`` is
taken by central differences of ``g`` (step ``STEP``), whose stencils cancel the first-order part.
With ``N_jk = |H_jk|`` (the norm of the position, or orientation, rows) at each pose, the upper
bounds

    u_j = sqrt(2 φ E / (n r_j)),     r_j = max over poses of Σ_k N_jk,

give ``|½ Σ_jk H_jk x_j x_k| ≤ ½ Σ_jk N_jk u_j u_k ≤ ½ Σ_j u_j² r_j ≤ φ E`` at every pose for every
``|x_j| ≤ u_j`` (``u_j u_k ≤ (u_j² + u_k²)/2``; n sources): the second-order terms stay below the
fraction ``φ`` (``plan.linear_fraction``) of the requirement ``E``. The second derivatives are
taken at every task pose up to ``MAX_POSES`` (64), beyond that at a farthest-point subset in joint
space (:func:`pose_subset`; the terms vary smoothly over the workspace, and the simulated
calibration checks every pose). A source with no second-order effect
(``r_j = 0``) is bounded by the user's upper bound only. The controller's compensation range
(``plan.compensation_range``, by source pattern) bounds an identified source's tolerance too. The
bound holds to second order with a linear fit; the simulated calibration
(:mod:`evotol.calibration.simulation`, nonlinear fit) checks it.

The parameters several definitions of this module share are described once, here.

Parameters
----------
task_joints : (n_task, n_variables) ndarray
    Joint values of the task poses (rad, m).
idn : evotol.calibration.identification.Identification
    The identification.
step : float
    Central-difference step (m or rad).
"""
from __future__ import annotations

import fnmatch

import numpy as np

from evotol.calibration.compensation import Compensation
from evotol.calibration.plan import MEASURED

#: finite-difference step of the second derivatives (m or rad)
STEP = 1e-3
#: task poses at which the second derivatives are taken at most (a farthest-point subset beyond)
MAX_POSES = 64


def pose_subset(joints: np.ndarray, n: int = MAX_POSES) -> np.ndarray:
    """Indices of at most ``n`` task configurations spread over the set: all of them when there are no
    more, else a farthest-point subset in joint space (started at the first, each next one the
    farthest from those taken).

    Parameters
    ----------
    joints : (m, n_variables) ndarray
        Joint values of the task poses (rad, m).
    n : int
        Largest subset.

    Returns
    -------
    (min(m, n),) ndarray of int
        Indices into ``joints``, sorted.
    """
    m = len(joints)
    if m <= n:
        return np.arange(m)
    Q = (joints - joints.mean(0)) / np.maximum(joints.std(0), 1e-12)
    take = [0]
    d = np.linalg.norm(Q - Q[0], axis=1)
    for _ in range(n - 1):
        i = int(np.argmax(d))
        take.append(i)
        d = np.minimum(d, np.linalg.norm(Q - Q[i], axis=1))
    return np.sort(np.array(take))


def _post_error(robot, idn, plan, comp, E) -> np.ndarray:
    """g(x) (n_task, m, 6) for source errors E (m, n_columns): linear fit, the controller's compensation."""
    Qc = idn.joints
    fc = robot.pose_error_at_joints(Qc, np.broadcast_to(E, (len(Qc),) + E.shape).copy())
    idx = np.concatenate([np.arange(6)[MEASURED[c]] for c in plan.measure])
    y = np.swapaxes(fc[:, :, idx], 0, 1).reshape(E.shape[0], -1) * idn.weights    # (m, n_rows) whitened
    Ehat = np.zeros_like(E)
    Ehat[:, idn.identified] = y @ idn.estimator.T
    return comp.residual(E, Ehat)


def second_order(robot, idn, plan, task_joints, step: float = STEP) -> np.ndarray:
    """Second derivatives ``H`` (n_task, 6, n, n) of the post-calibration error in every source.

    Parameters
    ----------
    robot : evotol.robots.mechanism.model.error_model.MechanismModel
        The uncalibrated model (nonlinear ``pose_error_at_joints``).
    idn : evotol.calibration.identification.Identification
        The identification (a described mechanism's, with joint values).

    Returns
    -------
    (n_task, 6, n, n) ndarray
        ``∂²g/∂x_j∂x_k`` (m or rad per unit² of source error), symmetric in the last two axes;
        central differences, whose stencils cancel the first-order part.
    """
    n = len(idn.source_names)
    pairs = [(j, k) for j in range(n) for k in range(j, n)]
    signs = np.array([(1, 1), (1, -1), (-1, 1), (-1, -1)], float) * step
    X = np.zeros((len(pairs), 4, n))
    for i, (j, k) in enumerate(pairs):
        X[i, :, j] += signs[:, 0]
        X[i, :, k] += signs[:, 1]
    g = _post_error(robot, idn, plan, Compensation(robot, task_joints), X.reshape(-1, n)).reshape(len(task_joints), len(pairs), 4, 6)
    h = (g[:, :, 0] - g[:, :, 1] - g[:, :, 2] + g[:, :, 3]) / (4 * step * step)      # (n_task, n_pairs, 6)
    H = np.zeros((len(task_joints), 6, n, n))
    jj, kk = np.array(pairs).T
    H[:, :, jj, kk] = np.swapaxes(h, 1, 2)
    H[:, :, kk, jj] = np.swapaxes(h, 1, 2)
    return H


def linear_range_bounds(robot, idn, plan, task_joints, requirement) -> np.ndarray:
    """``u_j`` (n,) of every source (module docstring); inf where a source has no second-order effect.

    Parameters
    ----------
    plan : evotol.calibration.plan.CalibrationPlan
        The plan (``linear_fraction``).
    requirement : evotol.core.requirement.Requirement
        Its position (m) and orientation (rad) bounds.

    Returns
    -------
    (n,) ndarray
        Upper bound per source (m or rad).
    """
    H = second_order(robot, idn, plan, task_joints[pose_subset(task_joints)])
    n = H.shape[-1]
    u = np.full(n, np.inf)
    for comp, rows in MEASURED.items():
        E = getattr(requirement, comp)
        if E is None:
            continue
        N = np.linalg.norm(H[:, rows], axis=1)                 # (n_task, n, n)
        r = N.sum(axis=2).max(axis=0)                          # (n,)
        with np.errstate(divide="ignore"):
            u = np.minimum(u, np.sqrt(2 * plan.linear_fraction * E / (n * r)))
    return u


def calibrated_upper_bounds(robot, idn, plan, task_joints, requirement) -> dict:
    """Upper bound of each source's tolerance after calibration (module docstring), and why.

    Parameters
    ----------
    plan : evotol.calibration.plan.CalibrationPlan
        The plan (``linear_fraction``, ``compensation_range``).
    task_joints : (n_task, n_variables) ndarray or None
        Joint values of the task poses; None (a model without joint maps): compensation range only.
    requirement : evotol.core.requirement.Requirement
        The requirement (its position and orientation bounds, m and rad).

    Returns
    -------
    dict of str to dict
        Source name -> ``{"linear_range": u_j or None (m or rad), "compensation_range": or None
        (identified sources), "bound": the smaller, or None, "identified": bool}``.
    """
    names = list(idn.source_names)
    lin = linear_range_bounds(robot, idn, plan, task_joints, requirement) if task_joints is not None else np.full(len(names), np.inf)
    ident = set(idn.identified)
    sources = set(robot.source_names)
    out = {}
    for j, n in enumerate(names):
        if n not in sources:       # a component of a disk or ball source: no bound of its own
            continue
        comp = [float(v) for p, v in dict(plan.compensation_range).items() if fnmatch.fnmatchcase(n, p)]
        c = min(comp) if comp and j in ident else None
        u = float(lin[j]) if np.isfinite(lin[j]) else None
        vals = [v for v in (u, c) if v is not None]
        out[n] = {"linear_range": u, "compensation_range": c, "bound": min(vals) if vals else None,
                  "identified": j in ident}
    return out


def noise_second_order(robot, idn, plan, task_joints, step: float = STEP) -> dict:
    """Second-order effect of the noise-driven identified values, at ``k`` sigma (m, rad).

    The noise moves the identified values by ``η ~ N(0, Σ_K)``; the controller compensates them on
    the nonlinear model, so beyond the linear noise term ``J_K η`` (in the noise covariance) there
    is ``½ Σ_jk Hc_jk η_j η_k``, ``Hc`` the second derivatives of the compensated error in the
    identified values (central differences of :meth:`Compensation.residual` with no true error).
    With ``|η_j| ≤ k σ_j`` it is at most ``½ Σ_jk |Hc_jk| k² σ_j σ_k``. An ill-conditioned plan
    (large ``σ_j``) makes it large.

    Parameters
    ----------
    idn : evotol.calibration.identification.Identification
        The identification (``sigma_K``).
    plan : evotol.calibration.plan.CalibrationPlan
        The plan (``k``).

    Returns
    -------
    dict of str to float
        ``"position"`` (m) and ``"orientation"`` (rad): the largest bound over the task poses.
    """
    K = idn.identified
    nK, n = len(K), len(idn.source_names)
    s = plan.k * np.sqrt(np.maximum(np.diag(idn.sigma_K), 0.0)) if nK else np.zeros(0)
    if not nK or not np.any(s > 0):
        return {"position": 0.0, "orientation": 0.0}
    task_joints = task_joints[pose_subset(task_joints)]
    comp = Compensation(robot, task_joints)
    pairs = [(j, k) for j in range(nK) for k in range(j, nK)]
    signs = np.array([(1, 1), (1, -1), (-1, 1), (-1, -1)], float) * step
    X = np.zeros((len(pairs), 4, n))
    for i, (j, k) in enumerate(pairs):
        X[i, :, K[j]] += signs[:, 0]
        X[i, :, K[k]] += signs[:, 1]
    X = X.reshape(-1, n)
    g = comp.residual(np.zeros_like(X), X).reshape(len(task_joints), len(pairs), 4, 6)
    h = (g[:, :, 0] - g[:, :, 1] - g[:, :, 2] + g[:, :, 3]) / (4 * step * step)
    out = {}
    for c, rows in MEASURED.items():
        N = np.linalg.norm(h[:, :, rows], axis=2)                         # (n_task, n_pairs)
        wgt = np.array([(1.0 if j == k else 2.0) * s[j] * s[k] for j, k in pairs])
        out[c] = float(0.5 * (N @ wgt).max())
    return out

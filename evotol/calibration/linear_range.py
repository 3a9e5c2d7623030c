"""How large a calibrated source may be: the identification's linear range and the controller's range.

After calibration an identified source has no first-order effect (its column of ``J M`` is zero),
so the first-order model would let its tolerance grow without bound. It may not: the allocation
is certified on the first-order model, which holds only while the terms it ignores are small.

Second-order terms. The post-calibration error of a robot with source errors ``x`` at a task pose is
``g(x)``: the nonlinear model's readings at the calibration configurations, the *iterated* fit
(:func:`iterated_fit`: Gauss-Newton iterations from the linear fit ``x̂_K = (B⁺)_K y`` -- the
identification the simulated calibration uses, :mod:`evotol.calibration.simulation`), and the
controller's compensation of ``x̂_K`` (:mod:`evotol.calibration.compensation`), the true model's error
after it. Its first-order part is ``J M x``; what the first-order model ignores is
``½ Σ_jk H_jk x_j x_k + O(|x|³)``. The second-order terms come from every source, not only the
identified ones: a source the fit absorbs into an identified one (a shift read as a joint offset)
makes the identified value, and the correction the controller applies, large -- its second-order
effect is what limits it. Where the identified model can reproduce the readings exactly (every
identifiable source identified) the iterated fit leaves no second-order term at all, where a
one-step linear fit leaves ``O(|x|²)`` (issue 44: that made the cap about 10x stricter than the
identification evotol simulates needs). ``H_jk`` is taken by central differences of ``g`` (step
``STEP``), whose stencils cancel the first-order part; entries below their round-off
``TOL / STEP²`` (the compensation's tolerance) are zero. With ``N_jk = |H_jk|`` (the norm of the
position, or orientation, rows) at each pose, the upper bounds

    u_j = sqrt(2 φ E / (n r_j)),     r_j = max over poses of Σ_k N_jk,

give ``|½ Σ_jk H_jk x_j x_k| ≤ ½ Σ_jk N_jk u_j u_k ≤ ½ Σ_j u_j² r_j ≤ φ E`` at every pose for every
``|x_j| ≤ u_j`` (``u_j u_k ≤ (u_j² + u_k²)/2``; n sources): the second-order terms stay below the
fraction ``φ`` (``plan.linear_fraction``) of the requirement ``E``. The second derivatives are
taken at every task pose up to ``MAX_POSES`` (64), beyond that at a farthest-point subset in joint
space (:func:`pose_subset`). A source with no second-order effect (``r_j = 0``) is bounded by the
user's upper bound only. The controller's compensation range (``plan.compensation_range``, by
source pattern) bounds an identified source's tolerance too.

Beyond second order. :func:`checked_range` runs the iterated fit on robots at the corners of the
final bounds (every order, and whether the fit converges) and, if the residual beyond first order
exceeds ``φ E`` or a fit does not converge, scales every bound down by a bisection. What the
requirement keeps for these terms (:func:`remainder_allowance`) is the larger of the proven
``max_poses ½ Σ_jk N_jk b_j b_k`` at the final bounds ``b`` and the largest value the check saw;
:func:`evotol.calibration.model.noise_allowance` takes it off the requirement.

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

from evotol.calibration.compensation import TOL, Compensation
from evotol.calibration.configurations import pose_error_of_robots
from evotol.calibration.identification import registration_columns
from evotol.calibration.plan import MEASURED

#: finite-difference step of the second derivatives (m or rad). Small, because every stencil point is an
#: iterated fit that must converge: at 1e-3 (1 mm, 1 mrad) 96 of the 1 200 stencil fits of a PUMA 560
#: calibrated over its workspace did not, and their differences put the caps at 1-4 um (cost 28.9
#: against 1.93 uncalibrated); at 1e-5, 1 198 of 1 200 converge and the caps come out at the scale the
#: corner check (checked_range) confirms. Round-off is TOL / STEP**2 = 1e-3 m per unit**2, far below the
#: second derivatives of an arm (~ its lengths, 0.1-1 m per rad**2).
STEP = 1e-5
#: task poses at which the second derivatives are taken at most (a farthest-point subset beyond)
MAX_POSES = 64
#: chord iterations of the iterated fit at most; the relative size of the update that stops them (round-off),
#: and the one below which a fit counts as converged
FIT_ITERATIONS, FIT_STOP, FIT_TOL = 20, 1e-15, 1e-9
#: robots at the corners of the bounds in the convergence check, and the halvings of its bisection
CHECK_ROBOTS, BISECTIONS = 16, 6


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


def fit_operator(robot, idn, plan) -> tuple[np.ndarray, np.ndarray | None]:
    """The whole linear fit ``B⁺`` (n_reg + n_K, n_rows) on whitened rows and the registration's columns.

    Returns
    -------
    Bp : (n_reg + n_K, n_rows) ndarray
        ``[δr̂; x̂_K] = B⁺ (w y)``, ``B = [R_kept, A_K]`` (identification module docstring).
    R : (n_rows, n_reg) ndarray or None
        The kept registration columns, whitened (None: a known instrument).
    """
    Qc = idn.joints
    mrows = np.concatenate([np.arange(6)[MEASURED[c]] for c in plan.measure])
    AK = robot.sensitivity_at_joints(Qc)[:, mrows][:, :, idn.identified].reshape(-1, len(idn.identified))
    R = None
    if idn.registration:
        Rg, rn = registration_columns(robot, plan, Qc)
        R = Rg[:, mrows][:, :, [rn.index(r) for r in idn.registration]].reshape(-1, len(idn.registration))
        R = R * idn.weights[:, None]
    AK = AK * idn.weights[:, None]
    return np.linalg.pinv(AK if R is None else np.column_stack([R, AK])), R


def iterated_fit(robot, idn, plan, Y, fit=None) -> tuple[np.ndarray, np.ndarray]:
    """Identified source errors (m, n_columns) from whitened readings ``Y`` (m, n_rows): the iterated fit.

    The simplified Gauss-Newton (chord) iteration ``z ← z + B⁺ (Y − f(z))`` from the linear fit
    ``z = B⁺ Y``, ``f`` the nonlinear model's whitened readings (plus ``R δr``), until the largest
    update is below ``FIT_STOP`` of the largest value, or below ``FIT_TOL`` and no longer shrinking
    tenfold (round-off), at most ``FIT_ITERATIONS`` times; a fit whose last update is above ``FIT_TOL``
    has not converged. Its fixed point
    satisfies ``B⁺ (Y − f(ẑ)) = 0``: where the identified model can reproduce the readings it does
    (``ẑ`` the exact least-squares solution), otherwise it differs from the nonlinear least-squares
    solution by third-order terms only (``A(ẑ) − A(0)`` and the misfit are both ``O(|x|)``, resp.
    ``O(|x|²)``), so the two share their first and second derivatives in the source errors.

    Parameters
    ----------
    Y : (m, n_rows) ndarray
        Whitened readings ``w y`` at the plan's configurations (configuration-major rows).
    fit : tuple, optional
        :func:`fit_operator`'s result, if already computed.

    Returns
    -------
    Ehat : (m, n_columns) ndarray
        Identified values in the identified columns, zero elsewhere (m or rad).
    converged : (m,) ndarray of bool
        Whether each robot's last update was below ``FIT_TOL`` of its largest value (and finite).
    """
    Bp, R = fit if fit is not None else fit_operator(robot, idn, plan)
    n_reg = 0 if R is None else R.shape[1]
    Qc, K = idn.joints, idn.identified
    mrows = np.concatenate([np.arange(6)[MEASURED[c]] for c in plan.measure])
    Ehat = np.zeros((len(Y), robot.n_columns))

    def readings(z):
        Ehat[:, K] = z[:, n_reg:]
        f = np.swapaxes(pose_error_of_robots(robot, Qc, Ehat)[:, :, mrows], 0, 1).reshape(len(Y), -1) * idn.weights
        return f + (z[:, :n_reg] @ R.T if n_reg else 0.0)

    z = Y @ Bp.T
    last = np.inf
    for _ in range(FIT_ITERATIONS):
        dz = (Y - readings(z)) @ Bp.T
        z = z + dz
        step = np.abs(dz).max(axis=1, initial=0.0) / np.maximum(np.abs(z).max(axis=1, initial=0.0), 1e-300)
        worst = step.max(initial=0.0)
        if worst <= FIT_STOP or (worst <= FIT_TOL and worst > 0.1 * last):     # converged, or stalled at round-off
            break
        last = worst
    Ehat[:, K] = z[:, n_reg:]
    return Ehat, (step <= FIT_TOL) & np.all(np.isfinite(z), axis=1)


def _post_error(robot, idn, plan, comp, E) -> np.ndarray:
    """g(x) (n_task, m, 6) for source errors E (m, n_columns): iterated fit, the controller's compensation."""
    mrows = np.concatenate([np.arange(6)[MEASURED[c]] for c in plan.measure])
    Y = np.swapaxes(pose_error_of_robots(robot, idn.joints, E)[:, :, mrows], 0, 1).reshape(E.shape[0], -1) * idn.weights
    return comp.residual(E, iterated_fit(robot, idn, plan, Y)[0])


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


def second_order_norms(robot, idn, plan, task_joints) -> dict:
    """``N_jk = |H_jk|`` per measured component at the task poses (a subset beyond ``MAX_POSES``).

    Entries below the round-off of the central differences, ``TOL / STEP²`` (the compensation's
    tolerance over the step squared: what four residuals each known to ``TOL`` can show), are zero.

    Returns
    -------
    dict of str to (n_task, n, n) ndarray
        ``"position"`` (m per unit²) and ``"orientation"`` (rad per unit²).
    """
    H = second_order(robot, idn, plan, task_joints[pose_subset(task_joints)])
    out = {}
    for comp, rows in MEASURED.items():
        N = np.linalg.norm(H[:, rows], axis=1)
        out[comp] = np.where(N > TOL / STEP ** 2, N, 0.0)
    return out


def linear_range_bounds(robot, idn, plan, task_joints, requirement, norms: dict | None = None) -> np.ndarray:
    """``u_j`` (n,) of every source (module docstring); inf where a source has no second-order effect.

    Parameters
    ----------
    plan : evotol.calibration.plan.CalibrationPlan
        The plan (``linear_fraction``).
    requirement : evotol.core.requirement.Requirement
        Its position (m) and orientation (rad) bounds.
    norms : dict, optional
        :func:`second_order_norms`, if already computed.

    Returns
    -------
    (n,) ndarray
        Upper bound per source (m or rad).
    """
    norms = second_order_norms(robot, idn, plan, task_joints) if norms is None else norms
    n = len(idn.source_names)
    u = np.full(n, np.inf)
    for comp, N in norms.items():
        E = getattr(requirement, comp)
        if E is None:
            continue
        r = N.sum(axis=2).max(axis=0)                          # (n,)
        with np.errstate(divide="ignore"):
            u = np.minimum(u, np.sqrt(2 * plan.linear_fraction * E / (n * r)))
    return u


def remainder_allowance(norms: dict, bounds) -> dict:
    """The second-order allowance ``max over poses ½ Σ_jk N_jk b_j b_k`` of sources within ``bounds`` (m, rad).

    It bounds ``|½ Σ_jk H_jk x_j x_k|`` for every ``|x_j| ≤ b_j``: what the first-order model leaves
    out at the final upper bounds (at most ``φ E`` when the linear-range bounds bind, less where the
    user's bounds are smaller); :func:`evotol.calibration.model.noise_allowance` takes it off the
    requirement.

    Parameters
    ----------
    norms : dict
        :func:`second_order_norms`.
    bounds : (n,) array_like
        Upper bound of every column (m or rad).

    Returns
    -------
    dict of str to float
        ``"position"`` (m) and ``"orientation"`` (rad).
    """
    b = np.asarray(bounds, float)
    return {c: float(0.5 * np.einsum("pjk,j,k->p", N, b, b).max(initial=0.0)) for c, N in norms.items()}


def calibrated_upper_bounds(robot, idn, plan, task_joints, requirement, norms: dict | None = None) -> dict:
    """Upper bound of each source's tolerance after calibration (module docstring), and why.

    Parameters
    ----------
    plan : evotol.calibration.plan.CalibrationPlan
        The plan (``linear_fraction``, ``compensation_range``).
    task_joints : (n_task, n_variables) ndarray or None
        Joint values of the task poses; None (a model without joint maps): compensation range only.
    requirement : evotol.core.requirement.Requirement
        The requirement (its position and orientation bounds, m and rad).
    norms : dict, optional
        :func:`second_order_norms`, if already computed.

    Returns
    -------
    dict of str to dict
        Source name -> ``{"linear_range": u_j or None (m or rad), "compensation_range": or None
        (identified sources), "bound": the smaller, or None, "identified": bool}``.
    """
    names = list(idn.source_names)
    lin = (linear_range_bounds(robot, idn, plan, task_joints, requirement, norms) if task_joints is not None
           else np.full(len(names), np.inf))
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


def checked_range(robot, idn, plan, task_joints, bounds, requirement, robots: int = CHECK_ROBOTS,
                  halvings: int = BISECTIONS, seed: int = 0) -> tuple[float, dict]:
    """The largest scale ``c`` in (0, 1] of ``bounds`` within which the iterated fit still does what the cap assumes.

    ``robots`` robots with errors at the corners ``x_j = ±c b_j`` (signs drawn with ``seed``, no
    noise) are read on the nonlinear model, identified by :func:`iterated_fit` and compensated; ``c``
    passes when every fit converges and the residual beyond the first-order prediction,
    ``max over poses |g(x) − J M x|``, stays within ``φ E`` for every constrained component (the
    linear range's promise, now with every order and the fit's convergence). ``c = 1`` is tried
    first, then a bisection on (0, 1) of ``halvings`` steps keeps the largest passing value.

    Parameters
    ----------
    bounds : (n,) array_like
        Upper bound of every column after the linear-range and the user's bounds (m or rad).
    requirement : evotol.core.requirement.Requirement
        The user's requirement (m, rad).
    robots : int
        Robots at the corners.
    halvings : int
        Bisection steps when ``c = 1`` fails.
    seed : int
        Seed of the corners' signs.

    Returns
    -------
    c : float
        The scale (1.0 when the bounds pass as they are).
    seen : dict of str to float
        The largest residual beyond first order at ``c`` over the robots and poses (m, rad).
    """
    b = np.asarray(bounds, float)
    rng = np.random.default_rng(seed)
    X = rng.choice([-1.0, 1.0], size=(robots, len(b))) * b
    mrows = np.concatenate([np.arange(6)[MEASURED[c]] for c in plan.measure])
    comp = Compensation(robot, task_joints)
    JM = robot.sensitivity_at_joints(task_joints) @ idn.M                                  # (n_task, 6, n)
    fit = fit_operator(robot, idn, plan)
    limits = {c: plan.linear_fraction * getattr(requirement, c) for c in MEASURED if getattr(requirement, c) is not None}

    def run(c):
        E = c * X
        Y = np.swapaxes(pose_error_of_robots(robot, idn.joints, E)[:, :, mrows], 0, 1).reshape(robots, -1) * idn.weights
        Ehat, ok = iterated_fit(robot, idn, plan, Y, fit)
        beyond = comp.residual(E, Ehat) - np.einsum("pij,sj->psi", JM, E)
        seen = {k: float(np.linalg.norm(beyond[:, :, MEASURED[k]], axis=2).max()) for k in limits}
        return bool(ok.all()) and all(np.isfinite(v) and v <= limits[k] for k, v in seen.items()), seen

    good, seen = run(1.0)
    if good:
        return 1.0, seen
    lo, hi, seen = 0.0, 1.0, {k: 0.0 for k in limits}
    for _ in range(halvings):
        mid = 0.5 * (lo + hi)
        passed, s_mid = run(mid)
        if passed:
            lo, seen = mid, s_mid
        else:
            hi = mid
    return lo, seen

"""The linear identification of a calibration plan: which sources it sees, and what it leaves.

Measurements. At the plan's configurations ``q_c`` the instrument reads the tool's position (and
orientation): ``y = A δp + R δr + ε``, with ``A`` (n_rows, n_columns) the measured rows of the
model's first-order map (:meth:`~evotol.robots.base.RobotErrorModel.sensitivity`) stacked over the
configurations, ``R`` the registration of an unknown instrument frame (base: 3 shifts and 3
rotations; target on the tool: 3 shifts, plus 3 rotations with orientation measured), and
``ε ~ N(0, diag σ²)`` the instrument noise. Rows are weighted by ``1/σ`` (weighted least squares,
the best linear unbiased estimator).

Identification. With ``B = [R_kept, A_K]`` (the kept registration columns and the identified
sources ``K``) the fit is ``[δr̂; δp̂_K] = B⁺ y``; the controller compensates ``δp̂_K``. At a task pose
with first-order map ``J`` the error after compensation is

    e = J δp − J_K δp̂_K = (J − J_K (B⁺)_K A) δp − J_K (B⁺)_K ε = J M δp + noise,

``M = I − E_K (B⁺)_K A`` (issue 36; ``E_K`` puts the K entries in place), and the noise term has the
covariance ``J_K Σ_K J_Kᵀ`` with ``Σ_K = (B⁺)_K (B⁺)_Kᵀ`` (weighted rows).

Base set. :func:`identify` takes the columns in a stated order (registration, then the sources
asked for -- with ``identify = "identifiable"`` the actuator offsets first, then every source in
model order) and keeps one when its unit-norm column has a residual above ``RTOL`` after
projection on the kept ones: a QR factorisation with the pivots in that order (Gram-Schmidt,
re-orthogonalised), rank-revealing because a column is dropped exactly when it lies in the span
of the kept ones. Each dropped source is reported with the kept columns it is a combination of
(and its residual), or as unseen (its column is zero: it moves no measured coordinate). The rank
reported is the number of identifiable directions: that of the seen columns (unit-normalised) from
their singular values (above 1e-9 of the largest), unseen columns left out; a
column whose residual lies between 1e-9 and ``RTOL`` counts in the rank but is not kept: its
identified value would carry the noise amplified by more than 1e6.
"""
from __future__ import annotations

import fnmatch
from dataclasses import dataclass, field

import numpy as np

from evotol.calibration.configurations import calibration_joints, calibration_poses
from evotol.calibration.plan import IDENTIFIABLE, MEASURED
from evotol._runtime.keyword_checks import did_you_mean
from evotol.errors import ValidationError

#: a unit column whose residual on the kept columns is below this is dependent on them (sin of the angle)
RTOL = 1e-6
REG_BASE = ("base.shift_x", "base.shift_y", "base.shift_z", "base.tilt_x", "base.tilt_y", "base.tilt_z")
REG_TOOL = ("target.shift_x", "target.shift_y", "target.shift_z", "target.tilt_x", "target.tilt_y", "target.tilt_z")


def _skew(p: np.ndarray) -> np.ndarray:
    """[p]x for p (n, 3): (n, 3, 3)."""
    z = np.zeros(len(p))
    return np.stack([np.stack([z, -p[:, 2], p[:, 1]], -1), np.stack([p[:, 2], z, -p[:, 0]], -1),
                     np.stack([-p[:, 1], p[:, 0], z], -1)], 1)


def measured_map(robot, plan):
    """(first-order map (n, 6, n_columns) at the calibration configurations, joints or None, poses or None).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The error model.

    Returns
    -------
    S : (n, 6, n_columns) ndarray
        ``[dp (m); dphi (rad)]`` per unit source error at each configuration.
    joints : (n, n_variables) ndarray or None
        The configurations' joint values (rad, m), for a described mechanism.
    poses : (n, dim) ndarray or None
        The configurations' workspace poses, for a model without joint maps.

    Raises
    ------
    evotol.errors.ValidationError
        What :func:`evotol.calibration.configurations.calibration_joints` refuses.
    """
    Q = calibration_joints(robot, plan)
    if Q is None:
        P = calibration_poses(robot, plan)
        return np.asarray(robot.sensitivity(P), float), None, P
    return np.asarray(robot.sensitivity_at_joints(Q), float), Q, None


def registration_columns(robot, plan, joints) -> tuple[np.ndarray, list[str]]:
    """First-order effect (n, 6, n_reg) of the instrument's registration on the readings, and its names.

    Parameters
    ----------
    robot : evotol.robots.mechanism.model.error_model.MechanismModel
        A described mechanism (its tip frame at the configurations).
    plan : evotol.calibration.plan.CalibrationPlan
        The plan (``measure`` decides whether the target's rotation is registered).
    joints : (n, n_variables) ndarray
        The calibration configurations (rad, m).

    Returns
    -------
    R : (n, 6, n_reg) ndarray
        Per unit registration error (m, rad): the base frame's shifts and small rotations, then the
        target's shifts (and rotations) in the tip frame.
    names : list of str
        ``base.shift_x`` ... ``target.shift_z`` (``target.tilt_*`` with orientation measured).

    Raises
    ------
    evotol.errors.ValidationError
        A model without joint maps (its tip frame is not known).
    """
    if joints is None:
        raise ValidationError("calibration.instrument", "unknown", "a described mechanism (the registration needs "
                              "the tip frame at each configuration); or instrument = 'known'")
    kin = robot.kin
    n = len(joints)
    st = kin.state({v: joints[:, i] for i, v in enumerate(kin.variables)}, n, twists=False)
    T = np.asarray(st.world[robot.mechanism.end_effector], float).reshape(n, 4, 4)
    p, Rt = T[:, :3, 3], T[:, :3, :3]
    eye = np.broadcast_to(np.eye(3), (n, 3, 3))
    zero = np.zeros((n, 3, 3))
    cols = [np.concatenate([eye, zero], 1), np.concatenate([-_skew(p), eye], 1), np.concatenate([Rt, zero], 1)]
    names = list(REG_BASE) + list(REG_TOOL[:3])
    if "orientation" in plan.measure:
        cols.append(np.concatenate([zero, Rt], 1))
        names += list(REG_TOOL[3:])
    R = np.concatenate(cols, 2)
    if robot.mechanism.planar:
        R = robot._planar(R)
    return R, names


def _rows(S: np.ndarray, plan) -> np.ndarray:
    """Measured rows of (n, 6, m) stacked configuration-major: (n * rows, m)."""
    idx = np.concatenate([np.arange(6)[MEASURED[c]] for c in plan.measure])
    return S[:, idx, :].reshape(-1, S.shape[-1])


def _select(Z: np.ndarray, order: list[int], rtol: float = RTOL):
    """Greedy QR in the given pivot order: (kept, dependent {j: (residual, coefficients over kept)}, unseen)."""
    norms = np.linalg.norm(Z, axis=0)
    scale = norms.max() if norms.size else 0.0
    basis = np.zeros((Z.shape[0], 0))
    kept, dependent, unseen = [], {}, []
    for j in order:
        if norms[j] <= 1e-12 * max(scale, 1e-300):
            unseen.append(j)
            continue
        v = Z[:, j] / norms[j]
        r = v - basis @ (basis.T @ v)
        r = r - basis @ (basis.T @ r)
        res = float(np.linalg.norm(r))
        if res > rtol:
            kept.append(j)
            basis = np.column_stack([basis, r / res])
        else:
            U = Z[:, kept] / norms[kept]
            coef = np.linalg.lstsq(U, v, rcond=None)[0] if kept else np.zeros(0)
            dependent[j] = (res, coef)
    return kept, dependent, unseen


def _combination(coef, kept, labels, top: int = 3) -> str:
    order = np.argsort(-np.abs(coef))[:top]
    terms = [f"{coef[i]:+.3g} {labels[kept[i]]}" for i in order if abs(coef[i]) > 1e-3 * np.abs(coef).max()]
    return " ".join(terms) + (" ..." if np.sum(np.abs(coef) > 1e-3 * np.abs(coef).max()) > top else "")


@dataclass
class Identification:
    """What a plan identifies and what it leaves (module docstring), SI.

    Parameters
    ----------
    source_names : list of str
        One label per column of the model's map: the source's name, ``name[k]`` for the k-th
        component of a disk or ball source (only interval sources are identified).
    identified : list of int
        Column indices ``K`` of the identified (compensated) sources.
    registration : list of str
        The registration parameters kept (an unknown instrument frame), else empty.
    M : (n_columns, n_columns) ndarray
        Post-calibration map: the error after compensation is ``J M δp`` (first order).
    sigma_K : (n_K, n_K) ndarray
        Covariance of the identified parameters from the instrument noise (m², rad²).
    condition : float
        Condition number of ``[R_kept, A_K]`` with unit-norm columns (dimensionless).
    rank : int
        Rank of all the measured columns (sources and registration), from their singular values.
    n_measurements : int
        Measured coordinates (configurations x rows).
    dropped : dict of str to str
        Source (or registration) name -> why the base set does not hold it.
    unseen : list of str
        Sources that move no measured coordinate at any configuration.
    joints : ndarray or None
        The calibration configurations (rad, m), for a described mechanism.
    poses : ndarray or None
        The calibration poses (SI), for a model without joint maps.
    estimator : (n_K, n_measurements) ndarray or None
        ``(B⁺)_K``: the identified values from the weighted readings ``w y`` (m or rad per unit).
    weights : (n_measurements,) ndarray or None
        ``1/σ`` of each measured row (1/m, 1/rad), or ones for a noiseless plan.
    """

    source_names: list
    identified: list
    registration: list
    M: np.ndarray
    sigma_K: np.ndarray
    condition: float
    rank: int
    n_measurements: int
    dropped: dict = field(default_factory=dict)
    unseen: list = field(default_factory=list)
    joints: np.ndarray | None = None
    poses: np.ndarray | None = None
    estimator: np.ndarray | None = None
    weights: np.ndarray | None = None

    @property
    def identified_names(self) -> list[str]:
        """Names of the identified sources, in model order."""
        return [self.source_names[j] for j in self.identified]

    def to_dict(self) -> dict:
        """The identification as plain data (JSON): names, counts, condition number, why sources were dropped.

        Returns
        -------
        dict
            ``identified``, ``registration``, ``n_identified``, ``rank``, ``n_measurements``,
            ``condition_number``, ``dropped`` (name -> reason), ``unseen``, ``n_configurations``.
        """
        n_conf = len(self.joints) if self.joints is not None else len(self.poses)
        return {"identified": self.identified_names, "registration": list(self.registration),
                "n_identified": len(self.identified), "rank": int(self.rank), "n_measurements": int(self.n_measurements),
                "condition_number": float(self.condition), "dropped": dict(self.dropped), "unseen": list(self.unseen),
                "n_configurations": int(n_conf)}


def identify(robot, plan) -> Identification:
    """The plan's identification of the robot's sources (module docstring): base set, ``M``, noise.

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The (uncalibrated) error model.

    Returns
    -------
    Identification
        The identified sources, the post-calibration map and the noise covariance.

    Raises
    ------
    evotol.errors.ValidationError
        Before any fit: a pattern that matches no source, an identified source that is not an
        interval, fewer measurements than identified parameters, identified sources that the plan
        cannot tell apart (names them and what they are a combination of), a noise that is zero on
        some axes and not on others; and what the configurations refuse.
    """
    names = list(robot.source_names)
    S, Q, P = measured_map(robot, plan)
    A = _rows(S, plan)
    n_rows = A.shape[0]
    sig = plan.sigma_rows(len(S))
    if np.any(sig > 0) and np.any(sig == 0):
        raise ValidationError("calibration.noise", {c: v.tolist() for c, v in plan.noise.items()},
                              "standard deviations > 0 on every measured axis (or 0 on all, a noiseless study)")
    w = 1.0 / sig if np.all(sig > 0) else np.ones(n_rows)
    cols = [s.dim for s in robot.sources]
    if plan.instrument == "unknown":
        Rg, reg_names = registration_columns(robot, plan, Q)
        Rr = _rows(Rg, plan)
    else:
        Rr, reg_names = np.zeros((n_rows, 0)), []
    start = np.concatenate([[0], np.cumsum(cols)[:-1]]).astype(int)        # first column of each source
    colnames = [n if d == 1 else f"{n}[{k}]" for n, d in zip(names, cols) for k in range(d)]
    interval = [int(start[j]) for j, d in enumerate(cols) if d == 1]       # only intervals are identified
    if plan.identify == IDENTIFIABLE:
        actuator = [int(start[j]) for j, d in enumerate(cols) if d == 1 and robot.sources[j].group == "actuator"]
        candidates = actuator + [c for c in interval if c not in actuator]
    else:
        candidates = []
        for pat in plan.identify:
            hit = [j for j, n in enumerate(names) if fnmatch.fnmatchcase(n, pat)]
            if not hit:
                raise ValidationError("calibration.identify", pat, f"a pattern matching a source of {robot.name}"
                                      + did_you_mean(pat, names))
            shaped = [names[j] for j in hit if cols[j] != 1]
            if shaped:
                raise ValidationError("calibration.identify", shaped[0], "interval sources (a clearance disk or ball "
                                      "is not identified by a geometric calibration)")
            candidates += [int(start[j]) for j in hit if int(start[j]) not in candidates]
        candidates.sort()
    names = colnames
    n_reg = len(reg_names)
    Z = np.column_stack([Rr, A]) * w[:, None]
    order = list(range(n_reg)) + [n_reg + j for j in candidates]
    labels = [f"registration {r}" for r in reg_names] + names
    kept, dependent, unseen = _select(Z, order)
    if plan.identify != IDENTIFIABLE:
        n_params = n_reg + len(candidates)
        if n_rows < len([k for k in kept if k < n_reg]) + len(candidates):
            raise ValidationError("calibration.configurations", n_rows,
                                  f"at least {n_params} measured coordinates for {len(candidates)} identified sources"
                                  f"{f' and {n_reg} registration parameters' if n_reg else ''} (fewer measurements "
                                  "than identified parameters)")
        bad = [j - n_reg for j in order[n_reg:] if j not in kept]
        if bad:
            why = "; ".join(f"{names[j]} " + ("moves no measured coordinate" if j + n_reg in unseen else
                            "= " + _combination(dependent[j + n_reg][1], kept, labels)) for j in bad[:3])
            raise ValidationError("calibration.identify", [names[j] for j in bad],
                                  f"sources this plan can identify; not identifiable: {why}"
                                  + (f" (+{len(bad) - 3} more)" if len(bad) > 3 else ""))
    elif n_rows < len(kept):
        raise ValidationError("calibration.configurations", n_rows, f"at least {len(kept)} measured coordinates")
    K = sorted(j - n_reg for j in kept if j >= n_reg)
    regk = [j for j in kept if j < n_reg]
    B = Z[:, regk + [n_reg + j for j in K]]
    Bn = B / np.linalg.norm(B, axis=0)
    s = np.linalg.svd(Bn, compute_uv=False)
    cond = float(s[0] / s[-1]) if s.size else 1.0
    Pinv = np.linalg.pinv(B)[len(regk):]                   # (n_K, n_rows), whitened rows
    Aw = A * w[:, None]
    M = np.eye(A.shape[1])
    M[K] -= Pinv @ Aw
    sigma_K = Pinv @ Pinv.T if np.all(sig > 0) else np.zeros((len(K), len(K)))
    zn = np.linalg.norm(Z, axis=0)
    Zs = Z[:, zn > 1e-12 * max(zn.max(initial=0.0), 1e-300)]    # _select's unseen test: a zero column is no direction
    sv = np.linalg.svd(Zs / np.linalg.norm(Zs, axis=0), compute_uv=False) if Zs.size else np.zeros(0)
    rank = int((sv > 1e-9 * sv[0]).sum()) if sv.size else 0
    dropped = {}
    for j, (res, coef) in dependent.items():
        dropped[labels[j]] = (f"not identifiable apart from {_combination(coef, kept, labels)} (residual {res:.1g} "
                              f"of its unit column, below {RTOL:g})")
    for j in unseen:
        dropped[labels[j]] = "moves no measured coordinate at any calibration configuration"
    return Identification(names, K, [reg_names[j] for j in regk], M, sigma_K, cond, rank, n_rows, dropped,
                          [labels[j] for j in unseen if j >= n_reg], Q, P, estimator=Pinv, weights=w)

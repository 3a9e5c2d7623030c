"""The ISO 9283 figures of a mechanism (serial or closed-loop) with systematic and random sources: predicted
(first order) and a simulated ISO 9283 test on the nonlinear model (docs/iso9283.md).

Parameters
----------
robot : evotol.robots.mechanism.model.error_model.MechanismModel
    The mechanism (its workspace has coordinates x, y, z; its sources are the systematic columns).
positions : (p, 3) array_like
    Commanded positions (m), e.g. :func:`evotol.measures.iso9283.poses.iso_positions`.
systematic : (n_columns,) array_like
    Tolerance ``t_i`` of each column of the model (m or rad; errors uniform in ``±t_i``; 0: none).
sources : sequence of evotol.robots.mechanism.model.random_sources.RandomSource
    The random sources (their ``tolerance`` is used unless ``random_t`` is given).
random_t : (n_random,) array_like or None
    Tolerances of the random sources overriding theirs (SI).
S : (p, 6, n_columns) ndarray
    The first-order map at the positions (:func:`joints_and_maps`).
direction : (3,) array_like
    A unit approach motion of the tool (base frame).
loadings : list of ndarray
    :func:`evotol.robots.mechanism.model.random_sources.column_loading` of the sources.
t : (n_random,) ndarray
    Tolerances of the random sources (SI).
signs : list of dict
    Per pose, the approach sign of each joint (:func:`approach_signs`).
"""
from __future__ import annotations

import numpy as np
from scipy.stats import binom

from evotol.errors import ValidationError
from evotol.measures.iso9283.figures import (ap_at_yield, ap_worst_case, cycle_errors_linear, figures_of_test, gaussian_rp,
                                    orientation_figures_of_test, rp_from_errors, worst_direction)
from evotol.measures.iso9283.poses import full_poses
from evotol.robots.mechanism.model.random_sources import backlash_offset, column_loading, cycle_errors, unit_draws

#: approach motions (unit, base frame): the unidirectional test approaches moving down; the
#: multi-directional test adds motions along +x and +y (ISO 9283 approaches parallel to the base axes)
APPROACHES = {"-z": (0.0, 0.0, -1.0), "+x": (1.0, 0.0, 0.0), "+y": (0.0, 1.0, 0.0)}


def joints_and_maps(robot, positions):
    """Joint values and the first-order map at commanded positions.

    Returns
    -------
    q : dict of str to (p,) ndarray
        Every joint variable (rad, m).
    S : (p, 6, n_columns) ndarray
        The first-order map ``[dp; dphi]`` per unit of each column.
    """
    q = robot.joint_values(full_poses(robot, np.asarray(positions, float)))
    return q, robot.sensitivity_at_joints(q)


def approach_signs(robot, S, direction) -> list[dict]:
    """Per pose, the sign of each actuated joint's motion when the tool approaches moving along
    ``direction`` at constant orientation: ``sign(J_q⁺ [d; 0])``; 0 for a joint that does not move
    (``|dq| ≤ 1e-9 max |dq|``): its lost motion is not taken up and may sit anywhere in ``±b'/2``.

    Returns
    -------
    list of dict
        Per pose, actuated joint -> -1.0, 0.0 or 1.0.
    """
    names = list(robot.source_names)
    act = [j for j in robot.kin.actuated if j in names]
    Jq = S[:, :, [names.index(j) for j in act]]
    rhs = np.concatenate([np.asarray(direction, float), np.zeros(3)])
    out = []
    for i in range(len(S)):
        dq = np.linalg.lstsq(Jq[i], rhs, rcond=None)[0]
        out.append(dict(zip(act, np.where(np.abs(dq) > 1e-9 * np.abs(dq).max(), np.sign(dq), 0.0))))
    return out


def _tols(sources, random_t):
    t = np.array([s.tolerance for s in sources] if random_t is None else random_t, float)
    if len(t) != len(sources):
        raise ValidationError("random tolerances", len(t), f"{len(sources)} values, one per random source")
    return t


def lost_motion_columns(sources, loadings, t, signs) -> tuple[np.ndarray, np.ndarray]:
    """Per pose (p, n_columns): the lost-motion offsets ``−s b/2`` at full lost motion, and the
    half-range ``b/2`` of the lost motion of joints the approach does not move (``s = 0``).

    Returns
    -------
    lm, free : (p, n_columns) ndarray
        Offsets and half-ranges (rad).
    """
    lm = np.array([backlash_offset(sources, loadings, t, sg) for sg in signs])
    free = np.array([backlash_offset(sources, loadings, t, {j: -1.0 if v == 0 else 0.0 for j, v in sg.items()})
                     for sg in signs])
    return lm, free


def lost_motion_parts(robot, S, sources, loadings) -> tuple[np.ndarray, np.ndarray]:
    """The lost motion's share of the column box per unit random tolerance (unidirectional test).

    Returns
    -------
    C, H : (p, n_columns, n_random) ndarray
        Centre and extra half-width of the box of column errors per unit of each random tolerance
        (zero but for backlash: ``−s/4`` and ``1/4``, or ``0`` and ``1/2`` for a joint that does not move).
    """
    signs = approach_signs(robot, S, APPROACHES["-z"])
    K, p, m = len(sources), len(S), S.shape[2]
    C, H = np.zeros((p, m, K)), np.zeros((p, m, K))
    for k in range(K):
        e = np.zeros(K)
        e[k] = 1.0
        lm, free = lost_motion_columns(sources, loadings, e, signs)
        C[:, :, k], H[:, :, k] = lm / 2, np.abs(lm) / 2 + np.abs(free)
    return C, H


def rp_unit_errors(robot, S, sources, n_samples: int, seed: int = 0) -> np.ndarray:
    """Per random source, the first-order position errors of ``n_samples`` cycle draws at unit tolerance,
    centred on their mean: the fixed draws (common random numbers) on which RP is allocated.

    Parameters
    ----------
    n_samples : int
        Cycle draws.
    seed : int
        Seed of the draws.

    Returns
    -------
    (p, n_samples, 3, n_random) ndarray
        m per unit tolerance.
    """
    J = S[:, :3]
    draws = unit_draws(sources, n_samples, np.random.default_rng(seed))
    E = np.stack([np.einsum("pim,nm->pni", J, d @ G.T) for G, d in zip(column_loading(robot, sources), draws)], axis=-1)
    return E - E.mean(axis=1, keepdims=True)


def rp_value(E, t) -> np.ndarray:
    """RP ``= E l + 3 std l`` of the errors ``E t`` at each pose, as :func:`rp_with_gradient` computes it (the same
    values), without the gradient.

    Parameters
    ----------
    E, t
        As :func:`rp_with_gradient`: the unit errors and the random tolerances (SI).

    Returns
    -------
    (p,) ndarray
        m.
    """
    l = np.linalg.norm(E @ t, axis=-1)
    return l.mean(1) + 3 * l.std(1, ddof=1)


def rp_with_gradient(E, t) -> tuple[np.ndarray, np.ndarray]:
    """RP ``= E l + 3 std l`` (the mean over the draws, ``std`` with ``n − 1``) of the errors ``E t`` at each
    pose, and its gradient with respect to the tolerances (smooth on fixed draws).

    Parameters
    ----------
    E : (p, n, 3, n_random) ndarray
        :func:`rp_unit_errors`.

    Returns
    -------
    rp : (p,) ndarray
        m.
    grad : (p, n_random) ndarray
        m per unit tolerance.
    """
    e = E @ t                                                            # (p, n, 3)
    l = np.linalg.norm(e, axis=-1)
    dl = np.einsum("pni,pnik->pnk", e / np.maximum(l, 1e-300)[..., None], E)
    lm, sd = l.mean(1), l.std(1, ddof=1)
    dsd = np.einsum("pn,pnk->pk", l - lm[:, None], dl - dl.mean(1, keepdims=True)) / ((l.shape[1] - 1) * sd[:, None])
    return lm + 3 * sd, dl.mean(1) + 3 * dsd


def source_shares(robot, positions, systematic, sources, random_t=None) -> dict:
    """What each source takes of AP and of RP at the pose where each is largest (first order).

    AP: at the worst direction ``u*`` (:func:`worst_direction`), source ``i``'s term of ``h_K(u*)``
    over ``h_K(u*)`` (systematic ``t_i |u*·J_i|``; backlash its offset and range terms). RP: each random
    source's share of the variance ``E|e|²`` (its terms add up to 1).

    Returns
    -------
    dict
        ``AP`` and ``RP``: ``{source name: share}``, and ``AP_pose``/``RP_pose`` the pose indices.
    """
    _, S = joints_and_maps(robot, positions)
    J = S[:, :3]
    loadings, t = column_loading(robot, sources), _tols(sources, random_t)
    ts = np.asarray(systematic, float)
    C, H = lost_motion_parts(robot, S, sources, loadings)
    h_all = []
    for i in range(len(J)):
        c, h = C[i] @ t, ts + H[i] @ t
        a = worst_direction(J[i], c, h) @ J[i]
        h_all.append((a @ c + np.abs(a) @ h, a))
    i_ap = int(np.argmax([v for v, _ in h_all]))
    val, a = h_all[i_ap]
    ap = {n: float(ti * abs(ai) / val) for n, ti, ai in zip(robot.source_names, ts, a)}
    for s, k in zip(sources, range(len(sources))):
        if s.kind == "backlash":
            ap[s.name] = float((a @ C[i_ap, :, k] + np.abs(a) @ H[i_ap, :, k]) * t[k] / val)
    var = _unit_variances(sources)
    v = np.array([[tk * tk * np.sum((Ji @ G) ** 2 * vk) for G, tk, vk in zip(loadings, t, var)] for Ji in J])
    i_rp = int(np.argmax(v.sum(1))) if len(sources) else 0
    rp = {s.name: float(x) for s, x in zip(sources, v[i_rp] / max(v[i_rp].sum(), 1e-300))} if len(sources) else {}
    return {"AP": ap, "RP": rp, "AP_pose": i_ap, "RP_pose": i_rp}


def predict(robot, positions, systematic, sources, random_t=None, yield_=None, n_samples=200000, seed=0) -> dict:
    """Predicted AP and RP at each position, first order (module :mod:`evotol.measures.iso9283.figures`).

    Parameters
    ----------
    yield_ : float or None
        None: AP is the worst case over the tolerance box (attained value and proven bound);
        a share in (0, 1): AP at that yield (sampled robots).
    n_samples : int
        Cycle draws for RP (and robots for AP at a yield).
    seed : int or None
        Seed of the draws.

    Returns
    -------
    dict
        ``AP`` (p,), ``AP_bound`` (p,) (worst case only, else equal to ``AP``), ``RP`` (p,),
        ``RP_gaussian`` (p,) (the Gaussian shortcut, for comparison), all m; ``signs`` the approach
        signs per pose.
    """
    q, S = joints_and_maps(robot, positions)
    J = S[:, :3]
    loadings, t = column_loading(robot, sources), _tols(sources, random_t)
    signs = approach_signs(robot, S, APPROACHES["-z"])
    lm, free = lost_motion_columns(sources, loadings, t, signs)
    ts = np.asarray(systematic, float)
    ap, bound = np.empty(len(J)), np.empty(len(J))
    for i in range(len(J)):
        if yield_ is None:
            a, b = ap_worst_case(J[i:i + 1], lm[i] / 2, ts + np.abs(lm[i]) / 2 + np.abs(free[i]))
        else:
            a = b = ap_at_yield(J[i:i + 1], ts, lm[i], free[i], yield_, min(n_samples, 50000), seed)
        ap[i], bound[i] = a[0], b[0]
    rp = np.zeros(len(J))
    rp_gauss = np.zeros(len(J))
    if sources:
        draws = unit_draws(sources, n_samples, np.random.default_rng(seed))
        rp = rp_from_errors(cycle_errors_linear(J, loadings, t, draws))
        rp_gauss = gaussian_rp(J, loadings, t, _unit_variances(sources), n_samples, seed)
    return {"AP": ap, "AP_bound": bound, "RP": rp, "RP_gaussian": rp_gauss, "signs": signs}


def _unit_variances(sources) -> list:
    """Variance of each source's unit draw per component (:func:`unit_draws`)."""
    return [np.full(s.dim, 1 / 16) if s.kind == "radial_play" else
            np.array([(s.variation if s.kind == "backlash" else 1.0) ** 2 / 12]) for s in sources]


def predict_orientation(robot, positions, systematic, sources, random_t=None) -> dict:
    """Predicted orientation AP and RP per angle (ISO 9283 §7.2; rotations about the base axes x, y, z), first order.

    With ``r`` the row of the first-order map of one angle at a pose, a robot's mean angle error over the
    cycles is ``r (δ + o)`` (systematic errors in ``±t``, the lost motion's offset ``o``): its worst case is
    exact, ``|r·c| + Σ_i |r_i| h_i`` over the box of centre ``c`` and half-widths ``h`` (one linear function
    over a box). ``RP_a = 3 S_a`` tends to ``3 sqrt(Σ_k t_k² Σ_j (r G_k)_j² var_kj)`` for many cycles: exact
    for the variance of the linearised random sources, whatever their distribution.

    Returns
    -------
    dict
        ``AP`` and ``RP`` (p, 3): per pose the worst ``|ā − a_c|`` and ``3 S_a`` for a, b, c (rad).
    """
    _, S = joints_and_maps(robot, positions)
    R = S[:, 3:]
    loadings, t = column_loading(robot, sources), _tols(sources, random_t)
    lm, free = lost_motion_columns(sources, loadings, t, approach_signs(robot, S, APPROACHES["-z"])) if sources else \
        (np.zeros((len(S), S.shape[2])), np.zeros((len(S), S.shape[2])))
    h = np.asarray(systematic, float)[None] + np.abs(lm) / 2 + np.abs(free)                  # (p, m)
    ap = np.abs(np.einsum("pam,pm->pa", R, lm / 2)) + np.einsum("pam,pm->pa", np.abs(R), h)
    var = orientation_variance_weights(R, loadings, sources) @ (t * t) if sources else np.zeros_like(ap)
    return {"AP": ap, "RP": 3 * np.sqrt(var)}


def orientation_variance_weights(R, loadings, sources) -> np.ndarray:
    """Variance of each orientation angle per unit squared tolerance of each random source, first order:
    ``w_pak = Σ_j (r_pa G_k)_j² var_kj`` so that ``S_a² = Σ_k τ_k² w_pak`` (ISO 9283 §7.2; RP_a = 3 S_a).

    Parameters
    ----------
    R : (p, 3, n_columns) ndarray
        Orientation rows of the first-order map (rad per m or rad).

    Returns
    -------
    (p, 3, n_random) ndarray
        rad² per unit².
    """
    return np.stack([np.einsum("pam,mj->paj", R, G) ** 2 @ v for G, v in zip(loadings, _unit_variances(sources))], axis=-1)


def simulate(robot, positions, systematic, sources, random_t=None, n_robots=200, n_cycles=30,
             approaches=("-z",), seed=0) -> dict:
    """A simulated ISO 9283 test on the nonlinear model (``robot.pose_error_at_joints``).

    Each robot draws its systematic errors uniformly within ``±t`` and its as-built lost motion
    ``b' ~ U(0, b)`` once (a joint the approach does not move sits at ``U(±b'/2)``, once per robot and
    pose); each cycle draws the random sources anew. Per robot, pose and approach the
    standard's formulas give AP and RP (:func:`figures_of_test`); with several approaches, vAP.

    Parameters
    ----------
    n_robots : int
        Robots built within the tolerances.
    n_cycles : int
        Cycles per pose (ISO 9283: 30).
    approaches : sequence of str
        Keys of :data:`APPROACHES`; the first is the unidirectional test.
    seed : int or None
        Seed of the draws.

    Returns
    -------
    dict
        ``AP`` and ``RP`` (n_robots, p) of the first approach (m); ``vAP`` (n_robots, p) or None.

    Raises
    ------
    evotol.errors.ValidationError
        Fewer than 2 cycles or 1 robot, or an unknown approach.
    """
    if n_cycles < 2 or n_robots < 1:
        raise ValidationError("iso9283 simulation", (n_robots, n_cycles), "at least 1 robot and 2 cycles")
    bad = [a for a in approaches if a not in APPROACHES]
    if bad:
        raise ValidationError("iso9283 approach", bad[0], f"one of {tuple(APPROACHES)}")
    rng = np.random.default_rng(seed)
    P = np.asarray(positions, float)
    q, S = joints_and_maps(robot, P)
    loadings, t = column_loading(robot, sources), _tols(sources, random_t)
    ts = np.asarray(systematic, float)
    m, p, N = len(ts), len(P), n_robots * n_cycles
    delta = ts * rng.uniform(-1, 1, (n_robots, m))
    share = rng.random((n_robots, m))                                       # as-built lost motion b'/b
    bary = []
    for k, a in enumerate(approaches):
        lm, free = lost_motion_columns(sources, loadings, t, approach_signs(robot, S, APPROACHES[a]))   # (p, m)
        cyc = cycle_errors(loadings, t, unit_draws(sources, p * N, rng)).reshape(p, N, m) if sources else 0.0
        side = share * np.abs(free[:, None, :]) * rng.uniform(-1, 1, (p, n_robots, m))   # lost motion not taken up
        err = (delta + share * lm[:, None, :] + side).repeat(n_cycles, axis=1) + cyc           # (p, N, m)
        e6 = robot.pose_error_at_joints(q, err).reshape(p, n_robots, n_cycles, 6)
        e = e6[..., :3]
        f = figures_of_test(e + P[:, None, None, :], P[:, None, :])
        if k == 0:
            first, orient = f, orientation_figures_of_test(e6[..., 3:])
        bary.append(f["barycentre"])
    vap = None
    if len(bary) > 1:
        B = np.stack(bary)                                                   # (k, p, R, 3)
        vap = np.max(np.linalg.norm(B[:, None] - B[None], axis=-1), axis=(0, 1)).T
    return {"AP": first["AP"].T, "RP": first["RP"].T, "vAP": vap,
            "AP_abc": np.swapaxes(orient["AP"], 0, 1), "RP_abc": np.swapaxes(orient["RP"], 0, 1)}


def quantile_interval(x, y: float, level: float = 0.95):
    """The sample ``y`` quantile of x and its distribution-free ``level`` confidence interval from
    order statistics (binomial ranks); an end the sample cannot give is None.

    Parameters
    ----------
    x : (n,) array_like
        The sample.
    y : float
        Quantile in (0, 1]; 1: the sample maximum (its interval has no upper end).
    level : float
        Confidence level.

    Returns
    -------
    tuple
        (estimate, (low, high)).
    """
    s = np.sort(np.asarray(x, float))
    n = len(s)
    est = float(s[min(int(np.ceil(y * n)) - 1, n - 1)])
    lo = int(binom.ppf((1 - level) / 2, n, y))
    hi = int(binom.ppf((1 + level) / 2, n, y)) + 1
    return est, (float(s[lo - 1]) if lo >= 1 else None, float(s[hi - 1]) if hi <= n else None)

"""Random link lengths, actuator errors and joint clearances of the 5R mechanism, sampled by plain
Monte Carlo or Latin hypercube and propagated through the exact kinematics
(Lara-Molina et al. 2019, Secs. 2.2 and 2.5, Table 1).

Random variables (one row of the unit hypercube per sample, ``n_dims`` columns):

* link lengths, eq. 7: ``r_bar_i(Omega) = r_bar_i (1 + delta_r xi)``, ``xi ~ N(0, 1)``,
  ``delta_r = 0.004 %`` (Table 1). The paper has one random length per symmetric pair
  (``shared_lengths=True``: 3 columns r1, r2, r3); ``shared_lengths=False`` draws the six
  lengths ``A_1B_1, A_2B_2, B_1P, B_2P, OA_1, OA_2`` independently (6 columns). With
  ``renormalise=True`` the lengths are divided by the random ``D(Omega)`` as the paper does
  (``r_i(Omega) = r_bar_i(Omega) / D(Omega)``, Sec. 2.2), which removes their common scale;
* actuator angle errors, eqs. 8 / 23: ``dtheta_j = delta_theta xi``, ``delta_theta = 0.05 deg``;
* joint clearances at ``A_1, A_2, B_1, B_2`` in the contact mode (Sec. 2.5, assumptions 1-2 and
  7): the journal touches the bearing, so the joint centre is displaced by ``r_c`` along a
  random direction ``v``; ``v`` is uniform (the paper does not state a distribution). Two
  variants of the passive joints:

  - ``"contact"`` (default): ``c_Bi = r_c (cos v_Bi, sin v_Bi)``, like the active joints
    (eq. 23);
  - ``"eq24_printed"``: eq. 24 read as printed, ``c_Bi = r_c (e(v_Bi) - e(pi - v_Ai))`` with
    assumption 3's constraint ``|c_Bi| < r_c``; sampled exactly (no rejection) because the
    constraint only bounds the angle between ``e(v_Bi)`` and ``e(pi - v_Ai)`` to +-60 deg;
  - ``"none"``: no clearance.

  The end-effector joint ``P`` is in free flight (assumption 3) and adds no displacement.

The paper gives no value of ``r_c``: :data:`DEFAULT_CLEARANCE` is our choice (see docs).

The parameters several definitions of this module share are described once, here.

Parameters
----------
r1, r2, r3 : float
    Nominal crank, coupler and half-base lengths, in the length unit of the design
    (dimensionless in the paper).
poses : array_like, shape (n_poses, 2) or (2,)
    Nominal end-effector positions, length unit.
working_mode : str or tuple of int
    Elbow signs (see :func:`evotol.robots.planar5r.kinematics.conventions.working_mode_signs`).
assembly : {1, -1}
    Assembly mode sigma of eq. 15.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import special
from scipy.stats import qmc

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.planar5r import kinematics as K

#: Table 1: 0.004 % of the link length (standard deviation of eq. 7).
DELTA_R = 0.004e-2
#: Table 1: 0.05 deg (standard deviation of eqs. 8 / 23), in rad.
DELTA_THETA = np.deg2rad(0.05)
#: Radial clearance r_c in units of D (non-dimensional). Not printed in the paper: our choice,
#: 2e-4 D = 20 um for D = 100 mm, the clearance of a precision running fit (H7/g6 around 10 mm).
DEFAULT_CLEARANCE = 2e-4
#: Non-dimensional radius of the circles the paper draws around each nominal pose (Sec. 3).
PAPER_CIRCLE = 0.005

CLEARANCE_MODELS = ("contact", "eq24_printed", "none")
METHODS = ("mc", "lhs")


@dataclass(frozen=True)
class UncertaintyModel:
    """Distributions of the uncertain parameters (Table 1, Sec. 2.5).

    length_rel_std: ``delta_r`` of eq. 7 (relative std of each link length).
    theta_std: ``delta_theta`` of eq. 8 (rad, std of each actuator angle error).
    clearance: ``r_c`` (same length unit as the design's r1..r3) at A_1, A_2, B_1, B_2.
    clearance_model: ``"contact"``, ``"eq24_printed"`` or ``"none"`` (module docstring).
    shared_lengths: one random variable per symmetric pair (paper) or six independent lengths.
    renormalise: divide the random lengths by the random ``D(Omega)`` (paper, Sec. 2.2).

    Parameters
    ----------
    length_rel_std : float
        ``delta_r``, dimensionless (default 4e-5, i.e. 0.004 %).
    theta_std : float
        ``delta_theta``, rad (default 0.05 deg).
    clearance : float
        Radial clearance ``r_c``, length unit of the design (default 2e-4).
    clearance_model : {"contact", "eq24_printed", "none"}
        Model of the passive-joint clearances.
    shared_lengths : bool
        True: 3 length columns (paper); False: 6.
    renormalise : bool
        Divide the random lengths by ``D(Omega)``.

    Raises
    ------
    ValidationError
        If a standard deviation or the clearance is negative or not finite, or
        ``clearance_model`` is unknown.
    """

    length_rel_std: float = DELTA_R
    theta_std: float = DELTA_THETA
    clearance: float = DEFAULT_CLEARANCE
    clearance_model: str = "contact"
    shared_lengths: bool = True
    renormalise: bool = True

    def __post_init__(self):
        for name in ("length_rel_std", "theta_std", "clearance"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float, np.floating)) and np.isfinite(v) and v >= 0):
                raise ValidationError(f"UncertaintyModel.{name}", v, "a finite number >= 0")
        if self.clearance_model not in CLEARANCE_MODELS:
            raise ValidationError("UncertaintyModel.clearance_model", self.clearance_model, f"one of {CLEARANCE_MODELS}")

    @property
    def n_length_dims(self) -> int:
        """Columns of the unit hypercube used by the link lengths: 3 (shared) or 6."""
        return 3 if self.shared_lengths else 6

    @property
    def n_dims(self) -> int:
        """Columns of the unit hypercube: lengths, 2 actuator errors, 4 clearance directions."""
        return self.n_length_dims + 2 + 4

    def errors_from_unit(self, u: np.ndarray, r1: float, r2: float, r3: float) -> dict:
        """Map unit-hypercube rows ``u`` (n, n_dims) to the error parameters of
        :func:`evotol.robots.planar5r.kinematics.perturbed.perturbed_position` (arrays of shape (n,)).

        Parameters
        ----------
        u : ndarray, shape (n, n_dims)
            Rows of the unit hypercube ``[0, 1)^n_dims``.

        Returns
        -------
        dict of str to ndarray, each shape (n,)
            ``dA1B1 .. dOA2`` (length unit), ``dth1``, ``dth2`` (rad) and, unless the clearance model
            is ``"none"`` or ``clearance`` is 0, ``cA1x .. cB2y`` (length unit).

        Raises
        ------
        ValidationError
            If ``u`` is not of shape (n, n_dims).
        """
        u = np.asarray(u, dtype=float)
        if u.ndim != 2 or u.shape[1] != self.n_dims:
            raise ValidationError("unit samples shape", u.shape, f"(n, {self.n_dims})")
        xi = special.ndtri(np.clip(u[:, : self.n_length_dims + 2], 1e-16, 1 - 1e-16))
        nominal = np.array([r1, r2, r3] if self.shared_lengths else [r1, r1, r2, r2, r3, r3])
        lengths = nominal * (1.0 + self.length_rel_std * xi[:, : self.n_length_dims])
        if self.renormalise:
            lengths = lengths * (nominal.sum() / lengths.sum(axis=1))[:, None]
        dl = lengths - nominal
        if self.shared_lengths:
            dl = dl[:, [0, 0, 1, 1, 2, 2]]
        err = {k: dl[:, j] for j, k in enumerate(("dA1B1", "dA2B2", "dB1P", "dB2P", "dOA1", "dOA2"))}
        k = self.n_length_dims
        err["dth1"], err["dth2"] = self.theta_std * xi[:, k], self.theta_std * xi[:, k + 1]
        if self.clearance_model != "none" and self.clearance > 0:
            rc = self.clearance
            v = 2 * np.pi * u[:, k + 2: k + 6]
            vA1, vA2 = v[:, 0], v[:, 1]
            err["cA1x"], err["cA1y"] = rc * np.cos(vA1), rc * np.sin(vA1)
            err["cA2x"], err["cA2y"] = rc * np.cos(vA2), rc * np.sin(vA2)
            if self.clearance_model == "contact":
                vB1, vB2 = v[:, 2], v[:, 3]
                err["cB1x"], err["cB1y"] = rc * np.cos(vB1), rc * np.sin(vB1)
                err["cB2x"], err["cB2y"] = rc * np.cos(vB2), rc * np.sin(vB2)
            else:  # eq. 24 as printed, conditioned on |c_Bi| < r_c (assumption 3)
                for i, vA in ((1, vA1), (2, vA2)):
                    ref = np.pi - vA
                    vB = ref + (u[:, k + 3 + i] - 0.5) * (2 * np.pi / 3)
                    err[f"cB{i}x"] = rc * (np.cos(vB) - np.cos(ref))
                    err[f"cB{i}y"] = rc * (np.sin(vB) - np.sin(ref))
        return err


def unit_samples(n: int, d: int, method: str = "lhs", seed=0) -> np.ndarray:
    """``n`` points of ``[0, 1)^d``: plain Monte Carlo or a scrambled Latin hypercube
    (scipy.stats.qmc.LatinHypercube), reproducible from ``seed``.

    Parameters
    ----------
    n : int
        Number of points (at least 1).
    d : int
        Dimension.
    method : {"lhs", "mc"}
        Scrambled Latin hypercube or plain Monte Carlo.
    seed : int, numpy.random.Generator or None
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    ndarray, shape (n, d)
        Points in ``[0, 1)^d``.

    Raises
    ------
    ValidationError
        If ``n`` is below 1 or ``method`` is unknown.
    """
    if int(n) < 1:
        raise ValidationError("n_samples", n, "a positive integer")
    if method == "mc":
        return np.random.default_rng(seed).random((int(n), d))
    if method == "lhs":
        return qmc.LatinHypercube(d=d, seed=np.random.default_rng(seed)).random(int(n))
    raise ValidationError("method", method, f"one of {METHODS}")


def position_deviations(poses, r1, r2, r3, model: UncertaintyModel, unit: np.ndarray,
                        working_mode=K.DEFAULT_WORKING_MODE, assembly=1, failures: str = "raise"):
    """Deviation ``P(Omega) - P`` (n_poses, n_samples, 2) of the end-effector at ``poses``
    (n_poses, 2) for the sampled rows ``unit`` (n_samples, n_dims): the nominal crank angles
    come from the inverse kinematics; all poses x samples are one array pass.

    A sample "cannot be assembled" when its couplers no longer meet (``|B_1B_2| > r2 + r2'``),
    which happens next to a type II singularity. ``failures="raise"`` raises
    :class:`KinematicsError` naming the pose; ``failures="mask"`` returns ``(dp, assembled)``
    with ``dp = 0`` where ``assembled`` (n_poses, n_samples) is False.

    Parameters
    ----------
    model : UncertaintyModel
        Distributions of the uncertain parameters.
    unit : ndarray, shape (n_samples, n_dims)
        Unit-hypercube rows (see :func:`unit_samples`).
    failures : {"raise", "mask"}
        What a sample that cannot be assembled gives.

    Returns
    -------
    dp : ndarray, shape (n_poses, n_samples, 2)
        Deviations ``(dx, dy)``, length unit.
    assembled : ndarray of bool, shape (n_poses, n_samples)
        Only with ``failures="mask"``: True where the sample was assembled.

    Raises
    ------
    ValidationError
        If ``failures`` is invalid, or ``poses`` or ``unit`` has a wrong shape.
    KinematicsError
        If a pose is outside the theoretical workspace, or, with ``failures="raise"``, a sample
        cannot be assembled.
    """
    if failures not in ("raise", "mask"):
        raise ValidationError("failures", failures, "'raise' or 'mask'")
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    theta = K.inverse_kinematics(poses, r1, r2, r3, working_mode)
    err = model.errors_from_unit(unit, r1, r2, r3)
    px, py, h2 = K.perturbed_position(theta[:, None, :], r1, r2, r3, err, assembly)
    assembled = h2 >= 0
    dp = np.stack([px - poses[:, 0:1], py - poses[:, 1:2]], axis=-1)
    if failures == "mask":
        return np.where(assembled[..., None], dp, 0.0), assembled
    bad = ~np.all(assembled, axis=1)
    if bad.any():
        raise KinematicsError(f"5R: pose {poses[bad][0].tolist()} cannot be assembled for "
                              f"{int((~assembled[bad][0]).sum())} of {assembled.shape[1]} sampled errors "
                              f"(too close to a type II singularity)", poses=poses[bad])
    return dp


def sample_deviations(poses, r1, r2, r3, model: UncertaintyModel | None = None, n_samples: int = 1000,
                      method: str = "lhs", seed=0, working_mode=K.DEFAULT_WORKING_MODE, assembly=1,
                      failures: str = "raise"):
    """Monte Carlo (``method="mc"``) or Latin hypercube (``"lhs"``) deviations, (n_poses, n_samples, 2).

    The same ``n_samples`` parameter rows are used at every pose (common random numbers), so
    per-pose differences come from the kinematics, not from sampling noise. ``failures`` as in
    :func:`position_deviations`.

    Parameters
    ----------
    model : UncertaintyModel or None
        Distributions; None: :class:`UncertaintyModel` () (Table 1).
    n_samples : int
        Samples per pose.
    method : {"lhs", "mc"}
        Sampling method.
    seed : int, numpy.random.Generator or None
        Seed of the unit samples.
    failures : {"raise", "mask"}
        As :func:`position_deviations`.

    Returns
    -------
    ndarray or tuple of ndarray
        As :func:`position_deviations`: ``dp`` (n_poses, n_samples, 2), length unit, and with
        ``failures="mask"`` also ``assembled``.

    Raises
    ------
    ValidationError, KinematicsError
        As :func:`unit_samples` and :func:`position_deviations`.
    """
    model = model or UncertaintyModel()
    return position_deviations(poses, r1, r2, r3, model, unit_samples(n_samples, model.n_dims, method, seed),
                               working_mode, assembly, failures)


def pose_statistics(dp: np.ndarray, radius: float = PAPER_CIRCLE, assembled: np.ndarray | None = None) -> dict:
    """Per-pose statistics of deviations ``dp`` (n_poses, n_samples, 2).

    mean_dx, mean_dy, std_dx, std_dy: of the components; mean_dev, rms_dev, max_dev, q99_dev:
    of ``|dp|``; p_exceed: fraction of samples outside the circle of ``radius`` (the paper's
    0.005 non-dimensional circle by default). Arrays of shape (n_poses,). With an
    ``assembled`` mask (see :func:`position_deviations`) the moments use assembled samples only,
    a sample that cannot be assembled counts as exceeding, and ``p_unassembled`` is reported.

    Parameters
    ----------
    dp : ndarray, shape (n_poses, n_samples, 2)
        Deviations, length unit.
    radius : float
        Radius of the tolerance circle, length unit (default 0.005, non-dimensional).
    assembled : ndarray of bool, shape (n_poses, n_samples), or None
        Which samples were assembled; None: all.

    Returns
    -------
    dict of str to ndarray, each shape (n_poses,)
        ``mean_dx``, ``mean_dy``, ``std_dx``, ``std_dy``, ``mean_dev``, ``rms_dev``, ``max_dev``,
        ``q99_dev`` (length unit), ``p_exceed`` and ``p_unassembled`` (fractions).

    Raises
    ------
    KinematicsError
        If fewer than 2 samples are assembled at some pose.
    """
    dev = np.hypot(dp[..., 0], dp[..., 1])
    if assembled is None:
        assembled = np.ones(dev.shape, dtype=bool)
    n_ok = assembled.sum(1)
    if np.any(n_ok < 2):
        raise KinematicsError("5R: fewer than 2 assembled samples at some pose; no statistics")
    w = assembled.astype(float)

    def mean(a):
        return (a * w).sum(1) / n_ok

    mx, my = mean(dp[..., 0]), mean(dp[..., 1])
    sx = np.sqrt(((dp[..., 0] - mx[:, None]) ** 2 * w).sum(1) / (n_ok - 1))
    sy = np.sqrt(((dp[..., 1] - my[:, None]) ** 2 * w).sum(1) / (n_ok - 1))
    dev_ok = np.where(assembled, dev, np.nan)
    return dict(mean_dx=mx, mean_dy=my, std_dx=sx, std_dy=sy, mean_dev=mean(dev),
                rms_dev=np.sqrt(mean(dev * dev)), max_dev=np.nanmax(dev_ok, 1),
                q99_dev=np.nanquantile(dev_ok, 0.99, axis=1),
                p_exceed=np.mean((dev > radius) | ~assembled, 1), p_unassembled=1.0 - n_ok / dev.shape[1])


def convergence_study(poses, r1, r2, r3, model: UncertaintyModel | None = None,
                      sizes=(16, 32, 64, 128, 256, 512), n_rep: int = 100, n_reference: int = 2 ** 16,
                      seed=0, working_mode=K.DEFAULT_WORKING_MODE, assembly=1) -> dict:
    """Measured convergence of LHS vs plain MC (the paper's claim that LHS needs fewer samples).

    For each sample size N and method, ``n_rep`` independent replications estimate, at every
    pose, the mean deviation ``mean(dx)``, the RMS deviation ``rms(|dp|)`` and the probability
    ``P(|dp| > q90)`` (q90 = the reference 90 % quantile of ``|dp|``, so p = 0.1). The reference
    is one LHS run of ``n_reference`` samples. Returned errors are root-mean-square over
    replications, averaged over poses (the mean error in units of the reference rms deviation,
    the others relative). ``variance_ratio`` = MC error^2 / LHS error^2 = how many times more
    samples plain MC needs for the same accuracy.

    Parameters
    ----------
    model : UncertaintyModel or None
        Distributions; None: :class:`UncertaintyModel` ().
    sizes : sequence of int
        Sample sizes N compared.
    n_rep : int
        Replications per size and method.
    n_reference : int
        Samples of the reference LHS run.
    seed : int
        Seed of the replications (the reference uses ``seed + 10000``).

    Returns
    -------
    dict
        ``"sizes"``, ``"n_rep"``, ``"n_reference"``; ``"mc"`` and ``"lhs"``: dicts
        ``{"mean_dx", "rms_dev", "p_exceed_q90"}`` of lists (one dimensionless error per size);
        ``"variance_ratio"``: the same keys, MC over LHS squared error per size.

    Raises
    ------
    ValidationError, KinematicsError
        As :func:`position_deviations` (a sample that cannot be assembled raises).
    """
    model = model or UncertaintyModel()
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    ref_dp = sample_deviations(poses, r1, r2, r3, model, n_reference, "lhs", seed + 10_000, working_mode, assembly)
    ref_dev = np.hypot(ref_dp[..., 0], ref_dp[..., 1])
    ref_rms = np.sqrt(np.mean(ref_dev ** 2, 1))
    ref_mean = ref_dp[..., 0].mean(1)
    q90 = np.quantile(ref_dev, 0.9, axis=1)
    ref_p = np.mean(ref_dev > q90[:, None], 1)
    out = {"sizes": list(map(int, sizes)), "n_rep": int(n_rep), "n_reference": int(n_reference)}
    rng = np.random.default_rng(seed)
    for method in METHODS:
        rows = {"mean_dx": [], "rms_dev": [], "p_exceed_q90": []}
        for N in sizes:
            unit = np.concatenate([unit_samples(N, model.n_dims, method, rng.integers(2 ** 63)) for _ in range(n_rep)])
            dp = position_deviations(poses, r1, r2, r3, model, unit, working_mode, assembly).reshape(len(poses), n_rep, N, 2)
            dev = np.hypot(dp[..., 0], dp[..., 1])
            est_mean = dp[..., 0].mean(-1)
            est_rms = np.sqrt(np.mean(dev ** 2, -1))
            est_p = np.mean(dev > q90[:, None, None], -1)
            rows["mean_dx"].append(float(np.mean(np.sqrt(np.mean((est_mean - ref_mean[:, None]) ** 2, 1)) / ref_rms)))
            rows["rms_dev"].append(float(np.mean(np.sqrt(np.mean((est_rms / ref_rms[:, None] - 1) ** 2, 1)))))
            rows["p_exceed_q90"].append(float(np.mean(np.sqrt(np.mean((est_p - ref_p[:, None]) ** 2, 1)) / ref_p)))
        out[method] = rows
    out["variance_ratio"] = {k: [(m / l) ** 2 for m, l in zip(out["mc"][k], out["lhs"][k])] for k in out["mc"]}
    return out

"""The calibration simulated on the nonlinear model: what the first-order prediction is checked against.

:func:`simulate_calibration` draws robots with errors inside a design's tolerances (the
problem's distributions, one robot for every pose), and for each robot

1. reads the instrument at the plan's configurations: the nonlinear model's tool position (and
   orientation) error plus normal noise of the plan's sigmas;
2. identifies the plan's sources (and the registration of an unknown instrument frame, truth
   zero, linear) by nonlinear least squares on the nonlinear model
   (:func:`scipy.optimize.least_squares`, rows weighted by ``1/σ``, started at the linear fit);
3. compensates: at each task pose the controller moves the actuated joints so that the
   *identified* model reaches the pose (:mod:`evotol.calibration.compensation`);
4. measures the residual of the *true* model at the task poses.

Beside it, the first-order prediction for the same robots and noise, ``J M δp − J_K (B⁺)_K ε``,
and the first-order worst case. :class:`CalibrationCheck` reports the simulated worst residual
and quantile, the prediction's, the largest difference between the two (relative to the
requirement) and the fraction of robots outside the user's requirement.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from evotol.calibration.compensation import Compensation
from evotol.calibration.configurations import pose_error_of_robots
from evotol.calibration.identification import registration_columns
from evotol.calibration.plan import MEASURED
from evotol.calibration.random_share import draw_visits
from evotol.measures.statistical import distributions
from evotol.errors import ValidationError, is_integer

ROWS = {"position": slice(0, 3), "orientation": slice(3, 6)}


@dataclass
class CalibrationCheck:
    """Simulated calibration beside the first-order prediction (SI: m, rad).

    Parameters
    ----------
    n_samples : int
        Robots simulated.
    simulated, predicted : dict
        Component -> ``{"max": worst residual over robots and poses, "quantile": the
        ``quantile`` of each robot's worst residual over poses}`` (m or rad).
    difference : dict
        Component -> largest ``|simulated − predicted|`` over robots and poses (m or rad).
    worst_case : dict
        Component -> first-order worst case of the design plus the noise allowance (``k`` sigma and
        the second-order term; m or rad).
    requirement : dict
        Component -> the user's bound (m or rad).
    exceed_rate : dict
        Component -> fraction of simulated robots whose worst residual exceeds the bound.
    quantile : float
        The quantile reported.
    nls_failures : int
        Robots whose least-squares fit did not converge (kept in the statistics).
    seconds : float
        Wall time.
    samples : dict
        ``simulated`` and ``predicted`` residuals (n_poses, n_samples, 6) and the drawn ``errors``
        (n_samples, n_columns), SI; not written to JSON.
    """

    n_samples: int
    simulated: dict
    predicted: dict
    difference: dict
    worst_case: dict
    requirement: dict
    exceed_rate: dict
    quantile: float = 0.95
    nls_failures: int = 0
    seconds: float = 0.0
    samples: dict = field(default_factory=dict, repr=False)

    def to_dict(self) -> dict:
        """Plain data for JSON (SI).

        Returns
        -------
        dict
            Every field but the raw samples (``exceed_rate_<component>``, ``quantile_level``,
        ``n_fit_failures`` for the JSON unit rules, docs/units.md).
        """
        return {"n_samples": self.n_samples, "simulated": self.simulated, "predicted": self.predicted,
                "difference": self.difference, "worst_case": self.worst_case, "requirement": self.requirement,
                **{f"exceed_rate_{c}": v for c, v in self.exceed_rate.items()}, "quantile_level": self.quantile,
                "n_fit_failures": self.nls_failures, "seconds": self.seconds}


def simulate_calibration(problem, tolerances, n_samples: int = 200, seed: int = 0, quantile: float = 0.95,
                         method: str = "lhs") -> CalibrationCheck:
    """Simulate the plan's calibration of robots drawn within ``tolerances`` (module docstring).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        A calibrated problem (:func:`evotol.calibration.problem.calibrated_problem`) of a described
        mechanism.
    tolerances : mapping or array_like
        The design: source name -> tolerance, or one per source (m, rad).
    n_samples : int
        Robots simulated (each one a least-squares fit).
    seed : int
        Seed of the errors and of the noise.
    quantile : float
        Quantile of the robots' worst residual reported, in (0, 1).
    method : {"lhs", "mc"}
        Sampling of the source errors.

    Returns
    -------
    CalibrationCheck
        Simulated and predicted residuals, their difference, the worst case, exceed rates.

    Raises
    ------
    evotol.errors.ValidationError
        A problem without a calibration, a model without a nonlinear joint-space model, or a bad
        ``n_samples`` / ``quantile``.
    """
    t0 = time.perf_counter()
    info = problem.calibration
    if info is None:
        raise ValidationError("problem", problem.model.name, "a calibrated problem (evotol.calibration.calibrated_problem)")
    if not is_integer(n_samples, 1):
        raise ValidationError("n_samples", n_samples, "a positive integer")
    if not (0 < quantile < 1):
        raise ValidationError("quantile", quantile, "a number in (0, 1)")
    cal = problem.model
    robot, idn, plan = cal.base, info.identification, info.plan
    if idn.joints is None:
        raise ValidationError("calibration", robot.name, "a described mechanism (the simulation needs its nonlinear joint-space model)")
    t = problem.as_array(tolerances)
    rng = np.random.default_rng(seed)
    dims = [s.dim for s in robot.sources]
    Z = distributions.draw(distributions.uniforms(n_samples, sum(dims), method, rng), dims, problem.distributions)
    D = np.concatenate(problem.source_errors(Z, t), axis=1)                         # (m, n_cols)
    Qc = idn.joints
    q = robot.joint_values(problem.poses)
    Qt = np.stack([np.asarray(q[v], float) for v in robot.kin.variables], axis=1)
    mrows = np.concatenate([np.arange(6)[MEASURED[c]] for c in plan.measure])
    w = idn.weights
    sig_rows = plan.sigma_rows(len(Qc))
    eps = rng.standard_normal((n_samples, len(sig_rows))) * sig_rows                # (m, n_rows)
    K = idn.identified
    nK = len(K)
    Rlin = None
    if idn.registration:
        Rg, rn = registration_columns(robot, plan, Qc)
        Rlin = Rg[:, mrows][:, :, [rn.index(r) for r in idn.registration]].reshape(-1, len(idn.registration)) * w[:, None]
    n_reg = 0 if Rlin is None else Rlin.shape[1]
    part = info.random          # random sources: drawn anew at every visit (readings, task poses; random_share.py)
    Rc = None if part is None else draw_visits(part, len(Qc) * n_samples, rng).reshape(len(Qc), n_samples, -1)
    read = pose_error_of_robots(robot, Qc, D) if Rc is None else robot.pose_error_at_joints(Qc, D[None] + Rc)
    Y = (np.swapaxes(read[:, :, mrows], 0, 1).reshape(n_samples, -1) + eps) * w                # whitened

    def readings(X):                          # X (b, n_reg + nK) -> whitened model readings (b, n_rows)
        E = np.zeros((X.shape[0], robot.n_columns))
        E[:, K] = X[:, n_reg:]
        r = np.swapaxes(pose_error_of_robots(robot, Qc, E)[:, :, mrows], 0, 1).reshape(X.shape[0], -1) * w
        return r + (X[:, :n_reg] @ Rlin.T if n_reg else 0.0)

    AK = robot.sensitivity_at_joints(Qc)[:, mrows][:, :, K].reshape(-1, nK) * w[:, None]
    B = np.linalg.pinv(np.column_stack([Rlin, AK]) if n_reg else AK)
    Xhat = np.zeros((n_samples, n_reg + nK))
    failures = 0
    h = 1e-7
    for s in range(n_samples):
        def fun(x, s=s):
            return readings(x[None])[0] - Y[s]

        def jac(x):
            R = readings(x[None] + np.vstack([np.zeros(len(x)), h * np.eye(len(x))]))
            return ((R[1:] - R[0]) / h).T

        sol = least_squares(fun, B @ Y[s], jac=jac, method="lm", xtol=1e-12, ftol=1e-12)
        failures += int(not sol.success)
        Xhat[s] = sol.x
    Ehat = np.zeros((n_samples, robot.n_columns))
    Ehat[:, K] = Xhat[:, n_reg:]
    sim = Compensation(robot, Qt).residual(D, Ehat)                                     # (n_t, m, 6)
    # first-order prediction for the same robots and noise
    Jt = robot.sensitivity_at_joints(Qt)
    lin = np.einsum("pij,sj->psi", Jt @ idn.M, D) - np.einsum("pik,sk->psi", Jt[:, :, K], (eps * w) @ idn.estimator.T)
    if part is not None:        # the random sources' share of the readings, and their draw at each task pose (first order)
        Sc = robot.sensitivity_at_joints(Qc)[:, mrows]                                  # (n_c, rows, n_cols)
        yr = np.einsum("crm,csm->scr", Sc, Rc).reshape(n_samples, -1) * w
        rt = np.einsum("pim,psm->psi", Jt, draw_visits(part, len(Qt) * n_samples, rng).reshape(len(Qt), n_samples, -1))
        lin = lin - np.einsum("pik,sk->psi", Jt[:, :, K], yr @ idn.estimator.T) + rt
        sim = sim + rt
    wc = problem.evaluate(t[None], "worst_case")
    out = {k: {} for k in ("simulated", "predicted", "difference", "worst_case", "requirement", "exceed_rate")}
    for comp, E_req in problem.uncalibrated.components:
        ns = np.linalg.norm(sim[:, :, ROWS[comp]], axis=2).max(axis=0)                  # worst pose per robot
        nl = np.linalg.norm(lin[:, :, ROWS[comp]], axis=2).max(axis=0)
        out["simulated"][comp] = {"max": float(ns.max()), "quantile": float(np.quantile(ns, quantile))}
        out["predicted"][comp] = {"max": float(nl.max()), "quantile": float(np.quantile(nl, quantile))}
        out["difference"][comp] = float(np.abs(sim[:, :, ROWS[comp]] - lin[:, :, ROWS[comp]]).max())
        nz = info.noise.get(comp, {})
        allow = nz.get("allowance", 0.0) + nz.get("second_order", 0.0) + nz.get("remainder", 0.0) + \
            nz.get("random_worst_case", 0.0)
        out["worst_case"][comp] = float(np.max(getattr(wc, comp)[0])) + float(allow)
        out["requirement"][comp] = float(E_req)
        out["exceed_rate"][comp] = float(np.mean(ns > E_req))
    return CalibrationCheck(int(n_samples), **out, quantile=float(quantile), nls_failures=failures,
                            seconds=time.perf_counter() - t0, samples={"simulated": sim, "predicted": lin, "errors": D})

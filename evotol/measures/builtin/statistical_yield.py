"""The ``yield`` measure: at every pose P(``|δp|`` ≤ position and ``|δθ|`` ≤ orientation) ≥ the required
yield, for the first-order model (:class:`evotol.measures.statistical.FirstOrderYield`; Bonferroni bound
for both components) or the robot's own ``pose_error`` on common samples
(:class:`evotol.measures.statistical.SampledYield`, ``Requirement(model="nonlinear")``); ``docs/statistical.md``."""
from __future__ import annotations

import numpy as np

from evotol.measures.statistical import distributions

from evotol.measures import statistical
from evotol.measures.protocol import ComponentErrors, Evaluation, Measure, evaluation_of


def first_order_yield(problem) -> "statistical.FirstOrderYield | statistical.SampledYield":
    """The problem's statistical model for the ``yield`` measure (moments of the linear model, or
    the nonlinear model's samples), cached on the problem.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem; its requirement's ``model`` chooses the model.

    Returns
    -------
    evotol.measures.statistical.FirstOrderYield or evotol.measures.statistical.SampledYield
        ``SampledYield`` for ``Requirement(model="nonlinear")``, else ``FirstOrderYield``.
    """
    r = problem.requirement

    def build():
        shift = None if problem.shape.plain else (problem.shape.rho, problem.shape.kappa, problem.shape.offset)
        if r.model == "nonlinear":
            return statistical.SampledYield(problem.error_model, problem.poses, problem.distributions,
                                            dict(problem.components), r.mc_samples, r.seed, shift=shift)
        # a calibrated robot (evotol.calibration.model) adds its propagated instrument noise to the covariance
        cal = problem.model.part_of("calibration")
        noise = cal.noise_cov6(problem.poses) if cal is not None else None
        return statistical.FirstOrderYield(problem.blocks, problem.distributions, dict(problem.components), shift=shift,
                                           noise=noise)

    return problem.measure_cache("yield.model", build)


class YieldMeasure(Measure):
    """Yield lower bound per pose (``probability``) and each component's k-sigma equivalent error
    E·k_req/k(q) (m or rad) for the required yield."""

    name = "yield"
    brute_force_rtol = 0.0
    brute_force_atol = 0.005   # the Monte Carlo of brute_force has 40 000 samples: σ ≈ 0.0011 at a yield of 0.95

    def evaluate(self, problem, T: np.ndarray, top_only: bool = False) -> Evaluation:
        """The k-sigma equivalent errors of the constrained components, ``probability`` the yield's
        lower bound per pose, and whether it is ``exact`` (every source normal); ``top_only`` is
        ignored (the yield is computed at every pose).
        """
        y = first_order_yield(problem).evaluate(T, problem.requirement.required_yield)
        parts = {c: ComponentErrors(y.equivalent[c], y.equivalent[c], y.contributions.get(c)) for c in y.miss}
        return evaluation_of(parts, y.violation, probability=y.probability, exact=y.exact)

    def brute_force(self, problem, t: np.ndarray) -> dict[str, np.ndarray]:
        """The yield per pose by direct Monte Carlo of the linear model (40 000 samples of the sources'
        distributions, seed 7): the share of samples whose errors meet every bound, returned as
        ``"probability"`` (dimensionless, 0 to 1).
        """
        Z = distributions.unit_samples([s.dim for s in problem.error_model.sources], problem.distributions, 40_000,
                                       method="mc", seed=7)
        E = np.concatenate(problem.source_errors(Z, t), axis=1)
        rows = {"position": slice(0, 3), "orientation": slice(3, 6)}
        ok = np.ones((problem.n_poses, E.shape[0]), bool)
        for comp, lim in problem.components:
            ok &= np.linalg.norm(np.einsum("pik,sk->psi", problem.jacobian[:, rows[comp]], E), axis=2) <= lim
        return {"probability": ok.mean(axis=1)}


YIELD = YieldMeasure()

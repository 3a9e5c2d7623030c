"""The one result type every allocator returns, with the contributor report."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from evotol.measures import feasibility

from evotol.core import plausibility
from evotol.measures.protocol import Evaluation
from evotol.units.display import DisplayUnits, error_unit, pose_text, problem_units
from evotol.core.problem import ToleranceProblem


#: info entries that are a solver's raw diagnostics, not results: ``to_dict`` nests them under
#: ``"diagnostics"`` so they are not read as the verdict
DIAGNOSTICS = ("solver_message",)
#: a certificate with relative duality gap and KKT residual at most these is reported "certified optimal"
CERTIFIED_GAP = 1e-6
CERTIFIED_KKT = 1e-4


@dataclass
class AllocationResult:
    """Tolerances (SI), cost, accuracy at every pose, feasibility, history, contributors.

    ``errors`` holds the exact per-pose errors under the problem's measure; ``certificate`` holds
    optimality evidence where the method has it (lower bound, gap, KKT residual).

    Parameters
    ----------
    method : str
        The allocator's name, as reports show it.
    problem : ToleranceProblem
        The problem the design was allocated for.
    tolerances : dict of str to float
        Source name -> tolerance (SI: m or rad), in the problem's source order.
    cost : float
        Total cost of the design (cost units, :meth:`ToleranceProblem.cost`).
    feasible : bool
        Within the tolerance bounds and meeting the requirement (in budget mode: within the
        bounds and the budget; see :func:`make_result`).
    errors : Evaluation
        Errors of the design (one design row) at every pose under the problem's measure (m, rad).
    history : pandas.DataFrame, optional
        The allocator's progress per iteration or generation, if it keeps one.
    certificate : dict, optional
        Optimality evidence (``lower_bound`` in cost units, relative ``gap``, ``kkt_residual``).
    seconds : float
        Wall-clock time of the allocation (s).
    info : dict
        Further entries (``bound_ratio``, ``budget``, ``solver_message``, ``warnings`` ...).

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import allocate_optimum
    >>> res = allocate_optimum(problem)
    >>> res.method, res.feasible
    ('optimum', True)
    >>> print(res.summary())                                    # doctest: +ELLIPSIS
    optimum: cost 97.426; meets the requirement
    ...
    """

    method: str
    problem: ToleranceProblem = field(repr=False)
    tolerances: dict[str, float]
    cost: float
    feasible: bool
    errors: Evaluation = field(repr=False)
    history: pd.DataFrame | None = field(default=None, repr=False)
    certificate: dict | None = None
    seconds: float = 0.0
    info: dict = field(default_factory=dict)

    @property
    def t(self) -> np.ndarray:
        """The tolerances as an array in source order, shape (n_sources,) (SI: m or rad)."""
        return np.array([self.tolerances[n] for n in self.problem.names])

    def max_error(self, component: str = "position") -> float:
        """Largest error over the poses under the problem's measure.

        Parameters
        ----------
        component : {"position", "orientation"}
            The error component.

        Returns
        -------
        float
            The largest error (m for position, rad for orientation); NaN when the measure did
            not compute this component.
        """
        v = getattr(self.errors, component)
        return float(np.max(v)) if v is not None else float("nan")

    def worst_pose(self, component: str = "position") -> int:
        """Index of the pose with the largest error.

        Parameters
        ----------
        component : {"position", "orientation"}
            The error component (it must have been computed).

        Returns
        -------
        int
            Pose index into ``problem.poses``.
        """
        return int(np.argmax(getattr(self.errors, component)[0]))

    def contributions(self, component: str = "position", pose: int | str = "worst",
                      units: DisplayUnits | None = None) -> pd.DataFrame:
        """Each source's share (%) of the error at one pose (default: the worst pose).

        Worst case: share of h(u*) = Σ_j t_j‖B_jᵀu*‖ at the worst direction u*; RSS: share of the
        sum of squares. The standard contributor report of tolerance-analysis tools.

        Parameters
        ----------
        component : str
            ``"position"`` or ``"orientation"``.
        pose : int or "worst"
            Pose index, or the pose of the largest ``component`` error.
        units : DisplayUnits, optional
            Units of the ``±`` column (default: from the mechanism's ``display``).

        Returns
        -------
        pandas.DataFrame
            Columns source, group, tolerance (SI), unit (SI), ``±`` (the tolerance as text in
            display units, e.g. ``"±12.00 µm"``), cost (cost-model unit), percent; sorted by share.

        Raises
        ------
        ValueError
            The measure computed no contributions for ``component``.
        """
        c = getattr(self.errors, f"{component}_contrib")
        if c is None:
            raise ValueError(f"no contributions for measure {self.problem.requirement.measure}")
        p = self.worst_pose(component) if pose == "worst" else int(pose)
        share = 100 * c[0, p]
        p_ = self.problem
        u = units or problem_units(p_)
        shown = [u.format(t, unit, sign="±") for t, unit in zip(self.t, p_.units())]
        return pd.DataFrame({"source": p_.names, "group": p_.groups(), "tolerance": self.t,
                             "unit": p_.units(), "±": shown, "cost": p_.source_costs(self.t),
                             "percent": share}).sort_values("percent", ascending=False, ignore_index=True)

    def contributions_per_pose(self, component: str = "position") -> pd.DataFrame:
        """(n_poses × n_sources) table of % contributions.

        Parameters
        ----------
        component : {"position", "orientation"}
            The error component (its contributions must have been computed).

        Returns
        -------
        pandas.DataFrame
            One row per pose, one column per source name: share of the error (percent).
        """
        c = getattr(self.errors, f"{component}_contrib")
        return pd.DataFrame(100 * c[0], columns=list(self.problem.names))

    def __repr__(self) -> str:
        """One line: method, cost, feasibility, size and the largest error of each component."""
        units = {c: error_unit(self.problem, c) for c, _ in self.problem.components}     # "1": fractions of the limits
        errors = ", ".join(f"max {c} error {self.max_error(c):.4g}" + (f" {u}" if u != "1" else " of the limit")
                           for c, u in units.items())
        return (f"AllocationResult(method={self.method!r}, cost={self.cost:.6g}, feasible={self.feasible}, "
                f"{len(self.tolerances)} sources, {errors})")

    def to_frame(self) -> pd.DataFrame:
        """The design as a table, one row per source (pandas; ``to_dict`` gives the scalars).

        Returns
        -------
        pandas.DataFrame
            Indexed by source name: ``tolerance`` (SI), ``unit`` (m or rad), ``lower`` and
            ``upper`` (the allowed range, SI), ``locked`` (bool), ``cost`` (cost units,
            :meth:`ToleranceProblem.source_costs`) and ``cost_share`` (fraction of the total).
        """
        p = self.problem
        t = p.as_array(self.tolerances)
        costs = p.source_costs(t)
        total = float(costs.sum())
        units = [s.unit for s in p.error_model.sources]
        frame = pd.DataFrame({"tolerance": t, "unit": units, "lower": p.lower, "upper": p.upper,
                              "locked": np.asarray(p.locked, dtype=bool), "cost": costs,
                              "cost_share": costs / total if total > 0 else np.zeros_like(costs)},
                             index=pd.Index(list(p.names), name="source"))
        return frame

    def to_dict(self) -> dict:
        """The result as plain data (for JSON/YAML reports).

        Returns
        -------
        dict
            ``method``, ``tolerances`` (SI), ``cost``, ``feasible``, ``seconds``, ``measure``,
            ``shared``/``shared_cost`` if any, ``max_<component>_error`` (and ``_bound``; m, rad),
            ``certificate``, the scalar/list/dict/str ``info`` entries, ``verdict``, ``status``
            and, if the solver left a message, ``diagnostics``.
        """
        d = {"method": self.method, "tolerances": dict(self.tolerances), "cost": self.cost,
             "feasible": self.feasible, "seconds": self.seconds,
             "measure": self.problem.requirement.measure}
        if self.problem.shared:   # one value per tolerance variable, and which sources it drives
            d["shared"] = {g: list(m) for g, m in self.problem.shared.items()}
            d["shared_cost"] = self.problem.shared_cost
        for comp, _ in self.problem.components:
            d[f"max_{comp}_error"] = self.max_error(comp)
            b = getattr(self.errors, f"{comp}_bound")
            if b is not None:
                d[f"max_{comp}_error_bound"] = float(np.max(b))
        if self.certificate:
            d["certificate"] = self.certificate
        info = {k: v for k, v in self.info.items() if np.isscalar(v) or isinstance(v, (list, dict, str))}
        diagnostics = {k: info.pop(k) for k in DIAGNOSTICS if k in info}
        d.update(info)
        if self.verdict is not None:
            d["verdict"] = self.verdict
        d["status"] = self.status()
        if diagnostics:
            if self.solver_note:
                diagnostics["solver_message_meaning"] = self.solver_note
            d["diagnostics"] = diagnostics
        return d

    @property
    def verdict(self) -> str | None:
        """The certificate read as a sentence (None without a duality-gap certificate).

        The certificate, not the solver's exit message, decides: SLSQP often ends with
        "Positive directional derivative for linesearch" at a point whose proven lower bound
        matches the cost to 1e-13 (issue 15); that message is kept under ``diagnostics``.
        """
        c = self.certificate or {}
        if "gap" not in c or "lower_bound" not in c:
            return None
        gap, kkt = float(c["gap"]), float(c.get("kkt_residual", 0.0))
        if gap <= CERTIFIED_GAP:
            # the proven lower bound alone certifies the cost; a KKT residual above tolerance only
            # says the multipliers are not resolved (degenerate active poses), not that t is worse
            return (f"certified optimal: cost equals the proven lower bound {float(c['lower_bound']):.6g} "
                    f"to {abs(gap):.1e} (relative gap)"
                    + (f"; KKT residual {kkt:.1e} (multipliers not resolved)" if kkt > CERTIFIED_KKT else ""))
        return (f"not certified: relative gap {gap:.2e} to the proven lower bound {float(c['lower_bound']):.6g}"
                + (f", KKT residual {kkt:.1e}" if "kkt_residual" in c else ""))

    def status(self, units: DisplayUnits | None = None) -> str:
        """Whether the design meets the requirement, in words; in budget mode first whether it is
        within the budget (``feasible`` then means within the budget and the bounds, issue 25).

        Parameters
        ----------
        units : DisplayUnits, optional
            Display units of the errors quoted (default: from the mechanism's ``display``).

        Returns
        -------
        str
            E.g. ``"meets the requirement"``, ``"misses the requirement (position ..., ...)"``,
            prefixed by ``"within budget ...; "`` or ``"over budget ...; "`` in budget mode.
        """
        u = units or problem_units(self.problem)
        if "meets_requirement" in self.info:
            meets = bool(self.info["meets_requirement"])
        elif "bound_ratio" in self.info:        # the rule of evotol.measures.feasibility
            meets = bool(self.info["bound_ratio"] <= 1 + feasibility.FEASIBILITY_RTOL)
        else:
            meets = bool(self.errors.violation[0] <= feasibility.FEASIBILITY_RTOL)
        misses = [f"{comp} {u.format(self.max_error(comp), error_unit(self.problem, comp))}, "
                  f"{100 * (self.max_error(comp) / lim - 1):.2g} % above {u.format(lim, error_unit(self.problem, comp))}"
                  for comp, lim in self.problem.components
                  if self.max_error(comp) > lim * (1 + feasibility.FEASIBILITY_RTOL)]
        req = "meets the requirement" if meets else "misses the requirement" + (f" ({', '.join(misses)})" if misses else "")
        if "budget" in self.info:
            return (f"{'within' if self.info.get('within_budget') else 'over'} budget {self.info['budget']:.5g}; {req}")
        return req if self.feasible or not meets else f"{req}; outside the tolerance bounds"

    def summary(self, units: DisplayUnits | None = None) -> str:
        """Cost, status, the largest errors (display units) with the worst pose in workspace
        coordinates, the yield for a yield design, and the certificate read as a sentence.

        Parameters
        ----------
        units : DisplayUnits, optional
            Display units (default: from the mechanism's ``display``, :func:`evotol.units.display.default_units`).

        Returns
        -------
        str
            Several lines of text.
        """
        u = units or problem_units(self.problem)
        lines = [f"{self.method}: cost {self.cost:.5g}; {self.status(u)}"]
        for comp, lim in self.problem.components:
            eu = error_unit(self.problem, comp)
            p = self.worst_pose(comp)
            lines.append(f"  max {comp} error {u.format(self.max_error(comp), eu)} (requirement {u.format(lim, eu)}) "
                         f"at pose {p}: {pose_text(self.problem.model.workspace, self.problem.poses[p])}")
        if self.errors.probability is not None:
            y = self.errors.probability[0]
            lines.append(f"  yield (first-order, lower bound) at the worst pose {float(np.min(y)):.6g} "
                         f"(required {self.problem.requirement.required_yield:g}) at pose {int(np.argmin(y))}")
        if self.verdict is not None:
            lines.append(f"  {self.verdict}")
        if self.certificate:
            lines.append("  certificate: " + ", ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}"
                                                    for k, v in self.certificate.items()))
        note = self.solver_note
        if note:
            lines.append(f"  note: {note}")
        lines += [f"  warning: {w}" for w in self.info.get("warnings", [])]
        return "\n".join(lines)

    @property
    def solver_note(self) -> str | None:
        """The solver's exit message read against the certificate (None without a message)."""
        msg = self.info.get("solver_message")
        if not msg:
            return None
        if self.verdict and self.verdict.startswith("certified optimal"):
            return (f"the solver's exit message \"{msg}\" says only that its line search could make no "
                    "further progress at its working precision; the proven lower bound certifies the cost")
        return f"the solver's exit message: \"{msg}\""

def make_result(problem: ToleranceProblem, method: str, t, *, evaluation: Evaluation | None = None, history=None,
                certificate=None, seconds: float = 0.0, info=None, budget: float | None = None) -> AllocationResult:
    """Wrap design ``t`` as an :class:`AllocationResult`: a design in, a result out.

    Pure: the design is reported as given (an allocator that holds its final design to the rule of
    :mod:`evotol.measures.feasibility` does so before, with
    :func:`evotol.measures.feasibility.hold_to_rule`), nothing is issued (the plausibility lines
    go in ``info["warnings"]``; the allocators issue them).

    Parameters
    ----------
    problem : ToleranceProblem
        The problem the design belongs to.
    method : str
        The allocator's name, as reports show it.
    t : mapping or ndarray
        The design (SI: m or rad).
    evaluation : Evaluation, optional
        The design's proven evaluation (:func:`evotol.measures.feasibility.evaluate_proven`, as
        ``hold_to_rule`` returns it); computed here when not given.
    history : pandas.DataFrame, optional
        The allocator's progress, stored as is.
    certificate : dict, optional
        Optimality evidence (``lower_bound``, ``gap``, ``kkt_residual``), stored as is.
    seconds : float
        Wall-clock time of the allocation (s).
    info : dict, optional
        Further entries; ``bound_ratio``, the budget entries and ``warnings`` are added to a copy.
    budget : float, optional
        Budget mode: ``feasible`` then means within the bounds and the budget, and whether the
        requirement is met is ``info["meets_requirement"]`` (issue 15: "feasible" must mean what it says).

    Returns
    -------
    AllocationResult
        ``feasible``: within the bounds and meeting the requirement by the rule of
        :mod:`evotol.measures.feasibility`; ``info["bound_ratio"]``: proven largest error / requirement;
        ``info["warnings"]``: :func:`evotol.core.plausibility.result_warnings`, when there are any.

    Raises
    ------
    evotol.errors.ValidationError
        A design ``t`` that is not one non-negative finite value per source.
    """
    t = np.asarray(problem.as_array(t), dtype=float)
    ev = feasibility.evaluate_proven(problem, t) if evaluation is None else evaluation
    info = dict(info or {})
    f = problem.free
    in_bounds = bool(np.all(t[f] >= problem.lower[f] * (1 - 1e-9)) and np.all(t[f] <= problem.upper[f] * (1 + 1e-9)))
    cost = float(problem.cost(t))
    ratio = feasibility.bound_ratio(problem, ev)
    meets = bool(ratio <= 1 + feasibility.FEASIBILITY_RTOL)
    info["bound_ratio"] = ratio
    if budget is None:
        feasible = meets and in_bounds
    else:
        within = bool(cost <= budget * (1 + 1e-9))
        feasible = within and in_bounds
        info.update({"budget": float(budget), "within_budget": within, "meets_requirement": meets})
    result = AllocationResult(method, problem, dict(zip(problem.names, t.tolist())), cost,
                              feasible, ev, history, certificate, seconds, info)
    lines = plausibility.result_warnings(problem, result)      # unit slips, an inactive requirement (issue 27)
    if lines:
        result.info["warnings"] = lines
    return result

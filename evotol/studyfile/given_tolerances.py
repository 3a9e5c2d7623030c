"""``evotol run`` on a study whose every tolerance is given: the analysis, not a refusal (issue 33).

When every source of a study file is ``fixed`` (or ``locked``), there is nothing to allocate; the
question is what those tolerances give. :func:`given_tolerances_outcome` analyses them
(:func:`evotol.verification.tolerance_analysis.analyse`: worst case of the norm and per axis with
both signed limits, RSS, the probability of meeting the requirement and the error at the
requirement's probability, Monte Carlo on the nonlinear model, contributions, the worst pose, the
joints used at every pose), prints it, and writes ``NAME.json`` and ``NAME.html``
(:func:`evotol.reporting.analysis_page.render_analysis`). ``[verify] n_samples`` (default 1000)
and ``seed`` set the Monte Carlo; ``[requirement] probability`` (default 0.9973) the quantile.
With ``[requirement] iso9283`` or ``[iso9283]`` the summary also carries the ``iso9283`` block and the page
its section, as for an allocation study: AP and RP predicted and simulated for the given tolerances, and
whether they meet the requirement on which model (docs/iso9283.md).
"""
from __future__ import annotations


import numpy as np

from evotol._runtime.keyword_checks import check_table_keys
from evotol.core import plausibility
from evotol.core.axis_limits import configurations
from evotol.errors import ValidationError
from evotol.reporting.analysis_page import render_analysis
from evotol.reporting.iso9283 import verdict_lines
from evotol.studyfile.iso9283 import iso9283_block
from evotol.studyfile.kinds import Outcome
from evotol.studyfile.steps import run_steps
from evotol.summaries.user_study import source_table, study_units_block
from evotol.units.display import DisplayUnits
from evotol.verification.tolerance_analysis import analyse
from evotol.robots.mechanism.posture.held import joint_table

#: the ``[verify]`` keys an analysis reads (the others belong to allocation studies)
VERIFY_KEYS = ("n_samples", "nonlinear")


def analysis_summary(name: str, problem, analysis, *, seed: int, units: DisplayUnits, seconds: float) -> dict:
    """The JSON-ready summary of an analysis study (SI, with the display units stored).

    Parameters
    ----------
    name : str
        The study's name.
    problem : evotol.core.problem.ToleranceProblem
        The problem (every tolerance given).
    analysis : evotol.verification.tolerance_analysis.ToleranceAnalysis
        Its analysis.
    seed : int
        The Monte Carlo seed.
    units : DisplayUnits
        Display units of the page and the terminal.
    seconds : float
        Wall time, s.

    Returns
    -------
    dict
        ``kind = "analysis"``, the problem text, workspace, sources (with their given tolerance),
        ``analysis`` (:meth:`ToleranceAnalysis.to_dict`), ``joints`` (wrapped to (-π, π] for
        revolute joints) and the ``units`` block.
    """
    axis = problem.model.part_of("axis_limits")
    robot = configurations(problem.model, problem.poses)[0] if axis is not None else problem.model
    ws = robot.workspace
    d = analysis.to_dict()
    joints = joint_table(robot, analysis.poses)
    lim = axis.limits if axis is not None else None
    axis_limits = {"frame": lim.frame, "position": dict(lim.position), "orientation": dict(lim.orientation)} if lim else {}
    sources = source_table(problem)
    for row, t in zip(sources, analysis.t):
        row["tolerance"] = float(t)
    return {"name": name, "kind": "analysis", "problem": problem.describe(), "seed": seed, "robot": problem.model.name,
            "measure": problem.requirement.measure, "requirement": {c: v for c, v in problem.components},
            "axis_limits": axis_limits,
            "display_units": units.to_dict(),
            "workspace": {"names": list(ws.names), "units": list(ws.units), "display_units": list(ws.display_units),
                          "display_scale": list(ws.display_scale)},
            "poses": np.asarray(analysis.poses).tolist(), "sources": sources, "analysis": d, "joints": joints,
            "notes": list(problem.model.notes()), "seconds": seconds, "units": study_units_block(problem)}


def requirement_text(summary: dict, u: DisplayUnits) -> str:
    """The requirement in words: per-axis limits with their frame, or the norm bounds.

    Parameters
    ----------
    summary : dict
        :func:`analysis_summary`.
    u : DisplayUnits
        Display units.

    Returns
    -------
    str
        E.g. ``"|dx| <= 300.0 µm, |dz| <= 500.0 µm (tool frame)"`` or ``"position <= 500.0 µm"``.
    """
    al = summary.get("axis_limits") or {}
    if al:
        parts = [f"|d{a}| <= {u.format(v, 'm')}" for a, v in al["position"].items()]
        parts += [f"|dθ{a}| <= {u.format(v, 'rad')}" for a, v in al["orientation"].items()]
        return ", ".join(parts) + f" ({al['frame']} frame)"
    return ", ".join(f"{c} <= {u.format(v, 'm' if c == 'position' else 'rad')}" for c, v in summary["requirement"].items())


def analysis_lines(summary: dict):
    """The analysis as terminal lines, in the study's display units (one line per pose); the
    command prints them (the library never prints: issue 40).

    Parameters
    ----------
    summary : dict
        :func:`analysis_summary`.

    Yields
    ------
    str
        One line of the analysis, without its newline.
    """
    u = DisplayUnits(**summary["display_units"])
    a = summary["analysis"]
    L = lambda v: u.format(v, "m")          # noqa: E731
    req = requirement_text(summary, u)
    verdict = "meets" if a["meets"] else "MISSES"
    yield (f"[evotol] analysis of the given tolerances (every source given: nothing to allocate)")
    yield (f"  requirement ({summary['measure']}): {req}: the design {verdict} it (largest error / limit = "
          f"{a['violation'] + 1:.4g})")
    wc, ax = a["worst_case"]["position"], a["axes"]["base"]["position"]
    names = summary["workspace"]["names"]
    per_axis = a.get("probability_axes") or {}          # per-axis limits: P(meet) per axis (issue 41)
    p_heads = [f"P({k})" for k in per_axis] if per_axis else (["P(meet)"] if a.get("probability") is not None else [])
    yield (f"  {'pose':>4s}  {'worst |dp|':>11s}  {'x range':>21s}  {'y range':>21s}  {'z range':>21s}  {'RSS |dp|':>10s}"
           + "".join(f"  {h:>8s}" for h in p_heads))
    for i in range(len(wc["value"])):
        rng = "  ".join(f"{'[' + L(ax[k]['low'][i]).split()[0] + ', ' + L(ax[k]['high'][i]).split()[0] + ']':>21s}" for k in "xyz")
        probs = [v[i] for v in per_axis.values()] if per_axis else (
            [a["probability"][i]] if p_heads and len(a["probability"]) == len(wc["value"]) else [])
        yield (f"  {i:4d}  {L(wc['value'][i]):>11s}  {rng}  {L(a['rss']['position'][i]):>10s}"
               + "".join(f"  {v:8.5f}" for v in probs))
    if "tool" in a["axes"]:
        tx = a["axes"]["tool"]["position"]
        for i in range(len(wc["value"])):
            yield (f"  {i:4d}  tool frame: " + "  ".join(f"d{k} [{L(tx[k]['low'][i]).split()[0]}, {L(tx[k]['high'][i])}]" for k in "xyz"))
    p = wc["worst_pose"]
    pose = summary["poses"][p]
    shown = ", ".join(f"{n} = {v * k:.4g}" for n, v, k in zip(names, pose, summary["workspace"]["display_scale"]))
    yield (f"  worst pose #{p} ({shown}): |dp| <= {L(wc['value'][p])} (proven bound {L(wc['bound'][p])})")
    top = sorted(wc["contributions"].items(), key=lambda kv: -kv[1])[:5]
    yield ("  contributions there: " + ", ".join(f"{n} {v:.1f} %" for n, v in top))
    ap = a.get("error_at_probability", {})
    if ap:
        yield (f"  |dp| at probability {ap['probability']:.4g} (first-order, stated distributions): largest "
              f"{L(max(ap['position']))}")
    mc = a.get("monte_carlo", {})
    if mc:
        yield (f"  Monte Carlo ({mc['n_samples']} samples per pose): exceed rate {100 * mc['max_exceed_rate']:.3g} % (linear)"
              + (f", {100 * mc['max_exceed_rate_nonlinear']:.3g} % (nonlinear)" if mc.get("max_exceed_rate_nonlinear") is not None else "")
              + (f"; {mc['linearisation_verdict']}" if mc.get("linearisation_verdict") else ""))
    for line in verdict_lines(summary):       # ISO 9283: the verdict and its model (as an allocation study's)
        yield f"  ISO 9283 {line}"
    for line in summary.get("notes", []):
        yield (f"  note: {line}")


def given_tolerances_outcome(study, problem, units: DisplayUnits, iso=None) -> Outcome:
    """Analyse a study whose every tolerance is given (module docstring): one step, ``analysis``.

    Parameters
    ----------
    study : evotol.studyfile.kinds.Study
        The run (its file, seed and Ctrl-C).
    problem : evotol.core.problem.ToleranceProblem
        Its problem (every source fixed or locked).
    units : DisplayUnits
        Display units.
    iso : evotol.studyfile.iso9283.IsoStudy or None
        The study's ISO 9283 request: its figures for the given tolerances (and, with ``allocate``, the
        random sources allocated beside them) as a second step, the same ``iso9283`` block and page
        section as an allocation study (docs/iso9283.md).

    Returns
    -------
    evotol.studyfile.kinds.Outcome
        The summary (:func:`analysis_summary`, with ``warnings``) and its page.

    Raises
    ------
    evotol.errors.ValidationError
        A ``[verify]`` key other than ``n_samples`` and ``nonlinear``; ``[poses] refine`` (the
        analysis checks the poses listed; refinement belongs to an allocation, issue 39).
    KeyboardInterrupt
        A Ctrl-C stopped the analysis: there is nothing to write.
    """
    spec, seed = study.spec, study.seed
    vspec = dict(spec.get("verify", {}))
    check_table_keys(vspec, VERIFY_KEYS, "verify")
    if spec.get("poses", {}).get("refine"):
        raise ValidationError("poses.refine", spec["poses"]["refine"], "no refine when every tolerance is given: the "
                              "analysis of given tolerances checks the poses listed and does not search the workspace "
                              "for a worse one (give a finer grid or a Latin hypercube)")
    prob = problem.requirement.required_yield
    steps = {"analysis": lambda: analyse(problem, probability=float(prob), n_samples=int(vspec.get(
        "n_samples", 1000)), seed=seed, nonlinear=bool(vspec.get("nonlinear", True)))}
    if iso is not None:             # ISO 9283 AP/RP of the given tolerances (issue 44)
        steps["iso9283"] = lambda: iso9283_block(iso, problem, {}, seed)
    done = run_steps(steps, study.ctrl_c, study.log)
    if "analysis" not in done:
        raise KeyboardInterrupt     # the first step stopped: no analysis to write
    summary = analysis_summary(study.name, problem, done["analysis"], seed=seed, units=units, seconds=study.seconds())
    if "iso9283" in done:
        summary["iso9283"] = done["iso9283"]
    summary["warnings"] = plausibility.problem_warnings(problem)
    if "methods" in spec:
        summary["notes"].append(f"[methods] {sorted(spec['methods'])} not run: every tolerance is given, so there is "
                                "nothing to allocate; this is their analysis.")
    return Outcome(summary, render_analysis)

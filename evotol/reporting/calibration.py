"""The "What calibration buys" section of a calibrated study's report, from its JSON summary alone.

Reads ``summary["calibration"]`` (:func:`evotol.calibration.summary.calibration_summary`): the plan
and its identification (base set, condition number, unseen sources, why sources were dropped),
the noise's share of the requirement, the uncalibrated optimum's cost beside each calibrated
design's, the tolerances side by side per source (identified, freed, still driving the error,
capped by the linear or compensation range), and the simulated calibration beside the first-order
prediction (``docs/calibration.md``). :func:`terminal_lines` states the same for the terminal.

The parameters several definitions of this module share are described once, here.

Parameters
----------
summary : dict
    A user study's JSON summary with a ``calibration`` block (SI values).
"""
from __future__ import annotations

from evotol.units.display import DisplayUnits

_RULES = {"linear": "the quantile and the second-order terms taken off the bound (worst-case measures)",
          "quadrature": "the quantile added in quadrature, the second-order terms taken off (rss)",
          "covariance": "its covariance added to the yield model (exact for normal sources)"}


def _fmt(summary: dict, value, unit: str) -> str:
    if value is None:
        return "–"
    return DisplayUnits(**summary["display_units"]).format(value, unit)


def plan_text(summary: dict) -> str:
    """The calibration plan and its identification in one sentence (the page's and the terminal's).

    Returns
    -------
    str
        Configurations, what is measured, the noise, the base set and its condition number.
    """
    plan = summary["calibration"]["plan"]
    idn = plan["identification"]
    ident = ("every identifiable source" if plan["identify"] == "identifiable" else ", ".join(plan["identify"]))
    return (f"Calibration plan: {idn['n_configurations']} configurations, {' and '.join(plan['measure'])} measured "
            f"({idn['n_measurements']} coordinates), noise sigma "
            + "; ".join(f"{c} " + ", ".join(_fmt(summary, v, 'm' if c == 'position' else 'rad') for v in s)
                        for c, s in plan["noise_sigma"].items())
            + f", instrument frame {plan['instrument']}; identified: {ident}. Base set kept: "
            f"{idn['n_identified']} sources" + (f" and registration {', '.join(idn['registration'])}" if idn["registration"] else "")
            + f" ({idn['rank']} identifiable directions: the rank of the measured columns that move a reading); "
            f"condition number {idn['condition_number']:.3g}.")


def noise_texts(summary: dict) -> list[str]:
    """The noise's share of each requirement component, one sentence each.

    Returns
    -------
    list of str
        The propagated sigma, the noise's quantile at the plan's level, the second-order terms and the
        geometric share.
    """
    plan = summary["calibration"]["plan"]
    out = []
    for comp, n in plan["noise"].items():
        if not isinstance(n, dict):
            continue
        u = "m" if comp == "position" else "rad"
        rnd = "random_worst_case" in n        # random sources in the calibrated budget (issue 44 item 4)
        out.append(f"Noise share of the {comp} requirement {_fmt(summary, n['bound'], u)}: largest propagated sigma "
                   f"{_fmt(summary, n['sigma'], u)} ({plan['k']:g} sigma = {_fmt(summary, n.get('k_sigma', 0.0), u)}); "
                   f"{'the norm of the fit error (noise and random sources)' if rnd else 'the noise' + chr(39) + 's norm'} "
                   f"at a pose stays below {_fmt(summary, n['allowance'], u)} with probability "
                   f"{100 * n['coverage']:.2f} % (its quantile from the propagated covariance); second-order terms: "
                   f"{_fmt(summary, n['second_order'], u)} of the noise-driven corrections and "
                   f"{_fmt(summary, n.get('remainder', 0.0), u)} of the sources within their upper bounds; "
                   f"{_RULES[plan['noise']['rule']]}. The tolerances hold the geometric share "
                   f"{_fmt(summary, n['geometric_bound'], u)} (the requirement shown in the results table).")
        if rnd:
            out.append(_random_sentence(summary, plan, n, u))
    return out


def _random_sentence(summary: dict, plan: dict, n: dict, u: str) -> str:
    """What the random sources take of a calibrated requirement, and what they cost when allocated."""
    text = (f"Random sources ({len(plan.get('random_sources', {}))}, repeatability: calibration cannot remove them): "
            f"through the fit they raise that quantile from {_fmt(summary, n['noise_only'], u)} (noise alone) by "
            f"{_fmt(summary, n['random_identification'], u)}, and at a pose they add at most "
            f"{_fmt(summary, n['random_worst_case'], u)} (proven worst case), taken off the bound with it.")
    al = plan.get("random_allocation")
    if al:
        text += (f" They are {al['meaning']}; "
                 f"they cost {al['cost']:.4g}; the requirement {'binds' if al['active'] else 'does not bind'} "
                 f"(fit quantile + worst case {_fmt(summary, al['quantile'] + al['worst_case'], u)} of "
                 f"{_fmt(summary, al['budget'], u)} left for them).")
    poses = summary.get("iso9283", {}).get("poses", [])
    if poses and "calibrated" in poses[0]:
        ap = max(p["calibrated"]["AP"]["predicted"] for p in poses)
        rp = max(p["calibrated"]["RP"]["predicted"] for p in poses)
        text += (f" ISO 9283 after calibration (first order, largest over P1-P5): AP {_fmt(summary, ap, u)} "
                 f"(uncalibrated {_fmt(summary, max(p['AP']['predicted'] for p in poses), u)}), RP {_fmt(summary, rp, u)} "
                 "(unchanged).")
        req = summary["iso9283"].get("requirement", {})
        if al and al.get("iso"):        # the ISO requirement allocated in the calibrated budget (docs/iso9283.md)
            bind = ", ".join(k for k, v in al["iso"]["active"].items() if v) or "neither"
            text += (f" The random sources are allocated to AP <= {_fmt(summary, req.get('AP'), u)} and RP <= "
                     f"{_fmt(summary, req.get('RP'), u)} there too; binding: {bind}.")
    return text


def terminal_lines(summary: dict) -> list[str]:
    """What the page's calibration section states, as terminal lines (issue 41: a calibrated study
    printed nothing of its calibration).

    Parameters
    ----------
    summary : dict
        A user study's JSON summary; no lines without a ``calibration`` block.

    Returns
    -------
    list of str
        The plan, the noise share, the costs beside the uncalibrated optimum, the sources still
        driving the error and the simulated calibration, each line indented by two spaces after
        the first.
    """
    cal = summary.get("calibration")
    if not cal:
        return []
    out = ["[evotol] calibration (docs/calibration.md)", "  " + plan_text(summary)]
    if cal["plan"]["identification"]["unseen"]:
        out.append("  unseen by the instrument: " + ", ".join(cal["plan"]["identification"]["unseen"]))
    out += ["  " + line for line in noise_texts(summary)]
    out.append(f"  uncalibrated optimum cost {cal['uncalibrated']['cost']:.6g}; " + "; ".join(
        f"calibrated {m} {e['cost']:.6g}" + (f" ({100 * e['saving']:.1f} % saved" if e["saving"] is not None else " (")
        + f", {e['n_freed']} sources freed)" for m, e in cal["methods"].items()))
    for m, e in cal["methods"].items():
        top = sorted(((n, v) for n, v in e["effect_share_percent"].items() if v > 0), key=lambda kv: -kv[1])[:5]
        if top:
            out.append(f"  {m}: still driving the error after calibration: " + ", ".join(f"{n} {v:.1f} %" for n, v in top))
        c = e.get("simulation")
        for comp in (c or {}).get("simulated", {}):
            u = "m" if comp == "position" else "rad"
            out.append(f"  {m}: simulated calibration ({c['n_samples']} robots, nonlinear): max {comp} error "
                       f"{_fmt(summary, c['simulated'][comp]['max'], u)} (first-order {_fmt(summary, c['predicted'][comp]['max'], u)}), "
                       f"exceed rate {c['exceed_rate_' + comp]:.2%}, {c['n_fit_failures']} fit failures")
    return out


def calibration_section(rep, summary: dict) -> None:
    """Append the calibration section to a user study's report (module docstring).

    Parameters
    ----------
    rep : evotol.reporting.html.Report
        The page being built.
    """
    cal = summary["calibration"]
    plan = cal["plan"]
    idn = plan["identification"]
    rep.heading("What calibration buys")
    rep.text(plan_text(summary) + " Tolerances are allocated on the error left after the controller compensates the "
             "identified sources, e = (J − J_K A_K⁺ A) δp (docs/calibration.md).")
    if idn["unseen"]:
        rep.text("Sources the instrument cannot see (they move no measured coordinate at any configuration): "
                 + ", ".join(idn["unseen"]) + ".", note=True)
    for line in noise_texts(summary):
        rep.text(line)
    rows = [["uncalibrated optimum", cal["uncalibrated"]["cost"], "–", "–"]]
    for m, e in cal["methods"].items():
        rows.append([f"calibrated {m}", e["cost"], f"{100 * e['saving']:.1f} %" if e["saving"] is not None else "–",
                     e["n_freed"]])
    rep.table(rows, ["design", "cost", "saving", "sources freed"], table_id="calibration-costs")
    m = "optimum" if "optimum" in cal["methods"] else next(iter(cal["methods"]), None)
    if m is None:
        return
    e = cal["methods"][m]
    tol = e["tolerances"]
    share = e["effect_share_percent"]
    units = summary["units"]["tolerances"]
    srows = []
    for n in sorted(tol["calibrated"], key=lambda n: -share.get(n, 0.0)):
        srows.append([n, _fmt(summary, tol["uncalibrated"][n], units[n]), _fmt(summary, tol["calibrated"][n], units[n]),
                      "yes" if n in e["identified"] else "", "freed" if n in e["freed"] else "",
                      f"{share.get(n, 0.0):.1f}", e["capped_by"].get(n, "")])
    if not any(share.values()):
        rep.text("The calibration removes every first-order effect of the sources at the task poses: what is left "
                 "to pay for is the noise, the second-order terms (the linear-range bounds) and what the model does "
                 "not contain.", note=True)
    rep.text(f"Tolerances side by side (uncalibrated optimum vs calibrated {m}), sorted by their share of the "
             "first-order error left after calibration at the worst pose: the first rows still drive the error; "
             f"'freed' marks a tolerance at least 1.5 times the uncalibrated one. A source's upper bound is capped "
             f"by the identification's linear range (second-order terms below {100 * plan['linear_fraction']:g} % "
             "of the requirement) or the controller's compensation range.")
    rep.table(srows, ["source", "uncalibrated", "calibrated", "identified", "freed", "share after calibration (%)",
                      "capped by"], table_id="calibration-sources")
    checks = {k: v["simulation"] for k, v in cal["methods"].items() if "simulation" in v}
    if checks:
        crow = []
        for k, c in checks.items():
            for comp in c["simulated"]:
                u = "m" if comp == "position" else "rad"
                crow.append([k, comp, c["n_samples"], _fmt(summary, c["simulated"][comp]["max"], u),
                             _fmt(summary, c["predicted"][comp]["max"], u),
                             _fmt(summary, c["simulated"][comp]["quantile"], u), _fmt(summary, c["predicted"][comp]["quantile"], u),
                             _fmt(summary, c["difference"][comp], u), _fmt(summary, c["worst_case"][comp], u),
                             f"{c['exceed_rate_' + comp]:.2%}", c["n_fit_failures"]])
        rep.text("Simulated calibration (nonlinear model): robots drawn within the tolerances, readings with noise, "
                 "nonlinear least squares, compensation by the actuators, residual at the task poses -- beside the "
                 "first-order prediction for the same robots (the quantile is of each robot's worst pose).")
        rep.table(crow, ["design", "component", "robots", "simulated max", "first-order max",
                         f"simulated q{round(100 * next(iter(checks.values()))['quantile_level'])}",
                         f"first-order q{round(100 * next(iter(checks.values()))['quantile_level'])}", "largest difference",
                         "first-order worst case + noise quantile + second order", "exceed rate", "fit failures"], table_id="calibration-check")

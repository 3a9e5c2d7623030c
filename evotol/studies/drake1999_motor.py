"""The motor assembly of the Dimensioning & Tolerancing Handbook (Drake 1999, ch. 9): an
eleven-dimension gap with one-sided and unequal tolerances, analysed as the handbook does
(worst case, RSS, modified RSS) and with a stated six-sigma model (Cp, Cpk, fractions outside).

Data: ``evotol/studies/data/motor_assembly_handbook.json`` -- the handbook's inputs "as coded in the
open-source dimstack test suite (phcreery/dimstack, tests/test_McGrawHill.py, class
McGrawHill_1)"; the published figures compared here are the ones that test suite asserts for the
handbook (worst case, RSS, MRSS). The source gives no limits for the gap: LSL = 0 and
USL = 0.120 in are evotol's choice (so Cp, Cpk and the fractions outside cannot be compared with
a published value). Conventions: :mod:`evotol.measures.stack_analysis` and ``docs/stack_analysis.md``.
"""
from __future__ import annotations

import json
from importlib import resources

from evotol.measures.stack_analysis import Stack, StackDimension, StackModel, analyse_stack, fraction_outside
from evotol.reporting.stack_report import render_stack
from evotol.summaries.stack import stack_units_block
from evotol.studies import Study, StudyResult

INCH = 0.0254
CONFIG = {"seed": 0, "n_mc": 1_000_000, "lower_limit_in": 0.0, "upper_limit_in": 0.120}
QUICK = {"n_mc": 100_000}
SOURCE = ("P. J. Drake (ed.), Dimensioning and Tolerancing Handbook, McGraw-Hill 1999, ch. 9, the motor assembly; "
          "inputs and the figures below as coded in the dimstack test suite (phcreery/dimstack, "
          "tests/test_McGrawHill.py, class McGrawHill_1)")
#: the handbook's figures as the dimstack test suite asserts them (in): key -> (label, value, computed key)
PUBLISHED = [("mean gap", "0.0615", ("mean",)),
             ("worst case, lower", "-0.034", ("worst_case", "limits", 0)),
             ("worst case, upper", "0.157", ("worst_case", "limits", 1)),
             ("worst case, ±", "0.0955", ("worst_case", "half_width")),
             ("RSS, ±", "0.03808", ("rss", "half_width")),
             ("RSS, lower", "0.02342", ("rss", "limits", 0)),
             ("RSS, upper", "0.09958", ("rss", "limits", 1)),
             ("MRSS, ±", "0.05047", ("mrss", "half_width")),
             ("MRSS, lower", "0.011", ("mrss", "limits", 0)),
             ("MRSS, upper", "0.112", ("mrss", "limits", 1))]
MODELS = {"rss (t = 3σ normal)": StackModel(),
          "six sigma, dynamic (Cp = 2, 1.5σ shift)": StackModel(2.0, 0.25, "dynamic"),
          "six sigma, static (Cp = 2, 1.5σ shift)": StackModel(2.0, 0.25, "static")}


def handbook_data() -> dict:
    """The data file (``evotol/studies/data/motor_assembly_handbook.json``).

    Returns
    -------
    dict
        Its contents: ``source``, ``units`` (inch), ``convention``, ``dimensions``.
    """
    return json.loads(resources.files("evotol.studies").joinpath("data/motor_assembly_handbook.json").read_text(encoding="utf-8"))


def motor_stack(lower_in: float | None, upper_in: float | None, distribution: str = "normal") -> Stack:
    """The motor assembly's stack in SI (m): each length in [nominal − minus, nominal + plus],
    ``direction`` its sign in the loop; G and H are second parts made to E's and D's drawings.

    Parameters
    ----------
    lower_in, upper_in : float or None
        The gap's limits (in).
    distribution : str
        Every dimension's distribution (``"normal"``, ``"uniform"``, ``"triangular"``).

    Returns
    -------
    Stack
        The stack (m).
    """
    d = handbook_data()
    dims = tuple(StackDimension(x["name"], x["nominal"] * INCH, x["plus"] * INCH, -x["minus"] * INCH,
                                float(x["direction"]), distribution, x.get("same_part_as")) for x in d["dimensions"])
    return Stack(dims, "gap", None if lower_in is None else lower_in * INCH, None if upper_in is None else upper_in * INCH,
                 "m")


def _pick(d, path):
    for k in path:
        d = d[k]
    return d


def compute(config: dict) -> StudyResult:
    """Analyse the motor assembly and compare with the handbook's figures.

    Parameters
    ----------
    config : dict
        ``seed``, ``n_mc`` (Monte Carlo samples of the uniform-input check), ``lower_limit_in``,
        ``upper_limit_in`` (the gap's limits, in).

    Returns
    -------
    StudyResult
        ``summary``: ``stack`` (the analysis, SI), ``display`` (inch, 0.0001 in), ``published``
        (each figure beside evotol's, SI), ``uniform_inputs`` (fractions outside with every
        dimension uniform, Monte Carlo with Clopper–Pearson intervals), ``units``.
    """
    lo, hi = config["lower_limit_in"], config["upper_limit_in"]
    st = analyse_stack(motor_stack(lo, hi), MODELS, seed=config["seed"]).to_dict()
    figures = []
    for label, pub, path in PUBLISHED:
        value_in = _pick(st, path) / INCH
        digits = len(pub.split(".")[1])                  # the published figure's last digit
        figures.append({"figure": label, "published": pub, "computed": _pick(st, path),
                        "difference_in": round(value_in - float(pub), 6) + 0.0,
                        "agrees": bool(abs(value_in - float(pub)) <= 0.5 * 10 ** -digits + 1e-12),
                        "note": f"agrees to the published {digits} decimals" if abs(value_in - float(pub))
                        <= 0.5 * 10 ** -digits + 1e-12 else f"differs by {value_in - float(pub):+.2g} in"})
    uni = fraction_outside(motor_stack(lo, hi, "uniform"), StackModel(), n_samples=int(config["n_mc"]),
                           seed=config["seed"])
    summary = {"name": "drake1999-motor", "stack": st, "display": {"unit": "in", "precision": 1e-4},
               "seed": config["seed"], "units": stack_units_block({"difference_in": "in"}),
               "published": {"source": SOURCE, "figures": figures},
               "uniform_inputs": uni,
               "notes": [f"The source gives no limits for the gap: LSL = {lo:g} in and USL = {hi:g} in are evotol's "
                         "choice, so Cp, Cpk and the fractions outside have no published counterpart.",
                         "G and H are second parts made to E's and D's drawings: independent values, as the handbook "
                         "counts them (n = 11 in the MRSS factor).",
                         f"With every dimension uniform over its zone instead of normal (t = 3σ), Monte Carlo "
                         f"({uni['n_samples']} samples) finds {uni['below']:.3g} below LSL and {uni['above']:.3g} above "
                         "USL: the RSS verdict and this check are made on different models, stated here."]}
    return StudyResult(summary)


def render(result: StudyResult):
    """The page (:func:`evotol.reporting.stack_report.render_stack`).

    Parameters
    ----------
    result : StudyResult
        Output of :func:`compute`.

    Returns
    -------
    evotol.reporting.html.Report
        The HTML report.
    """
    return render_stack(result.summary, "Motor assembly (Drake 1999, ch. 9): worst case, RSS, MRSS, Cp/Cpk")


STUDY = Study(name="drake1999-motor", title="Motor assembly stack: worst case, RSS, modified RSS, Cp/Cpk",
              compute=compute, render=render, config=CONFIG, quick=QUICK,
              seed_paper="Drake (ed.), Dimensioning and Tolerancing Handbook, McGraw-Hill 1999, ch. 9")

"""5-bar tolerance synthesis (Deng 2012, Sec. VII.1.2, Figs. VII.2-VII.8), and NSGA-II beyond it.

Entries: the radial clearance Δb_xy of the five joints A, C (leg 1) and B, D, E (leg 2) on four
levels (1e-4, 1e-3, 1e-2, 1e-1 mm) and the axial clearance Δb_z on two (1e-3, 1e-1 mm):
4^5 x 2^5 = 32 768 entries. The tilt clearance follows the radial one through eq. III.2,
Δβ_xy = Δb_xy / h, with the joint length h = 10 mm (the thesis does not state h; 10 mm
reproduces its largest rotational error, 1.38 deg -- the study reports the h that would match
it exactly). Rotation about the axis: Δβ_z = 0 for the actuated A, B (locked) and 0.2 rad for
the passive C, D, E (idle motion, Sec. IV.3). Dimensions Tab. IV.2, working mode of
:mod:`evotol.robots.fivebar`, pose (0, 70) mm.

Objectives per entry: the global maximum positional error ``p_max_mm`` and rotational error
``r_max_deg`` of the closed-loop 5-bar (eqs. III.26-III.27), certified by the support-function
engine of :mod:`evotol.robots.clearance` (``p_upper_mm``/``r_upper_deg`` are the certified bounds), and
the manufacturing ``cost`` of the ten clearances under a reciprocal cost-tolerance model
(illustrative: the thesis has no cost; NSGA-II needs one).

The study evaluates the full factorial (resumable chunks on all local cores, or a Dask cluster),
reads off the thesis's 1000-entry random sample, applies the six filters of Figs. VII.3-VII.8 as
presets, derives the qualitative findings from main effects and kept level sets, runs NSGA-II on
continuous tolerances (cost vs p_max vs r_max) and draws everything in one parallel-coordinate
report.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from evotol import design as doe
from evotol.design import Factor, Objective
from evotol.errors import EvotolError
from evotol._runtime.executor import scheduler_of
from evotol.design.filtering import DesignStudy, Preset
from evotol.studies import Study, StudyResult
from evotol.studies._design_report import PRESET_HEADER, parcoords_counts, parcoords_section
from evotol.units import MM

NAME = "deng2012-tolsynth"
JOINTS = ("A", "C", "B", "D", "E")
#: thesis names (leg, joint) and whether the joint is actuated (Fig. IV.4)
THESIS_JOINT = {"A": "(1,1)", "C": "(1,2)", "B": "(2,1)", "D": "(2,2)", "E": "(2,3)"}
ACTIVE = {"A": True, "C": False, "B": True, "D": False, "E": False}
LEVELS_XY_MM = (1e-4, 1e-3, 1e-2, 1e-1)
LEVELS_Z_MM = (1e-3, 1e-1)
POSE_MM = (0.0, 70.0)
H_MM = 10.0
#: Fig. VII.2: ranges over the thesis's 1000 entries
THESIS_RANGES = {"p_max_mm": (0.0038, 1.41), "r_max_deg": (0.0024, 1.38)}


def factors() -> list[Factor]:
    """Δb_xy (4 levels) and Δb_z (2 levels) of the five joints, in mm (Sec. VII.1.2).

    Returns
    -------
    list of evotol.design.Factor
        Ten log-scaled factors ``db_xy_<joint>_mm`` (levels 1e-4, 1e-3, 1e-2, 1e-1 mm) then
        ``db_z_<joint>_mm`` (1e-3, 1e-1 mm), joints in the order A, C, B, D, E; ``si_scale``
        1e-3 (mm to m).
    """
    out = []
    for j in JOINTS:
        kind = "act." if ACTIVE[j] else "pas."
        out.append(Factor(f"db_xy_{j}_mm", LEVELS_XY_MM, log=True, si_scale=MM, group="radial",
                          label=f"Δb_xy {j}{THESIS_JOINT[j]} {kind} (mm)"))
    for j in JOINTS:
        kind = "act." if ACTIVE[j] else "pas."
        out.append(Factor(f"db_z_{j}_mm", LEVELS_Z_MM, log=True, si_scale=MM, group="axial",
                          label=f"Δb_z {j}{THESIS_JOINT[j]} {kind} (mm)"))
    return out


def presets() -> list[Preset]:
    """The filters of Figs. VII.3-VII.8.

    Returns
    -------
    list of evotol.design.filtering.Preset
        Six filters on ``p_max_mm`` (mm: >= 1, <= 0.05, <= 0.01) and ``r_max_deg`` (deg: >= 1,
        <= 0.05, <= 0.01).
    """
    return [Preset("p_max ≥ 1 mm", {"p_max_mm": (1.0, None)}, "Fig. VII.3"),
            Preset("p_max ≤ 0.05 mm", {"p_max_mm": (None, 0.05)}, "Fig. VII.4"),
            Preset("p_max ≤ 0.01 mm", {"p_max_mm": (None, 0.01)}, "Fig. VII.5"),
            Preset("r_max ≥ 1°", {"r_max_deg": (1.0, None)}, "Fig. VII.6"),
            Preset("r_max ≤ 0.05°", {"r_max_deg": (None, 0.05)}, "Fig. VII.7"),
            Preset("r_max ≤ 0.01°", {"r_max_deg": (None, 0.01)}, "Fig. VII.8")]


def default_cost_model():
    """Reciprocal cost per clearance, c = 1 + 1/(t / 1 µm) (evotol.cost_models.ReciprocalCost):
    a 0.1 µm fit costs 11 units, a 100 µm one 1.01 -- an illustrative shop model.

    Returns
    -------
    evotol.cost_models.ReciprocalCost
        ``ReciprocalCost(1.0, 1.0, scale=1e-6)``: takes a clearance in m, returns cost units.
    """
    from evotol.cost_models import ReciprocalCost

    return ReciprocalCost(1.0, 1.0, scale=1e-6)


_CACHE: dict = {}


@dataclass(frozen=True)
class FiveBarToleranceEvaluator:
    """Evaluates entries (DataFrame of ``db_xy_*_mm``, ``db_z_*_mm``) at one pose, vectorised.

    pose_mm: end-effector position (mm); h_mm: joint length of eq. III.2 (mm); beta_z_passive /
    beta_z_active: Δβ_z (rad); tol: relative certificate gap of the engine.
    Returns ``p_max_mm, r_max_deg, p_upper_mm, r_upper_deg, cost``.

    Parameters
    ----------
    pose_mm : tuple of float, optional
        End-effector position (x, y), mm; default (0, 70) mm.
    h_mm : float, optional
        Joint length h of eq. III.2 (Δβ_xy = Δb_xy / h), mm; default 10 mm.
    beta_z_passive : float, optional
        Rotational clearance Δβ_z about the axis of the passive joints C, D, E, rad; default 0.2.
    beta_z_active : float, optional
        Δβ_z of the actuated joints A, B, rad; default 0 (locked).
    tol : float, optional
        Relative certificate gap of the clearance engine (dimensionless); default 1e-3.
    """

    pose_mm: tuple[float, float] = POSE_MM
    h_mm: float = H_MM
    beta_z_passive: float = 0.2
    beta_z_active: float = 0.0
    tol: float = 1e-3

    def _model(self):
        """The engine's ClearanceEvaluator at the pose (maps computed once per process)."""
        key = (self.pose_mm, self.beta_z_passive, self.beta_z_active, self.tol)
        if key not in _CACHE:
            from evotol.robots.clearance import ClearanceEvaluator
            from evotol.robots.fivebar import FiveBar

            mech = FiveBar().clearance_mechanism(beta_z_passive=self.beta_z_passive, beta_z_active=self.beta_z_active)
            _CACHE[key] = ClearanceEvaluator(mech, [[self.pose_mm[0] * MM, self.pose_mm[1] * MM]], tol=self.tol)
        return _CACHE[key]

    def bounds(self, X: pd.DataFrame) -> np.ndarray:
        """Clearance bounds (n, 5, 4) [Δβ_xy, Δβ_z, Δb_xy, Δb_z] (rad, m) in the engine's joint order;
        Δβ_xy = Δb_xy / h (eq. III.2), Δβ_z by the thesis's actuated/passive convention.

        Parameters
        ----------
        X : pandas.DataFrame
            Entries (n rows) with the columns ``db_xy_<joint>_mm`` and ``db_z_<joint>_mm``, mm.

        Returns
        -------
        (n, 5, 4) ndarray
            Per entry and joint: Δβ_xy (rad), Δβ_z (rad), Δb_xy (m), Δb_z (m).

        Raises
        ------
        EvotolError
            If the engine's 5-bar joints are not actuated as in Fig. IV.4 (A and B actuated).
        """
        mech = self._model().mech
        names = [j.name for j in mech.joints]
        if {j.name: j.active for j in mech.joints} != {j: ACTIVE[j] for j in names}:
            raise EvotolError(f"5-bar joints {names} are not actuated as in Fig. IV.4 ({ACTIVE})")
        bxy = X[[f"db_xy_{j}_mm" for j in names]].to_numpy(float) * MM
        bz = X[[f"db_z_{j}_mm" for j in names]].to_numpy(float) * MM
        return mech.thesis_bounds(b_xy=bxy, b_z=bz, h=self.h_mm * MM, beta_z_passive=self.beta_z_passive,
                                  beta_z_active=self.beta_z_active)

    def __call__(self, X: pd.DataFrame) -> pd.DataFrame:
        res = self._model().evaluate(self.bounds(X), pose_index=0)
        cost = default_cost_model()
        tol_cols = [f"db_xy_{j}_mm" for j in JOINTS] + [f"db_z_{j}_mm" for j in JOINTS]
        c = cost.cost(X[tol_cols].to_numpy(float) * MM).sum(axis=1)
        return pd.DataFrame({"p_max_mm": res.p_max / MM, "r_max_deg": np.degrees(res.r_max),
                             "p_upper_mm": res.p_upper / MM, "r_upper_deg": np.degrees(res.r_upper),
                             "cost": c})


OBJECTIVES = ("p_max_mm", "r_max_deg", "cost")


def _findings(study: DesignStudy, pres: dict, design: str = "full factorial") -> tuple[list[str], dict]:
    """The thesis's qualitative statements, re-derived from our numbers (main effects, level sets)."""
    me_p = study.main_effects("p_max_mm").set_index("input")
    me_r = study.main_effects("r_max_deg").set_index("input")
    xy = [f"db_xy_{j}_mm" for j in JOINTS]
    z = [f"db_z_{j}_mm" for j in JOINTS]
    top_p = list(me_p.index[:2])
    act_xy = {"db_xy_A_mm", "db_xy_B_mm"}
    lines, facts = [], {}
    lab = lambda c: study.factors[c].label
    facts["p_main_effects_decades"] = me_p["effect"].to_dict()
    facts["r_main_effects_decades"] = me_r["effect"].to_dict()
    facts["p_dominant"] = top_p
    dom = set(top_p) == act_xy
    lines.append(
        ("The actuated joints' radial clearances dominate p_max: " if dom else "p_max is dominated by ")
        + ", ".join(f"{lab(c)} ({me_p.loc[c, 'effect']:.2f} decades)" for c in top_p)
        + "; the passive joints' radial clearances follow with "
        + ", ".join(f"{me_p.loc[c, 'effect']:.2f}" for c in xy if c not in top_p)
        + f" decades (main effect = spread of the mean log10 p_max over an input's levels, {design}).")
    zmax = max(me_p.loc[c, "effect"] for c in z)
    xymin = min(me_p.loc[c, "effect"] for c in xy)
    facts["dbz_max_effect_on_p_decades"] = zmax
    facts["dbz_matters_for_p"] = bool(zmax > 0.5 * xymin)
    zr = max(me_r.loc[c, "effect"] for c in z)
    facts["dbz_max_effect_on_r_decades"] = zr
    lines.append(
        f"Δb_z matters {'little' if zmax < 0.5 * xymin else 'comparably'} for p_max: its largest main effect is "
        f"{zmax:.3f} decades against {xymin:.2f} to {me_p.loc[top_p[0], 'effect']:.2f} decades for Δb_xy. "
        + (f"On r_max its largest main effect is {zr:.1e} decades: the axial play does not change the rotational "
           f"error (only the tilts Δβ_xy = Δb_xy / h do)." if zr < 1e-3 else
           f"On r_max its largest main effect is {zr:.3f} decades."))
    top_r = list(me_r.index[:2])
    facts["r_dominant"] = top_r
    lines.append("r_max is driven by " + ", ".join(f"{lab(c)} ({me_r.loc[c, 'effect']:.2f} decades)" for c in top_r)
                 + " ahead of " + ", ".join(f"{c.split('_')[2]} {me_r.loc[c, 'effect']:.2f}" for c in xy if c not in top_r)
                 + " decades.")
    for name in ("p_max ≤ 0.05 mm", "p_max ≤ 0.01 mm", "p_max ≥ 1 mm", "r_max ≥ 1°", "r_max ≤ 0.01°"):
        r = pres[name]
        if r.count == 0:
            lines.append(f"{name}: no entry is kept.")
            facts[name] = {"count": 0}
            continue
        both_z = [c for c in z if len(r.ranges[c]["levels"]) == 2]
        xy_max = {c: max(r.ranges[c]["levels"]) for c in xy}
        xy_min = {c: min(r.ranges[c]["levels"]) for c in xy}
        facts[name] = {"count": r.count, "dbz_free": both_z, "dbxy_max_kept": xy_max, "dbxy_min_kept": xy_min}
        if "≤" in name:
            txt = (f"{name} ({r.count} entries): the radial clearances stay at or below "
                   + ", ".join(f"{c.split('_')[2]} {xy_max[c]:g}" for c in xy) + " mm; "
                   + (f"Δb_z keeps both levels on {len(both_z)} of 5 joints"
                      + (f" ({', '.join(c.split('_')[2] for c in both_z)})" if both_z else "")))
        else:
            txt = (f"{name} ({r.count} entries): the radial clearances stay at or above "
                   + ", ".join(f"{c.split('_')[2]} {xy_min[c]:g}" for c in xy) + " mm; "
                   + f"Δb_z keeps both levels on {len(both_z)} of 5 joints")
        lines.append(txt + ".")
    return lines, facts


def thesis_endpoints(df: pd.DataFrame, n_sample: int = 1000) -> dict:
    """Where the thesis's range endpoints (Fig. VII.2) fall among the values our factorial takes.

    For each endpoint: the distinct value of ours nearest to it (log distance, values equal to 7
    significant digits grouped), how many entries take it, how many entries lie beyond it (more
    extreme), and the probability that a random ``n_sample``-entry sample of the factorial misses
    all of those -- i.e. that the sample's extreme is this value or a less extreme one.

    Parameters
    ----------
    df : pandas.DataFrame
        Evaluated entries with the columns ``p_max_mm`` (mm) and ``r_max_deg`` (deg), all
        positive (their log10 is taken).
    n_sample : int, optional
        Size of the thesis's random sample (1000 entries).

    Returns
    -------
    dict
        Keyed ``p_max_mm_min``, ``p_max_mm_max``, ``r_max_deg_min``, ``r_max_deg_max``; each a
        dict: ``thesis`` and ``ours_nearest`` (mm or deg), ``relative_difference``,
        ``n_entries_at_value``, ``n_entries_beyond``, ``rank_from_the_end`` and
        ``probability_sample_misses_those_beyond`` (sampling without replacement).
    """
    out = {}
    n = len(df)
    for col, (lo, hi) in THESIS_RANGES.items():
        v = np.sort(df[col].to_numpy(float))
        key = np.round(np.log10(v), 6)
        for end, t in (("min", lo), ("max", hi)):
            u, counts = np.unique(key, return_counts=True)
            i = int(np.argmin(np.abs(u - math.log10(t))))
            value = float(10 ** u[i])
            beyond = int(counts[:i].sum()) if end == "min" else int(counts[i + 1:].sum())
            p_miss = float(np.prod([(n - n_sample - k) / (n - k) for k in range(beyond)])) if beyond else 1.0
            out[f"{col}_{end}"] = {"thesis": t, "ours_nearest": value, "relative_difference": value / t - 1,
                                   "n_entries_at_value": int(counts[i]), "n_entries_beyond": beyond,
                                   "rank_from_the_end": (i if end == "min" else len(u) - 1 - i) + 1,
                                   "probability_sample_misses_those_beyond": p_miss}
    return out


CONFIG = {"seed": 0, "n_entries": None, "n_sample": 1000, "pop_size": 64, "n_gen": 40, "workers": None,
          "scheduler": None, "progress": True}
#: quick: a 256-entry random sample, its first 64 entries as "the thesis's sample", a tiny NSGA-II
QUICK = {"n_entries": 256, "n_sample": 64, "pop_size": 16, "n_gen": 3}
_KCOLS = [f"db_xy_{j}_mm" for j in JOINTS] + [f"db_z_{j}_mm" for j in JOINTS] + ["cost", "p_max_mm", "r_max_deg"]


def _axes(f):
    from evotol.reporting.parcoords import Axis

    return ([Axis(x.name, x.label, True) for x in f]
            + [Axis("cost", "cost (units)", True), Axis("p_max_mm", "p_max (mm)", True), Axis("r_max_deg", "r_max (deg)", True)])


def compute(config: dict) -> StudyResult:
    """Evaluate the full factorial (``n_entries``: a random sample), read off the thesis's sample,
    apply the presets, derive the findings and run NSGA-II on continuous tolerances. ``out_dir``
    holds the resumable chunk store.

    Parameters
    ----------
    config : dict
        Study config: ``seed``, ``quick``, ``n_entries`` (random subset size; ``None`` for the
        full 32 768-entry factorial), ``n_sample`` (the thesis's sample size), ``pop_size`` and
        ``n_gen`` (NSGA-II), ``workers``, ``scheduler`` (Dask address or ``None``), ``progress``
        (bool) and, set by the framework, ``out_dir`` (no chunk store without it).

    Returns
    -------
    StudyResult
        ``summary`` (objective ranges in mm and deg, presets, findings, certificate gap,
        evaluation log, NSGA-II knees, timing in s) and the tables ``entries`` (every evaluated
        entry: tolerances in mm, ``p_max_mm``, ``r_max_deg``, certified bounds, ``cost`` in cost
        units) and ``pareto`` (the NSGA-II front).
    """
    t0 = time.perf_counter()
    quick, seed = config["quick"], config["seed"]
    scheduler = scheduler_of(config["scheduler"])   # `evotol reproduce` on a cluster
    f = factors()
    ev = FiveBarToleranceEvaluator()
    entries = doe.random_subset(f, config["n_entries"], seed=seed) if config["n_entries"] else doe.full_factorial(f)
    store = Path(config["out_dir"]) / f"{NAME}_store{'_quick' if quick else ''}" if config.get("out_dir") else None
    log = doe.EvaluationLog()
    df = doe.evaluate(entries, ev, store=store,
                      workers=config["workers"], scheduler=scheduler, progress=config["progress"], log=log,
                      chunk_size=None if quick else 4096,   # ~2 ms/entry in chunks of 4096 vs ~5 ms in 256
                      description="5-bar tolerance entries")
    study = DesignStudy(df, objectives=list(OBJECTIVES), presets=presets(), name=NAME)

    # the thesis's 1000-entry sample, read out of the evaluated factorial (same entry ids)
    sample_ids = doe.random_subset(f, config["n_sample"], seed=seed)["entry"]
    sample = df[df["entry"].isin(sample_ids)] if not quick else df.iloc[:config["n_sample"]]
    pres = study.preset_results()
    pres_sample = study.preset_results(among=sample)
    findings, facts = _findings(study, pres, "256-entry random sample" if quick else "full factorial")

    # h that reproduces the thesis's largest rotational error: r_max ∝ 1/h at the all-0.1 mm entry
    top = df.loc[df["r_max_deg"].idxmax()]
    h_fit = H_MM * top["r_max_deg"] / THESIS_RANGES["r_max_deg"][1] if not quick else float("nan")
    endpoints = thesis_endpoints(df) if not quick else {}

    # NSGA-II on continuous tolerances: cost vs p_max vs r_max
    cont = [Factor(x.name, low=x.low, high=x.high, log=True, si_scale=MM, label=x.label, group=x.group) for x in f]
    objs = [Objective("cost", 1, log=True), Objective("p_max_mm", 1, log=True), Objective("r_max_deg", 1, log=True)]
    t1 = time.perf_counter()
    front = doe.nsga2(cont, ev, objs, pop_size=config["pop_size"], n_gen=config["n_gen"], seed=seed)
    t_nsga = time.perf_counter() - t1
    pareto = front.table
    knees = pareto[pareto["knee"]]

    gap = float(np.max(np.maximum(df["p_upper_mm"] / df["p_max_mm"], df["r_upper_deg"] / df["r_max_deg"]) - 1))
    rng_full = study.objective_ranges()
    rng_sample = study.objective_ranges(among=sample)
    summary = {
        "study": NAME, "quick": quick, "seed": seed, "n_entries": len(df), "pose_mm": list(POSE_MM),
        "h_mm": H_MM, "h_mm_matching_thesis_r_max": h_fit, "thesis_endpoints": endpoints,
        "objective_ranges": {k: [v["min"], v["max"]] for k, v in rng_full.items()},
        "objective_ranges_sample": {k: [v["min"], v["max"]] for k, v in rng_sample.items()},
        "n_sample": int(len(sample)),
        "thesis_ranges": THESIS_RANGES,
        "presets": {k: {"count": v.count, "ranges": v.ranges, "query": v.resolved_query} for k, v in pres.items()},
        "presets_sample": {k: {"count": v.count, "ranges": v.ranges} for k, v in pres_sample.items()},
        **parcoords_counts(study, pareto, _axes(f)),
        "findings": findings, "facts": facts,
        "certificate_gap_max": gap,
        "evaluation": {"seconds": log.seconds, "backend": log.backend, "chunks": log.n_chunks,
                       "chunks_resumed": len(log.chunks_resumed)},
        "nsga2": {"n_pareto": len(pareto), "n_evaluations": pareto.attrs["evotol"]["n_evaluations"],
                  "seconds": t_nsga, "knees": knees[_KCOLS].to_dict(orient="records")},
        "files": {"entries_parquet": f"{NAME}_entries.parquet", "entries_csv": f"{NAME}_entries.csv",
                  "pareto_parquet": f"{NAME}_pareto.parquet"},
        "figures": {"sample_entries": sample["entry"].astype(int).tolist()},
        "seconds": time.perf_counter() - t0,
    }
    return StudyResult(summary, {"entries": df, "pareto": pareto})


def render(result: StudyResult):
    """Findings, the parallel coordinates with the presets of Figs. VII.3-VII.8, ranges vs the
    thesis, main effects and the NSGA-II knees.

    Parameters
    ----------
    result : StudyResult
        Output of :func:`compute`: its summary and the tables ``entries`` and ``pareto``.

    Returns
    -------
    evotol.reporting.html.Report
        The HTML report.
    """
    from evotol.reporting.html import Report
    from evotol.reporting.parcoords import format_tick, preset_table_rows

    s, df, pareto = result.summary, result.tables["entries"], result.tables["pareto"]
    f = factors()
    study = DesignStudy(df, objectives=list(OBJECTIVES), presets=presets(), name=NAME)
    sample = df[df["entry"].isin(s["figures"]["sample_entries"])]
    ev = s["evaluation"]
    rep = Report("5-bar tolerance synthesis (Deng 2012, Sec. VII.1.2)",
                 f"{len(df)} entries{' (quick sample)' if s['quick'] else ' (full factorial 4^5 x 2^5)'} at pose "
                 f"({POSE_MM[0]:g}, {POSE_MM[1]:g}) mm; h = {H_MM:g} mm; evaluated in {ev['seconds']:.1f} s ({ev['backend']})")
    rep.heading("Findings (computed from the entries below)")
    rep.html("<ul>" + "".join(f"<li>{x}</li>" for x in s["findings"]) + "</ul>")
    parcoords_section(rep, study, pareto, _axes(f),
                      "One line per entry (level grid) plus the NSGA-II Pareto entries (orange) and their knee points "
                      "(red). Tolerance axes are log10 with tick labels in mm. Presets apply the filters of Figs. "
                      "VII.3-VII.8.", "Presets (Figs. VII.3-VII.8): kept entries and kept input levels")
    rep.text(f"The same filters on our {len(sample)}-entry random sample (seed {s['seed']}), the size the thesis plots "
             f"(its sample is unknown, so its readings are compared with both):")
    rep.table(preset_table_rows(study, among=sample), PRESET_HEADER)
    rep.heading("Objective ranges vs the thesis")
    rows = []
    rng_full, rng_sample = s["objective_ranges"], s["objective_ranges_sample"]
    for c, lab in (("p_max_mm", "p_max (mm)"), ("r_max_deg", "r_max (deg)")):
        rows.append([lab, f"[{format_tick(rng_full[c][0])}, {format_tick(rng_full[c][1])}]",
                     f"[{format_tick(rng_sample[c][0])}, {format_tick(rng_sample[c][1])}]",
                     f"[{THESIS_RANGES[c][0]:g}, {THESIS_RANGES[c][1]:g}]"])
    rep.table(rows, ["objective", f"ours, {len(df)} entries", f"ours, {len(sample)}-entry sample", "thesis, 1000 entries (Fig. VII.2)"])
    h_fit = s["h_mm_matching_thesis_r_max"]
    rep.text(f"Joint length h = {H_MM:g} mm in Δβ_xy = Δb_xy / h (eq. III.2). The thesis gives no h; "
             f"the h that makes our largest r_max equal the thesis's 1.38° is {float('nan') if h_fit is None else h_fit:.2f} mm. "
             f"Largest relative certificate gap over all entries: {s['certificate_gap_max']:.1e} (attained vs certified bound).")
    if s["thesis_endpoints"]:
        rep.text("Each endpoint of the thesis's ranges is a value our factorial takes: the nearest distinct value "
                 "of ours, how many entries are more extreme, and the probability that a random 1000-entry "
                 "sample misses all of them (so that its extreme is this value):")
        rep.table([[k.replace("_", " "), e["thesis"], e["ours_nearest"], f"{100 * e['relative_difference']:+.1f} %",
                    e["rank_from_the_end"], e["n_entries_beyond"], e["probability_sample_misses_those_beyond"]]
                   for k, e in s["thesis_endpoints"].items()],
                  ["endpoint", "thesis", "ours (nearest value)", "difference", "rank of our value from the end",
                   "entries beyond it", "P(1000-sample misses them)"], digits=4)
    rep.heading("Main effects (mean log10 objective per level, full factorial)")
    me_p, me_r = s["facts"]["p_main_effects_decades"], s["facts"]["r_main_effects_decades"]
    rep.table([[study.factors[c].label, me_p[c], me_r[c]] for c in study.inputs],
              ["input", "effect on p_max (decades)", "effect on r_max (decades)"])
    ns = s["nsga2"]
    rep.heading("NSGA-II on continuous tolerances (cost vs p_max vs r_max)")
    rep.text(f"{ns['n_pareto']} Pareto entries from {ns['n_evaluations']} evaluations "
             f"({ns['seconds']:.1f} s); knee points (nearest to the ideal point after log-normalising, and pymoo "
             f"high trade-off points):")
    rep.table([[k[c] for c in _KCOLS] for k in ns["knees"]], [x.label for x in f] + ["cost", "p_max (mm)", "r_max (deg)"], digits=3)
    rep.text("Cost model: " + repr(default_cost_model()) + " per clearance (SI tolerance), summed over the ten "
             "clearances -- illustrative; the thesis has no cost model.", note=True)
    return rep


STUDY = Study(name=NAME, title="5-bar tolerance synthesis on parallel coordinates + NSGA-II (Deng 2012 Sec. VII.1)",
              compute=compute, render=render, config=CONFIG, quick=QUICK, seed_paper="004 Deng 2012 (thesis), Ch. VII")

"""Units of the seed studies' JSON keys that neither a unit suffix nor the common rules name
(docs/units.md, issue 15): one table per study, read by :meth:`Study.units_block`.

The thesis-style maps of the Deng studies keep their historical keys (``p_max`` in mm, ``r_max``
in rad, pose coordinates ``x``/``y``/``z`` in mm) so that reports and users' scripts keep
working; their unit is stated here and written into every file's ``units`` block.
"""
from __future__ import annotations

from evotol.units import COST, COUNT, RELATIVE


def _robot_units(module: str, cls: str) -> dict[str, str]:
    """Per-source SI units of a shipped robot (``{name: "m" | "rad"}``)."""
    import importlib
    robot = getattr(importlib.import_module(module), cls)()
    return {s.name: s.unit for s in robot.sources}


def _paper_units(si: dict[str, str]) -> dict[str, str]:
    """The same sources in the paper's units: lengths in mm, angles in deg."""
    return {k: {"m": "mm", "rad": "deg"}[u] for k, u in si.items()}


_MAPS = {"map_seconds": "s", "p_max": "mm", "p_upper": "mm", "r_max": "rad", "r_upper": "rad", "x": "mm", "y": "mm", "z": "mm",
         "multistart_r": "rad", "grid": COUNT, "starts_below_global_p": COUNT, "speedup": RELATIVE,
         "min_abs_on_grid": "1: |sin(psi1 - psi2)|", "sin_psi1_minus_psi2": "1: sin(psi1 - psi2)",
         "margin": "1: fraction of the axis range", "singular_rows": "mixed: see the report's table columns",
         "monte_carlo_rows": "mixed: see the report's table columns",
         "baseline_rows": "mixed: see the report's table columns", "grid_points_on_locus": COUNT,
         "p_asymmetry_certified_points": COUNT, "multistart_n_variables": COUNT,
         "n_solved": COUNT, "n_reused": COUNT, "checked_poses": COUNT,
         "max_map_residual": RELATIVE, "max_consistency_residual": RELATIVE}
_GEOMETRY = {"b": "m", "d": "m", "e": "m", "l1": "m", "l2": "m", "a1": "m", "a2": "m", "p": "m",
             "alpha_0": "rad", "alpha_d": "rad", "beta": "rad",
             "b_xy": "m", "b_z": "m", "beta_xy": "rad", "beta_z_active": "rad", "beta_z_passive": "rad"}
_SYNTHESIS = {"presets_shown_in_report": COUNT, "report_lines": COUNT, "p_max_at": COUNT, "r_max_at": COUNT,
              "total": COUNT, "chunks": COUNT, "sample_entries": "index",
              "dbz_max_effect_on_p_decades": "decades (log10)", "dbz_max_effect_on_r_decades": "decades (log10)"}
_YIELD = "1: probability every response is within its limit (first-order model)"
_PROCESS = {"incumbent": COST, "smallest_pruned_bound": COST, "history": COST + " (best fitness per generation)",
            "leaf_kkt_residual": RELATIVE, "max_abs_normalised": RELATIVE + ": |response error| / limit",
            "yield": _YIELD, "yield_at_optimum": _YIELD, "worst_point_offsets": "m", "side": "1: sign (+1 above, -1 below)",
            "iteration": COUNT, "iterations": COUNT, "cost_difference": COST}


_NORMALISED = "1: length / D, D = (r1_bar + r2_bar + r3_bar) / 3 (Lara-Molina 2019 eqs. 1-2)"
_PROB = "1: probability"
_5R_KEYS = {k: _NORMALISED for k in (
    "r1", "r2", "r3", "s", "t", "mic_radius", "mic_center_y", "radius", "center_y", "x", "y", "cx",
    "type2_locus", "cloud", "poses", "mean_dx", "mean_dy", "std_dx", "std_dy", "mean_dev", "rms_dev", "max_dev",
    "q99_dev", "fk_ik_max_error", "fk_ik_max_error_lci_ge_0.01", "fk_ik_max_error_longdouble",
    "fk_ik_longdouble_eps", "delta_r", "clearance_rc", "circle")}
_5R_KEYS.update({k: "1: local conditioning index" for k in (
    "lci", "lci_max", "lci_at_mic_center", "lci_p90", "lci_median", "lci_mean_miw", "lci_min_miw", "lci_min_grid",
    "b", "d_max")})
_5R_KEYS.update({"usable_area": "1: area / D^2", "p_exceed": _PROB, "p_exceed_at_lower_bounds": _PROB, "p_unassembled": _PROB,
                 "p_exceed_max": _PROB, "p_exceed_optimiser": _PROB, "p_exceed_verified": _PROB,
                 "p_exceed_verified_max": _PROB, "p_exceed_verified_upper95": _PROB,
                 "p_exceed_probabilistic_model": _PROB, "calibration_factor": RELATIVE,
                 "sigma_multiple": "1: multiple of sigma", "timing": "s"})
_5R_SOURCES = {"clearance_A": "m", "clearance_B": "m", "clearance": "m", "theta": "rad", "A1B1": "m", "A2B2": "m",
               "B1P": "m", "B2P": "m", "OA1": "m", "OA2": "m", "theta1": "rad", "theta2": "rad",
               "clearance_A1": "m", "clearance_A2": "m", "clearance_B1": "m", "clearance_B2": "m"}
_5R_TABLES = {
    "settings": {k: COUNT for k in ("grid", "cloud", "conv_sizes", "conv_rep", "conv_ref", "pop", "alloc_grid")},
    "allocation": {**_5R_SOURCES, "D": "m", "radius": "m", "p_max": _PROB},
    "cost_parts": {k: COST for k in _5R_SOURCES},
    "convergence": {"sizes": COUNT, "mean_dx": "1: rms error / reference rms deviation",
                    "rms_dev": "1: relative rms error", "p_exceed_q90": "1: relative rms error"},
    "variance_ratio": {k: RELATIVE + ": MC error^2 / LHS error^2" for k in ("mean_dx", "rms_dev", "p_exceed_q90")},
}


def study_units(name: str) -> dict:
    """``keys``, ``tolerances`` and ``tables`` for :func:`evotol.units.make_units_block`."""
    if name in ("deng2012-5bar", "deng2012-irsbot2"):
        return {"keys": {**_MAPS, **_GEOMETRY}}
    if name in ("deng2012-dimsynth", "deng2012-tolsynth"):
        endpoints = {parent: {"thesis": unit, "ours_nearest": unit, "rank_from_the_end": COUNT,
                              "probability_sample_misses_those_beyond": _PROB}
                     for parent, unit in (("p_max_mm_min", "mm"), ("p_max_mm_max", "mm"),
                                          ("r_max_deg_min", "deg"), ("r_max_deg_max", "deg"))}
        return {"keys": {**_GEOMETRY, **_SYNTHESIS, "h_mm_matching_thesis_r_max": "mm"}, "tables": endpoints}
    if name in ("chase1990-clutch", "process-stack"):
        return {"keys": _PROCESS}
    if name == "choi2000-clutch":
        return {"keys": {**_PROCESS, "quality_loss_A": COST + " (loss at the limit)", "quality_loss": COST,
                         "K_per_rad2": COST + " per rad²", "processes": "index (1-based process id)",
                         "sensitivities_rad_per_mm": "rad/mm", "measure_over_limit": RELATIVE,
                         "loss_balance_ratio_A100": RELATIVE, "cage_nominal_mm": "mm", "lower_bound": COST,
                         "process_choice_part": COST, "tolerance_part": COST, "rtol": RELATIVE,
                         "max_relative_tolerance_difference": RELATIVE, "front_size": COUNT,
                         "rss_over_T_A0": RELATIVE, "rss_over_T_A20": RELATIVE, "rss_over_T_A100": RELATIVE,
                         "linear_optimum_nonlinear_worst_case_over_limit": RELATIVE, "proven_lower_bound": COST}}
    if name == "deng2012-clearalloc":
        return {"keys": {"best_feasible": COST, "ga_vs_doe": RELATIVE + ": (GA - DOE best) / DOE best"}}
    if name == "laramolina2019-5r":
        return {"keys": _5R_KEYS, "tables": _5R_TABLES}
    if name == "mechanisms":
        return {"keys": {"closure_residual": "m", "poses": COUNT, "joint_angle_abs_diff_rad_50_poses": "rad",
                         "rank": COUNT, "pinocchio_rank": COUNT, "combined_rank": COUNT, "rank_with_tip": COUNT,
                         "pinocchio_rank_with_tip": COUNT, "combined_rank_with_tip": COUNT, "n_configurations": COUNT,
                         "n_joints": COUNT, "fk_vs_pinocchio": "m",
                         "duplicated": "1: [source, source, sign +1 or -1] (equal columns up to sign)"}}
    if name == "yao2013":
        tol = _robot_units("evotol.robots.ucr3", "UCR3")
        return {"keys": {"worst_case_error": "m", "rss_error": "m", "tolerance": "m or rad (see tolerances)",
                         "ga_max_rss_error": "m", "best_fitness": COST + " + penalty",
                         "mean_fitness": COST + " + penalty", "best_feasible": COST,
                         "ga_unseeded_initial_best": COST + " + penalty", "table1": COST, "table2": COST,
                         "grid": COUNT, "ga_seconds_by_variant": "s"},
                "tolerances": tol}
    if name == "brahmia2023-delta":
        tol = _robot_units("evotol.robots.delta", "DeltaRobot")
        paper = _paper_units(tol)
        return {"keys": {"verification_error_mm_range": "mm", "paper_verification_error_mm_range": "mm",
                         "runs_reaching_displacement": COUNT, "jacobian_fd_relative_mismatch": RELATIVE,
                         "errors": "m or rad (per source, SI, in source order)", "nit": COUNT,
                         "rule_on_tables_a_si": "m or rad (per source, SI, in source order)"},
                "tolerances": tol,
                "tables": {"tolerance_intervals": paper, "intervals_paper_units": paper}}
    return {}

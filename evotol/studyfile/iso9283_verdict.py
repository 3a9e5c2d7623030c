"""Whether a design meets a study's ISO 9283 requirement, and on which model (docs/iso9283.md, "Verdicts").

A verdict names its model: AP's worst case is attained by explicit errors and bounded by a proven bound
(grid / cos δ), AP at a yield and RP are sampled on the first-order model, and the simulated ISO test on the
nonlinear model is shown beside as evidence (a sample never proves a worst case).

Parameters
----------
iso : evotol.studyfile.iso9283.IsoStudy
    The study's ISO 9283 request (its ``AP``, ``RP``, ``yield_``).
"""
from __future__ import annotations

import numpy as np

from evotol.measures.iso9283 import quantile_interval


def _verdict(req, value, attained, model, simulated, simulated_as) -> dict:
    """One figure's verdict: meets when ``value`` (a proven bound or the prediction) is within ``req``, does
    not meet when ``attained`` (a value explicit errors reach, or the prediction) exceeds it, else undecided."""
    meets = True if value <= req else (False if attained > req else None)
    return {"requirement": req, "predicted": float(value), "attained": float(attained), "meets": meets,
            "verdict": {True: "meets", False: "does not meet", None: "undecided (between attained and proven bound)"}[meets],
            "model": model, "simulated": None if simulated is None else float(simulated), "simulated_as": simulated_as,
            "simulated_within": None if simulated is None else bool(simulated <= req)}


def verdicts(iso, pred: dict, sim: dict, calibrated_ap=None, orient=None) -> dict:
    """Per required figure, whether the design meets it and on which model (a verdict names its model).

    Parameters
    ----------
    pred : dict
        :func:`evotol.measures.iso9283.predict` at the ISO poses.
    sim : dict
        :func:`evotol.measures.iso9283.simulate` of the same design.
    calibrated_ap : float or None
        The largest predicted AP after the study's calibration (m); None: uncalibrated.
    orient : dict or None
        :func:`evotol.measures.iso9283.predict_orientation` of the design, for ``iso.orientation``.

    Returns
    -------
    dict
        Per required figure (``AP``, ``RP``, and any of ``APa`` .. ``RPc`` in rad): ``requirement``,
        ``predicted`` (the value the verdict compares, largest over the poses, m), ``attained``, ``meets``
        (True, False, or None when a requirement lies between the attained worst case and its proven bound),
        ``verdict``, ``model``, ``simulated`` (the nonlinear test's largest over the poses; None for the
        calibrated AP, which this test does not calibrate) and ``simulated_within`` (a sample: evidence, not
        proof).
    """
    out = {}
    if iso.AP is not None:
        y = iso.yield_
        sim_ap = float(np.max([quantile_interval(sim["AP"][:, i], 1.0 if y is None else y)[0] for i in range(sim["AP"].shape[1])]))
        as_ = "the largest AP over the simulated robots" if y is None else f"the simulated robots' AP quantile at {y:g}"
        if calibrated_ap is not None:
            out["AP"] = _verdict(iso.AP, calibrated_ap, calibrated_ap, "first order after the study's calibration: "
                                 "systematic residual and lost motion (proven bound) plus the fit error's quantile", None,
                                 "not simulated after calibration here: the calibration section's simulated calibration")
        elif y is None:
            out["AP"] = _verdict(iso.AP, pred["AP_bound"].max(), pred["AP"].max(), "first-order worst case over the "
                                 "tolerance box: attained by explicit errors, proven bound grid / cos δ", sim_ap, as_)
        else:
            out["AP"] = _verdict(iso.AP, pred["AP"].max(), pred["AP"].max(), f"first order, AP at yield {y:g} sampled "
                                 "over robots drawn within the tolerances", sim_ap, as_)
    if iso.RP is not None:
        out["RP"] = _verdict(iso.RP, pred["RP"].max(), pred["RP"].max(), "first order, E l + 3 std l of the linearised "
                             "random sources, sampled", float(sim["RP"].mean(axis=0).max()), "the mean RP of the simulated tests")
    for k, lim in getattr(iso, "orientation", {}).items():     # APa .. RPc (rad): exact first order
        a = "abc".index(k[2])
        v = float(orient[k[:2]][:, a].max())
        simulated = np.abs(sim["AP_abc"][..., a]).max() if k[:2] == "AP" else sim["RP_abc"][..., a].mean(axis=0).max()
        out[k] = _verdict(lim, v, v, "first order, exact: the worst case of one linear function over the tolerance box"
                          if k[:2] == "AP" else "first order, exact: 3 sigma of the linearised random sources", float(simulated),
                          "the largest over the simulated robots" if k[:2] == "AP" else "the mean 3 S of the simulated tests")
    return out

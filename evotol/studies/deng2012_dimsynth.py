"""IRSBot-2 dimension synthesis (Deng 2012, Sec. VII.2, Tab. VII.1, Figs. VII.9-VII.16).

Design variables l1, l2, a1, a2, p on the three levels of Tab. VII.1 (3^5 = 243 designs), the
other parameters fixed at Tab. VI.4 (b = d = 50 mm, alpha_d = pi/6, beta = pi/4, e = 0). Each
design gets three objectives:

* ``area_mm2`` -- the area of the largest axis-aligned rectangle (the thesis's "cuboid-shaped
  sub-workspace") of the x-z plane in which the robot is assembled in its working mode and free
  of Type 1 and Type 2 singularities, found by workspace discretisation (Sec. VII.2.1, [BPC10]);
* ``p_max_mm`` and ``r_max_deg`` -- the maximum positional and rotational error of the platform
  due to the clearances of the distal modules and the parallelograms (114-variable model of
  Ch. V-VI), the largest over the rectangle's right-down corner, centre and left-up corner
  (Fig. VII.10), computed by the certified engine of :mod:`robots.clearance`.

Geometry of the equivalent planar mechanism (Sec. II.2.1, Fig. II.3): leg i is a planar 2R chain
from the equivalent base point ``O_i = (∓(b - a1 sin beta - p), -e)`` with proximal length l1 and
distal length l2eq (eq. II.1) to the platform point P = (x, z). Verified form of eq. II.1:
the distal link spans ``(a1 - a2) cos beta`` across the elbow plane, so
``l2eq = sqrt(l2² - (a1 - a2)² cos² beta)``; the thesis prints ``cos beta`` (not squared) --
kept as :func:`l2eq_printed`.

Working mode: elbows outward (leg 1's elbow left of the line O_1 -> P, leg 2's right of O_2 -> P),
the IRSBot-2's operating branch of eqs. II.5-II.6 (the engine's ``modes=(-1, -1)``). Assembly
mode: the distal links forming a V (sin(psi_1 - psi_2) < 0); the Type 2 singularity (distal links
parallel, Sec. II.4) bounds it. Type 1 singularities (proximal and distal link aligned) bound the
reachable set. A grid point below the base (z < -e: the robot hangs from its base) is kept when
both sines exceed ``sin(margin)`` in magnitude (default margin 2 deg: the sub-workspace stays off
the singular loci, where the clearance errors grow without bound).
"""
from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from evotol import doe
from evotol.doe import Factor, Objective
from evotol.errors import EvotolError, ValidationError
from evotol.filtering import DesignStudy, Preset
from evotol.studies import Study

MM = 1e-3

#: Tab. VI.4 (fixed parameters of the dimension synthesis), SI units
TAB_VI_4 = {"b": 50 * MM, "d": 50 * MM, "alpha_0": 0.0, "alpha_d": math.pi / 6, "beta": math.pi / 4, "e": 0.0}
#: Tab. VII.1: three levels of l1, l2, a1, a2, p (mm)
TAB_VII_1 = {"l1": (50.0, 100.0, 200.0), "l2": (50.0, 100.0, 200.0), "a1": (10.0, 30.0, 50.0),
             "a2": (5.0, 15.0, 30.0), "p": (15.0, 25.0, 40.0)}
#: Tab. VII.2: the thesis's two good designs (mm)
TAB_VII_2 = ((200.0, 100.0, 50.0, 15.0, 15.0), (200.0, 100.0, 50.0, 5.0, 15.0))


def l2eq(l2, a1, a2, beta):
    """Equivalent distal length, eq. II.1 in its verified form sqrt(l2² - ((a1 - a2) cos beta)²)."""
    return np.sqrt(np.asarray(l2) ** 2 - ((np.asarray(a1) - np.asarray(a2)) * np.cos(beta)) ** 2)


def l2eq_printed(l2, a1, a2, beta):
    """Eq. II.1 as printed: sqrt(l2² - (a1 - a2)² cos beta) (cos not squared; kept for comparison)."""
    return np.sqrt(np.asarray(l2) ** 2 - (np.asarray(a1) - np.asarray(a2)) ** 2 * np.cos(beta))


@dataclass(frozen=True)
class PlanarIRSBot2:
    """The equivalent planar mechanism of an IRSBot-2 design (Sec. II.2.1), SI units."""

    l1: float
    l2: float
    a1: float
    a2: float
    p: float
    b: float = TAB_VI_4["b"]
    beta: float = TAB_VI_4["beta"]
    e: float = TAB_VI_4["e"]

    def __post_init__(self):
        for k in ("l1", "l2", "a1", "a2", "p", "b"):
            v = getattr(self, k)
            if not (np.isfinite(v) and v > 0):
                raise ValidationError(f"PlanarIRSBot2.{k}", v, "a positive length (m)")
        if abs(self.a1 - self.a2) * math.cos(self.beta) >= self.l2:
            raise ValidationError("PlanarIRSBot2.l2", self.l2, "longer than the distal offset (a1 - a2) cos(beta)")

    @property
    def l2eq(self) -> float:
        return float(l2eq(self.l2, self.a1, self.a2, self.beta))

    @property
    def base_x(self) -> float:
        """|x| of the equivalent base points O_1, O_2 (eqs. II.3-II.4: -b + a1 sin beta + p)."""
        return self.b - self.a1 * math.sin(self.beta) - self.p

    def legs(self, x, z):
        """Elbows and singularity measures at platform points (x, z) (arrays, m).

        Returns dict with ``reachable`` (eqs. II.5-II.6: A_i² + B_i² >= C_i²), elbow points
        ``E1``, ``E2`` (..., 2) of the elbows-out working mode, ``q1``, ``q2`` (actuated angles,
        eq. II.3 convention x = ... + l1 cos q, z = ... - l1 sin q), ``psi1``, ``psi2`` (eqs.
        II.7-II.8), ``sin_t2`` = sin(psi_1 - psi_2) (Type 2 measure, det A of eq. II.38 / (2 l2eq)²)
        and ``sin_t1_1``, ``sin_t1_2`` = sin(q_i - psi_i) (Type 1 measures, eq. II.37).
        """
        x, z = np.broadcast_arrays(np.asarray(x, float), np.asarray(z, float))
        L1, L2 = self.l1, self.l2eq
        out = {"reachable": np.ones(x.shape, bool)}
        for i, (ox, side) in enumerate(((-self.base_x, 1.0), (self.base_x, -1.0)), start=1):
            dx, dz = x - ox, z + self.e
            d2 = dx * dx + dz * dz
            d = np.sqrt(d2)
            # elbow on circle(O_i, L1) ∩ circle(P, L2): foot along O->P, offset perpendicular
            a = (d2 + L1 * L1 - L2 * L2) / (2 * np.where(d > 0, d, 1.0))
            h2 = L1 * L1 - a * a
            ok = (h2 >= 0) & (d > 0)
            h = np.sqrt(np.where(ok, h2, 0.0))
            ux, uz = dx / np.where(d > 0, d, 1.0), dz / np.where(d > 0, d, 1.0)
            # elbows outward: leg 1's elbow on the right-hand normal of O_1 -> P (to the left
            # when P is straight below), leg 2's on the left-hand normal (mirror image)
            nx, nz = side * uz, -side * ux
            ex, ez = ox + a * ux + h * nx, -self.e + a * uz + h * nz
            out[f"E{i}"] = np.stack([ex, ez], -1)
            out[f"q{i}"] = np.arctan2(-(ez + self.e), ex - ox)
            out[f"psi{i}"] = np.arctan2(-(z - ez), x - ex)
            out[f"sin_t1_{i}"] = np.sin(out[f"q{i}"] - out[f"psi{i}"])
            out["reachable"] &= ok
        out["sin_t2"] = np.sin(out["psi1"] - out["psi2"])
        return out


def largest_rectangle(mask: np.ndarray) -> tuple[int, int, int, int, int]:
    """Largest axis-aligned all-True rectangle of grid points in a 2-D boolean array.

    Returns ``(area_in_cells, r0, r1, c0, c1)`` with inclusive row/column indices; the area
    counts cell spans ``(r1 - r0) * (c1 - c0)`` (point grid: the rectangle's corners are grid
    points that are all kept). Histogram-stack algorithm, O(rows x cols).
    """
    mask = np.asarray(mask, bool)
    nr, nc = mask.shape
    best = (0, 0, -1, 0, -1)
    heights = np.zeros(nc, int)
    for r in range(nr):
        heights = np.where(mask[r], heights + 1, 0)
        stack: list[int] = []
        hs = heights.tolist() + [0]
        for c in range(nc + 1):
            while stack and hs[stack[-1]] >= hs[c]:
                top = stack.pop()
                hgt = hs[top]
                left = stack[-1] + 1 if stack else 0
                w = c - left
                area = (hgt - 1) * (w - 1)
                if hgt > 0 and area > best[0]:
                    best = (area, r - hgt + 1, r, left, c - 1)
            stack.append(c)
    return best


@dataclass(frozen=True)
class SubWorkspace:
    """The largest singularity-free rectangle of a design (SI units) and its Fig. VII.10 points."""

    area: float                 # m²
    x: tuple[float, float]      # (x_min, x_max), m
    z: tuple[float, float]      # (z_min, z_max), m
    step: float                 # grid step, m
    n_kept: int                 # kept grid points

    @property
    def points(self) -> np.ndarray:
        """Right-down corner, centre and left-up corner (Fig. VII.10), shape (3, 2) [x, z] in m."""
        (x0, x1), (z0, z1) = self.x, self.z
        return np.array([[x1, z0], [(x0 + x1) / 2, (z0 + z1) / 2], [x0, z1]])


def singularity_free_rectangle(robot: PlanarIRSBot2, *, n: int = 161, margin_deg: float = 2.0,
                               below_elbows: bool = False) -> SubWorkspace:
    """Largest rectangle of the x-z plane below the base (z < -e) in which the robot is assembled in
    its working mode, on the V side of the Type 2 singularity and at least ``margin_deg`` away from
    both singularity types (module doc), by discretising the reachable region with n x n points.
    ``below_elbows``: also require the platform below both elbows (a stricter variant)."""
    reach = robot.base_x + robot.l1 + robot.l2eq
    depth = robot.l1 + robot.l2eq
    xs = np.linspace(-reach, reach, n)
    zs = np.linspace(-depth - robot.e, -robot.e, n)
    step = max(xs[1] - xs[0], zs[1] - zs[0])
    X, Z = np.meshgrid(xs, zs)                                   # rows: z, columns: x
    g = robot.legs(X, Z)
    s = math.sin(math.radians(margin_deg))
    keep = (g["reachable"] & (g["sin_t2"] <= -s) & (np.abs(g["sin_t1_1"]) >= s) & (np.abs(g["sin_t1_2"]) >= s)
            & (Z < -robot.e))
    if below_elbows:
        keep &= (np.sin(g["psi1"]) > 0) & (np.sin(g["psi2"]) > 0)
    area, r0, r1, c0, c1 = largest_rectangle(keep)
    if c1 < c0 or area == 0:
        return SubWorkspace(0.0, (0.0, 0.0), (0.0, 0.0), float(step), int(keep.sum()))
    dx, dz = xs[1] - xs[0], zs[1] - zs[0]
    return SubWorkspace(float(area * dx * dz), (float(xs[c0]), float(xs[c1])), (float(zs[r0]), float(zs[r1])),
                        float(step), int(keep.sum()))


# --------------------------------------------------------------------------- study
NAME = "deng2012-dimsynth"
DESIGN_VARS = ("l1", "l2", "a1", "a2", "p")
#: Sec. VII.2.2: clearances of every joint (distal modules and parallelograms)
CLEARANCE = {"b_xy": 0.1 * MM, "b_z": 0.1 * MM, "beta_xy": 0.01}
BETA_Z_ACTIVE, BETA_Z_PASSIVE = 0.001, 0.2
#: Sec. VII.2.2 text: ranges over the thesis's 243 designs
THESIS_RANGES = {"p_max_mm": (7.3, 30.6), "r_max_deg": (5.8, 24.3)}


def factors(continuous: bool = False) -> list[Factor]:
    """l1, l2, a1, a2, p (mm) on the levels of Tab. VII.1 (or their continuous span)."""
    out = []
    for k, lv in TAB_VII_1.items():
        if continuous:
            out.append(Factor(f"{k}_mm", low=min(lv), high=max(lv), si_scale=MM, label=f"{k} (mm)", group="dimension"))
        else:
            out.append(Factor(f"{k}_mm", lv, si_scale=MM, label=f"{k} (mm)", group="dimension"))
    return out


def presets() -> list[Preset]:
    """The filters of Figs. VII.12-VII.16."""
    return [Preset("f_a ≥ 4e4 mm²", {"area_mm2": (4e4, None)}, "Fig. VII.12"),
            Preset("f_a ≤ 3e3 mm²", {"area_mm2": (None, 3e3)}, "Fig. VII.13"),
            Preset("f_p ≤ 10 mm", {"p_max_mm": (None, 10.0)}, "Fig. VII.14"),
            Preset("f_r ≤ 8°", {"r_max_deg": (None, 8.0)}, "Fig. VII.15"),
            Preset("f_a ≥ 3e4, f_p ≤ 15, f_r ≤ 8", {"area_mm2": (3e4, None), "p_max_mm": (None, 15.0),
                                                    "r_max_deg": (None, 8.0)}, "Fig. VII.16")]


def clearance_bounds():
    """Sec. VII.2.2: Δb_xy = Δb_z = 0.1 mm, Δβ_xy = 0.01 rad on every joint; Δβ_z "very small" on the
    actuated joints (0.001 rad, Tab. VI.7) and "relatively higher" on the passive ones (0.2 rad,
    Tab. VI.3). Returns (distal, actuated, passive) ClearanceBounds."""
    from robots.clearance import ClearanceBounds

    b, bz, bxy = CLEARANCE["b_xy"], CLEARANCE["b_z"], CLEARANCE["beta_xy"]
    return (ClearanceBounds(bxy, BETA_Z_PASSIVE, b, bz), ClearanceBounds(bxy, BETA_Z_ACTIVE, b, bz),
            ClearanceBounds(bxy, BETA_Z_PASSIVE, b, bz))


def engine_mechanism(robot: PlanarIRSBot2):
    """The engine's IRSBot-2 (:class:`robots.irsbot2.IRSBot2`) of a design with the clearances of
    Sec. VII.2.2 in the distal modules and the parallelograms (Ch. V-VI, 114 variables)."""
    try:
        from robots.irsbot2 import IRSBot2
    except ImportError as exc:
        raise EvotolError("the IRSBot-2 clearance engine (robots/irsbot2.py, issue 6) is not available") from exc
    model = IRSBot2(b=robot.b, d=TAB_VI_4["d"], alpha_d=TAB_VI_4["alpha_d"], beta=robot.beta, e=robot.e,
                    l1=robot.l1, l2=robot.l2, a1=robot.a1, a2=robot.a2, p=robot.p)
    distal, actuated, passive = clearance_bounds()
    return model.clearance_mechanism(parallelograms=True, distal=distal, actuated=actuated, passive=passive)


def engine_pose_errors(robot: PlanarIRSBot2, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Certified maximum positional (m) and rotational (rad) error at ``points`` (k, 2) [x, z] (m)."""
    from robots.clearance import max_pose_error

    res = max_pose_error(engine_mechanism(robot), points)
    return np.asarray(res.p_max), np.asarray(res.r_max)


def engine_pose_errors_batch(robots: list, points: list) -> list[tuple[np.ndarray, np.ndarray]]:
    """:func:`engine_pose_errors` for many designs in one engine call.

    All designs share the joints and chains (only dimensions differ), so their per-pose maps
    (``mech.pose_maps``) stack along the pose axis and the engine solves every (design, point)
    case in one vectorised :func:`robots.clearance.evaluate_cases` call -- the same numbers as one
    call per design (test), at a lower cost per case. Falls back to one call per design if the
    maps do not stack."""
    from dataclasses import replace

    from robots.clearance import evaluate_cases

    if not robots:
        return []
    mechs = [engine_mechanism(r) for r in robots]
    maps = [m.pose_maps(np.asarray(pt, float)) for m, pt in zip(mechs, points)]

    def same(a, b):
        return (a.block == b.block and a.n_disk == b.n_disk and np.array_equal(a.cols, b.cols)
                and np.array_equal(a.cone_joint, b.cone_joint) and np.array_equal(a.cone_kind, b.cone_kind)
                and a.B.shape[1:] == b.B.shape[1:] and a.C_pos.shape[1:] == b.C_pos.shape[1:]
                and a.C_rot.shape[1:] == b.C_rot.shape[1:])

    ref = mechs[0]
    stackable = all(len(mp) == len(maps[0]) and all(same(a, b) for a, b in zip(mp, maps[0])) for mp in maps) and \
        all(np.array_equal(m.default_bounds(), ref.default_bounds()) for m in mechs)
    if not stackable:
        return [engine_pose_errors(r, pt) for r, pt in zip(robots, points)]
    merged = [replace(pm, C_pos=np.concatenate([mp[k].C_pos for mp in maps]),
                      C_rot=np.concatenate([mp[k].C_rot for mp in maps]),
                      B=np.concatenate([mp[k].B for mp in maps])) for k, pm in enumerate(maps[0])]
    n = sum(len(pt) for pt in points)
    b = ref.default_bounds()
    res = evaluate_cases(ref, merged, np.arange(n), np.broadcast_to(b, (n,) + b.shape))
    out, s = [], 0
    for pt in points:
        out.append((res.p_max[s:s + len(pt)], res.r_max[s:s + len(pt)]))
        s += len(pt)
    return out


@dataclass(frozen=True)
class IRSBot2DesignEvaluator:
    """Objectives of IRSBot-2 designs (rows with ``l1_mm, l2_mm, a1_mm, a2_mm, p_mm``).

    n_grid: points per side of the workspace discretisation; margin_deg: distance kept from the
    singular loci (module doc); pose_errors: ``(PlanarIRSBot2, points) -> (p (m), r (rad))``,
    the certified engine by default (tests plug in closed forms).
    Returns ``area_mm2, p_max_mm, r_max_deg``, the rectangle ``x0_mm, x1_mm, z0_mm, z1_mm``, the
    errors at the three points of Fig. VII.10 (``p_rd_mm, p_c_mm, p_lu_mm``, ``r_rd_deg`` ...).
    """

    n_grid: int = 161
    margin_deg: float = 2.0
    pose_errors: Callable | None = None

    def __call__(self, X: pd.DataFrame) -> pd.DataFrame:
        rows, robots, points = [], [], []
        for rec in X[[f"{k}_mm" for k in DESIGN_VARS]].to_numpy(float):
            robot = PlanarIRSBot2(*(rec * MM))
            w = singularity_free_rectangle(robot, n=self.n_grid, margin_deg=self.margin_deg)
            rows.append({"area_mm2": w.area / MM ** 2, "x0_mm": w.x[0] / MM, "x1_mm": w.x[1] / MM,
                         "z0_mm": w.z[0] / MM, "z1_mm": w.z[1] / MM})
            if w.area > 0:
                robots.append((len(rows) - 1, robot))
                points.append(w.points)
        if self.pose_errors is None:
            errs = engine_pose_errors_batch([r for _, r in robots], points)
        else:
            errs = [self.pose_errors(r, pt) for (_, r), pt in zip(robots, points)]
        nan = dict(p_max_mm=np.nan, r_max_deg=np.nan, p_rd_mm=np.nan, p_c_mm=np.nan, p_lu_mm=np.nan,
                   r_rd_deg=np.nan, r_c_deg=np.nan, r_lu_deg=np.nan, feasible=False)
        for row in rows:
            row.update(nan)
        for (i, _), (p, r) in zip(robots, errs):
            p, r = np.asarray(p, float) / MM, np.degrees(np.asarray(r, float))
            rows[i].update(p_max_mm=float(p.max()), r_max_deg=float(r.max()), p_rd_mm=p[0], p_c_mm=p[1],
                           p_lu_mm=p[2], r_rd_deg=r[0], r_c_deg=r[1], r_lu_deg=r[2], feasible=True)
        return pd.DataFrame(rows)


OBJECTIVES = ("area_mm2", "p_max_mm", "r_max_deg")


def _kept_levels(r, name):
    return r.ranges[name].get("levels") or []


def _findings(study: DesignStudy, pres: dict) -> tuple[list[str], dict]:
    """The thesis's statements on Figs. VII.12-VII.16, re-derived from our entries."""
    lines, facts = [], {}
    df = study.entries[study.entries["feasible"]]
    me_a = study.main_effects("area_mm2", log=False, among=df).set_index("input")
    me_p = study.main_effects("p_max_mm", among=df).set_index("input")
    me_r = study.main_effects("r_max_deg", among=df).set_index("input")
    facts["main_effects"] = {"area_mm2": me_a["effect"].to_dict(), "p_max_decades": me_p["effect"].to_dict(),
                             "r_max_decades": me_r["effect"].to_dict()}
    fmt = lambda lv: "{" + ", ".join(f"{v:g}" for v in lv) + "}"
    for name, var, thesis in (("f_a ≥ 4e4 mm²", ("l1_mm", "l2_mm"), "l1 = l2 = 200 mm"),
                              ("f_a ≤ 3e3 mm²", ("l1_mm",), "l1 = 50 mm"),
                              ("f_p ≤ 10 mm", ("l2_mm",), "l2 = 50 mm"),
                              ("f_r ≤ 8°", ("l1_mm", "l2_mm", "a1_mm", "a2_mm", "p_mm"), "no single parameter")):
        r = pres[name]
        kept = {v: _kept_levels(r, v) for v in var}
        facts[name] = {"count": r.count, "kept_levels": kept}
        if r.count == 0:
            lines.append(f"{name} ({pres[name].query if hasattr(pres[name], 'query') else ''}): no design is kept "
                         f"(thesis: {thesis}).")
            continue
        lines.append(f"{name}: {r.count} designs kept; " + "; ".join(f"{v.split('_')[0]} ∈ {fmt(kept[v])}" for v in var)
                     + f" (thesis: {thesis}).")
    top_a = me_a.index[0]
    top_p = me_p.index[0]
    top_r = me_r.index[0]
    facts.update(area_driver=top_a, p_driver=top_p, r_driver=top_r)
    lines.append(f"Largest main effects: on the area {top_a.split('_')[0]} ({me_a.loc[top_a, 'effect']:.3g} mm²), "
                 f"on p_max {top_p.split('_')[0]} ({me_p.loc[top_p, 'effect']:.2f} decades), on r_max "
                 f"{top_r.split('_')[0]} ({me_r.loc[top_r, 'effect']:.2f} decades).")
    return lines, facts


def run(out_dir: Path, quick: bool = False, seed: int = 0, *, scheduler: str | None = None,
        workers: int | None = None, progress: bool = True, pose_errors: Callable | None = None,
        n_grid: int | None = None) -> dict:
    """Evaluate the 243 designs of Tab. VII.1 (quick: 8 of them on a coarser grid), run NSGA-II on
    continuous dimensions, and write HTML, JSON and the entries."""
    from evotol.reporting.html import Report, write_json
    from evotol.reporting.parcoords import Axis, add_parcoords, format_tick, preset_table_rows

    t0 = time.perf_counter()
    scheduler = scheduler or os.environ.get("EVOTOL_DASK_SCHEDULER") or None   # `evotol reproduce` on a cluster
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    ev = IRSBot2DesignEvaluator(n_grid=n_grid or (81 if quick else 161), pose_errors=pose_errors)
    f = factors()
    entries = doe.random_subset(f, 8, seed=seed) if quick else doe.full_factorial(f)
    # always evaluate the thesis's two good designs (Tab. VII.2) -- they are grid designs
    log = doe.EvaluationLog()
    df = doe.evaluate(entries, ev, store=out_dir / f"{NAME}_store{'_quick' if quick else ''}", workers=workers,
                      scheduler=scheduler, progress=progress, log=log, chunk_size=None if not quick else 4,
                      description="IRSBot-2 designs")
    thesis = doe.evaluate(pd.DataFrame([dict(zip([x.name for x in f], d)) for d in TAB_VII_2]), ev,
                          workers=1, progress=False)
    study = DesignStudy(df, objectives=list(OBJECTIVES), presets=presets(), name=NAME)
    paths = study.save(out_dir / f"{NAME}_entries")
    pres = study.preset_results()
    findings, facts = _findings(study, pres)
    good = pres["f_a ≥ 3e4, f_p ≤ 15, f_r ≤ 8"].kept

    # Pareto designs of the grid (max area, min p_max, min r_max) -- threshold-free "good designs"
    from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

    ok = df[df["feasible"]].reset_index(drop=True)
    F = np.column_stack([-ok["area_mm2"], ok["p_max_mm"], ok["r_max_deg"]])
    grid_front = ok.iloc[NonDominatedSorting().do(F, only_non_dominated_front=True)]
    in_front = [bool(((grid_front[[x.name for x in f]].to_numpy() == np.array(d)).all(1)).any()) for d in TAB_VII_2]
    Fg = np.column_stack([-grid_front["area_mm2"], grid_front["p_max_mm"], grid_front["r_max_deg"]])
    grid_knees = grid_front.iloc[doe.knee_points(Fg, log=[False, True, True])] if len(grid_front) else grid_front
    cols = [x.name for x in f] + list(OBJECTIVES)
    fig16 = pres["f_a ≥ 3e4, f_p ≤ 15, f_r ≤ 8"]
    d2s = lambda d: "(" + ", ".join(f"{v:g}" for v in d) + ")"
    findings.append(
        f"Fig. VII.16's filter (f_a ≥ 3e4 mm², f_p ≤ 15 mm, f_r ≤ 8°) keeps {fig16.count} of our designs "
        f"(thesis: 2, Tab. VII.2). The thesis's designs {' and '.join(d2s(d) for d in TAB_VII_2)} give here "
        + "; ".join(f"area {t['area_mm2']:.3g} mm², p_max {t['p_max_mm']:.3g} mm, r_max {t['r_max_deg']:.3g}°"
                    for _, t in thesis.iterrows())
        + f"; {'both are' if all(in_front) else ('one is' if any(in_front) else 'neither is')} on the Pareto front "
        f"of our 243 designs ({len(grid_front)} non-dominated designs).")
    relaxed = study.filter("area_mm2 >= 3e4 and p_max_mm <= 15")
    facts["fig16_without_r"] = relaxed.to_dict()
    if relaxed.count:
        findings.append(
            f"Without its r_max bound, Fig. VII.16's filter keeps {relaxed.count} designs: "
            + "; ".join(f"{v.split('_')[0]} ∈ {{{', '.join(f'{x:g}' for x in relaxed.ranges[v]['levels'])}}}"
                        for v in study.inputs)
            + f" (their r_max is {relaxed.objective_ranges['r_max_deg']['min']:.3g}-"
              f"{relaxed.objective_ranges['r_max_deg']['max']:.3g}°; the smallest r_max of any design with "
              f"f_a ≥ 3e4 mm² is {ok.loc[ok['area_mm2'] >= 3e4, 'r_max_deg'].min():.3g}°).")
    where_p = ok[["p_rd_mm", "p_c_mm", "p_lu_mm"]].to_numpy().argmax(1)
    where_r = ok[["r_rd_deg", "r_c_deg", "r_lu_deg"]].to_numpy().argmax(1)
    names = ("right-down corner", "centre", "left-up corner")
    facts["p_max_at"] = {n: int((where_p == i).sum()) for i, n in enumerate(names)}
    facts["r_max_at"] = {n: int((where_r == i).sum()) for i, n in enumerate(names)}
    findings.append("Where the maximum occurs among the three points of Fig. VII.10: p_max at the "
                    + ", ".join(f"{n} for {int((where_p == i).sum())}" for i, n in enumerate(names))
                    + " designs; r_max at the " + ", ".join(f"{n} for {int((where_r == i).sum())}" for i, n in enumerate(names))
                    + " (thesis, Sec. VIII.1: the rotational error is large at the centre).")
    findings.append("Knees of our grid's Pareto front (best compromises, no thresholds): "
                    + "; ".join(f"{d2s(r[[x.name for x in f]].to_numpy())} -> {r['area_mm2']:.3g} mm², "
                                f"{r['p_max_mm']:.3g} mm, {r['r_max_deg']:.3g}°" for _, r in grid_knees.iterrows()) + ".")

    # NSGA-II on continuous dimensions: area vs p_max vs r_max
    t1 = time.perf_counter()
    pareto = doe.nsga2(factors(continuous=True), ev,
                       [Objective("area_mm2", -1), Objective("p_max_mm", 1, log=True), Objective("r_max_deg", 1, log=True)],
                       pop_size=4 if quick else 16, n_gen=2 if quick else 6, seed=seed,
                       initial=grid_front if len(grid_front) else None,
                       workers=1 if quick else (workers or os.cpu_count() or 1), scheduler=scheduler)
    t_nsga = time.perf_counter() - t1
    knees = pareto[pareto["knee"]]

    # ---- report
    rng = study.objective_ranges(among=ok)
    findings.append(f"Ranges over our designs: p_max [{rng['p_max_mm']['min']:.3g}, {rng['p_max_mm']['max']:.3g}] mm "
                    f"(thesis [7.3, 30.6]), r_max [{rng['r_max_deg']['min']:.3g}, {rng['r_max_deg']['max']:.3g}]° "
                    f"(thesis [5.8, 24.3]), area [{rng['area_mm2']['min']:.3g}, {rng['area_mm2']['max']:.3g}] mm².")
    rep = Report("IRSBot-2 dimension synthesis (Deng 2012, Sec. VII.2.2)",
                 f"{len(df)} designs ({'quick sample' if quick else 'Tab. VII.1 full factorial 3^5'}); fixed parameters "
                 f"Tab. VI.4; clearances Δb = 0.1 mm, Δβ_xy = 0.01 rad in the distal modules and parallelograms; "
                 f"evaluated in {log.seconds:.1f} s ({log.backend})")
    rep.heading("Findings (computed from the entries below)")
    rep.html("<ul>" + "".join(f"<li>{x}</li>" for x in findings) + "</ul>")
    rows = []
    for d, (_, t), fr in zip(TAB_VII_2, thesis.iterrows(), in_front):
        kept = any(((good[[x.name for x in f]].to_numpy() == np.array(d)).all(1))) if len(good) else False
        rows.append([", ".join(f"{v:g}" for v in d), t["area_mm2"], t["p_max_mm"], t["r_max_deg"],
                     "yes" if kept else "no", "yes" if fr else "no"])
    rep.heading("The thesis's good designs (Tab. VII.2) in our model")
    rep.table(rows, ["(l1, l2, a1, a2, p) mm", "area (mm²)", "p_max (mm)", "r_max (deg)", "kept by Fig. VII.16 filter",
                     "on our grid's Pareto front"])
    rep.heading("Parallel coordinates")
    rep.text("One line per design (level grid), NSGA-II Pareto designs on continuous dimensions in orange, knees in red. "
             "Presets apply the filters of Figs. VII.12-VII.16.")
    axes = [Axis(x.name, x.label) for x in f] + [Axis("area_mm2", "area (mm²)"), Axis("p_max_mm", "p_max (mm)", True),
                                                  Axis("r_max_deg", "r_max (deg)", True)]
    pc = add_parcoords(rep, study, axes=axes, color="p_max_mm", extra=pareto, div_id="pc")
    rep.heading("Presets (Figs. VII.12-VII.16)")
    rep.table(preset_table_rows(study), ["preset", "thesis", "query", "kept", "kept levels (mm)"])
    rep.heading("Objective ranges vs the thesis")
    rep.table([[c, f"[{format_tick(rng[c]['min'])}, {format_tick(rng[c]['max'])}]",
                f"[{THESIS_RANGES[c][0]:g}, {THESIS_RANGES[c][1]:g}]" if c in THESIS_RANGES else "–"] for c in OBJECTIVES],
              ["objective", "ours", "thesis (Sec. VII.2.2)"])
    rep.heading("Pareto designs of the level grid and NSGA-II knees")
    rep.table(grid_front[cols].to_numpy().tolist(), [x.label for x in f] + ["area (mm²)", "p_max (mm)", "r_max (deg)"], digits=4)
    rep.text(f"NSGA-II: {len(pareto)} Pareto designs from {pareto.attrs['evotol']['n_evaluations']} evaluations ({t_nsga:.1f} s); knees:")
    rep.table(knees[cols].to_numpy().tolist(), [x.label for x in f] + ["area (mm²)", "p_max (mm)", "r_max (deg)"], digits=4)
    rep.text(f"Workspace: the largest axis-aligned rectangle of x-z points (grid {ev.n_grid} x {ev.n_grid} over the reach) "
             f"below the base in the elbows-out working mode, with the distal links forming a V and "
             f"|sin| of the Type 1 and Type 2 singularity angles ≥ sin {ev.margin_deg:g}°. Pose errors at its right-down "
             f"corner, centre and left-up corner (Fig. VII.10), largest taken.", note=True)
    rep.write(out_dir / f"{NAME}.html")
    pareto_paths = doe.save_entries(pareto, out_dir / f"{NAME}_pareto")

    summary = {
        "study": NAME, "quick": quick, "seed": seed, "n_designs": len(df), "n_feasible": int(df["feasible"].sum()),
        "fixed_parameters_SI": TAB_VI_4,
        "clearance_SI": {**CLEARANCE, "beta_z_active": BETA_Z_ACTIVE, "beta_z_passive": BETA_Z_PASSIVE}, "n_grid": ev.n_grid, "margin_deg": ev.margin_deg,
        "objective_ranges": {k: [v["min"], v["max"]] for k, v in rng.items()}, "thesis_ranges": THESIS_RANGES,
        "presets": {k: {"count": v.count, "ranges": v.ranges, "query": v.resolved_query} for k, v in pres.items()},
        "presets_shown_in_report": pc["presets"],
        "report_lines": {"entries": pc["n_lines"], "drawn_by_default": pc["n_drawn"]},
        "good_designs": good[cols].to_dict(orient="records"),
        "grid_pareto_designs": grid_front[cols].to_dict(orient="records"),
        "grid_knees": grid_knees[cols].to_dict(orient="records"),
        "thesis_designs": [{"design_mm": list(d), "area_mm2": t["area_mm2"], "p_max_mm": t["p_max_mm"],
                            "r_max_deg": t["r_max_deg"], "on_grid_pareto_front": fr}
                           for d, (_, t), fr in zip(TAB_VII_2, thesis.iterrows(), in_front)],
        "findings": findings, "facts": facts,
        "evaluation": {"seconds": log.seconds, "backend": log.backend, "chunks_resumed": len(log.chunks_resumed)},
        "nsga2": {"n_pareto": len(pareto), "n_evaluations": pareto.attrs["evotol"]["n_evaluations"], "seconds": t_nsga,
                  "knees": knees[cols].to_dict(orient="records")},
        "files": {"entries_parquet": paths["parquet"].name, "entries_csv": paths["csv"].name,
                  "pareto_parquet": pareto_paths["parquet"].name},
        "seconds": time.perf_counter() - t0,
    }
    write_json(out_dir / f"{NAME}.json", summary)
    return summary


STUDY = Study(name=NAME, title="IRSBot-2 dimension synthesis on parallel coordinates + NSGA-II (Deng 2012 Sec. VII.2)",
              legacy_run=run, seed_paper="004 Deng 2012 (thesis), Ch. VII")

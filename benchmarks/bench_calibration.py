"""Benchmark of calibrated studies (issue 36 item 8): the calibrated UR5 study against the uncalibrated one.

Prints, in one run: the wall time of ``evotol run`` of ``reports/studies/ur5_urdf.toml`` and of
``reports/studies/ur5_calibrated.toml`` at the same 1 000 Latin-hypercube task poses (methods: the
sensitivity rule and the certified optimum; Monte Carlo verification with 300 samples; the
calibrated one also identifies, bounds the calibrated sources, allocates the uncalibrated optimum
for its comparison and simulates 200 calibrations per design), their ratio (target <= 2), and the
parts of the calibrated run. With ``--table``: the UR5 table of ``docs/calibration.md`` (uncalibrated,
offsets only, every identifiable; 200 simulated calibrations each).

Absolute times depend on the load of this shared 2-core machine; compare the ratio measured in one run.

Run: ``python benchmarks/bench_calibration.py`` (``--poses 200`` for a quicker run, ``--table``).
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _study(name: str, poses: int, out: Path) -> Path:
    text = (ROOT / "reports/studies" / f"{name}.toml").read_text().replace("grid = [3, 3, 3]", f"latin_hypercube = {poses}")
    text = text[:text.index("[methods]")] + "[methods]\nsensitivity = {}\noptimum = {}\n\n[verify]\nn_samples = 300\n"
    path = out / f"{name}.toml"
    path.write_text(text)
    return path


def table() -> None:
    """Print the UR5 table of docs/calibration.md."""
    import numpy as np

    from evotol.allocators import allocate_optimum
    from evotol.calibration import CalibrationPlan, calibrated_problem, simulate_calibration
    from evotol.errors import ValidationError
    from evotol.studyfile import load_problem

    spec = tomllib.loads((ROOT / "reports/studies/ur5_urdf.toml").read_text())
    P = load_problem(spec, base_dir=ROOT / "reports/studies")
    r0 = allocate_optimum(P)
    print(f"uncalibrated: certified optimum {r0.cost:.4f}")
    off = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint"]
    cases = [("task box, 5 offsets, first order only (noise 0, linear range off)", dict(noise=0.0, identify=off, linear_fraction=1e8)),
             ("task box, 5 offsets, 20 um", dict(noise="20 um", identify=off)),
             ("joint space, 5 offsets, 20 um", dict(noise="20 um", identify=off, over="joints")),
             ("task box, every identifiable, 20 um", dict(noise="20 um")),
             ("task box, every identifiable, 2 um", dict(noise="2 um")),
             ("joint space, every identifiable, 20 um", dict(noise="20 um", over="joints")),
             ("joint space, every identifiable, 20 um, instrument unknown", dict(noise="20 um", over="joints", instrument="unknown"))]
    for label, kw in cases:
        try:
            pc = calibrated_problem(P, CalibrationPlan(count=40, seed=0, **kw))
        except ValidationError as exc:
            print(f"{label}: refused: {exc}")
            continue
        idn, nz = pc.calibration.identification, pc.calibration.noise["position"]
        r = allocate_optimum(pc)
        chk = simulate_calibration(pc, r.t, n_samples=200, seed=1)
        print(f"{label}: identified {len(idn.identified)} + {len(idn.registration)} registration, rank {idn.rank}, "
              f"condition {idn.condition:.3g}; noise sigma {nz['sigma'] * 1e3:.4f} mm, 3 sigma {nz['allowance'] * 1e3:.4f} mm, "
              f"second order {nz['second_order'] * 1e3:.3g} mm; optimum {r.cost:.4f} ({100 * (1 - r.cost / r0.cost):.1f} % less, "
              f"{int(np.sum(np.isclose(r.t, pc.upper, rtol=1e-6)))} at the upper bound); simulated max "
              f"{chk.simulated['position']['max'] * 1e3:.4f} mm vs first order {chk.predicted['position']['max'] * 1e3:.4f} mm "
              f"(largest difference {chk.difference['position'] * 1e3:.3g} mm, {chk.nls_failures} fit failures)")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=1000, help="task poses (default 1000)")
    ap.add_argument("--table", action="store_true", help="also print the UR5 table of docs/calibration.md")
    args = ap.parse_args(argv)
    from evotol.studyfile import run_study_file

    print(f"load average {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        times = {}
        for name in ("ur5_urdf", "ur5_calibrated"):
            path = _study(name, args.poses, d)
            t0 = time.perf_counter()
            summary = run_study_file(path, out=d)
            times[name] = time.perf_counter() - t0
            cal = summary.get("calibration")
            extra = ""
            if cal:
                sims = sum(m.get("simulation", {}).get("seconds", 0.0) for m in cal["methods"].values())
                extra = (f"; optimum {cal['methods']['optimum']['cost']:.4f} vs uncalibrated {cal['uncalibrated']['cost']:.4f}, "
                         f"simulated calibrations {sims:.1f} s")
            print(f"{name}: {times[name]:.1f} s at {args.poses} poses{extra}")
    ratio = times["ur5_calibrated"] / times["ur5_urdf"]
    print(f"calibrated / uncalibrated: {ratio:.2f} (target <= 2): {'OK' if ratio <= 2 else 'MISSED'}")
    if args.table:
        table()


if __name__ == "__main__":
    main()

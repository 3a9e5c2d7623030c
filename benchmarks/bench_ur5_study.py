"""UR5 study benchmark (issue 43's table: "UR5 study (``ur5_urdf.toml``), 27 -> 216 -> 1 000 poses; target
1 000 poses <= 6 s"). Runs ``evotol run`` on ``reports/studies/ur5_urdf.toml`` as shipped (sensitivity,
optimum, GA of 80 x 150, Monte Carlo of 300 samples a pose on the nonlinear model, page and JSON) on grids of
3, 6 and 10 poses a side, each in its own process, and prints the wall time of each (the interpreter's start
and imports included, as a user sees it). The line ``N poses: X s wall`` is the one benchmarks/run_all.py
puts beside the target.

    python benchmarks/bench_ur5_study.py [--grids 3 6 10]
"""
import argparse
import os
import tempfile
from pathlib import Path

from bench_many_poses import run_text, shipped_text


def main(grids: list[int]) -> None:
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; reports/studies/ur5_urdf.toml as shipped "
          "(sensitivity, optimum, GA 80 x 150, Monte Carlo 300 samples a pose), page and JSON")
    with tempfile.TemporaryDirectory() as tmp:
        for n in grids:
            wall, _ = run_text(shipped_text(n), f"ur5_{n}", Path(tmp))
            print(f"  UR5 study, {n ** 3:5d} poses: {wall:.1f} s wall (load {os.getloadavg()[0]:.1f})", flush=True)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--grids", type=int, nargs="+", default=[3, 6, 10])
    main(ap.parse_args().grids)

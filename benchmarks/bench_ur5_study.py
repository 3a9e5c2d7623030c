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
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "reports" / "studies" / "ur5_urdf.toml"


def run(n: int, folder: Path) -> float:
    """Wall seconds of ``evotol run`` of the shipped UR5 study on an n x n x n grid, in a child process."""
    text = STUDY.read_text().replace("grid = [3, 3, 3]", f"grid = [{n}, {n}, {n}]")
    text = text.replace('mechanism = "ur5"', f'mechanism = "{ROOT / "robots" / "mechanisms" / "ur5.toml"}"')
    path = folder / f"ur5_{n}.toml"
    path.write_text(text)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "evotol.cli", "run", str(path), "--out", str(folder / f"out{n}")],
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"evotol run of {n}^3 poses failed: {proc.stderr[-2000:]}")
    return time.perf_counter() - t0


def main(grids: list[int]) -> None:
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; reports/studies/ur5_urdf.toml as shipped "
          "(sensitivity, optimum, GA 80 x 150, Monte Carlo 300 samples a pose), page and JSON")
    with tempfile.TemporaryDirectory() as tmp:
        for n in grids:
            print(f"  UR5 study, {n ** 3:5d} poses: {run(n, Path(tmp)):.1f} s wall (load {os.getloadavg()[0]:.1f})",
                  flush=True)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--grids", type=int, nargs="+", default=[3, 6, 10])
    main(ap.parse_args().grids)

"""Many poses benchmark (issue 43 item 4: memory that grows with what is kept; 100 000 poses in <= 4 GB
and <= 60 s). Runs ``evotol run`` on the UR5 study (``reports/studies/ur5_urdf.toml``: 36 sources, the
tool pointing down over a 200 mm box) with a finer grid, the ``sensitivity`` method and a Monte Carlo of
100 samples a pose on the nonlinear model (page and JSON written), each size in its own process, and
prints its wall time and peak memory (the child's maximum resident set size), then the memory a pose adds
between the two sizes. The lines ``N poses: X s wall, Y GB`` and ``per pose: Z kB`` are the ones
benchmarks/run_all.py puts beside issue 43's targets.

    python benchmarks/bench_many_poses.py [--grids 22 47]
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "reports" / "studies" / "ur5_urdf.toml"


def shipped_text(n: int) -> str:
    """``ur5_urdf.toml`` as shipped on an n x n x n grid (its mechanism file named by its path)."""
    text = STUDY.read_text().replace("grid = [3, 3, 3]", f"grid = [{n}, {n}, {n}]")
    return text.replace('mechanism = "ur5"', f'mechanism = "{ROOT / "robots" / "mechanisms" / "ur5.toml"}"')


def study_text(n: int) -> str:
    """The UR5 study on an n x n x n grid, sensitivity only, 100 Monte Carlo samples a pose."""
    text = re.sub(r"\[methods\].*?\n\n", "[methods]\nsensitivity = {}\n\n", shipped_text(n), flags=re.S)
    return text.replace("n_samples = 300", "n_samples = 100")


def run_text(text: str, name: str, folder: Path) -> tuple[float, float]:
    """(wall s, peak resident GB) of ``evotol run`` of the study file ``text`` in a child process."""
    path = folder / f"{name}.toml"
    path.write_text(text)
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "evotol.cli", "run", str(path), "--out", str(folder / f"out_{name}")],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    if status != 0:
        raise SystemExit(f"evotol run of {name} failed: {proc.stderr.read()[-2000:]}")
    return wall, usage.ru_maxrss * 1024 / 1e9            # ru_maxrss: kB on Linux


def run(n: int, folder: Path) -> tuple[float, float]:
    """(wall s, peak resident GB) of ``evotol run`` of the n³-pose study in a child process."""
    return run_text(study_text(n), f"ur5_{n}", folder)


def main(grids: list[int]) -> None:
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; UR5 study, sensitivity + Monte Carlo "
          "(100 samples a pose, nonlinear model), page and JSON")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in grids:
            wall, gb = run(n, Path(tmp))
            rows.append((n ** 3, wall, gb))
            print(f"  {n ** 3:7d} poses: {wall:.1f} s wall, {gb:.3f} GB peak (load {os.getloadavg()[0]:.1f})", flush=True)
    if len(rows) > 1:
        (p0, _, m0), (p1, w1, m1) = rows[0], rows[-1]
        per = (m1 - m0) * 1e9 / (p1 - p0)
        print(f"  per pose: {per / 1e3:.1f} kB (target <= 20 kB); {p1} poses: {w1:.1f} s (target <= 60 s for 100 000), "
              f"{m1:.2f} GB (target <= 4 GB)")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--grids", type=int, nargs="+", default=[22, 47])
    main(ap.parse_args().grids)

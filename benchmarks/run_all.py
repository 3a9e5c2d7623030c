"""Run every benchmark in this folder, one after the other, print what each measures, then every
ratio of the run side by side with its target (issue 43 item 6).

    python benchmarks/run_all.py [--only urdf,stack]

Each script's output is shown as it runs and kept; at the end:

1. **the issue's table**: the measures issue 43 set targets for, read from the scripts' lines (the
   same run, so one machine load for all), with the target beside each value and OK / MISSED;
2. **every other ratio or target line** the scripts printed, one per line, prefixed by its script.

The load average of the machine is printed at the start and the end (a shared machine measures
wall time slower; the URDF script also prints CPU seconds).
"""
from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import time
from pathlib import Path

here = Path(__file__).resolve().parent

#: (script, label, regex whose named groups pick the value, target text, test of the value)
TARGETS = [
    ("bench_urdf.py", "{arm} sensitivities at joints vs Pinocchio regressor loop, {n} poses",
     r"^(?P<arm>UR5|Panda): |^\s+(?P<n>\d+) poses\s+sensitivities at joints .*ratio (?P<v>[\d.]+)", "<= 0.4",
     lambda v: v <= 0.4),
    ("bench_urdf.py", "{arm} with inverse geometry vs Pinocchio IK + regressor, {n} poses",
     r"^(?P<arm>UR5|Panda): |^\s+(?P<n>\d+) poses\s+with inverse geometry .*ratio (?P<v>[\d.]+)", "<= 0.15",
     lambda v: v <= 0.15),
    ("bench_urdf.py", "{arm} nonlinear Monte Carlo kernel (pose-samples/s, wall)",
     r"^(?P<arm>UR5|Panda): |^\s+pose_error: .*\((?P<v>[\d.e+]+) wall\)", ">= 1e7", lambda v: v >= 1e7),
    ("bench_urdf.py", "UR5 study verification, verify_nonlinear (pose-samples/s, wall)",
     r"^UR5 study verification after .*\((?P<v>[\d.e+]+) wall\)", ">= 1e7", lambda v: v >= 1e7),
    ("bench_urdf.py", "UR5 study verification, verify_nonlinear's Monte Carlo (slope 300 -> 3 000 samples, wall)",
     r"^\s+its Monte Carlo \(the slope .*\((?P<v>[\d.e+]+) wall\)", ">= 1e7", lambda v: v >= 1e7),
    ("bench_many_poses.py", "UR5 study, {n} poses: wall time (s)",
     r"^\s*(?P<n>\d{6,}) poses: (?P<v>[\d.]+) s wall", "100 000 in <= 60 s", lambda v: v <= 60.0),
    ("bench_many_poses.py", "UR5 study, {n} poses: peak memory (GB)",
     r"^\s*(?P<n>\d+) poses: [\d.]+ s wall, (?P<v>[\d.]+) GB peak", "<= 4 GB", lambda v: v <= 4.0),
    ("bench_many_poses.py", "UR5 study: memory a pose adds (kB)",
     r"^\s*per pose: (?P<v>[\d.]+) kB", "<= 20 kB", lambda v: v <= 20.0),
    ("bench_ur5_study.py", "UR5 study (ur5_urdf.toml as shipped), {n} poses: evotol run wall time (s)",
     r"^\s*UR5 study, \s*(?P<n>1000) poses: (?P<v>[\d.]+) s wall", "1 000 poses in <= 6 s",
     lambda v: v <= 6.0),
    ("bench_stack.py", "[stack.allocation] worst-case optimum, {n} dimensions (s)",
     r"^\s*(?P<n>\d+) dimensions: optimum (?P<v>[\d.]+) s", "5 000 in <= 2 s",
     lambda v: v <= 2.0),
    ("bench_polyblock.py", "monotone allocator on the UR5 study's 36 sources, default budget (s)",
     r"^monotone allocator, UR5 study .*: (?P<v>[\d.]+) s wall", "seconds (<= 10 s)", lambda v: v <= 10.0),
    ("bench_stack.py", "refusal of rss on asymmetric zones, {n} dimensions (s)",
     r"^\s*(?P<n>\d+) dimensions: rss refusal after (?P<v>[\d.]+) s", "before any work (<= 0.5 s)",
     lambda v: v <= 0.5),
]


def issue_table(outputs: dict) -> list[str]:
    """Rows ``label | value | target | OK/MISSED`` of :data:`TARGETS` found in the outputs."""
    rows = []
    for script, label, pattern, target, ok in TARGETS:
        ctx = {"arm": "", "n": ""}
        for line in outputs.get(script, "").splitlines():
            m = re.search(pattern, line)
            if not m:
                continue
            got = {k: v for k, v in m.groupdict().items() if v is not None}
            if "v" not in got:
                ctx.update(got)
                continue
            ctx.update({k: v for k, v in got.items() if k != "v"})
            v = float(got["v"])
            rows.append(f"{label.format(**ctx):72s} {v:>10.3g}   target {target:>18s}   {'OK' if ok(v) else 'MISSED'}")
    return rows


def main(only: list[str] | None = None) -> None:
    outputs = {}
    print(f"load average at start {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores", flush=True)
    for script in sorted(here.glob("bench_*.py")):
        if only and not any(o in script.name for o in only):
            continue
        print(f"\n##### {script.name}", flush=True)
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, str(script)], cwd=here.parent, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)
        lines = []
        for line in proc.stdout:
            print(line, end="", flush=True)
            lines.append(line)
        rc = proc.wait()
        outputs[script.name] = "".join(lines)
        print(f"##### {script.name}: exit {rc}, {time.perf_counter() - t0:.1f} s", flush=True)
    print(f"\n===== issue 43's targets, this run (load average now {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    for row in issue_table(outputs) or ["(no targeted measure in the scripts run)"]:
        print(row)
    print("\n===== every ratio and target line of this run")
    for name, text in outputs.items():
        for line in text.splitlines():
            if re.search(r"ratio|target|pose-samples/s", line, re.I):
                print(f"{name:22s} {line.strip()}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", help="comma-separated parts of script names to run (default: all)")
    a = ap.parse_args()
    main(a.only.split(",") if a.only else None)

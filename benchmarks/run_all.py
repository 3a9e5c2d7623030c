"""Run every benchmark in this folder, one after the other, and print what each measures.

    python benchmarks/run_all.py
"""
import subprocess
import sys
import time
from pathlib import Path

here = Path(__file__).resolve().parent
for script in sorted(here.glob("bench_*.py")):
    print(f"\n##### {script.name}", flush=True)
    t0 = time.perf_counter()
    rc = subprocess.call([sys.executable, str(script)], cwd=here.parent)
    print(f"##### {script.name}: exit {rc}, {time.perf_counter() - t0:.1f} s", flush=True)

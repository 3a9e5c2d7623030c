"""Design-study benchmark (issue 3): prints measured times in one run.

1. the 32 768-entry 5-bar full factorial (Deng 2012 Sec. VII.1.2) on the certified clearance
   engine, on all local cores -- target < 120 s;
2. the 243-design IRSBot-2 dimension synthesis (Sec. VII.2.2) end to end -- target < 120 s;
3. the parallel-coordinate report in headless Chromium at 1 000, 8 192 and 32 768 lines: time to
   open, time until a preset's count is shown (JavaScript read-outs), time until the WebGL redraw
   of the lines is done, longest main-thread task while redrawing.

    python benchmarks/bench_synthesis.py [--skip-5bar] [--skip-irsbot2] [--skip-browser] [--workers N]
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd


def machine() -> str:
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    return f"{os.cpu_count()} cores, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}"


def bench_fivebar(workers: int | None, out: Path) -> pd.DataFrame:
    from evotol import doe
    from evotol.studies import deng2012_tolsynth as ts

    E = doe.full_factorial(ts.factors())
    ev = ts.FiveBarToleranceEvaluator()
    # per-entry cost of one vectorised chunk in this process (after building the pose maps)
    ev(E.iloc[:8])
    for n in (1024, 4096):
        t = time.perf_counter()
        ev(E.iloc[:n])
        dt = time.perf_counter() - t
        print(f"  one chunk of {n:5d} entries in-process: {dt:6.2f} s  ({1e3 * dt / n:.2f} ms/entry)")
    log = doe.EvaluationLog()
    t = time.perf_counter()
    df = doe.evaluate(E, ev, workers=workers, chunk_size=4096, progress=False, log=log)
    dt = time.perf_counter() - t
    print(f"  full factorial {len(df)} entries: {dt:.1f} s on {log.backend} "
          f"({len(df) / dt:.0f} entries/s) -> target < 120 s: {'MET' if dt < 120 else 'NOT MET'}  [{machine()}]")
    gap = np.max(np.maximum(df["p_upper_mm"] / df["p_max_mm"], df["r_upper_deg"] / df["r_max_deg"]) - 1)
    print(f"  largest relative certificate gap: {gap:.1e}")
    return df


def bench_irsbot2(workers: int | None, out: Path) -> None:
    from evotol.errors import EvotolError
    from evotol.studies import deng2012_dimsynth as ds

    t = time.perf_counter()
    try:
        s = ds.run(out / "irsbot2", workers=workers, progress=False)
    except EvotolError as exc:
        print(f"  not run: {exc}")
        return
    dt = time.perf_counter() - t
    print(f"  243 designs end to end (workspace, 3 x 114-variable pose errors, NSGA-II, report): {dt:.1f} s "
          f"(design evaluation {s['evaluation']['seconds']:.1f} s, NSGA-II {s['nsga2']['seconds']:.1f} s) "
          f"-> target < 120 s: {'MET' if dt < 120 else 'NOT MET'}  [{machine()}]")


def bench_browser(entries: pd.DataFrame, out: Path) -> None:
    from evotol.filtering import DesignStudy, Preset
    from evotol.reporting.headless import HeadlessChromium, find_chromium
    from evotol.reporting.html import Report
    from evotol.reporting.parcoords import Axis, add_parcoords

    if find_chromium() is None:
        print("  skipped: no chromium on PATH")
        return
    study = DesignStudy(entries, objectives=["p_max_mm", "r_max_deg", "cost"],
                        presets=[Preset("p_max ≤ 0.05 mm", {"p_max_mm": (None, 0.05)}, "Fig. VII.4")])
    axes = ([Axis(c, c, True) for c in study.inputs]
            + [Axis("cost", "cost", True), Axis("p_max_mm", "p_max (mm)", True), Axis("r_max_deg", "r_max (deg)", True)])
    rng = np.random.default_rng(0)
    print("  headless Chromium, WebGL by the SwiftShader software rasteriser (no GPU on this machine):")
    for n in (1000, 8192, len(entries)):
        sub = entries.iloc[np.sort(rng.choice(len(entries), n, replace=False))] if n < len(entries) else entries
        rep = Report("bench", "")
        info = add_parcoords(rep, study, axes=axes, among=sub, color="p_max_mm")
        path = rep.write(out / f"parcoords_{n}.html")
        with HeadlessChromium() as browser:
            t = time.perf_counter()
            page = browser.open(path, timeout=300)
            page.wait_for("document.getElementById('pc').getAttribute('data-ready')", timeout=300)
            t_open = time.perf_counter() - t
            page.evaluate("window.__lt = []; new PerformanceObserver(function(l){ l.getEntries().forEach("
                          "function(e){ window.__lt.push(e.duration); }); }).observe({entryTypes: ['longtask']}); 1")
            page.evaluate("document.querySelector('button[data-preset=\"p_max ≤ 0.05 mm\"]').click(); 1")
            ms = float(page.wait_for("document.getElementById('pc').getAttribute('data-apply-ms')", timeout=300))
            count_ms = float(page.evaluate("document.getElementById('pc').getAttribute('data-count-ms')"))
            shown = int(page.evaluate("document.getElementById('pc-count-n').textContent"))
            time.sleep(1.0)
            tasks = page.evaluate("window.__lt") or [0]
        ok = "matches" if shown == info["presets"]["p_max ≤ 0.05 mm"] else "DIFFERS from"
        print(f"  {n:6d} lines: open {t_open:5.1f} s; preset count shown after {count_ms:6.1f} ms ({shown}, {ok} Python); "
              f"lines redrawn after {ms / 1e3:5.1f} s; longest main-thread task {max(tasks) / 1e3:4.1f} s")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--skip-5bar", action="store_true")
    ap.add_argument("--skip-irsbot2", action="store_true")
    ap.add_argument("--skip-browser", action="store_true")
    args = ap.parse_args(argv)
    print(f"evotol design-study benchmark [{machine()}]")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        entries = None
        if not args.skip_5bar:
            print("5-bar tolerance synthesis, full factorial 4^5 x 2^5:")
            entries = bench_fivebar(args.workers, out)
        if not args.skip_irsbot2:
            print("IRSBot-2 dimension synthesis, 3^5 designs:")
            bench_irsbot2(args.workers, out)
        if not args.skip_browser:
            print("parallel-coordinate report:")
            if entries is None:
                from evotol import doe
                from evotol.studies import deng2012_tolsynth as ts

                entries = doe.evaluate(doe.random_subset(ts.factors(), 8192, seed=0), ts.FiveBarToleranceEvaluator(),
                                       progress=False, chunk_size=4096)
            bench_browser(entries, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

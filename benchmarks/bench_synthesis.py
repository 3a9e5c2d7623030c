"""Design-study benchmark (issue 3): prints measured times in one run.

1. the 32 768-entry 5-bar full factorial (Deng 2012 Sec. VII.1.2) on the certified clearance
   engine, on all local cores -- target < 120 s;
2. the 243-design IRSBot-2 dimension synthesis (Sec. VII.2.2) end to end -- target < 120 s;
3. the parallel-coordinate report of all entries in headless Chromium, drawing the default
   sample and drawing every line, on the two software WebGL renderers this machine has
   (SwiftShader, Mesa llvmpipe): time to open, time until a preset's count is shown (JavaScript
   read-outs), time until its lines are drawn (the rasteriser finished), time per mouse move
   while brushing an axis by hand.

    python benchmarks/bench_synthesis.py [--skip-5bar] [--skip-irsbot2] [--skip-browser] [--workers N]
                                         [--entries ENTRIES.parquet | --report REPORT.html]
"""
from __future__ import annotations

import argparse
import json
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
    from evotol import design as doe
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
        s = ds.STUDY.run(out / "irsbot2", workers=workers)         # the study as `evotol reproduce` runs it
    except EvotolError as exc:
        print(f"  not run: {exc}")
        return
    dt = time.perf_counter() - t
    print(f"  243 designs end to end (workspace, 3 x 114-variable pose errors, NSGA-II, report): {dt:.1f} s "
          f"(design evaluation {s['evaluation']['seconds']:.1f} s, NSGA-II {s['nsga2']['seconds']:.1f} s) "
          f"-> target < 120 s: {'MET' if dt < 120 else 'NOT MET'}  [{machine()}]")


# JavaScript: resolve when every queued parcoords draw has run and the GPU (or its software
# emulation) has finished it -- plotly draws 5 000 lines per animation frame, then a 1-pixel
# readPixels on each WebGL canvas waits for the rasteriser.
GL_FINISHED = """new Promise(function(res){ var gd = document.getElementById('pc'), t0 = performance.now();
  var n = Number(gd.getAttribute('data-drawn')) || 1, frames = Math.ceil(n / 5000) + 1;
  (function w(k){ if(k > 0){ requestAnimationFrame(function(){ w(k - 1); }); return; }
    var px = new Uint8Array(4);
    document.querySelectorAll('canvas.gl-canvas').forEach(function(c){ var gl = c.getContext('webgl');
      if(gl) gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px); });
    res(performance.now() - t0); })(frames); })"""

def measure_page(path: Path, preset: str, draw_all: bool, renderer: str) -> dict:
    """Open a parcoords report, apply a preset, brush an axis by hand; wall-clock numbers (s)."""
    from evotol.reporting.headless import HeadlessChromium

    with HeadlessChromium(webgl=renderer) as browser:
        t = time.perf_counter()
        page = browser.open(path, timeout=600)
        page.wait_for("document.getElementById('pc').getAttribute('data-ready')", timeout=600)
        if draw_all:
            page.evaluate("window.evotolParcoords['pc'].setDraw(true).then(function(){ return 1; })", timeout=600)
        page.evaluate(GL_FINISHED, timeout=600)
        out = {"open": time.perf_counter() - t,
               "renderer": page.evaluate("document.getElementById('pc').getAttribute('data-renderer')"),
               "drawn": int(page.evaluate("document.getElementById('pc').getAttribute('data-drawn')"))}
        t = time.perf_counter()
        page.evaluate(f"window.evotolParcoords['pc'].apply({preset!r})", timeout=600)
        page.evaluate(GL_FINISHED, timeout=600)
        out["preset_drawn"] = time.perf_counter() - t
        out["count_ms"] = float(page.evaluate("document.getElementById('pc').getAttribute('data-count-ms')"))
        out["shown"] = int(page.evaluate("document.getElementById('pc-count-n').textContent"))
        # brush by hand: press on the last axis (r_max), drag in 10 steps, release
        page.evaluate("document.getElementById('pc').scrollIntoView(); 1")
        x, top, h = page.evaluate("(function(){ var bs = document.querySelectorAll('#pc .axis-brush .background');"
                                  "var b = bs[bs.length - 1].getBoundingClientRect(); return [b.left + b.width / 2, b.top, b.height]; })()")

        def mouse(kind, y, buttons=1):
            page.send("Input.dispatchMouseEvent", {"type": kind, "x": x, "y": y, "button": "left",
                                                   "buttons": buttons, "clickCount": 1}, timeout=600)
        mouse("mousePressed", top + 0.05 * h)
        steps = []
        for k in range(1, 11):
            t = time.perf_counter()
            mouse("mouseMoved", top + (0.05 + 0.05 * k) * h)
            steps.append(time.perf_counter() - t)
        t = time.perf_counter()
        mouse("mouseReleased", top + 0.55 * h, 0)
        page.evaluate(GL_FINISHED, timeout=600)
        out["brush_step_median"], out["brush_step_max"] = float(np.median(steps)), max(steps)
        out["brush_release"] = time.perf_counter() - t
        out["brush_count"] = int(page.evaluate("document.getElementById('pc-count-n').textContent"))
        out["brushed"] = bool(page.evaluate("(function(){ var d = document.getElementById('pc').data[0].dimensions;"
                                            "return !!d[d.length - 1].constraintrange; })()"))
    return out


def bench_browser(entries: pd.DataFrame | None, out: Path, renderers=("swiftshader", "llvmpipe"),
                  report: Path | None = None) -> None:
    from evotol.design.filtering import DesignStudy, Preset
    from evotol.reporting.headless import find_chromium
    from evotol.reporting.html import Report
    from evotol.reporting.parcoords import DEFAULT_MAX_DRAWN, Axis, add_parcoords

    if find_chromium() is None:
        print("  skipped: no chromium on PATH")
        return
    preset = "p_max ≤ 0.05 mm"
    if report is not None:      # a study's own report (e.g. reports/deng2012-tolsynth.html)
        print(f"  {report}: default sample vs all lines; this machine has no GPU, so WebGL is emulated on the CPU "
              f"(times in s; 'step' = one mouse move while brushing):")
        meta = report.with_suffix(".json")      # the study's JSON holds the counts Python computed
        python_count = json.loads(meta.read_text()).get("presets_shown_in_report", {}).get(preset) if meta.exists() else None
        _measure_and_print(report, preset, python_count, renderers)
        return
    study = DesignStudy(entries, objectives=["p_max_mm", "r_max_deg", "cost"],
                        presets=[Preset(preset, {"p_max_mm": (None, 0.05)}, "Fig. VII.4")])
    axes = ([Axis(c, c, True) for c in study.inputs]
            + [Axis("cost", "cost", True), Axis("p_max_mm", "p_max (mm)", True), Axis("r_max_deg", "r_max (deg)", True)])
    rep = Report("bench", "")
    info = add_parcoords(rep, study, axes=axes, color="p_max_mm")
    path = rep.write(out / "parcoords.html")
    n = info["n_lines"]
    print(f"  {n} entries, {len(axes)} axes, default sample {DEFAULT_MAX_DRAWN} lines; this machine has no GPU, "
          f"so WebGL is emulated on the CPU (times in s; 'step' = one mouse move while brushing):")
    _measure_and_print(path, preset, info["presets"][preset], renderers)


def _measure_and_print(path: Path, preset: str, python_count: int | None, renderers) -> None:
    for renderer in renderers:
        rows = {}
        for draw_all in (False, True):
            try:
                r = measure_page(path, preset, draw_all, renderer)
            except Exception as exc:   # a renderer this Chromium cannot start is reported, not fatal
                print(f"  {renderer}: not measured ({type(exc).__name__}: {exc})")
                break
            rows[draw_all] = r
            ok = "" if python_count is None else ("= Python" if r["shown"] == python_count else "DIFFERS from Python")
            print(f"  {renderer:11s} {r['drawn']:6d} lines drawn: open {r['open']:5.1f}; preset -> count shown in "
                  f"{r['count_ms']:5.1f} ms ({r['shown']} {ok}), lines drawn {r['preset_drawn']:5.2f}; brush step median "
                  f"{r['brush_step_median']:5.2f} max {r['brush_step_max']:5.2f}, after release {r['brush_release']:5.2f} "
                  f"({'count ' + str(r['brush_count']) if r['brushed'] else 'BRUSH NOT APPLIED'})  "
                  f"[{r['renderer']}]")
        if len(rows) == 2:
            s_, a_ = rows[False], rows[True]
            print(f"  {renderer}: all lines / sample -- open x{a_['open'] / s_['open']:.1f}, preset redraw "
                  f"x{a_['preset_drawn'] / s_['preset_drawn']:.1f}, brush step x{a_['brush_step_median'] / s_['brush_step_median']:.1f}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--skip-5bar", action="store_true")
    ap.add_argument("--skip-irsbot2", action="store_true")
    ap.add_argument("--skip-browser", action="store_true")
    ap.add_argument("--report", type=Path, default=None,
                    help="measure this parcoords report (div 'pc', e.g. reports/deng2012-tolsynth.html) in the browser part")
    ap.add_argument("--entries", type=Path, default=None,
                    help="entries (.parquet) for the browser part instead of the factorial just evaluated, "
                         "e.g. reports/deng2012-tolsynth_entries.parquet")
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
            if args.report is not None:
                bench_browser(None, out, report=args.report)
                return 0
            if args.entries is not None:
                entries = pd.read_parquet(args.entries)
            if entries is None:
                from evotol import design as doe
                from evotol.studies import deng2012_tolsynth as ts

                entries = doe.evaluate(doe.random_subset(ts.factors(), 8192, seed=0), ts.FiveBarToleranceEvaluator(),
                                       progress=False, chunk_size=4096)
            bench_browser(entries, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

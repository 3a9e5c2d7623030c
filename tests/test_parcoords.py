"""Parallel-coordinate report (evotol.reporting.parcoords; Deng 2012 Figs. VII.1-VII.8).

The browser test opens the written HTML in headless Chromium, clicks a preset button and checks
that the count the page shows equals the count Python's DesignStudy.filter computed; brushing an
axis by hand (a plotly restyle, what a drag does) updates the count too.
"""
from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd
import pytest

from evotol import design as doe
from evotol.errors import ValidationError
from evotol.design.filtering import DesignStudy, Preset
from tests.browser import require_chromium
from evotol.reporting.html import Report
from evotol.reporting.parcoords import (KNEE, PARETO, Axis, add_parcoords, default_axes, drawn_lines, format_tick,
                                        log_ticks, parcoords_figure, parcoords_frame, preset_table_rows)

LEVELS_XY, LEVELS_Z = (1e-4, 1e-3, 1e-2, 1e-1), (1e-3, 1e-1)


class SerialChainClearance:
    """p_max (mm) = sqrt((Σ Δb_xy)² + (Σ Δb_z)²) of a translational-clearance serial chain."""

    def __call__(self, X):
        xy = X[[c for c in X if c.startswith("db_xy")]].to_numpy().sum(1)
        z = X[[c for c in X if c.startswith("db_z")]].to_numpy().sum(1)
        return pd.DataFrame({"p_max_mm": np.hypot(xy, z), "r_max_deg": np.degrees(xy / 20.0)})


def make_study(n_joints=3):
    f = ([doe.Factor(f"db_xy_{j}_mm", LEVELS_XY, log=True, label=f"Δb_xy {j} (mm)", si_scale=1e-3) for j in "ABCDE"[:n_joints]]
         + [doe.Factor(f"db_z_{j}_mm", LEVELS_Z, log=True, label=f"Δb_z {j} (mm)", si_scale=1e-3) for j in "ABCDE"[:n_joints]])
    df = doe.evaluate(doe.full_factorial(f), SerialChainClearance(), workers=1, progress=False)
    presets = [Preset("p_max ≥ 0.2 mm", {"p_max_mm": (0.2, None)}, "Fig. VII.3 (scaled)"),
               Preset("p_max ≤ 0.05 mm", {"p_max_mm": (None, 0.05)}, "Fig. VII.4"),
               Preset("r_max ≤ 0.01°", {"r_max_deg": (None, 0.01)}, "Fig. VII.8"),
               Preset("Δb_xy A = 0.1", {"db_xy_A_mm": (0.1, 0.1)}, "input filter")]
    return DesignStudy(df, presets=presets, name="toy")


def pareto_like(study, n=12):
    """A few off-grid entries standing in for NSGA-II output, one marked as knee."""
    rng = np.random.default_rng(0)
    e = pd.DataFrame({c: 10 ** rng.uniform(-4, -1, n) for c in study.inputs})
    ev = SerialChainClearance()(e)
    e = pd.concat([e, ev], axis=1)
    e["knee"] = np.arange(n) == 3
    return e


def test_format_and_log_ticks_are_readable():
    assert format_tick(1e-4) == "0.0001" and format_tick(0.05) == "0.05" and format_tick(200.0) == "200"
    assert format_tick(1e-6) == "10⁻⁶" and format_tick(2e-7) == "2·10⁻⁷"
    vals, text = log_ticks(-4.05, -0.95)
    assert text == ["0.0001", "0.001", "0.01", "0.1"] and np.allclose(vals, [-4, -3, -2, -1])
    vals, text = log_ticks(-2.0, -1.0)           # one decade: 1-2-5 ticks
    assert text == ["0.01", "0.02", "0.05", "0.1"]


def test_figure_draws_log10_axes_and_colours_extra_entries_apart():
    st = make_study()
    extra = pareto_like(st)
    axes = [Axis(c, c, log=True) for c in st.inputs] + [Axis("p_max_mm", "p_max (mm)", True), Axis("r_max_deg", "r (deg)", True)]
    frame = parcoords_frame(st, extra=extra)
    fig = parcoords_figure(frame, axes, "p_max_mm")
    dims = fig.data[0].dimensions
    assert dims[0].label == "source" and list(dims[0].ticktext) == ["level grid", PARETO, KNEE]
    np.testing.assert_allclose(dims[1].values, np.log10(frame["db_xy_A_mm"]))
    assert "0.0001" in dims[1].ticktext and "0.1" in dims[1].ticktext
    c = np.asarray(fig.data[0].line.color)
    src = frame["source"].to_numpy()
    assert c[src == "level grid"].max() <= 0.75 + 1e-12
    assert np.all(c[src == PARETO] == 0.875) and np.all(c[src == KNEE] == 1.0) and (src == KNEE).sum() == 1
    # knees are drawn last (on top)
    assert src[-1] == KNEE


def test_figure_with_only_nsga_lines_takes_the_colour_range_from_them():
    """No feasible grid entry, only NSGA-II lines: the figure draws them (orange 0.875, the knee 1.0)
    and its colour-bar range is the NSGA-II lines' log10 p_max range; with no line at all the
    error is a one-line ValidationError."""
    st = make_study(2)
    none = DesignStudy(st.entries.assign(feasible=False), presets=list(st.presets.values()), name="none")
    extra = pareto_like(st)
    axes = [Axis(c, c, log=True) for c in st.inputs] + [Axis("p_max_mm", "p_max (mm)", True)]
    frame = parcoords_frame(none, extra=extra)
    assert set(frame["source"]) == {PARETO, KNEE}
    fig = parcoords_figure(frame, axes, "p_max_mm")
    c = np.asarray(fig.data[0].line.color)
    assert (c == 0.875).sum() == 11 and (c == 1.0).sum() == 1
    bar = fig.data[0].line.colorbar
    lo, hi = np.log10(extra["p_max_mm"].min()), np.log10(extra["p_max_mm"].max())
    tv, tt = log_ticks(lo, hi)
    assert list(bar.ticktext) == tt + [PARETO, KNEE]
    np.testing.assert_allclose(bar.tickvals, [(t - lo) / (hi - lo) * 0.75 for t in tv] + [0.875, 1.0], rtol=1e-12)
    with pytest.raises(ValidationError, match=r"lines to draw = 0: expected at least one line"):
        parcoords_figure(parcoords_frame(none), axes, "p_max_mm")


def test_report_is_self_contained_and_lists_python_counts(tmp_path):
    st = make_study()
    rep = Report("toy", "")
    info = add_parcoords(rep, st, log_objectives=["p_max_mm", "r_max_deg"])
    for name, count in info["presets"].items():
        assert count == st.filter(name).count
    rows = preset_table_rows(st)
    assert [r[3] for r in rows] == [info["presets"][p] for p in st.presets]
    html = rep.render()
    assert not re.search(r'<script[^>]+src=["\']https?:', html), "the report must not load scripts from the network"
    assert 'data-preset="p_max ≤ 0.05 mm"' in html


# Slow (~8-11 s) because its check is strong: plotly redraws 524 lines in a software-rendered (SwiftShader) Chromium at every click.
def test_preset_button_in_headless_chromium_shows_the_python_count(tmp_path, chromium):
    require_chromium()
    st = make_study(3)
    extra = pareto_like(st)
    rep = Report("toy parcoords", "")
    info = add_parcoords(rep, st, extra=extra, log_objectives=["p_max_mm", "r_max_deg"], div_id="pc")
    path = rep.write(tmp_path / "toy.html")
    n_lines = len(st.entries) + len(extra)
    page = chromium.open(path)
    page.wait_for("document.getElementById('pc') && document.getElementById('pc').getAttribute('data-ready')")
    assert int(page.evaluate("document.getElementById('pc-count-n').textContent")) == n_lines
    for name in ["p_max ≤ 0.05 mm", "Δb_xy A = 0.1"]:
        page.evaluate(f"document.querySelector('button[data-preset=\"{name}\"]').click()")
        page.wait_for(f"document.getElementById('pc').getAttribute('data-preset') === {name!r} && "
                      "document.getElementById('pc').getAttribute('data-apply-ms')")
        shown = int(page.evaluate("document.getElementById('pc-count-n').textContent"))
        python = st.filter(name, among=parcoords_frame(st, extra=extra)).count
        assert shown == python == info["presets"][name]
        page.evaluate("document.getElementById('pc').removeAttribute('data-apply-ms')")
    # the kept-ranges panel reads like the thesis: Δb_z keeps only 0.001 under p_max <= 0.05
    page.evaluate("document.querySelector('button[data-preset=\"p_max ≤ 0.05 mm\"]').click()")
    page.wait_for("document.getElementById('pc').getAttribute('data-apply-ms')")
    ranges = page.evaluate("document.getElementById('pc-ranges').innerText")
    assert re.search(r"Δb_z A \(mm\)\s+levels 0\.001(;|\s*$|\n)", ranges)
    table = page.evaluate("document.getElementById('pc-table').innerText")
    assert table.count("\n") >= 1
    # brushing by hand = a restyle of one axis' constraint range; the count follows
    lo, hi = math.log10(0.02), math.log10(0.3)
    k = 1 + st.inputs.index("db_xy_B_mm")
    page.evaluate(f"Plotly.restyle('pc', {{'dimensions[{k}].constraintrange': [[{lo}, {hi}]]}}, [0]).then(function(){{ return 1; }})")
    shown = int(page.wait_for(f"document.getElementById('pc').getAttribute('data-kept')"))
    frame = parcoords_frame(st, extra=extra)
    expect = int(((frame["p_max_mm"] <= 0.05) & (frame["db_xy_B_mm"] >= 0.02) & (frame["db_xy_B_mm"] <= 0.3)).sum())
    assert shown == expect
    # 'all entries' clears every constraint
    page.evaluate("document.querySelector('button[data-preset=\"\"]').click()")
    page.wait_for(f"document.getElementById('pc-count-n').textContent === '{n_lines}'")


def test_drawn_sample_keeps_nsga_entries_preset_entries_and_axis_ends():
    st = make_study(3)
    extra = pareto_like(st)
    frame = parcoords_frame(st, extra=extra)
    axes = default_axes(st, ["p_max_mm", "r_max_deg"])
    presets = list(st.presets.values())
    idx = drawn_lines(frame, axes, presets, st, max_drawn=100, seed=0)
    assert len(idx) == 100 and np.all(np.diff(idx) > 0)
    assert np.array_equal(idx, drawn_lines(frame, axes, presets, st, max_drawn=100, seed=0))   # seeded
    assert set(np.flatnonzero(frame["source"].to_numpy() != "level grid")) <= set(idx)        # every NSGA-II line
    share = 100 // (2 * (len(presets) + 1))
    for p in presets:                                     # each preset: all its kept entries, or at least a share
        kept = set(st.filter(p, among=frame).kept.index)
        assert len(kept & set(idx)) >= min(len(kept), share)
    for a in axes:                                        # both ends of every axis are drawn
        v = a.values(frame[a.column])
        assert v[idx].min() == v.min() and v[idx].max() == v.max()
    assert np.array_equal(drawn_lines(frame, axes, presets, st, max_drawn=None), np.arange(len(frame)))
    with pytest.raises(Exception, match="max_drawn"):
        drawn_lines(frame, axes, presets, st, max_drawn=0)


N_TRACE_LINES = ("(function(v){ return v.bdata ? atob(v.bdata).length / 8 : v.length; })"
                 "(document.getElementById('pc').data[0].dimensions[1].values)")


def test_page_draws_a_sample_but_counts_every_entry_and_can_draw_all(tmp_path, chromium):
    require_chromium()
    st = make_study(3)
    extra = pareto_like(st)
    rep = Report("toy parcoords, sampled", "")
    info = add_parcoords(rep, st, extra=extra, log_objectives=["p_max_mm", "r_max_deg"], div_id="pc", max_drawn=100)
    n_lines = len(st.entries) + len(extra)
    assert info["n_drawn"] == 100 and info["n_lines"] == n_lines
    path = rep.write(tmp_path / "sampled.html")
    page = chromium.open(path)
    page.wait_for("document.getElementById('pc') && document.getElementById('pc').getAttribute('data-ready')")
    renderer = page.evaluate("document.getElementById('pc').getAttribute('data-renderer')")
    software = re.search("swiftshader|llvmpipe|software", renderer, re.I) is not None
    drawn = 100 if software else n_lines          # a hardware renderer draws every line by itself
    assert int(page.evaluate("document.getElementById('pc').getAttribute('data-drawn')")) == drawn
    assert int(page.evaluate(N_TRACE_LINES)) == drawn
    for name in ["p_max ≤ 0.05 mm", "r_max ≤ 0.01°"]:
        ms = page.evaluate(f"window.evotolParcoords['pc'].apply({name!r})")
        assert ms > 0
        assert int(page.evaluate("document.getElementById('pc-count-n').textContent")) == info["presets"][name]
    note = page.evaluate("document.getElementById('pc-drawn').innerText")
    assert (f"sample of 100 of {n_lines} lines" in note) if software else (f"All {n_lines} lines drawn" in note)
    # draw every line: the trace now holds all of them, the brushes and the count stay
    page.evaluate("document.querySelector('#pc-drawn button[data-draw=\"all\"]') ? "
                  "window.evotolParcoords['pc'].setDraw(true).then(function(){ return 1; }) : 1")
    assert int(page.evaluate(N_TRACE_LINES)) == n_lines
    assert int(page.evaluate("document.getElementById('pc-count-n').textContent")) == info["presets"]["r_max ≤ 0.01°"]
    assert page.evaluate("document.getElementById('pc').data[0].dimensions.some(function(d){ return d.constraintrange; })")
    assert f"All {n_lines} lines drawn" in page.evaluate("document.getElementById('pc-drawn').innerText")

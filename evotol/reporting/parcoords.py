"""Interactive parallel-coordinate reports of design studies (Deng 2012, Figs. VII.1-VII.16).

One plotly ``Parcoords`` trace (WebGL, so tens of thousands of lines stay interactive) with an
axis per input and per objective; tolerance axes spanning decades are drawn on log10 with tick
labels in the axis unit (``0.0001 … 0.1``). Lines are coloured by a chosen objective; entries
that come from NSGA-II (``source`` column) and their knee points get their own colours and a
``source`` axis, so they stand out from the level grid.

Named presets (:class:`evotol.filtering.Preset`, the filters of the thesis's figures) become
buttons that set the axes' constraint ranges; the page then shows how many entries are kept,
the range each axis keeps and a table of the kept entries. Brushing an axis by hand updates the
same read-outs. A static table beside it lists every preset's count computed in Python by
:meth:`evotol.filtering.DesignStudy.filter` (the numbers the page must reproduce).

Level of detail. Every entry is filtered, counted and tabulated, but plotly draws a parcoords
line with WebGL, which a machine without a GPU emulates on the CPU (SwiftShader, llvmpipe): there
each brush move redraws every line: 1.3-1.6 s per mouse move with 32 768 lines, 0.1-0.3 s with
1 000 (``benchmarks/bench_synthesis.py``, docs/synthesis.md). So when there are more than ``max_drawn`` lines the page draws
a fixed sample of them (every NSGA-II entry, each preset's kept entries up to a share, the entries
at each axis' ends, then a seeded random fill), says so above the plot, and offers a button that
draws all of them; with a hardware WebGL renderer it draws all of them at once by itself.

The report reads results; it computes no physics (STYLE.md).
"""
from __future__ import annotations

import base64
import html
import json
import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np
import pandas as pd

from evotol.doe import ENTRY, SOURCE
from evotol.errors import ValidationError
from evotol.filtering import DesignStudy, Preset

GRID, PARETO, KNEE = "level grid", "NSGA-II", "knee"
_SUP = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
_GRID_TOP = 0.75          # grid entries use [0, 0.75] of the colour scale; NSGA-II and knees the rest
#: lines drawn by default when WebGL may be software-rendered (the thesis's own figures draw 1 000)
DEFAULT_MAX_DRAWN = 1000
#: with a hardware WebGL renderer the page draws all lines up to this many
GPU_MAX_DRAWN = 200_000


@dataclass(frozen=True)
class Axis:
    """One parallel-coordinate axis: a column, its label and whether it is drawn on log10.

    Parameters
    ----------
    column : str
        Column of the entries table (values in the unit its name says).
    label : str, default ""
        Axis title; empty means ``column``.
    log : bool, default False
        Draw ``log10`` of the values (for positive values spanning decades).
    """

    column: str
    label: str = ""
    log: bool = False

    def values(self, s: pd.Series) -> np.ndarray:
        """The plotted values of a column: as they are, or their ``log10`` on a log axis.

        Parameters
        ----------
        s : pandas.Series
            The column's values (column unit).

        Returns
        -------
        ndarray
            Float values, ``log10`` of them when ``log``; same length as ``s``.

        Raises
        ------
        ValidationError
            A log axis has a value <= 0.
        """
        v = s.to_numpy(dtype=float)
        if self.log:
            if np.any(v <= 0):
                raise ValidationError(f"log axis {self.column}", float(v[v <= 0][0]), "positive values")
            return np.log10(v)
        return v

    def transform(self, x: float) -> float:
        """One value in plotted units (``log10(x)`` on a log axis).

        Parameters
        ----------
        x : float
            A value in the column unit (> 0 on a log axis).

        Returns
        -------
        float
            The position on the axis.
        """
        return math.log10(x) if self.log else float(x)


def format_tick(v: float) -> str:
    """Readable tick text: plain decimals from 0.0001 to 99 999, else ``2·10⁻⁵``.

    Parameters
    ----------
    v : float
        The value (axis unit).

    Returns
    -------
    str
        Four significant digits, or mantissa (three digits, none when 1) times a power of ten
        with a superscript exponent.
    """
    if v == 0:
        return "0"
    if 1e-4 <= abs(v) < 1e5:
        return f"{v:.4g}"
    e = int(math.floor(math.log10(abs(v)) + 1e-12))
    m = v / 10 ** e
    mant = "" if abs(m - 1) < 1e-9 else f"{m:.3g}·"
    return f"{mant}10{str(e).translate(_SUP)}"


def log_ticks(lo: float, hi: float) -> tuple[list[float], list[str]]:
    """Tick positions (log10 units) and labels (axis units) for a log axis spanning [lo, hi] (log10).

    Ticks at 1 per decade over three decades or more, at 1, 2, 5 over one or more, else at 1,
    1.5, 2, 3, 5, 7; the two ends when fewer than two ticks fall in the range.

    Parameters
    ----------
    lo : float
        Lower end of the axis, ``log10`` of the axis unit.
    hi : float
        Upper end, ``log10`` of the axis unit.

    Returns
    -------
    tickvals : list of float
        Tick positions (log10 units).
    ticktext : list of str
        Their labels in the axis unit (:func:`format_tick`).
    """
    d0, d1 = math.floor(lo + 1e-9), math.ceil(hi - 1e-9)
    mults = (1,) if d1 - d0 >= 3 else ((1, 2, 5) if d1 - d0 >= 1 else (1, 1.5, 2, 3, 5, 7))
    vals = [math.log10(m) + d for d in range(d0, d1 + 1) for m in mults]
    vals = [v for v in vals if lo - 1e-9 <= v <= hi + 1e-9]
    if len(vals) < 2:
        vals = [lo, hi]
    return vals, [format_tick(10 ** v) for v in vals]


def default_axes(study: DesignStudy, log_objectives: Sequence[str] | None = None) -> list[Axis]:
    """Inputs then objectives; factors with ``log=True`` on log10; objectives on log10 when listed
    in ``log_objectives`` or, by default, when positive and spanning more than two decades.

    Parameters
    ----------
    study : DesignStudy
        The evaluated entries, with their inputs, objectives and factors.
    log_objectives : sequence of str, optional
        The objective columns drawn on log10; None decides from the values (positive, max/min
        above 100).

    Returns
    -------
    list of Axis
        One axis per input (the factor's label, its ``log``), then one per objective.
    """
    axes = []
    for c in study.inputs:
        f = study.factors.get(c)
        axes.append(Axis(c, f.label if f else c, bool(f and f.log)))
    for c in study.objectives:
        if log_objectives is None:
            v = pd.to_numeric(study.entries[c], errors="coerce").to_numpy(float)
            v = v[np.isfinite(v)]
            log = bool(v.size and v.min() > 0 and v.max() / v.min() > 100)
        else:
            log = c in log_objectives
        axes.append(Axis(c, c, log))
    return axes


def _viridis(n: int = 9) -> list[str]:
    import plotly.colors as pc

    return pc.sample_colorscale("Viridis", [i / (n - 1) for i in range(n)])


def parcoords_frame(study: DesignStudy, among: pd.DataFrame | None = None,
                    extra: pd.DataFrame | None = None) -> pd.DataFrame:
    """The lines to draw: the (feasible) study entries, then the ``extra`` (NSGA-II) entries.

    Parameters
    ----------
    study : DesignStudy
        The evaluated entries.
    among : pandas.DataFrame, optional
        Draw these entries instead of all of the study's (e.g. a filtered subset).
    extra : pandas.DataFrame, optional
        NSGA-II entries (the axis columns, optional bool ``knee``) drawn after the grid; without
        an ``entry`` column they are numbered -1, -2, ...

    Returns
    -------
    pandas.DataFrame
        The feasible grid entries (``source = "level grid"``; the ``feasible`` column, when
        present, selects them), then the extra ones (``source`` ``"NSGA-II"`` or ``"knee"``,
        knees last), index reset.
    """
    grid = study.entries if among is None else among
    if "feasible" in grid:
        grid = grid[grid["feasible"].astype(bool)]
    grid = grid.assign(**{SOURCE: GRID})
    parts = [grid]
    if extra is not None and len(extra):
        e = extra.copy()
        knee = e["knee"].astype(bool) if "knee" in e else pd.Series(False, index=e.index)
        e[SOURCE] = np.where(knee, KNEE, PARETO)
        if ENTRY not in e:
            e[ENTRY] = -1 - np.arange(len(e))
        parts.append(e.sort_values(SOURCE, key=lambda s: s.eq(KNEE)))   # knees drawn last
    return pd.concat(parts, ignore_index=True)


def parcoords_figure(frame: pd.DataFrame, axes: Sequence[Axis], color: str, *, title: str = "",
                     height: int = 600):
    """A plotly Parcoords figure of ``frame`` (see :func:`parcoords_frame`), coloured by ``color``.

    The level-grid lines use the Viridis part of the colour scale (scaled to the grid's range of
    ``color``, or to all lines' range when there is no grid line); NSGA-II lines are orange, knees
    red, and a ``source`` axis is added first when there are any.

    Parameters
    ----------
    frame : pandas.DataFrame
        The lines, with every axis column and optionally ``source``.
    axes : sequence of Axis
        The axes, in drawing order.
    color : str
        The axis column that colours the lines.
    title : str, default ""
        Figure title; none when empty.
    height : int, default 600
        Figure height (pixels).

    Returns
    -------
    plotly.graph_objects.Figure
        One ``Parcoords`` trace.

    Raises
    ------
    ValidationError
        ``color`` is not an axis column, an axis column is missing from ``frame``, ``frame``
        has no line, ``color`` has no finite value, or a log axis has a value <= 0.
    """
    import plotly.graph_objects as go

    by_col = {a.column: a for a in axes}
    if color not in by_col:
        raise ValidationError("color", color, f"one of the axis columns {list(by_col)}")
    missing = [a.column for a in axes if a.column not in frame]
    if missing:
        raise ValidationError("axis columns", missing, f"columns of the entries {list(frame.columns)}")
    if len(frame) == 0:
        raise ValidationError("lines to draw", 0, "at least one line (a feasible entry or an extra entry)")
    src = frame[SOURCE].to_numpy() if SOURCE in frame else np.full(len(frame), GRID)
    has_extra = bool(np.any(src != GRID))
    dims = []
    if has_extra:
        code = np.select([src == PARETO, src == KNEE], [1, 2], 0)
        dims.append(dict(label="source", values=code, tickvals=[0, 1, 2], ticktext=[GRID, PARETO, KNEE],
                         range=[-0.1, 2.1]))
    for a in axes:
        v = a.values(frame[a.column])
        lo, hi = float(np.nanmin(v)), float(np.nanmax(v))
        pad = 0.02 * (hi - lo) if hi > lo else (0.5 if a.log else max(abs(lo) * 0.02, 1e-12))
        lo_r = lo - pad if (a.log or lo < 0) else max(lo - pad, 0.0)   # no negative ticks on a positive axis
        d = dict(label=a.label or a.column, values=v, range=[lo_r, hi + pad])
        if a.log:
            d["tickvals"], d["ticktext"] = log_ticks(lo - pad, hi + pad)
        dims.append(d)

    ca = by_col[color]
    cv = ca.values(frame[color])
    finite = np.isfinite(cv)
    ref = cv[finite & (src == GRID)] if np.any(finite & (src == GRID)) else cv[finite]   # no grid line: all lines
    if ref.size == 0:
        raise ValidationError(f"colour column {color}", "no finite value", "a finite value on at least one line")
    lo, hi = float(ref.min()), float(ref.max())
    top = _GRID_TOP if has_extra else 1.0
    c = np.clip((cv - lo) / (hi - lo if hi > lo else 1.0), 0, 1) * top
    c[src == PARETO], c[src == KNEE] = 0.875, 1.0
    vir = _viridis()
    scale = [[top * i / (len(vir) - 1), col] for i, col in enumerate(vir)]
    if has_extra:
        scale += [[0.76, "#ff7f0e"], [0.94, "#ff7f0e"], [0.95, "#d62728"], [1.0, "#d62728"]]
    if ca.log:
        tv, tt = log_ticks(lo, hi)
    else:
        tv = list(np.linspace(lo, hi, 5))
        tt = [format_tick(x) for x in tv]
    cb_vals = [(t - lo) / (hi - lo if hi > lo else 1.0) * top for t in tv]
    cb_text = list(tt)
    if has_extra:
        cb_vals += [0.875, 1.0]
        cb_text += [PARETO, KNEE]
    line = dict(color=c, colorscale=scale, cmin=0.0, cmax=1.0, showscale=True,
                colorbar=dict(title=dict(text=ca.label or color, side="right"), tickvals=cb_vals, ticktext=cb_text,
                              x=1.04, xpad=16, len=0.95, thickness=18))
    fig = go.Figure(go.Parcoords(line=line, dimensions=dims, labelangle=-20, labelside="top",
                                 unselected=dict(line=dict(color="#d9d9d9", opacity=0.25))))
    fig.update_layout(height=height, margin=dict(l=80, r=130, t=120, b=40),
                      title=dict(text=title) if title else None)
    return fig


def drawn_lines(frame: pd.DataFrame, axes: Sequence[Axis], presets: Sequence[Preset], study: DesignStudy,
                max_drawn: int, seed: int = 0, kept: Mapping[str, pd.Index] | None = None) -> np.ndarray:
    """Positions (into ``frame``) of the lines to draw when there are more than ``max_drawn``.

    In this order, until ``max_drawn`` are chosen: every NSGA-II / knee line; for each preset, up to
    ``max_drawn // (2 (presets + 1))`` of the entries it keeps (all of them when fewer), so a preset
    that keeps few entries shows all of them; the entries at both ends of every axis; then a seeded
    uniform sample of the rest. Returns all positions when ``len(frame) <= max_drawn``.
    ``kept``: each preset's kept index in ``frame``, when the caller has filtered already.

    Parameters
    ----------
    frame : pandas.DataFrame
        The lines (:func:`parcoords_frame`).
    axes : sequence of Axis
        The drawn axes (their extreme entries are kept).
    presets : sequence of Preset
        The presets whose kept entries are sampled.
    study : DesignStudy
        Filters ``frame`` by each preset when ``kept`` is None.
    max_drawn : int or None
        Most lines to draw; None draws all.
    seed : int, default 0
        Seed of the random choices.
    kept : mapping of str to pandas.Index, optional
        Each preset's kept index in ``frame``, by preset name.

    Returns
    -------
    ndarray of int
        Sorted positions into ``frame``.

    Raises
    ------
    ValidationError
        ``max_drawn`` is below 1 while ``frame`` has lines, or a log axis has a value <= 0.
    """
    n = len(frame)
    if max_drawn is None or n <= max_drawn:
        return np.arange(n)
    if int(max_drawn) < 1:
        raise ValidationError("max_drawn", max_drawn, "a positive number of lines")
    rng = np.random.default_rng(seed)
    chosen = np.zeros(n, dtype=bool)
    src = frame[SOURCE].to_numpy() if SOURCE in frame else np.full(n, GRID)
    chosen[src != GRID] = True
    share = max(1, int(max_drawn) // (2 * (len(presets) + 1)))
    for p in presets:
        index = kept[p.name] if kept is not None else study.filter(p, among=frame).kept.index
        pos = np.flatnonzero(frame.index.isin(index))
        pos = pos[~chosen[pos]]
        if len(pos) > share:
            pos = rng.choice(pos, share, replace=False)
        chosen[pos] = True
    for a in axes:
        v = a.values(frame[a.column])
        chosen[[int(np.nanargmin(v)), int(np.nanargmax(v))]] = True
    rest = np.flatnonzero(~chosen)
    room = int(max_drawn) - int(chosen.sum())
    if room > 0:
        chosen[rng.choice(rest, min(room, len(rest)), replace=False)] = True
    return np.flatnonzero(chosen)


def _b64(a: np.ndarray) -> dict:
    """A numpy array as plotly.js's typed-array JSON form ``{dtype, bdata}``."""
    a = np.ascontiguousarray(a)
    code = {np.dtype("float64"): "f8", np.dtype("float32"): "f4", np.dtype("int32"): "i4"}[a.dtype]
    return {"dtype": code, "bdata": base64.b64encode(a.tobytes()).decode("ascii")}


def _preset_ranges(preset: Preset, axes: Sequence[Axis], offset: int, frame: pd.DataFrame) -> list:
    """Constraint ranges ``[dim index, low, high]`` (plotted units) that a preset sets."""
    idx = {a.column: i for i, a in enumerate(axes)}
    out = []
    for col, (lo, hi) in preset.bounds.items():
        if col not in idx:
            raise ValidationError(f"preset {preset.name!r} column", col, f"an axis column {list(idx)}")
        a = axes[idx[col]]
        v = a.values(frame[col])
        span = float(np.nanmax(v) - np.nanmin(v)) or 1.0
        plo = a.transform(lo) if lo is not None else float(np.nanmin(v)) - span
        phi = a.transform(hi) if hi is not None else float(np.nanmax(v)) + span
        out.append([idx[col] + offset, plo, phi])
    return out


_JS = r"""
(function(){
var P = %(payload)s;
var gd = document.getElementById(P.div);
function q(id){ return document.getElementById(P.div + '-' + id); }
var TYPES = {f8: Float64Array, f4: Float32Array, i4: Int32Array, u4: Uint32Array, i2: Int16Array,
             u2: Uint16Array, i1: Int8Array, u1: Uint8Array};
var cache = {};
function decode(v){ // plotly.py sends numpy arrays as {dtype, bdata} (base64)
  if(!v || !v.bdata) return v;
  var bin = atob(v.bdata), buf = new ArrayBuffer(bin.length), u8 = new Uint8Array(buf);
  for(var i=0;i<bin.length;i++) u8[i] = bin.charCodeAt(i);
  return new TYPES[v.dtype](buf); }
function vals(k){ if(!(k in cache)) cache[k] = decode(P.full[k]); return cache[k]; }   // every entry
var sample = decode(P.drawn), inSample = new Uint8Array(P.n), drawAll = sample.length === P.n;
for(var s=0;s<sample.length;s++) inSample[sample[s]] = 1;
function renderer(){ try { var c = document.createElement('canvas'), gl = c.getContext('webgl');
    if(!gl) return 'no WebGL'; var e = gl.getExtension('WEBGL_debug_renderer_info');
    var name = String(e ? gl.getParameter(e.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER));
    var lose = gl.getExtension('WEBGL_lose_context'); if(lose) lose.loseContext();   // free the probe context
    return name; }
  catch(err){ return 'unknown'; } }
var GL = renderer(), SOFTWARE = /swiftshader|llvmpipe|softpipe|software|basic render|no webgl|unknown/i.test(GL);
function drawnNote(keep){
  var el = q('drawn'); if(!el) return;
  if(drawAll){ el.innerHTML = 'All ' + P.n + ' lines drawn (WebGL: ' + GL + ').' +
      (sample.length < P.n ? ' <button type="button" data-draw="sample">draw the ' + sample.length + '-line sample</button>' : '');
    return; }
  var kd = 0; for(var t=0;t<keep.length;t++) kd += inSample[keep[t]];
  el.innerHTML = 'Drawing a sample of ' + sample.length + ' of ' + P.n + ' lines (' + kd + ' of the ' + keep.length +
    ' kept entries); counts, kept ranges and the table cover all ' + P.n + ' entries. WebGL: ' + GL +
    (SOFTWARE ? ' (software rendering: every redraw is slow with many lines)' : '') +
    '. <button type="button" data-draw="all">draw all ' + P.n + ' lines</button>'; }
function setDraw(all){
  // swap the drawn lines (values of every axis and the colours) and keep the brushes
  if(all === drawAll) return Promise.resolve();
  var upd = {}, dims = gd.data[0].dimensions, n = all ? P.n : sample.length;
  for(var k=0;k<dims.length;k++){ var v = vals(k), out = new Float64Array(n);
    for(var i=0;i<n;i++) out[i] = v[all ? i : sample[i]];
    upd['dimensions[' + k + '].values'] = [out]; }
  var cf = decode(P.color), co = new Float64Array(n);
  for(var i=0;i<n;i++) co[i] = cf[all ? i : sample[i]];
  upd['line.color'] = [co];
  drawAll = all;
  gd.setAttribute('data-drawn', n);
  return Plotly.restyle(gd, upd, [0]);     // its plotly_restyle event refreshes the read-outs
}
function fmt(v){ if(!isFinite(v)) return String(v); var a=Math.abs(v);
  if(a===0) return '0'; if(a>=1e-4 && a<1e5) return String(Number(v.toPrecision(4)));
  return v.toExponential(3); }
function ranges(){ var dims = gd.data[0].dimensions, out = [];
  for(var k=0;k<dims.length;k++){ var cr = dims[k].constraintrange;
    if(cr && cr.length){ out.push([k, (Array.isArray(cr[0]) ? cr : [cr])]); } }
  return out; }
function keptRows(R){ R = R || ranges(); var n = P.n, keep = [];
  var cols = R.map(function(r){ return vals(r[0]); });
  for(var i=0;i<n;i++){ var ok = true;
    for(var j=0;j<R.length && ok;j++){ var v = cols[j][i], rs = R[j][1], any = false;
      for(var m=0;m<rs.length;m++){ if(v >= rs[m][0] && v <= rs[m][1]){ any = true; break; } }
      ok = any; }
    if(ok) keep.push(i); }
  return keep; }
function value(k, i){ var v = vals(k)[i]; return P.log[k] ? Math.pow(10, v) : v; }
function update(R){
  var keep = keptRows(R);
  q('count-n').textContent = keep.length;
  var dims = gd.data[0].dimensions, rows = [];
  // kept range of every axis
  var h = '<tr><th>axis</th><th>kept</th></tr>';
  for(var k=P.first;k<dims.length;k++){
    var lo = Infinity, hi = -Infinity, lv = {}, elo = Infinity, ehi = -Infinity, ne = 0;
    for(var t=0;t<keep.length;t++){ var i = keep[t], x = value(k, i);
      if(P.source[i] === P.grid){ if(x<lo) lo=x; if(x>hi) hi=x; if(P.discrete[k]) lv[fmt(x)] = x; }
      else { ne++; if(x<elo) elo=x; if(x>ehi) ehi=x; } }
    var keys = Object.keys(lv).sort(function(a,b){ return lv[a] - lv[b]; });
    var txt = lo <= hi ? (P.discrete[k] ? 'levels ' + keys.join(', ') : '[' + fmt(lo) + ', ' + fmt(hi) + ']') : '–';
    if(ne){ txt += '; NSGA-II [' + fmt(elo) + ', ' + fmt(ehi) + ']'; }
    h += '<tr><td>' + dims[k].label + '</td><td>' + txt + '</td></tr>'; }
  q('ranges').innerHTML = h;
  // table of kept entries, best colour value first
  var ck = P.colorDim, cv = vals(ck), order = keep.slice().sort(function(a,b){ return cv[a] - cv[b]; });
  var t = '<tr><th>entry</th><th>source</th>' + P.cols.map(function(k){ return '<th>' + dims[k].label + '</th>'; }).join('') + '</tr>';
  for(var r=0;r<Math.min(order.length, P.tableRows);r++){ var i = order[r];
    t += '<tr><td>' + P.entry[i] + '</td><td>' + P.source[i] + '</td>' +
         P.cols.map(function(k){ return '<td>' + fmt(value(k, i)) + '</td>'; }).join('') + '</tr>'; }
  q('table').innerHTML = t;
  q('table-note').textContent = keep.length > P.tableRows ? ('first ' + P.tableRows + ' of ' + keep.length + ' kept entries, sorted by ' + dims[ck].label) : (keep.length + ' kept entries, sorted by ' + dims[ck].label);
  gd.setAttribute('data-kept', keep.length);
  drawnNote(keep);
}
function apply(name){
  // the read-outs (count, kept ranges, table) are computed from the preset first and painted
  // at once; the WebGL redraw of the lines follows
  var upd = {}, dims = gd.data[0].dimensions, set = {}, R = [];
  var pr = P.presets.filter(function(p){ return p.name === name; })[0];
  if(pr){ pr.ranges.forEach(function(r){ set[r[0]] = [r[1], r[2]]; R.push([r[0], [[r[1], r[2]]]]); }); }
  for(var k=0;k<dims.length;k++){ upd['dimensions[' + k + '].constraintrange'] = [k in set ? set[k] : null]; }
  q('preset').textContent = pr ? pr.name : 'none';
  gd.setAttribute('data-preset', pr ? pr.name : '');
  var t0 = performance.now();
  update(R);
  gd.setAttribute('data-count-ms', (performance.now() - t0).toFixed(1));
  return new Promise(function(res){ requestAnimationFrame(function(){ setTimeout(function(){
    Plotly.restyle(gd, upd, [0]).then(function(){ requestAnimationFrame(function(){ requestAnimationFrame(function(){
      var ms = performance.now() - t0; gd.setAttribute('data-apply-ms', ms.toFixed(1)); res(ms); }); }); });
  }, 0); }); });
}
window.evotolParcoords = window.evotolParcoords || {};
window.evotolParcoords[P.div] = {apply: apply, update: update, keptRows: keptRows, setDraw: setDraw};
q('controls').addEventListener('click', function(ev){ var b = ev.target.closest('button[data-preset]');
  if(b){ apply(b.getAttribute('data-preset')); } });
q('drawn').addEventListener('click', function(ev){ var b = ev.target.closest('button[data-draw]');
  if(b){ setDraw(b.getAttribute('data-draw') === 'all'); } });
gd.on('plotly_restyle', function(){ update(); });
gd.setAttribute('data-drawn', sample.length);
gd.setAttribute('data-renderer', GL);
update();
// a hardware WebGL renderer draws every line at once; software rendering keeps the sample
var ready = (!drawAll && !SOFTWARE && P.n <= P.gpuMax) ? setDraw(true) : Promise.resolve();
ready.then(function(){ gd.setAttribute('data-ready', '1'); });
})();
"""


def add_parcoords(report, study: DesignStudy, *, axes: Sequence[Axis] | None = None, color: str | None = None,
                  presets: Sequence[Preset] | None = None, extra: pd.DataFrame | None = None,
                  among: pd.DataFrame | None = None, log_objectives: Sequence[str] | None = None,
                  table_rows: int = 50, div_id: str = "pc", title: str = "", height: int = 600,
                  max_drawn: int | None = DEFAULT_MAX_DRAWN, seed: int = 0) -> dict:
    """Add the interactive parallel-coordinate section to ``report`` (an :class:`html.Report`).

    Above ``max_drawn`` lines the page first draws the sample :func:`drawn_lines` picks and
    draws all of them on request or when WebGL is hardware-accelerated.

    Parameters
    ----------
    report : Report
        The page (:class:`evotol.reporting.html.Report`), appended to in place.
    study : DesignStudy
        The evaluated entries.
    axes : sequence of Axis, optional
        The axes; default :func:`default_axes`.
    color : str, optional
        Objective column colouring the lines (an axis column); default the first objective.
    presets : sequence of Preset, optional
        Filters shown as buttons (their columns must be axis columns); default the study's
        presets.
    extra : pandas.DataFrame, optional
        NSGA-II Pareto entries (columns of the axes, optional bool ``knee``) drawn on top.
    among : pandas.DataFrame, optional
        Draw only these entries (e.g. a filtered subset).
    log_objectives : sequence of str, optional
        Objectives on log10, for the default axes (see :func:`default_axes`).
    table_rows : int, default 50
        Rows of the page's table of kept entries.
    div_id : str, default "pc"
        ``id`` of the figure's ``<div>``, prefix of the ids of its controls (unique per page).
    title : str, default ""
        Figure title.
    height : int, default 600
        Figure height (pixels).
    max_drawn : int or None, default DEFAULT_MAX_DRAWN
        Lines drawn at first (1000); ``None`` always draws all of them.
    seed : int, default 0
        Seed of the drawn sample.

    Returns
    -------
    dict
        ``{"n_lines", "n_drawn", "presets": {name: count}}`` -- the Python counts the page shows.

    Raises
    ------
    ValidationError
        ``extra`` lacks an axis column, no entry is left to draw, ``color`` or a preset column
        is not an axis column, an axis column is missing, a log axis has a value <= 0, or
        ``max_drawn`` is below 1.
    """
    axes = list(axes) if axes is not None else default_axes(study, log_objectives)
    color = color or study.objectives[0]
    presets = list(presets) if presets is not None else list(study.presets.values())
    if extra is not None and len(extra):
        missing = [a.column for a in axes if a.column not in extra]
        if missing:
            raise ValidationError("extra (NSGA-II) entries columns", missing, "every axis column")
    frame = parcoords_frame(study, among, extra)
    if frame.empty:
        raise ValidationError("entries to draw", 0, "at least one feasible entry (the filter or study keeps none)")
    fig = parcoords_figure(frame, axes, color, title=title, height=height)
    offset = 1 if fig.data[0].dimensions[0].label == "source" else 0
    filtered = {p.name: study.filter(p, among=frame) for p in presets}
    counts = {name: r.count for name, r in filtered.items()}
    # every line's values go to the page; the figure holds the drawn sample (all lines when few)
    full = [_b64(np.asarray(d.values, dtype=float)) for d in fig.data[0].dimensions]
    color_full = np.asarray(fig.data[0].line.color, dtype=float)
    drawn = drawn_lines(frame, axes, presets, study, max_drawn, seed, kept={n: r.kept.index for n, r in filtered.items()})
    if len(drawn) < len(frame):
        for d in fig.data[0].dimensions:
            d.values = np.asarray(d.values)[drawn]
        fig.data[0].line.color = color_full[drawn]
    log_flags = ([False] * offset) + [a.log for a in axes]
    payload = {
        "div": div_id, "n": int(len(frame)), "first": offset, "log": log_flags,
        "full": full, "color": _b64(color_full), "drawn": _b64(drawn.astype(np.int32)), "gpuMax": GPU_MAX_DRAWN,
        "colorDim": offset + [a.column for a in axes].index(color),
        "cols": list(range(offset, offset + len(axes))), "tableRows": int(table_rows),
        "grid": GRID, "discrete": ([False] * offset) + [bool(a.column in study.factors and study.factors[a.column].is_discrete) for a in axes],
        "entry": frame[ENTRY].astype(int).tolist() if ENTRY in frame else list(range(len(frame))),
        "source": frame[SOURCE].tolist() if SOURCE in frame else [GRID] * len(frame),
        "presets": [{"name": p.name, "ranges": _preset_ranges(p, axes, offset, frame), "count": counts[p.name]}
                    for p in presets],
    }
    e = html.escape
    buttons = [f'<button type="button" data-preset="">all entries ({len(frame)})</button>']
    for p in presets:
        buttons.append(f'<button type="button" data-preset="{e(p.name)}" title="{e(p.query)} — {e(p.figure)}">'
                       f'{e(p.name)}</button>')
    report.html(
        f'<style>#{div_id}-controls button{{margin:.15em .3em .15em 0;padding:.3em .7em;border:1px solid #888;'
        f'border-radius:4px;background:#f7f7f7;cursor:pointer}}#{div_id}-controls button:hover{{background:#e8eefc}}'
        f'.ev-count{{font-size:1.1em}}</style>'
        f'<div id="{div_id}-controls"><b>Presets:</b> {"".join(buttons)}</div>'
        f'<p class="ev-count"><span id="{div_id}-count-n">{len(frame)}</span> of {len(frame)} entries kept '
        f'(preset: <span id="{div_id}-preset">none</span>). Drag along any axis to filter by hand; click an '
        f'axis filter bar to remove it.</p><p class="meta" id="{div_id}-drawn"></p>')
    report.figure(fig, div_id=div_id)
    report.html(f'<div style="display:flex;gap:2em;flex-wrap:wrap"><div><b>Kept range per axis</b>'
                f'<table class="ev" id="{div_id}-ranges"></table></div><div><b>Kept entries</b> '
                f'<span class="meta" id="{div_id}-table-note"></span><table class="ev" id="{div_id}-table"></table>'
                f'</div></div>')
    report.html(f'<script type="text/javascript">{_JS % {"payload": json.dumps(payload)}}</script>')
    return {"n_lines": int(len(frame)), "n_drawn": int(len(drawn)), "presets": counts}


def preset_table_rows(study: DesignStudy, presets: Sequence[Preset] | None = None,
                      among: pd.DataFrame | None = None) -> list[list]:
    """Rows ``[preset, figure, query, kept count, kept input ranges]`` for a static report table.

    Parameters
    ----------
    study : DesignStudy
        The evaluated entries, filtered by :meth:`evotol.filtering.DesignStudy.filter`.
    presets : sequence of Preset, optional
        The presets; default the study's.
    among : pandas.DataFrame, optional
        Filter these entries instead of all of the study's.

    Returns
    -------
    list of list
        One row per preset: name, figure, resolved query, kept count and the kept range (or
        levels) of each input as text.
    """
    presets = list(presets) if presets is not None else list(study.presets.values())
    rows = []
    for p in presets:
        r = study.filter(p, among=among)
        parts = []
        for name, rg in r.ranges.items():
            label = study.factors[name].label if name in study.factors else name
            if rg.get("levels") is not None:
                parts.append(f"{label}: {', '.join(format_tick(v) for v in rg['levels']) or '–'}")
            elif rg["min"] is not None:
                parts.append(f"{label}: [{format_tick(rg['min'])}, {format_tick(rg['max'])}]")
        rows.append([p.name, p.figure, r.resolved_query, r.count, "; ".join(parts) or "–"])
    return rows

/* evotol what-if explorer: recomputes cost, worst-case and RSS errors, the worst pose and the
 * contributions of a tolerance vector in the browser, offline (evotol/reporting/explorer.py).
 * The formulas are evotol's own: cost models (cost_models/*.py), worst case h(u) sampled on the
 * directions of ToleranceProblem.coefficients (evotol/measures.py), RSS with the mean shift.
 * Values are SI inside; the panel shows display units. window.evotolExplorer is the test hook. */
(function () {
  "use strict";
  var cfg = JSON.parse(document.getElementById("explorer-data").textContent);
  var E = cfg.explorer, NS = E.sources.length, NV = E.variables.length;
  var MAX_ROWS = 15;      /* contributions shown one by one; the rest summed in one row */

  /* ---- cost models: x = t / scale, the textbook formula f(x) (cost_models/) ---- */
  function polyval(x, p) {            /* numpy.polynomial.polynomial.polyval: Horner from the top */
    var c0 = p[p.length - 1];
    for (var i = 2; i <= p.length; i++) c0 = p[p.length - i] + c0 * x;
    return c0;
  }
  var MODELS = {
    exponential: function (x, p) { return p[0] * Math.exp(-p[1] * x); },
    power: function (x, p) { return p[0] * Math.pow(x, -p[1]); },
    reciprocal_power: function (x, p) { return p[0] + p[1] / Math.pow(x, p[2]); },
    reciprocal: function (x, p) { return p[0] + p[1] / x; },
    reciprocal_square: function (x, p) { return p[0] + p[1] / (x * x); },
    exp_reciprocal: function (x, p) { return p[0] * Math.pow(x, -p[1]) * Math.exp(-p[2] * x); },
    polynomial3: function (x, p) { return polyval(x, p); },
    polynomial4: function (x, p) { return polyval(x, p); },
    linear_exponential: function (x, p) { return p[0] + p[1] * x + p[2] * Math.exp(-p[3] * x); }
  };
  function modelCost(spec, t) {
    if (spec.model === "none") return 0;
    if (spec.model === "sum") {
      var s = 0;
      for (var i = 0; i < spec.terms.length; i++) s += modelCost(spec.terms[i], t);
      return s;
    }
    return MODELS[spec.model](t / spec.scale, spec.params);
  }
  function cost(t) {                  /* ToleranceProblem.cost: Tolerance.cost_of at the cost width */
    var c = 0;
    for (var j = 0; j < NS; j++) {
      var s = E.sources[j];
      if (s.cost_weight === 0 || s.cost.model === "none") continue;
      c += modelCost(s.cost, s.width === 1 ? t[j] : s.width * t[j]);
    }
    return c;
  }

  /* ---- first-order error model: support coefficients on the fixed direction sample ---- */
  function prepare(comp) {
    var P = comp.blocks.length, D = comp.directions, ND = D.length, K = comp.owner.length;
    var c = new Float64Array(P * ND * NS), k0 = new Float64Array(P * ND);
    var sq = new Float64Array(NS);
    for (var p = 0; p < P; p++) {
      var B = comp.blocks[p];
      for (var d = 0; d < ND; d++) {
        var u = D[d];
        sq.fill(0);
        var lin = new Float64Array(NS), cst = 0;
        for (var k = 0; k < K; k++) {
          var j = comp.owner[k];
          var pr = B[0][k] * u[0] + B[1][k] * u[1] + B[2][k] * u[2];
          sq[j] += pr * pr;
          lin[j] = pr;
        }
        var base = (p * ND + d) * NS;
        for (var j2 = 0; j2 < NS; j2++) {
          var s = E.sources[j2], v = Math.sqrt(sq[j2]);
          if (s.rho !== 1) v *= s.rho;
          if (s.dim === 1) {
            if (s.kappa !== 0) v += s.kappa * lin[j2];
            if (s.offset !== 0) cst += s.offset * lin[j2];
          }
          c[base + j2] = v;
        }
        k0[p * ND + d] = cst;
      }
    }
    return {name: comp.name, limit: comp.limit, P: P, ND: ND, c: c, k0: k0, comp: comp};
  }
  var COMPS = E.components.map(prepare);

  function errors(pc, t) {
    var P = pc.P, ND = pc.ND, S = pc.comp.sensitivity, B = pc.comp.blocks, owner = pc.comp.owner;
    var wc = new Float64Array(P), dir = new Int32Array(P), rss = new Float64Array(P);
    for (var p = 0; p < P; p++) {
      var best = -Infinity, bd = 0;
      for (var d = 0; d < ND; d++) {
        var base = (p * ND + d) * NS, h = pc.k0[p * ND + d];
        for (var j = 0; j < NS; j++) h += t[j] * pc.c[base + j];
        if (h > best) { best = h; bd = d; }
      }
      wc[p] = best; dir[p] = bd;
      var s2 = 0, shift = [0, 0, 0];
      for (var j2 = 0; j2 < NS; j2++) {
        var s = E.sources[j2], th = s.rho === 1 ? t[j2] : t[j2] * s.rho, a = S[p][j2] * th;
        s2 += a * a;
        if (s.dim === 1 && (s.offset !== 0 || s.kappa !== 0)) {
          var k = owner.indexOf(j2), m = s.offset + s.kappa * t[j2];
          for (var i = 0; i < 3; i++) shift[i] += m * B[p][i][k];
        }
      }
      rss[p] = Math.sqrt(s2) + Math.sqrt(shift[0] * shift[0] + shift[1] * shift[1] + shift[2] * shift[2]);
    }
    return {wc: wc, dir: dir, rss: rss};
  }
  function argmax(a) { var b = 0; for (var i = 1; i < a.length; i++) if (a[i] > a[b]) b = i; return b; }

  function contributions(pc, t, ev, measure, p) {
    var out = new Float64Array(NS);
    if (measure === "rss") {
      var S = pc.comp.sensitivity[p], tot = 0, sq = new Float64Array(NS);
      for (var j = 0; j < NS; j++) {
        var th = E.sources[j].rho === 1 ? t[j] : t[j] * E.sources[j].rho;
        sq[j] = (th * S[j]) * (th * S[j]); tot += sq[j];
      }
      var r = Math.sqrt(tot), val = ev.rss[p];
      for (var j3 = 0; j3 < NS; j3++) out[j3] = tot > 0 ? sq[j3] / tot * (val > 0 ? r / val : 1) : 0;
    } else {
      /* evotol.measures.worst_case: (rho t |B_j^T u| + (offset + kappa t) b_j.u) / h at the worst direction */
      var base = (p * pc.ND + ev.dir[p]) * NS, h = ev.wc[p], u = pc.comp.directions[ev.dir[p]], B = pc.comp.blocks[p];
      for (var j2 = 0; j2 < NS; j2++) {
        var s = E.sources[j2], v = t[j2] * pc.c[base + j2];
        if (s.dim === 1 && s.offset !== 0) {
          var k = pc.comp.owner.indexOf(j2);
          v += s.offset * (B[0][k] * u[0] + B[1][k] * u[1] + B[2][k] * u[2]);
        }
        out[j2] = h > 0 ? v / h : 0;
      }
    }
    return out;
  }

  /* ---- tolerances: variables -> sources (ToleranceProblem.full) ---- */
  function full(x) {
    var t = new Float64Array(NS);
    for (var j = 0; j < NS; j++) if (E.sources[j].locked !== null) t[j] = E.sources[j].locked;
    for (var v = 0; v < NV; v++) E.variables[v].members.forEach(function (j) { t[j] = x[v]; });
    return t;
  }

  /* ---- display ---- */
  function number(v, digits) {        /* evotol.units.display.number */
    digits = digits || 4;
    if (!isFinite(v)) return String(v);
    if (Math.abs(v) < 1e-9) return "0";   /* ROUND_OFF: round-off shows as 0 (issue 33) */
    var a = Math.abs(v);
    if (a >= 1e-4 && a < 1e6) {
      var r = +v.toExponential(digits - 1);   /* rounded first: 0.0999999 -> 0.1000 */
      return r.toFixed(Math.max(0, digits - 1 - Math.floor(Math.log10(Math.abs(r)))));
    }
    return v.toExponential(digits - 1);
  }
  function factor(unit) { return cfg.factors[unit] !== undefined ? cfg.factors[unit] : 1; }
  function label(unit) { return cfg.labels[unit] !== undefined ? cfg.labels[unit] : unit; }
  function show(v, unit) { return number(v * factor(unit)) + " " + label(unit); }
  /* source j's zone at tolerance t as the page writes it (evotol.reporting.drawing.zone_text): a disc or ball
     "r ≤ hi", a zone symmetric about the nominal "±hi", else the two deviations "+hi / −lo" ("0" for zero) */
  function zoneText(j, t) {
    var s = E.sources[j], z = t * s.zone_per_t, f = factor(s.unit);
    var lo = (s.offset - s.minus * z) * f, hi = (s.offset + s.plus * z) * f, u = " " + label(s.unit);
    if (s.dim > 1) return "r ≤ " + number(hi) + u;
    if (Math.abs(lo + hi) <= 1e-9 * Math.max(Math.abs(lo), Math.abs(hi))) return "±" + number(hi) + u;
    var signed = function (v) { return v === 0 ? "0" : v > 0 ? "+" + number(v) : "−" + number(-v); };
    return signed(hi) + " / " + signed(lo) + u;
  }
  function poseText(p) {
    var ws = cfg.workspace, pose = cfg.poses[p];
    return ws.names.map(function (n, i) {
      return n + " = " + number(pose[i] * ws.display_scale[i]) + (ws.display_units[i] === "1" ? "" : " " + ws.display_units[i]);
    }).join(", ");
  }

  var x = new Float64Array(NV), state = null;
  var root = document.getElementById("explorer");
  var measure = E.measure === "rss" ? "rss" : "wc";

  function recompute() {
    var t = full(x);
    var res = {t: Array.from(t), x: Array.from(x), cost: cost(t), components: {}};
    COMPS.forEach(function (pc) {
      var ev = errors(pc, t), key = measure === "rss" ? ev.rss : ev.wc, p = argmax(key);
      res.components[pc.name] = {wc: Array.from(ev.wc), rss: Array.from(ev.rss), worst_pose: p,
        direction: pc.comp.directions[ev.dir[p]],
        worst_pose_wc: argmax(ev.wc), worst_pose_rss: argmax(ev.rss),
        contributions: Array.from(contributions(pc, t, ev, measure === "rss" ? "rss" : "wc", p))};
    });
    state = res;
    render();
    return res;
  }

  function render() {
    var el = root.querySelector(".ex-out"), h = "<table class=\"ev\"><tr><th>quantity</th><th>value</th></tr>";
    h += "<tr><td>cost</td><td id=\"ex-cost\">" + number(state.cost, 6) + "</td></tr>";
    COMPS.forEach(function (pc) {
      var r = state.components[pc.name], eu = cfg.error_units[pc.name];
      var wcM = r.wc[r.worst_pose_wc], rsM = r.rss[r.worst_pose_rss];
      var ok = function (v) { return v <= pc.limit * (1 + 1e-9) ? "<span class=\"ok\">meets</span>" : "<span class=\"bad\">misses</span>"; };
      h += "<tr><td>worst-case " + pc.name + " error (largest over the poses; sampled directions)</td><td>" +
        show(wcM, eu) + " " + ok(wcM) + " " + show(pc.limit, eu) + " at #" + r.worst_pose_wc + ": " + poseText(r.worst_pose_wc) + "</td></tr>";
      h += "<tr><td>RSS " + pc.name + " error (largest over the poses)</td><td>" + show(rsM, eu) + " " + ok(rsM) + " " +
        show(pc.limit, eu) + " at #" + r.worst_pose_rss + ": " + poseText(r.worst_pose_rss) + "</td></tr>";
    });
    h += "</table>";
    COMPS.forEach(function (pc) {
      var r = state.components[pc.name], order = [];
      for (var j = 0; j < NS; j++) order.push(j);
      order.sort(function (a, b) { return r.contributions[b] - r.contributions[a]; });
      h += "<p>Contributions to the " + (measure === "rss" ? "RSS" : "worst-case") + " " + pc.name + " error at the worst pose #" +
        r.worst_pose + ":</p><table class=\"ev ex-contrib\"><tr><th>source</th><th>tolerance</th><th>share (%)</th></tr>";
      var rest = 0;
      order.forEach(function (j, i) {
        var s = E.sources[j];
        if (i >= MAX_ROWS) { rest += r.contributions[j]; return; }
        h += "<tr><td>" + s.name + "</td><td>" + zoneText(j, state.t[j]) + "</td><td>" + number(100 * r.contributions[j]) + "</td></tr>";
      });
      if (order.length > MAX_ROWS)
        h += "<tr><td>" + (order.length - MAX_ROWS) + " more sources</td><td></td><td>" + number(100 * rest) + "</td></tr>";
      h += "</table>";
    });
    el.innerHTML = h;
    root.querySelector("#ex-cost-head").textContent = number(state.cost, 6);
    if (window.Plotly) {      /* every component on one axis: error / requirement (1 = at the requirement) */
      var traces = [], n = 0;
      COMPS.forEach(function (pc) {
        var r = state.components[pc.name], idx = r.wc.map(function (_, i) { return i; });
        n = idx.length;
        traces.push({x: idx, y: r.wc.map(function (v) { return v / pc.limit; }), type: "bar", name: "worst case (" + pc.name + ")"});
        traces.push({x: idx, y: r.rss.map(function (v) { return v / pc.limit; }), type: "bar", name: "RSS (" + pc.name + ")"});
      });
      traces.push({x: [-0.5, n - 0.5], y: [1, 1], mode: "lines", name: "requirement", line: {dash: "dash", color: "#b00020"}});
      Plotly.react("ex-plot", traces, {title: {text: "error / requirement at every allocation pose (first-order)"},
        xaxis: {title: {text: "allocation pose #"}}, yaxis: {title: {text: "error / requirement"}}, barmode: "group",
        height: 360, margin: {t: 50}},
        {displaylogo: false, responsive: true});
    }
  }

  function setVariable(v, value, from) {
    var V = E.variables[v];
    x[v] = Math.min(V.upper, Math.max(V.lower, value));
    var row = root.querySelector("[data-var=\"" + v + "\"]");
    if (from !== "range") row.querySelector("input[type=range]").value = Math.log10(x[v]);
    if (from !== "number") row.querySelector("input[type=number]").value = number(x[v] * factor(V.unit));
  }
  function setAll(values) {
    for (var v = 0; v < NV; v++) setVariable(v, values[v]);
    return recompute();
  }

  /* ---- panel ---- */
  var rows = E.variables.map(function (V, v) {
    var lo = Math.log10(V.lower), hi = Math.log10(V.upper);
    return "<tr data-var=\"" + v + "\"><td>" + V.name + "</td><td>" + show(V.lower, V.unit) + "</td><td><input type=\"range\" min=\"" + lo +
      "\" max=\"" + hi + "\" step=\"" + (hi - lo) / 1000 + "\" style=\"width:22em\"></td><td>" + show(V.upper, V.unit) +
      "</td><td>" + (V.members.every(function (j) { var s = E.sources[j]; return s.offset === 0 && s.minus === s.plus; })
        ? "± " : "t = ") + "<input type=\"number\" step=\"any\" style=\"width:7em\"> " + label(V.unit) + "</td></tr>";
  }).join("");
  var buttons = Object.keys(E.starts).map(function (m) {
    return "<button type=\"button\" data-start=\"" + m + "\">reset to " + m + "</button>";
  }).join(" ");
  root.innerHTML = "<p>" + buttons + " &nbsp; cost <b id=\"ex-cost-head\"></b></p>" +
    "<div style=\"display:flex;gap:2em;flex-wrap:wrap\"><div><table class=\"ev\"><tr><th>tolerance</th><th>lower</th>" +
    "<th>log scale</th><th>upper</th><th>value</th></tr>" + rows + "</table></div><div class=\"ex-out\"></div></div>" +
    "<div id=\"ex-plot\"></div>";
  root.querySelectorAll("[data-var]").forEach(function (row) {
    var v = +row.getAttribute("data-var");
    row.querySelector("input[type=range]").addEventListener("input", function (e) {
      setVariable(v, Math.pow(10, +e.target.value), "range"); recompute();
    });
    row.querySelector("input[type=number]").addEventListener("change", function (e) {
      var val = parseFloat(e.target.value);
      if (isFinite(val) && val > 0) { setVariable(v, val / factor(E.variables[v].unit), "number"); recompute(); }
      else setVariable(v, x[v]);
    });
  });
  root.querySelectorAll("[data-start]").forEach(function (b) {
    b.addEventListener("click", function () { setAll(E.starts[b.getAttribute("data-start")]); });
  });
  var first = Object.keys(E.starts)[0];
  setAll(E.starts[first]);

  window.evotolExplorer = {
    /* tolerance per free variable (SI) -> the recomputed state */
    setVariables: function (values) { return setAll(values); },
    /* source j's zone text at tolerance t (SI), as the contributions table shows it */
    zoneText: function (j, t) { return zoneText(j, t); },
    /* the state without redrawing: for tolerance vectors per source outside the panel's bounds */
    evaluateSources: function (t) {
      var out = {cost: cost(t), components: {}};
      COMPS.forEach(function (pc) { var ev = errors(pc, t); out.components[pc.name] = {wc: Array.from(ev.wc), rss: Array.from(ev.rss)}; });
      return out;
    },
    state: function () { return state; },
    ready: true
  };
})();


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

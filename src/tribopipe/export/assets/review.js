// The review page's script (one function scope, added by export/review_page.py).
// The estimator below is tribopipe.reduction.manual's, sample for sample; the browser
// test holds the two equal. Text from the data goes into the page with textContent only.

var data = JSON.parse(document.getElementById("tribopipe-review-data").textContent);
var runs = data.runs;
var byId = {};
var decisions = {};
var HEADER = data.csv.header;     // tribopipe.review.HEADER
var FORMULA = data.csv.formula;   // tribopipe.escape.FORMULA_TRIGGERS

function el(tag, cls, text) {
  var e = document.createElement(tag);
  if (cls) { e.className = cls; }
  if (text !== undefined && text !== null) { e.textContent = String(text); }
  return e;
}

function fmt(v, digits) {
  return (v === null || v === undefined || !isFinite(v)) ? "–" : Number(v).toPrecision(digits || 4);
}

// ------------------------------------------------------------------ the estimator

function decode(b64) {
  var bin = atob(b64);
  var bytes = new Uint8Array(bin.length);
  for (var i = 0; i < bin.length; i++) { bytes[i] = bin.charCodeAt(i); }
  var view = new DataView(bytes.buffer);
  var out = new Float64Array(bytes.length / 8);
  for (var k = 0; k < out.length; k++) { out[k] = view.getFloat64(8 * k, true); }
  return out;
}

function samples(run) {
  if (!run.trace) { return null; }
  if (!run._s) { run._s = decode(run.trace.s); run._mu = decode(run.trace.mu); }
  return { s: run._s, mu: run._mu, terms: run.trace.terms };
}

function mean(x) {
  var sum = 0;
  for (var i = 0; i < x.length; i++) { sum += x[i]; }
  return sum / x.length;
}

// tribopipe.reduction.uncertainty.integrated_autocorrelation_time (Sokal's window, c = 5)
function tauInt(x) {
  var n = x.length;
  if (n < 4) { return 1; }
  var m = mean(x);
  var y = new Float64Array(n);
  var ss = 0;
  for (var i = 0; i < n; i++) { y[i] = x[i] - m; ss += y[i] * y[i]; }
  if (ss === 0) { return 1; }
  var tau = 1;
  for (var lag = 1; lag < n; lag++) {
    var acc = 0;
    for (var j = 0; j + lag < n; j++) { acc += y[j] * y[j + lag]; }
    tau += 2 * acc / ss;
    if (lag >= 5 * tau) { break; }
  }
  return Math.max(1, tau);
}

function combined(mu, reading, terms) {
  var a = mu * terms.u_relative;
  return Math.sqrt(reading * reading + a * a + terms.u_absolute * terms.u_absolute);
}

// tribopipe.reduction.manual.kinetic_over
function kinetic(run, from, to) {
  var x = samples(run);
  if (!x) { return { error: "no trace" }; }
  var s = x.s, n = s.length;
  if (!isFinite(from) || !isFinite(to) || to <= from) {
    return { error: "the window " + from + "–" + to + " mm must end after it starts" };
  }
  if (n === 0 || from > s[n - 1] || to < s[0] || from < 0) {
    return { error: "the window " + from + "–" + to + " mm lies outside the trace (sliding from " +
             fmt(s[0]) + " to " + fmt(s[n - 1]) + " mm)" };
  }
  var w = [], ws = [];
  for (var i = 0; i < n; i++) {
    if (s[i] >= from && s[i] <= to) { w.push(x.mu[i]); ws.push(s[i]); }
  }
  var need = Math.max(2, x.terms.min_plateau_samples);
  if (w.length < need) {
    return { error: "the window " + from + "–" + to + " mm holds " + w.length +
             " samples; the μ_K estimator needs at least " + need + " (min_plateau_samples)" };
  }
  var m = mean(w), ss = 0;
  for (var k = 0; k < w.length; k++) { ss += (w[k] - m) * (w[k] - m); }
  var sd = Math.sqrt(ss / (w.length - 1));
  var se = sd * Math.sqrt(tauInt(w) / w.length);
  return { mu_k: m, u_mu_k: combined(m, se, x.terms), n: w.length,
           start_mm: ws[0], end_mm: ws[ws.length - 1] };
}

// tribopipe.reduction.manual.quadratic_at: Cramer's rule on x scaled to [-1, 1]
function quadraticAt(x, y) {
  var scale = 0, i;
  for (i = 0; i < x.length; i++) { scale = Math.max(scale, Math.abs(x[i])); }
  if (scale === 0) { scale = 1; }
  var s0 = x.length, s1 = 0, s2 = 0, s3 = 0, s4 = 0, t0 = 0, t1 = 0, t2 = 0;
  var u = new Float64Array(x.length);
  for (i = 0; i < x.length; i++) {
    var v = x[i] / scale; u[i] = v;
    s1 += v; s2 += v * v; s3 += v * v * v; s4 += v * v * v * v;
    t0 += y[i]; t1 += v * y[i]; t2 += v * v * y[i];
  }
  var det = s0 * (s2 * s4 - s3 * s3) - s1 * (s1 * s4 - s3 * s2) + s2 * (s1 * s3 - s2 * s2);
  if (det === 0 || !isFinite(det)) { return [NaN, NaN]; }
  var c0 = (t0 * (s2 * s4 - s3 * s3) - s1 * (t1 * s4 - s3 * t2) + s2 * (t1 * s3 - s2 * t2)) / det;
  var c1 = (s0 * (t1 * s4 - t2 * s3) - t0 * (s1 * s4 - s3 * s2) + s2 * (s1 * t2 - t1 * s2)) / det;
  var c2 = (s0 * (s2 * t2 - s3 * t1) - s1 * (s1 * t2 - s3 * t0) + t0 * (s1 * s3 - s2 * s2)) / det;
  var rss = 0;
  for (i = 0; i < x.length; i++) {
    var r = y[i] - (c0 + c1 * u[i] + c2 * u[i] * u[i]);
    rss += r * r;
  }
  var inv00 = (s2 * s4 - s3 * s3) / det;
  return [c0, Math.sqrt(Math.max(rss / (x.length - 3) * inv00, 0))];
}

// tribopipe.reduction.manual.static_at
function staticAt(run, peak) {
  var x = samples(run);
  if (!x) { return { error: "no trace" }; }
  var s = x.s, n = s.length;
  if (!isFinite(peak) || n === 0 || !(s[0] <= peak && peak <= s[n - 1])) {
    return { error: "the static peak at " + peak + " mm lies outside the trace" };
  }
  var half = x.terms.peak_window_mm / 2, xs = [], ys = [];
  for (var i = 0; i < n; i++) {
    if (Math.abs(s[i] - peak) <= half) { xs.push(s[i] - peak); ys.push(x.mu[i]); }
  }
  if (xs.length < 5) {
    return { error: xs.length + " samples lie within " + half + " mm of the static peak at " +
             peak + " mm; reading a peak needs at least 5" };
  }
  var fit = quadraticAt(xs, ys);
  return { mu_s: fit[0], u_mu_s: combined(fit[0], fit[1], x.terms), n: xs.length };
}

// ------------------------------------------------------------------ decisions as CSV

function cell(text) {
  var t = String(text === null || text === undefined ? "" : text).replace(/[\u0000-\u001f\u007f]/g, " ");
  if (t && (FORMULA.indexOf(t[0]) >= 0 || t[0] === "'")) { t = "'" + t; }
  if (/[",\r\n]/.test(t)) { t = '"' + t.replace(/"/g, '""') + '"'; }
  return t;
}

function num(v) { return (v === null || v === undefined || !isFinite(v)) ? "" : String(v); }

function csvText() {
  var lines = [HEADER.join(",")];
  runs.forEach(function (run) {
    var d = decisions[run.id];
    if (!d) { return; }
    var row = [run.id, d.action, d.action === "window" ? num(d.from_mm) : "",
               d.action === "window" ? num(d.to_mm) : "",
               d.action === "window" ? num(d.peak_mm) : "", d.reason || "", d.who || "", d.date || ""];
    lines.push(row.map(cell).join(","));
  });
  return lines.join("\n") + "\n";
}

function today() { return new Date().toISOString().slice(0, 10); }

function updateDecisions() {
  var text = csvText();
  document.getElementById("decisions").value = text;
  document.getElementById("download").setAttribute(
    "href", "data:text/csv;charset=utf-8," + encodeURIComponent(text));
  document.getElementById("decision-count").textContent = String(Object.keys(decisions).length);
}

function decide(run, d) {
  if (d) {
    d.who = document.getElementById("reviewer").value.trim();
    d.date = today();
    decisions[run.id] = d;
  } else {
    delete decisions[run.id];
  }
  refresh(run);
  updateDecisions();
}

// ------------------------------------------------------------------ drawing

function setupCanvas(canvas) {
  var ratio = window.devicePixelRatio || 1;
  var w = Math.max(100, canvas.clientWidth), h = canvas.clientHeight;
  canvas.width = Math.round(w * ratio);
  canvas.height = Math.round(h * ratio);
  var ctx = canvas.getContext("2d");
  ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
  return { ctx: ctx, w: w, h: h };
}

var PAD = { l: 46, r: 10, t: 8, b: 20 };

function xRange(run) {
  var sh = run.trace.show;
  return sh.x1 > sh.x0 ? [sh.x0, sh.x1] : [sh.x0, sh.x0 + 1];
}

// min-max per pixel column of the samples (x never decreasing): the points that decide
// the drawn line (tribopipe.figures.decimate's rule)
function thin(xs, ys, xr, columns) {
  var outX = [], outY = [], i = 0, n = xs.length;
  var scale = columns / (xr[1] - xr[0]);
  while (i < n) {
    var col = Math.floor((xs[i] - xr[0]) * scale), lo = i, hi = i, j = i;
    while (j < n && Math.floor((xs[j] - xr[0]) * scale) === col) {
      if (ys[j] < ys[lo]) { lo = j; }
      if (ys[j] > ys[hi]) { hi = j; }
      j++;
    }
    var a = Math.min(lo, hi), b = Math.max(lo, hi);
    outX.push(xs[a]); outY.push(ys[a]);
    if (b !== a) { outX.push(xs[b]); outY.push(ys[b]); }
    i = j;
  }
  return [outX, outY];
}

function yRange(values, extra) {
  var lo = Infinity, hi = -Infinity;
  values.concat(extra || []).forEach(function (v) {
    if (v !== null && v !== undefined && isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
  });
  if (!(hi > lo)) { lo -= 0.5; hi += 0.5; }
  var pad = 0.06 * (hi - lo);
  return [lo - pad, hi + pad];
}

function axes(ctx, box, xr, yr, label) {
  ctx.strokeStyle = "#999"; ctx.lineWidth = 1;
  ctx.strokeRect(PAD.l, PAD.t, box.w - PAD.l - PAD.r, box.h - PAD.t - PAD.b);
  ctx.fillStyle = "#444"; ctx.font = "11px sans-serif";
  ctx.fillText(fmt(yr[1], 3), 2, PAD.t + 10);
  ctx.fillText(fmt(yr[0], 3), 2, box.h - PAD.b);
  ctx.fillText(label, 2, (box.h) / 2);
  ctx.fillText(fmt(xr[0], 3) + " mm", PAD.l, box.h - 5);
  var right = fmt(xr[1], 3) + " mm";
  ctx.fillText(right, box.w - PAD.r - ctx.measureText(right).width, box.h - 5);
}

function mapper(box, xr, yr) {
  var W = box.w - PAD.l - PAD.r, H = box.h - PAD.t - PAD.b;
  return {
    x: function (v) { return PAD.l + (v - xr[0]) / (xr[1] - xr[0]) * W; },
    y: function (v) { return PAD.t + (1 - (v - yr[0]) / (yr[1] - yr[0])) * H; },
    inv: function (px) { return xr[0] + (px - PAD.l) / W * (xr[1] - xr[0]); }
  };
}

function line(ctx, m, xs, ys, colour) {
  ctx.strokeStyle = colour; ctx.lineWidth = 1; ctx.beginPath();
  var pen = false;
  for (var i = 0; i < xs.length; i++) {
    if (ys[i] === null || xs[i] === null) { pen = false; continue; }
    if (pen) { ctx.lineTo(m.x(xs[i]), m.y(ys[i])); } else { ctx.moveTo(m.x(xs[i]), m.y(ys[i])); pen = true; }
  }
  ctx.stroke();
}

function current(run) {
  var d = decisions[run.id], a = run.auto;
  var cur = { from_mm: a.from_mm, to_mm: a.to_mm, mu_k: a.mu_k, u_mu_k: a.u_mu_k,
              peak_mm: a.peak_mm, mu_s: a.mu_s, u_mu_s: a.u_mu_s };
  if (d && d.action === "window" && run._k && !run._k.error) {
    cur.from_mm = d.from_mm; cur.to_mm = d.to_mm; cur.mu_k = run._k.mu_k; cur.u_mu_k = run._k.u_mu_k;
    if (d.peak_mm !== null && d.peak_mm !== undefined && run._p && !run._p.error) {
      cur.peak_mm = d.peak_mm; cur.mu_s = run._p.mu_s; cur.u_mu_s = run._p.u_mu_s;
    }
  }
  return cur;
}

function draw(run) {
  var card = run._card;
  if (!run.trace || !card) { return; }
  var sh = run.trace.show, a = run.auto, cur = current(run);
  var xr = xRange(run);
  run._xr = xr;
  var box = setupCanvas(card.mu);
  var ctx = box.ctx;
  ctx.clearRect(0, 0, box.w, box.h);
  var x = samples(run);
  var muLine = thin(x.s, x.mu, xr, Math.max(50, Math.round(box.w - PAD.l - PAD.r)));
  var yr = yRange(muLine[1], [cur.mu_s]);
  var m = mapper(box, xr, yr);
  run._map = m;
  // the automatic window, outlined; the current one shaded
  ctx.setLineDash([4, 3]); ctx.strokeStyle = "#2b6cb0";
  if (a.from_mm !== null && a.to_mm !== null) {
    ctx.strokeRect(m.x(a.from_mm), PAD.t, m.x(a.to_mm) - m.x(a.from_mm), box.h - PAD.t - PAD.b);
  }
  ctx.setLineDash([]);
  var lo = run._drag ? run._drag[0] : cur.from_mm, hi = run._drag ? run._drag[1] : cur.to_mm;
  if (lo !== null && hi !== null) {
    ctx.fillStyle = "rgba(43,108,176,0.18)";
    ctx.fillRect(m.x(Math.min(lo, hi)), PAD.t, Math.abs(m.x(hi) - m.x(lo)), box.h - PAD.t - PAD.b);
  }
  line(ctx, m, muLine[0], muLine[1], "#333");
  if (cur.mu_k !== null && cur.from_mm !== null) {
    ctx.strokeStyle = "#2b6cb0"; ctx.lineWidth = 2; ctx.beginPath();
    ctx.moveTo(m.x(cur.from_mm), m.y(cur.mu_k)); ctx.lineTo(m.x(cur.to_mm), m.y(cur.mu_k)); ctx.stroke();
  }
  if (cur.mu_s !== null && cur.peak_mm !== null) {
    var px = m.x(cur.peak_mm), U = 2 * (cur.u_mu_s || 0);
    ctx.strokeStyle = "#c0392b"; ctx.lineWidth = 1.5; ctx.beginPath();
    ctx.moveTo(px, m.y(cur.mu_s - U)); ctx.lineTo(px, m.y(cur.mu_s + U)); ctx.stroke();
    ctx.fillStyle = "#c0392b"; ctx.beginPath(); ctx.arc(px, m.y(cur.mu_s), 4, 0, 2 * Math.PI); ctx.fill();
  }
  axes(ctx, box, xr, yr, "μ");
  var fb = setupCanvas(card.force);
  fb.ctx.clearRect(0, 0, fb.w, fb.h);
  var fr = yRange(sh.f);
  var fm = mapper(fb, xr, fr);
  line(fb.ctx, fm, sh.s_f, sh.f, "#6b4f1d");
  axes(fb.ctx, fb, xr, fr, "F_N");
  run._drawn = true;
  card.root.setAttribute("data-drawn", "1");
}

// ------------------------------------------------------------------ one run's card

function numberInput(cls, label) {
  var wrap = el("label", null, label + " ");
  var input = el("input", cls);
  input.type = "number"; input.step = "any"; input.min = "0";
  wrap.appendChild(input);
  return { wrap: wrap, input: input };
}

function compute(run) {
  var d = decisions[run.id];
  run._k = null; run._p = null;
  if (d && d.action === "window") {
    run._k = kinetic(run, d.from_mm, d.to_mm);
    if (d.peak_mm !== null && d.peak_mm !== undefined) { run._p = staticAt(run, d.peak_mm); }
  }
}

function refresh(run) {
  var card = run._card, d = decisions[run.id];
  compute(run);
  card.root.classList.toggle("decided", !!d);
  var now = card.now, problem = "";
  now.textContent = "";
  ["data-mu-k", "data-u-mu-k", "data-mu-s", "data-u-mu-s", "data-n"].forEach(function (a) { now.removeAttribute(a); });
  if (d) {
    var text = "decision: " + d.action;
    if (d.action === "exclude") { text += " (" + d.reason + ")"; }
    if (d.action === "window") {
      if (run._k && run._k.error) { problem = run._k.error; } else if (run._k) {
        text += " — μ_K = " + fmt(run._k.mu_k) + " ± " + fmt(2 * run._k.u_mu_k, 2) +
                " over " + d.from_mm + "–" + d.to_mm + " mm (" + run._k.n + " samples)";
        now.setAttribute("data-mu-k", String(run._k.mu_k));
        now.setAttribute("data-u-mu-k", String(run._k.u_mu_k));
        now.setAttribute("data-n", String(run._k.n));
      }
      if (run._p && run._p.error) { problem = run._p.error; } else if (run._p) {
        text += "; μ_S = " + fmt(run._p.mu_s) + " ± " + fmt(2 * run._p.u_mu_s, 2) + " at " + d.peak_mm + " mm";
        now.setAttribute("data-mu-s", String(run._p.mu_s));
        now.setAttribute("data-u-mu-s", String(run._p.u_mu_s));
      }
    }
    now.textContent = text;
  }
  card.problem.textContent = problem;
  card.flags.classList.toggle("reviewed", !!(d && d.action === "accept"));
  card.flags.textContent = "flags: " + (run.flags.length ? run.flags.join(", ") : "none") +
    (d && d.action === "accept" ? " — accepted (reviewed)" : "");
  if (run._drawn || (run.trace && run._visible)) { draw(run); }
}

function setWindow(run, from, to, peak) {
  var d = { action: "window", from_mm: from, to_mm: to, peak_mm: peak, reason: "" };
  var old = decisions[run.id];
  if (old && old.action === "window" && old.reason) { d.reason = old.reason; }
  run._card.from.value = from; run._card.to.value = to;
  run._card.peak.value = (peak === null || peak === undefined) ? "" : peak;
  decide(run, d);
}

function readInputs(run) {
  var c = run._card;
  var from = parseFloat(c.from.value), to = parseFloat(c.to.value);
  var peak = c.peak.value.trim() === "" ? null : parseFloat(c.peak.value);
  if (!isFinite(from) || !isFinite(to)) { c.problem.textContent = "type both ends of the window (mm)"; return; }
  setWindow(run, from, to, peak);
}

function attachDrag(run) {
  var canvas = run._card.mu, start = null;
  function at(ev) {
    var rect = canvas.getBoundingClientRect();
    return run._map.inv(ev.clientX - rect.left);
  }
  canvas.addEventListener("pointerdown", function (ev) {
    if (!run._map) { return; }
    start = { x: ev.clientX, s: at(ev) };
    canvas.setPointerCapture(ev.pointerId);
  });
  canvas.addEventListener("pointermove", function (ev) {
    if (!start) { return; }
    run._drag = [start.s, at(ev)];
    draw(run);
  });
  canvas.addEventListener("pointerup", function (ev) {
    if (!start) { return; }
    var s0 = start.s, s1 = at(ev), moved = Math.abs(ev.clientX - start.x);
    start = null; run._drag = null;
    var xr = run._xr;
    function clamp(v) { return Math.min(Math.max(v, xr[0]), xr[1]); }
    var d = decisions[run.id];
    if (moved < 4) {
      // a click: the static peak, with the window the run has now
      var cur = current(run);
      setWindow(run, (d && d.action === "window") ? d.from_mm : cur.from_mm,
                (d && d.action === "window") ? d.to_mm : cur.to_mm, +clamp(s0).toPrecision(6));
    } else {
      var peak = (d && d.action === "window") ? d.peak_mm : null;
      setWindow(run, +clamp(Math.min(s0, s1)).toPrecision(6), +clamp(Math.max(s0, s1)).toPrecision(6), peak);
    }
  });
}

function card(run) {
  var root = el("article", "run" + (run.qc ? " flagged" : ""));
  root.id = "run-" + run.id;
  root.setAttribute("data-id", run.id);
  var name = (run.file || run.id) + (run.place ? " [" + run.place + "]" : "");
  root.appendChild(el("h3", null, name));
  var cond = run.pin + " / " + run.disc + ", " + fmt(run.force_N, 3) + " N, " +
    fmt(run.temperature_C, 3) + " °C · id " + run.id +
    (run.outlying ? " · " + fmt(run.outlying, 2) + " × r/2 from its group's mean" : "") +
    (run.excluded ? " · excluded in the map" + (run.exclusion_reason ? ": " + run.exclusion_reason : "") : "");
  root.appendChild(el("div", "muted", cond));
  var flags = el("div", "flags");
  root.appendChild(flags);
  var c = { root: root, flags: flags };
  if (run.trace) {
    var plots = el("div", "plots");
    c.mu = el("canvas", "mu"); c.force = el("canvas", "force");
    plots.appendChild(c.mu); plots.appendChild(c.force);
    root.appendChild(plots);
  } else {
    root.appendChild(el("p", "problem", run.trace_problem || "no trace of this run: accept or exclude only"));
  }
  var a = run.auto;
  var readings = el("div", "readings");
  readings.appendChild(el("span", "auto", "automatic: μ_S = " + fmt(a.mu_s) + " ± " +
    fmt(2 * a.u_mu_s, 2) + " at " + fmt(a.peak_mm) + " mm; μ_K = " + fmt(a.mu_k) + " ± " +
    fmt(2 * a.u_mu_k, 2) + " over " + fmt(a.from_mm) + "–" + fmt(a.to_mm) + " mm"));
  c.now = el("span", "now");
  readings.appendChild(c.now);
  root.appendChild(readings);
  c.problem = el("div", "problem");
  root.appendChild(c.problem);
  var actions = el("div", "actions");
  if (run.trace) {
    var f = numberInput("from", "μ_K from"), t = numberInput("to", "to"), p = numberInput("peak", "μ_S peak at");
    c.from = f.input; c.to = t.input; c.peak = p.input;
    actions.appendChild(f.wrap); actions.appendChild(t.wrap); actions.appendChild(p.wrap);
    var set = el("button", "set-window", "set window");
    set.type = "button";
    set.addEventListener("click", function () { readInputs(run); });
    [c.from, c.to, c.peak].forEach(function (inp) {
      inp.addEventListener("keydown", function (ev) { if (ev.key === "Enter") { readInputs(run); } });
    });
    actions.appendChild(set);
  }
  var accept = el("button", "accept", "accept");
  accept.type = "button";
  accept.addEventListener("click", function () { decide(run, { action: "accept", reason: c.reason.value.trim() }); });
  c.reason = el("input", "reason");
  c.reason.type = "text"; c.reason.placeholder = "reason";
  var exclude = el("button", "exclude", "exclude");
  exclude.type = "button";
  exclude.addEventListener("click", function () {
    var why = c.reason.value.trim();
    if (!why) { c.problem.textContent = "an exclusion needs a reason"; return; }
    decide(run, { action: "exclude", reason: why });
  });
  var undo = el("button", "undo", "undo");
  undo.type = "button";
  undo.addEventListener("click", function () { decide(run, null); });
  actions.appendChild(accept); actions.appendChild(c.reason); actions.appendChild(exclude);
  actions.appendChild(undo);
  root.appendChild(actions);
  run._card = c;
  if (run.trace) { attachDrag(run); }
  return root;
}

// ------------------------------------------------------------------ filters

function conditionOf(run) {
  return run.pin + " / " + run.disc + ", " + fmt(run.force_N, 3) + " N, " + fmt(run.temperature_C, 3) + " °C";
}

function fillSelect(id, values) {
  var select = document.getElementById(id);
  values.forEach(function (v) { var o = el("option", null, v); o.value = v; select.appendChild(o); });
  select.addEventListener("change", applyFilters);
}

function applyFilters() {
  var pair = document.getElementById("filter-pair").value;
  var cond = document.getElementById("filter-condition").value;
  var flag = document.getElementById("filter-flag").value;
  var shown = 0;
  runs.forEach(function (run) {
    var ok = (!pair || run.pin + " / " + run.disc === pair) && (!cond || conditionOf(run) === cond) &&
      (!flag || (flag === "*" ? run.qc : run.flags.indexOf(flag) >= 0));
    run._card.root.style.display = ok ? "" : "none";
    if (ok) { shown++; }
  });
  document.getElementById("shown").textContent = shown + " of " + runs.length + " runs shown";
}

function unique(values) {
  var seen = {}, out = [];
  values.forEach(function (v) { if (!seen[v]) { seen[v] = true; out.push(v); } });
  return out.sort();
}

// ------------------------------------------------------------------ start

var container = document.getElementById("runs");
var fragment = document.createDocumentFragment();
runs.forEach(function (run) {
  byId[run.id] = run;
  if (run.decision) {
    decisions[run.id] = { action: run.decision.action, from_mm: run.decision.from_mm,
                          to_mm: run.decision.to_mm, peak_mm: run.decision.peak_mm,
                          reason: run.decision.reason, who: run.decision.who, date: run.decision.date };
  }
  fragment.appendChild(card(run));
});
container.appendChild(fragment);
fillSelect("filter-pair", unique(runs.map(function (r) { return r.pin + " / " + r.disc; })));
fillSelect("filter-condition", unique(runs.map(conditionOf)));
fillSelect("filter-flag", unique([].concat.apply([], runs.map(function (r) { return r.flags; }))));

function show(run) {
  run._visible = true;
  var d = decisions[run.id];
  if (d && d.action === "window") {
    run._card.from.value = d.from_mm; run._card.to.value = d.to_mm;
    run._card.peak.value = (d.peak_mm === null || d.peak_mm === undefined) ? "" : d.peak_mm;
  }
  refresh(run);
  draw(run);
}

if ("IntersectionObserver" in window) {
  var observer = new IntersectionObserver(function (entries) {
    entries.forEach(function (entry) {
      if (!entry.isIntersecting) { return; }
      var run = byId[entry.target.getAttribute("data-id")];
      observer.unobserve(entry.target);
      show(run);
    });
  }, { rootMargin: "300px" });
  runs.forEach(function (run) {
    if (run.trace) { observer.observe(run._card.root); } else { refresh(run); }
  });
} else {
  runs.forEach(show);
}
runs.forEach(function (run) { if (!run.trace) { refresh(run); } });
applyFilters();
updateDecisions();
window.addEventListener("resize", function () { runs.forEach(function (r) { if (r._drawn) { draw(r); } }); });
document.getElementById("copy").addEventListener("click", function () {
  var text = csvText(), note = document.getElementById("copied");
  if (navigator.clipboard && navigator.clipboard.writeText) {
    navigator.clipboard.writeText(text).then(function () { note.textContent = "copied"; },
      function () { document.getElementById("decisions").select(); note.textContent = "press Ctrl+C"; });
  } else {
    document.getElementById("decisions").select(); note.textContent = "press Ctrl+C";
  }
});
document.getElementById("reviewer").addEventListener("change", function () {
  var who = document.getElementById("reviewer").value.trim();
  Object.keys(decisions).forEach(function (id) { decisions[id].who = who; });
  updateDecisions();
});

window.tribopipeReview = {
  kinetic: function (id, from, to) { return kinetic(byId[id], from, to); },
  staticAt: function (id, peak) { return staticAt(byId[id], peak); },
  csv: csvText,
  ready: true
};

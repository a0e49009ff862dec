/* The SVG plots: mu_K against pressure for the pair, and every disc of the pin. */

function niceStep(span, count) {
  var raw = span / count;
  var mag = Math.pow(10, Math.floor(Math.log10(raw)));
  var f = raw / mag;
  return (f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10) * mag;
}

function ticks(max, count) {
  var step = niceStep(max, count);
  var out = [];
  for (var v = 0; v <= max * (1 + 1e-9); v += step) out.push(Number(v.toPrecision(12)));
  return out;
}

/* An empty plot with axes: returns {g, x(), y()} mapping data to pixels. */
function axes(parent, w, h, m, xMax, yMax, small) {
  var s = svg("svg", { viewBox: "0 0 " + w + " " + h, role: "img" }, parent);
  var x = function (v) { return m.l + (v / xMax) * (w - m.l - m.r); };
  var y = function (v) { return h - m.b - (v / yMax) * (h - m.t - m.b); };
  var grid = svg("g", { class: "tpx-grid" }, s);
  var ax = svg("g", { class: "tpx-axis" }, s);
  ticks(xMax, small ? 3 : 6).forEach(function (v) {
    svg("line", { x1: x(v), x2: x(v), y1: m.t, y2: h - m.b }, grid);
    svgText(ax, x(v), h - m.b + (small ? 11 : 15), pyG(v, 4), { "text-anchor": "middle" });
  });
  ticks(yMax, small ? 3 : 5).forEach(function (v) {
    svg("line", { x1: m.l, x2: w - m.r, y1: y(v), y2: y(v) }, grid);
    svgText(ax, m.l - 4, y(v) + 4, pyG(v, 4), { "text-anchor": "end" });
  });
  svg("path", { d: "M" + m.l + "," + m.t + "V" + (h - m.b) + "H" + (w - m.r), fill: "none" }, ax);
  return { s: s, x: x, y: y };
}

function pairGroups(index) {
  return GROUPS.filter(function (g) { return g.pair === index; });
}

/* The temperatures of a pair as plot series: finite ones sorted, then null (unknown). */
function seriesTemperatures(pair) {
  var ts = pair.runs.map(function (r) { return r.temperature_C; });
  var out = sortedUnique(ts.filter(finite));
  if (ts.some(function (t) { return !finite(t); })) out.push(null);
  return out;
}

function sameT(a, b) { return a === b || (!finite(a) && !finite(b)); }

function tLabel(t) { return t === null ? "T unknown" : pyG(t) + " °C"; }

function fitCurve(plot, f, colour, width) {
  if (!f.curve.length) return;
  var d = f.curve.map(function (pt, i) {
    return (i ? "L" : "M") + plot.x(pt[0]).toFixed(2) + "," + plot.y(pt[1]).toFixed(2);
  }).join("");
  var path = svg("path", { d: d, fill: "none", stroke: colour, "stroke-width": width }, plot.s);
  tip(path, tLabel(f.temperature_C) + ": fit μ_K = " + pyFixed(f.k, 3) + "·p^" + pyFixed(f.exponent, 3) +
    ", R² = " + pyFixed(f.r_squared, 3));
}

function drawPairPlot(res) {
  var box = $("tpx-pair-plot");
  clear(box);
  var index = state.pair;
  var pair = PAIRS[index];
  var groups = pairGroups(index);
  var temps = seriesTemperatures(pair);
  var xs = pair.runs.map(function (r) { return r.pressure_kPa; });
  var ys = pair.runs.map(function (r) { return r.mu_k; });
  groups.forEach(function (g) { ys.push(g.mu_k_mean + (g.mu_k_std || 0)); });
  if (res) {
    xs.push(res.pressure_kPa);
    ys.push(res.mu_k.value + (res.mu_k.expanded || 0));
  }
  var xMax = Math.max.apply(null, xs.filter(finite).concat([1e-9])) * 1.08;
  var yMax = Math.max.apply(null, ys.filter(finite).concat([1e-9])) * 1.12 + 0.05 * temps.length;
  var W = 640, H = 400, M = { l: 52, r: 14, t: 30, b: 42 };
  var plot = axes(box, W, H, M, xMax, yMax, false);
  svgText(plot.s, W / 2, 18, pair.pin + " on " + pair.disc, { "text-anchor": "middle", "font-weight": "600" });
  svgText(plot.s, (M.l + W - M.r) / 2, H - 8, "contact pressure p [kPa]", { "text-anchor": "middle" });
  svgText(plot.s, 14, (M.t + H - M.b) / 2, "μ_K", { "text-anchor": "middle",
    transform: "rotate(-90 14 " + (M.t + H - M.b) / 2 + ")" });
  temps.forEach(function (t, i) {
    var colour = COLOURS[i % COLOURS.length];
    var chosen = res && sameT(t, res.temperature_C);
    pair.fits.filter(function (f) { return sameT(f.temperature_C, t); })
      .forEach(function (f) { fitCurve(plot, f, colour, chosen ? 2.4 : 1.4); });
    pair.runs.filter(function (r) { return sameT(r.temperature_C, t); }).forEach(function (r) {
      var c = svg("circle", { cx: plot.x(r.pressure_kPa), cy: plot.y(r.mu_k), r: 2.6, fill: colour,
        "fill-opacity": 0.45 }, plot.s);
      tip(c, "run " + r.id.slice(0, 8) + ": " + pyG(r.pressure_kPa) + " kPa, " + tLabel(r.temperature_C) +
        ", repeat " + (r.repeat === null ? "?" : r.repeat) + ": μ_K " + f3(r.mu_k) +
        (r.flags.length ? " (" + r.flags.join(", ") + ")" : "") +
        (r.review ? " [reviewed: " + r.review + "]" : "") +
        (runOrigin(r) ? " — from " + runOrigin(r) : ""));
    });
    groups.filter(function (g) { return sameT(g.temperature_C, t) && finite(g.mu_k_mean); })
      .forEach(function (g) {
        var gx = plot.x(g.pressure_kPa);
        if (finite(g.mu_k_std)) {
          svg("path", { d: "M" + gx + "," + plot.y(g.mu_k_mean - g.mu_k_std) + "V" +
            plot.y(g.mu_k_mean + g.mu_k_std), stroke: colour, "stroke-width": 1.3 }, plot.s);
        }
        var c = svg("circle", { cx: gx, cy: plot.y(g.mu_k_mean), r: 4.5, fill: colour,
          stroke: "#fff", "stroke-width": 1 }, plot.s);
        tip(c, pyG(g.pressure_kPa) + " kPa, " + tLabel(g.temperature_C) + ": mean μ_K " + f3(g.mu_k_mean) +
          (finite(g.mu_k_std) ? " ± " + f3(g.mu_k_std) + " (SD)" : "") + ", n = " + g.mu_k_n);
      });
    // legend
    var ly = M.t + 6 + i * 16;
    svg("rect", { x: W - M.r - 250, y: ly - 8, width: 10, height: 10, fill: colour }, plot.s);
    var fit = pair.fits.find(function (f) { return sameT(f.temperature_C, t); });
    var fitText = !fit ? "" : fit.k === null ? ": not fitted" :
      ": μ_K = " + pyFixed(fit.k, 3) + "·p^" + pyFixed(fit.exponent, 3) + ", R² " + pyFixed(fit.r_squared, 3);
    svgText(plot.s, W - M.r - 236, ly + 1, tLabel(t) + fitText);
  });
  if (res) {
    var px = plot.x(res.pressure_kPa);
    var py = plot.y(res.mu_k.value);
    if (res.mu_k.expanded !== null) { // value ± U, bounded at 0 (rounding.lower_bound)
      svg("path", { d: "M" + px + "," + plot.y(Math.max(0, res.mu_k.value - res.mu_k.expanded)) + "V" +
        plot.y(res.mu_k.value + res.mu_k.expanded), stroke: "#000", "stroke-width": 1.5 }, plot.s);
    }
    var dmd = svg("path", { d: "M" + px + "," + (py - 7) + "l7,7l-7,7l-7,-7z", fill: "#000",
      stroke: "#fff", "stroke-width": 1 }, plot.s);
    tip(dmd, "chosen: " + pyG(res.pressure_kPa) + " kPa, " +
      (res.temperature_C === null ? "T unknown" : pyG(res.temperature_C) + " °C") + ": μ_K " +
      f3(res.mu_k.value) + (res.clamped ? " (edge value held)" : ""));
  }
}

function drawOverview() {
  var box = $("tpx-overview");
  clear(box);
  var pin = PINS[pinOf(state.pair)];
  var xs = [];
  var ys = [];
  pin.pairs.forEach(function (i) {
    pairGroups(i).forEach(function (g) { xs.push(g.pressure_kPa); ys.push(g.mu_k_mean); });
    PAIRS[i].fits.forEach(function (f) { f.curve.forEach(function (pt) { ys.push(pt[1]); }); });
  });
  var xMax = Math.max.apply(null, xs.filter(finite).concat([1e-9])) * 1.08;
  var yMax = Math.max.apply(null, ys.filter(finite).concat([1e-9])) * 1.1;
  pin.pairs.forEach(function (i) {
    var pair = PAIRS[i];
    var panel = make("div", null, "tpx-panel" + (i === state.pair ? " tpx-on" : ""));
    panel.tabIndex = 0;
    panel.setAttribute("role", "button");
    panel.setAttribute("aria-label", "select disc " + pair.disc);
    panel.dataset.pair = String(i);
    var W = 240, H = 180, M = { l: 34, r: 8, t: 22, b: 20 };
    var plot = axes(panel, W, H, M, xMax, yMax, true);
    svgText(plot.s, W / 2, 14, pair.disc, { "text-anchor": "middle", "font-weight": "600" });
    seriesTemperatures(pair).forEach(function (t, k) {
      var colour = COLOURS[k % COLOURS.length];
      pair.fits.filter(function (f) { return sameT(f.temperature_C, t); })
        .forEach(function (f) { fitCurve(plot, f, colour, 1); });
      var gs = pairGroups(i).filter(function (g) { return sameT(g.temperature_C, t) && finite(g.mu_k_mean); })
        .sort(function (a, b) { return a.pressure_kPa - b.pressure_kPa; });
      gs.forEach(function (g) {
        var c = svg("circle", { cx: plot.x(g.pressure_kPa), cy: plot.y(g.mu_k_mean), r: 3, fill: colour }, plot.s);
        tip(c, pair.disc + ", " + pyG(g.pressure_kPa) + " kPa, " + tLabel(g.temperature_C) + ": mean μ_K " +
          f3(g.mu_k_mean) + ", n = " + g.mu_k_n);
      });
    });
    var choose = function () {
      state.pair = i;
      discSelect.value = String(i);
      update(true);
    };
    panel.addEventListener("click", choose);
    panel.addEventListener("keydown", function (ev) {
      if (ev.key === "Enter" || ev.key === " ") { ev.preventDefault(); choose(); }
    });
    box.appendChild(panel);
  });
}

/* The SVG plots: mu_K against pressure for the pair at its chosen speed, and every disc
   of the pin. Each is drawn at the width it is shown (one unit of the SVG is one pixel),
   so its text keeps the size the style sheet gives it. */

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

/* A tick's text: the browser's own shortest text of the value to 4 digits. */
function tickText(v) { return String(Number(v.toPrecision(4))); }

/* An empty plot with axes: returns {s, x(), y()} mapping data to pixels. */
function axes(parent, w, h, m, xMax, yMax, small) {
  var s = svg("svg", { viewBox: "0 0 " + w + " " + h, width: w, height: h, role: "img",
    class: small ? "tpx-small" : "tpx-main-plot" }, parent);
  var x = function (v) { return m.l + (v / xMax) * (w - m.l - m.r); };
  var y = function (v) { return h - m.b - (v / yMax) * (h - m.t - m.b); };
  var grid = svg("g", { class: "tpx-grid" }, s);
  var ax = svg("g", { class: "tpx-axis" }, s);
  var nx = Math.max(2, Math.min(small ? 4 : 8, Math.floor((w - m.l - m.r) / 60)));
  var ny = Math.max(3, Math.min(small ? 4 : 8, Math.floor((h - m.t - m.b) / 36)));
  ticks(xMax, nx).forEach(function (v) {
    svg("line", { x1: x(v), x2: x(v), y1: m.t, y2: h - m.b }, grid);
    svgText(ax, x(v), h - m.b + 15, tickText(v), { "text-anchor": "middle" });
  });
  ticks(yMax, ny).forEach(function (v) {
    svg("line", { x1: m.l, x2: w - m.r, y1: y(v), y2: y(v) }, grid);
    svgText(ax, m.l - 5, y(v) + 4, tickText(v), { "text-anchor": "end" });
  });
  svg("path", { d: "M" + m.l + "," + m.t + "V" + (h - m.b) + "H" + (w - m.r), fill: "none" }, ax);
  return { s: s, x: x, y: y };
}

/* The groups of a pair at one nominal speed [mm/s]. */
function pairGroups(index, speed) {
  return GROUPS.filter(function (g) {
    return g.pair === index && (!finite(g.nominal_speed_mm_s) || g.nominal_speed_mm_s === speed);
  });
}

/* The temperatures of a pair's runs as plot series: finite ones sorted, then null. */
function seriesTemperatures(runs) {
  var ts = runs.map(function (r) { return r.temperature_C; });
  var out = sortedUnique(ts.filter(finite));
  if (ts.some(function (t) { return !finite(t); })) out.push(null);
  return out;
}

function sameT(a, b) { return a === b || (!finite(a) && !finite(b)); }

function tLabel(pair, t) {
  if (t === null) return say("t_unknown", {});
  var at = pair.speeds.map(function (s) { return s.temperatures; }).reduce(function (a, b) { return a.concat(b); }, [])
    .find(function (x) { return x.value === t; });
  return say("t_label", { t: at ? at.text : tickText(t) });
}

function fitCurve(plot, f, colour, width) {
  if (!f.curve.length) return;
  var d = f.curve.map(function (pt, i) {
    return (i ? "L" : "M") + plot.x(pt[0]).toFixed(2) + "," + plot.y(pt[1]).toFixed(2);
  }).join("");
  var path = svg("path", { d: d, fill: "none", stroke: colour, "stroke-width": width }, plot.s);
  tip(path, say("fit_tip", { legend: f.legend }));
}

/* The runs shown: the pair's at the chosen speed, of the chosen lab. */
function shownRuns(index, speed) {
  return runsOf(index).filter(function (r) {
    return r.speed_mm_s === speed && (state.lab < 0 || r.lab === state.lab);
  });
}

function plotWidth(box, fallback) { return Math.max(240, Math.floor(box.clientWidth || fallback)); }

function drawPairPlot(res) {
  var box = $("tpx-pair-plot");
  clear(box);
  var index = state.pair;
  var pair = PAIRS[index];
  var at = speedOf(pair);
  var speed = at.speed_mm_s;
  var runs = shownRuns(index, speed);
  var groups = pairGroups(index, speed);
  var temps = seriesTemperatures(runs.length ? runs : runsOf(index).filter(function (r) {
    return r.speed_mm_s === speed; }));
  var xs = runs.map(function (r) { return r.pressure_kPa; });
  var ys = runs.map(function (r) { return r.mu_k; });
  groups.forEach(function (g) { xs.push(g.pressure_kPa); ys.push(g.mu_k_mean + (g.mu_k_std || 0)); });
  if (res) {
    xs.push(res.pressure_kPa);
    ys.push(res.mu_k.value + (res.mu_k.expanded || 0));
  }
  var W = plotWidth(box, 600);
  var H = Math.round(Math.min(440, Math.max(280, W * 0.62)));
  var legendRows = temps.length + (state.colour === "lab" ? DATA.labs.length : 0);
  var M = { l: 56, r: 14, t: 30 + 18 * legendRows, b: 46 };
  var xMax = Math.max.apply(null, xs.filter(finite).concat([1e-9])) * 1.08;
  var yMax = Math.max.apply(null, ys.filter(finite).concat([1e-9])) * 1.1;
  var plot = axes(box, W, H, M, xMax, yMax, false);
  var several = pair.speeds.length > 1;
  svgText(plot.s, W / 2, 18, say(several ? "pair_title_speed" : "pair_title",
    { pin: pair.pin, disc: pair.disc, speed: at.text }),
    { "text-anchor": "middle", "font-weight": "600", class: "tpx-title" });
  svgText(plot.s, (M.l + W - M.r) / 2, H - 8, say("x_axis", {}), { "text-anchor": "middle" });
  svgText(plot.s, 14, (M.t + H - M.b) / 2, say("y_axis", {}), { "text-anchor": "middle",
    transform: "rotate(-90 14 " + (M.t + H - M.b) / 2 + ")" });
  var byLab = state.colour === "lab";
  temps.forEach(function (t, i) {
    var colour = COLOURS[i % COLOURS.length];
    var chosen = res && sameT(t, res.temperature_C);
    var fits = pair.fits.filter(function (f) { return sameT(f.temperature_C, t) && f.speed_mm_s === speed; });
    fits.forEach(function (f) { fitCurve(plot, f, colour, chosen ? 2.6 : 1.5); });
    runs.filter(function (r) { return sameT(r.temperature_C, t); }).forEach(function (r) {
      var c = svg("circle", { cx: plot.x(r.pressure_kPa), cy: plot.y(r.mu_k), r: 3,
        fill: byLab ? COLOURS[(r.lab + 3) % COLOURS.length] : colour, "fill-opacity": byLab ? 0.8 : 0.45,
        class: "tpx-run" }, plot.s);
      c.dataset.lab = String(r.lab);
      tip(c, say(r.flags.length ? "run_tip_flags" : "run_tip", {
        repeat: r.repeat === null ? say("repeat_unknown", {}) : r.repeat, lab: DATA.labs[r.lab],
        line: r.line, flags: r.flags.join(say("list_join", {})) }));
    });
    groups.filter(function (g) { return sameT(g.temperature_C, t) && finite(g.mu_k_mean); })
      .forEach(function (g) {
        var gx = plot.x(g.pressure_kPa);
        if (finite(g.mu_k_std)) {
          svg("path", { d: "M" + gx + "," + plot.y(g.mu_k_mean - g.mu_k_std) + "V" +
            plot.y(g.mu_k_mean + g.mu_k_std), stroke: colour, "stroke-width": 1.4 }, plot.s);
        }
        var c = svg("circle", { cx: gx, cy: plot.y(g.mu_k_mean), r: 5, fill: colour,
          stroke: "#fff", "stroke-width": 1, class: "tpx-mean" }, plot.s);
        tip(c, say("mean_tip", { p: g.text.pressure_kPa, t: tLabel(pair, g.temperature_C),
          mean: g.text.mu_k_mean, sd: g.text.mu_k_std || say("sd_unknown", {}), n: g.text.mu_k_n }));
      });
    // legend: the temperature and its fit at this speed
    var ly = 30 + i * 18;
    svg("rect", { x: M.l + 6, y: ly - 9, width: 11, height: 11, fill: colour }, plot.s);
    svgText(plot.s, M.l + 22, ly + 1, say(fits.length ? "legend_fit" : "legend",
      { t: tLabel(pair, t), fit: fits.length ? fits[0].legend : "" }), { class: "tpx-legend" });
  });
  if (byLab) {
    DATA.labs.forEach(function (name, k) {
      var ly = 30 + (temps.length + k) * 18;
      svg("circle", { cx: M.l + 11, cy: ly - 4, r: 4, fill: COLOURS[(k + 3) % COLOURS.length] }, plot.s);
      svgText(plot.s, M.l + 22, ly + 1, say("lab_legend", { lab: name }), { class: "tpx-legend" });
    });
  }
  if (res) {
    var px = plot.x(res.pressure_kPa);
    var py = plot.y(res.mu_k.value);
    if (res.mu_k.expanded !== null) { // value ± U, bounded at 0 (rounding.lower_bound)
      svg("path", { d: "M" + px + "," + plot.y(Math.max(0, res.mu_k.value - res.mu_k.expanded)) + "V" +
        plot.y(res.mu_k.value + res.mu_k.expanded), stroke: "#000", "stroke-width": 1.6 }, plot.s);
    }
    var dmd = svg("path", { d: "M" + px + "," + (py - 7) + "l7,7l-7,7l-7,-7z", fill: "#000",
      stroke: "#fff", "stroke-width": 1 }, plot.s);
    tip(dmd, say("chosen_tip", { p: pInput.value, t: res.temperature_C === null ?
      say("t_unknown", {}) : say("t_label", { t: tInput.value }), mu: estimateText(res.mu_k) }));
  }
}

function drawOverview() {
  var box = $("tpx-overview");
  clear(box);
  var pin = PINS[pinOf(state.pair)];
  var wanted = speedOf(PAIRS[state.pair]).speed_mm_s;
  /* each pair at the chosen speed where it has it, else at its first */
  var speedFor = function (i) {
    var s = PAIRS[i].speeds.find(function (x) { return x.speed_mm_s === wanted; });
    return (s || PAIRS[i].speeds[0]).speed_mm_s;
  };
  var xs = [];
  var ys = [];
  pin.pairs.forEach(function (i) {
    pairGroups(i, speedFor(i)).forEach(function (g) { xs.push(g.pressure_kPa); ys.push(g.mu_k_mean); });
    PAIRS[i].fits.forEach(function (f) {
      if (f.speed_mm_s === speedFor(i)) f.curve.forEach(function (pt) { ys.push(pt[1]); });
    });
  });
  var xMax = Math.max.apply(null, xs.filter(finite).concat([1e-9])) * 1.08;
  var yMax = Math.max.apply(null, ys.filter(finite).concat([1e-9])) * 1.1;
  var panels = pin.pairs.map(function (i) {
    var panel = make("div", null, "tpx-panel" + (i === state.pair ? " tpx-on" : ""));
    box.appendChild(panel);
    return panel;
  });
  pin.pairs.forEach(function (i, k) {
    var pair = PAIRS[i];
    var speed = speedFor(i);
    var panel = panels[k];
    panel.tabIndex = 0;
    panel.setAttribute("role", "button");
    panel.setAttribute("aria-label", say("panel_label", { disc: pair.disc }));
    panel.dataset.pair = String(i);
    var W = plotWidth(panel, 240) - 2;
    var H = Math.round(W * 0.72);
    var M = { l: 42, r: 10, t: 24, b: 24 };
    var plot = axes(panel, W, H, M, xMax, yMax, true);
    var at = pair.speeds.find(function (x) { return x.speed_mm_s === speed; });
    svgText(plot.s, W / 2, 15, pair.disc, { "text-anchor": "middle", "font-weight": "600", class: "tpx-title" });
    if (pair.speeds.length > 1) {
      svgText(plot.s, W - M.r, M.t + 12, say("speed_mark", { speed: at.text }),
        { "text-anchor": "end", class: "tpx-legend" });
    }
    var groups = pairGroups(i, speed);
    var temps = sortedUnique(groups.map(function (g) { return g.temperature_C; }).filter(finite));
    if (groups.some(function (g) { return !finite(g.temperature_C); })) temps.push(null);
    temps.forEach(function (t, c) {
      var colour = COLOURS[c % COLOURS.length];
      pair.fits.filter(function (f) { return sameT(f.temperature_C, t) && f.speed_mm_s === speed; })
        .forEach(function (f) { fitCurve(plot, f, colour, 1.2); });
      groups.filter(function (g) { return sameT(g.temperature_C, t) && finite(g.mu_k_mean); })
        .forEach(function (g) {
          var dot = svg("circle", { cx: plot.x(g.pressure_kPa), cy: plot.y(g.mu_k_mean), r: 3.5, fill: colour }, plot.s);
          tip(dot, say("panel_tip", { disc: pair.disc, p: g.text.pressure_kPa,
            t: tLabel(pair, g.temperature_C), mean: g.text.mu_k_mean, n: g.text.mu_k_n }));
        });
    });
    var choose = function () {
      state.pair = i;
      discSelect.value = String(i);
      newPair();
    };
    panel.addEventListener("click", choose);
    panel.addEventListener("keydown", function (ev) {
      if (ev.key === "Enter" || ev.key === " ") { ev.preventDefault(); choose(); }
    });
  });
}

/* tribopipe query, redone: the rule of tribopipe/interpolation.py and tribopipe/query.py on
   the pair's points, and the rounding of tribopipe/rounding.py (round_gum, plus_minus,
   decimal_text) for the numbers it computes (tests/test_interpolation.py runs this file in
   node and holds it equal to the Python). Every other text comes from Python (DATA). */

function QueryError(message) { this.name = "QueryError"; this.message = message; }
QueryError.prototype = Object.create(Error.prototype);

function finite(v) { return typeof v === "number" && Number.isFinite(v); }

function sortedUnique(values) {
  return Array.from(new Set(values)).sort(function (a, b) { return a - b; });
}

/* interpolation.bracket: [[index, weight], ...] into sorted unique xs for x, and clamped. */
function bracket(xs, x) {
  var n = xs.length;
  if (n === 1) return [[[0, 1.0]], x !== xs[0]];
  if (x <= xs[0]) return [[[0, 1.0]], x < xs[0]];
  if (x >= xs[n - 1]) return [[[n - 1, 1.0]], x > xs[n - 1]];
  var hi = 0;
  while (hi < n && xs[hi] <= x) hi += 1;
  var lo = hi - 1;
  if (x === xs[lo]) return [[[lo, 1.0]], false];
  var wHi = (x - xs[lo]) / (xs[hi] - xs[lo]);
  return [[[lo, 1.0 - wHi], [hi, wHi]], false];
}

/* interpolation._pressure_segment: {lo, hi, w, log, span, clamped} (positions into ps). */
function pressureSegment(ps, mus, p) {
  var b = bracket(ps, p);
  if (b[0].length === 1) return {lo: b[0][0][0], hi: null, w: 0.0, log: false, span: 0.0, clamped: b[1]};
  var lo = b[0][0][0];
  var hi = b[0][1][0];
  if (ps[lo] > 0 && mus[lo] > 0 && mus[hi] > 0) {
    var span = Math.log(ps[hi] / ps[lo]);
    return {lo: lo, hi: hi, w: Math.log(p / ps[lo]) / span, log: true, span: span, clamped: false};
  }
  return {lo: lo, hi: hi, w: 1.0 - b[0][0][1], log: false, span: 0.0, clamped: false};
}

/* interpolation.stencil: {segments: [{tWeight, lo, hi, w, log, span}], clampedP, clampedT};
   `needed` is what a request without a temperature is told (Python's text). */
function stencil(ps, ts, mus, p, t, needed) {
  var n = ps.length;
  var all = [];
  for (var i = 0; i < n; i += 1) all.push(i);
  var sets = [[all, 1.0]];
  var clampedT = false;
  var known = ts.filter(finite);
  if (known.length) {
    var temps = sortedUnique(known);
    var tBrackets;
    if (t === null) {
      if (temps.length > 1) throw new QueryError(needed);
      tBrackets = [[0, 1.0]];
    } else {
      var b = bracket(temps, t);
      tBrackets = b[0];
      clampedT = b[1];
    }
    sets = tBrackets.map(function (tw) {
      return [all.filter(function (k) { return ts[k] === temps[tw[0]]; }), tw[1]];
    });
  }
  var clampedP = false;
  var segments = sets.map(function (set) {
    var idx = set[0].slice().sort(function (a, b) { return ps[a] - ps[b]; });
    var seg = pressureSegment(idx.map(function (k) { return ps[k]; }),
      idx.map(function (k) { return mus[k]; }), p);
    clampedP = clampedP || seg.clamped;
    return {tWeight: set[1], lo: idx[seg.lo], hi: seg.hi === null ? null : idx[seg.hi],
      w: seg.w, log: seg.log, span: seg.span};
  });
  return {segments: segments, clampedP: clampedP, clampedT: clampedT};
}

/* Stencil.weights: each point's share of the value. */
function stencilWeights(st, n) {
  var out = new Array(n).fill(0);
  st.segments.forEach(function (s) {
    out[s.lo] += s.tWeight * (s.hi !== null ? 1.0 - s.w : 1.0);
    if (s.hi !== null) out[s.hi] += s.tWeight * s.w;
  });
  return out;
}

/* interpolation.segment_value */
function segmentValue(s, mus) {
  if (s.hi === null) return mus[s.lo];
  if (s.log) return Math.exp((1.0 - s.w) * Math.log(mus[s.lo]) + s.w * Math.log(mus[s.hi]));
  return (1.0 - s.w) * mus[s.lo] + s.w * mus[s.hi];
}

/* interpolation.evaluate and interpolation.interpolation_u */
function evaluateStencil(st, mus) {
  return st.segments.reduce(function (acc, s) { return acc + s.tWeight * segmentValue(s, mus); }, 0);
}

function interpolationU(st, mus, kappa) {
  var total = 0.0;
  st.segments.forEach(function (s) {
    if (s.hi === null || !s.log) return;
    var bend = 0.5 * kappa * s.w * (1.0 - s.w) * s.span * s.span;
    total += s.tWeight * Math.abs(segmentValue(s, mus)) * bend;
  });
  return total;
}

/* query._estimate over a pair's points (each {pressure_kPa, temperature_C, mean, half, u,
   budget, n}) with the map's curvature kappa; `needed` as stencil's. */
function estimate(points, p, t, kappa, needed) {
  var mus = points.map(function (q) { return q.mean; });
  var st = stencil(
    points.map(function (q) { return q.pressure_kPa; }),
    points.map(function (q) { return q.temperature_C === null ? NaN : q.temperature_C; }),
    mus, p, t, needed);
  var w = stencilWeights(st, points.length);
  var unc = 0;
  var uncKnown = true;
  var uGroups = 0;
  var uKnown = true;
  var budgets = true;
  var used = [];
  points.forEach(function (q, i) {
    if (!(w[i] > 0)) return;
    if (finite(q.half)) unc += w[i] * q.half; else uncKnown = false;
    if (finite(q.u)) uGroups += w[i] * q.u; else uKnown = false;
    if (!q.budget) budgets = false;
    used.push({
      pressure_kPa: q.pressure_kPa,
      temperature_C: finite(q.temperature_C) ? q.temperature_C : null,
      mean: q.mean,
      ci95_half_width: finite(q.half) ? q.half : null,
      n: q.n,
      weight: w[i],
      u: finite(q.u) ? q.u : null,
      point: q,
    });
  });
  var uInterp = interpolationU(st, mus, kappa);
  var expanded = uKnown ? 2.0 * Math.hypot(uGroups, uInterp) : null;
  if (expanded !== null && !(expanded >= U_FLOOR)) expanded = null; // rounding.known_u
  expanded = heldU(expanded, st.clampedP || st.clampedT);
  return {
    value: evaluateStencil(st, mus),
    uncertainty: uncKnown ? unc : null,
    used: used,
    clamped_pressure: st.clampedP,
    clamped_temperature: st.clampedT,
    u_combined: uKnown && budgets ? uGroups : null,
    u_interpolation: uInterp,
    u_groups: uKnown ? uGroups : null,
    expanded: expanded,
    budgets_known: budgets,
    n_min: Math.min.apply(null, used.map(function (u) { return u.n; })),
  };
}

/* rounding.U_FLOOR: a smaller U is identical repeats or floating-point noise */
var U_FLOOR = 1e-6;

/* interpolation.held_u: outside the measured range U is withdrawn */
function heldU(expanded, clamped) { return clamped ? null : expanded; }

function extrapolated(est) {
  return est.clamped_pressure || est.clamped_temperature || est.clamped_speed === true;
}

/* rounding.round_gum: [valueText, UText], U to two significant digits, the value to the
   same decimal, half away from zero on the shortest decimal text of each number. */
function decimalParts(x) {
  var m = /^(-?)(\d+)(?:\.(\d+))?(?:e([+-]\d+))?$/.exec(String(x));
  var digits = (m[2] + (m[3] || "")).replace(/^0+(?=\d)/, "");
  var exp = (m[4] ? Number(m[4]) : 0) - (m[3] || "").length; // value = digits × 10^exp
  return {neg: m[1] === "-", digits: digits, exp: exp};
}

/* the decimal x rounded half away from zero to a multiple of 10^q, as [neg, BigInt units] */
function quantize(x, q) {
  var d = decimalParts(x);
  var units;
  if (d.exp >= q) {
    units = BigInt(d.digits) * (10n ** BigInt(d.exp - q));
  } else {
    var cut = q - d.exp;
    var scale = 10n ** BigInt(cut);
    var whole = BigInt(d.digits);
    units = whole / scale;
    if ((whole % scale) * 2n >= scale) units += 1n;
  }
  return [d.neg, units];
}

function fixedText(neg, units, q) {
  var text = units.toString();
  if (q >= 0) {
    text = units === 0n ? "0" : text + "0".repeat(q);
  } else {
    var dec = -q;
    text = text.padStart(dec + 1, "0");
    text = text.slice(0, text.length - dec) + "." + text.slice(text.length - dec);
  }
  return (neg && units !== 0n ? "-" : "") + text;
}

function adjusted(x) { // Decimal.adjusted(): the power of ten of the leading digit
  var d = decimalParts(x);
  return d.exp + d.digits.length - 1;
}

function roundGum(value, U) {
  var q = adjusted(U) - 1;
  var u = quantize(U, q);
  if (u[1].toString().length > 2) { q += 1; u = quantize(U, q); }
  var v = quantize(value, q);
  return [fixedText(v[0], v[1], q), fixedText(u[0], u[1], q)];
}

/* rounding.decimal_text: x rounded half away from zero on its shortest decimal text, to
   `digits` significant digits laid out as Python's "g" lays them out, or (digits null) to
   `places` decimals. */
function decimalText(x, digits, places) {
  if (!Number.isFinite(x)) return Number.isNaN(x) ? "nan" : x > 0 ? "inf" : "-inf";
  var r;
  if (digits === null || digits === undefined) {
    r = quantize(x, -places);
    return fixedText(r[0], r[1], -places);
  }
  if (x === 0) return "0";
  var e = adjusted(x);
  r = quantize(x, e - digits + 1);
  if (r[1].toString().length > digits) { e += 1; r = quantize(x, e - digits + 1); }
  var sign = r[0] ? "-" : "";
  if (e >= -4 && e < digits) {
    var text = fixedText(r[0], r[1], e - digits + 1);
    return text.indexOf(".") < 0 ? text : text.replace(/\.?0+$/, "");
  }
  var d = r[1].toString();
  var tail = d.slice(1).replace(/0+$/, "");
  return sign + d[0] + (tail ? "." + tail : "") + "e" + (e < 0 ? "-" : "+") +
    String(Math.abs(e)).padStart(2, "0");
}

function g6(x) { return decimalText(x, 6); }     // format "g" of a computed number
function f3(x) { return decimalText(x, null, 3); } // three decimals, as the tables

/* rounding.plus_minus: "0.53 ± 0.11", bounded at zero as "0.05 +0.11/−0.05" */
function plusMinus(value, U, asciiOnly) {
  var r = roundGum(value, U);
  var minus = asciiOnly ? "-" : "\u2212";
  if (Number(r[0]) < Number(r[1])) return r[0] + " +" + r[1] + "/" + minus + r[0];
  return r[0] + (asciiOnly ? " +/- " : " \u00b1 ") + r[1];
}

/* query.estimate_text (the words from DATA.texts.why_no_u) */
function estimateText(est, asciiOnly) {
  var out = extrapolated(est);
  if (est.expanded !== null && !out) return plusMinus(est.value, est.expanded, asciiOnly);
  var why = DATA.texts.why_no_u;
  return f3(est.value) + " (" + (out ? why.extrapolated : est.n_min < 2 ?
    why.single_run : why.unknown) + ")";
}

/* query.uncertainty_notes */
function uncertaintyNotes(est) {
  var notes = [];
  if (est.n_min < 2) notes.push(DATA.texts.notes.single_run);
  if (!est.budgets_known) notes.push(DATA.texts.notes.no_budget);
  return notes;
}

/* query.name_key, from Python's own rule as data (DATA.texts.names): the white space
   str.strip removes, and each character whose casefold is not its lower case. */
var NAME_EDGES = null;
function nameKey(text) {
  var names = DATA.texts.names;
  if (NAME_EDGES === null) {
    NAME_EDGES = new RegExp("^[" + names.space + "]+|[" + names.space + "]+$", "gu");
  }
  return Array.from(String(text).replace(NAME_EDGES, ""), function (c) {
    return Object.prototype.hasOwnProperty.call(names.fold, c) ? names.fold[c] : c.toLowerCase();
  }).join("");
}

/* A name as a link or a caller writes it, against a pair's name: the name itself or the
   key Python matches (DATA.pairs[i].keys: query.name_key). */
function sameName(text, name, key) {
  return String(text) === name || nameKey(text) === key;
}

function findPair(pin, disc) {
  for (var i = 0; i < PAIRS.length; i += 1) {
    if (sameName(pin, PAIRS[i].pin, PAIRS[i].keys[0]) &&
        sameName(disc, PAIRS[i].disc, PAIRS[i].keys[1])) return i;
  }
  return -1;
}

/* query.SPEED_MATCH_REL: a requested speed this close (in ln v) to a measured one is it */
var SPEED_MATCH_REL = 0.01;

/* query.speed_weights: [[index, weight], ...] into a pair's sorted speeds [mm/s] for v
   (linear in ln v, interpolation.speed_bracket), and clamped. */
function speedWeights(speeds, v, needed) {
  if (v === null) {
    if (speeds.length > 1) throw new QueryError(needed);
    return [[[0, 1.0]], false];
  }
  if (typeof v !== "number" || !Number.isFinite(v) || !(v > 0)) {
    throw new QueryError(DATA.texts.errors.speed.replace("{}", decimalText(Number(v), 17)));
  }
  for (var i = 0; i < speeds.length; i += 1) {
    if (Math.abs(Math.log(v / speeds[i])) <= SPEED_MATCH_REL) return [[[i, 1.0]], false];
  }
  return bracket(speeds.map(Math.log), Math.log(v));
}

/* query._blend: one estimate from [[weight, speed, estimate], ...] at measured speeds. */
function blend(parts) {
  function weighted(name) {
    var total = 0;
    for (var i = 0; i < parts.length; i += 1) {
      var x = parts[i][2][name];
      if (x === null) return null;
      total += parts[i][0] * x;
    }
    return total;
  }
  var value = 0;
  var uInterp = 0;
  parts.forEach(function (q) { value += q[0] * q[2].value; uInterp += q[0] * q[2].u_interpolation; });
  var uGroups = weighted("u_groups");
  var expanded = uGroups === null ? null : 2.0 * Math.hypot(uGroups, uInterp);
  if (expanded !== null && !(expanded >= U_FLOOR)) expanded = null;
  expanded = heldU(expanded, parts.some(function (q) { return extrapolated(q[2]); }));
  var used = [];
  parts.forEach(function (q) {
    q[2].used.forEach(function (u) {
      var copy = Object.assign({}, u);
      copy.weight = u.weight * q[0];
      copy.speed_mm_s = q[1];
      used.push(copy);
    });
  });
  return {
    value: value,
    uncertainty: weighted("uncertainty"),
    used: used,
    clamped_pressure: parts.some(function (q) { return q[2].clamped_pressure; }),
    clamped_temperature: parts.some(function (q) { return q[2].clamped_temperature; }),
    u_combined: weighted("u_combined"),
    u_interpolation: uInterp,
    u_groups: uGroups,
    expanded: expanded,
    budgets_known: parts.every(function (q) { return q[2].budgets_known; }),
    n_min: Math.min.apply(null, parts.map(function (q) { return q[2].n_min; })),
    clamped_speed: false,
  };
}

/* The pair's measured speeds: [{speed_mm_s, text, mu_k_points, mu_s_points, ...}]. */
function pairSpeeds(pair) { return pair.speeds; }

/* query._held_speed */
function heldSpeed(est, clamped) {
  est.clamped_speed = clamped;
  est.expanded = heldU(est.expanded, clamped);
  return est;
}

/* query.query: mu_K (and mu_S) of a pair at a pressure [kPa], temperature [°C] (or
   null) and sliding speed [mm/s] (or null: a pair of one speed); the result has the
   fields of QueryResult.to_dict(). Throws a QueryError. */
function query(pin, disc, p, t, v) {
  if (t === undefined) t = null;
  if (v === undefined) v = null;
  var errors = DATA.texts.errors;
  if (typeof p !== "number" || !Number.isFinite(p) || p < 0) {
    throw new QueryError(errors.pressure.replace("{}", decimalText(Number(p), 17)));
  }
  if (t !== null && (typeof t !== "number" || !Number.isFinite(t))) {
    throw new QueryError(errors.temperature.replace("{}", decimalText(Number(t), 17)));
  }
  var index = findPair(pin, disc);
  if (index < 0) {
    throw new QueryError(errors.no_pair.replace("{pin}", JSON.stringify(String(pin)))
      .replace("{disc}", JSON.stringify(String(disc))));
  }
  var pair = PAIRS[index];
  var speeds = pairSpeeds(pair);
  var sw = speedWeights(speeds.map(function (x) { return x.speed_mm_s; }), v, pair.speed_needed);
  var notes = [];
  if (pair.left_out) notes.push(DATA.texts.notes.left_out.replace("{n}", String(pair.left_out)));
  var kParts = [];
  var sParts = [];
  var kPoints = [];
  sw[0].forEach(function (iw) {
    var at = speeds[iw[0]];
    kParts.push([iw[1], at.speed_mm_s,
      estimate(at.mu_k_points, p, t, DATA.curvature.mu_k, at.temperature_needed)]);
    sParts.push(at.mu_s_points.length ? [iw[1], at.speed_mm_s,
      estimate(at.mu_s_points, p, t, DATA.curvature.mu_s, at.temperature_needed)] : null);
    kPoints = kPoints.concat(at.mu_k_points);
  });
  var muK = heldSpeed(blend(kParts), sw[1]);
  var muS = sParts.every(function (q) { return q !== null; }) ? heldSpeed(blend(sParts), sw[1]) : null;
  if (muS === null) {
    notes.push(DATA.texts.notes[speeds.length > 1 ? "mu_s_unknown_speeds" : "mu_s_unknown"]);
  }
  notes = notes.concat(uncertaintyNotes(muK));
  [muK, muS].forEach(function (est) { // QueryResult.to_dict's text and lower
    if (est === null) return;
    est.text = estimateText(est);
    est.lower = est.expanded === null ? null : Math.max(0.0, est.value - est.expanded);
  });
  if (muK.clamped_pressure) notes.push(DATA.texts.notes.clamped_pressure);
  if (muK.clamped_temperature) notes.push(DATA.texts.notes.clamped_temperature);
  if (sw[1]) notes.push(DATA.texts.notes.clamped_speed);
  var pressures = kPoints.map(function (q) { return q.pressure_kPa; });
  return {
    pin: pair.pin,
    disc: pair.disc,
    pressure_kPa: p,
    temperature_C: t,
    mu_k: muK,
    mu_s: muS,
    pressure_range_kPa: [Math.min.apply(null, pressures), Math.max.apply(null, pressures)],
    temperatures_C: sortedUnique(kPoints.map(function (q) { return q.temperature_C; })
      .filter(finite)),
    notes: notes,
    speed_mm_s: v === null ? speeds[0].speed_mm_s : v,
    speeds_mm_s: speeds.map(function (x) { return x.speed_mm_s; }),
    clamped: muK.clamped_pressure || muK.clamped_temperature || sw[1],
    pair: index,
  };
}

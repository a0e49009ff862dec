/* tribopipe query, redone: the interpolation of tribopipe/query.py on its own points. */

function QueryError(message) { this.name = "QueryError"; this.message = message; }
QueryError.prototype = Object.create(Error.prototype);

function finite(v) { return typeof v === "number" && Number.isFinite(v); }

function sortedUnique(values) {
  return Array.from(new Set(values)).sort(function (a, b) { return a - b; });
}

/* query._bracket: [[index, weight], ...] into sorted unique xs for x, and clamped. */
function bracket(xs, x) {
  var n = xs.length;
  if (n === 1) return [[[0, 1.0]], x !== xs[0]];
  if (x <= xs[0]) return [[[0, 1.0]], x < xs[0]];
  if (x >= xs[n - 1]) return [[[n - 1, 1.0]], x > xs[n - 1]];
  var hi = 0;
  while (hi < n && xs[hi] <= x) hi += 1; // numpy searchsorted(side="right")
  var lo = hi - 1;
  if (x === xs[lo]) return [[[lo, 1.0]], false];
  var wHi = (x - xs[lo]) / (xs[hi] - xs[lo]);
  return [[[lo, 1.0 - wHi], [hi, wHi]], false];
}

/* query.interpolation_weights: [weights, clampedPressure, clampedTemperature]. */
function interpolationWeights(ps, ts, p, t) {
  var n = ps.length;
  var weights = new Array(n).fill(0);
  var all = [];
  for (var i = 0; i < n; i += 1) all.push(i);
  var sets = [[all, 1.0]];
  var clampedT = false;
  var known = ts.filter(finite);
  if (known.length) {
    var temps = sortedUnique(known);
    var tBrackets;
    if (t === null) {
      if (temps.length > 1) {
        throw new QueryError("temperature needed: this pair is measured at " +
          temps.map(function (v) { return pyG(v); }).join(", ") + " °C");
      }
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
  sets.forEach(function (set) {
    var idx = set[0].slice().sort(function (a, b) { return ps[a] - ps[b]; });
    var pb = bracket(idx.map(function (k) { return ps[k]; }), p);
    clampedP = clampedP || pb[1];
    pb[0].forEach(function (pw) { weights[idx[pw[0]]] += set[1] * pw[1]; });
  });
  return [weights, clampedP, clampedT];
}

/* query._estimate over a pair's points (each {pressure_kPa, temperature_C, mean, half, u, n}). */
function estimate(points, p, t) {
  var w = interpolationWeights(
    points.map(function (q) { return q.pressure_kPa; }),
    points.map(function (q) { return q.temperature_C === null ? NaN : q.temperature_C; }),
    p, t);
  var value = 0;
  var unc = 0;
  var uncKnown = true;
  var uComb = 0;
  var uKnown = true;
  var used = [];
  points.forEach(function (q, i) {
    if (!(w[0][i] > 0)) return;
    value += w[0][i] * q.mean;
    if (finite(q.half)) unc += w[0][i] * q.half; else uncKnown = false;
    if (finite(q.u)) uComb += w[0][i] * q.u; else uKnown = false;
    used.push({
      pressure_kPa: q.pressure_kPa,
      temperature_C: finite(q.temperature_C) ? q.temperature_C : null,
      mean: q.mean,
      ci95_half_width: finite(q.half) ? q.half : null,
      n: q.n,
      weight: w[0][i],
      u: finite(q.u) ? q.u : null,
      run_ids: q.run_ids,
    });
  });
  return {
    value: value,
    uncertainty: uncKnown ? unc : null,
    used: used,
    clamped_pressure: w[1],
    clamped_temperature: w[2],
    u_combined: uKnown ? uComb : null,
  };
}

function key(name) { return String(name).trim().toLowerCase(); }

function findPair(pin, disc) {
  var kp = key(pin);
  var kd = key(disc);
  for (var i = 0; i < PAIRS.length; i += 1) {
    if (key(PAIRS[i].pin) === kp && key(PAIRS[i].disc) === kd) return i;
  }
  return -1;
}

/* query.query: mu_K (and mu_S) of a pair at a pressure [kPa] and temperature [°C] (or
   null); the result has the fields of QueryResult.to_dict(). Throws a QueryError. */
function query(pin, disc, p, t) {
  if (t === undefined) t = null;
  if (typeof p !== "number" || !Number.isFinite(p) || p < 0) {
    throw new QueryError("contact pressure must be a finite number >= 0 kPa, got " + pyRepr(Number(p)));
  }
  if (t !== null && (typeof t !== "number" || !Number.isFinite(t))) {
    throw new QueryError("temperature must be a finite number in °C, got " + pyRepr(Number(t)));
  }
  var index = findPair(pin, disc);
  if (index < 0) {
    throw new QueryError("no groups for pin " + JSON.stringify(String(pin)) + " on disc " +
      JSON.stringify(String(disc)) + " in this map");
  }
  var pair = PAIRS[index];
  var notes = [];
  if (pair.left_out) notes.push(pair.left_out + " group(s) without a temperature were left out");
  var muK = estimate(pair.mu_k_points, p, t);
  var muS = pair.mu_s_points.length ? estimate(pair.mu_s_points, p, t) : null;
  if (muS === null) notes.push("mu_s unknown: no group of this pair holds a static coefficient");
  if (muK.uncertainty === null) notes.push("uncertainty unknown: a group used has fewer than 2 runs");
  if (muK.clamped_pressure) {
    notes.push("pressure outside the range measured (at a temperature used): edge value held");
  }
  if (muK.clamped_temperature) notes.push("temperature outside the measured range: edge value held");
  var pressures = pair.mu_k_points.map(function (q) { return q.pressure_kPa; });
  return {
    pin: pair.pin,
    disc: pair.disc,
    pressure_kPa: p,
    temperature_C: t,
    mu_k: muK,
    mu_s: muS,
    pressure_range_kPa: [Math.min.apply(null, pressures), Math.max.apply(null, pressures)],
    temperatures_C: sortedUnique(pair.mu_k_points.map(function (q) { return q.temperature_C; })
      .filter(finite)),
    notes: notes,
    clamped: muK.clamped_pressure || muK.clamped_temperature,
    pair: index,
  };
}

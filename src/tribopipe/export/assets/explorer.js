/* tribopipe friction-map explorer: plain JavaScript and SVG, no library, no network.
 *
 * The map's data are the JSON document in #explorer-data (see tribopipe/export/explorer.py).
 * mu_K and mu_S at a condition are interpolated exactly as `tribopipe query` does
 * (tribopipe/query.py): temperature first, then pressure, linear between the measured
 * group means, held at the ends and said so; the uncertainty is the same weighted sum of
 * the groups' 95 % CI half-widths. Numbers are printed the way Python prints them.
 * Text from the data reaches the page through textContent and createElement only.
 */
(function () {
  "use strict";

  var root = document.getElementById("tpx");
  var dataElement = document.getElementById("explorer-data");
  if (!root || !dataElement) return;
  var DATA = JSON.parse(dataElement.textContent);
  var PAIRS = DATA.pairs;
  var GROUPS = DATA.groups;
  var SVG_NS = "http://www.w3.org/2000/svg";
  var COLOURS = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#7f7f7f"];

  // ------------------------------------------------------------------ numbers as Python prints them

  /* Exact decimal digits of |x| (finite): {digits, exp} with x = 0.d1d2... * 10^(exp+1),
     i.e. exp is the power of ten of the first significant digit; digits "" for zero. */
  function decimal(x) {
    var a = Math.abs(x);
    if (a === 0) return { digits: "", exp: 0 };
    if (a >= 1e21 || a < 1e-30) {
      // outside what toFixed writes exactly: 17 significant digits are enough to round from
      var m = a.toExponential(16).split("e");
      return { digits: m[0].replace(".", "").replace(/0+$/, ""), exp: parseInt(m[1], 10) };
    }
    var parts = a.toFixed(100).split("."); // exact: ECMAScript's toFixed is correctly rounded
    var all = parts[0] + parts[1];
    var lead = all.search(/[1-9]/);
    return { digits: all.slice(lead).replace(/0+$/, ""), exp: parts[0].length - lead - 1 };
  }

  /* The first `keep` digits of `digits`, rounded half-to-even on an exact tie (Python's
     rule); returns [digits, carried] where carried means the result gained a digit. */
  function roundDigits(digits, keep) {
    if (keep < 0) return ["", false];
    if (digits.length <= keep) return [digits + "0".repeat(keep - digits.length), false];
    var head = digits.slice(0, keep);
    var next = digits.charCodeAt(keep) - 48;
    var up;
    if (next !== 5) up = next > 5;
    else if (/[1-9]/.test(digits.slice(keep + 1))) up = true;
    else up = keep > 0 && (head.charCodeAt(keep - 1) - 48) % 2 === 1;
    if (!up) return [head, false];
    var d = head.split("");
    var i = d.length - 1;
    while (i >= 0 && d[i] === "9") { d[i] = "0"; i -= 1; }
    if (i < 0) return ["1" + d.join(""), true];
    d[i] = String.fromCharCode(d[i].charCodeAt(0) + 1);
    return [d.join(""), false];
  }

  function special(x) {
    if (Number.isNaN(x)) return "nan";
    return x > 0 ? "inf" : "-inf";
  }

  function sign(x) { return x < 0 || Object.is(x, -0) ? "-" : ""; }

  /* Python's format(x, ".<dec>f"). */
  function pyFixed(x, dec) {
    if (!Number.isFinite(x)) return special(x);
    var d = decimal(x);
    var n = d.digits === "" ? "0" : roundDigits(d.digits, d.exp + 1 + dec)[0];
    n = (n === "" ? "0" : n).replace(/^0+(?=\d)/, "");
    if (n.length < dec + 1) n = "0".repeat(dec + 1 - n.length) + n;
    var body = dec > 0 ? n.slice(0, n.length - dec) + "." + n.slice(n.length - dec) : n;
    return sign(x) + body;
  }

  function expText(e) { return "e" + (e < 0 ? "-" : "+") + String(Math.abs(e)).padStart(2, "0"); }

  /* Python's format(x, ".<prec>g") (default precision 6). */
  function pyG(x, prec) {
    if (prec === undefined) prec = 6;
    if (prec === 0) prec = 1;
    if (!Number.isFinite(x)) return special(x);
    var d = decimal(x);
    if (d.digits === "") return sign(x) + "0";
    var r = roundDigits(d.digits, prec);
    var e = r[1] ? d.exp + 1 : d.exp;
    var digits = r[0].slice(0, prec);
    var body;
    if (e >= -4 && e < prec) {
      var intPart, frac;
      if (e >= 0) { intPart = digits.slice(0, e + 1); frac = digits.slice(e + 1); }
      else { intPart = "0"; frac = "0".repeat(-e - 1) + digits; }
      frac = frac.replace(/0+$/, "");
      body = frac ? intPart + "." + frac : intPart;
    } else {
      var tail = digits.slice(1).replace(/0+$/, "");
      body = digits[0] + (tail ? "." + tail : "") + expText(e);
    }
    return sign(x) + body;
  }

  /* Python's repr(float(x)): the shortest text that reads back as x. */
  function pyRepr(x) {
    if (!Number.isFinite(x)) return special(x);
    if (x === 0) return sign(x) + "0.0";
    var m = Math.abs(x).toExponential().split("e"); // shortest round-trip digits
    var digits = m[0].replace(".", "");
    var e = parseInt(m[1], 10);
    var body;
    if (e >= -4 && e < 16) {
      if (e >= 0) {
        var intPart = (digits + "0".repeat(Math.max(0, e + 1 - digits.length))).slice(0, e + 1);
        body = intPart + "." + (digits.slice(e + 1) || "0");
      } else {
        body = "0." + "0".repeat(-e - 1) + digits;
      }
    } else {
      body = digits[0] + (digits.length > 1 ? "." + digits.slice(1) : "") + expText(e);
    }
    return sign(x) + body;
  }

  function f3(x) { return x === null || x === undefined ? "" : pyFixed(x, 3); }
  function g6(x) { return x === null || x === undefined ? "" : pyG(x, 6); }

  // ------------------------------------------------------------------ query, as tribopipe/query.py

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

  /* query._estimate over a pair's points (each {pressure_kPa, temperature_C, mean, half, n}). */
  function estimate(points, p, t) {
    var w = interpolationWeights(
      points.map(function (q) { return q.pressure_kPa; }),
      points.map(function (q) { return q.temperature_C === null ? NaN : q.temperature_C; }),
      p, t);
    var value = 0;
    var unc = 0;
    var uncKnown = true;
    var used = [];
    points.forEach(function (q, i) {
      if (!(w[0][i] > 0)) return;
      value += w[0][i] * q.mean;
      if (finite(q.half)) unc += w[0][i] * q.half; else uncKnown = false;
      used.push({
        pressure_kPa: q.pressure_kPa,
        temperature_C: finite(q.temperature_C) ? q.temperature_C : null,
        mean: q.mean,
        ci95_half_width: finite(q.half) ? q.half : null,
        n: q.n,
        weight: w[0][i],
        run_ids: q.run_ids,
      });
    });
    return {
      value: value,
      uncertainty: uncKnown ? unc : null,
      used: used,
      clamped_pressure: w[1],
      clamped_temperature: w[2],
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

  // ------------------------------------------------------------------ export text

  /* simulators._one_line: no name may end a comment line. */
  function oneLine(text) { return text.replace(/[\u0000-\u001f\u007f-\u009f\u2028\u2029]/g, " "); }

  function abaqusName(pin, disc) {
    var text = (pin + "__ON__" + disc).replace(/[^A-Za-z0-9]+/g, "_").replace(/^_+|_+$/g, "");
    return ("FRIC_" + text.toUpperCase()).slice(0, 80);
  }

  function num(x) { return pyG(x, 10); } // simulators._num

  function usedText(res) {
    return res.mu_k.used.map(function (u) {
      return pyG(u.pressure_kPa) + " kPa" + (u.temperature_C === null ? "" : "/" + pyG(u.temperature_C) + " C") +
        " (w=" + pyG(u.weight, 3) + ")";
    }).join(", ");
  }

  /* simulators.condition_snippet(res, fmt, source=map): a constant mu_K for ABAQUS or Ansys. */
  function conditionSnippet(res, fmt) {
    var c = fmt === "abaqus" ? "**" : "!";
    var what = (fmt === "abaqus" ? "ABAQUS friction input" : "Ansys MAPDL friction input") +
      " at one condition (kinetic coefficient mu_k, held constant)";
    var t = res.temperature_C === null ? "unknown" : pyG(res.temperature_C) + " C";
    var lines = [
      c + " " + what,
      c + " written by tribopipe " + DATA.tribopipe_version + " from the friction map" +
        (DATA.source ? " " + DATA.source : ""),
      c + " values: group means of the runs (repeats) at each nominal condition",
      c + " pair: pin " + res.pin + " on disc " + res.disc,
      c + " condition: contact pressure " + pyG(res.pressure_kPa) + " kPa, temperature " + t,
      c + " mu_k = " + num(res.mu_k.value) +
        (res.mu_k.uncertainty === null ? "" : " +/- " + num(res.mu_k.uncertainty) + " (95 % CI)"),
      c + " mu_s = " + (res.mu_s === null ? "unknown (not in the map)" : num(res.mu_s.value)),
      c + " from measured groups: " + usedText(res),
    ];
    if (res.clamped) lines.push(c + " outside the measured range: edge value held constant");
    lines.push(c + " a constant coefficient: the solver uses it at every pressure and temperature; " +
      "for the dependence export the pair's table (tribopipe export " + fmt + " --pin PIN --disc DISC)");
    lines = lines.map(oneLine);
    var mu = num(res.mu_k.value);
    if (fmt === "abaqus") {
      lines.push("*SURFACE INTERACTION, NAME=" + abaqusName(res.pin, res.disc), "*FRICTION", mu);
    } else {
      lines.push(oneLine("! material 1: pin " + res.pin + " on disc " + res.disc),
        "TB,FRIC,1,,,ISO", "TBDATA,1," + mu);
    }
    return lines.join("\n") + "\n";
  }

  var CSV_COLUMNS = ["pin", "disc", "pressure_kPa", "temperature_C", "mu_k", "mu_k_ci95_half_width",
    "mu_s", "mu_s_ci95_half_width", "clamped_pressure", "clamped_temperature", "measured_groups",
    "notes", "map", "tribopipe_version"];

  /* One CSV cell: numbers at full precision, text quoted where needed; text that a
     spreadsheet would run as a formula (= + - @ first) is prefixed with an apostrophe. */
  function csvCell(v) {
    if (v === null || v === undefined) return "";
    if (typeof v === "number") return pyRepr(v);
    if (typeof v === "boolean") return v ? "True" : "False";
    var s = String(v);
    if (/^[=+\-@\t\r]/.test(s)) s = "'" + s;
    return /[",\r\n]|^\s|\s$/.test(s) ? '"' + s.replace(/"/g, '""') + '"' : s;
  }

  function csvText(res) {
    var row = [res.pin, res.disc, res.pressure_kPa, res.temperature_C, res.mu_k.value,
      res.mu_k.uncertainty, res.mu_s ? res.mu_s.value : null, res.mu_s ? res.mu_s.uncertainty : null,
      res.mu_k.clamped_pressure, res.mu_k.clamped_temperature, usedText(res), res.notes.join("; "),
      DATA.source, DATA.tribopipe_version];
    return CSV_COLUMNS.join(",") + "\r\n" + row.map(csvCell).join(",") + "\r\n";
  }

  var EXPORTS = {
    csv: { ext: "csv", mime: "text/csv", make: csvText },
    abaqus: { ext: "inp", mime: "text/plain", make: function (r) { return conditionSnippet(r, "abaqus"); } },
    ansys: { ext: "mac", mime: "text/plain", make: function (r) { return conditionSnippet(r, "ansys"); } },
  };

  function slug(text) {
    return key(text).replace(/[^a-z0-9]+/g, "-").replace(/^-+|-+$/g, "").slice(0, 40) || "x";
  }

  function fileName(res, fmt) {
    var t = res.temperature_C === null ? "" : "_" + pyG(res.temperature_C) + "C";
    return "tribopipe_" + slug(res.pin) + "_" + slug(res.disc) + "_" + pyG(res.pressure_kPa) + "kPa" +
      t + "." + EXPORTS[fmt].ext;
  }

  // ------------------------------------------------------------------ DOM helpers

  function $(id) { return document.getElementById(id); }

  function make(tag, text, cls) {
    var e = document.createElement(tag);
    if (text !== undefined && text !== null) e.textContent = String(text);
    if (cls) e.className = cls;
    return e;
  }

  function svg(tag, attrs, parent) {
    var e = document.createElementNS(SVG_NS, tag);
    Object.keys(attrs || {}).forEach(function (k) { e.setAttribute(k, String(attrs[k])); });
    if (parent) parent.appendChild(e);
    return e;
  }

  function svgText(parent, x, y, text, attrs) {
    var e = svg("text", Object.assign({ x: x, y: y }, attrs || {}), parent);
    e.textContent = String(text);
    return e;
  }

  function tip(node, text) { svg("title", {}, node).textContent = String(text); }

  function clear(node) { while (node.firstChild) node.removeChild(node.firstChild); }

  /* Text of a number input: the number, null when empty, NaN when not a number. */
  function inputNumber(input) {
    if (input.validity && input.validity.badInput) return NaN;
    var s = input.value.trim();
    return s === "" ? null : Number(s);
  }

  // ------------------------------------------------------------------ selection

  var pinSelect = $("pin");
  var discSelect = $("disc");
  var tInput = $("temperature");
  var pInput = $("pressure");
  var state = { pair: 0, result: null, sortKey: null, sortDir: 1 };

  var PINS = []; // [{key, name, pairs: [index...]}]
  PAIRS.forEach(function (pair, i) {
    var k = key(pair.pin);
    var pin = PINS.find(function (q) { return q.key === k; });
    if (!pin) { pin = { key: k, name: pair.pin, pairs: [] }; PINS.push(pin); }
    pin.pairs.push(i);
  });

  function pinOf(pairIndex) {
    var k = key(PAIRS[pairIndex].pin);
    return PINS.findIndex(function (q) { return q.key === k; });
  }

  function fillSelect(select, items) {
    clear(select);
    items.forEach(function (it) {
      var o = make("option", it.text);
      o.value = String(it.value);
      select.appendChild(o);
    });
  }

  function pairTemperatures(pair) {
    return sortedUnique(pair.mu_k_points.map(function (q) { return q.temperature_C; }).filter(finite));
  }

  function pairPressures(pair, t) {
    return sortedUnique(pair.mu_k_points.filter(function (q) {
      return t === undefined || q.temperature_C === t;
    }).map(function (q) { return q.pressure_kPa; }));
  }

  function fillDefaults(pair) {
    var temps = pairTemperatures(pair);
    if (tInput.value.trim() === "" && !tInput.validity.badInput && temps.length) {
      tInput.value = String(temps[0]);
    }
    if (pInput.value.trim() === "" && !pInput.validity.badInput) {
      var t = inputNumber(tInput);
      var at = pairPressures(pair, temps.indexOf(t) >= 0 ? t : undefined);
      pInput.value = String(at[0]);
    }
  }

  function chip(text, active, onClick) {
    var b = make("button", text, "tpx-chip" + (active ? " tpx-on" : ""));
    b.type = "button";
    b.addEventListener("click", onClick);
    return b;
  }

  function renderMeasured(pair) {
    var box = $("tpx-measured");
    clear(box);
    var temps = pairTemperatures(pair);
    var t = inputNumber(tInput);
    box.appendChild(document.createTextNode("measured temperatures: "));
    if (!temps.length) box.appendChild(document.createTextNode("unknown "));
    temps.forEach(function (v) {
      box.appendChild(chip(pyG(v) + " °C", v === t, function () { tInput.value = String(v); update(false); }));
    });
    var p = inputNumber(pInput);
    box.appendChild(document.createTextNode(" · pressures: "));
    pairPressures(pair).forEach(function (v) {
      box.appendChild(chip(pyG(v) + " kPa", v === p, function () { pInput.value = String(v); update(false); }));
    });
    var tl = $("tpx-temperature-list");
    var pl = $("tpx-pressure-list");
    clear(tl);
    clear(pl);
    temps.forEach(function (v) { var o = make("option"); o.value = String(v); tl.appendChild(o); });
    pairPressures(pair).forEach(function (v) { var o = make("option"); o.value = String(v); pl.appendChild(o); });
  }

  function setPin(pinIndex, discKey) {
    var pin = PINS[pinIndex];
    pinSelect.value = String(pinIndex);
    fillSelect(discSelect, pin.pairs.map(function (i) { return { value: i, text: PAIRS[i].disc }; }));
    var chosen = pin.pairs.find(function (i) { return key(PAIRS[i].disc) === discKey; });
    state.pair = chosen === undefined ? pin.pairs[0] : chosen;
    discSelect.value = String(state.pair);
  }

  function note(text) {
    var e = $("tpx-selection-note");
    e.textContent = text || "";
    e.hidden = !text;
  }

  function writeUrl() {
    var q = new URLSearchParams();
    q.set("pin", PAIRS[state.pair].pin);
    q.set("disc", PAIRS[state.pair].disc);
    if (pInput.value.trim() !== "") q.set("pressure", pInput.value.trim());
    if (tInput.value.trim() !== "") q.set("temperature", tInput.value.trim());
    var url = location.pathname + "?" + q.toString() + location.hash;
    try {
      history.replaceState(history.state, "", url);
    } catch (e) {
      // a host that refuses (a sandboxed frame): the page works, the link does not follow
    }
  }

  function readUrl() {
    var q = new URLSearchParams(location.search);
    var notes = [];
    var pinIndex = 0;
    if (q.has("pin")) {
      var k = key(q.get("pin"));
      var found = PINS.findIndex(function (p) { return p.key === k; });
      if (found < 0) notes.push("the link's pin “" + q.get("pin") + "” is not in this map");
      else pinIndex = found;
    }
    var discKey = q.has("disc") ? key(q.get("disc")) : null;
    setPin(pinIndex, discKey);
    if (discKey !== null && key(PAIRS[state.pair].disc) !== discKey) {
      notes.push("the link's disc “" + q.get("disc") + "” is not measured with " + PINS[pinIndex].name);
    }
    [["temperature", tInput], ["pressure", pInput]].forEach(function (f) {
      if (!q.has(f[0])) return;
      var text = q.get(f[0]).trim();
      if (text !== "" && Number.isFinite(Number(text))) f[1].value = text;
      else notes.push("the link's " + f[0] + " “" + q.get(f[0]) + "” is not a number");
    });
    note(notes.join("; "));
  }

  // ------------------------------------------------------------------ the result

  function renderResult(res, error) {
    var muK = $("mu-k");
    var muS = $("mu-s");
    var clamped = $("clamped");
    var err = $("tpx-error");
    var notes = $("tpx-notes");
    var body = $("tpx-used-points").tBodies[0];
    clear(notes);
    clear(body);
    err.textContent = error || "";
    err.hidden = !error;
    if (!res) {
      muK.textContent = "–";
      muS.textContent = "–";
      clamped.textContent = "–";
      clamped.className = "";
      ["value", "uncertainty", "clampedPressure", "clampedTemperature"].forEach(function (k) {
        delete muK.dataset[k];
      });
      return;
    }
    muK.textContent = f3(res.mu_k.value) +
      (res.mu_k.uncertainty === null ? "" : " ± " + f3(res.mu_k.uncertainty));
    muK.dataset.value = pyRepr(res.mu_k.value);
    muK.dataset.uncertainty = res.mu_k.uncertainty === null ? "" : pyRepr(res.mu_k.uncertainty);
    muK.dataset.clampedPressure = String(res.mu_k.clamped_pressure);
    muK.dataset.clampedTemperature = String(res.mu_k.clamped_temperature);
    muS.textContent = res.mu_s === null ? "unknown (no group of this pair holds it)" :
      f3(res.mu_s.value) + (res.mu_s.uncertainty === null ? "" : " ± " + f3(res.mu_s.uncertainty));
    var what = [];
    if (res.mu_k.clamped_pressure) what.push("pressure");
    if (res.mu_k.clamped_temperature) what.push("temperature");
    clamped.textContent = res.clamped ?
      "yes: " + what.join(" and ") + " outside the measured range, edge value held" : "no";
    clamped.className = res.clamped ? "tpx-clamped" : "";
    res.notes.forEach(function (n) { notes.appendChild(make("li", n)); });
    var runs = {};
    PAIRS[res.pair].runs.forEach(function (r) { runs[r.id] = r; });
    res.mu_k.used.forEach(function (u) {
      var tr = make("tr");
      var repeats = u.run_ids.map(function (id) { return runs[id]; }).filter(Boolean)
        .map(function (r) { return f3(r.mu_k); }).join(", ");
      [g6(u.pressure_kPa), u.temperature_C === null ? "?" : g6(u.temperature_C), f3(u.mean),
        u.ci95_half_width === null ? "–" : f3(u.ci95_half_width), String(u.n), f3(u.weight)]
        .forEach(function (v) { tr.appendChild(make("td", v)); });
      tr.appendChild(make("td", repeats, "tpx-t"));
      body.appendChild(tr);
    });
  }

  function renderExport() {
    var fmt = $("tpx-export-format").value;
    $("tpx-export-text").value = state.result ? EXPORTS[fmt].make(state.result) : "";
    $("tpx-copy").disabled = !state.result;
    $("tpx-download").disabled = !state.result;
    $("tpx-export-status").textContent = "";
  }

  function copyText() {
    var text = $("tpx-export-text").value;
    var status = $("tpx-export-status");
    function fallback() {
      var area = $("tpx-export-text");
      area.focus();
      area.select();
      var ok = false;
      try { ok = document.execCommand("copy"); } catch (e) { ok = false; }
      status.textContent = ok ? "copied" : "select the text below and copy it (Ctrl+C)";
    }
    if (navigator.clipboard && window.isSecureContext) {
      navigator.clipboard.writeText(text).then(function () { status.textContent = "copied"; }, fallback);
    } else {
      fallback();
    }
  }

  function download() {
    if (!state.result) return;
    var fmt = $("tpx-export-format").value;
    var blob = new Blob([$("tpx-export-text").value], { type: EXPORTS[fmt].mime + ";charset=utf-8" });
    var url = URL.createObjectURL(blob);
    var a = make("a");
    a.href = url;
    a.download = fileName(state.result, fmt);
    document.body.appendChild(a);
    a.click();
    a.remove();
    setTimeout(function () { URL.revokeObjectURL(url); }, 2000);
    $("tpx-export-status").textContent = "downloaded " + a.download;
  }

  // ------------------------------------------------------------------ plots (SVG)

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
      ys.push(res.mu_k.value + (res.mu_k.uncertainty || 0));
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
          (r.flags.length ? " (" + r.flags.join(", ") + ")" : ""));
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
      if (res.mu_k.uncertainty !== null) {
        svg("path", { d: "M" + px + "," + plot.y(res.mu_k.value - res.mu_k.uncertainty) + "V" +
          plot.y(res.mu_k.value + res.mu_k.uncertainty), stroke: "#000", "stroke-width": 1.5 }, plot.s);
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

  // ------------------------------------------------------------------ the group table

  function qcText(g) {
    var out = [];
    if (g.range_exceeds_r) out.push("range > r");
    if (g.qc_flagged) out.push("flagged run");
    return out.join(", ");
  }

  var COLUMNS = [
    { key: "pin", label: "pin", text: true },
    { key: "disc", label: "disc", text: true },
    { key: "normal_force_N", label: "F [N]", fmt: g6 },
    { key: "pressure_kPa", label: "p [kPa]", fmt: function (v) { return v === null ? "" : pyG(v, 4); } },
    { key: "temperature_C", label: "T [°C]", fmt: g6 },
    { key: "mu_k_n", label: "n", fmt: String },
    { key: "mu_k_mean", label: "μ_K mean", fmt: f3 },
    { key: "mu_k_std", label: "μ_K SD", fmt: f3 },
    { key: "mu_k_ci95_low", label: "μ_K CI low", fmt: f3 },
    { key: "mu_k_ci95_high", label: "μ_K CI high", fmt: f3 },
    { key: "mu_k_cv", label: "μ_K CV", fmt: f3 },
    { key: "mu_s_n", label: "μ_S n", fmt: String },
    { key: "mu_s_mean", label: "μ_S mean", fmt: f3 },
    { key: "qc", label: "QC", text: true, get: qcText },
  ];

  function cellValue(col, g) { return col.get ? col.get(g) : g[col.key]; }

  function renderTableHead() {
    var head = $("tpx-group-table").tHead;
    clear(head);
    var tr = make("tr");
    COLUMNS.forEach(function (col) {
      var th = make("th", col.label, col.text ? "tpx-t" : "");
      th.dataset.key = col.key;
      th.tabIndex = 0;
      th.setAttribute("aria-sort", state.sortKey === col.key ? (state.sortDir > 0 ? "ascending" : "descending") : "none");
      var sortBy = function () {
        state.sortDir = state.sortKey === col.key ? -state.sortDir : 1;
        state.sortKey = col.key;
        renderTable();
      };
      th.addEventListener("click", sortBy);
      th.addEventListener("keydown", function (ev) { if (ev.key === "Enter") sortBy(); });
      tr.appendChild(th);
    });
    head.appendChild(tr);
  }

  function compare(col, a, b, dir) {
    var va = cellValue(col, a);
    var vb = cellValue(col, b);
    var ea = va === null || va === undefined || va === "";
    var eb = vb === null || vb === undefined || vb === "";
    if (ea || eb) return ea === eb ? 0 : ea ? 1 : -1; // missing values last either way
    if (col.text) return dir * String(va).localeCompare(String(vb));
    return dir * (va - vb);
  }

  function renderTable() {
    renderTableHead();
    var body = $("tpx-group-table").tBodies[0];
    clear(body);
    var scope = $("tpx-group-scope").value;
    var tokens = $("tpx-group-filter").value.toLowerCase().split(/\s+/).filter(Boolean);
    var pinKey = key(PAIRS[state.pair].pin);
    var used = {};
    if (state.result) {
      state.result.mu_k.used.forEach(function (u) { used[u.pressure_kPa + "|" + u.temperature_C] = true; });
    }
    var rows = GROUPS.map(function (g, i) { return [g, i]; }).filter(function (gi) {
      var g = gi[0];
      if (scope === "pin" && key(g.pin) !== pinKey) return false;
      if (scope === "pair" && g.pair !== state.pair) return false;
      var hay = [g.pin, g.disc, qcText(g), g6(g.pressure_kPa), g6(g.temperature_C) + " °C"].join(" ").toLowerCase();
      return tokens.every(function (t) { return hay.indexOf(t) >= 0; });
    });
    var col = COLUMNS.find(function (c) { return c.key === state.sortKey; });
    if (col) {
      rows.sort(function (a, b) { return compare(col, a[0], b[0], state.sortDir) || a[1] - b[1]; });
    }
    rows.forEach(function (gi) {
      var g = gi[0];
      var tr = make("tr");
      var isUsed = state.result && g.pair === state.pair &&
        used[g.pressure_kPa + "|" + (finite(g.temperature_C) ? g.temperature_C : null)];
      tr.className = (isUsed ? "tpx-used " : "") + (qcText(g) ? "tpx-flag" : "");
      tr.tabIndex = 0;
      tr.dataset.group = String(gi[1]);
      COLUMNS.forEach(function (c) {
        var v = cellValue(c, g);
        var td = make("td", c.fmt ? (v === null || v === undefined ? "" : c.fmt(v)) : v,
          c.text ? "tpx-t" : "");
        if (c.key === "qc") td.className += " tpx-qc";
        tr.appendChild(td);
      });
      var choose = function () {
        var p = PAIRS[g.pair];
        setPin(pinOf(g.pair), key(p.disc));
        state.pair = g.pair;
        discSelect.value = String(g.pair);
        tInput.value = finite(g.temperature_C) ? String(g.temperature_C) : "";
        pInput.value = String(g.pressure_kPa);
        update(false);
      };
      tr.addEventListener("click", choose);
      tr.addEventListener("keydown", function (ev) { if (ev.key === "Enter") choose(); });
      body.appendChild(tr);
    });
    $("tpx-group-count").textContent = rows.length + " of " + GROUPS.length + " groups";
  }

  // ------------------------------------------------------------------ wiring

  function compute() {
    var p = inputNumber(pInput);
    var t = inputNumber(tInput);
    if (p === null) return [null, "enter a contact pressure [kPa]"];
    if (Number.isNaN(p)) return [null, "the contact pressure is not a number"];
    if (Number.isNaN(t)) return [null, "the temperature is not a number"];
    var pair = PAIRS[state.pair];
    try {
      return [query(pair.pin, pair.disc, p, t), null];
    } catch (e) {
      if (e instanceof QueryError) return [null, e.message];
      throw e;
    }
  }

  /* Recompute and redraw everything; `withDefaults` fills an empty temperature and
     pressure with measured ones (on load and when the pair changes, not while typing, so
     a cleared field is answered as query answers it). */
  function update(withDefaults) {
    var pair = PAIRS[state.pair];
    if (withDefaults === true) fillDefaults(pair);
    var out = compute();
    state.result = out[0];
    renderMeasured(pair);
    renderResult(out[0], out[1]);
    renderExport();
    drawPairPlot(out[0]);
    drawOverview();
    renderTable();
    writeUrl();
  }

  fillSelect(pinSelect, PINS.map(function (p, i) { return { value: i, text: p.name }; }));
  pinSelect.addEventListener("change", function () {
    setPin(Number(pinSelect.value), key(PAIRS[state.pair].disc));
    note("");
    update(true);
  });
  discSelect.addEventListener("change", function () {
    state.pair = Number(discSelect.value);
    note("");
    update(true);
  });
  [tInput, pInput].forEach(function (input) {
    input.addEventListener("input", function () { update(false); });
  });
  $("tpx-form").addEventListener("submit", function (ev) { ev.preventDefault(); });
  $("tpx-export-format").addEventListener("change", renderExport);
  $("tpx-copy").addEventListener("click", copyText);
  $("tpx-download").addEventListener("click", download);
  $("tpx-group-filter").addEventListener("input", renderTable);
  $("tpx-group-scope").addEventListener("change", renderTable);

  if (!PAIRS.length) {
    renderResult(null, "the map holds no pair with a finite μ_K");
    return;
  }
  readUrl();
  update(true);

  /* For scripts and tests: the page's own computation, and its current selection. */
  window.tribopipeExplorer = Object.freeze({
    data: DATA,
    query: query,
    result: function () { return state.result; },
    exportText: function (fmt, res) { return EXPORTS[fmt].make(res || state.result); },
    fileName: function (fmt) { return state.result ? fileName(state.result, fmt) : null; },
    format: { fixed: pyFixed, g: pyG, repr: pyRepr },
  });
})();

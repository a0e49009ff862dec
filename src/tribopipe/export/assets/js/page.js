/* The selection (controls and address), the result shown, and the wiring (last part). */

var pinSelect = $("pin");
var discSelect = $("disc");
var tInput = $("temperature");
var pInput = $("pressure");
var vSelect = $("speed");
/* `missing`: what the link asked for that the map does not hold (a pin, a disc, a pair):
   no μ is shown until the user chooses a pair. */
var state = { pair: 0, result: null, sortKey: null, sortDir: 1, missing: null, speed: 0 };

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
    setNumber(tInput, temps[0]);
  }
  if (pInput.value.trim() === "" && !pInput.validity.badInput) {
    var t = inputNumber(tInput);
    var at = pairPressures(pair, temps.indexOf(t) >= 0 ? t : undefined);
    setNumber(pInput, at[0]);
  }
}

/* The speed selector: shown for a pair measured at several sliding speeds; the chosen
   speed's points become the pair's points (plots, chips) and the query's speed. */
function pairSpeedList(pair) { return pair.speeds && pair.speeds.length > 1 ? pair.speeds : []; }

function renderSpeeds(pair) {
  var speeds = pairSpeedList(pair);
  $("tpx-speed-label").hidden = !speeds.length;
  if (!speeds.length) { clear(vSelect); return; }
  if (state.speed >= speeds.length) state.speed = 0;
  if (vSelect.options.length !== speeds.length) {
    fillSelect(vSelect, speeds.map(function (x, i) { return { value: i, text: pyG(x.speed_mm_s) }; }));
  }
  vSelect.value = String(state.speed);
  pair.mu_k_points = speeds[state.speed].mu_k_points;
  pair.mu_s_points = speeds[state.speed].mu_s_points;
}

function chosenSpeed(pair) {
  var speeds = pairSpeedList(pair);
  return speeds.length ? speeds[state.speed].speed_mm_s : null;
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
    box.appendChild(chip(pyG(v) + " °C", v === t, function () { setNumber(tInput, v); update(false); }));
  });
  var p = inputNumber(pInput);
  box.appendChild(document.createTextNode(" · pressures: "));
  pairPressures(pair).forEach(function (v) {
    box.appendChild(chip(pyG(v) + " kPa", v === p, function () { setNumber(pInput, v); update(false); }));
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
  if (state.missing) return;  // the address keeps what the link asked for
  var q = new URLSearchParams();
  q.set("pin", PAIRS[state.pair].pin);
  q.set("disc", PAIRS[state.pair].disc);
  if (urlText(pInput) !== "") q.set("pressure", urlText(pInput));
  if (urlText(tInput) !== "") q.set("temperature", urlText(tInput));
  var speed = chosenSpeed(PAIRS[state.pair]);
  if (speed !== null) q.set("speed", pyRepr(speed));
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
  var missing = [];
  var pinIndex = 0;
  if (q.has("pin")) {
    var k = key(q.get("pin"));
    var found = PINS.findIndex(function (p) { return p.key === k; });
    if (found < 0) missing.push("the link's pin “" + q.get("pin") + "” is not in this map");
    else pinIndex = found;
  }
  var discKey = q.has("disc") ? key(q.get("disc")) : null;
  setPin(pinIndex, discKey);
  if (!missing.length && discKey !== null && key(PAIRS[state.pair].disc) !== discKey) {
    var known = PAIRS.some(function (p) { return key(p.disc) === discKey; });
    missing.push("the link's disc “" + q.get("disc") + "” " + (known ?
      "is not measured with " + PINS[pinIndex].name : "is not in this map"));
  }
  var pair = PAIRS[state.pair];
  if (q.has("speed")) {
    var wanted = Number(q.get("speed"));
    var at = pairSpeedList(pair).findIndex(function (x) { return x.speed_mm_s === wanted; });
    if (at >= 0) state.speed = at;
    else notes.push("the link's speed “" + q.get("speed") + "” is not measured for this pair");
  }
  renderSpeeds(pair);
  [["temperature", tInput, pairTemperatures(pair)], ["pressure", pInput, pairPressures(pair)]]
    .forEach(function (f) {
      if (!q.has(f[0])) return;
      var text = q.get(f[0]).trim();
      var n = Number(text);
      if (text !== "" && Number.isFinite(n)) {
        // a measured value written to 4 significant digits (or in full) means that value:
        // it shows rounded and counts exact
        var measured = f[2].find(function (v) { return v === n || sig4(v) === text; });
        if (Number(pyG(n)) === n && measured === n) f[1].value = text;  // as typed
        else if (measured !== undefined) setNumber(f[1], measured);
        else if (Number(pyG(n)) === n) f[1].value = text;
        else setNumber(f[1], n);
      } else notes.push("the link's " + f[0] + " “" + q.get(f[0]) + "” is not a number");
    });
  state.missing = missing.length ? missing.join("; ") +
    ": no μ is shown; choose a pin and a disc above" : null;
  note(notes.concat(missing).join("; "));
}


// ---------------------------------------------------------------- the result

function renderResult(res, error) {
  var muK = $("mu-k");
  var muKu = $("mu-k-u");
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
    muKu.textContent = "–";
    delete muKu.dataset.u;
    muS.textContent = "–";
    clamped.textContent = "–";
    clamped.className = "";
    ["value", "uncertainty", "clampedPressure", "clampedTemperature"].forEach(function (k) {
      delete muK.dataset[k];
    });
    return;
  }
  muK.textContent = estimateText(res.mu_k);
  muK.dataset.value = pyRepr(res.mu_k.value);
  muK.dataset.uncertainty = res.mu_k.expanded === null ? "" : pyRepr(res.mu_k.expanded);
  // GUM combined standard uncertainty (k = 1) and the expanded U = 2u, beside the CI
  muKu.textContent = "interpolation u = " + pyG(res.mu_k.u_interpolation, 2) +
    (res.mu_k.budgets_known ? "" : "; some runs carry no budget of their own: their u is the stated estimate of the founding cell") +
    "; repeats' 95 % CI half-width " + (res.mu_k.uncertainty === null ? "unknown" : f3(res.mu_k.uncertainty));
  muKu.dataset.u = res.mu_k.u_combined === null ? "" : pyRepr(res.mu_k.u_combined);
  muK.dataset.clampedPressure = String(res.mu_k.clamped_pressure);
  muK.dataset.clampedTemperature = String(res.mu_k.clamped_temperature);
  muS.textContent = res.mu_s === null ? "unknown (no group of this pair holds it)" :
    estimateText(res.mu_s);
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
    [g6(u.pressure_kPa), u.temperature_C === null ? "?" : g6(u.temperature_C), f3(u.mean),
      u.ci95_half_width === null ? "–" : f3(u.ci95_half_width),
      u.u === null ? "–" : f3(u.u), String(u.n), f3(u.weight)]
      .forEach(function (v) { tr.appendChild(make("td", v)); });
    var cell = make("td", null, "tpx-t");
    // one line per repeat: its μ_K and the file and test it came from
    u.run_ids.map(function (id) { return runs[id]; }).filter(Boolean).forEach(function (r) {
      var from = runOrigin(r);
      cell.appendChild(make("div", f3(r.mu_k) + (r.review ? " (reviewed: " + r.review + ")" : "") +
        (from ? " — " + from : ""), "tpx-repeat"));
    });
    tr.appendChild(cell);
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


// ---------------------------------------------------------------- wiring

function compute() {
  if (state.missing) return [null, state.missing];
  var p = inputNumber(pInput);
  var t = inputNumber(tInput);
  if (p === null) return [null, "enter a contact pressure [kPa]"];
  if (Number.isNaN(p)) return [null, "the contact pressure is not a number"];
  if (Number.isNaN(t)) return [null, "the temperature is not a number"];
  var pair = PAIRS[state.pair];
  try {
    return [query(pair.pin, pair.disc, p, t, chosenSpeed(pair)), null];
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
  renderSpeeds(pair);
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
  state.speed = 0;
  clear(vSelect);
  state.missing = null;
  note("");
  update(true);
});
vSelect.addEventListener("change", function () {
  state.speed = Number(vSelect.value);
  update(false);
});
discSelect.addEventListener("change", function () {
  state.pair = Number(discSelect.value);
  state.speed = 0;
  clear(vSelect);
  state.missing = null;
  note("");
  update(true);
});
[tInput, pInput].forEach(function (input) {
  input.addEventListener("input", function () {
    delete input.dataset.shown;  // typed: the text is the value
    update(false);
  });
});
$("tpx-form").addEventListener("submit", function (ev) { ev.preventDefault(); });
$("tpx-export-format").addEventListener("change", renderExport);
$("tpx-copy").addEventListener("click", copyText);
$("tpx-download").addEventListener("click", download);
$("tpx-group-filter").addEventListener("input", renderTable);
$("tpx-group-scope").addEventListener("change", renderTable);
METHODS.forEach(function (m) { $("tpx-group-method").appendChild(make("option", m)); });
$("tpx-group-method-label").hidden = METHODS.length < 2;
$("tpx-group-method").addEventListener("change", renderTable);

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

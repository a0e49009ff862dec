/* The selection (controls and address), the result shown, and the wiring (last part). */

var pinSelect = $("pin");
var discSelect = $("disc");
var tInput = $("temperature");
var pInput = $("pressure");
var vSelect = $("speed");
var labSelect = $("lab");
var colourSelect = $("colour-by");
/* `missing`: what the link asked for that the map does not hold (a pin, a disc, a pair):
   no μ is shown until the user chooses a pair. `lab`: the lab shown (-1: every lab). */
var state = { pair: 0, result: null, sortKey: null, sortDir: 1, missing: null, speed: 0,
  lab: -1, colour: "temperature" };

var PINS = []; // [{key, name, pairs: [index...]}]
PAIRS.forEach(function (pair, i) {
  var k = pair.keys[0];
  var pin = PINS.find(function (q) { return q.key === k; });
  if (!pin) { pin = { key: k, name: pair.pin, pairs: [] }; PINS.push(pin); }
  pin.pairs.push(i);
});

function pinOf(pairIndex) {
  var k = PAIRS[pairIndex].keys[0];
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

/* The speed shown for a pair: its points, measured temperatures and pressures. */
function speedOf(pair) {
  if (state.speed >= pair.speeds.length) state.speed = 0;
  return pair.speeds[state.speed];
}

function fillDefaults(pair) {
  var at = speedOf(pair);
  if (tInput.value.trim() === "" && !tInput.validity.badInput && at.temperatures.length) {
    setNumber(tInput, at.temperatures[0].value, at.temperatures[0].text);
  }
  if (pInput.value.trim() === "" && !pInput.validity.badInput) {
    var t = inputNumber(tInput);
    var first = at.mu_k_points.filter(function (q) { return q.temperature_C === t; })
      .sort(function (a, b) { return a.pressure_kPa - b.pressure_kPa; })[0];
    var p = first ? { value: first.pressure_kPa, text: first.text.p } : at.pressures[0];
    setNumber(pInput, p.value, p.text);
  }
}

/* The speed selector: shown only for a pair measured at several sliding speeds. */
function renderSpeeds(pair) {
  var several = pair.speeds.length > 1;
  $("tpx-speed-label").hidden = !several;
  if (!several) { clear(vSelect); state.speed = 0; return; }
  speedOf(pair);
  if (vSelect.options.length !== pair.speeds.length || vSelect.dataset.pair !== String(state.pair)) {
    fillSelect(vSelect, pair.speeds.map(function (x, i) { return { value: i, text: x.text }; }));
    vSelect.dataset.pair = String(state.pair);
  }
  vSelect.value = String(state.speed);
}

function chosenSpeed(pair) {
  return pair.speeds.length > 1 ? speedOf(pair).speed_mm_s : null;
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
  var at = speedOf(pair);
  var t = inputNumber(tInput);
  var p = inputNumber(pInput);
  var temps = make("span", say("measured_temperatures", {}), "tpx-chips");
  if (!at.temperatures.length) temps.appendChild(document.createTextNode(say("unknown", {})));
  at.temperatures.forEach(function (v) {
    temps.appendChild(chip(say("temperature_chip", { t: v.text }), v.value === t, function () {
      setNumber(tInput, v.value, v.text); update(false);
    }));
  });
  var ps = make("span", say("measured_pressures", {}), "tpx-chips");
  at.pressures.forEach(function (v) {
    ps.appendChild(chip(say("pressure_chip", { p: v.text }), v.value === p, function () {
      setNumber(pInput, v.value, v.text); update(false);
    }));
  });
  box.appendChild(temps);
  box.appendChild(ps);
  var tl = $("tpx-temperature-list");
  var pl = $("tpx-pressure-list");
  clear(tl);
  clear(pl);
  at.temperatures.forEach(function (v) { var o = make("option"); o.value = v.text; tl.appendChild(o); });
  at.pressures.forEach(function (v) { var o = make("option"); o.value = v.text; pl.appendChild(o); });
}

function setPin(pinIndex, discName) {
  var pin = PINS[pinIndex];
  pinSelect.value = String(pinIndex);
  fillSelect(discSelect, pin.pairs.map(function (i) { return { value: i, text: PAIRS[i].disc }; }));
  var chosen = discName === null ? undefined : pin.pairs.find(function (i) {
    return sameName(discName, PAIRS[i].disc, PAIRS[i].keys[1]);
  });
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
  var pair = PAIRS[state.pair];
  if (pair.speeds.length > 1) q.set("speed", speedOf(pair).text);
  if (state.lab >= 0) q.set("lab", DATA.labs[state.lab]);
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
    var found = PINS.findIndex(function (p) {
      return sameName(q.get("pin"), p.name, p.key);
    });
    if (found < 0) missing.push(say("link_pin_missing", { pin: q.get("pin") }));
    else pinIndex = found;
  }
  var discName = q.has("disc") ? q.get("disc") : null;
  setPin(pinIndex, discName);
  var pair = PAIRS[state.pair];
  if (!missing.length && discName !== null && !sameName(discName, pair.disc, pair.keys[1])) {
    var known = PAIRS.some(function (p) { return sameName(discName, p.disc, p.keys[1]); });
    missing.push(known ? say("link_disc_other_pin", { disc: discName, pin: PINS[pinIndex].name })
      : say("link_disc_missing", { disc: discName }));
  }
  if (q.has("speed")) {
    var text = q.get("speed").trim();
    var at = pair.speeds.length > 1 ? pair.speeds.findIndex(function (x) {
      return x.text === text || x.speed_mm_s === Number(text);
    }) : -1;
    if (at >= 0) state.speed = at;
    else if (pair.speeds.length > 1) {
      notes.push(say("link_speed_missing", { speed: q.get("speed") }));
    }
  }
  if (q.has("lab")) {
    state.lab = DATA.labs.indexOf(q.get("lab"));
    if (state.lab < 0) notes.push(say("link_lab_missing", { lab: q.get("lab") }));
  }
  renderSpeeds(pair);
  var measured = speedOf(pair);
  [["temperature", tInput, measured.temperatures], ["pressure", pInput, measured.pressures]]
    .forEach(function (f) {
      if (!q.has(f[0])) return;
      var typed = q.get(f[0]).trim();
      var n = Number(typed);
      if (typed !== "" && Number.isFinite(n)) {
        // a measured value written as the tables print it (or in full) means that value
        var m = f[2].find(function (v) { return v.text === typed || v.value === n; });
        // (shown as the tables print it where that text is not the value itself)
        if (m !== undefined && Number(m.text) !== m.value) setNumber(f[1], m.value, m.text);
        else f[1].value = typed;
      } else notes.push(say("link_not_number", { field: say(f[0], {}), value: q.get(f[0]) }));
    });
  state.missing = missing.length ? say("no_mu_shown", { missing: missing.join("; ") }) : null;
  note(notes.concat(missing).join("; "));
}


// ---------------------------------------------------------------- the result

/* A standard uncertainty to two significant digits, by the GUM rule (rounding.round_gum). */
function uText(u) { return u > 0 ? roundGum(u, u)[1] : "0"; }

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
  muK.dataset.value = String(res.mu_k.value);
  muK.dataset.uncertainty = res.mu_k.expanded === null ? "" : String(res.mu_k.expanded);
  // GUM combined standard uncertainty (k = 1) and the expanded U = 2u, beside the CI
  muKu.textContent = say("u_line", { u: uText(res.mu_k.u_interpolation),
    half: res.mu_k.uncertainty === null ? say("unknown", {}) : f3(res.mu_k.uncertainty) });
  muKu.dataset.u = res.mu_k.u_combined === null ? "" : String(res.mu_k.u_combined);
  muK.dataset.clampedPressure = String(res.mu_k.clamped_pressure);
  muK.dataset.clampedTemperature = String(res.mu_k.clamped_temperature);
  muS.textContent = res.mu_s === null ? say("mu_s_none", {}) : estimateText(res.mu_s);
  var what = [];
  if (res.mu_k.clamped_pressure) what.push(say("pressure", {}));
  if (res.mu_k.clamped_temperature) what.push(say("temperature", {}));
  if (res.mu_k.clamped_speed) what.push(say("speed", {}));
  clamped.textContent = res.clamped ? say("clamped_yes", { what: what.join(say("and", {})),
    extrapolated: DATA.texts.extrapolated }) : say("clamped_no", {});
  clamped.className = res.clamped ? "tpx-clamped" : "";
  res.notes.forEach(function (n) { notes.appendChild(make("li", n)); });
  var runs = runsOf(res.pair);
  res.mu_k.used.forEach(function (u) {
    var text = u.point.text;
    var tr = make("tr");
    var cells = [text.p, text.t, text.mean, text.half, text.u, String(u.n), f3(u.weight)];
    if (PAIRS[res.pair].speeds.length > 1) cells.splice(2, 0, speedText(res.pair, u.speed_mm_s));
    cells.forEach(function (v) { tr.appendChild(make("td", v)); });
    var cell = make("td", null, "tpx-t");
    // one line per repeat: its μ_K and the file and test it came from
    u.point.runs.forEach(function (i) {
      if (runs[i]) cell.appendChild(make("div", runs[i].line, "tpx-repeat"));
    });
    if (!runs.length) cell.appendChild(make("div", say(DATA.runs_beside && !RUNS_MISSING[res.pair] ?
      "loading" : "not_at_hand", {}), "tpx-muted"));
    tr.appendChild(cell);
    body.appendChild(tr);
  });
  $("tpx-used-speed").hidden = PAIRS[res.pair].speeds.length < 2;
}

function speedText(pairIndex, v) {
  var at = PAIRS[pairIndex].speeds.find(function (x) { return x.speed_mm_s === v; });
  return at ? at.text : "";
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
    status.textContent = say(ok ? "copied" : "copy_by_hand", {});
  }
  if (navigator.clipboard && window.isSecureContext) {
    navigator.clipboard.writeText(text).then(function () { status.textContent = say("copied", {}); },
      fallback);
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
  $("tpx-export-status").textContent = say("downloaded", { name: a.download });
}


// ---------------------------------------------------------------- wiring

function compute() {
  if (state.missing) return [null, state.missing];
  var p = inputNumber(pInput);
  var t = inputNumber(tInput);
  if (p === null) return [null, say("enter_pressure", {})];
  if (Number.isNaN(p)) return [null, say("pressure_nan", {})];
  if (Number.isNaN(t)) return [null, say("temperature_nan", {})];
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
  sayMissingRuns();
}

/* A pair's runs arrived from beside the page (or were found missing): redraw what
   shows them. */
function runsArrived(index) {
  if (index !== state.pair) return;
  renderResult(state.result, compute()[1]);
  drawPairPlot(state.result);
  sayMissingRuns();
}

function sayMissingRuns() {
  if (!DATA.runs_beside || !RUNS_MISSING[state.pair]) return;
  note("the runs of this pair are not beside the page (" + DATA.runs_beside + "/pair-" +
    state.pair + ".js): the groups and fits show, the repeats do not");
}

function newPair() {
  state.speed = 0;
  state.missing = null;
  note("");
  update(true);
}

fillSelect(pinSelect, PINS.map(function (p, i) { return { value: i, text: p.name }; }));
pinSelect.addEventListener("change", function () {
  setPin(Number(pinSelect.value), PAIRS[state.pair].disc);
  newPair();
});
vSelect.addEventListener("change", function () {
  state.speed = Number(vSelect.value);
  update(false);
});
discSelect.addEventListener("change", function () {
  state.pair = Number(discSelect.value);
  newPair();
});
[tInput, pInput].forEach(function (input) {
  input.addEventListener("input", function () {
    delete input.dataset.shown;  // typed: the text is the value
    update(false);
  });
});
/* the labs: a filter and a colouring, offered where the map holds more than one */
$("tpx-lab-label").hidden = DATA.labs.length < 2;
$("tpx-colour-label").hidden = DATA.labs.length < 2;
fillSelect(labSelect, [{ value: -1, text: say("every_lab", {}) }].concat(
  DATA.labs.map(function (name, i) { return { value: i, text: name }; })));
labSelect.addEventListener("change", function () { state.lab = Number(labSelect.value); update(false); });
colourSelect.addEventListener("change", function () { state.colour = colourSelect.value; update(false); });
$("tpx-form").addEventListener("submit", function (ev) { ev.preventDefault(); });
$("tpx-export-format").addEventListener("change", renderExport);
$("tpx-copy").addEventListener("click", copyText);
$("tpx-download").addEventListener("click", download);
$("tpx-group-filter").addEventListener("input", renderTable);
$("tpx-group-scope").addEventListener("change", renderTable);
/* the plots are drawn at the size they are shown, so their text keeps its size: again
   when the window changes width */
var drawnWidth = root.clientWidth;
window.addEventListener("resize", function () {
  if (root.clientWidth === drawnWidth || !PAIRS.length) return;
  drawnWidth = root.clientWidth;
  drawPairPlot(state.result);
  drawOverview();
});
METHODS.forEach(function (m) { $("tpx-group-method").appendChild(make("option", m)); });
$("tpx-group-method-label").hidden = METHODS.length < 2;
$("tpx-group-method").addEventListener("change", renderTable);

if (!PAIRS.length) {
  renderResult(null, say("no_pair", {}));
  return;
}
readUrl();
labSelect.value = String(state.lab);
update(true);

/* For scripts and tests: the page's own computation, and its current selection. */
window.tribopipeExplorer = Object.freeze({
  data: DATA,
  query: query,
  runs: runsOf,
  result: function () { return state.result; },
  exportText: function (fmt, res) { return EXPORTS[fmt].make(res || state.result); },
  fileName: function (fmt) { return state.result ? fileName(state.result, fmt) : null; },
  format: { decimal: decimalText },
});

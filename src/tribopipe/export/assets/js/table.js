/* The group table: filtered by words, scope and lab, sorted by any column. Every head and
   cell's text comes from Python (DATA.texts.heads, GROUPS[i].text: the tables' rounding);
   the numbers sort. */

var COLUMNS = [
  { key: "pin", text: true },
  { key: "disc", text: true },
  { key: "normal_force_N" },
  { key: "pressure_kPa" },
  { key: "temperature_C" },
  { key: "mu_k_n" },
  { key: "mu_k_mean" },
  { key: "mu_k_std" },
  { key: "mu_k_ci95_low" },
  { key: "mu_k_ci95_high" },
  { key: "mu_k_cv" },
  { key: "mu_s_n" },
  { key: "mu_s_mean" },
  { key: "qc", text: true },
];

/* the nominal sliding speed, where a pair of the map holds several (the group table has it) */
if (GROUPS.some(function (g) { return finite(g.nominal_speed_mm_s); })) {
  COLUMNS.splice(5, 0, { key: "nominal_speed_mm_s" });
}
/* the labs, where the map holds several */
if (DATA.labs.length > 1) COLUMNS.push({ key: "labs", text: true });

function cellText(col, g) {
  if (col.key === "pin" || col.key === "disc" || col.key === "test_method") return g[col.key];
  if (col.key === "labs") return g.labs.map(function (i) { return DATA.labs[i]; }).join(", ");
  return g.text[col.key] || "";
}

function sortValue(col, g) { return col.text ? cellText(col, g) : g[col.key]; }

/* the test methods of the groups (the map's, in its own order): a column and a filter
   where there are several; methods are never pooled, each group has one */
var METHODS = DATA.methods || [];
if (METHODS.length > 1) {
  COLUMNS.splice(2, 0, { key: "test_method", text: true });
}

function renderTableHead() {
  var head = $("tpx-group-table").tHead;
  clear(head);
  var tr = make("tr");
  COLUMNS.forEach(function (col) {
    var th = make("th", null, col.text ? "tpx-t" : "");
    th.appendChild(words(DATA.texts.heads[col.key]));
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
  var va = sortValue(col, a);
  var vb = sortValue(col, b);
  var ea = va === null || va === undefined || va === "";
  var eb = vb === null || vb === undefined || vb === "";
  if (ea || eb) return ea === eb ? 0 : ea ? 1 : -1; // missing values last either way
  if (col.text) return dir * String(va).localeCompare(String(vb));
  return dir * (va - vb);
}

/* A filter word as a test: found anywhere, names compared by query.name_key's rule. */
function wordPattern(word) {
  var key = nameKey(word);
  return { test: function (hay) { return nameKey(hay).indexOf(key) >= 0; } };
}

function renderTable() {
  renderTableHead();
  var body = $("tpx-group-table").tBodies[0];
  clear(body);
  var scope = $("tpx-group-scope").value;
  var method = $("tpx-group-method").value;
  var patterns = $("tpx-group-filter").value.split(/\s+/).filter(Boolean).map(wordPattern);
  var pinKey = PAIRS[state.pair].keys[0];
  var used = {};
  if (state.result) {
    state.result.mu_k.used.forEach(function (u) { used[u.pressure_kPa + "|" + u.temperature_C + "|" + u.speed_mm_s] = true; });
  }
  var rows = GROUPS.map(function (g, i) { return [g, i]; }).filter(function (gi) {
    var g = gi[0];
    if (scope === "pin" && PAIRS[g.pair].keys[0] !== pinKey) return false;
    if (scope === "pair" && g.pair !== state.pair) return false;
    if (state.lab >= 0 && g.labs.indexOf(state.lab) < 0) return false;
    if (method && g.test_method !== method) return false;
    var hay = [g.pin, g.disc, g.text.qc, g.text.pressure_kPa, g.text.temperature_C + " °C"]
      .concat(g.labs.map(function (i) { return DATA.labs[i]; })).join(" ");
    return patterns.every(function (w) { return w.test(hay); });
  });
  var col = COLUMNS.find(function (c) { return c.key === state.sortKey; });
  if (col) {
    rows.sort(function (a, b) { return compare(col, a[0], b[0], state.sortDir) || a[1] - b[1]; });
  }
  var speeds = PAIRS[state.pair].speeds;
  rows.forEach(function (gi) {
    var g = gi[0];
    var tr = make("tr");
    var v = finite(g.nominal_speed_mm_s) ? g.nominal_speed_mm_s : speeds[0].speed_mm_s;
    var isUsed = state.result && g.pair === state.pair &&
      used[g.pressure_kPa + "|" + (finite(g.temperature_C) ? g.temperature_C : null) + "|" + v];
    tr.className = (isUsed ? "tpx-used " : "") + (g.text.qc ? "tpx-flag" : "");
    tr.tabIndex = 0;
    tr.dataset.group = String(gi[1]);
    COLUMNS.forEach(function (c) {
      var td = make("td", null, c.text ? "tpx-t" : "");
      td.appendChild(words(cellText(c, g)));
      if (c.key === "qc") td.className += " tpx-qc";
      tr.appendChild(td);
    });
    var choose = function () {
      var p = PAIRS[g.pair];
      setPin(pinOf(g.pair), p.disc);
      state.pair = g.pair;
      discSelect.value = String(g.pair);
      state.speed = finite(g.nominal_speed_mm_s) ? Math.max(0, p.speeds.findIndex(function (x) {
        return x.speed_mm_s === g.nominal_speed_mm_s;
      })) : 0;
      if (finite(g.temperature_C)) setNumber(tInput, g.temperature_C, g.text.temperature_C);
      else { tInput.value = ""; delete tInput.dataset.shown; }
      setNumber(pInput, g.pressure_kPa, g.text.pressure_kPa);
      update(false);
    };
    tr.addEventListener("click", choose);
    tr.addEventListener("keydown", function (ev) { if (ev.key === "Enter") choose(); });
    body.appendChild(tr);
  });
  $("tpx-group-count").textContent = say("group_count", { shown: rows.length, total: GROUPS.length });
}

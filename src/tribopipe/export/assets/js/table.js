/* The group table: filtered by words and scope, sorted by any column. */

function qcText(g) {
  var out = [];
  if (g.range_exceeds_r) out.push("range > r");
  if (g.qc_flagged) out.push("flagged run");
  if (g.reviewed) out.push(g.reviewed + " reviewed");
  return out.join(", ");
}

/* A group mean with its U (k = 2) as query.estimate_text writes it ('' without a mean). */
function groupText(g, q) {
  var mean = g[q + "_mean"];
  if (!finite(mean)) return "";
  return estimateText({value: mean, expanded: g[q + "_U"], n_min: g[q + "_n"]});
}

var COLUMNS = [
  { key: "pin", label: "pin", text: true },
  { key: "disc", label: "disc", text: true },
  { key: "normal_force_N", label: "F [N]", fmt: g6 },
  { key: "pressure_kPa", label: "p [kPa]", fmt: function (v) { return v === null ? "" : pyG(v, 4); } },
  { key: "temperature_C", label: "T [°C]", fmt: g6 },
  { key: "mu_k_n", label: "n", fmt: String },
  { key: "mu_k_mean", label: "μ_K ± U (k = 2)", show: function (g) { return groupText(g, "mu_k"); } },
  { key: "mu_k_std", label: "μ_K SD", fmt: f3 },
  { key: "mu_k_ci95_low", label: "μ_K 95 % CI low (repeats)", fmt: f3 },
  { key: "mu_k_ci95_high", label: "μ_K 95 % CI high (repeats)", fmt: f3 },
  { key: "mu_k_cv", label: "μ_K CV", fmt: f3 },
  { key: "mu_s_n", label: "μ_S n", fmt: String },
  { key: "mu_s_mean", label: "μ_S ± U (k = 2)", show: function (g) { return groupText(g, "mu_s"); } },
  { key: "qc", label: "QC", text: true, get: qcText },
];

/* the nominal sliding speed, where a pair of the map holds several (the group table has it) */
if (GROUPS.some(function (g) { return finite(g.nominal_speed_mm_s); })) {
  COLUMNS.splice(5, 0, { key: "nominal_speed_mm_s", label: "v [mm/s]", fmt: g6 });
}

/* the test methods of the groups (the map's, in its own order): a column and a filter
   where there are several; methods are never pooled, each group has one */
var METHODS = DATA.methods || [];
if (METHODS.length > 1) {
  COLUMNS.splice(2, 0, { key: "test_method", label: "method", text: true });
}

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
  var method = $("tpx-group-method").value;
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
    if (method && g.test_method !== method) return false;
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
      var shownText = c.show ? c.show(g) : c.fmt ? (v === null || v === undefined ? "" : c.fmt(v)) : v;
      var td = make("td", shownText, c.text ? "tpx-t" : "");
      if (c.key === "qc") td.className += " tpx-qc";
      tr.appendChild(td);
    });
    var choose = function () {
      var p = PAIRS[g.pair];
      setPin(pinOf(g.pair), key(p.disc));
      state.pair = g.pair;
      discSelect.value = String(g.pair);
      if (finite(g.temperature_C)) setNumber(tInput, g.temperature_C);
      else { tInput.value = ""; delete tInput.dataset.shown; }
      setNumber(pInput, g.pressure_kPa);
      update(false);
    };
    tr.addEventListener("click", choose);
    tr.addEventListener("keydown", function (ev) { if (ev.key === "Enter") choose(); });
    body.appendChild(tr);
  });
  $("tpx-group-count").textContent = rows.length + " of " + GROUPS.length + " groups";
}

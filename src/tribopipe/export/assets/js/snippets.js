/* The selection as CSV and as the ABAQUS/Ansys text of simulators.condition_snippet. */

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

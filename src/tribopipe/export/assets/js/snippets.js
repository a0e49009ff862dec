/* The selection as CSV and as the ABAQUS/Ansys text of fe_decks.condition_snippet. */

/* simbase.safe_text(value, ascii_only=True): Python's ascii() without the quotes, so no
   newline, control or non-ASCII character of a name survives into a deck's comment. */
function deckSafe(value) {
  var s = String(value);
  var quote = s.indexOf("'") >= 0 && s.indexOf('"') < 0 ? '"' : "'";
  var out = "";
  var hex = function (c, n) { return c.toString(16).padStart(n, "0"); };
  for (var ch of s) {
    var c = ch.codePointAt(0);
    if (ch === "\\") out += "\\\\";
    else if (ch === quote) out += "\\" + ch;
    else if (ch === "\t") out += "\\t";
    else if (ch === "\n") out += "\\n";
    else if (ch === "\r") out += "\\r";
    else if (c < 0x20 || c >= 0x7f) {
      out += c < 0x100 ? "\\x" + hex(c, 2) : c < 0x10000 ? "\\u" + hex(c, 4) : "\\U" + hex(c, 8);
    } else out += ch;
  }
  return out;
}

/* fe_decks.ansys_safe: also "$", MAPDL's command separator. */
function ansysSafe(value) { return deckSafe(value).replace(/\$/g, "\\x24"); }

/* textwrap.wrap(text, width, subsequent_indent=indent, break_on_hyphens=False), for text
   whose only whitespace is ASCII (what the deck-safe comment bodies hold). */
function wrap(text, width, indent) {
  var chunks = text.split(/([\t\n\x0b\x0c\r ]+)/).filter(function (c) { return c !== ""; });
  chunks.reverse();
  var lines = [];
  var top = function () { return chunks[chunks.length - 1]; };
  while (chunks.length) {
    var cur = [];
    var curLen = 0;
    var prefix = lines.length ? indent : "";
    var w = width - prefix.length;
    if (top().trim() === "" && lines.length) chunks.pop();
    while (chunks.length && curLen + top().length <= w) {
      curLen += top().length;
      cur.push(chunks.pop());
    }
    if (chunks.length && top().length > w) { // a word longer than a line is cut
      var left = w < 1 ? 1 : w - curLen;
      cur.push(top().slice(0, left));
      chunks[chunks.length - 1] = top().slice(left);
      curLen = cur.join("").length;
    }
    if (cur.length && cur[cur.length - 1].trim() === "") cur.pop();
    if (cur.length) lines.push(prefix + cur.join(""));
  }
  return lines;
}

/* simbase.comment_block: comment lines of at most `width` (100) characters. */
function commentBlock(comment, bodies, width) {
  if (width === undefined) width = 100;
  var out = [];
  bodies.forEach(function (body) {
    var indent = " ".repeat(body.length - body.replace(/^ +/, "").length);
    var wrapped = wrap(body, width - comment.length - 1, indent + "  ");
    (wrapped.length ? wrapped : [""]).forEach(function (w) {
      out.push((comment + " " + w).replace(/\s+$/, ""));
    });
  });
  return out;
}

/* fe_decks.abaqus_name */
function abaqusName(pin, disc) {
  var text = (pin + "__ON__" + disc).replace(/[^A-Za-z0-9]+/g, "_").replace(/^_+|_+$/g, "");
  return ("FRIC_" + text.toUpperCase()).slice(0, 80);
}

function num(x) { return pyG(x, 10); } // simbase.num

function usedText(res) {
  return res.mu_k.used.map(function (u) {
    return pyG(u.pressure_kPa) + " kPa" + (u.temperature_C === null ? "" : "/" + pyG(u.temperature_C) + " C") +
      " (w=" + pyG(u.weight, 3) + ")";
  }).join(", ");
}

/* simbase.condition_lines */
function conditionLines(res, safe) {
  var t = res.temperature_C === null ? "unknown" : pyG(res.temperature_C) + " C";
  var lines = [
    "pair: pin " + safe(res.pin) + " on disc " + safe(res.disc),
    "condition: contact pressure " + pyG(res.pressure_kPa) + " kPa, temperature " + t,
    "mu_k = " + num(res.mu_k.value) + "; " + estimateText(res.mu_k, true) +
      (res.mu_k.expanded === null ? "" : " (U, k = 2)"),
    "mu_s = " + (res.mu_s === null ? "unknown (not in the map)" : num(res.mu_s.value) + "; " +
      estimateText(res.mu_s, true) + (res.mu_s.expanded === null ? "" : " (U, k = 2)")),
    "from measured groups: " + usedText(res),
  ];
  if (res.clamped) lines.push("outside the measured range: edge value held constant");
  return lines;
}

/* fe_decks.condition_snippet(res, fmt, source=map): a constant mu_K for ABAQUS or Ansys;
   the header lines, which do not depend on the condition, come rendered from Python. */
function conditionSnippet(res, fmt) {
  var lines = DATA.snippet_headers[fmt].slice();
  var note = "a constant coefficient: the solver uses it at every pressure and temperature; for " +
    "the dependence export the pair's table (tribopipe export " + fmt + " --pin PIN --disc DISC)";
  var mu = num(res.mu_k.value);
  if (fmt === "abaqus") {
    lines = lines.concat(commentBlock("**", conditionLines(res, deckSafe).concat([note])));
    lines.push("*SURFACE INTERACTION, NAME=" + abaqusName(res.pin, res.disc), "*FRICTION", mu);
  } else {
    lines = lines.concat(commentBlock("!", conditionLines(res, ansysSafe).concat([note,
      "material 1: pin " + ansysSafe(res.pin) + " on disc " + ansysSafe(res.disc)])));
    lines.push("TB,FRIC,1,,,ISO", "TBDATA,1," + mu);
  }
  return lines.join("\n") + "\n";
}

var CSV_COLUMNS = ["pin", "disc", "pressure_kPa", "temperature_C", "mu_k", "mu_k_U_k2",
  "mu_k_ci95_half_width", "mu_s", "mu_s_U_k2", "mu_s_ci95_half_width", "clamped_pressure", "clamped_temperature", "measured_groups",
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
    res.mu_k.expanded, res.mu_k.uncertainty, res.mu_s ? res.mu_s.value : null,
    res.mu_s ? res.mu_s.expanded : null, res.mu_s ? res.mu_s.uncertainty : null,
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

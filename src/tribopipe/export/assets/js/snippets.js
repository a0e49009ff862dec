/* The selection as CSV and as the simulator input of every format the registry
   (tribopipe/export/registry.py) gives a snippet: DATA.snippets lists them, with the
   opening lines of each rendered by Python (DATA.snippet_headers); SNIPPETS below adds the
   lines that depend on the condition, each function the copy of its Python writer
   (tests/test_snippets_js.py holds every one equal to it, and SNIPPETS to the registry). */

/* escape.sim_comment(value, "**"): Python's ascii() without the quotes, so no
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

/* escape.sim_comment(value, "!"): also "$", MAPDL's command separator. */
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

/* simbase.xml_comment(text, ascii_only=True); the opening is split because a page's
   script may not hold "<" "!--" (explorer._script refuses it) */
function xmlComment(text) {
  return "<" + "!-- " + deckSafe(text).replace(/-(?=-)/g, "- ") + " -->";
}

/* usd._comment */
function hashComment(text) { return ("# " + deckSafe(text)).replace(/\s+$/, ""); }

/* simbase.static_and_dynamic: [static, dynamic, where the static came from] */
function staticAndDynamic(res) {
  var muK = res.mu_k.value;
  if (res.mu_s === null) {
    return [muK, muK, "static = mu_k: the map holds no mu_s for this pair (an imported " +
      "published map holds mu_k only), so the onset of slip takes the kinetic coefficient; " +
      "the static coefficient is written all the same, never left to the engine's default"];
  }
  if (res.mu_s.value < muK) {
    return [muK, muK, "static = mu_k: the map's mu_s (" + num(res.mu_s.value) + ") is below " +
      "mu_k at this condition and the engine needs static >= dynamic, so static is raised to mu_k"];
  }
  return [res.mu_s.value, muK, "static = mu_s (breakaway), dynamic = mu_k (sliding)"];
}

/* usd.write_usd(res, source=map) */
function usdSnippet(res) {
  var sd = staticAndDynamic(res);
  var lines = DATA.snippet_headers.usd.concat(
    conditionLines(res, String).concat([sd[2]]).map(hashComment));
  lines.push("", 'def Scope "TribopipeFriction"', "{", '    def Material "PinOnDisc" (',
    '        prepend apiSchemas = ["PhysicsMaterialAPI", "PhysxMaterialAPI"]', "    )", "    {",
    "        float physics:dynamicFriction = " + num(sd[1]),
    "        float physics:staticFriction = " + num(sd[0]),
    '        uniform token physxMaterial:frictionCombineMode = "average"', "    }");
  [['Cube "Pin"', ["double size = 0.02", "double3 xformOp:translate = (0, 0, 0.02)"]],
   ['Cylinder "Disc"', ['uniform token axis = "Z"', "double height = 0.02", "double radius = 0.2",
     "double3 xformOp:translate = (0, 0, 0)"]]].forEach(function (example) {
    lines.push("", "    def " + example[0] + " (",
      '        prepend apiSchemas = ["PhysicsCollisionAPI", "MaterialBindingAPI"]', "    )", "    {");
    example[1].forEach(function (line) { lines.push("        " + line); });
    lines.push("        rel material:binding:physics = </TribopipeFriction/PinOnDisc>",
      '        uniform token[] xformOpOrder = ["xformOp:translate"]', "    }");
  });
  lines.push("}");
  return lines.join("\n") + "\n";
}

/* pybullet.write_pybullet(res, source=map): the pin's link, mu_K */
function pybulletSnippet(res) {
  var mu = res.mu_k.value;
  var lines = DATA.snippet_headers.pybullet.concat(conditionLines(res, String).concat([
    "contact: pin " + num(mu) + " x disc " + num(1.0) + " = " + num(mu * 1.0)]).map(xmlComment));
  lines.push('<robot name="pin">', '  <link name="pin">', "    <contact>",
    '      <lateral_friction value="' + num(mu) + '"/>', "    </contact>", "    <inertial>",
    '      <mass value="0.1"/>',
    '      <inertia ixx="6.667e-06" ixy="0" ixz="0" iyy="6.667e-06" iyz="0" izz="6.667e-06"/>',
    "    </inertial>", "    <collision>", '      <geometry><box size="0.02 0.02 0.02"/></geometry>',
    "    </collision>", "  </link>", "</robot>");
  return lines.join("\n") + "\n";
}

/* drake.write_drake(res, source=map) */
function drakeSnippet(res) {
  var sd = staticAndDynamic(res);
  var lines = DATA.snippet_headers.drake.concat(
    conditionLines(res, String).concat([sd[2]]).map(xmlComment));
  lines.push('<sdf version="1.9" xmlns:drake="http://drake.mit.edu">',
    '  <model name="tribopipe_pin_on_disc">');
  [["pin", "0 0 0.02 0 0 0", "0.02 0.02 0.02", "0.1", "6.667e-06", "6.667e-06"],
   ["disc", "0 0 0 0 0 0", "0.4 0.4 0.02", "1.0", "0.01337", "0.02667"]].forEach(function (l) {
    lines.push('    <link name="' + l[0] + '">', "      <pose>" + l[1] + "</pose>", "      <inertial>",
      "        <mass>" + l[3] + "</mass>",
      "        <inertia><ixx>" + l[4] + "</ixx><iyy>" + l[4] + "</iyy><izz>" + l[5] + "</izz>" +
        "<ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia>",
      "      </inertial>", '      <collision name="' + l[0] + '_collision">',
      "        <geometry><box><size>" + l[2] + "</size></box></geometry>",
      "        <drake:proximity_properties>",
      "          <drake:mu_dynamic>" + num(sd[1]) + "</drake:mu_dynamic>",
      "          <drake:mu_static>" + num(sd[0]) + "</drake:mu_static>",
      "        </drake:proximity_properties>", "      </collision>", "    </link>");
  });
  lines.push("  </model>", "</sdf>");
  return lines.join("\n") + "\n";
}

/* the condition-dependent part of each registered snippet, by format name */
var SNIPPETS = {
  abaqus: function (r) { return conditionSnippet(r, "abaqus"); },
  ansys: function (r) { return conditionSnippet(r, "ansys"); },
  usd: usdSnippet,
  pybullet: pybulletSnippet,
  drake: drakeSnippet,
};

var EXPORTS = { csv: { ext: "csv", mime: "text/csv", make: csvText } };
DATA.snippets.forEach(function (s) {
  EXPORTS[s.name] = { ext: s.suffix, mime: "text/plain", make: SNIPPETS[s.name] };
});

function slug(text) {
  return key(text).replace(/[^a-z0-9]+/g, "-").replace(/^-+|-+$/g, "").slice(0, 40) || "x";
}

function fileName(res, fmt) {
  var t = res.temperature_C === null ? "" : "_" + pyG(res.temperature_C) + "C";
  return "tribopipe_" + slug(res.pin) + "_" + slug(res.disc) + "_" + pyG(res.pressure_kPa) + "kPa" +
    t + "." + EXPORTS[fmt].ext;
}

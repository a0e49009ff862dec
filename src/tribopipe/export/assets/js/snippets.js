/* The selection as CSV and as the simulator input of every format the registry
   (tribopipe/export/registry.py) gives a snippet: DATA.snippets lists them, with the
   opening lines of each rendered by Python (DATA.snippet_headers); SNIPPETS below adds the
   lines that depend on the condition, each function the copy of its Python writer
   (tests/test_snippets_js.py holds every one equal to it, and SNIPPETS to the registry). */

/* headers.comment_block of lines that never wrap (numbers and the library's words: the
   condition lines hold one measured group a line); every line that could wrap (the pair's,
   the note) comes laid out from Python. */
function commentLines(comment, bodies) {
  return bodies.map(function (body) { return (comment + " " + body).replace(/\s+$/, ""); });
}

function num(x) { return decimalText(x, 10); } // unit_systems.num

function usedText(res) {
  return res.mu_k.used.map(function (u) {
    return g6(u.pressure_kPa) + " kPa" + (u.temperature_C === null ? "" : "/" + g6(u.temperature_C) + " C") +
      " (w=" + decimalText(u.weight, 3) + ")";
  }).join(", ");
}

/* headers.condition_lines after the first (the pair's, which Python renders escaped for
   each format: PAIRS[i].snippet): numbers and the library's words only */
function conditionLines(res) {
  var t = res.temperature_C === null ? "unknown" : g6(res.temperature_C) + " C";
  var lines = [
    "condition: contact pressure " + g6(res.pressure_kPa) + " kPa, temperature " + t,
    "mu_k = " + num(res.mu_k.value) + "; " + estimateText(res.mu_k, true) +
      (res.mu_k.expanded === null ? "" : " (U, k = 2)"),
    "mu_s = " + (res.mu_s === null ? DATA.texts.snippet.mu_s_unknown : num(res.mu_s.value) + "; " +
      estimateText(res.mu_s, true) + (res.mu_s.expanded === null ? "" : " (U, k = 2)")),
    "from measured groups:",
  ].concat(res.mu_k.used.map(function (u) {
    return "  " + g6(u.pressure_kPa) + " kPa" + (u.temperature_C === null ? "" : "/" +
      g6(u.temperature_C) + " C") + " (w=" + decimalText(u.weight, 3) + ")";
  }));
  if (res.clamped) lines.push(DATA.texts.snippet.clamped);
  return lines;
}

/* fe_decks.condition_snippet(res, fmt, source=map): a constant mu_K for ABAQUS or Ansys;
   the header lines, which do not depend on the condition, come rendered from Python, and
   so do the lines that name the pair. */
function conditionSnippet(res, fmt) {
  var named = PAIRS[res.pair].snippet[fmt];
  var note = DATA.texts.snippet.note_lines[fmt];
  var mu = num(res.mu_k.value);
  var lines = DATA.snippet_headers[fmt].concat(named.head);
  if (fmt === "abaqus") {
    lines = lines.concat(commentLines("**", conditionLines(res)), note);
    lines.push("*SURFACE INTERACTION, NAME=" + named.name[0], "*FRICTION", mu);
  } else {
    lines = lines.concat(commentLines("!", conditionLines(res)), note, named.material);
    lines.push("TB,FRIC,1,,,ISO", "TBDATA,1," + mu);
  }
  return lines.join("\n") + "\n";
}

/* A text of numbers and the library's words (DATA.texts.notes: no quote and no formula
   start in them, tests/test_explorer.py holds them so) as one quoted CSV field; every
   other text cell comes from Python (DATA.csv, PAIRS[i].csv: escape.csv_cell). */
function csvQuoted(text) { return '"' + text + '"'; }

/* a number in full: the shortest text that reads back as it (the browser's own) */
function csvNumber(v) { return v === null || v === undefined ? "" : String(v); }

/* The condition as CSV: the header and the cells that are text come from Python
   (DATA.csv, PAIRS[i].csv: tribopipe.escape.csv_cell, quoted as the csv module does). */
function csvText(res) {
  var pair = PAIRS[res.pair];
  var row = [pair.csv[0], pair.csv[1], csvNumber(res.pressure_kPa), csvNumber(res.temperature_C),
    csvNumber(res.mu_k.value), csvNumber(res.mu_k.expanded), csvNumber(res.mu_k.uncertainty),
    csvNumber(res.mu_s ? res.mu_s.value : null), csvNumber(res.mu_s ? res.mu_s.expanded : null),
    csvNumber(res.mu_s ? res.mu_s.uncertainty : null),
    res.mu_k.clamped_pressure ? "True" : "False", res.mu_k.clamped_temperature ? "True" : "False",
    csvQuoted(usedText(res)), csvQuoted(res.notes.join("; "))].concat(DATA.csv.cells);
  return DATA.csv.header + "\r\n" + row.join(",") + "\r\n";
}

/* xml_text.xml_comment and usd._comment of a line of numbers and the library's words (no
   name: those lines come escaped from Python); the opening is split because a page's
   script may not hold "<" "!--" (explorer._script refuses it) */
function xmlComment(text) { return "<" + "!-- " + text + " -->"; }

function hashComment(text) { return ("# " + text).replace(/\s+$/, ""); }

/* coefficients.static_and_dynamic: [static, dynamic, where the static came from] (the words
   from DATA.texts.snippet.static) */
function staticAndDynamic(res) {
  var muK = res.mu_k.value;
  var why = DATA.texts.snippet.static;
  if (res.mu_s === null) return [muK, muK, why.no_mu_s];
  if (res.mu_s.value < muK) return [muK, muK, why.raised.replace("{mu_s}", num(res.mu_s.value))];
  return [res.mu_s.value, muK, why.mu_s];
}

/* usd.write_usd(res, source=map) */
function usdSnippet(res) {
  var sd = staticAndDynamic(res);
  var lines = DATA.snippet_headers.usd.concat(PAIRS[res.pair].snippet.usd.head,
    conditionLines(res).concat([sd[2]]).map(hashComment));
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
  var lines = DATA.snippet_headers.pybullet.concat(PAIRS[res.pair].snippet.pybullet.head,
    conditionLines(res).concat([
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
  var lines = DATA.snippet_headers.drake.concat(PAIRS[res.pair].snippet.drake.head,
    conditionLines(res).concat([sd[2]]).map(xmlComment));
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

function fileName(res, fmt) {
  var t = res.temperature_C === null ? "" : "_" + g6(res.temperature_C) + "C";
  return "tribopipe_" + PAIRS[res.pair].slug + "_" + g6(res.pressure_kPa) + "kPa" + t + "." +
    EXPORTS[fmt].ext;
}

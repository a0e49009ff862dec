/* tribopipe friction-map explorer: plain JavaScript and SVG, no library, no network.
 *
 * This first part reads the map's data: the JSON document in #explorer-data (see
 * tribopipe/export/explorer.py). Every text the page shows around a number comes from
 * there, made by the library; the script computes what must react to the user: mu_K and
 * mu_S at a condition, exactly as `tribopipe query` does (query.js), and the simulator
 * snippets' numbers (snippets.js). Text reaches the page through textContent and
 * createElement only (dom.js). The parts share one function scope (see README.md).
 */

var root = document.getElementById("tpx");
var dataElement = document.getElementById("explorer-data");
if (!root || !dataElement) return;
var DATA = JSON.parse(dataElement.textContent);
var PAIRS = DATA.pairs;
var GROUPS;
var SVG_NS = "http://www.w3.org/2000/svg";
var COLOURS = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#7f7f7f"];

/* A pair's runs (explorer.py's _runs, packed as columns and rows), read from their own
   data element the first time the pair is shown; or, for a large map, from the file
   DATA.runs_beside/pair-<i>.js beside the page, added as a script when the pair is shown
   (it calls window.tribopipeRuns; the page redraws when it arrives). Until then, and
   where the file is missing, the pair has no runs to show and says so. */
var RUNS = {};
var RUNS_MISSING = {};
/* Rows packed as columns and rows (explorer.py's _packed; "name/key" a nested key). */
function unpack(packed) {
  var cols = packed.columns.map(function (c) { return c.split("/"); });
  return packed.rows.map(function (row) {
    var r = {};
    cols.forEach(function (c, k) {
      if (c.length > 1) (r[c[0]] = r[c[0]] || {})[c[1]] = row[k];
      else r[c[0]] = row[k];
    });
    return r;
  });
}
GROUPS = unpack(DATA.groups);
/* Each speed's interpolation points travel packed too (explorer.py's POINT_LISTS). */
PAIRS.forEach(function (pair) {
  pair.speeds.forEach(function (at) {
    at.mu_k_points = unpack(at.mu_k_points);
    at.mu_s_points = unpack(at.mu_s_points);
  });
});
GROUPS.forEach(function (g) { g.pin = PAIRS[g.pair].pin; g.disc = PAIRS[g.pair].disc; });

window.tribopipeRuns = function (index, packed) {
  RUNS[index] = unpack(packed);
  if (typeof runsArrived === "function") runsArrived(index);
};
function runsOf(index) {
  if (index in RUNS) return RUNS[index];
  var e = document.getElementById("tpx-runs-" + index);
  if (e) {
    RUNS[index] = unpack(JSON.parse(e.textContent));
    return RUNS[index];
  }
  if (DATA.runs_beside && !RUNS_MISSING[index] && !document.getElementById("tpx-load-" + index)) {
    var s = document.createElement("script");
    s.id = "tpx-load-" + index;
    // the folder is one name beside the page; "#", "?" or "%" in it are not a URL's own
    s.src = encodeURIComponent(DATA.runs_beside) + "/pair-" + index + ".js";
    s.onerror = function () { RUNS_MISSING[index] = true; runsArrived(index); };
    document.head.appendChild(s);
  }
  return [];
}

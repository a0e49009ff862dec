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
var GROUPS = DATA.groups;
var SVG_NS = "http://www.w3.org/2000/svg";
var COLOURS = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#7f7f7f"];

/* A pair's runs (explorer.py's _runs), read from their own data element the first time
   the pair is shown: a large map's page parses one pair's runs at a time. */
var RUNS = {};
function runsOf(index) {
  if (!(index in RUNS)) {
    var e = document.getElementById("tpx-runs-" + index);
    RUNS[index] = e ? JSON.parse(e.textContent) : (DATA.runs ? DATA.runs[index] : []);
  }
  return RUNS[index];
}

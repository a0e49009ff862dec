/* tribopipe friction-map explorer: plain JavaScript and SVG, no library, no network.
 *
 * This first part reads the map's data: the JSON document in #explorer-data (see
 * tribopipe/export/explorer.py). mu_K and mu_S at a condition are interpolated exactly as
 * `tribopipe query` does (query.js); numbers are printed the way Python prints them
 * (pyformat.js). Text from the data reaches the page through textContent and
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

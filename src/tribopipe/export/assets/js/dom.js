/* Small DOM helpers: elements and SVG built with createElement and textContent only. */

function $(id) { return document.getElementById(id); }

/* One of the page's own texts (DATA.texts.page, made by Python) with its {names} filled
   in one pass: a value is never read as a template or as markup. */
function say(key, values) {
  return DATA.texts.page[key].replace(/\{(\w+)\}/g, function (m, k) { return String(values[k]); });
}

function make(tag, text, cls) {
  var e = document.createElement(tag);
  if (text !== undefined && text !== null) e.textContent = String(text);
  if (cls) e.className = cls;
  return e;
}

function svg(tag, attrs, parent) {
  var e = document.createElementNS(SVG_NS, tag);
  Object.keys(attrs || {}).forEach(function (k) { e.setAttribute(k, String(attrs[k])); });
  if (parent) parent.appendChild(e);
  return e;
}

function svgText(parent, x, y, text, attrs) {
  var e = svg("text", Object.assign({ x: x, y: y }, attrs || {}), parent);
  e.textContent = String(text);
  return e;
}

function tip(node, text) { svg("title", {}, node).textContent = String(text); }

function clear(node) { while (node.firstChild) node.removeChild(node.firstChild); }

/* Text of a number input: the number, null when empty, NaN when not a number. A value the
   page filled in (setNumber) counts exact while its rounded text is shown unchanged. */
function inputNumber(input) {
  if (input.validity && input.validity.badInput) return NaN;
  var s = input.value.trim();
  if (s === "") return null;
  return input.dataset.shown === s ? Number(input.dataset.exact) : Number(s);
}

/* Fill a number input with a measured value (say 11.78925504 kPa) and its text as the
   tables print it (from Python: "11.79"): the text is shown, the exact value kept for the
   computation until the user types. */
function setNumber(input, value, text) {
  input.value = text;
  if (Number(text) === value) {
    delete input.dataset.shown;
    delete input.dataset.exact;
  } else {
    input.dataset.shown = text;
    input.dataset.exact = String(value);  // the shortest text that reads back as value
  }
}

/* An input's text as the address carries it: what the user typed, or the text of a value
   the page filled in (a link reading it back means the measured value). */
function urlText(input) { return input.value.trim(); }

/* A name or heading as text that may break between its words, never inside one (a hyphen
   inside a name such as "00-50" is no place to break): each word in a .tpx-word span. */
function words(text) {
  var frag = document.createDocumentFragment();
  String(text).split(/( +)/).forEach(function (part) {
    if (part === "") return;
    if (/^ +$/.test(part)) frag.appendChild(document.createTextNode(part));
    else frag.appendChild(make("span", part, "tpx-word"));
  });
  return frag;
}

/* Small DOM helpers: elements and SVG built with createElement and textContent only. */

function $(id) { return document.getElementById(id); }

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

/* Fill a number input with a value (a measured pressure, say 11.78925504 kPa): shown as
   Python's format(v, "g") (6 significant digits, as the chips show it), the exact value
   kept for the computation and the address until the user types. */
function setNumber(input, value) {
  var shown = pyG(value);
  input.value = shown;
  if (Number(shown) === value) {
    delete input.dataset.shown;
    delete input.dataset.exact;
  } else {
    input.dataset.shown = shown;
    input.dataset.exact = pyRepr(value);
  }
}

/* A number to 4 significant digits, as the address writes a value the page filled in
   (35.36776… kPa -> "35.37"; 0.000123456 -> "0.0001235"; 123456 -> "123500"). */
function sig4(value) { return String(Number(value.toPrecision(4))); }

/* An input's text as the address carries it: what the user typed, or a value the page
   filled in to 4 significant digits (a link reading it back means the measured value). */
function urlText(input) {
  var s = input.value.trim();
  return s !== "" && input.dataset.shown === s ? sig4(Number(input.dataset.exact)) : s;
}

/* Where a run came from, in words: "file · test / result" (the parts the map knows). */
function runOrigin(run) {
  var place = [run.test, run.result].filter(function (v) { return v; }).join(" / ");
  return [run.file, place].filter(function (v) { return v; }).join(" · ");
}

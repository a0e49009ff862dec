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

/* Text of a number input: the number, null when empty, NaN when not a number. */
function inputNumber(input) {
  if (input.validity && input.validity.badInput) return NaN;
  var s = input.value.trim();
  return s === "" ? null : Number(s);
}

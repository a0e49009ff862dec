/* Numbers printed exactly as Python's format() and repr() print them. */

/* Exact decimal digits of |x| (finite): {digits, exp} with x = 0.d1d2... * 10^(exp+1),
   i.e. exp is the power of ten of the first significant digit; digits "" for zero. */
function decimal(x) {
  var a = Math.abs(x);
  if (a === 0) return { digits: "", exp: 0 };
  if (a >= 1e21 || a < 1e-30) {
    // outside what toFixed writes exactly: 17 significant digits are enough to round from
    var m = a.toExponential(16).split("e");
    return { digits: m[0].replace(".", "").replace(/0+$/, ""), exp: parseInt(m[1], 10) };
  }
  var parts = a.toFixed(100).split("."); // exact: ECMAScript's toFixed is correctly rounded
  var all = parts[0] + parts[1];
  var lead = all.search(/[1-9]/);
  return { digits: all.slice(lead).replace(/0+$/, ""), exp: parts[0].length - lead - 1 };
}

/* The first `keep` digits of `digits`, rounded half-to-even on an exact tie (Python's
   rule); returns [digits, carried] where carried means the result gained a digit. */
function roundDigits(digits, keep) {
  if (keep < 0) return ["", false];
  if (digits.length <= keep) return [digits + "0".repeat(keep - digits.length), false];
  var head = digits.slice(0, keep);
  var next = digits.charCodeAt(keep) - 48;
  var up;
  if (next !== 5) up = next > 5;
  else if (/[1-9]/.test(digits.slice(keep + 1))) up = true;
  else up = keep > 0 && (head.charCodeAt(keep - 1) - 48) % 2 === 1;
  if (!up) return [head, false];
  var d = head.split("");
  var i = d.length - 1;
  while (i >= 0 && d[i] === "9") { d[i] = "0"; i -= 1; }
  if (i < 0) return ["1" + d.join(""), true];
  d[i] = String.fromCharCode(d[i].charCodeAt(0) + 1);
  return [d.join(""), false];
}

function special(x) {
  if (Number.isNaN(x)) return "nan";
  return x > 0 ? "inf" : "-inf";
}

function sign(x) { return x < 0 || Object.is(x, -0) ? "-" : ""; }

/* Python's format(x, ".<dec>f"). */
function pyFixed(x, dec) {
  if (!Number.isFinite(x)) return special(x);
  var d = decimal(x);
  var n = d.digits === "" ? "0" : roundDigits(d.digits, d.exp + 1 + dec)[0];
  n = (n === "" ? "0" : n).replace(/^0+(?=\d)/, "");
  if (n.length < dec + 1) n = "0".repeat(dec + 1 - n.length) + n;
  var body = dec > 0 ? n.slice(0, n.length - dec) + "." + n.slice(n.length - dec) : n;
  return sign(x) + body;
}

function expText(e) { return "e" + (e < 0 ? "-" : "+") + String(Math.abs(e)).padStart(2, "0"); }

/* Python's format(x, ".<prec>g") (default precision 6). */
function pyG(x, prec) {
  if (prec === undefined) prec = 6;
  if (prec === 0) prec = 1;
  if (!Number.isFinite(x)) return special(x);
  var d = decimal(x);
  if (d.digits === "") return sign(x) + "0";
  var r = roundDigits(d.digits, prec);
  var e = r[1] ? d.exp + 1 : d.exp;
  var digits = r[0].slice(0, prec);
  var body;
  if (e >= -4 && e < prec) {
    var intPart, frac;
    if (e >= 0) { intPart = digits.slice(0, e + 1); frac = digits.slice(e + 1); }
    else { intPart = "0"; frac = "0".repeat(-e - 1) + digits; }
    frac = frac.replace(/0+$/, "");
    body = frac ? intPart + "." + frac : intPart;
  } else {
    var tail = digits.slice(1).replace(/0+$/, "");
    body = digits[0] + (tail ? "." + tail : "") + expText(e);
  }
  return sign(x) + body;
}

/* Python's repr(float(x)): the shortest text that reads back as x. */
function pyRepr(x) {
  if (!Number.isFinite(x)) return special(x);
  if (x === 0) return sign(x) + "0.0";
  var m = Math.abs(x).toExponential().split("e"); // shortest round-trip digits
  var digits = m[0].replace(".", "");
  var e = parseInt(m[1], 10);
  var body;
  if (e >= -4 && e < 16) {
    if (e >= 0) {
      var intPart = (digits + "0".repeat(Math.max(0, e + 1 - digits.length))).slice(0, e + 1);
      body = intPart + "." + (digits.slice(e + 1) || "0");
    } else {
      body = "0." + "0".repeat(-e - 1) + digits;
    }
  } else {
    body = digits[0] + (digits.length > 1 ? "." + digits.slice(1) : "") + expText(e);
  }
  return sign(x) + body;
}

function f3(x) { return x === null || x === undefined ? "" : pyFixed(x, 3); }
function g6(x) { return x === null || x === undefined ? "" : pyG(x, 6); }

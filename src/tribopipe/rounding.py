"""How every output prints a value with its expanded uncertainty: the GUM rule, once.

GUM (JCGM 100:2008, 7.2.6): the uncertainty is given to at most two significant digits
and the value to the same decimal place. :func:`round_gum` rounds U to two significant
digits and the value to U's last digit, both half away from zero on the shortest decimal
text of the float (``0.0125`` → ``0.013``, as a person rounds the printed number, not the
binary ``0.01249999…``). :func:`plus_minus` writes ``value ± U`` and, because a
coefficient of friction is never negative, writes an interval whose lower end would fall
below 0 as ``value +U/−value`` (the interval [0, value + U], bounded at zero).

Every other number an output computes and prints (a simulator file's coefficient, an
estimate without U, a weight) is written by :func:`decimal_text`, the same rounding to a
number of significant digits or of decimals: so the explorer page, which computes such
numbers for any condition, needs one rule, not a copy of Python's ``format``.

The explorer page carries a copy of these rules (``roundGum``, ``plusMinus`` and
``decimalText`` in ``export/assets/js/query.js``); ``tests/test_interpolation.py`` holds
them equal on a grid of values by running the JavaScript in node.
"""

from __future__ import annotations

import math
from decimal import ROUND_HALF_UP, Decimal

#: significant digits of an expanded uncertainty (GUM 7.2.6)
U_DIGITS = 2
#: a U below this is no uncertainty but identical repeats or floating-point noise (μ is
#: of order 1): it is reported as unknown, never as "± 0"
U_FLOOR = 1e-6


def known_u(expanded: float | None) -> bool:
    """True when ``expanded`` is a U worth printing: finite and at least :data:`U_FLOOR`."""
    return expanded is not None and math.isfinite(expanded) and expanded >= U_FLOOR


def _decimal(value: float) -> Decimal:
    """The shortest decimal text of ``value`` as a :class:`Decimal`."""
    return Decimal(repr(float(value)))


def _fixed(value: Decimal) -> str:
    """``value`` as plain fixed-point text (no exponent; a rounded zero without its sign)."""
    text = format(value, "f")
    return text.lstrip("-") if value.is_zero() else text


#: significant digits of a computed number in a simulator's input file (enough that a
#: solver's interpolation between a table's rows matches tribopipe's)
FILE_DIGITS = 10


def decimal_text(value: float, *, digits: int | None = None, places: int | None = None) -> str:
    """``value`` as text, rounded half away from zero on its shortest decimal text (the
    rule of :func:`round_gum`): to ``digits`` significant digits laid out as ``format``'s
    ``"g"`` lays them out (trailing zeros dropped, an exponent ``e-05``/``e+16`` below
    10⁻⁴ or from 10^digits), or to ``places`` decimals as ``"f"`` does. A rounded zero
    has no sign; ``nan``, ``inf``, ``-inf`` as Python writes them.

    ``decimal_text(0.5312345678449, digits=10)`` → ``"0.5312345678"``;
    ``decimal_text(0.0125, places=3)`` → ``"0.013"``; ``decimal_text(1e-5, digits=6)``
    → ``"1e-05"``. Exactly one of ``digits`` (≥ 1) and ``places`` (≥ 0) is given."""
    if (digits is None) == (places is None):
        raise ValueError("decimal_text needs exactly one of digits and places")
    if not math.isfinite(value):
        return repr(float(value))
    d = _decimal(value)
    if places is not None:
        return _fixed(d.quantize(Decimal(1).scaleb(-places), rounding=ROUND_HALF_UP))
    assert digits is not None and digits >= 1
    if d.is_zero():
        return "0"
    exp = d.adjusted()
    r = d.quantize(Decimal(1).scaleb(exp - digits + 1), rounding=ROUND_HALF_UP)
    if r.adjusted() > exp:  # 9.9996 → 10.00: one digit too many
        exp += 1
        r = d.quantize(Decimal(1).scaleb(exp - digits + 1), rounding=ROUND_HALF_UP)
    if -4 <= exp < digits:
        text = _fixed(r)
        return text.rstrip("0").rstrip(".") if "." in text else text
    mantissa = _fixed(r.scaleb(-exp))
    mantissa = mantissa.rstrip("0").rstrip(".") if "." in mantissa else mantissa
    return f"{mantissa}e{'-' if exp < 0 else '+'}{abs(exp):02d}"


def round_gum(value: float, expanded: float) -> tuple[str, str]:
    """``(value_text, U_text)``: ``expanded`` (U > 0, finite) to two significant digits,
    ``value`` to the same decimal place, both rounded half away from zero.

    ``round_gum(0.53412, 0.1149)`` → ``("0.53", "0.11")``; ``round_gum(0.5, 0.0996)`` →
    ``("0.50", "0.10")``. Raises :class:`ValueError` for a non-finite value or a U that is
    not a positive finite number.
    """
    if not (math.isfinite(value) and math.isfinite(expanded) and expanded > 0):
        raise ValueError(f"round_gum needs a finite value and a positive U, got "
                         f"{value!r}, {expanded!r}")
    u = _decimal(expanded)
    step = Decimal(1).scaleb(u.adjusted() - U_DIGITS + 1)
    u_round = u.quantize(step, rounding=ROUND_HALF_UP)
    if u_round.adjusted() > u.adjusted():  # 0.0996 → 0.100: two digits are 0.10
        step = step.scaleb(1)
        u_round = u.quantize(step, rounding=ROUND_HALF_UP)
    v_round = _decimal(value).quantize(step, rounding=ROUND_HALF_UP)
    return _fixed(v_round), _fixed(u_round)


def plus_minus(value: float, expanded: float, *, ascii_only: bool = False) -> str:
    """``"0.53 ± 0.11"`` by :func:`round_gum`; where value − U < 0 the interval is bounded
    at zero and written ``"0.05 +0.11/−0.05"`` (a coefficient of friction is ≥ 0).
    ``ascii_only`` writes ``+/-`` and ``-`` (for the fixed-format simulator decks)."""
    v_text, u_text = round_gum(value, expanded)
    minus, pm = ("-", "+/-") if ascii_only else ("\u2212", "\u00b1")
    if Decimal(v_text) < Decimal(u_text):
        return f"{v_text} +{u_text}/{minus}{v_text}"
    return f"{v_text} {pm} {u_text}"


def round_significant(value: float, digits: int) -> float:
    """``value`` rounded to ``digits`` significant digits (0 and non-finite unchanged)."""
    if not math.isfinite(value) or value == 0:
        return value
    return round(value, digits - 1 - math.floor(math.log10(abs(value))))


def lower_bound(value: float, expanded: float) -> float:
    """The lower end of the interval ``value ± expanded`` for a coefficient of friction:
    ``max(0, value − expanded)``."""
    return max(0.0, value - expanded)

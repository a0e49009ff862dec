"""What a value from outside must be: one rule per concept, used at every edge.

Names (pin, disc, campaign and instrument names, ``[names]`` entries, map rows) and the
numbers that define a run (forces, temperatures, radii, μ, counts) reach tribopipe through
CLI options, config files, manifest cells, file names, imported tables and other labs'
maps. Each edge calls the checks here, so a value means the same everywhere:

* a **name** is text of at most :data:`MAX_NAME_CHARS` characters, not blank, with no
  control, format, surrogate, private-use or unassigned character and no line or paragraph
  separator (so it is one line wherever it is written; spaces are fine);
* a **file name** (the map's ``source_file``) is text of at most :data:`MAX_TEXT_CHARS`
  characters without NUL or a lone surrogate: a file is named by whoever wrote it, so it
  is kept as it is (U+202E, a newline and all) and every output escapes it where it is
  written (:mod:`tribopipe.escape`);
* a **number** is an ``int`` or ``float`` (never a ``bool``), finite and inside the
  physical :class:`Range` of its quantity (:data:`FORCE_N`, :data:`TEMPERATURE_C`,
  :data:`MU`, :data:`PIN_RADIUS_MM`, ...);
* a **count** is an ``int`` (never a ``bool`` or a float) within its bounds.

Every check returns the value or raises :class:`~tribopipe.errors.ValidationError`, one
line naming what was checked (and the file, line and column when the caller gives them)
and what was expected. The bounds are generous: they refuse what cannot be a measurement
(a negative force, −300 °C, μ = 10³⁰⁶, a 10⁻³⁰⁰ mm pin), not what is merely unusual.
"""

from __future__ import annotations

import math
import numbers
import os
import re
import unicodedata
from dataclasses import dataclass
from typing import Any

from .errors import ValidationError
from .escape import printable

#: longest name [characters] (pins, discs, campaigns, instruments, a map's ids)
MAX_NAME_CHARS = 200
#: longest free text [characters] (a map's reasons, flags, file names, methods)
MAX_TEXT_CHARS = 4096
#: Unicode categories a name may not hold: controls, format characters (bidi overrides,
#: zero-width joiners), surrogates, private use, unassigned, line and paragraph separators
_FORBIDDEN_CATEGORIES = frozenset({"Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp"})


@dataclass(frozen=True)
class Range:
    """A closed (or, with ``low_open``, half-open) interval of physical values in ``unit``."""

    low: float
    high: float
    unit: str = ""
    low_open: bool = False

    def __contains__(self, value: object) -> bool:
        if not isinstance(value, int | float) or isinstance(value, bool):
            return False
        if not math.isfinite(value):
            return False
        above = value > self.low if self.low_open else value >= self.low
        return above and value <= self.high

    def describe(self) -> str:
        """``"> 0 and <= 100000 N"`` style text for a message."""
        unit = f" {self.unit}" if self.unit else ""
        low = ">" if self.low_open else ">="
        return f"{low} {self.low:g}{unit} and <= {self.high:g}{unit}"


#: nominal or measured total normal force [N]: positive, at most 100 kN
FORCE_N = Range(0.0, 1e5, "N", low_open=True)
#: contact pressure [kPa]: positive, finite (it follows from force and pin radius)
PRESSURE_KPA = Range(0.0, 1e12, "kPa", low_open=True)
#: nominal or measured temperature [°C]: above absolute zero, at most 3000 °C
TEMPERATURE_C = Range(-273.15, 3000.0, "°C", low_open=True)
#: a coefficient of friction: 0 to 10 (the highest dry friction of soft elastomers,
#: adhesion-dominated on smooth glass, is a few units; beyond 10 a force in mN was read
#: as N, or a torque column is something else)
MU = Range(0.0, 10.0)
#: radius of one pin [mm]
PIN_RADIUS_MM = Range(0.01, 500.0, "mm")
#: friction radius of the cell [mm]
FRICTION_RADIUS_MM = Range(0.1, 1000.0, "mm")
#: nominal disc speed [rpm]
SPEED_RPM = Range(1e-6, 1e5, "rpm")
#: a sliding speed [mm/s]: positive (a friction run slides)
SLIDING_SPEED_MM_S = Range(0.0, 1e6, "mm/s", low_open=True)
#: a repeat number within a condition
MAX_REPEAT = 1_000_000


def _fail(problem: str, path: str | os.PathLike[str] | None, line: int | None,
          column: str | None) -> ValidationError:
    return ValidationError(problem, path=path, line=line, column=column)


def _shown(value: Any, limit: int = 60) -> str:
    """A value for a message: its repr, shortened, one printable line."""
    if isinstance(value, str) and len(value) > limit:
        return printable(repr(value[:limit])) + f"… ({len(value)} characters)"
    text = printable(repr(value))
    return text if len(text) <= limit + 10 else text[: limit + 10] + "…"


def text_problem(value: Any, max_chars: int = MAX_TEXT_CHARS) -> str | None:
    """Why ``value`` is not one line of printable text of at most ``max_chars``
    characters (blank allowed), or ``None`` when it is."""
    if not isinstance(value, str):
        return f"expected text, got {type(value).__name__}"
    if len(value) > max_chars:
        return f"expected at most {max_chars} characters, got {len(value)}"
    if not value.isprintable():
        for ch in value:
            if unicodedata.category(ch) in _FORBIDDEN_CATEGORIES:
                return (f"expected one line of printable text, got the character "
                        f"{printable(repr(ch))} (U+{ord(ch):04X})")
    return None


def file_name_problem(value: Any, max_chars: int = MAX_TEXT_CHARS) -> str | None:
    """Why ``value`` is not a file name as the map keeps it (module docstring), or ``None``
    when it is. Bytes of a name that were not UTF-8 are kept as ``\\xNN`` text (see
    :func:`tribopipe.frictionmap.records.stored_file_name`), never as lone surrogates."""
    if not isinstance(value, str):
        return f"expected text, got {type(value).__name__}"
    if len(value) > max_chars:
        return f"expected at most {max_chars} characters, got {len(value)}"
    found = _NOT_IN_FILE_NAMES.search(value)
    if found is not None:
        ch = found.group()
        return (f"expected a file name, got the character {printable(repr(ch))} "
                f"(U+{ord(ch):04X})")
    return None


#: the characters a file name as the map keeps it never holds: NUL and lone surrogates
_NOT_IN_FILE_NAMES = re.compile("[\x00\ud800-\udfff]")


def name_problem(value: Any) -> str | None:
    """Why ``value`` is not a name (see the module docstring), or ``None`` when it is."""
    if isinstance(value, str) and not value.strip():
        return "expected a name, got blank text"
    return text_problem(value, MAX_NAME_CHARS)


def check_name(value: Any, what: str, *, path: str | os.PathLike[str] | None = None,
               line: int | None = None, column: str | None = None) -> str:
    """``value`` when it is a name (module docstring); else :class:`ValidationError`
    naming ``what`` (e.g. ``"pin"``, ``"[campaign] name"``)."""
    problem = name_problem(value)
    if problem is not None:
        raise _fail(f"{what}: {problem} ({_shown(value)})", path, line, column)
    return value


def is_number(value: Any) -> bool:
    """True for an ``int`` or ``float`` (NumPy's included), never for a ``bool``."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool | str) and \
        type(value).__name__ not in ("bool_", "bool")


def check_number(value: Any, bounds: Range, what: str, *,
                 path: str | os.PathLike[str] | None = None, line: int | None = None,
                 column: str | None = None) -> float:
    """``float(value)`` when it is a number (not a bool) inside ``bounds``; else
    :class:`ValidationError` naming ``what`` and the expected range."""
    if not is_number(value):
        raise _fail(f"{what}: expected a number {bounds.describe()}, got {_shown(value)}",
                    path, line, column)
    number = float(value)
    if number not in bounds:
        raise _fail(f"{what}: expected a number {bounds.describe()}, got {_shown(value)}",
                    path, line, column)
    return number


def check_count(value: Any, what: str, *, low: int = 0, high: int = MAX_REPEAT,
                path: str | os.PathLike[str] | None = None, line: int | None = None,
                column: str | None = None) -> int:
    """``value`` when it is a whole number (an ``int``, never a ``bool`` or a float) in
    ``low … high``; else :class:`ValidationError` naming ``what``."""
    if not isinstance(value, numbers.Integral) or isinstance(value, bool) or \
            type(value).__name__ == "bool_":
        raise _fail(f"{what}: expected a whole number from {low} to {high}, got "
                    f"{_shown(value)}", path, line, column)
    number = int(value)
    if not low <= number <= high:
        raise _fail(f"{what}: expected a whole number from {low} to {high}, got {number}",
                    path, line, column)
    return number

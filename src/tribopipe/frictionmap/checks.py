"""Checks of map rows that come from elsewhere: physical ranges, duplicate ids, provenance
and text that could turn into something else in a spreadsheet or a file we write.

:func:`validate_runs` looks at a whole map DataFrame (the schema's dtypes, as
:func:`~tribopipe.frictionmap.schema.records_frame` builds it) and returns every problem,
one :class:`RowProblem` per row and field, instead of stopping at the first. It is what
``tribopipe map validate`` and a merge of another lab's data package run on the rows
(:mod:`tribopipe.frictionmap.package`); it is written as the one place for row checks of
imported and merged data, so a stricter version can replace it without touching its
callers.

The ranges are physics, not habits of our fixtures (each with its reason in
:data:`RANGES`): a normal force, a contact pressure and a sliding speed of a run in contact
are positive; a coefficient of friction is a ratio of magnitudes, so at least 0, and above
:data:`MU_MAX` it is a column or unit mix-up rather than any dry friction of an elastomer;
no temperature lies at or below absolute zero; distances, times, the plateau's SD, repeat
and interval numbers are not negative; a window does not end before it starts; no stored
number is infinite. Every rule of :func:`~tribopipe.frictionmap.schema.check_runs` (the
rules every map row keeps, on every read and write: names one printable line of at most
200 characters, upper bounds from :mod:`tribopipe.validate`) is checked here too, so rows
that pass here are rows the map accepts.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from datetime import datetime
from typing import TYPE_CHECKING, Any

from ..escape import FORMULA_TRIGGERS
from ..validate import MU, TEMPERATURE_C, name_problem, text_problem
from .schema import (
    _KIND,
    COLUMN_RANGES,
    COUNT_RANGES,
    NAME_COLUMNS,
    REQUIRED,
    RUN_COLUMNS,
    SOURCE_REDUCED,
    _missing,
)

if TYPE_CHECKING:
    import pandas as pd

#: A kinetic or static coefficient above this is refused as implausible: the highest dry
#: friction coefficients reported for soft elastomers (adhesion-dominated, on smooth glass)
#: are a few units; 10 leaves room for them and still catches a force in mN read as N.
MU_MAX = MU.high
#: Absolute zero [°C]: a temperature at or below it is not a temperature.
ABSOLUTE_ZERO_C = TEMPERATURE_C.low

#: field → (lowest allowed, whether the lowest is allowed itself, highest or None, reason)
RANGES: dict[str, tuple[float, bool, float | None, str]] = {
    "normal_force_N": (0.0, False, None, "a run in contact presses the pins on the disc"),
    "pressure_kPa": (0.0, False, None, "a run in contact has a positive contact pressure"),
    "normal_force_measured_N": (0.0, False, None,
                                "a run in contact presses the pins on the disc"),
    "pressure_measured_kPa": (0.0, False, None,
                              "a run in contact has a positive contact pressure"),
    "temperature_C": (ABSOLUTE_ZERO_C, False, None, "nothing is colder than absolute zero"),
    "temperature_measured_C": (ABSOLUTE_ZERO_C, False, None,
                               "nothing is colder than absolute zero"),
    "sliding_speed_mm_s": (0.0, False, None, "a friction run slides"),
    "repeat": (0.0, True, None, "repeat numbers count up from 0 or 1"),
    "mu_s": (0.0, True, MU_MAX, "a coefficient of friction is a ratio of magnitudes"),
    "mu_k": (0.0, True, MU_MAX, "a coefficient of friction is a ratio of magnitudes"),
    "mu_s_distance_mm": (0.0, True, None, "sliding distance from the start of sliding"),
    "mu_s_time_s": (0.0, True, None, "time from the start of the interval"),
    "mu_k_window_start_mm": (0.0, True, None, "sliding distance from the start of sliding"),
    "mu_k_window_end_mm": (0.0, True, None, "sliding distance from the start of sliding"),
    "mu_k_window_start_s": (0.0, True, None, "time from the start of the interval"),
    "mu_k_window_end_s": (0.0, True, None, "time from the start of the interval"),
    "plateau_std": (0.0, True, None, "a standard deviation is not negative"),
    "u_mu_s": (0.0, True, None, "a standard uncertainty is not negative"),
    "u_mu_k": (0.0, True, None, "a standard uncertainty is not negative"),
    "interval": (0.0, True, None, "interval numbers count up from 0 or 1"),
}
#: (start, end) columns of a window that must not end before it starts
WINDOWS: tuple[tuple[str, str], ...] = (
    ("mu_k_window_start_mm", "mu_k_window_end_mm"),
    ("mu_k_window_start_s", "mu_k_window_end_s"),
)
#: a spreadsheet runs a cell starting with one of these as a formula
FORMULA_START = tuple(sorted(FORMULA_TRIGGERS))
_CONTROL = re.compile(r"[\x00-\x1f\x7f\u2028\u2029]")
_SHA256 = re.compile(r"[0-9a-f]{64}")
_CONFIG_HASH = re.compile(r"[0-9a-f]{16}")


@dataclass(frozen=True)
class RowProblem:
    """One problem of one row: ``row`` counts from 1 in the order given, ``field`` is the
    column, ``problem`` says what is wrong and what was expected."""

    row: int
    measurement_id: str | None
    field: str
    problem: str

    def line(self, where: str) -> str:
        """``<where>: row <row>, field <field>: <problem>`` (one line)."""
        return f"{where}: row {self.row}, field {self.field}: {self.problem}"


def _number(value: Any) -> str:
    return repr(float(value)) if isinstance(value, float) else str(value)


def validate_runs(runs: pd.DataFrame, *, require_lab: bool = False) -> list[RowProblem]:
    """Every problem of the map rows ``runs`` (map dtypes, columns :data:`RUN_COLUMNS`),
    in row order: values outside :data:`RANGES`, infinite numbers, windows that end before
    they start, a ``measurement_id`` seen in an earlier row, missing or malformed provenance
    (``source_file``, a SHA-256 ``file_hash``, ``tribopipe_version``, an ISO 8601
    ``reduced_at``; for reduced rows also ``method`` and a 16-digit ``config_hash``; the
    ``lab`` when ``require_lab``), and text with control characters or starting like a
    spreadsheet formula; and what :func:`~tribopipe.frictionmap.schema.records_frame`
    requires (id, source, pin, disc and a finite μ_K in every row, μ_S in reduced rows).
    An empty list means the rows pass. ``runs`` is not modified."""
    problems: list[RowProblem] = []
    rows = runs.loc[:, list(RUN_COLUMNS)].to_dict(orient="records")
    seen: dict[str, int] = {}
    for i, row in enumerate(rows, 1):
        mid = row["measurement_id"] if isinstance(row["measurement_id"], str) else None

        def add(field: str, problem: str, i: int = i, mid: str | None = mid) -> None:
            problems.append(RowProblem(i, mid, field, problem))

        for name in ("measurement_id", "source", "pin", "disc", *sorted(REQUIRED)):
            if _missing(row[name]) or not str(row[name]).strip():
                add(name, "missing, expected a value in every row")
        if row["source"] == SOURCE_REDUCED and _missing(row["mu_s"]):
            add("mu_s", "missing; only imported rows may lack mu_s")
        if mid is not None:
            if mid in seen:
                add("measurement_id", f"duplicate id {mid} (first in row {seen[mid]})")
            else:
                seen[mid] = i
        for name in RUN_COLUMNS:
            value = row[name]
            if _missing(value):
                continue
            if _KIND[name] == "float" and math.isinf(float(value)):
                add(name, f"{_number(value)} is not a finite number")
                continue
            if name in RANGES:
                _check_range(name, float(value), add)
            _check_bound(name, value, add)
            if _KIND[name] == "str":
                _check_text(name, str(value), add)
        for start, end in WINDOWS:
            a, b = row[start], row[end]
            if not (_missing(a) or _missing(b)) and float(b) < float(a):
                add(end, f"{_number(b)} ends before the window's start {_number(a)}")
        _check_provenance(row, add, require_lab)
    return problems


def _check_range(name: str, value: float, add: Any) -> None:
    low, inclusive, high, reason = RANGES[name]
    if value < low or (value == low and not inclusive):
        expected = f"at least {low:g}" if inclusive else f"above {low:g}"
        add(name, f"{_number(value)} is out of range, expected {expected} ({reason})")
    elif high is not None and value > high:
        add(name, f"{_number(value)} is out of range, expected at most {high:g} ({reason})")


def _check_bound(name: str, value: Any, add: Any) -> None:
    """The upper bounds every map row keeps (:func:`~tribopipe.frictionmap.schema.check_runs`:
    no force, pressure, temperature or count beyond any measurement), where
    :data:`RANGES` sets none."""
    if name in COLUMN_RANGES and (name not in RANGES or RANGES[name][2] is None):
        high = COLUMN_RANGES[name].high
        if math.isfinite(float(value)) and float(value) > high:
            add(name, f"{_number(value)} is out of range, expected at most {high:g}")
    elif name in COUNT_RANGES and int(value) > COUNT_RANGES[name][1]:
        add(name, f"{value} is out of range, expected at most {COUNT_RANGES[name][1]}")


def _check_text(name: str, text: str, add: Any) -> None:
    problem = name_problem(text) if name in NAME_COLUMNS else text_problem(text)
    if _CONTROL.search(text):
        add(name, "contains a control character or line break, expected one line of text")
    elif problem is not None:
        add(name, problem)
    elif text.startswith(FORMULA_START):
        add(name, f"starts with {text[0]!r}, which a spreadsheet runs as a formula")


def _check_provenance(row: dict[str, Any], add: Any, require_lab: bool) -> None:
    def absent(name: str) -> bool:
        value = row[name]
        return _missing(value) or not str(value).strip()

    if require_lab and absent("lab"):
        add("lab", "missing, expected the laboratory that measured the run")
    for name in ("source_file", "tribopipe_version"):
        if absent(name):
            add(name, "missing, expected provenance of the row")
    if absent("file_hash"):
        add("file_hash", "missing, expected the SHA-256 of the source file")
    elif not _SHA256.fullmatch(str(row["file_hash"])):
        add("file_hash", "expected 64 lowercase hexadecimal digits (SHA-256)")
    if absent("reduced_at"):
        add("reduced_at", "missing, expected the UTC time of reduction or import")
    elif not _iso_time(str(row["reduced_at"])):
        add("reduced_at", f"{row['reduced_at']!r} is not an ISO 8601 time")
    if row["source"] == SOURCE_REDUCED:
        if absent("method"):
            add("method", "missing, expected the reduction method of a reduced run")
        if absent("config_hash"):
            add("config_hash", "missing, expected the settings hash of a reduced run")
        elif not _CONFIG_HASH.fullmatch(str(row["config_hash"])):
            add("config_hash", "expected 16 lowercase hexadecimal digits")


def _iso_time(text: str) -> bool:
    try:
        datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        return False
    return True

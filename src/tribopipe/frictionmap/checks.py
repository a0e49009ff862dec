"""Checks of map rows that come from elsewhere: physical ranges, duplicate ids, provenance
and text that could turn into something else in a spreadsheet or a file we write.

:func:`validate_runs` looks at a whole map DataFrame (the schema's dtypes, as
:func:`~tribopipe.frictionmap.schema.records_frame` builds it) and returns every problem,
one :class:`RowProblem` per row and field, instead of stopping at the first. It is what
``tribopipe map validate`` and a merge of another lab's data package run on the rows
(:mod:`tribopipe.frictionmap.package`); it is written as the one place for row checks of
imported and merged data, so a stricter version can replace it without touching its
callers.

The ranges and the required columns are those of the one table of row rules,
:data:`tribopipe.frictionmap.schema.COLUMNS` (each range with its reason), which the
store's :func:`~tribopipe.frictionmap.schema.check_runs` keeps too: rows that pass here
are rows the map accepts (a file's own name, ``source_file``, kept raw). Beyond it, this
checks what a row from elsewhere must also show: a window that does not end before it
starts, a unique id, provenance, and text that is one line and does not start like a
spreadsheet formula.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from datetime import datetime
from typing import TYPE_CHECKING, Any, cast

from ..escape import FORMULA_TRIGGERS, printable
from ..validate import file_name_problem, name_problem, text_problem
from .schema import (
    ALWAYS,
    CHOICES,
    COLUMNS,
    FILE_NAME_COLUMNS,
    IN_PACKAGES,
    IN_REDUCED_ROWS,
    NAME_COLUMNS,
    RUN_COLUMNS,
    SOURCE_REDUCED,
    Column,
    is_missing,
)

if TYPE_CHECKING:
    import pandas as pd

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
    in row order: what the table of row rules (:data:`~tribopipe.frictionmap.schema.COLUMNS`)
    requires (its required columns, with those required in packages, i.e. ``lab``, when
    ``require_lab``; its bounds; finite numbers; names and one-line texts), windows that
    end before they start, a ``measurement_id`` seen in an earlier row, missing or
    malformed provenance (``source_file``, a SHA-256 ``file_hash``, ``tribopipe_version``,
    an ISO 8601 ``reduced_at``; for reduced rows also ``method`` and a 16-digit
    ``config_hash``), and text with control characters or starting like a spreadsheet
    formula. An empty list means the rows pass. ``runs`` is not modified."""
    problems: list[RowProblem] = []
    rows = cast("list[dict[str, Any]]", runs.loc[:, list(RUN_COLUMNS)].to_dict(orient="records"))
    seen: dict[str, int] = {}
    for i, row in enumerate(rows, 1):
        mid = row["measurement_id"] if isinstance(row["measurement_id"], str) else None

        def add(field: str, problem: str, i: int = i, mid: str | None = mid) -> None:
            problems.append(RowProblem(i, mid, field, problem))

        for column in COLUMNS:
            name = column.name
            if column.required == ALWAYS and (
                    is_missing(row[name]) or not str(row[name]).strip()):
                add(name, "missing, expected a value in every row")
            elif (column.required == IN_REDUCED_ROWS and row["source"] == SOURCE_REDUCED
                  and is_missing(row[name])):
                add(name, f"missing; only imported rows may lack {name}")
            elif column.required == IN_PACKAGES and require_lab and (
                    is_missing(row[name]) or not str(row[name]).strip()):
                add(name, "missing, expected a value in every row of a data package")
        if mid is not None:
            if mid in seen:
                add("measurement_id", f"duplicate id {mid} (first in row {seen[mid]})")
            else:
                seen[mid] = i
        for column in COLUMNS:
            name, value = column.name, row[column.name]
            if is_missing(value):
                continue
            if column.kind == "float" and math.isinf(float(value)):
                add(name, f"{_number(value)} is not a finite number")
                continue
            if column.bounds is not None:
                _check_range(column, value, add)
            if column.kind == "str":
                _check_text(name, str(value), add)
        for start, end in WINDOWS:
            a, b = row[start], row[end]
            if not (is_missing(a) or is_missing(b)) and float(b) < float(a):
                add(end, f"{_number(b)} ends before the window's start {_number(a)}")
        _check_provenance(row, add)
    return problems


def _check_range(column: Column, value: Any, add: Any) -> None:
    """A number outside its column's bounds, said with the bound and the reason."""
    assert column.bounds is not None
    low, high, number = column.bounds.low, column.bounds.high, float(value)
    reason = f" ({column.reason})" if column.reason else ""
    if number < low or (number == low and column.bounds.low_open):
        expected = f"above {low:g}" if column.bounds.low_open else f"at least {low:g}"
        add(column.name, f"{_number(value)} is out of range, expected {expected}{reason}")
    elif number > high:
        add(column.name, f"{_number(value)} is out of range, expected at most {high:g}"
            f"{reason}")


def _check_text(name: str, text: str, add: Any) -> None:
    if name in FILE_NAME_COLUMNS:
        problem = file_name_problem(text)
    else:
        problem = name_problem(text) if name in NAME_COLUMNS else text_problem(text)
    if name not in FILE_NAME_COLUMNS and _CONTROL.search(text):
        add(name, "contains a control character or line break, expected one line of text")
    elif problem is not None:
        add(name, problem)
    elif CHOICES.get(name) and text not in CHOICES[name]:
        add(name, f"{printable(text)[:60]!r} is not one of "
            + ", ".join(repr(c) for c in CHOICES[name]))
    elif text.startswith(FORMULA_START):
        add(name, f"starts with {text[0]!r}, which a spreadsheet runs as a formula")


def _check_provenance(row: dict[str, Any], add: Any) -> None:
    def absent(name: str) -> bool:
        value = row[name]
        return is_missing(value) or not str(value).strip()

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

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
from typing import TYPE_CHECKING, Any

from ..escape import FORMULA_TRIGGERS, printable
from ..validate import file_name_problem, name_problem, text_problem
from .schema import (
    ALWAYS,
    CHOICES,
    COLUMNS,
    FILE_NAME_COLUMNS,
    IN_PACKAGES,
    IN_REDUCED_ROWS,
    KIND,
    NAME_COLUMNS,
    SOURCE_REDUCED,
    Column,
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
    formula. An empty list means the rows pass. ``runs`` is not modified.

    The checks run column by column (a text is checked once per distinct value), so the
    cost and the memory grow with the rows' columns, not with a copy of every row; the
    problems come out as a row-by-row reading finds them: by row, then in the order of
    the checks (required values, the id, each column's value, the windows, provenance)."""
    import numpy as np

    found: list[tuple[int, int, str, str]] = []  # (position, check order, field, problem)
    n = len(runs)
    ids = runs["measurement_id"]
    reduced = np.asarray(runs["source"].eq(SOURCE_REDUCED).fillna(False), dtype=bool)
    missing = {c.name: np.asarray(runs[c.name].isna(), dtype=bool) for c in COLUMNS}

    def blank(name: str) -> Any:
        """Missing, or text that is empty or white space only."""
        out = missing[name].copy()
        if KIND[name] == "str":
            out |= np.asarray(runs[name].str.strip().eq("").fillna(False), dtype=bool)
        return out

    def add_rows(rows: Any, order: int, field: str, problem: str | Any) -> None:
        for i in np.flatnonzero(rows):
            found.append((int(i), order, field,
                          problem if isinstance(problem, str) else problem(int(i))))

    for k, column in enumerate(COLUMNS):  # order 0…: required values
        name = column.name
        if column.required == ALWAYS:
            add_rows(blank(name), k, name, "missing, expected a value in every row")
        elif column.required == IN_REDUCED_ROWS:
            add_rows(reduced & missing[name], k, name,
                     f"missing; only imported rows may lack {name}")
        elif column.required == IN_PACKAGES and require_lab:
            add_rows(blank(name), k, name,
                     "missing, expected a value in every row of a data package")
    # an id seen in an earlier row: only the ids that repeat are looked at one by one
    id_texts = ids.astype(str)
    repeated = np.flatnonzero(np.asarray(id_texts.duplicated(keep=False), dtype=bool)
                              & ~missing["measurement_id"])
    first: dict[str, int] = {}
    for i, mid in zip(repeated.tolist(), id_texts.iloc[repeated].tolist(), strict=True):
        if mid in first:
            found.append((i, 1000, "measurement_id",
                          f"duplicate id {mid} (first in row {first[mid] + 1})"))
        else:
            first[mid] = i
    for k, column in enumerate(COLUMNS):  # order 2000…: each column's values
        _check_column(runs, column, ~missing[column.name], 2000 + k, found)
    for k, (start, end) in enumerate(WINDOWS):  # order 3000…: windows
        a = np.asarray(runs[start], dtype=float)
        b = np.asarray(runs[end], dtype=float)
        with np.errstate(invalid="ignore"):
            bad = ~np.isnan(a) & ~np.isnan(b) & (b < a)
        add_rows(bad, 3000 + k, end,
                 lambda i, a=a, b=b, end=end: f"{_number(float(b[i]))} ends before the "
                 f"window's start {_number(float(a[i]))}")
    _provenance(runs, blank, reduced, found)
    found.sort(key=lambda p: (p[0], p[1]))
    return [RowProblem(i + 1, _id_of(ids.iat[i]), field, problem)
            for i, _, field, problem in found if i < n]


def _id_of(value: Any) -> str | None:
    """A row's ``measurement_id`` as a problem names it (``None`` when it is no text)."""
    return value if isinstance(value, str) else None


def _check_column(runs: pd.DataFrame, column: Column, present: Any, order: int,
                  found: list[tuple[int, int, str, str]]) -> None:
    """The value checks of one column (present values only): a finite number inside its
    bounds, a text of its kind."""
    import numpy as np
    import pandas as pd

    name = column.name
    if column.kind in ("float", "int"):
        values = np.asarray(pd.to_numeric(runs[name]).astype("float64").to_numpy(
            na_value=np.nan), dtype=float)
        # the rows worth a look: not finite, or outside the bounds (a comparison with
        # NaN is false, so those are looked at too); the others pass
        with np.errstate(invalid="ignore"):
            inside = np.isfinite(values) if column.kind == "float" else ~np.isnan(values)
            if column.bounds is not None:
                b = column.bounds
                inside &= (values > b.low if b.low_open else values >= b.low)
                inside &= values <= b.high
        look = np.flatnonzero(present & ~inside)
        raw = runs[name].iloc[look].tolist()
        for i, value in zip(look.tolist(), raw, strict=True):
            number = values[i]
            if column.kind == "float" and math.isinf(number):
                found.append((int(i), order, name, f"{_number(value)} is not a finite number"))
                continue
            if column.bounds is not None:
                _check_range(column, value,
                             lambda f, p, i=int(i): found.append((i, order, f, p)))
    elif column.kind == "str":
        codes, uniques = pd.factorize(runs[name])
        problems: dict[int, str] = {}
        for u, text in enumerate(uniques.tolist()):
            _check_text(name, str(text), lambda f, p, u=u: problems.setdefault(u, p))
        if problems:
            for j in np.flatnonzero(np.isin(codes, list(problems)) & present).tolist():
                found.append((j, order, name, problems[int(codes[j])]))


def _provenance(runs: pd.DataFrame, blank: Any, reduced: Any,
                found: list[tuple[int, int, str, str]]) -> None:
    """The provenance checks, column-wise, in the order a row-by-row reading makes them
    (order 4000…)."""
    import numpy as np

    def add(rows: Any, order: int, field: str, problem: Any) -> None:
        for i in np.flatnonzero(rows):
            found.append((int(i), 4000 + order, field,
                          problem if isinstance(problem, str) else problem(int(i))))

    def malformed(name: str, ok: Any) -> Any:
        """Rows whose present value of ``name`` fails ``ok`` (checked once per value)."""
        import pandas as pd

        codes, uniques = pd.factorize(runs[name])
        bad = [u for u, text in enumerate(uniques.tolist()) if not ok(str(text))]
        return np.isin(codes, bad) & (codes >= 0)

    for k, name in enumerate(("source_file", "tribopipe_version")):
        add(blank(name), k, name, "missing, expected provenance of the row")
    absent = blank("file_hash")
    add(absent, 2, "file_hash", "missing, expected the SHA-256 of the source file")
    add(~absent & malformed("file_hash", lambda t: _SHA256.fullmatch(t) is not None), 2,
        "file_hash", "expected 64 lowercase hexadecimal digits (SHA-256)")
    absent = blank("reduced_at")
    add(absent, 3, "reduced_at", "missing, expected the UTC time of reduction or import")
    times = runs["reduced_at"]
    add(~absent & malformed("reduced_at", _iso_time), 3, "reduced_at",
        lambda i: f"{times.iat[i]!r} is not an ISO 8601 time")
    add(reduced & blank("method"), 4, "method",
        "missing, expected the reduction method of a reduced run")
    absent = blank("config_hash")
    add(reduced & absent, 5, "config_hash",
        "missing, expected the settings hash of a reduced run")
    add(reduced & ~absent & malformed("config_hash",
                                      lambda t: _CONFIG_HASH.fullmatch(t) is not None),
        5, "config_hash", "expected 16 lowercase hexadecimal digits")


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


def _iso_time(text: str) -> bool:
    try:
        datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        return False
    return True

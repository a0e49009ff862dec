"""The row checks run column by column and give what a row-by-row reading gives.

:func:`tribopipe.frictionmap.checks.validate_runs` checks each column at once (a text once
per distinct value) so that a package of 10⁵ rows is checked without a copy of every row.
This holds it equal, problem for problem and in the same order, to the row-by-row
reading it replaced (kept here, as it was, as the reference), on real rows — the founding
paper's published rows and really reduced ones — with seeded faults in every column."""

from __future__ import annotations

import math
import random
from typing import Any, cast

import numpy as np
import pandas as pd
import pytest

from published_map import PUBLISHED_CSV, published_runs
from reduced_runs import make_processed
from tribopipe import frictionmap as fm
from tribopipe.frictionmap.checks import (
    _CONFIG_HASH,
    _SHA256,
    WINDOWS,
    RowProblem,
    _check_range,
    _check_text,
    _iso_time,
    _number,
    validate_runs,
)
from tribopipe.frictionmap.schema import (
    ALWAYS,
    COLUMNS,
    IN_PACKAGES,
    IN_REDUCED_ROWS,
    KIND,
    RUN_COLUMNS,
    SOURCE_REDUCED,
    is_missing,
)


def reference(runs: pd.DataFrame, *, require_lab: bool = False) -> list[RowProblem]:
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


#: a faulty value of each kind: (kind, values to try)
FAULTS: dict[str, list[Any]] = {
    "float": [math.inf, -math.inf, -1.0, 1e12, -300.0, None, 0.0],
    "int": [-1, 0, 10**9, None],
    "bool": [True, False],
    "str": [None, "", "  ", "=SUM(A1)", "line\nbreak", "tab\there", "+1", "x" * 300,
            "\u2028", "ok text", "not-a-hash", "2026-13-45", "abc123"],
}


@pytest.fixture(scope="module")
def rows(tmp_path_factory) -> pd.DataFrame:
    reduced, _ = make_processed(tmp_path_factory.mktemp("rows"))
    return pd.concat([fm.read_map(reduced), published_runs(PUBLISHED_CSV)],
                     ignore_index=True)


def faulty(rows: pd.DataFrame, seed: int, n_faults: int) -> pd.DataFrame:
    """``rows`` with ``n_faults`` seeded faults (a cell of any column set to a faulty
    value of its kind, or an id repeated), as unvalidated map rows."""
    rng = random.Random(seed)
    records = fm.schema.frame_records(rows)
    for _ in range(n_faults):
        i = rng.randrange(len(records))
        if rng.random() < 0.1:
            records[i]["measurement_id"] = records[rng.randrange(len(records))][
                "measurement_id"]
            continue
        name = rng.choice(RUN_COLUMNS)
        records[i][name] = rng.choice(FAULTS[KIND[name]])
    return fm.schema.unvalidated_frame(records, where="row")


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("require_lab", [False, True])
def test_column_wise_checks_equal_the_row_by_row_reading(rows, seed, require_lab):
    frame = faulty(rows, seed, n_faults=5 + 40 * seed)
    expected = reference(frame, require_lab=require_lab)
    assert expected  # the faults are seen
    assert validate_runs(frame, require_lab=require_lab) == expected


def test_clean_rows_pass_both(rows):
    assert validate_runs(rows) == reference(rows) == []
    assert not np.all(rows["lab"].isna())

"""One table of row rules (``frictionmap.schema.COLUMNS``): the store's row check, the
package validator and the ``datapackage.json`` constraints all say what it says.

Each bounded column is tried just inside and just outside each of its bounds in an
otherwise valid row; each required column is tried missing. The store's check
(``records_frame``) and the validator (``validate_runs``) must agree with the table and
with each other, and the Table Schema field of every column must state the table's type,
unit, bounds and requirement.
"""

from __future__ import annotations

import math
from typing import Any

import pytest

from tribopipe.errors import MapError
from tribopipe.frictionmap.checks import validate_runs
from tribopipe.frictionmap.datapackage import TABLE_TYPES, runs_fields
from tribopipe.frictionmap.schema import (
    ALWAYS,
    COLUMNS,
    IN_PACKAGES,
    IN_REDUCED_ROWS,
    SOURCE_REDUCED,
    Column,
    MapRow,
    frame_rows,
    records_frame,
)


def valid_record() -> dict[str, Any]:
    """A reduced run that keeps every rule (values inside every bound)."""
    record: dict[str, Any] = {}
    for c in COLUMNS:
        if c.kind == "str":
            record[c.name] = c.choices[0] if c.choices else "x"
        elif c.kind == "bool":
            record[c.name] = False
        elif c.kind == "int":
            record[c.name] = 1
        else:
            record[c.name] = 0.5 if c.bounds is None else min(max(c.bounds.low, 0) + 0.5,
                                                             c.bounds.high)
    record.update(source=SOURCE_REDUCED, file_hash="a" * 64, config_hash="b" * 16,
                  reduced_at="2026-11-25T08:00:00Z", method="tribopipe-v2", flags="",
                  mu_k_window_start_mm=0.5, mu_k_window_end_mm=0.5,
                  mu_k_window_start_s=0.5, mu_k_window_end_s=0.5)
    return record


def store_accepts(record: dict[str, Any]) -> bool:
    try:
        records_frame([record])
    except MapError:
        return False
    return True


def validator_problems(record: dict[str, Any], column: str) -> list[str]:
    runs = records_frame([valid_record()])
    runs.loc[0, column] = record[column]  # past the store's check: the rows as read
    # (a window ending before its start is a rule between two columns, not the table's)
    return [p.problem for p in validate_runs(runs, require_lab=True)
            if p.field == column and "ends before the window's start" not in p.problem]


def test_the_valid_record_passes_both_checks() -> None:
    record = valid_record()
    assert store_accepts(record)
    assert validate_runs(records_frame([record]), require_lab=True) == []


def edge_cases(c: Column) -> list[tuple[float, bool]]:
    """(value, allowed) pairs at and beyond ``c``'s bounds."""
    assert c.bounds is not None
    low, high = c.bounds.low, c.bounds.high
    step = 1 if c.kind == "int" else max(abs(high), 1.0) * 1e-9
    below = low - 1 if c.kind == "int" else math.nextafter(low, -math.inf)
    return [(low, not c.bounds.low_open), (below, False), (high, True),
            (high + step, False)]


BOUNDED = [c for c in COLUMNS if c.bounds is not None]


@pytest.mark.parametrize("column", BOUNDED, ids=[c.name for c in BOUNDED])
def test_store_and_validator_keep_the_tables_bounds(column: Column) -> None:
    for value, allowed in edge_cases(column):
        record = {**valid_record(), column.name: value}
        assert store_accepts(record) is allowed, (column.name, value)
        if column.kind == "float":  # (an int column's dtype cannot hold the value past it)
            assert (validator_problems(record, column.name) == []) is allowed, (
                column.name, value)


REQUIRED = [c for c in COLUMNS if c.required and c.kind != "bool"]


@pytest.mark.parametrize("column", REQUIRED, ids=[c.name for c in REQUIRED])
def test_a_required_column_missing_is_refused_where_the_table_says(column: Column) -> None:
    record = {**valid_record(), column.name: None}
    in_the_store = column.required in (ALWAYS, IN_REDUCED_ROWS)
    assert store_accepts(record) is not in_the_store
    assert validator_problems(record, column.name) != []
    imported = {**record, "source": "imported:lab"}
    if column.required == IN_REDUCED_ROWS:
        assert store_accepts(imported)
    if column.required == IN_PACKAGES:
        runs = records_frame([imported])
        assert not [p for p in validate_runs(runs) if p.field == column.name]


def test_the_datapackage_constraints_equal_the_table() -> None:
    fields = {f["name"]: f for f in runs_fields()}
    assert list(fields) == [c.name for c in COLUMNS]
    for c in COLUMNS:
        f = fields[c.name]
        want_type = "datetime" if c.name == "reduced_at" else TABLE_TYPES[c.kind]
        assert f["type"] == want_type, c.name
        assert f.get("unit", "") == c.unit, c.name
        constraints = f.get("constraints", {})
        assert constraints.get("required", False) is (c.required in (ALWAYS, IN_PACKAGES))
        if c.bounds is None:
            assert "minimum" not in constraints and "maximum" not in constraints, c.name
        else:
            assert (constraints["minimum"], constraints["maximum"]) == (
                c.bounds.low, c.bounds.high), c.name


def test_the_row_type_is_the_table_of_row_rules() -> None:
    """``MapRow`` has one field per column, in the table's order, of its kind, optional
    exactly where the table lets the column be missing; a drift fails at import."""
    import dataclasses

    from tribopipe.frictionmap import schema

    row_fields = [f for f in dataclasses.fields(MapRow) if f.init]
    assert [f.name for f in row_fields] == [c.name for c in COLUMNS]
    for f, c in zip(row_fields, COLUMNS, strict=True):
        optional = c.required != ALWAYS and c.kind != "bool"
        assert f.type == {"str": "str", "float": "float", "int": "int",
                          "bool": "bool"}[c.kind] + (" | None" if optional else "")
    drifted = (*COLUMNS, Column("spare_N", "float", "N", "a column the row type lacks"))
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(schema, "COLUMNS", drifted)
        mp.setattr(schema, "RUN_COLUMNS", tuple(c.name for c in drifted))
        with pytest.raises(AssertionError, match="differ from COLUMNS"):
            schema._check_row_type()


def test_a_misspelt_or_mistyped_column_is_refused_by_name() -> None:
    record = valid_record()
    row = MapRow.from_mapping(record)
    assert row.as_dict() == record
    assert frame_rows(records_frame([row])) == [row]
    with pytest.raises(MapError, match="unknown column.*mu_kk"):
        MapRow.from_mapping({**record, "mu_kk": 0.5})
    with pytest.raises(MapError, match="expected float") as err:
        MapRow.from_mapping({**record, "mu_k": "0.5"})
    assert err.value.column == "mu_k"

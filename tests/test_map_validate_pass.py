"""``map validate`` of a map folder in one pass of work: each text checked once per distinct
value, the numbers whole columns at a time, each part read once.

The row rules (:func:`tribopipe.frictionmap.schema.check_runs`) and the checksum of a map's
rows (:func:`~tribopipe.frictionmap.schema.content_sha256`) look at a text column once per
distinct value where it is a column of text; this holds them equal, error for error and
digest for digest, to the value-by-value reading they replaced (kept here, as it was, as
the reference), on real rows with seeded faults in every column. And ``map validate``
reads each part of a map folder once: the schema version it reports comes from the same
read, not from a second one."""

from __future__ import annotations

import hashlib
import json
import math
import random
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from published_map import PUBLISHED_CSV, published_runs
from reduced_runs import make_processed
from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.errors import MapError
from tribopipe.frictionmap import parts, schema
from tribopipe.frictionmap.schema import (
    ADDED_IN_VERSION,
    ALWAYS,
    COLUMNS,
    FILE_NAME_COLUMNS,
    IN_REDUCED_ROWS,
    KIND,
    NAME_COLUMNS,
    RUN_COLUMNS,
    SCHEMA_VERSION,
    SOURCE_REDUCED,
    check_runs,
    content_sha256,
    is_missing,
)
from tribopipe.validate import file_name_problem, name_problem, text_problem


def reference_check_runs(frame: pd.DataFrame, where: str = "row") -> None:
    """The row rules as they were read value by value (the text columns; the numbers are
    whole-column checks in both)."""
    from tribopipe.escape import printable

    reduced = (frame["source"] == SOURCE_REDUCED).to_numpy(dtype=bool)
    for column in COLUMNS:
        name, kind, bounds = column.name, column.kind, column.bounds
        if kind == "str":
            checker = (name_problem if name in NAME_COLUMNS else
                       file_name_problem if name in FILE_NAME_COLUMNS else text_problem)
            for i, value in enumerate(frame[name].tolist()):
                missing = value is None or (isinstance(value, float) and value != value)
                if missing and name not in NAME_COLUMNS:
                    continue
                problem = "missing, expected a name" if missing else checker(value)
                if problem is None and column.choices and value not in column.choices:
                    problem = (f"{printable(str(value))[:60]!r} is not one of "
                               + ", ".join(repr(c) for c in column.choices))
                if problem is not None:
                    raise schema._row_error(frame, where, i, name, f"{name}: {problem}")
        elif kind == "float":
            values = frame[name].to_numpy(dtype=float)
            present = ~np.isnan(values)
            if bounds is None:
                bad = present & ~np.isfinite(values)
                expected = "a finite number or missing"
            else:
                low = values > bounds.low if bounds.low_open else values >= bounds.low
                bad = present & ~(low & (values <= bounds.high))
                expected = f"a number {bounds.describe()}"
            if column.required == ALWAYS:
                bad |= ~present
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise schema._row_error(frame, where, i, name,
                                        f"{name} is {float(values[i])!r}, expected {expected}")
            if column.required == IN_REDUCED_ROWS and (reduced & ~present).any():
                i = int(np.flatnonzero(reduced & ~present)[0])
                raise schema._row_error(frame, where, i, name, f"{name} is missing; only "
                                        f"imported rows may lack {name}")
        elif kind == "int" and bounds is not None:
            values_i = frame[name]
            bad_i = values_i.notna() & ((values_i < bounds.low) | (values_i > bounds.high))
            if bad_i.any():
                i = int(np.flatnonzero(bad_i.to_numpy(dtype=bool))[0])
                raise schema._row_error(frame, where, i, name, f"{name} is {values_i.iloc[i]}, "
                                        f"expected a whole number from {bounds.low:.0f} to "
                                        f"{bounds.high:.0f}")


def reference_sha256(frame: pd.DataFrame, version: int = SCHEMA_VERSION) -> str:
    """The checksum of a map's rows as it was computed value by value."""
    digest = hashlib.sha256(f"tribopipe.frictionmap rows={len(frame)}".encode())
    for name in RUN_COLUMNS:
        if ADDED_IN_VERSION.get(name, 1) > version:
            continue
        kind = KIND[name]
        column = frame[name]
        if kind == "float":
            values = column.to_numpy(dtype="float64")
            data = np.where(np.isnan(values), np.nan, values).astype("<f8").tobytes()
        elif kind == "int":
            ints = column.astype("Int64")
            mask = ints.isna()
            data = (np.asarray(mask, dtype="u1").tobytes()
                    + ints.fillna(0).to_numpy(dtype="int64").astype("<i8").tobytes())
        elif kind == "bool":
            data = np.asarray(column, dtype=bool).astype("u1").tobytes()
        else:
            texts = [None if is_missing(v) else str(v) for v in column.tolist()]
            data = json.dumps(texts, ensure_ascii=False).encode("utf-8", "surrogatepass")
        digest.update(f"|{name}:{kind}:{len(data)}|".encode())
        digest.update(data)
    return digest.hexdigest()


#: faulty texts for the text columns (control characters, blanks, NUL, a name too long,
#: a value outside a column's choices)
TEXT_FAULTS: list[Any] = [None, "", "  ", "line\nbreak", "tab\there", "x" * 300, "\u2028",
                          "a\x00b", "not one of the choices", "ok"]
NUMBER_FAULTS: dict[str, list[Any]] = {"float": [math.inf, -1.0, 1e12, None, 0.0],
                                        "int": [-1, 0, 10**9, None]}


@pytest.fixture(scope="module")
def rows(tmp_path_factory: pytest.TempPathFactory) -> pd.DataFrame:
    reduced, _ = make_processed(tmp_path_factory.mktemp("rows"))
    return pd.concat([fm.read_map(reduced), published_runs(PUBLISHED_CSV)],
                     ignore_index=True)


def faulty(rows: pd.DataFrame, seed: int, n_faults: int) -> pd.DataFrame:
    """``rows`` with ``n_faults`` seeded faults, as unvalidated map rows."""
    rng = random.Random(seed)
    records = fm.schema.frame_records(rows)
    for _ in range(n_faults):
        i = rng.randrange(len(records))
        name = rng.choice(RUN_COLUMNS)
        if KIND[name] == "str":
            records[i][name] = rng.choice(TEXT_FAULTS)
        elif KIND[name] in ("float", "int"):
            records[i][name] = rng.choice(NUMBER_FAULTS[KIND[name]])
    return fm.schema.unvalidated_frame(records, where="row")


def _error(check: Any, frame: pd.DataFrame) -> str | None:
    try:
        check(frame)
    except MapError as exc:
        return str(exc)
    return None


def _as_objects(frame: pd.DataFrame) -> pd.DataFrame:
    """``frame`` with its text columns as plain Python objects (not pandas' ``str``
    dtype): the value-by-value path of the checks."""
    out = frame.copy()
    for name in RUN_COLUMNS:
        if KIND[name] == "str":
            out[name] = pd.Series([None if is_missing(v) else v for v in frame[name].tolist()],
                                  dtype=object, index=frame.index)
    return out


@pytest.mark.parametrize("seed", range(16))
def test_row_rules_by_distinct_text_equal_the_value_by_value_reading(rows, seed):
    frame = faulty(rows, seed, n_faults=1 + 3 * seed)
    assert any(frame[c].dtype == "str" for c in RUN_COLUMNS)  # the distinct-value path
    expected = _error(reference_check_runs, frame)
    assert expected is not None or seed == 0
    assert _error(check_runs, frame) == expected
    # a column of Python objects takes the value-by-value path: the same error
    assert _error(check_runs, _as_objects(frame)) == expected


def test_clean_rows_pass_the_row_rules(rows):
    assert _error(check_runs, rows) is None
    assert _error(reference_check_runs, rows) is None


@pytest.mark.parametrize("seed", range(8))
def test_the_checksum_of_rows_is_the_value_by_value_one(rows, seed):
    frame = faulty(rows, seed, n_faults=20 * seed)
    for version in (1, 5, SCHEMA_VERSION):
        digest = reference_sha256(frame, version)
        assert content_sha256(frame, version) == digest
        assert content_sha256(_as_objects(frame), version) == digest
    changed = frame.copy()
    changed.loc[0, "pin"] = str(changed.loc[0, "pin"]) + " "
    assert content_sha256(changed) != content_sha256(frame)


def test_a_file_name_with_nul_or_a_lone_surrogate_is_named_by_its_first_such_character():
    assert file_name_problem("run\x00\udc80.csv") == (
        "expected a file name, got the character '\\x00' (U+0000)")
    assert file_name_problem("run\udc80\x00.csv") == (
        "expected a file name, got the character '\\udc80' (U+DC80)")
    assert file_name_problem("ünïcødé run 😀.csv") is None


def test_map_validate_reads_each_part_once(tmp_path: Path,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    """Each part's bytes are read once (checksum, rows, every check): the schema version
    the command reports comes from that read, not from reading the map again."""
    map_path = tmp_path / "friction_map.parquet"
    runs = published_runs(PUBLISHED_CSV)
    fm.store.append_frame(map_path, runs.iloc[:100])
    fm.store.append_frame(map_path, runs.iloc[100:])
    manifest = parts.read_manifest(map_path)
    assert len(manifest.parts) >= 1
    reads: list[str] = []
    original = parts.read_part_bytes

    def counting(folder: Path, part: parts.Part) -> bytes:
        reads.append(part.file)
        return original(folder, part)

    monkeypatch.setattr(parts, "read_part_bytes", counting)
    monkeypatch.setattr(fm.store, "read_part_bytes", counting)
    result = CliRunner().invoke(main, ["map", "validate", str(map_path)])
    assert "169 runs" in result.output, result.output
    assert sorted(reads) == sorted(p.file for p in manifest.parts), reads


def test_the_checksum_of_long_text_columns_is_hashed_in_pieces(rows, monkeypatch):
    """A text column is turned into JSON a few thousand cells at a time: the pieces give
    the digest of the whole list (cut here every 7 cells, and with a piece of one)."""
    frame = faulty(rows, 3, n_faults=30)
    digest = reference_sha256(frame)
    for size in (7, len(frame) - 1, len(frame), 10**6):
        monkeypatch.setattr(schema, "HASH_BATCH_ROWS", size)
        assert content_sha256(frame) == digest
    assert content_sha256(frame.iloc[:0]) == reference_sha256(frame.iloc[:0])

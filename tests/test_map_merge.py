"""A landing that merges the map's last parts (so that parts stay few) copies the kept
parts' rows a batch at a time into the new part, never holding them as one frame: what
it holds stays the same whatever the size of the part it merges into. The part it
writes is the one its rows would make as one frame: the same rows, Arrow types and
row checksum (the code path it replaces, run on the same pieces)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from test_frictionmap import run_record
from tribopipe import frictionmap as fm
from tribopipe.frictionmap import store
from tribopipe.frictionmap.schema import META_KEY, RUN_COLUMNS, MapRow, records_frame

BASE = run_record(0)


def _row(i: int, **changes: Any) -> MapRow:
    """A distinct map row (its own id, content and file), on one of a few pairs."""
    return replace(BASE, measurement_id=f"{i:016x}", file_hash=f"{i:064x}",
                   source_file=f"data/run{i}.txt", repeat=i % 40 + 1,
                   disc=f"disc {i // 40 % 5}", mu_k=0.3 + (i % 97) / 1000, **changes)


def _rows(first: int, n: int) -> list[MapRow]:
    """``n`` rows from ``first``, some with unknown labels, notes or exclusions."""
    out = []
    for i in range(first, first + n):
        changes: dict[str, Any] = {}
        if i % 7 == 0:
            changes["temperature_C"] = None
        if i % 11 == 0:
            changes.update(excluded=True, exclusion_reason="a slipped pin, said in a note")
        if i % 13 == 0:
            changes["lab"] = "Another lab, ünïcode"
        out.append(_row(i, **changes))
    return out


def _table_and_info(data: bytes | memoryview) -> tuple[pa.Table, dict[str, Any]]:
    table = pq.ParquetFile(pa.BufferReader(bytes(data))).read()
    info = json.loads(table.schema.metadata[META_KEY])
    info.pop("written_at")
    return table, info


def test_a_merged_part_is_the_part_its_rows_make_as_one_frame(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(store, "MERGE_BATCH_ROWS", 1024)  # batches smaller than a part
    path = tmp_path / "friction_map.parquet"
    fm.append_records(path, _rows(0, 2500))
    (kept,) = fm.parts.read_manifest(path).parts
    changed = records_frame(_rows(5000, 300), where="row")
    fresh = records_frame(_rows(9000, 700), where="row")
    merged = store._merged_bytes(path, store._Merged((kept, changed, fresh)))
    # the code path it replaces: every row of the pieces as one frame, then the part
    whole = pd.concat([fm.read_map(path), changed, fresh], ignore_index=True)
    before = store._part_bytes(whole)
    new_table, new_info = _table_and_info(merged)
    old_table, old_info = _table_and_info(before)
    assert new_info == old_info  # the rows' checksum, their count and sources
    assert new_table.schema.equals(old_table.schema, check_metadata=False)
    assert new_table.equals(old_table)
    assert new_table.schema.metadata[b"pandas"] == old_table.schema.metadata[b"pandas"]
    # written a batch of rows at a time
    groups = pq.ParquetFile(pa.BufferReader(bytes(merged))).metadata
    assert groups.num_row_groups > 1
    assert all(groups.row_group(g).num_rows <= store.MERGE_BATCH_ROWS
               for g in range(groups.num_row_groups))


def test_parts_merged_by_appends_read_and_verify_as_the_rows_landed(tmp_path: Path) -> None:
    path = tmp_path / "friction_map.parquet"
    rows: list[MapRow] = []
    for first, n in ((0, 1500), (2000, 40), (3000, 30), (4000, 600)):
        fm.append_records(path, _rows(first, n))
        rows += _rows(first, n)
    assert [p.n_runs for p in fm.parts.read_manifest(path).parts] == [2170]  # all merged
    got = fm.read_map(path)
    assert got["measurement_id"].tolist() == [r.measurement_id for r in rows]
    pd.testing.assert_frame_equal(got, records_frame(rows, where="row"))
    store.verify_map(path)  # every part's rows against its checksum, every row's rules
    assert fm.store.stored_groups(path, fm.store.map_metadata(path)) is not None


def test_a_landing_that_merges_holds_a_batch_of_the_kept_rows_not_the_part(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The largest block a landing makes (rows × columns of a frame read from a part or
    written into one) is the rows it brings or a batch of the merge, not the part it
    merges into (its 4,000 rows held as one frame of every column before)."""
    path = tmp_path / "friction_map.parquet"
    fm.append_records(path, _rows(0, 4000))
    blocks: list[int] = []
    from_arrow, part_bytes = store._from_arrow, store._part_bytes

    def counted_from_arrow(table: Any, *args: Any, **kwargs: Any) -> pd.DataFrame:
        frame = from_arrow(table, *args, **kwargs)
        blocks.append(frame.shape[0] * frame.shape[1])
        return frame

    def counted_part_bytes(runs: pd.DataFrame) -> bytes:
        blocks.append(runs.shape[0] * runs.shape[1])
        return part_bytes(runs)

    monkeypatch.setattr(store, "_from_arrow", counted_from_arrow)
    monkeypatch.setattr(store, "_part_bytes", counted_part_bytes)
    monkeypatch.setattr(store, "MERGE_BATCH_ROWS", 1024)  # batches smaller than the part
    brought = 1000
    fm.append_records(path, _rows(10_000, brought))  # 4,000 <= 4 x 1,000: merged
    assert [p.n_runs for p in fm.parts.read_manifest(path).parts] == [5000]
    columns = len(RUN_COLUMNS)
    print(f"largest block {max(blocks)} cells, {max(blocks) / columns:.0f} rows of "
          f"{columns} columns")
    assert max(blocks) <= max(brought, 1024) * columns, max(blocks)

"""Appends that cost what they add: what a locked write of a map folder reads and writes.

Every Parquet read of the store is recorded (which part, which columns) while real
appends, replacements, drops and exclusions run on a real map folder of several parts:
the rows the duplicate check and the fold need are read of every part as a column
projection, every column only of the parts holding a run the change compares, replaces
or drops, and only those parts are rewritten; the rest keep their bytes. The result is
the map the whole-map fold (:func:`tribopipe.frictionmap.store.fold_records`) gives.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd
import pytest

from map_files import map_bytes
from test_frictionmap import run_record
from tribopipe import frictionmap as fm
from tribopipe.frictionmap import store
from tribopipe.frictionmap.duplicates import CHECK_COLUMNS, GROUP_COLUMNS
from tribopipe.frictionmap.schema import RUN_COLUMNS
from tribopipe.stats import GROUP_INPUT_COLUMNS


def _two_parts(tmp_path: Path) -> tuple[Path, list[str]]:
    """A map folder of two parts (40 runs, then 9: too many to be merged into the first),
    and its part files in order."""
    path = tmp_path / "friction_map.parquet"
    fm.append_records(path, [run_record(i, repeat=i + 1) for i in range(40)])
    fm.append_records(path, [run_record(100 + i, repeat=i + 1, disc="glass")
                             for i in range(9)])
    parts = [p.file for p in fm.parts.read_manifest(path).parts]
    assert len(parts) == 2
    return path, parts


@pytest.fixture
def reads(monkeypatch: pytest.MonkeyPatch) -> list[tuple[str, tuple[str, ...]]]:
    """Each part the store reads, with the columns it parses (records the real reads)."""
    seen: list[tuple[str, tuple[str, ...]]] = []
    real = store._read_parts

    def recording(p: Path, parts: Any, columns: Any = None, *,
                  full: bool = False) -> pd.DataFrame:
        parts = list(parts)
        for part in parts:
            seen.append((part.file, tuple(RUN_COLUMNS if columns is None else columns)))
        return real(p, parts, columns, full=full)

    monkeypatch.setattr(store, "_read_parts", recording)
    return seen


def _whole(path: Path, cols: tuple[str, ...]) -> bool:
    return set(cols) == set(RUN_COLUMNS)


def test_a_new_run_reads_the_ids_and_writes_one_part(tmp_path: Path, reads: list) -> None:
    path, parts = _two_parts(tmp_path)
    before = map_bytes(path)
    new = run_record(500, disc="wood")
    expected, _ = store.fold_records(fm.read_map(path), [new])
    reads.clear()
    report = fm.append_records(path, [new])
    assert report.added == 1
    # one read of every part: the ids (the fold) and the statistics' columns (the stored
    # groups of the touched conditions); no part read whole (a new run compares nothing)
    assert sorted(f for f, _ in reads) == sorted(parts)
    assert all(set(cols) == {"measurement_id", *GROUP_INPUT_COLUMNS} for _, cols in reads), reads
    after = map_bytes(path)
    assert after[parts[0]] == before[parts[0]]           # the large part kept its bytes
    pd.testing.assert_frame_equal(fm.read_map(path), expected)


def test_a_replaced_run_rewrites_only_its_part(tmp_path: Path, reads: list) -> None:
    path, parts = _two_parts(tmp_path)
    before = map_bytes(path)
    changed = run_record(3, repeat=4, mu_k=0.123)          # a run of the first part
    expected, _ = store.fold_records(fm.read_map(path), [changed], replace=True)
    reads.clear()
    report = fm.update_map(path, [changed], replace=True)
    assert report.replaced == 1
    whole = [f for f, cols in reads if _whole(path, cols)]
    assert whole == [parts[0]], reads                    # only the part holding the run
    manifest = fm.parts.read_manifest(path)
    assert parts[1] in {p.file for p in manifest.parts}  # the other part is kept as it is
    assert parts[0] not in {p.file for p in manifest.parts}
    assert map_bytes(path)[parts[1]] == before[parts[1]]
    pd.testing.assert_frame_equal(fm.read_map(path), expected)


def test_an_unchanged_run_reads_its_part_and_writes_nothing(tmp_path: Path,
                                                            reads: list) -> None:
    path, parts = _two_parts(tmp_path)
    before = map_bytes(path)
    reads.clear()
    report = fm.append_records(path, [run_record(102, repeat=3, disc="glass")])
    assert (report.unchanged, report.changed) == (1, False)
    assert [f for f, cols in reads if _whole(path, cols)] == [parts[1]]
    assert map_bytes(path) == before


def test_a_drop_rewrites_only_the_part_that_held_the_run(tmp_path: Path, reads: list) -> None:
    path, parts = _two_parts(tmp_path)
    gone = run_record(104, repeat=5, disc="glass").measurement_id
    expected = fm.read_map(path)
    expected = expected.loc[expected["measurement_id"] != gone].reset_index(drop=True)
    reads.clear()
    report = fm.update_map(path, [], drop_ids=[gone])
    assert report.dropped_ids == (gone,)
    assert [f for f, cols in reads if _whole(path, cols)] == [parts[1]]
    assert parts[0] in {p.file for p in fm.parts.read_manifest(path).parts}
    pd.testing.assert_frame_equal(fm.read_map(path), expected)


def test_an_exclusion_reads_three_columns_and_rewrites_one_part(tmp_path: Path,
                                                                reads: list) -> None:
    path, parts = _two_parts(tmp_path)
    target = run_record(105, repeat=6, disc="glass").measurement_id
    reads.clear()
    assert fm.exclude_runs(path, [target], "pin debonded") == [target]
    assert [set(cols) for f, cols in reads if f == parts[0]] == [
        {*store.EXCLUSION_COLUMNS, *GROUP_INPUT_COLUMNS}]
    assert [f for f, cols in reads if _whole(path, cols)] == [parts[1]]
    runs = fm.read_map(path).set_index("measurement_id")
    assert bool(runs.at[target, "excluded"]) and runs["excluded"].sum() == 1
    assert runs.at[target, "exclusion_reason"] == "pin debonded"
    assert fm.include_runs(path, [target]) == [target]
    assert not fm.read_map(path)["excluded"].any()


def test_the_checked_append_gives_its_decision_the_columns_it_asked(tmp_path: Path,
                                                                     reads: list) -> None:
    """The one duplicate check (``update_map_with``) reads its columns of every row, and
    the rows as the change left them are those columns, equal to a whole read's."""
    path, parts = _two_parts(tmp_path)
    asked = (*CHECK_COLUMNS, *GROUP_COLUMNS)
    given: list[list[str]] = []

    def decide(current: pd.DataFrame) -> tuple[list, tuple]:
        given.append(list(current.columns))
        return [run_record(700, disc="wood")], ()

    reads.clear()
    report, after = fm.store.change_map_with(path, decide, columns=asked)
    assert report.added == 1
    assert set(given[0]) == {*asked, *GROUP_INPUT_COLUMNS}
    assert not [f for f, cols in reads if _whole(path, cols)]
    whole = fm.read_map(path)
    pd.testing.assert_frame_equal(after, whole.loc[:, list(after.columns)])


def test_a_decision_that_needs_every_column_gets_them(tmp_path: Path) -> None:
    path, _ = _two_parts(tmp_path)
    given: list[int] = []

    def decide(current: pd.DataFrame) -> tuple[list, tuple]:
        given.append(len(current.columns))
        return [], ()

    fm.store.change_map_with(path, decide, columns=CHECK_COLUMNS,
                             needs_all=lambda rows: len(rows) > 0)
    assert given == [len(RUN_COLUMNS)]

"""`map show` reads what it prints: a few columns of every run, every column of a few.

Every conversion of the store's Arrow rows into the map's DataFrame
(``frictionmap.store._from_arrow``) is recorded, with the columns and the number of rows
it converts, while the real command runs (``click.testing``) on a real map folder of two
parts with an excluded and a reviewed run: the summary's columns
(:data:`~tribopipe.frictionmap.summary.SUMMARY_COLUMNS`) are converted for every run,
every column only for the two runs it prints whole. Its text is the text of the summary
of every column of every run (the map opened whole), byte for byte, for a map folder and
for a map kept as one file.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from test_frictionmap import run_record
from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.errors import MapError
from tribopipe.frictionmap import store
from tribopipe.frictionmap.schema import RUN_COLUMNS
from tribopipe.frictionmap.snapshot import open_map
from tribopipe.frictionmap.summary import SUMMARY_COLUMNS, map_summary

REVIEW = {"review": "accept", "review_by": "A. Person", "review_date": "2026-11-02",
          "review_reason": "flags checked on the trace"}


def _map_with_shown_runs(path: Path) -> tuple[str, str]:
    """A map folder of two parts (40 runs, then 9) with one run excluded and one
    reviewed, both in the first part; their ids."""
    first = [run_record(i, repeat=i + 1) for i in range(40)]
    first[7] = replace(first[7], **REVIEW)
    fm.append_records(path, first)
    fm.append_records(path, [run_record(100 + i, repeat=i + 1, disc="glass")
                             for i in range(9)])
    assert len(fm.parts.read_manifest(path).parts) == 2
    excluded = first[3].measurement_id
    assert fm.exclude_runs(path, [excluded], "pin slipped in the holder") == [excluded]
    return excluded, first[7].measurement_id


@pytest.fixture
def conversions(monkeypatch: pytest.MonkeyPatch) -> list[tuple[tuple[str, ...], int]]:
    """Each conversion of Arrow rows into map rows: its columns and its number of rows."""
    seen: list[tuple[tuple[str, ...], int]] = []
    real = store._from_arrow

    def recording(table: Any, columns: Any = RUN_COLUMNS, **kw: Any) -> Any:
        seen.append((tuple(columns), table.num_rows))
        return real(table, columns, **kw)

    monkeypatch.setattr(store, "_from_arrow", recording)
    return seen


def _show(path: Path, *args: str) -> str:
    result = CliRunner().invoke(main, ["map", "show", "--map", str(path), *args])
    assert result.exit_code == 0, result.output
    return result.output


def test_show_reads_a_few_columns_of_every_run_and_every_column_of_those_it_prints(
        tmp_path: Path, conversions: list) -> None:
    path = tmp_path / "friction_map.parquet"
    excluded, reviewed = _map_with_shown_runs(path)
    conversions.clear()
    text = _show(path)
    # every run: the summary's columns (not every column); the two runs it prints whole:
    # every column, of those two rows only
    assert conversions == [(SUMMARY_COLUMNS, 49), (RUN_COLUMNS, 2)]
    assert len(SUMMARY_COLUMNS) < len(RUN_COLUMNS) / 3
    assert f"    {excluded}  " in text and "pin slipped in the holder" in text
    assert "reviewed runs: 1 (accept 1)" in text
    assert f"    {reviewed}  accept [A. Person, 2026-11-02]: flags checked" in text
    # the same text as the summary of the map opened whole
    assert text == map_summary(open_map(path)) + "\n"


def test_show_of_a_map_without_shown_runs_reads_no_row_whole(tmp_path: Path,
                                                              conversions: list) -> None:
    path = tmp_path / "friction_map.parquet"
    fm.append_records(path, [run_record(i, repeat=i + 1) for i in range(5)])
    conversions.clear()
    text = _show(path)
    assert conversions == [(SUMMARY_COLUMNS, 5)]
    assert "excluded runs" not in text and text == map_summary(open_map(path)) + "\n"


def test_show_with_runs_and_groups_and_of_a_single_file_map_prints_the_same_text(
        tmp_path: Path) -> None:
    folder = tmp_path / "friction_map.parquet"
    _map_with_shown_runs(folder)
    whole = open_map(folder)
    assert _show(folder, "--runs") == map_summary(whole, runs_listed=True) + "\n"
    single = tmp_path / "single.parquet"
    store._write_atomic(single, whole.runs)  # the format before map folders: one file
    assert single.is_file()
    assert _show(single) == _show(folder).replace(str(folder), str(single))
    assert _show(single, "--groups") == _show(folder, "--groups").replace(str(folder),
                                                                          str(single))


def test_rows_by_id_refuses_an_id_the_commit_does_not_hold(tmp_path: Path) -> None:
    path = tmp_path / "friction_map.parquet"
    excluded, _ = _map_with_shown_runs(path)
    snap = open_map(path, SUMMARY_COLUMNS)
    assert list(snap.rows_of([excluded])["measurement_id"]) == [excluded]
    with pytest.raises(MapError, match="changed while it was read"):
        snap.rows_of([excluded, "0" * 16])

"""A reduced run's row is checked against the row rules once on its way into the map (when
its record is built, so a bad run fails alone): the store takes the checked record as it
is, and a map of parts is not checked row by row again on read (each part's checksum
vouches for it); a single-file map is checked on read."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from tribopipe.cli import main
from tribopipe.frictionmap import schema, store
from tribopipe.frictionmap.schema import MapRow, checked_row

EXAMPLE = Path(__file__).resolve().parents[1] / "raw" / "example" / "DS30_steel_5N_20C_r1.csv"


def _count_rows_checked(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """The number of rows of every call of the row rules (check_runs), wherever called."""
    seen: list[int] = []
    original = schema.check_runs

    def counting(frame: pd.DataFrame, where: str = "row") -> pd.DataFrame:
        seen.append(len(frame))
        return original(frame, where)

    monkeypatch.setattr(schema, "check_runs", counting)
    monkeypatch.setattr(store, "check_runs", counting)
    return seen


def test_a_reduced_run_is_checked_once_on_its_way_in(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    map_path = tmp_path / "friction_map.parquet"
    result = CliRunner().invoke(main, ["map", "import", "--published", "--map", str(map_path)])
    assert result.exit_code == 0, result.output
    n_map = len(store.read_map(map_path))
    seen = _count_rows_checked(monkeypatch)
    result = CliRunner().invoke(main, [
        "reduce", str(EXAMPLE), "--pin", "Dragonskin 30", "--disc", "steel", "--force", "5",
        "--temperature", "20", "--repeat", "1", "--map", str(map_path),
        "--output", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    assert len(store.read_map(map_path)) == n_map + 1
    # the new run's row once (its record; the store folds it in unchecked) and nothing
    # else: the map's rows were checked as they came in, and a read checks each part's
    # bytes against its checksum instead (`map validate` checks every row again)
    assert seen == [1], seen


def test_a_single_file_map_s_rows_are_checked_on_every_read(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A map in the format before parts carries only a checksum of its rows computed by
    whoever wrote the file: its reader checks every row."""
    built = tmp_path / "built.parquet"
    CliRunner().invoke(main, ["map", "import", "--published", "--map", str(built)])
    single = store.write_map_copy(tmp_path / "single.parquet", store.read_map(built))
    seen = _count_rows_checked(monkeypatch)
    assert len(store.read_map(single)) == 169
    assert seen == [169], seen


def test_a_checked_row_changed_since_is_checked_again(monkeypatch: pytest.MonkeyPatch
                                                     ) -> None:
    runs = pd.read_parquet(Path(__file__).parent / "data" / "friction_map_v3.parquet")
    values = {k: (None if pd.isna(v) else v) if not isinstance(v, str) else v
              for k, v in runs.iloc[0].to_dict().items()}
    row = MapRow.from_mapping(values)
    assert not row.checked
    record = checked_row(row)
    assert isinstance(record, MapRow) and record == row and record.checked
    seen = _count_rows_checked(monkeypatch)
    schema.records_frame([record])
    assert seen == []  # checked when it was built
    # a batch worker's record crosses to the parent pickled: still checked
    import pickle
    assert pickle.loads(pickle.dumps(record)).checked
    # a row cannot change in place; a changed copy is a new row, checked again
    with pytest.raises(dataclasses.FrozenInstanceError):
        record.mu_k = -1.0  # type: ignore[misc]
    changed = dataclasses.replace(record, mu_k=-1.0)
    assert not changed.checked
    with pytest.raises(schema.MapError, match="mu_k"):
        schema.records_frame([changed])
    assert seen == [1]

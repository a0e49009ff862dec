"""``map publish`` streams: the runs are written a batch at a time from the map's Arrow
table, the group table comes from the stored groups where the filling of the labs leaves
them the same, the explorer page is written from the runs it shows, and every file equals
what the whole-frame functions give for the same rows.

The batches are cut small here (7 rows) so that a real map of a few hundred rows goes
through many of them; the whole-frame functions (``package_runs_table``,
``group_statistics``, ``validate_runs``, ``frictionmap_table``, ``explorer_data``) are the
reference."""

from __future__ import annotations

import dataclasses
import io
import json
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pytest

from published_map import PUBLISHED_CSV, published_runs
from reduced_runs import SPREAD_RUNS, make_processed
from tribopipe import frictionmap as fm
from tribopipe.errors import MapError
from tribopipe.export import publish
from tribopipe.export.citation import Publisher
from tribopipe.export.explorer import explorer_parts, read_embedded_data
from tribopipe.export.tables import frictionmap_csv, frictionmap_table
from tribopipe.fit import fit_power_law
from tribopipe.frictionmap import schema
from tribopipe.frictionmap.checks import validate_runs
from tribopipe.frictionmap.published import PUBLISHED_LAB
from tribopipe.frictionmap.store import MapCopyWriter, load_map_table, stored_groups
from tribopipe.stats import OWN_LAB, group_statistics

LAB = "Stream Lab"


@pytest.fixture(autouse=True)
def small_batches(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(publish, "PUBLISH_BATCH_ROWS", 7)
    monkeypatch.setattr(schema, "HASH_BATCH_ROWS", 5)


@pytest.fixture(scope="module")
def own_map(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A lab's own map folder: really reduced runs, none naming its lab."""
    path, _ = make_processed(tmp_path_factory.mktemp("own"), SPREAD_RUNS)
    return path


def _map_of(folder: Path, *frames: pd.DataFrame) -> Path:
    path = folder / "friction_map.parquet"
    for frame in frames:
        fm.store.append_frame(path, frame)
    return path


def _expected_groups(path: Path) -> pd.DataFrame:
    return group_statistics(publish.package_runs_table(fm.read_map(path), LAB))


def _package_groups(path: Path) -> tuple[pd.DataFrame, bool]:
    """The package's group table of the map at ``path`` and whether it came from the
    stored groups."""
    table, info = load_map_table(path)
    own = fm.store.frame_of_table(table, ["lab", "source"])
    runs = publish.package_runs_table(fm.store.frame_of_table(table), LAB)
    rows = stored_groups(path, info)
    used = rows is not None and publish.filled_group_rows(rows, own, LAB) is not None
    return publish.package_group_table(path, info, own, runs, LAB), used


def test_own_runs_without_a_lab_take_their_groups_from_the_stored_ones(own_map):
    groups, stored = _package_groups(own_map)
    assert stored
    assert set(groups["labs"]) == {LAB}
    pd.testing.assert_frame_equal(groups, _expected_groups(own_map), check_exact=True)


def test_runs_that_all_name_their_lab_take_the_stored_groups_as_they_are(own_map, tmp_path):
    runs = fm.read_map(own_map)
    runs["lab"] = ["Lab A" if i % 2 else "Lab B" for i in range(len(runs))]
    path = _map_of(tmp_path, runs)
    groups, stored = _package_groups(path)
    assert stored
    assert {"Lab A;Lab B"} <= set(groups["labs"])
    pd.testing.assert_frame_equal(groups, _expected_groups(path), check_exact=True)


@pytest.mark.parametrize("case", ["published and own", "a group of both", "own lab named"])
def test_where_filling_the_labs_changes_the_groups_every_run_is_grouped(own_map, tmp_path,
                                                                        case):
    runs = fm.read_map(own_map)
    if case == "published and own":  # two names fill the runs without a lab
        frames = [runs, published_runs(PUBLISHED_CSV)]
    elif case == "a group of both":  # one group with and without a lab
        runs.loc[0, "lab"] = LAB
        frames = [runs]
    else:  # a run that names its lab "(own lab)"
        runs.loc[0, "lab"] = OWN_LAB
        frames = [runs]
    path = _map_of(tmp_path, *frames)
    groups, stored = _package_groups(path)
    assert not stored
    pd.testing.assert_frame_equal(groups, _expected_groups(path), check_exact=True)
    if case == "published and own":
        assert {LAB, PUBLISHED_LAB} <= set(groups["labs"])


def test_the_published_files_equal_the_whole_frame_ones(own_map, tmp_path):
    runs = pd.concat([fm.read_map(own_map), published_runs(PUBLISHED_CSV)],
                     ignore_index=True)
    runs.loc[3, "excluded"], runs.loc[3, "exclusion_reason"] = True, "a bad run"
    path = _map_of(tmp_path / "map", runs)
    done = publish.publish_map(path, tmp_path / "pkg", Publisher(LAB), date="2026-01-01",
                               evidence=False)
    whole = publish.package_runs_table(fm.read_map(path), LAB)
    assert len(whole) > 5 * publish.PUBLISH_BATCH_ROWS
    data = done.path / "data"
    out = io.StringIO()
    publish.write_table_csv(out, whole, [schema.KIND[c] for c in fm.RUN_COLUMNS])
    assert (data / "runs.csv").read_text(encoding="utf-8") == out.getvalue()
    copy = fm.read_map(data / "runs.parquet")  # its checksum is checked on the way
    pd.testing.assert_frame_equal(copy, fm.records_frame(schema.frame_records(whole)),
                                  check_exact=True)
    assert (data / "frictionmap.csv").read_text(encoding="utf-8") == frictionmap_csv(
        frictionmap_table(whole))
    groups = group_statistics(whole)
    table, members = publish.package_groups(groups)
    assert (data / "groups.csv").read_text(encoding="utf-8") == publish.table_csv(
        table, [publish.column_kind(table[c]) for c in table.columns])
    assert len(pd.read_csv(data / "group_runs.csv")) == len(members)
    page = read_embedded_data((done.path / "explorer.html").read_text(encoding="utf-8"))
    reference = read_embedded_data(dict(explorer_parts(
        whole, "explorer.html", groups=groups, fits=fit_power_law(whole), title=(
            Publisher(LAB).package_title), source=LAB))["explorer.html"])
    for data_ in (page, reference):
        data_.pop("generated")
    assert page == reference
    assert fm.check_package(done.path).ok


def test_the_problems_of_the_rows_are_found_batch_by_batch_as_in_the_whole(own_map):
    runs = pd.concat([fm.read_map(own_map), published_runs(PUBLISHED_CSV)],
                     ignore_index=True)
    for i in (0, 6, 7, 8, 20, 150):  # the first and last rows of batches, and within
        runs.loc[i, "test"] = f"=cell{i}"
    runs.loc[30, "lab"] = "   "  # filled: not a problem
    table = pa.Table.from_pandas(runs, preserve_index=False)
    found = publish.run_problems(table, LAB)
    expected = validate_runs(publish.package_runs_table(runs, LAB), require_lab=True)
    assert [p.row for p in found] == [1, 7, 8, 9, 21, 151]
    assert found == expected


def test_a_map_copy_written_in_batches_is_a_map(own_map, tmp_path):
    runs = fm.read_map(own_map)
    target = tmp_path / "copy.parquet"
    with MapCopyWriter(target, len(runs), runs["source"].dropna(),
                       schema.content_sha256(runs)) as writer:
        for start in range(0, len(runs), 4):
            writer.write(runs.iloc[start:start + 4])
        writer.finish()
    pd.testing.assert_frame_equal(fm.read_map(target), runs, check_exact=True)
    assert fm.store.map_metadata(target)["n_runs"] == len(runs)


def test_a_map_copy_left_unfinished_or_short_leaves_no_file(own_map, tmp_path):
    runs = fm.read_map(own_map)
    target = tmp_path / "copy.parquet"
    with pytest.raises(RuntimeError), MapCopyWriter(target, len(runs), [], "0" * 64) as w:
        w.write(runs.iloc[:3])
        raise RuntimeError("killed")
    with pytest.raises(MapError, match="3 rows written"), \
            MapCopyWriter(target, len(runs), [], "0" * 64) as w:
        w.write(runs.iloc[:3])
        w.finish()
    assert list(tmp_path.iterdir()) == []
    target.write_bytes(b"x")
    with pytest.raises(MapError, match="exists already"):
        MapCopyWriter(target, 0, [], "0" * 64)


def test_a_map_copy_with_a_wrong_checksum_is_refused_when_read(own_map, tmp_path):
    runs = fm.read_map(own_map)
    target = tmp_path / "copy.parquet"
    with MapCopyWriter(target, len(runs), [], "0" * 64) as writer:
        writer.write(runs)
        writer.finish()
    with pytest.raises(MapError, match="fails its checksum"):
        fm.read_map(target)


def test_the_runs_of_the_explorer_give_the_page_of_every_run(own_map):
    runs = publish.package_runs_table(fm.read_map(own_map), LAB)
    runs.loc[1, "excluded"] = True
    shown = publish.explorer_runs(runs)
    assert len(shown) == len(runs) - 1
    assert list(shown.columns) == list(publish.EXPLORER_COLUMNS)
    groups, fits = group_statistics(runs), fit_power_law(runs)

    def page(frame: pd.DataFrame) -> dict[str, Any]:
        data = read_embedded_data(dict(explorer_parts(frame, "e.html", groups=groups, fits=fits))[
            "e.html"])
        data.pop("generated")
        return data

    assert page(shown) == page(runs)


def test_a_snapshot_a_command_opened_publishes_as_its_path(own_map, tmp_path):
    by_path = publish.publish_map(own_map, tmp_path / "a", Publisher(LAB),
                                  date="2026-01-01", evidence=False)
    by_snapshot = publish.publish_map(fm.snapshot.open_map(own_map), tmp_path / "b",
                                      Publisher(LAB), date="2026-01-01", evidence=False)
    for name in ("data/runs.csv", "data/groups.csv", "data/frictionmap.csv"):
        assert (by_path.path / name).read_bytes() == (by_snapshot.path / name).read_bytes()
    described = json.loads((by_path.path / "datapackage.json").read_text(encoding="utf-8"))
    assert [r["path"] for r in described["resources"]][:2] == ["data/runs.csv",
                                                              "data/runs.parquet"]
    assert dataclasses.astuple(by_path)[1] == len(fm.read_map(own_map))

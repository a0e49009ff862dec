"""The map as a folder of immutable parts and a manifest: an append adds a part and leaves
every committed byte alone; a changed part, a damaged manifest, a missing part are refused
in one line naming how to go back; the previous commit is kept and restores by a rename;
other tools read the folder as the committed rows; a single-file map converts in one
command; compaction keeps the rows; a full disk leaves the map as it was."""

from __future__ import annotations

import errno
import json
import shutil
from pathlib import Path

import pandas as pd
import pytest

from hostile import assert_clean_failure, invoke
from map_files import map_bytes, the_part
from test_frictionmap import run_record
from tribopipe import frictionmap as fm
from tribopipe.errors import MapError
from tribopipe.frictionmap.snapshot import open_map


def _map(tmp_path: Path, n: int = 3) -> Path:
    path = tmp_path / "friction_map.parquet"
    fm.append_records(path, [run_record(i, repeat=i + 1) for i in range(n)])
    return path


def test_a_new_map_is_a_folder_of_one_part_and_a_manifest(tmp_path: Path) -> None:
    path = _map(tmp_path)
    assert path.is_dir()
    manifest = fm.parts.read_manifest(path)
    assert manifest.n_runs == 3 and len(manifest.parts) == 1 and manifest.generation == 1
    # the part is itself a friction map (our metadata, the checksum of its rows)
    part = fm.read_map(the_part(path))
    pd.testing.assert_frame_equal(part, fm.read_map(path))
    info = fm.store.map_metadata(path)
    assert (info["format"], info["n_runs"], info["parts"]) == ("parts", 3, 1)


def test_an_append_adds_a_part_and_leaves_every_committed_byte_alone(tmp_path: Path) -> None:
    path = tmp_path / "friction_map.parquet"
    fm.append_records(path, [run_record(i, repeat=i + 1) for i in range(40)])
    before = map_bytes(path)
    committed = {p.file for p in fm.parts.read_manifest(path).parts}
    report = fm.append_records(path, [run_record(100, repeat=1, disc="glass")])
    assert report.added == 1
    after = map_bytes(path)
    for name in committed:
        assert after[name] == before[name]          # the 40-run part was not rewritten
    manifest = fm.parts.read_manifest(path)
    assert [p.n_runs for p in manifest.parts] == [40, 1]
    runs = fm.read_map(path)
    assert len(runs) == 41 and runs["measurement_id"].iloc[-1] == report.added_ids[0]


def test_small_parts_are_merged_so_parts_stay_few(tmp_path: Path) -> None:
    path = tmp_path / "friction_map.parquet"
    fm.append_records(path, [run_record(i, repeat=i + 1) for i in range(64)])
    for i in range(60):
        fm.append_records(path, [run_record(1000 + i, repeat=1, disc=f"d{i}")])
    manifest = fm.parts.read_manifest(path)
    sizes = [p.n_runs for p in manifest.parts]
    assert sum(sizes) == 124 and len(sizes) <= 6, sizes
    # each part holds more than MERGE_FACTOR times the rows of the next
    assert all(a > fm.store.MERGE_FACTOR * b for a, b in zip(sizes, sizes[1:], strict=False)), sizes
    ids = fm.read_map(path)["measurement_id"].tolist()
    assert ids == [run_record(i, repeat=i + 1).measurement_id for i in range(64)] + [
        run_record(1000 + i, repeat=1, disc=f"d{i}").measurement_id for i in range(60)]
    assert not list(fm.parts.leftovers(path))


def test_a_changed_part_fails_its_checksum_and_nothing_overwrites_it(tmp_path: Path) -> None:
    path = _map(tmp_path)
    part = the_part(path)
    raw = bytearray(part.read_bytes())
    raw[len(raw) // 2] ^= 0x01
    part.write_bytes(bytes(raw))
    before = map_bytes(path)
    for action in (lambda: fm.read_map(path),
                   lambda: fm.append_records(path, [run_record(9)]),
                   lambda: fm.exclude_runs(path, [run_record(0, repeat=1).measurement_id],
                                           "x")):
        with pytest.raises(MapError, match="fails its checksum") as info:
            action()
        assert str(path) in str(info.value) and "\n" not in str(info.value)
    assert map_bytes(path) == before
    stderr = assert_clean_failure(invoke("map", "show", "--map", str(path)))
    assert "fails its checksum" in stderr and len(stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("damage", ["json", "digest", "missing_part", "outside", "lost"])
def test_a_damaged_manifest_is_one_line(tmp_path: Path, damage: str) -> None:
    path = _map(tmp_path)
    manifest = path / fm.parts.MANIFEST
    data = json.loads(manifest.read_text())
    if damage == "json":
        manifest.write_text(manifest.read_text()[:-20])
    elif damage == "digest":
        data["n_runs"] = 4
        data["parts"][0]["n_runs"] = 4
        manifest.write_text(json.dumps(data))
    elif damage == "missing_part":
        the_part(path).unlink()
    elif damage == "outside":
        data["parts"][0]["file"] = "../elsewhere.parquet"
        body = {k: v for k, v in data.items() if k != "manifest_sha256"}
        data["manifest_sha256"] = fm.parts._digest(body)
        manifest.write_text(json.dumps(data))
    else:
        manifest.unlink()
    with pytest.raises(MapError) as info:
        fm.read_map(path)
    assert "\n" not in str(info.value) and str(path) in str(info.value)
    stderr = assert_clean_failure(invoke("map", "show", "--map", str(path)))
    assert len(stderr.strip().splitlines()) == 1, stderr


def test_the_previous_commit_is_kept_and_restores_by_a_rename(tmp_path: Path) -> None:
    path = _map(tmp_path)
    before = fm.read_map(path)
    first = before["measurement_id"].iloc[0]
    fm.exclude_runs(path, [first], "pin debonded")
    assert fm.read_map(path)["excluded"].iloc[0]
    # the refusal of a damaged map names the way back
    the_part(path).write_bytes(b"garbage")
    with pytest.raises(MapError, match="renaming _manifest.json.bak to _manifest.json"):
        fm.read_map(path)
    (path / fm.parts.MANIFEST_BACKUP).replace(path / fm.parts.MANIFEST)
    pd.testing.assert_frame_equal(fm.read_map(path), before)
    # and the restored map takes writes again
    assert fm.exclude_runs(path, [first], "pin debonded") == [first]
    assert len(fm.read_map(path)) == 3


def test_other_tools_read_the_folder_as_the_committed_rows(tmp_path: Path) -> None:
    path = _map(tmp_path)
    fm.append_records(path, [run_record(1, repeat=2, mu_k=0.61)], replace=True)
    fm.exclude_runs(path, [run_record(2, repeat=3).measurement_id], "pin slipped")
    theirs = pd.read_parquet(path)                   # pyarrow reads the folder as a dataset
    ours = fm.read_map(path)
    assert sorted(theirs["measurement_id"]) == sorted(ours["measurement_id"])
    assert len(theirs) == 3 and 0.61 in set(theirs["mu_k"])


def test_a_full_disk_leaves_the_committed_map(tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    path = _map(tmp_path)
    before = map_bytes(path)
    real = fm.parts._write_new

    def full(*args: object, **kwargs: object) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(fm.parts, "_write_new", full)
    with pytest.raises(MapError, match="No space left on device") as info:
        fm.append_records(path, [run_record(50, repeat=1, disc="glass")])
    assert "\n" not in str(info.value)
    monkeypatch.setattr(fm.parts, "_write_new", real)
    assert map_bytes(path) == before and len(fm.read_map(path)) == 3


def test_a_folder_that_is_not_a_map_is_refused_and_never_written(tmp_path: Path) -> None:
    folder = tmp_path / "photos"
    folder.mkdir()
    (folder / "pin.jpg").write_bytes(b"\xff\xd8")
    with pytest.raises(MapError, match="not a friction map"):
        fm.append_records(folder, [run_record(1)])
    assert [p.name for p in folder.iterdir()] == ["pin.jpg"]


def test_a_single_file_map_upgrades_in_one_command(tmp_path: Path) -> None:
    built = _map(tmp_path / "built")
    single = fm.store.write_map_copy(tmp_path / "friction_map.parquet", fm.read_map(built))
    rows = fm.read_map(single)
    # a single-file map still reads and takes writes, rewritten whole
    fm.exclude_runs(single, [rows["measurement_id"].iloc[1]], "checked")
    rows = fm.read_map(single)
    result = invoke("map", "upgrade", "--map", str(single))
    assert result.exit_code == 0, result.output
    assert "converted to a map folder of parts (3 runs)" in result.output
    assert single.is_dir() and fm.store.backup_path(single).is_file()
    pd.testing.assert_frame_equal(fm.read_map(single), rows)
    pd.testing.assert_frame_equal(fm.read_map(fm.store.backup_path(single)), rows)
    again = invoke("map", "upgrade", "--map", str(single))
    assert again.exit_code == 0 and "nothing to do" in again.output


def test_an_interrupted_upgrade_is_refused_then_finished(tmp_path: Path) -> None:
    built = _map(tmp_path / "built")
    path = tmp_path / "friction_map.parquet"
    # what a conversion killed between its two renames leaves: the file moved to .bak,
    # the finished folder beside
    staged = tmp_path / ".friction_map.parquet.upgrade"
    shutil.copytree(built, staged)
    fm.store.write_map_copy(fm.store.backup_path(path), fm.read_map(built))
    with pytest.raises(MapError, match="run `tribopipe map upgrade` again"):
        fm.read_map(path)
    with pytest.raises(MapError, match="interrupted"):
        fm.append_records(path, [run_record(7)])
    assert not path.exists()
    assert invoke("map", "upgrade", "--map", str(path)).exit_code == 0
    pd.testing.assert_frame_equal(fm.read_map(path), fm.read_map(built))


def test_compaction_keeps_the_rows_in_order_in_one_part(tmp_path: Path) -> None:
    path = tmp_path / "friction_map.parquet"
    fm.append_records(path, [run_record(i, repeat=i + 1) for i in range(40)])
    fm.append_records(path, [run_record(100, repeat=1, disc="glass")])
    before = fm.read_map(path)
    result = invoke("map", "compact", "--map", str(path))
    assert result.exit_code == 0, result.output
    assert "2 part(s) → 1" in result.output
    assert len(fm.parts.read_manifest(path).parts) == 1
    pd.testing.assert_frame_equal(fm.read_map(path), before)
    # the previous commit (two parts) is kept for a restore
    (path / fm.parts.MANIFEST_BACKUP).replace(path / fm.parts.MANIFEST)
    pd.testing.assert_frame_equal(fm.read_map(path), before)
    assert len(fm.parts.read_manifest(path).parts) == 2


def test_map_validate_checks_every_row_of_every_part(tmp_path: Path) -> None:
    path = _map(tmp_path)
    assert invoke("map", "validate", str(path)).exit_code == 0
    # a part rewritten with a bad row and a manifest made to match it: the reads trust
    # the manifest's checksums; `map validate` checks the rows themselves
    part = the_part(path)
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pq.read_table(part)
    mu = table.column("mu_k").to_pylist()
    mu[1] = -0.5
    table = table.set_column(table.schema.get_field_index("mu_k"), "mu_k",
                             pa.array(mu, pa.float64()))
    pq.write_table(table, part)
    data = json.loads((path / fm.parts.MANIFEST).read_text())
    data["parts"][0]["sha256"] = fm.parts.hashlib.sha256(part.read_bytes()).hexdigest()
    data["parts"][0]["bytes"] = part.stat().st_size
    body = {k: v for k, v in data.items() if k != "manifest_sha256"}
    data["manifest_sha256"] = fm.parts._digest(body)
    (path / fm.parts.MANIFEST).write_text(json.dumps(data))
    stderr = assert_clean_failure(invoke("map", "validate", str(path)))
    assert "fails the checksum of its rows" in stderr


def test_a_snapshot_reads_the_columns_asked_and_derives_once(tmp_path: Path) -> None:
    path = _map(tmp_path)
    snap = open_map(path, ["pin", "measurement_id"])
    assert snap.columns == ("measurement_id", "pin") and snap.n_runs == 3
    assert snap.ids == frozenset(fm.read_map(path)["measurement_id"])
    with pytest.raises(MapError, match="opened without column"):
        snap.require(["mu_k"])
    full = open_map(path)
    calls: list[int] = []
    first = full.derived("n", lambda: calls.append(1) or len(calls))
    assert full.derived("n", lambda: calls.append(1) or len(calls)) == first == 1
    assert full.groups() is full.groups()
    # a caller changing its rows changes its own copy, not the snapshot
    runs = full.runs
    runs.loc[0, "mu_k"] = 0.99
    assert full.runs["mu_k"].iloc[0] != 0.99


def test_a_snapshot_gives_each_group_s_runs_without_a_growing_cell(tmp_path: Path) -> None:
    path = _map(tmp_path, 6)
    snap = open_map(path)
    groups = snap.groups()
    members = snap.group_members()
    assert list(members.columns) == ["group", "measurement_id"]
    assert len(members) == 6 and members["group"].is_monotonic_increasing
    assert sorted(members["measurement_id"]) == sorted(snap.runs["measurement_id"])
    for g in range(len(groups)):
        runs = snap.group_runs(g)
        assert set(runs["measurement_id"]) == set(str(groups["run_ids"].iloc[g]).split(";"))
        assert runs["pin"].nunique() == 1

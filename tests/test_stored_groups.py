"""Stored condition groups never drift from the groups of the map's rows.

A map folder keeps :func:`tribopipe.stats.group_rows` of every condition beside its parts
and every write recomputes the conditions it touched. After each real change — appends,
a second lab's runs, replacements, drops, exclusions and inclusions, a review applied by
a batch, compaction, a conversion from one file — the groups a command reads from the
stored copy (:meth:`MapSnapshot.groups`) must equal the groups computed from every row
(:func:`tribopipe.stats.group_statistics`), in every variant the commands ask for.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from test_frictionmap import run_record
from test_review import FILES, batch, campaign, reduced, write_review  # noqa: F401 (fixtures)
from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.errors import MapError
from tribopipe.frictionmap import parts, store
from tribopipe.frictionmap.snapshot import open_map
from tribopipe.stats import group_statistics


def _record(i: int, **labels: object) -> dict:
    """Run ``i``: its pair, force and temperature from ``i`` (several conditions, repeats
    with scatter), unless ``labels`` say otherwise."""
    conditions = {"pin": ("Ecoflex 00-50", "Dragonskin 30")[i % 2],
                  "disc": ("steel", "glass", "wood")[(i // 2) % 3],
                  "force_N": (1.0, 3.0)[(i // 6) % 2],
                  "temperature_C": (20.0, 40.0)[(i // 12) % 2], "repeat": i // 24 + 1}
    conditions.update(labels)
    return run_record(i, mu_k=0.3 + 0.011 * (i % 7), **conditions)


def assert_no_drift(path: Path) -> None:
    """The stored groups, finished as each command asks, equal those of every row."""
    snap = open_map(path)
    assert snap.stored_group_rows() is not None, "the map holds no stored groups"
    runs = fm.read_map(path)
    for options in ({}, {"show_speed": True, "show_method": True}, {"show_method": True}):
        stored = snap.groups(**options)
        computed = group_statistics(runs, **options)
        pd.testing.assert_frame_equal(stored, computed, check_exact=False, rtol=1e-12)
    store.verify_map(path)  # `map validate` compares them too
    # and what is derived from them: which runs each group holds
    members = snap.group_members()
    assert sorted(members["measurement_id"]) == sorted(
        runs.loc[~runs["excluded"], "measurement_id"])


@pytest.fixture
def path(tmp_path: Path) -> Path:
    path = tmp_path / "friction_map.parquet"
    fm.append_records(path, [_record(i) for i in range(48)])
    return path


def test_appends_keep_the_stored_groups_equal(path: Path) -> None:
    assert_no_drift(path)
    fm.append_records(path, [_record(100 + i) for i in range(5)])       # into groups
    assert_no_drift(path)
    fm.append_records(path, [_record(200, pin="Ecoflex 00-50", disc="acrylic")])  # a new one
    assert_no_drift(path)
    # a second lab at the same conditions: ISO 5725 figures, the pooled U
    other = [{**_record(300 + i).as_dict(), "lab": "Lab B", "mu_k": 0.6 + 0.01 * i}
             for i in range(12)]
    fm.append_records(path, other)
    assert_no_drift(path)
    groups = open_map(path).groups()
    assert (groups["mu_k_labs"] == 2).any() and groups["mu_k_s_L"].notna().any()


def test_replacements_and_drops_keep_them_equal(path: Path) -> None:
    moved = _record(5, force_N=3.0, temperature_C=40.0)        # moves to another group
    fm.update_map(path, [moved, _record(7, mu_s=0.95)], replace=True)
    assert_no_drift(path)
    fm.update_map(path, [], drop_ids=[_record(8).measurement_id, _record(9).measurement_id])
    assert_no_drift(path)


def test_exclusions_and_inclusions_keep_them_equal(path: Path) -> None:
    ids = [_record(i).measurement_id for i in (0, 2, 4)]
    fm.exclude_runs(path, ids, "pin debonded")
    assert_no_drift(path)
    fm.include_runs(path, ids[:1])
    assert_no_drift(path)
    # a group whose every run is excluded leaves the table, and comes back
    lonely = _record(400, disc="cardboard")
    fm.append_records(path, [lonely])
    fm.exclude_runs(path, [lonely.measurement_id], "torn")
    assert_no_drift(path)
    fm.include_runs(path, [lonely.measurement_id])
    assert_no_drift(path)


def test_compaction_and_upgrade_keep_them_equal(path: Path, tmp_path: Path) -> None:
    for k in range(3):
        fm.append_records(path, [_record(500 + 10 * k + i) for i in range(3)])
    store.compact_map(path)
    assert len(parts.read_manifest(path).parts) == 1
    assert_no_drift(path)
    single = tmp_path / "single.parquet"
    store.write_map_copy(single, fm.read_map(path))
    assert open_map(single).stored_group_rows() is None      # a single file has none
    store.upgrade_map(single)
    assert_no_drift(single)


def test_a_folder_without_stored_groups_computes_them_then_stores_them(path: Path) -> None:
    """A map folder written before groups were stored reads as before, and its next
    write stores them (all of them: there is nothing to bring up to date)."""
    manifest = parts.read_manifest(path)
    old = parts.Manifest(manifest.generation + 1, manifest.parts, manifest.written_at,
                         manifest.tribopipe_version, manifest.sources)  # no groups
    parts.commit(path, old, manifest)
    snap = open_map(path)
    assert snap.stored_group_rows() is None
    pd.testing.assert_frame_equal(snap.groups(), group_statistics(fm.read_map(path)))
    fm.append_records(path, [_record(600)])
    assert_no_drift(path)


def test_a_changed_groups_file_is_refused(path: Path) -> None:
    entry = parts.read_manifest(path).groups
    assert entry is not None and entry.file.startswith(parts.GROUPS_DIR + "/")
    target = path / entry.file
    data = bytearray(target.read_bytes())
    data[len(data) // 2] ^= 0x01
    target.chmod(0o644)
    target.write_bytes(bytes(data))
    with pytest.raises(MapError, match="fails its checksum"):
        open_map(path).groups()
    with pytest.raises(MapError, match="fails its checksum"):
        fm.append_records(path, [_record(700)])


def test_other_tools_read_the_folder_without_the_groups(path: Path) -> None:
    table = pd.read_parquet(path)
    assert len(table) == 48 and "mu_k_n" not in table.columns


def test_a_batch_review_and_a_reduce_replace_keep_them_equal(
        campaign: Path) -> None:  # noqa: F811 - the fixture of test_review
    """A real batch with a review file (a window, an exclusion, an accept), then `reduce
    --replace` of a reviewed run's export (which reads every column of the map under the
    lock, to give the run its review again)."""
    map_path = campaign / "out" / "friction_map.parquet"
    assert_no_drift(map_path)
    ids = list(fm.read_map(map_path)["measurement_id"])
    review = write_review(campaign, [
        [ids[0], "window", "0.6", "1.1", "0.15", "late", "A. Person", "2026-11-27"],
        [FILES[1], "exclude", "", "", "", "pin slipped", "A. Person", "2026-11-27"],
        [ids[2], "accept", "", "", "", "looked at it", "B. Person", "2026-11-27"]])
    assert batch(campaign, "--review", str(review)).exit_code == 0
    assert_no_drift(map_path)
    assert open_map(map_path).groups()["reviewed"].sum() >= 2
    result = CliRunner().invoke(main, [
        "reduce", str(campaign / "raw" / FILES[0]), "--pin", "Dragonskin 30", "--disc",
        "acrylic glass", "--force", "1", "--temperature", "10", "--repeat", "1",
        "--map", str(map_path), "--out", str(campaign / "out"), "--replace"],
        catch_exceptions=False)
    assert result.exit_code == 0, result.output
    assert_no_drift(map_path)


def test_map_validate_refuses_stored_groups_that_drifted(path: Path) -> None:
    """Stored groups with a changed mean, committed with a valid checksum (as a bug in
    a writer would leave them): `map validate` names the difference, `map compact`
    computes them again."""
    from tribopipe.frictionmap.stored_groups import groups_bytes

    manifest = parts.read_manifest(path)
    rows = open_map(path).stored_group_rows()
    assert rows is not None
    rows = rows.copy()
    rows.loc[0, "mu_k_mean"] += 0.01
    entry = parts.write_groups(path, manifest.generation + 1, groups_bytes(rows), len(rows))
    drifted = parts.Manifest(manifest.generation + 1, manifest.parts, manifest.written_at,
                             manifest.tribopipe_version, manifest.sources, entry)
    parts.commit(path, drifted, manifest)
    with pytest.raises(MapError, match="stored condition groups differ.*mu_k_mean"):
        store.verify_map(path)
    assert len(parts.read_manifest(path).parts) == 1
    assert store.compact_map(path) == (1, 1)   # one part, its groups computed again
    assert_no_drift(path)

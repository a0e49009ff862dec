"""A map that cannot be silently corrupted, and rows that cannot come in broken.

* Every map carries the SHA-256 of its content in its Parquet metadata, checked on every
  read: a flipped bit is refused in one line (or, where it hits bytes that hold no value,
  read identically), never read with changed values, never rewritten as a valid map.
* A damaged map's Arrow, JSON, metadata, Unicode and key errors are one ``MapError`` line.
* ``map merge`` and ``map import`` check every row as a reduced record is checked.
* A rewrite keeps the map's file mode (or the umask's for a new map) and its previous
  version as ``<map>.bak``; a map written before the checksum existed still reads.
"""

from __future__ import annotations

import json
import os
import random
import shutil
import stat
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from hostile import assert_clean_failure, invoke
from map_files import map_bytes, single_file, the_part
from reduced_runs import make_processed
from tribopipe import frictionmap as fm
from tribopipe.errors import MapError
from tribopipe.frictionmap.schema import content_sha256

#: flips per test run (seeded): a few hundred, a few seconds
N_FLIPS = 300


@pytest.fixture(scope="module")
def small_map(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A real map: six reduced runs and ten rows of the published map imported, as one
    Parquet file (the format before map folders of parts, whose reader checks every row
    and the checksum of the rows; a map folder's parts are checked by
    tests/test_frictionmap_parts.py)."""
    root = tmp_path_factory.mktemp("hostile_map")
    map_path, _ = make_processed(root)
    lines = fm.published.published_csv_path().read_text(encoding="utf-8").splitlines()[:11]
    table = root / "published_part.csv"
    table.write_text("\n".join(lines) + "\n", encoding="utf-8")
    fm.import_table(map_path, table)
    return single_file(map_path, root / "single.parquet")


def _copy(src: Path, dst: Path) -> Path:
    dst.write_bytes(src.read_bytes())
    return dst


def _rewrite_parquet(src: Path, dst: Path, *, change_table=None, change_info=None) -> Path:
    """Write ``src``'s table to ``dst`` through pyarrow, changed, keeping our metadata
    (``change_info`` edits its JSON) — what another program editing the map would do."""
    table = pq.read_table(src)
    meta = dict(table.schema.metadata)
    if change_table is not None:
        table = change_table(table)
    info = json.loads(meta[fm.schema.META_KEY])
    if change_info is not None:
        change_info(info)
    meta[fm.schema.META_KEY] = json.dumps(info).encode()
    pq.write_table(table.replace_schema_metadata(meta), dst)
    return dst


# ------------------------------------------------------------------ the checksum


def test_the_map_carries_the_checksum_of_its_content(small_map: Path) -> None:
    info = fm.store.map_metadata(small_map)
    runs = fm.read_map(small_map)
    assert info["content_sha256"] == content_sha256(runs)
    assert len(runs) == 16


def test_a_value_changed_by_another_program_fails_the_checksum(small_map: Path,
                                                               tmp_path: Path) -> None:
    def nudge(table: pa.Table) -> pa.Table:
        mu = table.column("mu_k").to_pylist()
        mu[3] = mu[3] + 0.01          # a plausible value: only the checksum can tell
        return table.set_column(table.schema.get_field_index("mu_k"), "mu_k",
                                pa.array(mu, pa.float64()))
    edited = _rewrite_parquet(small_map, tmp_path / "edited.parquet", change_table=nudge)
    before = edited.read_bytes()
    with pytest.raises(MapError, match="fails its checksum") as info:
        fm.read_map(edited)
    assert str(edited) in str(info.value) and "\n" not in str(info.value)
    # and nothing rewrites it as a valid map
    with pytest.raises(MapError, match="fails its checksum"):
        fm.append_records(edited, [])
    with pytest.raises(MapError, match="fails its checksum"):
        fm.exclude_runs(edited, [fm.read_map(small_map)["measurement_id"].iloc[0]], "x")
    assert edited.read_bytes() == before


def test_the_refusal_names_the_previous_version_to_restore(small_map: Path,
                                                           tmp_path: Path) -> None:
    map_path = _copy(small_map, tmp_path / "map.parquet")
    first = fm.read_map(map_path)["measurement_id"].iloc[0]
    fm.exclude_runs(map_path, [first], "pin debonded")      # a rewrite keeps the old map
    backup = fm.store.backup_path(map_path)
    assert backup.read_bytes() == small_map.read_bytes()
    _rewrite_parquet(map_path, map_path, change_table=lambda t: t.slice(0, 15))
    with pytest.raises(MapError) as info:
        fm.read_map(map_path)
    message = str(info.value)
    assert "fails its checksum" in message and f"restore it from {backup}" in message
    result = invoke("map", "show", "--map", str(map_path))
    assert "restore it from" in assert_clean_failure(result)


def test_a_map_from_before_the_checksum_reads_and_gains_one(small_map: Path,
                                                            tmp_path: Path) -> None:
    legacy = _rewrite_parquet(small_map, tmp_path / "legacy.parquet",
                              change_info=lambda info: info.pop("content_sha256"))
    assert "content_sha256" not in fm.store.map_metadata(legacy)
    pd.testing.assert_frame_equal(fm.read_map(legacy), fm.read_map(small_map))
    first = fm.read_map(legacy)["measurement_id"].iloc[0]
    fm.exclude_runs(legacy, [first], "checked by hand")
    assert fm.store.map_metadata(legacy)["content_sha256"] == content_sha256(fm.read_map(legacy))


@pytest.mark.parametrize(("column", "value"), [
    ("u_mu_s", -1.0), ("u_mu_k", float("inf")), ("u_mu_k", 5e3),
])
def test_a_map_row_with_an_impossible_uncertainty_is_refused_on_read(
        small_map: Path, tmp_path: Path, column: str, value: float) -> None:
    bad = _bad_other(small_map, tmp_path / "bad.parquet", column, value)
    with pytest.raises(MapError, match=column) as info:
        fm.read_map(bad)
    assert str(bad) in str(info.value) and "\n" not in str(info.value)
    stderr = assert_clean_failure(invoke("map", "show", "--map", str(bad)))
    assert column in stderr and len(stderr.strip().splitlines()) == 1, stderr


def test_a_missing_uncertainty_reads_the_same_stored_as_nan_or_as_null(
        small_map: Path, tmp_path: Path) -> None:
    """u_mu_s/u_mu_k are nullable (imported rows have none): a NaN cell and a null cell
    both read as missing, and neither is refused."""
    runs = fm.read_map(small_map)
    reduced = int(runs.index[runs["source"] == fm.schema.SOURCE_REDUCED][0])
    as_null = _bad_other(small_map, tmp_path / "null.parquet", "u_mu_k", None)
    as_nan = _bad_other(small_map, tmp_path / "nan.parquet", "u_mu_k", float("nan"))
    read_null, read_nan = fm.read_map(as_null), fm.read_map(as_nan)
    assert pd.isna(read_null["u_mu_k"].iloc[2]) and pd.isna(read_nan["u_mu_k"].iloc[2])
    pd.testing.assert_frame_equal(read_null, read_nan)
    assert runs["u_mu_k"].iloc[reduced] > 0        # a reduced run has one


def test_a_checksum_written_by_an_older_schema_still_verifies(small_map: Path,
                                                              tmp_path: Path) -> None:
    """A map whose schema version predates columns we added since is checked over the
    columns it had: an upgrade of tribopipe never makes a sound map fail its checksum."""
    gone = [name for name, added in fm.schema.ADDED_IN_VERSION.items()
            if added == fm.schema.SCHEMA_VERSION]
    old_digest = content_sha256(fm.read_map(small_map), fm.schema.SCHEMA_VERSION - 1)
    assert old_digest != content_sha256(fm.read_map(small_map))

    def downgrade(info: dict) -> None:
        info["schema_version"] = fm.schema.SCHEMA_VERSION - 1
        info["content_sha256"] = old_digest
    older = _rewrite_parquet(small_map, tmp_path / "older.parquet",
                             change_table=lambda t: t.drop_columns(gone),
                             change_info=downgrade)
    runs = fm.read_map(older)
    assert runs[gone].isna().all().all()
    pd.testing.assert_frame_equal(runs.drop(columns=gone),
                                  fm.read_map(small_map).drop(columns=gone))

    def nudge(table: pa.Table) -> pa.Table:
        mu = table.column("mu_k").to_pylist()
        mu[3] = mu[3] + 0.01
        return table.set_column(table.schema.get_field_index("mu_k"), "mu_k",
                                pa.array(mu, pa.float64()))
    edited = _rewrite_parquet(older, tmp_path / "edited.parquet", change_table=nudge)
    with pytest.raises(MapError, match="fails its checksum"):
        fm.read_map(edited)


def test_damaged_pandas_metadata_does_not_decide_how_the_map_reads(small_map: Path,
                                                                   tmp_path: Path) -> None:
    table = pq.read_table(small_map)
    meta = dict(table.schema.metadata)
    pandas_meta = json.loads(meta[b"pandas"])
    for column in pandas_meta["columns"]:
        column.pop("numpy_type", None)     # was KeyError: 'numpy_type'
    meta[b"pandas"] = json.dumps(pandas_meta).encode()
    damaged = tmp_path / "pandas_meta.parquet"
    pq.write_table(table.replace_schema_metadata(meta), damaged)
    pd.testing.assert_frame_equal(fm.read_map(damaged), fm.read_map(small_map))


@pytest.mark.slow  # a real process or a larger data set: `pytest -m slow`
def test_every_flipped_bit_is_refused_or_reads_identically(small_map: Path,
                                                           tmp_path: Path) -> None:
    raw = small_map.read_bytes()
    original = fm.read_map(small_map)
    target = tmp_path / "flipped.parquet"
    rng = random.Random(9)
    outcomes = {"refused": 0, "identical": 0}
    for _ in range(N_FLIPS):
        position, bit = rng.randrange(len(raw)), rng.randrange(8)
        flipped = bytearray(raw)
        flipped[position] ^= 1 << bit
        target.write_bytes(bytes(flipped))
        try:
            runs = fm.read_map(target)
        except MapError as exc:
            assert "\n" not in str(exc) and str(target) in str(exc)
            outcomes["refused"] += 1
            continue
        # the flip hit bytes that carry no value (statistics, padding, our write time)
        try:
            pd.testing.assert_frame_equal(runs, original)
        except AssertionError as exc:
            raise AssertionError(f"bit {bit} of byte {position} changed the map's values "
                                 f"and was read: {exc}") from None
        outcomes["identical"] += 1
    assert outcomes["refused"] > N_FLIPS // 5 and outcomes["identical"] > 0, outcomes


@pytest.mark.slow  # a real process or a larger data set: `pytest -m slow`
def test_map_merge_of_flipped_maps_is_one_line(small_map: Path, tmp_path: Path) -> None:
    ours = tmp_path / "ours.parquet"
    fm.import_table(ours)                      # the published map
    saved = shutil.copytree(ours, tmp_path / "saved.parquet")
    raw = small_map.read_bytes()
    rng = random.Random(4)
    other = tmp_path / "other.parquet"
    refused = 0
    for _ in range(40):
        flipped = bytearray(raw)
        flipped[rng.randrange(len(raw))] ^= 1 << rng.randrange(8)
        other.write_bytes(bytes(flipped))
        result = invoke("map", "merge", str(other), "--map", str(ours))
        assert "Traceback" not in result.output, result.output
        assert result.exception is None or isinstance(result.exception, SystemExit), \
            f"{type(result.exception).__name__}: {result.exception}"
        if result.exit_code == 1:
            assert len(result.stderr.strip().splitlines()) == 1, result.stderr
            refused += 1
        else:
            assert result.exit_code == 0, result.output
            shutil.rmtree(ours)                # a clean merge: start again from ours
            shutil.copytree(saved, ours)
    assert refused > 5


# ------------------------------------------------------------------ merge and import


def _bad_other(src: Path, dst: Path, column: str, value, arrow_type=None) -> Path:
    """Another lab's map, written like a legacy map (no checksum), with one bad cell."""
    def change(table: pa.Table) -> pa.Table:
        values = table.column(column).to_pylist()
        values[2] = value
        kind = arrow_type or table.schema.field(column).type
        if arrow_type is not None and arrow_type == pa.string():
            values = [str(v).lower() for v in values]
        return table.set_column(table.schema.get_field_index(column), column,
                                pa.array(values, kind))
    return _rewrite_parquet(src, dst, change_table=change,
                            change_info=lambda info: info.pop("content_sha256"))


@pytest.mark.parametrize(("column", "value", "arrow_type", "expected"), [
    ("normal_force_N", -3.0, None, "normal_force_N"),
    ("mu_k", -0.4, None, "mu_k"),
    ("mu_k", 1e306, None, "mu_k"),
    ("temperature_C", -300.0, None, "temperature_C"),
    ("temperature_C", float("inf"), None, "temperature_C"),
    ("pressure_measured_kPa", float("inf"), None, "pressure_measured_kPa"),
    ("excluded", False, pa.string(), "excluded"),     # "false" marked every run excluded
    ("pin", "Dragonskin\n*HEADING", None, "pin"),
    ("disc", "steel\u202e", None, "disc"),
    ("repeat", 10**12, None, "repeat"),
    ("u_mu_k", -1.0, None, "u_mu_k"),
    ("u_mu_s", float("inf"), None, "u_mu_s"),
    ("u_mu_s", 1e306, None, "u_mu_s"),
])
def test_map_merge_checks_every_row(small_map: Path, tmp_path: Path, column: str, value,
                                    arrow_type, expected: str) -> None:
    other = _bad_other(small_map, tmp_path / "other.parquet", column, value, arrow_type)
    ours = tmp_path / "ours.parquet"
    fm.import_table(ours)
    before = map_bytes(ours)
    stderr = assert_clean_failure(invoke("map", "merge", str(other), "--map", str(ours)))
    assert str(other) in stderr and expected in stderr, stderr
    assert len(stderr.strip().splitlines()) == 1, stderr
    assert map_bytes(ours) == before


HEADER = "pin,disc,contactForce,contactPressure,temperature,measurementNo,cof\n"


@pytest.mark.parametrize(("row", "column"), [
    ("DS30,steel,-3,-35.37,20,1,0.5\n", "normal_force_N"),
    ("DS30,steel,3,35.37,20,1,-0.5\n", "mu_k"),
    ("DS30,steel,3,35.37,-300,1,0.5\n", "temperature_C"),
    ("DS30,steel,3,35.37,20,1,1e306\n", "mu_k"),
    ('"DS30\n*HEADING",steel,3,35.37,20,1,0.5\n', "pin"),
    ("DS30,steel,3,35.37,20,1e30,0.5\n", "repeat"),
])
def test_map_import_checks_every_row(tmp_path: Path, row: str, column: str) -> None:
    table = tmp_path / "theirs.csv"
    table.write_text(HEADER + "DS30,steel,1,11.79,20,1,0.6\n" + row, encoding="utf-8")
    ours = tmp_path / "ours.parquet"
    stderr = assert_clean_failure(invoke("map", "import", str(table), "--map", str(ours)))
    assert f"{table}:3" in stderr or f"{table}:" in stderr, stderr
    assert len(stderr.strip().splitlines()) == 1, stderr
    assert not ours.exists()


def test_a_frictionmap_csv_we_wrote_reads_back_with_formula_names(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    table = tmp_path / "theirs.csv"
    table.write_text(HEADER + "=HYPERLINK(x),-cmd,3,35.37,20,1,0.5\n", encoding="utf-8")
    ours = tmp_path / "ours.parquet"
    monkeypatch.chdir(tmp_path)  # the lab's materials file names them: they are data
    refused = invoke("map", "import", str(table), "--map", str(ours))
    assert refused.exit_code == 1 and "unknown pin '=HYPERLINK(x)'" in refused.output
    Path("materials.toml").write_text(
        '[materials]\n"=HYPERLINK(x)" = { class = "other" }\n"-cmd" = { class = "other" }\n',
        encoding="utf-8")
    assert invoke("map", "import", str(table), "--map", str(ours)).exit_code == 0
    out = invoke("map", "table", "--format", "frictionmap", "--map", str(ours)).stdout
    assert "'=HYPERLINK(x),'-cmd," in out
    again = tmp_path / "again.csv"
    again.write_text(out, encoding="utf-8")
    runs = fm.read_map(ours)
    back = fm.published.read_frictionmap_table(again)
    assert (back["pin"][0], back["disc"][0]) == (runs["pin"][0], runs["disc"][0])


# ------------------------------------------------------------------ file mode


def test_a_rewrite_keeps_the_maps_mode(small_map: Path, tmp_path: Path) -> None:
    map_path = _copy(small_map, tmp_path / "shared.parquet")
    map_path.chmod(0o664)                      # colleagues on the shared drive read it
    first = fm.read_map(map_path)["measurement_id"].iloc[0]
    fm.exclude_runs(map_path, [first], "pin debonded")
    assert stat.S_IMODE(map_path.stat().st_mode) == 0o664


@pytest.mark.parametrize(("umask", "mode"), [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_a_new_map_gets_the_umasks_mode(tmp_path: Path, umask: int, mode: int) -> None:
    old = os.umask(umask)
    try:
        fm.import_table(tmp_path / "new.parquet")
    finally:
        os.umask(old)
    folder = tmp_path / "new.parquet"
    files = [folder / fm.parts.MANIFEST, the_part(folder)]
    assert [stat.S_IMODE(f.stat().st_mode) for f in files] == [mode, mode]
    assert stat.S_IMODE(folder.stat().st_mode) == 0o777 & ~umask


def test_a_commit_keeps_the_map_folder_s_mode(small_map: Path, tmp_path: Path) -> None:
    folder = tmp_path / "shared.parquet"
    fm.write_map(folder, fm.read_map(small_map))
    for f in folder.iterdir():
        f.chmod(0o664)                         # colleagues on the shared drive read it
    first = fm.read_map(folder)["measurement_id"].iloc[0]
    fm.exclude_runs(folder, [first], "pin debonded")
    assert stat.S_IMODE(the_part(folder).stat().st_mode) == 0o664
    assert stat.S_IMODE((folder / fm.parts.MANIFEST).stat().st_mode) == 0o664

"""Maps written before this version still read, and keep what they say.

``tests/data/frictionmap_v1.parquet`` was written by tribopipe with schema version 1 and
reduction method ``tribopipe-v1`` (see ``tests/data/README.md``); its reduced run is
regenerated here byte for byte from its seed. Issue 14: the uncertainty columns are new
(schema version 3; ``lab`` came in version 2), a v1 run keeps its method in the map until
it is re-reduced with ``--replace``.

``tests/data/friction_map_v3.parquet`` and ``tests/data/package_v3/`` were written by the
code of schema version 3 (``scripts/make_v3_fixtures.py``), before the ``test`` and
``result`` columns of version 4: a session export of two tests, the published rows, one
excluded run. They read, validate and merge with those columns missing, and the same
export reduced by today's code gives the same run ids.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.files import file_sha256

DATA = Path(__file__).parent / "data"
V1_MAP = DATA / "frictionmap_v1.parquet"
V3_MAP = DATA / "friction_map_v3.parquet"
V3_PACKAGE = DATA / "package_v3"
V1_RUN = SyntheticRun(mu_s=0.8, mu_k=0.55, noise=0.005, duration_s=120.0, seed=14)
LABELS = ["--pin", "Dragonskin 30", "--disc", "steel", "--force", "3", "--temperature", "20",
          "--repeat", "1"]


@pytest.fixture
def v1_map(tmp_path: Path) -> Path:
    target = tmp_path / "friction_map.parquet"
    shutil.copyfile(V1_MAP, target)
    return target


@pytest.fixture
def v1_export(tmp_path: Path) -> Path:
    return write_rheocompass_export(tmp_path / "v1_run.csv", V1_RUN, project="v1",
                                    test="Friction", sample="pin")


def reduced_row(runs):
    return runs[runs["source"] == fm.schema.SOURCE_REDUCED].iloc[0]


def test_a_version_1_map_reads_with_the_new_columns_missing() -> None:
    info = json.loads(pq.read_schema(V1_MAP).metadata[fm.schema.META_KEY])
    assert info["schema_version"] == 1
    assert "u_mu_k" not in pq.read_schema(V1_MAP).names
    assert "lab" not in pq.read_schema(V1_MAP).names
    runs = fm.read_map(V1_MAP)
    assert len(runs) == 4
    assert runs["u_mu_k"].isna().all() and runs["u_mu_s"].isna().all()
    assert runs["lab"].isna().all()
    row = reduced_row(runs)
    assert row["method"].startswith("tribopipe-v1")
    assert row["mu_k"] == pytest.approx(0.55, abs=0.01)


def test_the_regenerated_export_is_the_run_in_the_v1_map(v1_export: Path) -> None:
    assert file_sha256(v1_export) == reduced_row(fm.read_map(V1_MAP))["file_hash"]


def test_writing_to_an_old_map_keeps_its_rows_and_stores_the_current_schema(
    v1_map: Path, tmp_path: Path
) -> None:
    other = tmp_path / "other.csv"
    write_rheocompass_export(other, SyntheticRun(seed=15, duration_s=180.0), project="v2",
                             test="Friction", sample="pin")
    result = CliRunner().invoke(main, ["reduce", str(other), *LABELS, "--repeat", "2",
                                       "--map", str(v1_map), "--output", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    info = json.loads(pq.read_schema(v1_map).metadata[fm.schema.META_KEY])
    assert info["schema_version"] == fm.schema.SCHEMA_VERSION == 6
    runs = fm.read_map(v1_map)
    assert len(runs) == 5
    old = runs[runs["method"].str.startswith("tribopipe-v1")]
    assert len(old) == 1 and math.isnan(old["u_mu_k"].iloc[0])
    assert math.isnan(old["nominal_speed_mm_s"].iloc[0])
    new = runs[runs["method"].str.startswith("tribopipe-v2")]
    assert len(new) == 1 and 0 < new["u_mu_k"].iloc[0] < 0.1
    assert new["nominal_speed_mm_s"].iloc[0] > 0


def test_a_v1_run_keeps_its_method_until_replaced(v1_map: Path, v1_export: Path,
                                                   tmp_path: Path) -> None:
    args = ["reduce", str(v1_export), *LABELS, "--map", str(v1_map),
            "--output", str(tmp_path / "out")]
    kept = CliRunner().invoke(main, args)
    assert kept.exit_code == 0, kept.output
    assert "1 kept conflicting" in kept.output
    row = reduced_row(fm.read_map(v1_map))
    assert row["method"].startswith("tribopipe-v1") and math.isnan(row["u_mu_k"])

    replaced = CliRunner().invoke(main, [*args, "--replace"])
    assert replaced.exit_code == 0, replaced.output
    assert "1 replaced" in replaced.output
    runs = fm.read_map(v1_map)
    assert len(runs) == 4  # the same run, updated in place; the imported rows untouched
    row = reduced_row(runs)
    assert row["method"].startswith("tribopipe-v2")
    assert row["u_mu_k"] > 0 and row["u_mu_s"] >= row["u_mu_k"]
    assert (runs["method"] == "published").sum() == 3


def v3_fixture_script():
    """``scripts/make_v3_fixtures.py`` as a module (its session's tests and seeds)."""
    import importlib.util

    path = Path(__file__).parents[1] / "scripts" / "make_v3_fixtures.py"
    spec = importlib.util.spec_from_file_location("make_v3_fixtures", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_version_3_map_reads_with_test_and_result_missing() -> None:
    info = json.loads(pq.read_schema(V3_MAP).metadata[fm.schema.META_KEY])
    assert info["schema_version"] == 3
    assert {"test", "result"}.isdisjoint(pq.read_schema(V3_MAP).names)
    runs = fm.read_map(V3_MAP)
    assert len(runs) == 5 and runs["test"].isna().all() and runs["result"].isna().all()
    reduced = runs[runs["source"] == fm.schema.SOURCE_REDUCED]
    assert reduced["interval"].notna().all() and reduced["u_mu_k"].notna().all()
    assert reduced["excluded"].tolist() == [False, True]


def test_the_session_reduced_again_is_the_same_two_runs_and_fills_nothing_in(
    tmp_path: Path
) -> None:
    from generators.synthetic import write_rheocompass_session
    from tribopipe.config import load_settings
    from tribopipe.labels import RunLabels
    from tribopipe.pipeline import reduce_export

    script = v3_fixture_script()
    target = tmp_path / "friction_map.parquet"
    shutil.copyfile(V3_MAP, target)
    raw = write_rheocompass_session(tmp_path / "v3_session.txt", script.session_tests(),
                                    project="v3")
    old = fm.read_map(target)
    assert file_sha256(raw) in set(old["file_hash"])  # the export, byte for byte
    settings = load_settings()
    done = reduce_export(raw, settings, lambda export, place, name: RunLabels(
        "Dragonskin 30", "steel", script.TESTS[place.test][2], 20.0, 1))
    records = [run.record for run in done.reduced]
    assert {r.test for r in records} == set(script.TESTS)
    report = fm.append_records(target, records)
    # ids hash the test and result as before: the same runs, nothing added or in conflict
    assert len(report.unchanged_ids) == 2 and not report.added_ids
    assert not report.conflicting_ids
    # nothing changed, so nothing is written: the map stays as the old code left it
    assert fm.store.map_metadata(target)["schema_version"] == 3
    assert fm.read_map(target).equals(old)


def test_a_version_3_package_validates_and_merges(tmp_path: Path) -> None:
    checked = CliRunner().invoke(main, ["map", "validate", str(V3_PACKAGE)])
    assert checked.exit_code == 0, checked.output
    assert checked.output.strip().endswith(
        f"valid friction-map package from Fixture Lab, 5 runs: 3 measured by "
        f"{fm.published.PUBLISHED_LAB}, 2 measured by Fixture Lab")
    merged = tmp_path / "merged.parquet"
    result = CliRunner().invoke(main, ["map", "merge", str(V3_PACKAGE), "--map", str(merged)])
    assert result.exit_code == 0, result.output
    runs = fm.read_map(merged)
    assert len(runs) == 5 and set(runs["lab"]) >= {"Fixture Lab"}
    assert runs["test"].isna().all() and runs["result"].isna().all()
    assert fm.store.map_metadata(merged)["schema_version"] == fm.schema.SCHEMA_VERSION == 6


def test_map_show_runs_names_what_each_map_knows_of_a_run_s_origin(tmp_path: Path) -> None:
    old = CliRunner().invoke(main, ["map", "show", "--runs", "--map", str(V3_MAP)])
    assert old.exit_code == 0, old.output
    lines = [ln.strip() for ln in old.output.splitlines()]
    session = [ln for ln in lines if "v3_session.txt" in ln]
    # the excluded run in the summary and both runs in the list; no test a v3 map lacks
    assert len(session) == 3 and all("[interval 2]" in ln for ln in session)
    assert sum("(excluded)" in ln for ln in session) == 1
    assert sum("frictionmap_published.csv" in ln for ln in lines) == 3

    script = v3_fixture_script()
    from generators.synthetic import write_rheocompass_session

    folder = tmp_path / "raw"
    folder.mkdir()
    write_rheocompass_session(folder / "v4_session.txt", script.session_tests(), project="v4")
    manifest = folder / "manifest.csv"
    manifest.write_text("file,test,pin,disc,normal_force_N,temperature_C,repeat\n" + "".join(
        f'v4_session.txt,"{name}",Dragonskin 30,steel,{force},20,1\n'
        for name, (_, _, force, _) in script.TESTS.items()), encoding="utf-8")
    new_map = tmp_path / "friction_map.parquet"
    batch = CliRunner().invoke(main, ["batch", str(folder), "--manifest", str(manifest),
                                      "--map", str(new_map), "--output", str(tmp_path / "o"),
                                      "--no-plots", "-j", "1"])
    assert batch.exit_code == 0, batch.output
    shown = CliRunner().invoke(main, ["map", "show", "--runs", "--map", str(new_map)])
    assert shown.exit_code == 0, shown.output
    for name in script.TESTS:
        (line,) = [ln for ln in shown.output.splitlines() if name in ln]
        assert f"v4_session.txt [{name} / " in line and "/ interval 2]" in line
    plain = CliRunner().invoke(main, ["map", "show", "--map", str(new_map)]).output
    assert "v4_session.txt" not in plain  # the list only with --runs


def test_a_column_added_later_missing_in_the_older_row_is_no_difference() -> None:
    """The rule lives beside the schema versions: every content column a later schema
    added, missing in the map's older row, is no difference of the run; present and
    different, it is one."""
    import dataclasses

    from test_frictionmap import run_record
    from tribopipe.frictionmap.schema import (
        ADDED_IN_VERSION,
        ADDED_LATER_CONTENT,
        CONTENT_COLUMNS,
        REVIEW_COLUMNS,
    )

    # a review's columns are the exception: missing there means "not reviewed"
    assert ADDED_LATER_CONTENT == {c for c in ADDED_IN_VERSION if c in CONTENT_COLUMNS
                                   and c not in REVIEW_COLUMNS}
    new = run_record(1)
    older = dataclasses.replace(new, **dict.fromkeys(ADDED_LATER_CONTENT))
    runs = fm.records_frame([older])
    _, report = fm.store.fold_records(runs, [new])
    assert report.unchanged_ids == (new.measurement_id,) and not report.conflicting_ids
    changed = dataclasses.replace(new, u_mu_k=(new.u_mu_k or 0.0) + 0.01)
    _, report = fm.store.fold_records(fm.records_frame([new]), [changed])
    assert report.conflicting_ids == (new.measurement_id,)
    assert report.differences[new.measurement_id] == ("u_mu_k",)

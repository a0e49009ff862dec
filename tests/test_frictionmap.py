"""The friction-map store: records from real reductions, schema checks, idempotent append,
replace, refusal of foreign files, import of the published map, merge and exclusions.

The helpers at the top (``reduced_result``, ``run_record``) are shared by the other
``test_frictionmap_*`` modules.
"""

from __future__ import annotations

import functools
import hashlib
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from conftest import shared_file
from generators.synthetic import SyntheticRun, make_intervals
from map_files import map_bytes, the_part
from tribopipe import __version__
from tribopipe import frictionmap as fm
from tribopipe.config import InstrumentConfig, load_settings, settings_from_dict
from tribopipe.errors import MapError, ValidationError
from tribopipe.labels import RunLabels, Tolerances, decide_run
from tribopipe.measurement import Measurement, MeasurementMeta
from tribopipe.reduction.reduce import ReductionResult, reduce_measurement

PUBLISHED_CSV = fm.published.published_csv_path()


@functools.cache
def reduced_result() -> ReductionResult:
    """A real reduction of a seeded synthetic run (μ_S 0.8, μ_K 0.55, 3 N, 20 °C)."""
    settings = load_settings()
    frames = make_intervals(SyntheticRun(seed=7, duration_s=180))
    meta = MeasurementMeta(source_file="run.txt", file_format="synthetic", interval=2)
    return reduce_measurement(Measurement(frames[-1], meta), settings.instrument,
                              settings.reduction)


def file_hash_of(i: int) -> str:
    """A stand-in SHA-256 of raw file number ``i``."""
    return hashlib.sha256(f"raw file {i}".encode()).hexdigest()


def run_record(
    i: int = 0,
    *,
    pin: str | None = "Ecoflex 00-50",
    disc: str | None = "steel",
    force_N: float | None = 3.0,
    temperature_C: float | None = 20.0,
    repeat: int | None = 1,
    settings=None,
    **result_changes,
) -> dict:
    """The map record of raw file ``i``: the real reduction with ``result_changes``
    (e.g. ``mu_k=0.5``) applied, labelled with the given nominal conditions."""
    result = replace(reduced_result(), **result_changes)
    meta = MeasurementMeta(source_file=f"data/run{i}.txt", file_format="synthetic", interval=2)
    labels = RunLabels(pin=pin, disc=disc, normal_force_N=force_N,
                       temperature_C=temperature_C, repeat=repeat)
    return record_of(result, labels, meta, file_hash_of(i), settings or load_settings())


def record_of(result, labels, meta, file_hash, settings, tolerances=None):
    """``make_record`` of a run whose flags are decided by ``decide_run`` from ``labels``
    and ``tolerances``, as the pipeline decides them."""
    verdict = decide_run(labels, result.flags, result.normal_force_mean_N,
                         result.temperature_C, tolerances,
                         speed_set_point_rpm=result.speed_set_point_rpm,
                         sliding_speed_measured_mm_s=result.sliding_speed_mm_s,
                         instrument=settings.instrument)
    return fm.make_record(result=result, verdict=verdict, meta=meta, file_hash=file_hash,
                          settings=settings)


# --------------------------------------------------------------------------- records


def test_nominal_pressure_converts_newtons_on_three_pins_to_kilopascal():
    cell = InstrumentConfig()
    # (1 N / 3) / (π · 9 mm²) = 0.011789 N/mm² = 11.789 kPa: the published 11.79
    assert cell.pressure_kPa(1.0) == pytest.approx(1 / 3 / (math.pi * 9e-6) / 1e3)
    assert round(cell.pressure_kPa(1.0), 2) == 11.79
    assert round(cell.pressure_kPa(9.0), 1) == 106.1
    one_pin = InstrumentConfig(n_pins=1, pin_radius_mm=2.0)
    assert one_pin.pressure_kPa(1.0) == pytest.approx(1.0 / (math.pi * 4e-6) / 1e3)


def test_make_record_carries_the_reduction_and_its_provenance():
    result = reduced_result()
    settings = load_settings()
    rec = run_record(5, force_N=3.0, temperature_C=20.0, repeat=2)
    assert set(rec.as_dict()) == set(fm.RUN_COLUMNS)
    assert rec.mu_s == result.mu_s and rec.mu_k == result.mu_k
    assert 0.75 < rec.mu_s < 0.85 and 0.5 < rec.mu_k < 0.6  # the synthetic truth
    assert (rec.mu_k_window_start_mm, rec.mu_k_window_end_mm) == result.mu_k_window_mm
    assert (rec.mu_k_window_start_s, rec.mu_k_window_end_s) == result.mu_k_window_s
    assert rec.normal_force_measured_N == result.normal_force_mean_N
    assert rec.pressure_kPa == pytest.approx(settings.instrument.pressure_kPa(3.0))
    assert rec.sliding_speed_mm_s == pytest.approx(0.007, rel=0.02)
    assert rec.source == "reduced" and rec.source_file == "run5.txt"
    assert rec.file_hash == file_hash_of(5) and rec.config_hash == settings.config_hash
    assert rec.tribopipe_version == __version__ and rec.interval == 2
    assert rec.reduced_at.endswith("Z") and rec.excluded is False
    assert rec.flags == ";".join(sorted(result.flags))
    meta = MeasurementMeta(source_file="x", file_format="synthetic", interval=2)
    assert rec.measurement_id == fm.measurement_id(file_hash_of(5), meta)


def test_measurement_id_depends_on_content_and_interval_not_on_the_file_name():
    a = MeasurementMeta(source_file="a.txt", file_format="rheocompass", interval=2)
    renamed = replace(a, source_file="copy of a.txt")
    other_interval = replace(a, interval=3)
    h = file_hash_of(1)
    assert fm.measurement_id(h, a) == fm.measurement_id(h, renamed)
    assert fm.measurement_id(h, a) != fm.measurement_id(h, other_interval)
    assert fm.measurement_id(h, a) != fm.measurement_id(file_hash_of(2), a)
    assert len(fm.measurement_id(h, a)) == 16


def test_missing_nominal_force_uses_the_measured_mean_and_is_flagged():
    rec = run_record(force_N=None, normal_force_mean_N=2.96)
    assert rec.normal_force_N == 3.0
    assert "nominal_force_estimated" in rec.flags.split(";")
    assert rec.pressure_kPa == pytest.approx(InstrumentConfig().pressure_kPa(3.0))


def test_off_nominal_force_and_temperature_are_flagged():
    rec = run_record(force_N=5.0, temperature_C=10.0)  # the run measured 3 N at 20 °C
    assert {"normal_force_off_nominal", "temperature_off_nominal"} <= set(rec.flags.split(";"))
    assert run_record(force_N=3.0, temperature_C=20.0).flags == ""


def test_off_nominal_flags_follow_the_tolerances_given():
    # the run measured ~3 N at 20 °C; nominal 3.2 N is 6 % off: within 10 %, not within 5 %
    result = replace(reduced_result(), normal_force_mean_N=3.0, temperature_C=20.0)
    meta = MeasurementMeta(source_file="data/run.txt", file_format="synthetic", interval=2)
    labels = RunLabels(pin="Ecoflex 00-50", disc="steel", normal_force_N=3.2,
                       temperature_C=21.5, repeat=1)

    def flags(tolerances):
        return record_of(result, labels, meta, file_hash_of(0), load_settings(),
                         tolerances).flags

    assert flags(None) == ""
    assert flags(Tolerances(force_rel=0.05)) == "normal_force_off_nominal"
    assert flags(Tolerances(temperature_C=1.0)) == "temperature_off_nominal"


def test_nominal_pressure_follows_the_instrument_geometry():
    two_mm = settings_from_dict({"instrument": {"pin_radius_mm": 2.0}})
    rec = run_record(force_N=3.0, settings=two_mm)
    assert rec.pressure_kPa == pytest.approx(1.0 / (math.pi * 4.0) * 1e3)
    assert rec.config_hash != run_record(force_N=3.0).config_hash


@pytest.mark.parametrize("labels", [{"pin": None}, {"disc": None}])
def test_a_run_without_pin_or_disc_cannot_be_recorded(labels):
    with pytest.raises(MapError, match="pin and/or disc") as err:
        run_record(**labels)
    assert "run0.txt" in str(err.value) and "--pin" in str(err.value)


def test_a_blank_pin_or_disc_is_refused_where_the_labels_are_made():
    with pytest.raises(ValidationError, match="disc: expected a name"):
        run_record(disc="")


def test_a_run_without_mu_k_is_refused():
    with pytest.raises(MapError, match="mu_k"):
        run_record(mu_k=float("nan"))


def test_records_frame_refuses_a_reduced_row_without_mu_s_and_names_the_column():
    rec = run_record().as_dict()  # a changed copy of a checked record is checked again
    rec["mu_s"] = None
    with pytest.raises(MapError, match="only imported rows may lack mu_s") as err:
        fm.records_frame([rec])
    assert err.value.column == "mu_s"
    del rec["flags"]
    with pytest.raises(MapError, match="lacks column"):
        fm.records_frame([rec])


# --------------------------------------------------------------------------- store


def test_append_then_read_gives_the_same_rows_and_schema_metadata(tmp_path):
    path = tmp_path / "processed" / "friction_map.parquet"
    records = [run_record(i, repeat=i + 1, mu_k=0.5 + 0.01 * i) for i in range(3)]
    report = fm.append_records(path, records)
    assert report.added == 3 and report.added_ids == tuple(r.measurement_id for r in records)
    runs = fm.read_map(path)
    pd.testing.assert_frame_equal(runs, fm.records_frame(records))
    info = pq.read_schema(the_part(path)).metadata[fm.schema.META_KEY]
    assert f'"schema_version": {fm.schema.SCHEMA_VERSION}'.encode() in info
    assert b'"unit": "kPa"' in info
    meta = fm.store.map_metadata(path)
    assert meta["n_runs"] == 3 and meta["sources"] == ["reduced"]
    assert meta["tribopipe_version"] == __version__
    units = {c["name"]: c["unit"] for c in meta["columns"]}
    assert units["pressure_kPa"] == "kPa" and units["sliding_speed_mm_s"] == "mm/s"
    assert [c["name"] for c in meta["columns"]] == list(fm.RUN_COLUMNS)


def test_read_map_of_an_absent_file_is_an_empty_map(tmp_path):
    runs = fm.read_map(tmp_path / "nothing.parquet")
    assert list(runs.columns) == list(fm.RUN_COLUMNS) and runs.empty


def test_appending_the_same_run_twice_keeps_one_row_and_leaves_the_file_alone(tmp_path):
    path = tmp_path / "map.parquet"
    fm.append_records(path, [run_record(1)])
    before = map_bytes(path)
    again = run_record(1)  # a fresh reduction: new reduced_at, same content
    report = fm.append_records(path, [again])
    assert (report.added, report.unchanged) == (0, 1)
    assert map_bytes(path) == before
    assert len(fm.read_map(path)) == 1


def test_a_rereduction_with_another_config_replaces_only_when_asked(tmp_path):
    path = tmp_path / "map.parquet"
    old = run_record(1)
    fm.append_records(path, [old, run_record(2)])
    other_config = settings_from_dict({"reduction": {"median_window": 9}})
    new = run_record(1, settings=other_config, mu_k=0.57)
    kept = fm.append_records(path, [new])
    assert kept.kept_conflicting == 1 and kept.conflicting_ids == (old.measurement_id,)
    assert set(kept.differences[old.measurement_id]) == {"mu_k", "config_hash"}
    assert "pass --replace" in kept.summary()
    assert fm.read_map(path)["mu_k"].iloc[0] == old.mu_k
    replaced = fm.append_records(path, [new], replace=True)
    assert replaced.replaced_ids == (old.measurement_id,)
    runs = fm.read_map(path)
    assert len(runs) == 2 and runs["mu_k"].iloc[0] == 0.57
    assert runs["config_hash"].iloc[0] == other_config.config_hash


def test_a_replaced_run_keeps_its_exclusion(tmp_path):
    path = tmp_path / "map.parquet"
    rec = run_record(1)
    fm.append_records(path, [rec])
    fm.exclude_runs(path, [rec.measurement_id], "pin slipped")
    fm.append_records(path, [run_record(1, mu_k=0.6)], replace=True)
    row = fm.read_map(path).iloc[0]
    assert row["mu_k"] == 0.6 and row["excluded"] and row["exclusion_reason"] == "pin slipped"


def test_fold_records_does_not_modify_its_inputs():
    runs = fm.records_frame([run_record(1)])
    snapshot = runs.copy()
    new = [run_record(1, mu_k=0.7), run_record(2)]
    copies = [r.as_dict() for r in new]
    merged, report = fm.store.fold_records(runs, new, replace=True)
    pd.testing.assert_frame_equal(runs, snapshot)
    assert [r.as_dict() for r in new] == copies
    assert len(merged) == 2 and report.replaced == 1 and report.added == 1


def test_a_text_file_at_the_map_path_is_refused_and_never_overwritten(tmp_path):
    path = tmp_path / "friction_map.parquet"
    path.write_text("pin,disc,mu\nEcoflex,steel,0.5\n")
    before = path.read_bytes()
    with pytest.raises(MapError, match="not a readable Parquet file") as err:
        fm.append_records(path, [run_record(1)])
    assert str(path) in str(err.value)
    assert path.read_bytes() == before
    with pytest.raises(MapError, match="not a readable Parquet file"):
        fm.read_map(path)


def test_a_foreign_parquet_file_is_refused_and_never_overwritten(tmp_path):
    path = tmp_path / "friction_map.parquet"
    pd.DataFrame({"mu_k": [0.5]}).to_parquet(path)
    before = path.read_bytes()
    for action in (
        lambda: fm.read_map(path),
        lambda: fm.append_records(path, [run_record(1)]),
        lambda: fm.import_table(path, PUBLISHED_CSV),
        lambda: fm.write_map(path, fm.records_frame([run_record(1)])),
    ):
        with pytest.raises(MapError, match="not a tribopipe friction map") as err:
            action()
        assert str(path) in str(err.value)
    assert path.read_bytes() == before


def test_a_map_from_a_newer_schema_or_with_a_missing_column_is_refused(tmp_path):
    path = tmp_path / "map.parquet"
    fm.append_records(path, [run_record(1)])
    table = pq.read_table(path)
    newer = table.replace_schema_metadata(
        {fm.schema.META_KEY: b'{"schema": "tribopipe.frictionmap", "schema_version": 99}'}
    )
    pq.write_table(newer, tmp_path / "newer.parquet")
    with pytest.raises(MapError, match="schema version 99"):
        fm.read_map(tmp_path / "newer.parquet")
    pq.write_table(table.drop_columns(["mu_k"]), tmp_path / "cut.parquet")
    with pytest.raises(MapError, match="lacks column") as err:
        fm.read_map(tmp_path / "cut.parquet")
    assert err.value.column == "mu_k"


def test_a_map_with_a_nan_mu_k_is_refused_on_read(tmp_path):
    path = tmp_path / "map.parquet"  # a single-file map: its reader checks every row
    fm.store.write_map_copy(path, fm.records_frame([run_record(1)]))
    table = pq.read_table(path)
    i = table.column_names.index("mu_k")
    broken = table.set_column(i, "mu_k", pa.array([float("nan")]))
    pq.write_table(broken, path)
    with pytest.raises(MapError, match="mu_k is nan"):
        fm.read_map(path)


# --------------------------------------------------------------------------- exclusions


def test_exclude_needs_a_reason_keeps_the_run_and_include_restores_it(tmp_path):
    path = tmp_path / "map.parquet"
    recs = [run_record(i, repeat=i) for i in range(1, 4)]
    fm.append_records(path, recs)
    target = recs[1].measurement_id
    with pytest.raises(MapError, match="needs a reason"):
        fm.exclude_runs(path, [target], "  ")
    assert fm.exclude_runs(path, [target[:8]], "air bubble under the pin") == [target]
    runs = fm.read_map(path)
    assert len(runs) == 3
    row = runs.set_index("measurement_id").loc[target]
    assert row["excluded"] and row["exclusion_reason"] == "air bubble under the pin"
    assert fm.exclude_runs(path, [target], "air bubble under the pin") == []  # no change
    assert fm.include_runs(path, [target]) == [target]
    row = fm.read_map(path).set_index("measurement_id").loc[target]
    assert not row["excluded"] and pd.isna(row["exclusion_reason"])


def test_excluding_an_unknown_id_names_it(tmp_path):
    path = tmp_path / "map.parquet"
    fm.append_records(path, [run_record(1)])
    with pytest.raises(MapError, match="no run with measurement id 'deadbeef00'"):
        fm.exclude_runs(path, ["deadbeef00"], "typo")


# --------------------------------------------------------------------------- import


def test_the_shipped_published_csv_is_the_reference_file_byte_for_byte():
    """Every other test reads the shipped copy; this one (skipped without ../shared) ties
    it to the reference file."""
    reference = shared_file("reference", "frictionmap_published.csv")
    assert PUBLISHED_CSV.read_bytes() == reference.read_bytes()


def test_importing_the_published_csv_gives_169_published_rows_without_mu_s(tmp_path):
    path = tmp_path / "map.parquet"
    report = fm.import_table(path)  # the shipped copy
    assert report.added == 169
    runs = fm.read_map(path)
    assert set(runs["source"]) == {fm.schema.SOURCE_PUBLISHED}
    assert runs["mu_s"].isna().all() and np.isfinite(runs["mu_k"]).all()
    assert set(runs["pin"]) == {"Dragonskin 30", "Ecoflex 00-50"}
    assert runs["disc"].nunique() == 9
    assert sorted(runs["normal_force_N"].unique()) == [1.0, 3.0, 5.0, 7.0, 9.0]
    assert (runs["sliding_speed_mm_s"] == 0.007).all()
    assert set(runs["method"]) == {"published"} and runs["config_hash"].isna().all()
    assert runs["measurement_id"].is_unique
    # imported pressure is the published one; it matches the cell geometry to 4 digits
    expected = [InstrumentConfig().pressure_kPa(f) for f in runs["normal_force_N"]]
    np.testing.assert_allclose(runs["pressure_kPa"], expected, rtol=5e-4)


def test_importing_twice_is_idempotent(tmp_path):
    path = tmp_path / "map.parquet"
    fm.import_table(path, PUBLISHED_CSV)
    before = map_bytes(path)
    report = fm.import_table(path, PUBLISHED_CSV)
    assert (report.added, report.unchanged) == (0, 169)
    assert map_bytes(path) == before


def test_the_mat_and_the_csv_import_to_identical_rows(tmp_path):
    mat = shared_file("reference", "FrictionMap.mat")
    from_mat = fm.records_frame(fm.import_records(mat))
    from_csv = fm.records_frame(fm.import_records(PUBLISHED_CSV))
    provenance = ["source_file", "file_hash", "reduced_at"]
    pd.testing.assert_frame_equal(from_mat.drop(columns=provenance),
                                  from_csv.drop(columns=provenance))
    assert set(from_mat["source_file"]) == {"FrictionMap.mat"}
    path = tmp_path / "map.parquet"
    fm.import_table(path, mat)
    assert fm.import_table(path, PUBLISHED_CSV).unchanged == 169


def test_a_published_subset_under_another_name_is_still_published(tmp_path):
    subset = tmp_path / "my_copy.csv"
    lines = PUBLISHED_CSV.read_text().splitlines()
    subset.write_text("\n".join(lines[:11]) + "\n")
    recs = fm.import_records(subset)
    assert {r.source for r in recs} == {fm.schema.SOURCE_PUBLISHED}
    published_ids = {r.measurement_id for r in fm.import_records(PUBLISHED_CSV)}
    assert {r.measurement_id for r in recs} <= published_ids


def test_another_labs_csv_is_labelled_with_its_file_and_has_no_speed(tmp_path):
    other = tmp_path / "lab_b.csv"
    other.write_text(
        "pin,disc,contactForce,contactPressure,temperature,measurementNo,cof\n"
        "Ecoflex 00-50,PTFE,3.0,35.37,23.0,1.0,0.21\n"
        "Ecoflex 00-50,PTFE,3.0,35.37,23.0,2.0,0.23\n"
    )
    recs = fm.import_records(other)
    assert {r.source for r in recs} == {"import:lab_b.csv"}
    assert all(r.sliding_speed_mm_s is None for r in recs)
    labelled = fm.import_records(other, source="lab B 2025")
    assert {r.source for r in labelled} == {"lab B 2025"}
    assert labelled[0].measurement_id != recs[0].measurement_id


@pytest.mark.parametrize(
    ("text", "match", "line", "column"),
    [
        ("pin,disc,contactForce\nA,B,1\n", "missing column", 1, "contactPressure"),
        (
            "pin,disc,contactForce,contactPressure,temperature,measurementNo,cof\n"
            "A,B,1,11.79,20,1,0.5\nA,B,1,11.79,20,2,n/a\n",
            "'n/a' is not a finite number",
            3,
            "cof",
        ),
        (
            "pin,disc,contactForce,contactPressure,temperature,measurementNo,cof\n"
            "A,,1,11.79,20,1,0.5\n",
            "empty, expected a material name",
            2,
            "disc",
        ),
        (
            "pin,disc,contactForce,contactPressure,temperature,measurementNo,cof\n"
            "DS30,steel,1,11.79,20,1,0.5\nDS30,steel,1,11.79,20,1,0.6\n",
            "same pin, disc, force",
            3,
            "measurementNo",
        ),
    ],
)
def test_a_bad_frictionmap_csv_names_the_line_and_column(tmp_path, text, match, line, column):
    bad = tmp_path / "bad.csv"
    bad.write_text(text)
    with pytest.raises(MapError, match=match) as err:
        fm.import_records(bad)
    assert err.value.line == line and err.value.column == column
    assert f"{bad}:{line}:" in str(err.value)


def test_a_mat_file_without_a_table_is_refused(tmp_path):
    from scipy.io import savemat

    path = tmp_path / "numbers.mat"
    savemat(path, {"x": np.arange(3.0)})
    with pytest.raises(MapError, match="holds no MATLAB table") as err:
        fm.import_records(path)
    assert str(path) in str(err.value)


# --------------------------------------------------------------------------- merge


def test_merge_stores_shared_runs_once_and_reports_conflicts(tmp_path):
    ours, theirs = tmp_path / "ours.parquet", tmp_path / "theirs.parquet"
    fm.append_records(ours, [run_record(1), run_record(2)])
    fm.import_table(ours, PUBLISHED_CSV)
    fm.append_records(theirs, [run_record(2), run_record(3), run_record(1, mu_k=0.42)])
    fm.import_table(theirs, PUBLISHED_CSV)
    report = fm.merge_map(ours, theirs).report
    assert report.added == 1 and report.unchanged == 170 and report.kept_conflicting == 1
    assert report.conflicting_ids == (run_record(1).measurement_id,)
    runs = fm.read_map(ours)
    assert len(runs) == 3 + 169 and runs["measurement_id"].is_unique
    assert fm.merge_map(ours, theirs, replace=True).report.replaced == 1


def test_merging_a_map_into_itself_or_a_missing_file_is_refused(tmp_path):
    path = tmp_path / "map.parquet"
    fm.append_records(path, [run_record(1)])
    with pytest.raises(MapError, match="into itself"):
        fm.merge_map(path, path)
    with pytest.raises(MapError, match="file not found"):
        fm.merge_map(path, tmp_path / "absent.parquet")


# --------------------------------------------------------------------------- summary


def test_map_summary_lists_pairs_flags_exclusions_and_repeatability(tmp_path):
    path = tmp_path / "map.parquet"
    fm.import_table(path, PUBLISHED_CSV)
    flagged = run_record(1, force_N=None, normal_force_mean_N=3.0)
    fm.append_records(path, [flagged, run_record(2, repeat=2)])
    fm.exclude_runs(path, [run_record(2).measurement_id], "disc not cleaned")
    text = fm.map_summary(path)
    assert "runs: 171 (1 excluded)" in text
    assert "Ecoflex 00-50 / steel: 16 runs" in text
    assert "nominal_force_estimated 1" in text
    assert "disc not cleaned" in text and run_record(2).measurement_id in text
    assert "repeatability mu_k: s_r =" in text
    assert Path(path).exists()


def test_map_show_lists_a_runs_flags_as_every_output_writes_them(tmp_path):
    """``map show --runs`` writes a run's flags as a list (``a, b``), as the reduce
    table, the report and the batch's flagged lines do, not as the map's cell text."""
    from dataclasses import replace

    from tribopipe.frictionmap.schema import frame_rows
    from tribopipe.frictionmap.summary import run_line

    path = tmp_path / "map.parquet"
    fm.append_records(path, [run_record(1)])
    (row,) = frame_rows(fm.read_map(path))
    row = replace(row, flags="normal_force_off_nominal;temperature_off_nominal")
    assert run_line(row).endswith("; flags normal_force_off_nominal, temperature_off_nominal")
    assert run_line(replace(row, flags="")).endswith("; flags -")


def test_map_summary_names_a_hostile_map_path_on_one_line(tmp_path):
    """The map's path is written as a terminal line (:func:`tribopipe.escape.display_path`):
    a newline or a bidi override in it neither splits the header nor reorders it."""
    path = tmp_path / "evil\nname\u202e.parquet"
    fm.append_records(path, [run_record(1)])
    first, second = fm.map_summary(path).splitlines()[:2]
    assert first.startswith("friction map ") and first.endswith("evil\\nname\\u202e.parquet")
    assert second.startswith("  runs: 1 ")


# --------------------------------------------------------------------------- end to end


def test_real_exports_reduced_by_the_pipeline_land_once_in_the_map(tmp_path):
    from generators.synthetic import write_rheocompass_export
    from tribopipe.pipeline import reduce_file

    path = tmp_path / "map.parquet"
    settings = load_settings()
    labels = RunLabels(pin="Ecoflex 00-50", disc="steel", normal_force_N=3.0,
                       temperature_C=20.0, repeat=1)
    raw = write_rheocompass_export(tmp_path / "run1.txt", SyntheticRun(seed=3, duration_s=120),
                                   project="p", test="friction", sample="EF50")
    first = reduce_file(raw, settings, labels)
    assert fm.append_records(path, [first.record]).added == 1
    row = fm.read_map(path).iloc[0]
    assert row["file_hash"] == first.file_hash
    assert row["interval"] == first.measurement.meta.interval
    assert row["mu_k"] == pytest.approx(0.55, abs=0.02)

    copy = tmp_path / "copy of run1.txt"
    copy.write_bytes(raw.read_bytes())
    again = reduce_file(copy, settings, labels)
    assert fm.append_records(path, [again.record]).unchanged == 1

    stricter = settings_from_dict({"reduction": {"median_window": 9}})
    redo = reduce_file(raw, stricter, labels)
    assert fm.append_records(path, [redo.record]).kept_conflicting == 1
    assert fm.append_records(path, [redo.record], replace=True).replaced == 1
    assert fm.read_map(path)["config_hash"].tolist() == [stricter.config_hash]


def test_a_map_with_a_text_column_stored_as_numbers_is_refused(tmp_path):
    path = tmp_path / "map.parquet"  # a single-file map: its reader checks every row
    fm.store.write_map_copy(path, fm.records_frame([run_record(1)]))
    table = pq.read_table(path)
    i = table.column_names.index("pin")
    pq.write_table(table.set_column(i, "pin", pa.array([7])), path)
    with pytest.raises(MapError, match="stored as int64, not text") as err:
        fm.read_map(path)
    assert err.value.column == "pin" and str(path) in str(err.value)


def test_update_map_drops_stale_runs_and_adds_new_ones_in_one_write(tmp_path):
    path = tmp_path / "map.parquet"
    old = [run_record(1), run_record(2), run_record(3)]
    fm.append_records(path, old)
    stale = [old[0].measurement_id, old[1].measurement_id, "not-in-the-map"]
    report = fm.update_map(path, [run_record(4), old[1]], drop_ids=stale)
    assert report.dropped_ids == (old[0].measurement_id,)  # old[1] is re-supplied: kept
    assert report.added == 1 and report.unchanged == 1
    assert "1 dropped" in report.summary()
    ids = fm.read_map(path)["measurement_id"].tolist()
    assert ids == [old[1].measurement_id, old[2].measurement_id,
                   run_record(4).measurement_id]
    before = map_bytes(path)
    assert not fm.update_map(path, [], drop_ids=["not-in-the-map"]).changed
    assert map_bytes(path) == before


def test_a_map_path_inside_a_file_is_a_clean_error(tmp_path):
    blocker = tmp_path / "processed"
    blocker.write_text("not a directory")
    with pytest.raises(MapError, match="cannot lock the friction map") as err:
        fm.append_records(blocker / "friction_map.parquet", [run_record(1)])
    assert "friction_map.parquet" in str(err.value)
    assert blocker.read_text() == "not a directory"


def test_fold_reports_each_id_once_in_first_seen_order_when_records_repeat():
    a, b = run_record(1), run_record(2)
    a2, b2 = run_record(1, mu_k=0.5), run_record(2, mu_k=0.5)
    runs = fm.records_frame([a])
    merged, report = fm.store.fold_records(runs, [b, a, a2, b2, a, a2], replace=True)
    assert report.added_ids == (b.measurement_id,)
    assert report.unchanged_ids == (a.measurement_id,)
    assert report.replaced_ids == (a.measurement_id,)
    assert list(merged["measurement_id"]) == [a.measurement_id, b.measurement_id]
    assert list(merged["mu_k"]) == [0.5, 0.5]
    _, kept = fm.store.fold_records(runs, [a2, a, a2], replace=False)
    assert kept.conflicting_ids == (a.measurement_id,) and kept.unchanged_ids == (
        a.measurement_id,)


# --------------------------------------------------------------------------- schema versions


def test_a_version_1_map_written_by_the_old_code_still_reads_and_upgrades_on_write(tmp_path):
    # tests/data/friction_map_v1.parquet was written by tribopipe at commit 064bf4b
    # (scripts/make_v1_map.py): schema version 1, no `lab` column
    old = Path(__file__).parent / "data" / "friction_map_v1.parquet"
    assert fm.store.map_metadata(old)["schema_version"] == 1
    assert "lab" not in pq.read_schema(old).names
    runs = fm.read_map(old)
    assert list(runs.columns) == list(fm.RUN_COLUMNS) and len(runs) == 171
    assert runs["lab"].isna().all()
    assert int(runs["excluded"].sum()) == 1
    assert (runs["source"] == fm.schema.SOURCE_PUBLISHED).sum() == 169
    copy = tmp_path / "friction_map.parquet"
    copy.write_bytes(old.read_bytes())
    # the same published rows imported again by the new code (which names their lab) are
    # the same runs: `lab` is provenance, not content
    assert fm.import_table(copy).unchanged == 169
    report = fm.append_records(copy, [run_record(1)])
    assert report.added == 1
    assert fm.store.map_metadata(copy)["schema_version"] == fm.schema.SCHEMA_VERSION
    upgraded = fm.read_map(copy)
    pd.testing.assert_frame_equal(upgraded.iloc[:171], runs)


def test_a_record_built_without_the_columns_added_later_reads_them_as_missing():
    rec = run_record(1).as_dict()  # a changed copy: checked again
    rec.pop("lab")
    frame = fm.records_frame([rec])
    assert frame["lab"].isna().all()
    with pytest.raises(MapError, match="lacks column"):
        fm.records_frame([{k: v for k, v in rec.items() if k != "mu_k"}])

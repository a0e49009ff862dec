"""Every real export reads to the facts read off the file by hand.

Counts of tests/results/intervals/points and individual values (with their SI conversion)
were looked up in the files themselves (decoded with a text editor), not produced by the
reader. Files whose licence allows it live in tests/data; the others are read from
../shared/real-exports and skip where it is absent.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from conftest import shared_file
from tribopipe.errors import MissingQuantityError, ReadError
from tribopipe.measurement import ANGLE, NORMAL_FORCE, SPEED, TEMPERATURE, TIME, TORQUE
from tribopipe.readers import describe_export, read_export, require_columns

COPIED = [
    "rheocompass_en_utf16_two_tests.csv",
    "rheocompass_en_two_tests.xlsx",
    "rheocompass_en_utf16_amplitude_sweep.csv",
    "rheocompass_en_utf16_small.txt",
    "rheocompass_resaved_cp1252.txt",
    "rheoplus_mcr302_stress_relaxation.txt",
    "rheoplus_after_excel_roundtrip.csv",
]


@pytest.mark.parametrize("name", COPIED)
def test_copies_in_tests_data_are_byte_identical(data_dir: Path, name: str) -> None:
    original = shared_file("real-exports", name)
    assert (data_dir / name).read_bytes() == original.read_bytes()


def test_tests_data_readme_names_the_mit_copyright_holders(data_dir: Path) -> None:
    readme = (data_dir / "README.md").read_text(encoding="utf-8")
    assert "Copyright (c) 2022 Giuseppe Ciccone" in readme
    assert "Copyright (c) 2021 jennybennett" in readme
    for name in COPIED:
        assert name in readme
    for name in ("rheocompass_fr_utf16_laos.csv", "rheocompass_en_utf8_comma.csv"):
        assert not (data_dir / name).exists(), f"{name} has no licence and must not be copied"


def test_smallest_rheocompass_file(data_dir: Path) -> None:
    ms = read_export(data_dir / "rheocompass_en_utf16_small.txt")
    assert len(ms) == 1
    m = ms[0]
    meta = m.meta
    assert (meta.file_format, meta.encoding, meta.delimiter, meta.decimal) == (
        "rheocompass", "utf-16", "\t", ".")
    assert meta.project == "Shear Test | DESKTOP-4HEH0CM, 2/24/2020 | 2"
    assert (meta.test, meta.interval, meta.n_points_declared) == ("Test", 1, 20)
    assert meta.header_line == 8
    assert len(m.data) == 20
    first = m.data.iloc[0]
    assert first["point_no"] == 1 and first[TIME] == 6.0
    assert first[TORQUE] == pytest.approx(3.5868e-3)  # 3.5868 mN·m
    assert first["viscosity_Pa_s"] == pytest.approx(72.195)  # 72195 mPa·s
    assert first["shear_rate_1_s"] == 50.0
    assert m.data[TIME].iloc[-1] == 120.0
    assert (m.data["status"] == "").all()  # the Status column is empty in this file
    assert dict(meta.column_map)["Torque"] == TORQUE
    assert meta.original_units[meta.original_columns.index("Torque")] == "[mN·m]"


def test_missing_normal_force_is_the_callers_error_with_file_interval_and_columns(
    data_dir: Path,
) -> None:
    m = read_export(data_dir / "rheocompass_en_utf16_small.txt")[0]
    require_columns(m, TIME, TORQUE)  # present: no error
    with pytest.raises(MissingQuantityError) as exc:
        require_columns(m, TORQUE, NORMAL_FORCE)
    message = str(exc.value)
    assert "rheocompass_en_utf16_small.txt" in message
    assert "interval 1" in message and NORMAL_FORCE in message
    assert "Torque → torque_Nm" in message and "Viscosity → viscosity_Pa_s" in message
    assert "\n" not in message


def test_two_tests_in_one_utf16_file(data_dir: Path) -> None:
    ms = read_export(data_dir / "rheocompass_en_utf16_two_tests.csv")
    assert [m.meta.test for m in ms] == ["Stress Relaxation 1", "Stress Relaxation"]
    assert [m.meta.result for m in ms] == ["Step strain 1", "Step strain 1"]
    assert [m.meta.interval for m in ms] == [1, 1]
    assert [len(m.data) for m in ms] == [451, 155]
    first, second = ms
    assert first.data[TIME].iloc[0] == pytest.approx(0.1)
    assert first.data[TORQUE].iloc[0] == pytest.approx(0.011214e-3)
    assert first.data["shear_strain_pct"].iloc[0] == pytest.approx(2.96)
    assert first.data[TIME].iloc[-1] == pytest.approx(1498.930)
    assert second.data[TORQUE].iloc[0] == pytest.approx(-0.040448e-3)
    assert second.meta.header_line == 468


def test_excel_export_reads_to_the_same_tables_as_the_utf16_file(data_dir: Path) -> None:
    text = read_export(data_dir / "rheocompass_en_utf16_two_tests.csv")
    xlsx = read_export(data_dir / "rheocompass_en_two_tests.xlsx")
    assert xlsx[0].meta.file_format == "rheocompass-xlsx"
    assert len(text) == len(xlsx) == 2
    for a, b in zip(text, xlsx, strict=True):
        pd.testing.assert_frame_equal(a.data, b.data)
        for field in ("project", "test", "result", "interval", "original_columns",
                      "original_units", "column_map", "n_points_declared", "header_line"):
            assert getattr(a.meta, field) == getattr(b.meta, field), field


def test_amplitude_sweep_placeholders_and_joined_status_flags(data_dir: Path) -> None:
    m = read_export(data_dir / "rheocompass_en_utf16_amplitude_sweep.csv")[0]
    assert len(m.data) == 25
    # Torque is in µN·m in this file: 0.0026733 µN·m
    assert m.data[TORQUE].iloc[0] == pytest.approx(2.6733e-9)
    assert m.data[TORQUE].iloc[-1] == pytest.approx(5.2707e-6)
    # "ME-,taD,TruStrain™" is one TAB cell holding three flags
    assert m.data["status"].iloc[0] == "ME-,taD,TruStrain™"
    assert m.data["status"].iloc[1] == "TruStrain™"
    # Loss Factor 20000.000 where tan δ was not determined (points 1 and 7..16)
    lf = m.data["loss_factor"].to_numpy()
    assert np.isnan(lf[[0, *range(6, 16)]]).all()
    assert lf[1] == pytest.approx(1.432) and lf[24] == pytest.approx(10.434)
    assert dict(m.meta.extra)["loss_factor_placeholders"] == "11"
    assert m.data["shear_strain"].iloc[0] == pytest.approx(0.000101)


def test_resaved_cp1252_file_with_quoted_padded_cells(data_dir: Path) -> None:
    ms = read_export(data_dir / "rheocompass_resaved_cp1252.txt")
    meta = ms[0].meta
    assert (meta.encoding, meta.delimiter, meta.decimal) == ("cp1252", "\t", ".")
    assert meta.project == "Viscosity Curve | DESKTOP-4HEH0CM, 8/1/2019 | 1"  # unquoted
    assert len(ms) == 12 and len({m.meta.test for m in ms}) == 12
    assert ms[0].meta.test == "Steady State Viscosity Curve-LO80C"
    assert ms[1].meta.test == "Steady State Viscosity Curve-75C"
    assert all(len(m.data) == 25 for m in ms)
    first = ms[0].data.iloc[0]
    # the meaning row says "Constant component" over Time: still the time column
    assert first[TIME] == 10.0
    assert first[TORQUE] == pytest.approx(-0.0073426e-6)  # µN·m in cp1252 (0xB5, 0xB7)
    assert first["viscosity_Pa_s"] == pytest.approx(-0.0224)


def test_utf8_comma_file_with_seven_results(shared_dir: Path) -> None:
    path = shared_file("real-exports", "rheocompass_en_utf8_comma.csv")
    ms = read_export(path)
    meta = ms[0].meta
    assert (meta.encoding, meta.delimiter, meta.decimal) == ("utf-8-sig", ",", ".")
    summary = describe_export(path)
    assert summary.tests == ("Test_r1", "Test_r2")
    assert len(summary.results) == 7
    assert len(ms) == 20
    assert [len(m.data) for m in ms[:3]] == [500, 60, 25]
    assert ms[0].data[TORQUE].iloc[0] == pytest.approx(-37.51e-6)  # µN·m
    sr2 = ms[2]
    assert (sr2.meta.result, sr2.meta.interval) == ("Stress Relaxation 2", 1)
    # a quoted cell holding comma-joined flags stays one cell
    assert sr2.data["status"].iloc[0] == "ME-,WMa,taD,TruStrain™"
    assert sr2.data[TORQUE].iloc[0] == pytest.approx(10.369e-6)
    assert np.isnan(sr2.data["loss_factor"].iloc[0])  # 20000 placeholder


def test_french_laos_file(shared_dir: Path) -> None:
    path = shared_file("real-exports", "rheocompass_fr_utf16_laos.csv")
    ms = read_export(path)
    meta = ms[0].meta
    assert (meta.encoding, meta.delimiter, meta.decimal) == ("utf-16", "\t", ",")
    assert meta.project == "Brice LAOS Carbopol 20230907"
    assert len(ms) == 10 and {m.meta.test for m in ms} == {"Carbopol 20230906"}
    assert [m.meta.result for m in ms] == ["Flow Curve 1"] * 4 + ["LAOS 1"] * 3 + [
        "Oscillations 1"] * 3
    assert [m.meta.interval for m in ms] == [1, 2, 3, 4, 1, 2, 3, 1, 2, 3]
    first = ms[0].data.iloc[0]
    assert first[TORQUE] == pytest.approx(2.3981e-3)  # "2,3981" mN·m
    assert first[NORMAL_FORCE] == pytest.approx(0.05)  # "0,05" N
    assert first[TEMPERATURE] == pytest.approx(21.0)  # "21,00" °C
    assert first["shear_stress_Pa"] == pytest.approx(73.196)
    assert first["shear_strain_pct"] == pytest.approx(2.21e4)  # "2,21E+04"
    # Flow Curve interval 2: all 20 points "(invalide)"
    assert len(ms[1].data) == 0 and ms[1].meta.n_invalid_points == 20
    # LAOS interval 2: Temps runs on (201...), Intervalle Temps restarts (1...)
    laos2 = ms[5].data
    assert laos2[TIME].iloc[0] == 201.0 and laos2["interval_time_s"].iloc[0] == 1.0
    # LAOS interval 3: 8 points, each followed by raw-waveform sub-rows (last two columns)
    laos3 = ms[6]
    assert len(laos3.data) == 8 and laos3.meta.n_points_declared == 8
    assert laos3.meta.n_waveform_rows == 4096
    assert laos3.data[TORQUE].iloc[0] == pytest.approx(0.053306e-3)
    assert sum(m.meta.n_invalid_points for m in ms) == 57
    # every interval has both torque and normal force: the friction-relevant pair
    assert all(m.has(TORQUE, NORMAL_FORCE) for m in ms if len(m.data))


def test_rheoplus_data_series_file(data_dir: Path) -> None:
    ms = read_export(data_dir / "rheoplus_mcr302_stress_relaxation.txt")
    assert len(ms) == 6
    assert [len(m.data) for m in ms] == [100, 100, 100, 99, 100, 100]
    assert [m.meta.n_points_declared for m in ms] == [100, 100, 100, 99, 100, 100]
    meta = ms[0].meta
    assert (meta.file_format, meta.encoding, meta.delimiter, meta.decimal) == (
        "rheoplus", "utf-8", "\t", ".")
    assert meta.sample == "5perc 8arm 10kDa PEGMAL + 2kDa PEGSH sample 1 day 0 sr 1"
    assert dict(meta.extra)["device"].startswith("MCR302 SN81338429")
    first = ms[0].data.iloc[0]
    assert first[TORQUE] == pytest.approx(-1.51e-3)  # -1.51E+3 µNm
    assert first[ANGLE] == pytest.approx(1.14e-3)  # 1.14E0 mrad
    assert first[TIME] == pytest.approx(0.01)
    # two "Relaxation Modulus" columns, both kept
    assert first["relaxation_modulus_Pa"] == first["relaxation_modulus_2_Pa"] == -2.61e6
    # ****** is no value
    assert ms[0].data["storage_modulus_Pa"].isna().all()
    assert first["complex_viscosity_Pa_s"] != first["complex_viscosity_Pa_s"]  # NaN


def test_rheoplus_after_excel_round_trip_is_read_with_the_damage_noted(
    data_dir: Path,
) -> None:
    ms = read_export(data_dir / "rheoplus_after_excel_roundtrip.csv")
    meta = ms[0].meta
    assert (meta.encoding, meta.delimiter, meta.decimal) == ("cp1252", ",", ".")
    assert [m.meta.interval for m in ms] == list(range(1, 16))
    extra = dict(meta.extra)
    assert "#NAME?" in extra["excel_damage"]
    assert extra["interval_header"].startswith("missing")
    assert len(ms[0].data) == 80 and meta.n_points_declared is None
    assert len(ms[2].data) == 79 and ms[2].meta.n_invalid_points == 1  # "1,invalid point"
    last = ms[-1].data.iloc[-1]
    assert last["point_no"] == 28
    assert last[SPEED] == pytest.approx(59.7 * 2 * math.pi / 60)  # 59.7 1/min
    assert last[TORQUE] == pytest.approx(36.6e-6)  # 36.6 µNm (0xB5 in cp1252)
    assert last[TEMPERATURE] == 37.0
    assert last["viscosity_Pa_s"] == pytest.approx(7.27)


def test_a_destroyed_data_cell_after_excel_is_refused(tmp_path: Path, data_dir: Path) -> None:
    text = (data_dir / "rheoplus_after_excel_roundtrip.csv").read_bytes().decode("cp1252")
    damaged = text.replace("\n3,15,6460,", "\n3,#NAME?,6460,", 1)
    assert damaged != text
    path = tmp_path / "damaged.csv"
    path.write_bytes(damaged.encode("cp1252"))
    with pytest.raises(ReadError) as exc:
        read_export(path)
    message = str(exc.value)
    assert "damaged.csv:5" in message and "Excel" in message and "'Time'" in message


def test_inspect_summary_of_the_french_file(shared_dir: Path) -> None:
    s = describe_export(shared_file("real-exports", "rheocompass_fr_utf16_laos.csv"))
    assert (len(s.tests), len(s.results), len(s.intervals)) == (1, 3, 10)
    assert s.n_points == 60 + 0 + 51 + 51 + 200 + 30 + 8 + 30 + 0 + 16
    cols = {c.original: (c.unit, c.column) for c in s.intervals[0].columns}
    assert cols["Couple"] == ("[mN·m]", TORQUE)
    assert cols["Temps"] == ("[s]", TIME)
    assert cols["Intervalle Temps"] == ("[s]", "interval_time_s")
    assert s.intervals[0].friction_ready
    text = s.to_text()
    assert "Couple [mN·m]" in text and "torque_Nm" in text and "decimal: ," in text

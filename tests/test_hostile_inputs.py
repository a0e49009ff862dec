"""Hostile values at every edge: configs, CLI options, manifests, campaign configs and the
traces themselves. Each case was reproduced on the code before it was fixed (a traceback,
a silent number, a batch lost with one row); each must now be one line naming the file,
the key or row and what was expected, failing only that row or file."""

from __future__ import annotations

import json
import math
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from generators.synthetic import make_intervals, write_intervals_export
from helpers import reduce_cli
from hostile import (
    GOOD_RUN,
    assert_clean_failure,
    assert_one_line_each,
    good_export,
    invoke,
)
from tribopipe.campaign import load_campaign, read_manifest, run_campaign
from tribopipe.config import load_settings, settings_from_dict
from tribopipe.errors import ConfigError, ValidationError
from tribopipe.frictionmap import read_map
from tribopipe.labels import RunLabels

PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"


# --------------------------------------------------------------------- instrument configs


@pytest.mark.parametrize(("table", "key", "value"), [
    ("instrument", "pin_radius_mm", "1e300"),      # was OverflowError
    ("instrument", "pin_radius_mm", "1e-300"),     # was an infinite pressure in the map
    ("instrument", "friction_radius_mm", "1e300"),  # was "Maximum allowed size exceeded"
    ("instrument", "pin_radius_mm", "true"),
    ("instrument", "n_pins", "true"),
    ("instrument", "n_pins", "3.0"),
    ("instrument", "name", '"two\\nlines"'),
    ("reduction", "median_window", "true"),
    ("reduction", "median_window", "4"),            # an even median window
    ("reduction", "min_plateau_samples", "30.5"),   # a fractional count
    ("reduction", "block_mm", "1e-9"),              # allocated 7 GiB, then 24 GB
    ("reduction", "peak_window_mm", "1e300"),
    ("reduction", "settle_tol", "true"),
])
def test_instrument_config_refuses_in_one_line(tmp_path: Path, table: str, key: str,
                                               value: str) -> None:
    cfg = tmp_path / "cell.toml"
    cfg.write_text(f"[{table}]\n{key} = {value}\n", encoding="utf-8")
    with pytest.raises(ConfigError) as info:
        load_settings(cfg)
    message = str(info.value)
    assert str(cfg) in message and key in message and "\n" not in message
    result = invoke("reduce", str(good_export(tmp_path / "run.csv")), "--instrument", str(cfg),
                    "--no-map", "--output", str(tmp_path / "out"))
    assert key in assert_clean_failure(result)


def test_the_founding_config_and_the_shipped_instrument_files_stay_valid() -> None:
    repo = Path(__file__).resolve().parents[1]
    assert load_settings().instrument.n_pins == 3
    for path in sorted((repo / "configs" / "instruments").glob("*.toml")):
        load_settings(path)


def test_every_bound_is_generous_for_real_cells() -> None:
    settings = settings_from_dict({"instrument": {"pin_radius_mm": 0.5, "n_pins": 1,
                                                  "friction_radius_mm": 40.0},
                                   "reduction": {"median_window": 7, "block_mm": 0.01}})
    assert settings.reduction.median_window == 7


# --------------------------------------------------------------------- labels from the CLI


@pytest.mark.parametrize(("option", "value", "expected"), [
    ("--force", "1e308", "normal force"),    # was "pressure_kPa": Infinity, no flag
    ("--force", "-3", "normal force"),
    ("--force", "0", "normal force"),
    ("--temperature", "-300", "temperature"),
    ("--temperature", "inf", "temperature"),
    ("--temperature", "nan", "temperature"),
    ("--repeat", "-1", "repeat"),
    ("--pin", "Ecoflex\n*HEADING", "pin"),   # a keyword line in ABAQUS and Ansys
    ("--disc", "steel\r\nimport os", "disc"),
    ("--pin", "x" * 201, "pin"),
    ("--pin", "   ", "pin"),
    ("--disc", "steel\u202e", "disc"),       # a bidi override reverses what follows
])
def test_reduce_refuses_a_bad_label_in_one_line(tmp_path: Path, option: str, value: str,
                                                expected: str) -> None:
    export = good_export(tmp_path / "run.csv")
    args = ["reduce", str(export), "--pin", "DS30", "--disc", "steel", "--force", "3",
            "--temperature", "20", option, value, "--map", str(tmp_path / "map.parquet"),
            "--output", str(tmp_path / "out")]
    stderr = assert_clean_failure(invoke(*args))
    assert expected in stderr and len(stderr.strip().splitlines()) == 1, stderr
    assert not (tmp_path / "map.parquet").exists()


def test_labels_refuse_bool_and_text_where_numbers_belong() -> None:
    with pytest.raises(ValidationError):
        RunLabels(pin="p", disc="d", normal_force_N=True)
    with pytest.raises(ValidationError):
        RunLabels(pin="p", disc="d", repeat=2.5)
    with pytest.raises(ValidationError):
        RunLabels(pin="p", disc="d", temperature_C="20")
    assert RunLabels(pin="Dragonskin 30", disc="steel", normal_force_N=3, repeat=2).repeat == 2


# --------------------------------------------------------------------- manifests


def _campaign(tmp_path: Path, manifest: str, extra: str = "") -> Path:
    raw = tmp_path / "raw"
    raw.mkdir()
    for i in range(3):
        good_export(raw / f"run{i}.csv", replace(GOOD_RUN, seed=10 + i))
    (raw / "manifest.csv").write_text(manifest, encoding="utf-8")
    cfg = tmp_path / "c.toml"
    cfg.write_text('[campaign]\nname = "m"\nraw_dir = "raw"\noutput_dir = "out"\n'
                   f'manifest = "raw/manifest.csv"\nplots = false\n{extra}', encoding="utf-8")
    return cfg


HEADER = "file,pin,disc,normal_force_N,temperature_C,repeat\n"


@pytest.mark.parametrize(("cell_row", "expected"), [
    ("run1.csv,DS30,steel,3,20,1e30\n", "repeat"),       # aborted the whole batch
    ("run1.csv,DS30,steel,-3,20,1\n", "normal_force_N"),
    ("run1.csv,DS30,steel,3,-300,1\n", "temperature_C"),
    ("run1.csv,DS30,steel,3,inf,1\n", "temperature_C"),
    ("run1.csv,DS30,steel,1e308,20,1\n", "normal_force_N"),
    ('run1.csv,"DS30\n*HEADING",steel,3,20,1\n', "pin"),
    ("run1.csv,DS30,=HYPERLINK(x)" + "y" * 200_000 + ",3,20,1\n", "disc"),  # was _csv.Error
    ("run1.csv,DS30,steel,3,20,2.5\n", "repeat"),
])
def test_a_bad_manifest_row_fails_that_file_only(tmp_path: Path, cell_row: str,
                                                 expected: str) -> None:
    manifest = (HEADER + "run0.csv,DS30,steel,3,20,1\n" + cell_row
                + "run2.csv,DS30,steel,3,20,2\n")
    cfg = _campaign(tmp_path, manifest)
    row = read_manifest(tmp_path / "raw" / "manifest.csv").get("run1.csv")
    assert row is not None and row.problem is not None and expected in row.problem
    assert "\n" not in row.problem and len(row.problem) < 500
    result = invoke("batch", str(cfg), "--jobs", "1")
    stderr = assert_clean_failure(result)
    assert_one_line_each(stderr, ["run1.csv"])
    runs = read_map(tmp_path / "out" / "friction_map.parquet")
    assert sorted(runs["repeat"].tolist()) == [1, 2]   # the neighbours landed


def test_names_table_refuses_a_name_with_a_newline(tmp_path: Path) -> None:
    cfg = _campaign(tmp_path, HEADER + "run0.csv,DS30,steel,3,20,1\n",
                    extra='[names]\nDS30 = "Dragonskin\\n*HEADING"\n')
    with pytest.raises(ConfigError) as info:
        load_campaign(cfg)
    assert "[names]" in str(info.value) and "DS30" in str(info.value)


# --------------------------------------------------------------------- campaign configs


@pytest.mark.parametrize(("line", "key"), [
    ('glob = "/etc/*"', "glob"),           # was NotImplementedError
    ('glob = ""', "glob"),                 # was ValueError
    ('glob = "../*"', "glob"),
    ('name = "' + "n" * 100_000 + '"', "name"),   # was "File name too long"
    ('name = "a\\u0000b"', "name"),
])
def test_campaign_config_refuses_in_one_line(tmp_path: Path, line: str, key: str) -> None:
    cfg = _campaign(tmp_path, HEADER + "run0.csv,DS30,steel,3,20,1\n", extra="")
    text = cfg.read_text(encoding="utf-8").replace('name = "m"\n', "")
    cfg.write_text(text.replace("[campaign]\n", f"[campaign]\n{line}\n"), encoding="utf-8")
    with pytest.raises(ConfigError) as info:
        load_campaign(cfg)
    assert key in str(info.value) and len(str(info.value)) < 600
    stderr = assert_clean_failure(invoke("batch", str(cfg)))
    assert key in stderr and len(stderr.strip().splitlines()) == 1


def test_an_output_dir_that_is_a_file_is_one_line(tmp_path: Path) -> None:
    cfg = _campaign(tmp_path, HEADER + "run0.csv,DS30,steel,3,20,1\n")
    (tmp_path / "out").write_text("not a folder", encoding="utf-8")  # was FileExistsError
    stderr = assert_clean_failure(invoke("batch", str(cfg)))
    assert "out" in stderr and "folder" in stderr and len(stderr.strip().splitlines()) == 1
    assert (tmp_path / "out").read_text(encoding="utf-8") == "not a folder"


def test_a_folder_campaign_refuses_an_absolute_glob(tmp_path: Path) -> None:
    raw = tmp_path / "raw"
    raw.mkdir()
    good_export(raw / "run0.csv")
    stderr = assert_clean_failure(invoke("batch", str(raw), "--glob", "/etc/*", "--pattern",
                                         PATTERN, "--output", str(tmp_path / "out")))
    assert "glob" in stderr


# --------------------------------------------------------------------- the traces


def _plain_export(path: Path, change=None) -> Path:
    """The good run's friction interval as a plain CSV, after ``change(frame)``."""
    frame = make_intervals(GOOD_RUN)[-1]
    if change is not None:
        change(frame)
    frame.to_csv(path, index=False)
    return path


def _reduce_json(tmp_path: Path, export: Path):
    return reduce_cli(export, "--json", "--no-map", "--output", tmp_path / "o")


def test_zero_torque_is_flagged_no_friction_signal(tmp_path: Path) -> None:
    def zero(frame: pd.DataFrame) -> None:
        frame["torque_Nm"] = 0.0
    result = _reduce_json(tmp_path, _plain_export(tmp_path / "zero.csv", zero))
    assert result.exit_code == 0, result.output
    row = json.loads(result.stdout)[0]
    assert "no_friction_signal" in row["flags"]


def test_constant_torque_is_flagged_no_friction_signal(tmp_path: Path) -> None:
    def stuck(frame: pd.DataFrame) -> None:
        frame["torque_Nm"] = 0.004
        del frame["angle_rad"], frame["speed_rad_s"]   # no rest to take an offset from
    result = _reduce_json(tmp_path, _plain_export(tmp_path / "stuck.csv", stuck))
    assert result.exit_code == 0, result.output
    assert "no_friction_signal" in json.loads(result.stdout)[0]["flags"]


def test_a_good_run_is_not_flagged_no_friction_signal(tmp_path: Path) -> None:
    result = _reduce_json(tmp_path, _plain_export(tmp_path / "good.csv"))
    assert result.exit_code == 0, result.output
    assert "no_friction_signal" not in json.loads(result.stdout)[0]["flags"]


def test_constant_time_is_refused_with_its_reason(tmp_path: Path) -> None:
    def frozen(frame: pd.DataFrame) -> None:
        frame["time_s"] = 5.0
    stderr = assert_clean_failure(_reduce_json(tmp_path, _plain_export(tmp_path / "t.csv",
                                                                        frozen)))
    assert "t.csv" in stderr and "time" in stderr and "constant" in stderr


def test_time_going_backwards_is_refused_with_its_reason(tmp_path: Path) -> None:
    def backwards(frame: pd.DataFrame) -> None:
        t = frame["time_s"].to_numpy().copy()
        t[400:410] = t[400:410][::-1]
        frame["time_s"] = t
    stderr = assert_clean_failure(_reduce_json(tmp_path, _plain_export(tmp_path / "b.csv",
                                                                        backwards)))
    assert "b.csv" in stderr and "backwards" in stderr


def test_nan_cells_are_counted_as_invalid(tmp_path: Path) -> None:
    def holes(frame: pd.DataFrame) -> None:
        torque = frame["torque_Nm"].to_numpy().copy()
        torque[100:112] = np.nan
        frame["torque_Nm"] = torque
    export = _plain_export(tmp_path / "holes.csv", holes)
    assert ",," in export.read_text() or "nan" in export.read_text().lower()
    result = invoke("inspect", str(export))
    assert result.exit_code == 0, result.output
    assert "12 missing or invalid values" in result.stdout, result.stdout
    data = json.loads(invoke("inspect", str(export), "--json").stdout)
    assert data["intervals"][0]["n_invalid_values"] == 12


def test_a_huge_measured_force_fails_the_file_and_json_stays_strict(tmp_path: Path) -> None:
    def huge(frame: pd.DataFrame) -> None:
        frame["normal_force_N"] = 1e308
    bad = _plain_export(tmp_path / "huge.csv", huge)
    good = _plain_export(tmp_path / "good.csv")
    result = invoke("reduce", str(bad), str(good), "--json", "--no-map",
                    "--output", str(tmp_path / "o"))
    stderr = assert_clean_failure(result)
    assert_one_line_each(stderr, ["huge.csv"])
    rows = json.loads(result.stdout, parse_constant=_refuse_constant)
    assert [Path(r["file"]).name for r in rows] == ["good.csv"]
    for path in (tmp_path / "o" / "summaries").glob("*.json"):
        json.loads(path.read_text(), parse_constant=_refuse_constant)


def test_a_huge_torque_in_the_setup_interval_fails_the_file_in_one_line(
        tmp_path: Path) -> None:
    """The set-up interval gives the torque zero: a sample there beyond any measurement
    fails that file, naming the set-up interval and the point (it overflowed the offset's
    statistics), and its neighbour reduces."""
    setup, friction = make_intervals(GOOD_RUN)
    setup = setup.copy()
    setup.loc[3, "torque_Nm"] = -1e200    # its square overflows
    bad = write_intervals_export(tmp_path / "setup_huge.txt", [setup, friction],
                                 project="p", test="t", sample="DS30")
    good = _plain_export(tmp_path / "good.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        result = invoke("reduce", str(bad), str(good), "--json", "--no-map",
                        "--output", str(tmp_path / "o"))
    stderr = assert_clean_failure(result)
    assert_one_line_each(stderr, ["setup_huge.txt"])
    assert "interval 1" in stderr and "point 4" in stderr and "torque_Nm" in stderr, stderr
    assert [Path(r["file"]).name for r in json.loads(result.stdout)] == ["good.csv"]


def _refuse_constant(name: str) -> None:
    raise AssertionError(f"JSON holds {name}: not strict JSON")


def test_a_huge_torque_fails_the_file_in_a_batch(tmp_path: Path) -> None:
    raw = tmp_path / "raw"
    raw.mkdir()

    def huge(frame: pd.DataFrame) -> None:
        frame["torque_Nm"] = frame["torque_Nm"] * 1e300   # μ up to 1e306 was accepted
    _plain_export(raw / "DS30_steel_3N_20C_r1.csv", huge)
    _plain_export(raw / "DS30_steel_3N_20C_r2.csv")
    cfg = tmp_path / "c.toml"
    cfg.write_text(f'[campaign]\nraw_dir = "raw"\noutput_dir = "out"\n'
                   f'filename_pattern = "{PATTERN}"\nplots = false\n', encoding="utf-8")
    report = run_campaign(load_campaign(cfg), jobs=1)
    assert [f for f, _ in report.failures] == ["DS30_steel_3N_20C_r1.csv"]
    runs = read_map(tmp_path / "out" / "friction_map.parquet")
    assert runs["repeat"].tolist() == [2]
    assert math.isfinite(runs["mu_k"].iloc[0])

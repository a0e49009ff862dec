"""Force-based instruments: units, exports as their software writes them, the sled's
normal force, the zero taken only where unloaded, end stops, run-out and reciprocating
cycles. Analytic traces with a known answer (the rig families are in the benchmark)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tribopipe.config import TEST_METHODS, load_settings, settings_from_dict
from tribopipe.errors import ConfigError, MissingQuantityError
from tribopipe.measurement import (
    FRICTION_FORCE,
    NORMAL_FORCE,
    POSITION,
    TIME,
    Measurement,
    MeasurementMeta,
)
from tribopipe.readers import read_export
from tribopipe.reduction.intervals import end_stop, load_fraction
from tribopipe.reduction.reduce import reduce_measurement, revolution_locked
from tribopipe.units import parse_unit

CONFIGS = Path(__file__).resolve().parents[1] / "configs" / "instruments"
G = 9.80665


@pytest.mark.parametrize(("unit", "quantity", "value", "si", "suffix"), [
    ("[µs]", None, 250.0, 250e-6, "s"),
    ("[us]", None, 1.0, 1e-6, "s"),
    ("[ms]", None, 1500.0, 1.5, "s"),
    ("[gf]", None, 100.0, 0.980665, "N"),
    ("[kgf]", None, 2.0, 19.6133, "N"),
    ("[lbf]", None, 1.0, 4.4482216152605, "N"),
    ("[N]", None, 3.0, 3.0, "N"),
    ("[in]", None, 2.0, 0.0508, "m"),
    ("[µm]", None, 5.0, 5e-6, "m"),
    ("[um]", None, 5.0, 5e-6, "m"),
    ("[mm]", None, 5.0, 5e-3, "m"),
    ("[cm]", None, 5.0, 5e-2, "m"),
    ("[m]", None, 5.0, 5.0, "m"),
    ("[rev]", None, 1.5, 3 * math.pi, "rad"),
    ("[revs]", None, 1.0, 2 * math.pi, "rad"),
    ("[mm/min]", None, 150.0, 2.5e-3, "m_s"),
    ("[rpm]", "speed", 60.0, 2 * math.pi, "rad_s"),
])
def test_unit_conversions(unit: str, quantity: str | None, value: float, si: float,
                          suffix: str) -> None:
    spec = parse_unit(unit, quantity)
    assert spec is not None and spec.suffix == suffix
    assert float(spec.to_si([value])[0]) == pytest.approx(si, rel=1e-12)


# ------------------------------------------------------------------ exports as written


def test_testxpert_layout(tmp_path: Path) -> None:
    """Header block, decimal comma, unit row, trailing separator, a repeated header line
    and a footer."""
    path = tmp_path / "zwick.csv"
    body = [f"{i / 10:.1f};{i / 4:.3f};{i / 100:.2f};".replace(".", ",") for i in range(50)]
    lines = ["Prüfprogramm;Reibung;", "Geschwindigkeit;150;mm/min;", "",
             "Prüfzeit;Standardweg;Standardkraft;", "[s];[mm];[N];", *body[:25],
             "Prüfzeit;Standardweg;Standardkraft;", *body[25:], "", "Ende;",
             "Fmax;0,49;N;"]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    (m,) = read_export(path)
    assert list(m.data.columns) == [TIME, POSITION, FRICTION_FORCE]
    assert len(m.data) == 50
    assert m.data[TIME].iloc[-1] == pytest.approx(4.9)
    assert m.data[POSITION].iloc[-1] == pytest.approx(49 / 4 * 1e-3)
    assert m.data[FRICTION_FORCE].iloc[-1] == pytest.approx(0.49)
    assert dict(m.meta.extra)["repeated_header_lines"] == "1"
    assert dict(m.meta.extra)["header_block_lines"] == "2"


def test_bluehill_layout_and_large_file(tmp_path: Path) -> None:
    """Comma CSV, quoted header block, units in parentheses in the header; long enough
    for the column-wise reading."""
    path = tmp_path / "instron.csv"
    rows = [f"{i * 0.01:.2f},{i * 0.025:.4f},{0.5 + 1e-4 * i:.5f}" for i in range(5000)]
    path.write_text("\n".join(['"Sample","PE"', '"Test speed","150 mm/min"', "",
                               '"Time (s)","Extension (mm)","Load (lbf)"', *rows]) + "\n")
    (m,) = read_export(path)
    assert len(m.data) == 5000
    assert m.data[FRICTION_FORCE].iloc[0] == pytest.approx(0.5 * 4.4482216152605)


def test_tsv_with_units(tmp_path: Path) -> None:
    path = tmp_path / "rig.tsv"
    rows = [f"{i}\t{i * 0.1:.2f}\t{10 + i:.1f}\t5" for i in range(30)]
    path.write_text("\n".join(["Time [µs]\tPosition [in]\tFriction Force [gf]\t"
                               "Normal Force [N]", *rows]) + "\n", encoding="utf-8")
    (m,) = read_export(path)
    assert m.data[TIME].iloc[2] == pytest.approx(2e-6)
    assert m.data[POSITION].iloc[10] == pytest.approx(1.0 * 0.0254)
    assert m.data[FRICTION_FORCE].iloc[0] == pytest.approx(10 * 9.80665e-3)


# ---------------------------------------------------------------------- a sled's pull


def _measurement(columns: dict[str, np.ndarray]) -> Measurement:
    return Measurement(data=pd.DataFrame(columns), meta=MeasurementMeta(
        source_file="sled.csv", file_format="csv"))


def sled_trace(*, mu_s: float = 0.35, mu_k: float = 0.25, rest_load_N: float = 0.0,
               offset_N: float = 0.0, stop_s: float = 0.0, rest_s: float = 2.0,
               noise_N: float = 0.002, seed: int = 0) -> Measurement:
    """A crosshead at 2.5 mm/s after ``rest_s`` at rest; the load rises over 2 mm to
    μ_S·F_N and falls to μ_K·F_N; ``stop_s`` at the end the crosshead stands still and
    the load falls to half; 100 Hz; a 200 g sled (no normal-force column)."""
    rng = np.random.default_rng(seed)
    n_force = 0.2 * G
    t = np.arange(0.0, rest_s + 60.0 + stop_s, 0.01)
    move = np.clip(t - rest_s, 0.0, 60.0)
    x = 2.5 * move
    rise = np.clip(x / 2.0, 0.0, 1.0)
    mu = np.where(x < 2.0, rest_load_N / n_force + rise * (mu_s - rest_load_N / n_force),
                  mu_k + (mu_s - mu_k) * np.exp(-(x - 2.0) / 0.5))
    load = mu * n_force
    stopped = t > rest_s + 60.0
    load = np.where(stopped, 0.5 * mu_k * n_force, load)
    load = load + offset_N + rng.normal(0.0, noise_N, t.size)
    return _measurement({TIME: t, POSITION: x * 1e-3, FRICTION_FORCE: load})


SLED = load_settings(CONFIGS / "sled-d1894.toml")


def test_sled_normal_force_from_its_mass() -> None:
    got = reduce_measurement(sled_trace(), SLED.instrument, SLED.reduction)
    assert got.normal_force_mean_N == pytest.approx(0.2 * G)
    assert got.parameters.instrument.normal_force_source == "sled mass 200 g × g = 1.96133 N"
    assert got.parameters.instrument.test_method == "sled D1894"
    assert got.parameters.instrument.tangential_channel == FRICTION_FORCE
    assert got.mu_k == pytest.approx(0.25, abs=0.003)
    assert got.mu_s == pytest.approx(0.35, abs=0.01)
    assert "zero_under_load" not in got.flags
    # the sled's ± 5 g enters the budget: 1.44 % of μ
    assert got.parameters.uncertainty.mu_k["normal_force"] == pytest.approx(
        0.25 * 0.0144, rel=0.05)


def test_sled_weight_in_newtons_and_no_normal_force_refused() -> None:
    weight = replace(SLED.instrument, sled_mass_g=None, sled_weight_N=0.2 * G)
    got = reduce_measurement(sled_trace(), weight, SLED.reduction)
    assert got.parameters.instrument.normal_force_source.startswith("sled weight 1.96")
    none = replace(SLED.instrument, sled_mass_g=None)
    with pytest.raises(MissingQuantityError, match="normal_force_N"):
        reduce_measurement(sled_trace(), none, SLED.reduction)


def test_zero_under_load_is_flagged_and_not_subtracted() -> None:
    """A record that starts with the string already pulled to 0.45 N: before, that load
    was subtracted as the zero and μ_K came out near 0.02."""
    pre = sled_trace(rest_load_N=0.45)
    got = reduce_measurement(pre, SLED.instrument, SLED.reduction)
    assert "zero_under_load" in got.flags
    assert "torque_offset_unknown" not in got.flags
    assert got.mu_k == pytest.approx(0.25, abs=0.003)
    assert got.parameters.torque_offset_Nm == 0.0
    assert got.parameters.instrument.zero_load_fraction > 1.0
    # the unknown zero's size enters the uncertainty
    assert got.parameters.uncertainty.torque_offset_u_Nm == pytest.approx(
        0.01 / math.sqrt(3))


def test_true_zero_offset_is_subtracted() -> None:
    got = reduce_measurement(sled_trace(offset_N=0.05), SLED.instrument, SLED.reduction)
    assert "zero_under_load" not in got.flags
    assert got.parameters.torque_offset_Nm == pytest.approx(0.05, abs=0.002)
    assert got.mu_k == pytest.approx(0.25, abs=0.003)


def test_zero_given_or_off() -> None:
    trace = sled_trace(offset_N=0.05)
    given = replace(SLED.instrument, zero_offset=0.05)
    got = reduce_measurement(trace, given, SLED.reduction)
    assert got.parameters.torque_offset_source == "given"
    assert got.mu_k == pytest.approx(0.25, abs=0.003)
    off = replace(SLED.instrument, zero_offset="off")
    got = reduce_measurement(trace, off, SLED.reduction)
    assert got.parameters.torque_offset_Nm == 0.0
    assert got.mu_k == pytest.approx(0.25 + 0.05 / (0.2 * G), abs=0.003)
    # the keyword overrides the file
    got = reduce_measurement(trace, off, SLED.reduction, torque_offset_Nm=0.05)
    assert got.mu_k == pytest.approx(0.25, abs=0.003)


def test_rest_after_sliding_is_a_second_zero() -> None:
    rng = np.random.default_rng(3)
    n_force = 0.2 * G
    t = np.arange(0.0, 66.0, 0.01)
    x = 2.5 * np.clip(t - 2.0, 0.0, 60.0)
    load = np.where((x > 0) & (t < 62.0), 0.25 * n_force, 0.0)
    drift = 0.02 * t / t[-1]  # the zero drifts by 20 mN over the record
    trace = _measurement({TIME: t, POSITION: x * 1e-3,
                          FRICTION_FORCE: load + drift + rng.normal(0, 0.001, t.size)})
    inst = replace(SLED.instrument, rest_after_sliding=True)
    got = reduce_measurement(trace, inst, SLED.reduction)
    assert "zero_drift" in got.flags
    assert got.parameters.instrument.zero_second == pytest.approx(0.02 * 64 / 66, abs=0.002)
    assert got.mu_k == pytest.approx(0.25, abs=0.004)
    steady = _measurement({TIME: t, POSITION: x * 1e-3,
                           FRICTION_FORCE: load + rng.normal(0, 0.001, t.size)})
    assert "zero_drift" not in reduce_measurement(steady, inst, SLED.reduction).flags


def test_end_stop_is_trimmed() -> None:
    stop = sled_trace(stop_s=5.0)
    got = reduce_measurement(stop, SLED.instrument, SLED.reduction)
    assert got.parameters.instrument.end_stop_samples >= 450
    assert got.mu_k == pytest.approx(0.25, abs=0.003)
    assert got.mu_k_window_s[1] <= 62.0 + 0.05
    # a record that ends sliding trims nothing
    assert reduce_measurement(sled_trace(), SLED.instrument,
                              SLED.reduction).parameters.instrument.end_stop_samples == 0


def test_end_stop_mask() -> None:
    t = np.arange(0.0, 10.0, 0.01)
    s = np.minimum(t, 8.0)
    stop = end_stop(t, s, np.ones(t.size, dtype=bool), 0.5)
    assert stop[-1] and not stop[: 790].any()
    assert not end_stop(t, t, np.ones(t.size, dtype=bool), 0.5).any()


def test_load_fraction() -> None:
    assert load_fraction(0.0, 1.0) == 0.0
    assert load_fraction(0.1, 1.1) == pytest.approx(0.1)
    assert load_fraction(1.0, 1.0) == math.inf


# ------------------------------------------------------------------- rotary: run-out

ROTARY = load_settings(CONFIGS / "rotary-pin-on-disc.toml")


def rotary_trace(*, run_out: float = 0.0, saw_pp: float = 0.0, saw_period_mm: float = 3.0,
                 harmonic: int = 1, seed: int = 0) -> Measurement:
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 62.0, 0.02)
    rev = np.clip(t - 1.0, 0.0, None) * 1.0  # 60 rpm
    s = rev * 2 * math.pi * 10.0
    mu = np.where(s > 0, 0.3 + run_out * np.sin(harmonic * 2 * math.pi * rev + 0.4), 0.0)
    if saw_pp:
        mu = mu + saw_pp * (((s / saw_period_mm) % 1.0) - 0.5) * (s > 20)
    fn = 5.0 + 0.01 * rng.standard_normal(t.size)
    return _measurement({TIME: t, "angle_rad": 2 * math.pi * rev,
                         FRICTION_FORCE: mu * fn + rng.normal(0, 0.005, t.size),
                         NORMAL_FORCE: fn})


@pytest.mark.parametrize("harmonic", [1, 2, 3])
def test_run_out_is_not_stick_slip(harmonic: int) -> None:
    got = reduce_measurement(rotary_trace(run_out=0.02, harmonic=harmonic),
                             ROTARY.instrument, ROTARY.reduction)
    assert "run_out" in got.flags
    assert "stick_slip" not in got.flags
    assert got.mu_k == pytest.approx(0.3, abs=0.003)


def test_saw_tooth_off_the_rotation_stays_stick_slip() -> None:
    got = reduce_measurement(rotary_trace(saw_pp=0.05, saw_period_mm=3.0),
                             ROTARY.instrument, ROTARY.reduction)
    assert "stick_slip" in got.flags
    assert "run_out" not in got.flags


def test_revolution_locked() -> None:
    assert revolution_locked(62.8, 3000.0, 62.83, 0.05)
    assert revolution_locked(31.4, 3000.0, 62.83, 0.05)
    assert not revolution_locked(3.0, 3000.0, 62.83, 0.05)
    assert not revolution_locked(45.0, 3000.0, 62.83, 0.05)
    assert not revolution_locked(62.8, 3000.0, None, 0.05)


# ------------------------------------------------------------ linear reciprocating

RECIP = load_settings(CONFIGS / "linear-reciprocating.toml")


def reciprocating_trace(*, mu: float = 0.3, offset_N: float = 0.1, tilt: float = 0.02,
                        sign: float = 1.0, seed: int = 0) -> Measurement:
    """A triangle stroke of 10 mm at 1 Hz for 60 cycles after 1 s at rest."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 61.0, 0.002)
    phase = np.clip(t - 1.0, 0.0, None) % 1.0
    x = np.where(phase < 0.5, 20.0 * phase, 20.0 * (1.0 - phase))  # mm
    v = np.gradient(x, t)
    fn = 10.0 + 0.02 * rng.standard_normal(t.size)
    moving = t > 1.0
    f = sign * mu * fn * np.tanh(v / 0.2) * moving + tilt * fn + offset_N
    return _measurement({TIME: t, POSITION: x * 1e-3,
                         FRICTION_FORCE: f + rng.normal(0, 0.02, t.size), NORMAL_FORCE: fn})


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_reciprocating_cycles(sign: float) -> None:
    got = reduce_measurement(reciprocating_trace(sign=sign), RECIP.instrument, RECIP.reduction)
    p = got.parameters
    assert p.n_cycles >= 58
    assert got.mu_k == pytest.approx(0.3, abs=0.002)
    # the tilt and the offset show at rest too: the zero takes them, both directions agree
    assert p.mu_k_forward == pytest.approx(p.mu_k_backward, abs=0.005)
    assert 0.5 * (p.mu_k_forward + p.mu_k_backward) == pytest.approx(0.3, abs=0.002)
    # without the zero each stroke carries them one way; the cycle's mean cancels them
    off = reduce_measurement(reciprocating_trace(sign=sign),
                             replace(RECIP.instrument, zero_offset="off"), RECIP.reduction)
    q = off.parameters
    assert abs(q.mu_k_forward - q.mu_k_backward) == pytest.approx(2 * 0.03, abs=0.005)
    assert off.mu_k == pytest.approx(got.mu_k, abs=1e-9)
    assert p.stroke_length_mm == pytest.approx(10.0, abs=0.05)
    assert len(p.cycles) == p.n_cycles
    assert got.sliding_distance_mm == pytest.approx(60 * 20.0, rel=0.01)


# ------------------------------------------------------------------------- configs


def test_instrument_files_load() -> None:
    methods = {load_settings(p).instrument.test_method for p in CONFIGS.glob("*.toml")}
    assert methods == set(TEST_METHODS)


@pytest.mark.parametrize(("instrument", "message"), [
    ({"test_method": "tilting plane"}, "test_method: expected one of"),
    ({"sled_mass_g": 200.0, "sled_weight_N": 2.0}, "not both"),
    ({"sled_mass_g": -1.0}, "sled_mass_g"),
    ({"zero_offset": "sometimes"}, "zero_offset"),
    ({"zero_offset": float("nan")}, "zero_offset"),
    ({"rest_after_sliding": "yes"}, "rest_after_sliding"),
])
def test_bad_instrument_keys(instrument: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        settings_from_dict({"instrument": instrument})


def test_windows_fit_metres() -> None:
    params = settings_from_dict({"reduction": {"peak_window_mm": 3150.0, "block_mm": 5000.0,
                                               "plateau_min_mm": 2e6}}).reduction
    assert params.peak_window_mm == 3150.0
    with pytest.raises(ConfigError, match="peak_window_mm"):
        settings_from_dict({"reduction": {"peak_window_mm": 2e6}})


def test_hash_of_a_config_without_the_new_keys_is_unchanged() -> None:
    """A config that uses none of the force-instrument keys keeps its hash (and a batch
    its reduced runs)."""
    plain = load_settings(CONFIGS / "t-pid44.toml")
    assert plain.config_hash == load_settings(None).config_hash == "bd32ca6cbce867a1"
    assert SLED.config_hash != plain.config_hash


# ------------------------------------------------------------- the map and its method


def _two_method_map(tmp_path: Path) -> Path:
    """The published map with the Dragonskin 30 on steel runs relabelled as sled runs."""
    from tribopipe.frictionmap import import_table, read_map, write_map
    from tribopipe.frictionmap.published import published_csv_path

    path = tmp_path / "friction_map.parquet"
    import_table(path, published_csv_path())
    runs = read_map(path)
    sled = (runs["pin"] == "Dragonskin 30") & (runs["disc"] == "steel")
    runs.loc[sled, "test_method"] = "sled D1894"
    write_map(path, runs)
    return path


def test_groups_never_pool_two_methods(tmp_path: Path) -> None:
    from tribopipe.frictionmap import read_map
    from tribopipe.stats import group_statistics

    runs = read_map(_two_method_map(tmp_path))
    groups = group_statistics(runs)
    assert "test_method" in groups.columns
    assert set(groups["test_method"]) == {"rheometer pin-on-disc", "sled D1894"}
    # a copy of a sled group's runs labelled as the rheometer's: two groups, not one
    sled = runs[runs["test_method"] == "sled D1894"].copy()
    sled["test_method"] = None
    sled["measurement_id"] = sled["measurement_id"] + "r"
    both = group_statistics(pd.concat([runs, sled], ignore_index=True))
    ds = both[(both["pin"] == "Dragonskin 30") & (both["disc"] == "steel")]
    assert len(ds) == 2 * len(groups[(groups["pin"] == "Dragonskin 30")
                                     & (groups["disc"] == "steel")])
    # a map of one method shows no method column, as before
    one = group_statistics(runs[runs["test_method"].isna()])
    assert "test_method" not in one.columns


def test_a_row_names_a_known_method(tmp_path: Path) -> None:
    from tribopipe.frictionmap import read_map, records_frame
    from tribopipe.frictionmap.checks import validate_runs
    from tribopipe.frictionmap.schema import frame_records

    runs = read_map(_two_method_map(tmp_path))
    record = dict(frame_records(runs.iloc[:1])[0])
    record["test_method"] = "tilting plane"
    with pytest.raises(Exception, match="test_method"):
        records_frame([record])
    runs.loc[runs.index[0], "test_method"] = "tilting plane"
    problems = [p for p in validate_runs(runs) if p.field == "test_method"]
    assert problems and "is not one of" in problems[0].problem


def test_map_table_filters_by_method(tmp_path: Path) -> None:
    from click.testing import CliRunner

    from tribopipe.cli import main

    path = _two_method_map(tmp_path)
    runner = CliRunner()
    out = runner.invoke(main, ["map", "table", "--map", str(path), "--method", "sled D1894"])
    assert out.exit_code == 0, out.output
    lines = out.output.strip().splitlines()
    assert all("Dragonskin 30,steel" in line for line in lines[1:])
    paper = runner.invoke(main, ["map", "table", "--map", str(path), "--layout", "paper",
                                 "--format", "markdown"])
    assert paper.exit_code == 0 and "| method |" in paper.output
    bad = runner.invoke(main, ["map", "table", "--map", str(path), "--method", "tilt"])
    assert bad.exit_code != 0 and "unknown test method 'tilt'" in bad.output
    assert "Traceback" not in bad.output


def test_explorer_data_carries_the_methods(tmp_path: Path) -> None:
    from tribopipe.export.explorer import explorer_data
    from tribopipe.frictionmap import read_map

    data = explorer_data(read_map(_two_method_map(tmp_path)))
    assert data["methods"] == ["rheometer pin-on-disc", "sled D1894"]
    assert {g["test_method"] for g in data["groups"]} == set(data["methods"])
    i = next(i for i, p in enumerate(data["pairs"])
             if (p["pin"], p["disc"]) == ("Dragonskin 30", "steel"))
    assert {r["test_method"] for r in data["runs"][i]} == {"sled D1894"}  # the pair's runs


# ------------------------------------------------------------------- end to end


def _sled_csv(path: Path, **kwargs: float) -> Path:
    m = sled_trace(**kwargs)
    lines = ['"Sample","PE film"', '"Test speed","150 mm/min"', "",
             '"Time (s)","Extension (mm)","Load (N)"']
    lines += [f"{t:.3f},{x * 1e3:.4f},{f:.6f}" for t, x, f in zip(
        m.data[TIME], m.data[POSITION], m.data[FRICTION_FORCE], strict=True)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_reduce_a_sled_export_into_the_map(tmp_path: Path) -> None:
    """The real CLI: a D1894 sled export with its instrument file; the row records the
    method, the statement of the normal force is in the summary."""
    import json
    import subprocess
    import sys

    from tribopipe.frictionmap import read_map

    export = _sled_csv(tmp_path / "pe_steel.csv", rest_load_N=0.45)
    map_path = tmp_path / "map.parquet"
    lab = tmp_path / "materials.toml"  # the lab's own material, one line
    lab.write_text('[materials]\n"PE film" = { class = "polymer" }\n', encoding="utf-8")
    done = subprocess.run(
        [sys.executable, "-m", "tribopipe", "reduce", str(export), "--pin", "PE film",
         "--materials", str(lab), "--disc", "steel", "--temperature", "23", "--repeat", "1",
         "--instrument",
         str(CONFIGS / "sled-d1894.toml"), "--map", str(map_path), "-o", str(tmp_path / "o"),
         "--json"], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    (row,) = read_map(map_path).to_dict(orient="records")
    assert row["test_method"] == "sled D1894"
    assert "zero_under_load" in row["flags"]
    assert row["mu_k"] == pytest.approx(0.25, abs=0.004)
    assert row["normal_force_measured_N"] == pytest.approx(0.2 * G)
    summary = json.loads(next((tmp_path / "o").rglob("*.json")).read_text())
    assert "sled mass 200 g" in json.dumps(summary)
    # --zero off: the pull at rest is not a zero either way
    off = subprocess.run(
        [sys.executable, "-m", "tribopipe", "reduce", str(export), "--instrument",
         str(CONFIGS / "sled-d1894.toml"), "--zero", "0.45", "--no-map", "--json"],
        capture_output=True, text=True, check=False)
    assert off.returncode == 0, off.stderr
    assert json.loads(off.stdout)[0]["mu_k"] == pytest.approx(0.25 - 0.45 / (0.2 * G),
                                                              abs=0.004)
    bad = subprocess.run(
        [sys.executable, "-m", "tribopipe", "reduce", str(export), "--zero", "maybe",
         "--no-map"], capture_output=True, text=True, check=False)
    assert bad.returncode != 0
    assert "--zero: expected auto, off or a number" in bad.stderr
    assert "Traceback" not in bad.stderr


def test_a_rheometer_run_whose_pins_start_pre_sheared() -> None:
    """The torque channel keeps the same rule: a rest that already carries the sliding
    torque is no zero (flagged); a small true offset still is one (subtracted)."""
    from tribopipe.config import load_settings as settings_of

    rng = np.random.default_rng(5)
    t = np.arange(0.0, 1200.0, 0.1)
    angle = np.clip(t - 100.0, 0.0, None) * 0.005 * 2 * math.pi / 60  # 0.005 rpm
    r_m = 13.37e-3
    sliding_torque = 0.4 * 3.0 * r_m
    at_rest = angle == 0
    base = settings_of(None)

    def run(rest_torque: float, offset: float) -> Measurement:
        torque = np.where(at_rest, rest_torque, sliding_torque) + offset
        torque = torque + rng.normal(0, 2e-6, t.size)
        return _measurement({TIME: t, "angle_rad": angle, "torque_Nm": torque,
                             NORMAL_FORCE: 3.0 + rng.normal(0, 0.003, t.size)})

    sheared = reduce_measurement(run(0.9 * sliding_torque, 0.0), base.instrument,
                                 base.reduction)
    assert "zero_under_load" in sheared.flags
    assert sheared.mu_k == pytest.approx(0.4, abs=0.003)
    honest = reduce_measurement(run(0.0, 2e-4), base.instrument, base.reduction)
    assert "zero_under_load" not in honest.flags
    assert honest.parameters.torque_offset_Nm == pytest.approx(2e-4, rel=0.02)
    assert honest.mu_k == pytest.approx(0.4, abs=0.003)


def test_inspect_names_the_force_channel(tmp_path: Path) -> None:
    from click.testing import CliRunner

    from tribopipe.cli import main

    export = _sled_csv(tmp_path / "sled.csv")
    out = CliRunner().invoke(main, ["inspect", str(export)])
    assert out.exit_code == 0, out.output
    assert "[friction force]" in out.output
    assert "Load [N]       → friction_force_N" in out.output
    assert "header block lines: 2" in out.output
    assert "reduce reads: interval 1" in out.output


def test_a_batch_of_sled_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A folder of sled exports through `batch`: the nominal speed is the instrument
    file's 150 mm/min (no rotational set point), so the runs are not off nominal."""
    from click.testing import CliRunner

    from tribopipe.cli import main
    from tribopipe.frictionmap import read_map

    folder = tmp_path / "raw"
    folder.mkdir()
    _sled_csv(folder / "PTFE_steel_2N_23C_r1.csv", seed=1)
    _sled_csv(folder / "PTFE_steel_2N_23C_r2.csv", seed=2, rest_load_N=0.4)
    monkeypatch.chdir(tmp_path)
    out = CliRunner().invoke(main, [
        "batch", str(folder), "--pattern", "{pin}_{disc}_{force}N_{temperature}C_r{repeat}",
        "--instrument", str(CONFIGS / "sled-d1894.toml"), "-o", str(tmp_path / "out"),
        "--jobs", "1", "--no-plots"])
    assert out.exit_code == 0, out.output
    runs = read_map(tmp_path / "out" / "friction_map.parquet").sort_values("repeat")
    assert list(runs["test_method"]) == ["sled D1894"] * 2
    assert list(runs["nominal_speed_mm_s"]) == [2.5, 2.5]
    assert "sliding_speed_off_nominal" not in ";".join(runs["flags"].fillna(""))
    assert runs["flags"].fillna("").tolist()[1] == "zero_under_load"
    assert runs["mu_k"].tolist() == pytest.approx([0.25, 0.25], abs=0.004)


def _pair_of_two_methods(tmp_path: Path) -> tuple[Path, pd.DataFrame]:
    """The published map plus a copy of the Dragonskin 30 on steel runs, labelled as sled
    runs with μ 1.5 times the rheometer's: one pair measured by two methods."""
    from tribopipe.frictionmap import import_table, read_map, write_map
    from tribopipe.frictionmap.published import published_csv_path

    path = tmp_path / "friction_map.parquet"
    import_table(path, published_csv_path())
    runs = read_map(path)
    sled = runs[(runs["pin"] == "Dragonskin 30") & (runs["disc"] == "steel")].copy()
    sled["test_method"] = "sled D1894"
    sled["measurement_id"] = sled["measurement_id"] + "-sled"
    sled["mu_k"] = sled["mu_k"] * 1.5
    write_map(path, pd.concat([runs, sled], ignore_index=True))
    return path, sled


def test_query_and_export_never_pool_two_methods(tmp_path: Path) -> None:
    import json

    from click.testing import CliRunner

    from tribopipe.cli import main

    path, sled = _pair_of_two_methods(tmp_path)
    p, t = float(sled["pressure_kPa"].iloc[0]), float(sled["temperature_C"].iloc[0])
    at = sled[(sled["pressure_kPa"] == p) & (sled["temperature_C"] == t)]
    runner = CliRunner()
    ask = ["query", "--map", str(path), "--pin", "Dragonskin 30", "--disc", "steel",
           "--pressure", f"{p!r}", "--temperature", f"{t!r}"]
    refused = runner.invoke(main, ask)
    assert refused.exit_code != 0 and "Traceback" not in refused.output
    assert "2 test methods (rheometer pin-on-disc; sled D1894)" in refused.output
    assert "--method" in refused.output
    sled_out = runner.invoke(main, [*ask, "--method", "sled D1894", "--json"])
    assert sled_out.exit_code == 0, sled_out.output
    data = json.loads(sled_out.output)
    assert data["method"] == "sled D1894"
    assert data["mu_k"]["value"] == pytest.approx(float(at["mu_k"].mean()), rel=1e-9)
    rheo = json.loads(runner.invoke(main, [*ask, "--method", "RHEOMETER pin-on-disc",
                                           "--json"]).output)
    assert rheo["method"] == "rheometer pin-on-disc"
    assert data["mu_k"]["value"] == pytest.approx(1.5 * rheo["mu_k"]["value"], rel=1e-9)
    text = runner.invoke(main, [*ask, "--method", "sled D1894"])
    assert text.exit_code == 0 and "test method: sled D1894" in text.output
    absent = runner.invoke(main, [*ask, "--method", "rotary pin-on-disc"])
    assert absent.exit_code != 0 and "no group measured by 'rotary pin-on-disc'" in \
        absent.output
    # a single-condition export reads the same rule
    export = ["export", "mujoco", "--map", str(path), "--pin", "Dragonskin 30", "--disc",
              "steel", "--pressure", f"{p!r}", "--temperature", f"{t!r}"]
    no_choice = runner.invoke(main, export)
    assert no_choice.exit_code != 0 and "sled D1894" in no_choice.output
    chosen = runner.invoke(main, [*export, "--method", "sled D1894"])
    assert chosen.exit_code == 0, chosen.output
    assert f"{float(at['mu_k'].mean()):.3f}"[:4] in chosen.output
    # a pair of one method needs no choice
    from tribopipe.frictionmap import read_map

    runs = read_map(path)
    eco = runs[(runs["pin"] == "Ecoflex 00-50") & (runs["disc"] == "steel")].iloc[0]
    other = runner.invoke(main, ["query", "--map", str(path), "--pin", "Ecoflex 00-50",
                                 "--disc", "steel", "--pressure", f"{float(eco['pressure_kPa'])!r}",
                                 "--temperature", f"{float(eco['temperature_C'])!r}", "--json"])
    assert other.exit_code == 0, other.output
    assert json.loads(other.output)["method"] == "rheometer pin-on-disc"

"""The nominal sliding speed is part of a run's condition: decided once from the interval's
set point (or the instrument config), rounded by one rule, flagged when the measured speed
strays; groups split by it and show it only where a pair holds several speeds; maps older
than the column read and group as the founding speed."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from test_frictionmap import reduced_result, run_record
from tribopipe import frictionmap as fm
from tribopipe.config import InstrumentConfig
from tribopipe.labels import (
    FLAG_SPEED_OFF,
    RunLabels,
    Tolerances,
    decide_run,
    nominal_speed_mm_s,
    round_speed,
)
from tribopipe.physics import FOUNDING_SLIDING_SPEED_MM_S, sliding_speed_mm_s
from tribopipe.stats import group_statistics, nominal_speeds

DATA = Path(__file__).parent / "data"


def test_nominal_speed_rounds_the_set_point_then_the_sliding_speed():
    cell = InstrumentConfig()
    expected = round_speed(sliding_speed_mm_s(0.005, cell.friction_radius_mm))
    # a measured set point a little off the dialled 0.005 rpm is still 0.005 rpm
    assert nominal_speed_mm_s(0.00503, cell) == expected
    assert nominal_speed_mm_s(0.00497, cell) == expected
    # no set point: the instrument's nominal speed
    assert nominal_speed_mm_s(None, cell) == expected == FOUNDING_SLIDING_SPEED_MM_S
    assert nominal_speed_mm_s(float("nan"), cell) == expected
    faster = nominal_speed_mm_s(0.15, cell)
    assert faster == pytest.approx(30 * expected, rel=0.02)
    assert faster == round_speed(faster)


def test_a_measured_speed_off_its_nominal_is_flagged_once():
    labels = RunLabels(pin="a", disc="b", normal_force_N=3.0, temperature_C=20.0)
    nominal = nominal_speed_mm_s(0.05, InstrumentConfig())
    on = decide_run(labels, (), 3.0, 20.0, speed_set_point_rpm=0.05,
                    sliding_speed_measured_mm_s=nominal * 1.05)
    off = decide_run(labels, (), 3.0, 20.0, speed_set_point_rpm=0.05,
                     sliding_speed_measured_mm_s=nominal * 1.2)
    assert on.nominal_speed_mm_s == off.nominal_speed_mm_s == nominal
    assert FLAG_SPEED_OFF not in on.flags and FLAG_SPEED_OFF in off.flags
    loose = decide_run(labels, (), 3.0, 20.0, Tolerances(speed_rel=0.3),
                       speed_set_point_rpm=0.05, sliding_speed_measured_mm_s=nominal * 1.2)
    assert FLAG_SPEED_OFF not in loose.flags


def test_the_map_row_carries_the_nominal_speed_of_the_set_point():
    record = run_record(1)
    result = reduced_result()
    assert record.nominal_speed_mm_s == nominal_speed_mm_s(
        result.speed_set_point_rpm, InstrumentConfig())
    stepped = run_record(2, speed_set_point_rpm=0.15)
    assert stepped.nominal_speed_mm_s == nominal_speed_mm_s(0.15, InstrumentConfig())
    # the measured speed stayed at 0.005 rpm: off the 0.15 rpm set point
    assert FLAG_SPEED_OFF in stepped.flags.split(";")


def _pair(i: int, pin: str, speed: float | None, mu_k: float) -> dict:
    return {**run_record(0).as_dict(), "measurement_id": f"r{i:03d}", "pin": pin,
            "nominal_speed_mm_s": speed, "mu_k": mu_k, "repeat": i}


def test_groups_split_by_nominal_speed_and_show_it_only_where_a_pair_has_several():
    one = [_pair(1, "A", 0.007, 0.50), _pair(2, "A", 0.007, 0.52)]
    groups = group_statistics(fm.records_frame(one))
    assert "nominal_speed_mm_s" not in groups.columns and groups["mu_k_n"].tolist() == [2]
    several = one + [_pair(3, "A", 0.07, 0.60), _pair(4, "A", 0.07, 0.62),
                     _pair(5, "B", 0.007, 0.3)]
    groups = group_statistics(fm.records_frame(several))
    assert groups["nominal_speed_mm_s"].tolist() == [0.007, 0.07, 0.007]
    assert groups["mu_k_n"].tolist() == [2, 2, 1]
    assert groups["mu_k_mean"].tolist() == pytest.approx([0.51, 0.61, 0.3])
    # the speeds' means do not mix: the pooled repeatability is the repeats' own
    assert groups["mu_k_std"].iloc[0] == pytest.approx(math.sqrt(2e-4))
    hidden = group_statistics(fm.records_frame(several), show_speed=False)
    assert "nominal_speed_mm_s" not in hidden.columns and len(hidden) == 3


def test_a_row_without_a_nominal_speed_counts_as_the_founding_speed():
    rows = [_pair(1, "A", None, 0.50), _pair(2, "A", FOUNDING_SLIDING_SPEED_MM_S, 0.52)]
    groups = group_statistics(fm.records_frame(rows))
    assert groups["mu_k_n"].tolist() == [2] and "nominal_speed_mm_s" not in groups.columns


@pytest.mark.parametrize("name", ["friction_map_v1.parquet", "friction_map_v3.parquet"])
def test_older_maps_read_and_group_as_before(name):
    runs = fm.read_map(DATA / name)
    assert runs["nominal_speed_mm_s"].isna().all()
    assert (nominal_speeds(runs) == FOUNDING_SLIDING_SPEED_MM_S).all()
    groups = group_statistics(runs)
    assert "nominal_speed_mm_s" not in groups.columns
    # the same groups as without any speed: one per pin, disc, force, temperature
    included = runs.loc[~runs["excluded"].astype(bool)]
    keys = {(p, d, round(f, 6), t if t == t else None) for p, d, f, t in zip(
        included["pin"], included["disc"], included["normal_force_N"],
        included["temperature_C"], strict=True)}
    assert len(groups) >= len(keys)
    assert int(groups["mu_k_n"].sum()) == int(np.isfinite(included["mu_k"]).sum())


# ---------------------------------------------------------------------------- query


def _two_speed_groups():
    from tribopipe.query import groups_of

    rows = [_pair(1, "A", 0.007, 0.50), _pair(2, "A", 0.007, 0.52),
            _pair(3, "A", 0.07, 0.60), _pair(4, "A", 0.07, 0.62), _pair(5, "B", 0.007, 0.3)]
    return groups_of(fm.records_frame(rows), "map.parquet")


def test_query_interpolates_linearly_in_log_speed_between_measured_speeds():
    from tribopipe.query import query

    groups = _two_speed_groups()
    p = float(groups["pressure_kPa"].iloc[0])
    at_low = query(groups, "A", "steel", p, 20.0, 0.007)
    at_high = query(groups, "A", "steel", p, 20.0, 0.07)
    assert at_low.mu_k.value == pytest.approx(0.51) and at_high.mu_k.value == pytest.approx(0.61)
    v = 0.007 * 10 ** 0.3
    mid = query(groups, "A", "steel", p, 20.0, v)
    assert mid.mu_k.value == pytest.approx(0.51 + 0.3 * (0.61 - 0.51))
    assert not mid.clamped and mid.speed_mm_s == v and mid.speeds_mm_s == (0.007, 0.07)
    assert sorted(u.weight for u in mid.mu_k.used) == pytest.approx([0.3, 0.7])
    # U carried with the weights: between the two speeds' U
    assert min(at_low.mu_k.expanded, at_high.mu_k.expanded) <= mid.mu_k.expanded <= max(
        at_low.mu_k.expanded, at_high.mu_k.expanded) + 1e-12
    data = mid.to_dict()
    assert data["speed_mm_s"] == v and set(data["mu_k"]) >= {"value", "expanded", "text"}


def test_query_holds_and_flags_outside_the_measured_speeds_and_needs_a_speed_only_where_several():
    from tribopipe.errors import ExportError
    from tribopipe.query import query

    groups = _two_speed_groups()
    p = float(groups["pressure_kPa"].iloc[0])
    fast = query(groups, "A", "steel", p, 20.0, 1.0)
    assert fast.mu_k.value == pytest.approx(0.61) and fast.clamped and fast.mu_k.clamped_speed
    assert any("speed outside" in n for n in fast.notes)
    with pytest.raises(ExportError, match="sliding speed needed"):
        query(groups, "A", "steel", p, 20.0)
    one = query(groups, "B", "steel", p, 20.0)
    assert one.speed_mm_s == 0.007 and not one.clamped
    held = query(groups, "B", "steel", p, 20.0, 0.07)
    assert held.mu_k.value == pytest.approx(0.3) and held.mu_k.clamped_speed


# ---------------------------------------------------------------------------- the JS copy


def _multi_speed_runs():
    """The published runs, budgeted, at two more nominal speeds with faster μ_K (one
    pair stays at one speed)."""
    import pandas as pd

    from published_map import PUBLISHED_CSV, published_runs
    from test_interpolation import budgeted_runs

    base = budgeted_runs(published_runs(PUBLISHED_CSV))
    base["nominal_speed_mm_s"] = 0.007
    parts = [base]
    movers = base[base["disc"] != "steel"]
    for factor, speed in ((1.15, 0.021), (1.3, 0.07)):
        faster = movers.copy()
        faster["nominal_speed_mm_s"] = speed
        faster["mu_k"] = faster["mu_k"] * factor
        faster["measurement_id"] = faster["measurement_id"] + f"-{speed}"
        parts.append(faster)
    return pd.concat(parts, ignore_index=True)


def test_the_js_query_between_speeds_is_the_python_query():
    from test_interpolation import run_node
    from tribopipe.export.explorer import explorer_data
    from tribopipe.query import groups_of, pairs, query

    runs = _multi_speed_runs()
    groups = groups_of(runs, "map")
    data = explorer_data(runs, groups=groups)
    conditions = []
    for pin, disc in pairs(groups):
        pair = groups[(groups["pin"] == pin) & (groups["disc"] == disc)]
        p = float(pair["pressure_kPa"].median())
        t = float(pair["temperature_C"].min()) + 3.0
        several = pair["nominal_speed_mm_s"].nunique() > 1
        for v in ([0.007, 0.01, 0.021, 0.05, 0.07, 0.2, 0.001] if several else [None, 0.05]):
            conditions.append([pin, disc, p, t, v])
    got = run_node(data, "return " + json.dumps(conditions) + ".map(function (c) { "
                   "return query(c[0], c[1], c[2], c[3], c[4]); });")
    for (pin, disc, p, t, v), page in zip(conditions, got, strict=True):
        res = query(groups, pin, disc, p, t, v)
        assert page["notes"] == list(res.notes), (pin, disc, v)
        assert page["clamped"] == res.clamped and page["speed_mm_s"] == res.speed_mm_s
        assert page["speeds_mm_s"] == list(res.speeds_mm_s)
        for mine, est in ((page["mu_k"], res.mu_k), (page["mu_s"], res.mu_s)):
            for name in ("value", "uncertainty", "u_interpolation", "u_groups", "expanded"):
                a, b = mine[name], getattr(est, name)
                assert (a is None) == (b is None), (name, pin, disc, v)
                if a is not None:
                    assert a == pytest.approx(b, rel=1e-12, abs=1e-15), (name, pin, disc, v)
            assert mine["text"] == est.text() and mine["clamped_speed"] == est.clamped_speed
            assert [u["weight"] for u in mine["used"]] == pytest.approx(
                [u.weight for u in est.used], rel=1e-12)
            assert [u["speed_mm_s"] for u in mine["used"]] == [u.speed_mm_s for u in est.used]


# ---------------------------------------------------------------------------- exports


def test_abaqus_and_ansys_tables_carry_the_measured_slip_rates():
    from tribopipe.export.fe_decks import write_abaqus, write_ansys
    from tribopipe.query import groups_of, query

    runs = _multi_speed_runs()
    groups = groups_of(runs, "map")
    pin, disc = "Dragonskin 30", "acrylic glass"
    deck = write_abaqus(groups, pin=pin, disc=disc, units="m-N-s")
    rows = [line.split(", ") for line in deck.splitlines()
            if line and line[0].isdigit()]
    slips = sorted({float(r[1]) for r in rows})
    # the measured speeds, and rows between them (the engine reads linearly in v)
    measured = [0.007e-3, 0.021e-3, 0.07e-3]
    assert all(any(s == pytest.approx(m) for s in slips) for m in measured)
    assert len(slips) > len(measured) and min(slips) == pytest.approx(measured[0])
    assert max(slips) == pytest.approx(measured[-1])
    # the slip rate varies fastest, and every cell is query at its speed
    assert [float(r[1]) for r in rows[:len(slips)]] == pytest.approx(slips)
    for r in rows[:2 * len(slips)]:
        p_kPa, t, v = float(r[2]) * 1e-3, float(r[3]), float(r[1]) * 1e3
        assert float(r[0]) == pytest.approx(query(groups, pin, disc, p_kPa, t, v).mu_k.value,
                                            rel=1e-6)
    assert "measured nominal sliding speeds" in deck and "slip rate(s) added" in deck
    # a pair of one speed keeps its one slip rate
    steel = write_abaqus(groups, pin=pin, disc="steel")
    assert len({line.split(", ")[1] for line in steel.splitlines()
                if line and line[0].isdigit()}) == 1
    mapdl = write_ansys(groups, pin=pin, disc=disc)
    assert mapdl.count("TBFIELD,SLRV,") == len(rows)
    lines = mapdl.splitlines()
    first = lines.index(next(x for x in lines if x.startswith("TBFIELD,SLRV")))
    assert lines[first - 1].startswith("TBFIELD,NPRES") and lines[first + 1].startswith("TBDATA")


def test_a_pair_of_several_speeds_exports_at_one_temperature():
    """A deck restricted to one temperature (``--temperature``) of a pair measured at
    several speeds is its table over pressure and slip rate at that temperature, each
    cell query's value there; its comment names the cells filled, with their speed."""
    from tribopipe.export.fe_decks import write_abaqus, write_ansys
    from tribopipe.query import groups_of, query

    groups = groups_of(_multi_speed_runs(), "map")
    pin, disc = "Dragonskin 30", "acrylic glass"
    pair = groups[(groups["pin"] == pin) & (groups["disc"] == disc)]
    t = float(pair["temperature_C"].min()) + 3.0  # between measured temperatures
    deck = write_abaqus(groups, pin=pin, disc=disc, temperature_C=t)
    rows = [[float(x) for x in line.split(", ")] for line in deck.splitlines()
            if line and line[0].isdigit()]
    assert rows and {r[3] for r in rows} == {t}
    assert len({r[1] for r in rows}) > 3  # the three measured slip rates and rows between
    for mu, v, p_MPa, _ in rows[:: max(1, len(rows) // 25)]:  # units mm-N-s
        assert mu == pytest.approx(query(groups, pin, disc, p_MPa * 1e3, t, v).mu_k.value,
                                   rel=1e-6)
    filled = [line for line in deck.splitlines() if line.startswith("**   p = ")]
    assert filled and all(f"T = {t:g} C, v = " in line for line in filled)
    mapdl = write_ansys(groups, pin=pin, disc=disc, temperature_C=t)
    assert mapdl.count("TBFIELD,SLRV,") == len(rows)
    assert mapdl.count("TBFIELD,TEMP,") == 1
    # every temperature: the comment names the pressure rows added that the deck holds,
    # those of every speed's table (not of the pair's groups read as one speed)
    whole = write_abaqus(groups, pin=pin, disc=disc)
    text = " ".join(line[2:].strip() for line in whole.splitlines() if line.startswith("**"))
    said = re.search(r"(\d+) pressure row\(s\) added .*? Added at \(kPa\): "
                     r"([\d.]+(?:, [\d.]+)*)", text)
    assert said is not None
    added = [float(x) for x in said.group(2).split(", ")]
    held = {float(line.split(", ")[2]) * 1e3 for line in whole.splitlines()
            if line and line[0].isdigit()}
    measured = {float(v) for v in pair["pressure_kPa"]}
    extra = [p for p in held if not any(abs(p - q) <= 1e-6 * q for q in measured)]
    assert int(said.group(1)) == len(added) == len(extra) > 0
    assert all(any(abs(a - p) <= 5e-4 * p for p in extra) for a in added)


@pytest.fixture(scope="module")
def speed_grid_query():
    """The multi-speed map's groups, one pair, and query's μ_K on a grid of pressure x
    speed x temperature over its measured range (geometric midpoints between the measured
    speeds and 0.0121 mm/s included), computed once for both engines."""
    from tribopipe.query import groups_of, query

    groups = groups_of(_multi_speed_runs(), "map")
    pin, disc = "Dragonskin 30", "acrylic glass"
    pair = groups[(groups.pin == pin) & (groups.disc == disc)]
    speeds = sorted(set(pair.nominal_speed_mm_s))
    assert speeds == [0.007, 0.021, 0.07]
    vs = sorted(set(np.geomspace(speeds[0], speeds[-1], 9))
                | {math.sqrt(a * b) for a, b in zip(speeds, speeds[1:], strict=False)}
                | {0.0121})
    ps = np.geomspace(pair.pressure_kPa.min(), pair.pressure_kPa.max(), 7)
    temps = sorted(set(pair.temperature_C))
    ts = sorted(set(temps) | {(temps[0] + temps[-1]) / 2 + 0.5})
    grid = {(float(p), float(t), float(v)): query(groups, pin, disc, p, t, v).mu_k.value
            for v in vs for p in ps for t in ts}
    return groups, pin, disc, grid


@pytest.mark.parametrize("fmt", ["abaqus", "ansys"])
def test_the_engines_reading_between_speeds_stays_within_tolerance_of_query(
        fmt, speed_grid_query):
    """Read the pair's table over slip rate, pressure and temperature as the engine does
    (linear between rows, ends held) on a grid of pressure x speed x temperature: within
    the promise of query, where rows at the measured speeds alone left gaps up to 0.024
    (the engine's weights linear in v against query's linear in ln v)."""
    from sim_files import engine_reading_by_speed, parse_abaqus
    from tribopipe.export.fe_decks import write_abaqus, write_ansys
    from tribopipe.interpolation import ENGINE_TOLERANCE

    groups, pin, disc, grid = speed_grid_query
    if fmt == "abaqus":
        (block,) = parse_abaqus(write_abaqus(groups, pin=pin, disc=disc)).values()
        entries = [(r[3], r[2] * 1e3, r[1], r[0]) for r in block["rows"]]  # mm-N-s: MPa
    else:
        entries, field = [], {}
        for line in write_ansys(groups, pin=pin, disc=disc).splitlines():
            if line.startswith("TBFIELD,"):
                _, name, value = line.split(",")
                field[name] = float(value)
            elif line.startswith("TBDATA,1,"):
                entries.append((field["TEMP"], field["NPRES"] * 1e3, field["SLRV"],
                                float(line.split(",")[2])))
    reading = engine_reading_by_speed(entries)
    gaps = {key: abs(reading(*key) - mu) for key, mu in grid.items()}
    worst = max(gaps.values())
    assert worst <= ENGINE_TOLERANCE, (worst, max(gaps, key=gaps.get))


def test_lsdyna_fits_fs_fd_dc_to_the_measured_speeds():
    from tribopipe.export.simulators import export_simulator_input
    from tribopipe.fit import fit_decay

    truth = (0.4, 0.7, 20.0)
    curve = [(v, truth[1] + (truth[0] - truth[1]) * math.exp(-truth[2] * v))
             for v in (0.007, 0.021, 0.07, 0.21)]
    fit = fit_decay(curve)
    assert (fit.fs, fit.fd, fit.dc_s_per_mm) == pytest.approx(truth, rel=1e-4)
    assert fit.rising and fit.max_abs < 1e-8
    assert fit_decay(curve[:2]) is None

    runs = _multi_speed_runs()
    from tribopipe.query import groups_of

    groups = groups_of(runs, "map")
    pin, disc = "Dragonskin 30", "acrylic glass"
    p = float(groups.loc[groups["disc"] == disc, "pressure_kPa"].iloc[0])
    deck = export_simulator_input(groups, "lsdyna", pin=pin, disc=disc, pressure_kPa=p,
                                  temperature_C=20.0, speed_mm_s=0.021)
    assert "fitted to mu_k over the measured sliding speeds" in deck and "residuals rms" in deck
    one = export_simulator_input(groups, "lsdyna", pin=pin, disc="steel", pressure_kPa=p,
                                 temperature_C=20.0, coefficient="mu_s")
    assert "no speed dependence measured" in one
    from tribopipe.errors import ExportError

    # one message names the missing speed with the speeds the pair is measured at
    with pytest.raises(ExportError, match=r"lsdyna takes one condition; give --speed \("
                                          r"0\.007, 0\.021, 0\.07 mm/s\)"):
        export_simulator_input(groups, "lsdyna", pin=pin, disc=disc, pressure_kPa=p,
                               temperature_C=20.0)


# ---------------------------------------------------------------------------- end to end


def test_a_stepped_speed_test_gives_one_run_and_one_nominal_speed_per_step(tmp_path):
    from generators.speed import SPEEDS_RPM, speed_grid, write_test
    from tribopipe.config import load_settings
    from tribopipe.pipeline import read_runs, reduce_run, run_summary

    grid = speed_grid()
    assert len(grid) == 48 and {len(t.steps) for t in grid} == {4}
    test = grid[5]
    export = read_runs(write_test(tmp_path / "stepped.txt", test))
    assert len(export.runs) == len(SPEEDS_RPM)
    labels = RunLabels(pin=test.pair.pin, disc=test.pair.disc, normal_force_N=test.force_N,
                       temperature_C=test.temperature_C, repeat=test.repeat)
    settings = load_settings()
    records = []
    for (place, measurement), step in zip(export.runs, test.steps, strict=True):
        outcome = reduce_run(export, place, measurement, settings, labels)
        assert outcome.result.speed_set_point_rpm == pytest.approx(step.speed_rpm, rel=1e-3)
        assert outcome.result.mu_k == pytest.approx(step.mu_k, abs=0.002)
        assert FLAG_SPEED_OFF not in outcome.verdict.flags
        summary = run_summary(outcome)
        assert summary["nominal_speed_mm_s"] == outcome.record.nominal_speed_mm_s
        assert summary["speed_set_point_rpm"] == outcome.result.speed_set_point_rpm
        records.append(outcome.record)
    speeds = [r.nominal_speed_mm_s for r in records]
    assert speeds == [nominal_speed_mm_s(v, settings.instrument) for v in SPEEDS_RPM]
    assert len(set(speeds)) == 4
    groups = group_statistics(fm.records_frame(records))
    assert groups["nominal_speed_mm_s"].tolist() == speeds and set(groups["mu_k_n"]) == {1}


def test_the_power_law_fit_never_mixes_speeds():
    from tribopipe.fit import FIT_COLUMNS, fit_power_law

    runs = _multi_speed_runs()
    fits = fit_power_law(runs)
    assert "nominal_speed_mm_s" in fits.columns
    acrylic = fits[fits["disc"] == "acrylic glass"]
    assert sorted(set(acrylic["nominal_speed_mm_s"])) == [0.007, 0.021, 0.07]
    one = fit_power_law(runs[runs["nominal_speed_mm_s"] == 0.007])
    assert list(one.columns) == list(FIT_COLUMNS)


def test_a_map_of_several_speeds_publishes_validates_and_merges(tmp_path):
    from click.testing import CliRunner

    from tribopipe.cli import main

    map_path = tmp_path / "m.parquet"
    fm.write_map(map_path, _multi_speed_runs())
    runner = CliRunner()
    out = runner.invoke(main, ["map", "publish", "-o", str(tmp_path / "pkg"), "--lab", "Lab",
                               "--map", str(map_path)])
    assert out.exit_code == 0, out.output
    header = (tmp_path / "pkg" / "data" / "groups.csv").read_text().splitlines()[0]
    assert "nominal_speed_mm_s" in header.split(",")
    valid = runner.invoke(main, ["map", "validate", str(tmp_path / "pkg")])
    assert valid.exit_code == 0 and "valid" in valid.output, valid.output
    merged = runner.invoke(main, ["map", "merge", str(tmp_path / "pkg"), "--map",
                                  str(tmp_path / "merged.parquet")])
    assert merged.exit_code == 0, merged.output
    runs = fm.read_map(tmp_path / "merged.parquet")
    assert sorted(set(runs["nominal_speed_mm_s"])) == [0.007, 0.021, 0.07]

"""Seeded synthetic runs and the RheoCompass export writer.

The generator must be reproducible and its truth must describe what it generates; the
writer must produce what RheoCompass writes (checked line by line against a real export)
so that the readers, the examples and the benchmark exercise the real layout.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import DATA
from generators.synthetic import (
    SHAPES,
    SyntheticRun,
    make_intervals,
    mu_curve,
    rheocompass_text,
    truth,
    write_rheocompass_export,
)
from tribopipe.config import InstrumentConfig, ReductionParams
from tribopipe.measurement import RHEOMETER_COLUMNS
from tribopipe.readers import read_export
from tribopipe.reduction.intervals import select_friction_interval
from tribopipe.reduction.reduce import reduce_measurement

RUN = SyntheticRun(mu_s=0.9, mu_k=0.6, noise=0.008, torque_offset_Nm=3e-4, seed=5)


def test_same_seed_same_numbers_other_seed_other_numbers() -> None:
    a, b = make_intervals(RUN), make_intervals(RUN)
    for x, y in zip(a, b, strict=True):
        pd.testing.assert_frame_equal(x, y)
    c = make_intervals(replace(RUN, seed=6))
    assert not np.allclose(a[1]["torque_Nm"], c[1]["torque_Nm"])


def test_intervals_have_the_canonical_columns_and_lengths() -> None:
    setup, friction = make_intervals(RUN)
    assert list(setup.columns) == list(RHEOMETER_COLUMNS)
    assert list(friction.columns) == list(RHEOMETER_COLUMNS)
    assert len(setup) == round(RUN.setup_s * RUN.sample_rate_Hz)
    assert len(friction) == round(RUN.duration_s * RUN.sample_rate_Hz)
    assert np.allclose(np.diff(friction["time_s"]), 0.1)
    assert len(make_intervals(replace(RUN, setup_interval=False))) == 1


def test_set_up_ramps_the_force_without_rotation() -> None:
    setup = make_intervals(RUN)[0]
    assert (setup["angle_rad"] == 0).all() and (setup["speed_rad_s"] == 0).all()
    assert setup["normal_force_N"].iloc[0] < 0.1 * RUN.normal_force_N
    assert setup["normal_force_N"].iloc[-50:].mean() == pytest.approx(3.0, abs=0.01)
    # with the disc at rest the torque is the zero offset
    assert setup["torque_Nm"].median() == pytest.approx(3e-4, abs=5e-5)


def test_friction_interval_turns_at_the_set_speed_after_the_rest() -> None:
    friction = make_intervals(RUN)[1]
    at_rest = friction["time_s"] <= RUN.rest_s
    assert (friction.loc[at_rest, "angle_rad"] == 0).all()
    omega = RUN.speed_rpm * 2 * math.pi / 60
    assert friction.loc[~at_rest, "speed_rad_s"].to_numpy() == pytest.approx(omega)
    travelled = friction["angle_rad"].iloc[-1] * RUN.friction_radius_mm
    assert travelled == pytest.approx(truth(RUN).sliding_distance_mm, rel=1e-9)
    # 300 s at 0.007 mm/s, less the 2 s rest: 2.086 mm
    assert travelled == pytest.approx(0.0070 * 298, rel=0.01)


def test_the_curve_peaks_at_mu_s_and_settles_at_mu_k() -> None:
    want = truth(RUN)
    s = np.linspace(0, 2.0, 20001)
    mu = mu_curve(RUN, s)
    assert mu.max() == pytest.approx(RUN.mu_s, abs=1e-6)
    assert s[np.argmax(mu)] == pytest.approx(want.mu_s_distance_mm, abs=1e-3)
    assert 0.05 <= want.mu_s_distance_mm <= 0.25
    assert mu[-1] == pytest.approx(RUN.mu_k, abs=1e-6)


def test_stick_slip_saw_tooth_averages_to_mu_k() -> None:
    run = replace(RUN, shape="stick_slip")
    p = truth(run).shape_params
    start = p["peak_distance_mm"]
    cycles = 20
    s = np.linspace(start, start + cycles * p["stick_slip_period_mm"], 200_001)[:-1]
    mu = mu_curve(run, s)
    assert mu.mean() == pytest.approx(run.mu_k, abs=1e-4)
    assert np.ptp(mu) == pytest.approx(p["stick_slip_amplitude"], rel=1e-3)
    assert truth(run).stick_slip


def test_no_overshoot_has_mu_s_equal_to_mu_k_in_its_truth() -> None:
    run = replace(RUN, shape="no_overshoot")
    want = truth(run)
    assert want.mu_s == want.mu_k == run.mu_k
    assert not want.static_distinct
    assert np.all(np.diff(mu_curve(run, np.linspace(0, 2, 1000))) >= 0)


def test_drift_shape_settles_slowly() -> None:
    run = replace(RUN, shape="drift")
    s_half = truth(run).shape_params["peak_distance_mm"] + 0.5
    fast = mu_curve(RUN, np.array([s_half]))[0]
    slow = mu_curve(run, np.array([s_half]))[0]
    assert fast == pytest.approx(RUN.mu_k, abs=1e-4)
    assert slow - RUN.mu_k > 0.01


def test_bad_runs_are_refused() -> None:
    with pytest.raises(ValueError, match="shape must be one of"):
        SyntheticRun(shape="wobbly")
    with pytest.raises(ValueError, match="direction"):
        SyntheticRun(direction=0)
    assert set(SHAPES) == {"overshoot", "no_overshoot", "stick_slip", "drift", "cliff"}


# --------------------------------------------------------------------------- the writer


def _lines(path: Path) -> list[str]:
    raw = path.read_bytes()
    assert raw[:2] == b"\xff\xfe"  # UTF-16 LE BOM
    text = raw[2:].decode("utf-16-le")
    assert "\n" not in text.replace("\r\n", "")  # CRLF only
    assert text.endswith("\r\n")
    return text[:-2].split("\r\n")


def test_export_layout_line_by_line(tmp_path: Path) -> None:
    path = write_rheocompass_export(tmp_path / "run.csv", RUN, project="Friction campaign",
                                    test="DS30 on steel", sample="DS30")
    lines = _lines(path)
    assert lines[:6] == ["Project:\tFriction campaign", "", "Test:\tDS30 on steel", "",
                         "Result:\tDS30 1", ""]
    assert lines[6] == "Interval and data points:\t1\t200"
    assert lines[7] == ("Interval data:\tPoint No.\tTime\tTorque\tNormal Force\t"
                        "Deflection Angle\tRotational Speed\tTemperature\tStatus")
    assert lines[8] == "\t" * 8
    assert lines[9] == "\t\t[s]\t[mN·m]\t[N]\t[mrad]\t[1/min]\t[°C]\t"
    first = lines[10].split("\t")
    assert first[0] == "" and first[1] == "1" and first[-1] == "" and len(first) == 9
    second_header = lines.index("Interval and data points:\t2\t3000")
    assert lines[second_header - 1] == ""
    assert len(lines) == second_header + 4 + 3000
    last = lines[-1].split("\t")
    assert last[1] == "3000"
    assert float(last[2]) == pytest.approx(300.0)
    # speed 0.005 1/min, angle in mrad
    assert float(last[6]) == pytest.approx(0.005)
    assert float(last[5]) == pytest.approx(0.005 * 2 * math.pi / 60 * 298 * 1e3, rel=1e-3)


def test_export_structure_matches_a_real_rheocompass_file(tmp_path: Path) -> None:
    """Same block structure as a real RheoCompass UTF-16 export: label lines, blank
    separators, the interval header, the meaning row of bare TABs, the unit row."""
    # the copy in tests/data (MIT, byte-identical to ../shared's: test_readers_real checks)
    real = DATA / "rheocompass_en_utf16_small.txt"
    real_lines = _lines(real)
    ours = _lines(write_rheocompass_export(tmp_path / "r.txt", replace(RUN, setup_interval=False),
                                           project="P", test="T", sample="S"))

    def kind(line: str) -> str:
        if not line:
            return "blank"
        if line.strip("\t") == "":
            return "tabs"
        if line.startswith("\t\t["):
            return "units"
        if line.startswith("\t"):
            return "data"
        return line.split("\t")[0]

    assert [kind(x) for x in ours[:11]] == [kind(x) for x in real_lines[:11]]
    # each row has as many cells as the header row
    width = len(real_lines[7].split("\t"))
    assert all(len(x.split("\t")) == width for x in real_lines[8:])
    width = len(ours[7].split("\t"))
    assert all(len(x.split("\t")) == width for x in ours[8:])


def test_french_export_has_french_labels_and_decimal_commas(tmp_path: Path) -> None:
    path = write_rheocompass_export(tmp_path / "fr.csv", RUN, project="P", test="T",
                                    sample="S", language="fr")
    lines = _lines(path)
    assert lines[0] == "Projet:\tP"
    assert lines[4] == "Résultat:\tS 1"
    assert lines[6] == "Intervalle et points de données:\t1\t200"
    assert lines[7].startswith("Interval données:\tPoint No.\tTemps\tCouple\tForce Normale")
    row = lines[10].split("\t")
    assert all("." not in cell for cell in row)
    assert "," in row[2]
    english = _lines(write_rheocompass_export(tmp_path / "en.csv", RUN, project="P",
                                              test="T", sample="S"))
    assert [c.replace(",", ".") for c in row] == english[10].split("\t")


def test_written_numbers_are_the_generated_ones(tmp_path: Path) -> None:
    lines = _lines(write_rheocompass_export(tmp_path / "n.csv", RUN, project="P", test="T",
                                            sample="S"))
    start = lines.index("Interval and data points:\t2\t3000") + 4
    table = np.array([[float(c) for c in line.split("\t")[1:8]] for line in lines[start:]])
    friction = make_intervals(RUN)[1]
    np.testing.assert_allclose(table[:, 1], friction["time_s"], atol=0.005)
    np.testing.assert_allclose(table[:, 2] / 1e3, friction["torque_Nm"], atol=1e-8)
    np.testing.assert_allclose(table[:, 3], friction["normal_force_N"], atol=5e-5)
    np.testing.assert_allclose(table[:, 4] / 1e3, friction["angle_rad"], atol=1e-7)
    np.testing.assert_allclose(table[:, 5] * 2 * math.pi / 60, friction["speed_rad_s"],
                               atol=1e-7)


def test_unknown_language_is_refused() -> None:
    with pytest.raises(ValueError, match="language"):
        rheocompass_text(RUN, project="P", test="T", sample="S", language="de")


# --------------------------------------------------------------------------- end to end


@pytest.mark.parametrize("language", ["en", "fr"])
@pytest.mark.parametrize(
    "run",
    [
        SyntheticRun(mu_s=0.85, mu_k=0.6, noise=0.008, torque_offset_Nm=4e-4,
                     normal_force_N=1.0, seed=71),
        SyntheticRun(shape="stick_slip", mu_s=1.1, mu_k=0.8, noise=0.015, seed=72,
                     direction=-1),
        SyntheticRun(shape="no_overshoot", mu_k=0.45, noise=0.003, setup_interval=False,
                     torque_offset_Nm=-2e-4, seed=73),
    ],
    ids=["overshoot-offset", "stick-slip-reverse", "no-overshoot-no-setup"],
)
def test_export_read_select_reduce_gives_the_truth(
    tmp_path: Path, run: SyntheticRun, language: str
) -> None:
    readers = pytest.importorskip("tribopipe.readers")
    path = write_rheocompass_export(tmp_path / "run.csv", run, project="E2E", test="T",
                                    sample="S", language=language)
    items = readers.read_export(path)
    assert len(items) == (2 if run.setup_interval else 1)
    picked = select_friction_interval(items)
    got = reduce_measurement(picked, InstrumentConfig(), ReductionParams())
    want = truth(run)
    assert got.mu_k == pytest.approx(want.mu_k, abs=0.01)
    if want.static_distinct:
        assert got.mu_s == pytest.approx(want.mu_s, abs=0.02)
        assert "static_not_distinct" not in got.flags
    else:
        assert "static_not_distinct" in got.flags
    assert ("stick_slip" in got.flags) == want.stick_slip
    assert got.temperature_C == pytest.approx(run.temperature_C, abs=0.05)
    assert got.pressure_kPa == pytest.approx(11.789 * run.normal_force_N, rel=0.01)
    assert got.sliding_distance_mm == pytest.approx(want.sliding_distance_mm, abs=0.002)


@settings(max_examples=10, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    language=st.sampled_from(["en", "fr"]),
    direction=st.sampled_from([-1, 1]),
    setup=st.booleans(),
)
def test_what_is_written_reads_back_as_the_generated_si_data(
    tmp_path_factory: pytest.TempPathFactory, seed: int, language: str, direction: int,
    setup: bool,
) -> None:
    readers = pytest.importorskip("tribopipe.readers")
    run = SyntheticRun(seed=seed, direction=direction, setup_interval=setup, duration_s=60.0)
    path = tmp_path_factory.mktemp("rt") / "run.csv"
    write_rheocompass_export(path, run, project="P", test="T", sample="S", language=language)
    items = readers.read_export(path)
    frames = make_intervals(run)
    assert len(items) == len(frames)
    # the written precision: 0.01 s, 1e-5 mN·m, 1e-4 N, 1e-4 mrad, 1e-6 rpm, 0.01 °C
    tolerance = {"time_s": 0.006, "torque_Nm": 6e-9, "normal_force_N": 6e-5,
                 "angle_rad": 6e-8, "speed_rad_s": 1e-7, "temperature_C": 0.006}
    for measurement, frame in zip(items, frames, strict=True):
        for column, atol in tolerance.items():
            np.testing.assert_allclose(measurement.data[column], frame[column], atol=atol,
                                       err_msg=column)


def test_a_cliff_run_rises_linearly_and_slips_within_0_01_mm() -> None:
    run = SyntheticRun(shape="cliff", mu_s=0.9, mu_k=0.6, seed=4)
    want = run.truth()
    s_pk = want.mu_s_distance_mm
    s = np.array([0.5 * s_pk, s_pk, s_pk + 0.01, s_pk + 0.2])
    mu = mu_curve(run, s)
    assert mu[0] == pytest.approx(0.45)  # half way up a linear rise
    assert mu[1] == pytest.approx(0.9)
    assert mu[2] < 0.6 + 0.3 * np.exp(-1)  # most of the drop within 0.01 mm
    assert mu[3] == pytest.approx(0.6, abs=1e-6)
    assert want.static_distinct and not want.stick_slip


def test_a_session_export_is_its_tests_one_after_the_other(tmp_path: Path) -> None:
    """Several tests in one file, as RheoCompass exports a session and as the real two-test
    export lays it out: one Project line, each test's Test/Result block with its intervals
    numbered from 1, a blank line between tests. One test alone is the plain export."""
    from generators.synthetic import (
        SyntheticTest,
        rheocompass_session_text,
        write_rheocompass_session,
    )
    from tribopipe.readers import read_export

    one = replace(RUN, duration_s=20.0)
    steps = (replace(RUN, duration_s=20.0, seed=6),
             replace(RUN, duration_s=20.0, seed=7, setup_interval=False))
    tests = [SyntheticTest("A", "pin", (one,)), SyntheticTest("B", "pin", steps)]
    assert rheocompass_session_text(tests[:1], project="P") == rheocompass_text(
        one, project="P", test="A", sample="pin")
    path = write_rheocompass_session(tmp_path / "s.csv", tests, project="P")
    lines = _lines(path)
    b = lines.index("Test:\tB")
    assert lines[b - 1] == "" and lines[b + 2] == "Result:\tpin 1"
    assert lines[b + 4] == "Interval and data points:\t1\t200"
    assert [(m.meta.test, m.meta.interval, len(m.data)) for m in read_export(path)] == [
        ("A", 1, 200), ("A", 2, 200), ("B", 1, 200), ("B", 2, 200), ("B", 3, 200)]
    with pytest.raises(ValueError, match="at least one"):
        SyntheticTest("empty", "pin", ())


def test_utf8_comma_export_reads_back_like_the_utf16_one(tmp_path: Path) -> None:
    """The writer's UTF-8 + BOM, comma-separated variant (as RheoCompass' comma export):
    same lines with commas, a cell holding a comma quoted; the reader finds the same
    tables in it as in the UTF-16/TAB save of the same run."""
    kw = {"project": "Bench, lab 2", "test": "T", "sample": "S"}
    tab = write_rheocompass_export(tmp_path / "tab.csv", RUN, **kw)
    comma = write_rheocompass_export(tmp_path / "comma.csv", RUN, encoding="utf-8",
                                     delimiter=",", **kw)
    raw = comma.read_bytes()
    assert raw[:3] == b"\xef\xbb\xbf"
    lines = raw[3:].decode("utf-8").split("\r\n")
    assert lines[0] == 'Project:,"Bench, lab 2"'
    assert lines[10].split(",") == _lines(tab)[10].split("\t")
    ours, theirs = read_export(comma), read_export(tab)
    assert len(ours) == len(theirs) == 2
    for a, b in zip(ours, theirs, strict=True):
        pd.testing.assert_frame_equal(a.data, b.data)
    with pytest.raises(ValueError, match="language='en'"):
        write_rheocompass_export(tmp_path / "x.csv", RUN, language="fr", delimiter=",", **kw)
    with pytest.raises(ValueError, match="encoding"):
        write_rheocompass_export(tmp_path / "x.csv", RUN, encoding="latin-1", **kw)
    # a session export too
    from generators.synthetic import SyntheticTest, write_rheocompass_session

    tests = [SyntheticTest("A", "S", (RUN,)), SyntheticTest("B", "S", (replace(RUN, seed=9),))]
    session = write_rheocompass_session(tmp_path / "s.csv", tests, project="P",
                                        encoding="utf-8", delimiter=",")
    assert [m.meta.test for m in read_export(session)] == ["A", "A", "B", "B"]

"""μ_S / μ_K detection validated on seeded synthetic runs with known truth.

The acceptance criterion of the issue: μ_K within ±0.01 and a distinct μ_S within ±0.02
across shapes (overshoot, no overshoot, stick-slip, slow drift), noise 0.003–0.015, torque
offset and set-up interval; the right flags raised, and none on clean runs. Bad input
gives one clear ``ReductionError`` naming the measurement, never a NaN μ.
"""

from __future__ import annotations

import itertools
import json
import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from generators.synthetic import SyntheticRun, make_intervals, truth
from tribopipe.config import InstrumentConfig, ReductionParams, settings_from_dict
from tribopipe.errors import ConfigError, MissingQuantityError, ReductionError
from tribopipe.measurement import Measurement, MeasurementMeta
from tribopipe.reduction.intervals import select_friction_interval
from tribopipe.reduction.reduce import FLAGS, ReductionResult, reduce_measurement

INSTRUMENT = InstrumentConfig()
PARAMS = ReductionParams()
TRACE_COLUMNS = [
    "time_s", "sliding_distance_mm", "normal_force_N", "pressure_kPa",
    "friction_force_N", "mu", "mu_smooth", "in_contact",
]


def measurements(run: SyntheticRun, name: str = "run.csv") -> list[Measurement]:
    """The run's intervals as the readers would hand them over."""
    return [
        Measurement(
            frame,
            MeasurementMeta(source_file=name, file_format="synthetic", test="Friction",
                            result="Friction 1", interval=i),
        )
        for i, frame in enumerate(make_intervals(run), start=1)
    ]


def reduce_run(run: SyntheticRun, params: ReductionParams = PARAMS) -> ReductionResult:
    return reduce_measurement(select_friction_interval(measurements(run)), INSTRUMENT, params)


def friction_only(run: SyntheticRun, **changes: object) -> Measurement:
    """The friction interval of ``run`` with columns changed (None drops a column)."""
    frame = make_intervals(run)[-1]
    for column, value in changes.items():
        if value is None:
            frame = frame.drop(columns=[column])
        else:
            frame = frame.assign(**{column: value})
    return Measurement(frame, MeasurementMeta(source_file="bad.csv", file_format="synthetic",
                                              test="Friction", interval=2))


# --------------------------------------------------------------------------- validation grid

GRID = list(
    itertools.product(
        ("overshoot", "no_overshoot", "stick_slip", "drift"),
        (0.003, 0.008, 0.015),
        ((0.80, 0.55), (1.20, 0.95)),
        (0.0, 5e-4),  # torque zero offset [N·m]: 0.5 mN·m is 0.04 in μ at 1 N
        (True, False),
    )
)


@pytest.mark.parametrize(("shape", "noise", "mus", "offset", "setup"), GRID)
def test_known_truth_across_the_grid(
    shape: str, noise: float, mus: tuple[float, float], offset: float, setup: bool
) -> None:
    seed = GRID.index((shape, noise, mus, offset, setup))
    run = SyntheticRun(mu_s=mus[0], mu_k=mus[1], shape=shape, noise=noise,
                       torque_offset_Nm=offset, setup_interval=setup, normal_force_N=1.0,
                       seed=seed)
    want = truth(run)
    got = reduce_run(run)
    assert got.mu_k == pytest.approx(want.mu_k, abs=0.01)
    expected_flags = set()
    if want.static_distinct:
        assert got.mu_s == pytest.approx(want.mu_s, abs=0.02)
    else:
        expected_flags.add("static_not_distinct")
    if want.stick_slip:
        expected_flags.add("stick_slip")
    assert set(got.flags) == expected_flags
    assert got.mu_s >= got.mu_k


def test_the_offset_is_found_in_the_set_up_interval() -> None:
    run = SyntheticRun(torque_offset_Nm=4e-4, noise=0.003, seed=3)
    got = reduce_run(run)
    assert got.parameters.torque_offset_source.startswith("set-up interval")
    assert got.parameters.torque_offset_Nm == pytest.approx(4e-4, abs=2e-5)


def test_without_set_up_the_offset_comes_from_the_rest_before_motion() -> None:
    run = SyntheticRun(torque_offset_Nm=4e-4, setup_interval=False, rest_s=3.0, seed=4)
    got = reduce_run(run)
    assert got.parameters.torque_offset_source.startswith("at-rest start")
    assert got.parameters.torque_offset_Nm == pytest.approx(4e-4, abs=5e-5)
    assert got.mu_k == pytest.approx(run.mu_k, abs=0.01)


def test_a_set_up_of_one_sample_gives_the_offset_but_not_a_false_precision() -> None:
    """One at-rest sample is a zero with no scatter to judge it by: the offset is used, and
    its uncertainty is the unknown offset's (b/√3), not 0."""
    run = SyntheticRun(torque_offset_Nm=4e-4, noise=0.003, seed=3)
    items = measurements(run)
    items[0] = Measurement(items[0].data.iloc[:1].reset_index(drop=True), items[0].meta)
    one = reduce_measurement(select_friction_interval(items), INSTRUMENT, PARAMS)
    full = reduce_run(run)
    assert one.parameters.torque_offset_source.startswith("set-up interval 1 (too few")
    u_one = one.parameters.uncertainty.torque_offset_u_Nm
    assert u_one == pytest.approx(INSTRUMENT.torque_offset_unknown_Nm / math.sqrt(3))
    assert full.parameters.uncertainty.torque_offset_u_Nm < u_one / 10
    assert one.u_mu_k > full.u_mu_k


def test_an_offset_that_cannot_be_estimated_is_said_so() -> None:
    run = SyntheticRun(torque_offset_Nm=4e-4, setup_interval=False, rest_s=0.0,
                       normal_force_N=1.0, seed=5)
    got = reduce_run(run)
    assert got.parameters.torque_offset_source.startswith("not estimated")
    assert got.parameters.torque_offset_Nm == 0.0
    # the offset stays in μ: 0.4 mN·m / 13.37 mm / 1 N = 0.030
    assert got.mu_k - run.mu_k == pytest.approx(0.030, abs=0.01)
    # ... and giving it explicitly removes it
    fixed = reduce_measurement(select_friction_interval(measurements(run)), INSTRUMENT,
                               PARAMS, torque_offset_Nm=4e-4)
    assert fixed.parameters.torque_offset_source == "given"
    assert fixed.mu_k == pytest.approx(run.mu_k, abs=0.01)


# --------------------------------------------------------------------------- flags


def test_stick_slip_is_flagged_and_its_mean_is_mu_k() -> None:
    run = SyntheticRun(shape="stick_slip", mu_s=0.9, mu_k=0.6, noise=0.008, seed=11)
    got = reduce_run(run)
    assert "stick_slip" in got.flags
    assert got.mu_k == pytest.approx(0.6, abs=0.01)
    assert got.plateau_std > 0.02  # the saw-tooth, not the noise


def test_no_overshoot_reports_mu_s_equal_to_mu_k() -> None:
    got = reduce_run(SyntheticRun(shape="no_overshoot", mu_k=0.7, noise=0.015, seed=12))
    assert got.flags == ("static_not_distinct",)
    assert got.mu_s == got.mu_k
    assert got.parameters.mu_s_peak_raw >= got.mu_k - 0.02


def test_a_short_trace_is_flagged() -> None:
    got = reduce_run(SyntheticRun(duration_s=60.0, seed=13))  # 0.4 mm of sliding
    assert "short_trace" in got.flags
    assert math.isfinite(got.mu_k) and math.isfinite(got.mu_s)


def test_an_unstable_normal_force_is_flagged() -> None:
    got = reduce_run(SyntheticRun(normal_force_wobble=0.15, seed=14))
    assert "normal_force_unstable" in got.flags
    assert got.parameters.normal_force_cv > PARAMS.normal_force_cv_max
    assert got.mu_k == pytest.approx(0.55, abs=0.01)


def test_a_run_that_keeps_drifting_has_no_steady_state() -> None:
    got = reduce_run(SyntheticRun(drift_per_mm=0.08, noise=0.005, seed=15))
    assert "no_steady_state" in got.flags
    assert got.plateau_drift_per_mm == pytest.approx(0.08, abs=0.01)


def test_a_slow_transient_that_does_not_settle_in_time_has_no_steady_state() -> None:
    run = SyntheticRun(shape="drift", mu_s=1.0, mu_k=0.6, duration_s=150.0, seed=16)
    assert "no_steady_state" in reduce_run(run).flags


def test_flags_are_known_names_in_a_fixed_order() -> None:
    got = reduce_run(SyntheticRun(shape="no_overshoot", duration_s=60.0, seed=17))
    assert set(got.flags) <= set(FLAGS)
    assert list(got.flags) == [f for f in FLAGS if f in got.flags]


# --------------------------------------------------------------------------- evidence


def test_the_result_carries_its_evidence() -> None:
    run = SyntheticRun(mu_s=0.85, mu_k=0.6, noise=0.005, temperature_C=10.0, seed=21)
    want = truth(run)
    got = reduce_run(run)
    trace = got.trace
    assert list(trace.columns) == TRACE_COLUMNS
    assert trace["in_contact"].dtype == bool
    # μ_K is the mean of the trace's μ over the reported window
    lo, hi = got.mu_k_window_mm
    inside = trace["sliding_distance_mm"].between(lo, hi) & trace["in_contact"]
    assert trace.loc[inside, "mu"].mean() == pytest.approx(got.mu_k, abs=1e-3)
    t_lo, t_hi = got.mu_k_window_s
    assert trace["time_s"].iloc[0] <= t_lo < t_hi <= trace["time_s"].iloc[-1]
    assert PARAMS.run_in_mm <= lo < hi <= got.sliding_distance_mm + 1e-9
    assert hi - lo >= PARAMS.plateau_min_mm
    # μ_S where the peak was put, and when
    assert got.mu_s_distance_mm == pytest.approx(want.mu_s_distance_mm, abs=0.02)
    assert got.mu_s_time_s == pytest.approx(
        run.rest_s + got.mu_s_distance_mm / got.sliding_speed_mm_s, abs=0.2
    )
    assert got.normal_force_mean_N == pytest.approx(3.0, abs=0.01)
    assert got.pressure_kPa == pytest.approx(35.37, abs=0.05)
    assert got.temperature_C == pytest.approx(10.0, abs=0.05)
    assert got.sliding_speed_mm_s == pytest.approx(0.0070, abs=1e-4)
    assert got.sliding_distance_mm == pytest.approx(want.sliding_distance_mm, abs=0.002)
    assert got.plateau_std == pytest.approx(0.005, abs=0.002)
    assert abs(got.plateau_drift_per_mm) < PARAMS.max_drift_per_mm
    assert got.method.startswith("tribopipe-v2")
    assert got.parameters.distance_source == "angle"
    assert got.parameters.settings.run_in_mm == PARAMS.run_in_mm
    json.dumps(got.parameters.to_json())  # provenance must be storable as JSON


def test_the_trace_round_trips_through_parquet(tmp_path) -> None:
    got = reduce_run(SyntheticRun(seed=22))
    path = tmp_path / "trace.parquet"
    got.trace.to_parquet(path, index=False)
    back = pd.read_parquet(path)
    pd.testing.assert_frame_equal(back, got.trace)


def test_out_of_contact_samples_are_masked() -> None:
    run = SyntheticRun(seed=23)
    frame = make_intervals(run)[-1]
    force = frame["normal_force_N"].to_numpy().copy()
    force[1000:1100] = 0.05  # the pins lift off for 10 s
    m = Measurement(frame.assign(normal_force_N=force),
                    MeasurementMeta(source_file="lift.csv", file_format="synthetic"))
    got = reduce_measurement(m, INSTRUMENT, PARAMS)
    lifted = got.trace.iloc[1000:1100]
    assert not lifted["in_contact"].any()
    assert lifted["mu"].isna().all()
    assert got.mu_k == pytest.approx(run.mu_k, abs=0.01)


@pytest.mark.parametrize(
    "change",
    [
        {"angle_rad": None},  # distance from the integrated speed
        {"angle_rad": None, "speed_rad_s": None},  # nominal speed × time
    ],
)
def test_distance_without_angle(change: dict) -> None:
    run = SyntheticRun(rest_s=0.0, seed=24)
    got = reduce_measurement(friction_only(run, **change), INSTRUMENT, PARAMS)
    assert got.parameters.distance_source == ("speed" if len(change) == 1 else "nominal")
    assert got.mu_k == pytest.approx(run.mu_k, abs=0.01)
    assert got.sliding_distance_mm == pytest.approx(truth(run).sliding_distance_mm, abs=0.01)


def test_reverse_rotation_and_negative_normal_force_give_the_same_numbers() -> None:
    run = SyntheticRun(seed=25, torque_offset_Nm=2e-4)
    forward = reduce_run(run)
    reverse = reduce_run(replace(run, direction=-1))
    # same friction, the noise draws add rather than flip: equal within the noise
    assert reverse.mu_k == pytest.approx(forward.mu_k, abs=0.003)
    assert reverse.parameters.torque_sign == -1.0
    frames = make_intervals(run)
    flipped = [
        Measurement(f.assign(normal_force_N=-f["normal_force_N"]),
                    MeasurementMeta("neg.csv", "synthetic", test="T", result="R", interval=i))
        for i, f in enumerate(frames, start=1)
    ]
    negative = reduce_measurement(select_friction_interval(flipped), INSTRUMENT, PARAMS)
    assert negative.mu_k == pytest.approx(forward.mu_k, abs=1e-9)
    assert negative.normal_force_mean_N > 0


# --------------------------------------------------------------------------- bad input


def test_zero_normal_force_is_one_clear_error() -> None:
    run = SyntheticRun(seed=31)
    m = friction_only(run, normal_force_N=np.zeros(3000))
    with pytest.raises(ReductionError) as err:
        reduce_measurement(m, INSTRUMENT, PARAMS)
    message = str(err.value)
    assert "bad.csv" in message and "interval 2" in message
    assert "contact threshold" in message and "\n" not in message


@pytest.mark.parametrize("column", ["torque_Nm", "normal_force_N"])
def test_more_than_half_missing_is_an_error(column: str) -> None:
    run = SyntheticRun(seed=32)
    values = make_intervals(run)[-1][column].to_numpy().copy()
    values[::3] = np.nan
    values[1::3] = np.nan
    with pytest.raises(ReductionError, match=f"bad.csv.*2000 of 3000 {column} values"):
        reduce_measurement(friction_only(run, **{column: values}), INSTRUMENT, PARAMS)


def test_a_few_missing_values_are_dropped_and_counted() -> None:
    run = SyntheticRun(seed=33)
    torque = make_intervals(run)[-1]["torque_Nm"].to_numpy().copy()
    torque[500:520] = np.nan
    got = reduce_measurement(friction_only(run, torque_Nm=torque), INSTRUMENT, PARAMS)
    assert got.parameters.n_dropped_incomplete == 20
    assert got.mu_k == pytest.approx(run.mu_k, abs=0.01)


def test_no_rotation_is_an_error_in_select_and_in_reduce() -> None:
    run = SyntheticRun(seed=34)
    still = [
        Measurement(f.assign(angle_rad=0.0, speed_rad_s=0.0),
                    MeasurementMeta("still.csv", "synthetic", test="T", interval=i))
        for i, f in enumerate(make_intervals(run), start=1)
    ]
    with pytest.raises(ReductionError, match="still.csv: no rotation in any of the 2"):
        select_friction_interval(still)
    with pytest.raises(ReductionError, match=r"still.csv \[T / interval 2\]: no rotation"):
        reduce_measurement(still[1], INSTRUMENT, PARAMS)


def test_too_few_samples_is_an_error() -> None:
    frame = make_intervals(SyntheticRun(seed=35))[-1].iloc[100:110]
    m = Measurement(frame, MeasurementMeta("tiny.csv", "synthetic", interval=1))
    with pytest.raises(ReductionError, match="tiny.csv.*only 10 complete samples"):
        reduce_measurement(m, INSTRUMENT, PARAMS)


def test_a_missing_torque_column_names_what_was_found() -> None:
    m = friction_only(SyntheticRun(seed=36), torque_Nm=None)
    with pytest.raises(MissingQuantityError, match="torque_Nm") as err:
        reduce_measurement(m, INSTRUMENT, PARAMS)
    assert "bad.csv" in str(err.value) and "normal_force_N" in str(err.value)


# --------------------------------------------------------------------------- purity


def test_no_reduction_function_mutates_its_inputs() -> None:
    """astropy/pybaselines style: every input array is read-only; nothing may write."""
    from tribopipe import physics
    from tribopipe.reduction import detection as d
    from tribopipe.reduction import intervals

    frames = []
    for frame in make_intervals(SyntheticRun(torque_offset_Nm=2e-4, seed=51)):
        columns = {}
        for name in frame.columns:
            values = frame[name].to_numpy().copy()
            values.flags.writeable = False
            columns[name] = values
        frames.append(pd.DataFrame(columns, copy=False))
    snapshot = [f.copy(deep=True) for f in frames]
    items = [Measurement(f, MeasurementMeta("ro.csv", "synthetic", test="T", interval=i))
             for i, f in enumerate(frames, start=1)]
    picked = select_friction_interval(items)
    result = reduce_measurement(picked, INSTRUMENT, PARAMS)

    t = frames[1]["time_s"].to_numpy()
    mu = result.trace["mu"].to_numpy()[100:].copy()
    mu.flags.writeable = False
    angle = frames[1]["angle_rad"].to_numpy()
    speed = frames[1]["speed_rad_s"].to_numpy()
    force = frames[1]["normal_force_N"].to_numpy()
    torque = frames[1]["torque_Nm"].to_numpy()
    physics.contact_pressure_kPa(force, 3, 3.0)
    physics.friction_force_N(torque, 13.37)
    physics.coefficient_of_friction(torque, force)
    physics.rpm_to_rad_s(speed)
    physics.distance_from_angle_mm(angle, 13.37)
    physics.distance_from_speed_mm(t, speed, 13.37)
    physics.distance_from_nominal_mm(t, 0.005, 13.37)
    s, _ = physics.sliding_distance_mm(t, 13.37, angle_rad=angle, speed_rad_s=speed)
    s.flags.writeable = False
    d.noise_std(mu)
    d.median_smooth(mu, 5)
    d.peak_smooth(mu, 29)
    d.static_peak_curve(mu, 29)
    d.linear_slope(s[100:], mu)
    d.find_plateau_start(s[100:], mu, 0.25, 0.005, PARAMS)
    d.stick_slip_test(s[100:], mu, PARAMS)
    d.cliff_peak_curve(mu, d.static_peak_curve(mu, 29), 63, 0.005, 4.0)
    intervals.leading_rest(s, 1e-3)
    intervals.estimate_torque_offset_Nm(torque, intervals.leading_rest(s, 1e-3), 5)
    intervals.setup_torque_offset_Nm(items[0])
    intervals.robust_mean(torque)
    for before, after in zip(snapshot, frames, strict=True):
        pd.testing.assert_frame_equal(before, after)


# --------------------------------------------------------------------------- properties


@settings(max_examples=15, deadline=None)
@given(
    offset=st.floats(-1e-3, 1e-3),
    scale=st.floats(0.3, 3.0),
    seed=st.integers(0, 10_000),
)
def test_mu_does_not_depend_on_offset_or_load_scale(offset: float, scale: float,
                                                    seed: int) -> None:
    """Adding a torque offset (seen in the set-up) or scaling torque and normal force
    together changes nothing in μ."""
    run = SyntheticRun(seed=seed, noise=0.008)
    base = reduce_run(run)
    frames = [f.assign(torque_Nm=f["torque_Nm"] * scale + offset,
                       normal_force_N=f["normal_force_N"] * scale)
              for f in make_intervals(run)]
    items = [Measurement(f, MeasurementMeta("p.csv", "synthetic", test="T", interval=i))
             for i, f in enumerate(frames, start=1)]
    other = reduce_measurement(select_friction_interval(items), INSTRUMENT,
                               replace(PARAMS))
    assert other.mu_k == pytest.approx(base.mu_k, abs=1e-6)
    assert other.mu_s == pytest.approx(base.mu_s, abs=1e-6)
    assert other.flags == base.flags


@settings(max_examples=20, deadline=None)
@given(
    shape=st.sampled_from(["overshoot", "no_overshoot", "stick_slip", "drift"]),
    noise=st.floats(0.0, 0.03),
    duration=st.floats(30.0, 400.0),
    seed=st.integers(0, 10_000),
)
def test_any_run_gives_finite_numbers_and_consistent_windows(
    shape: str, noise: float, duration: float, seed: int
) -> None:
    got = reduce_run(SyntheticRun(shape=shape, noise=noise, duration_s=duration, seed=seed))
    for value in (got.mu_s, got.mu_k, got.plateau_std, got.plateau_drift_per_mm,
                  got.pressure_kPa, got.mu_s_distance_mm, got.mu_s_time_s):
        assert math.isfinite(value)
    assert got.mu_s >= got.mu_k
    lo, hi = got.mu_k_window_mm
    assert 0 <= lo <= hi <= got.sliding_distance_mm + 1e-9
    assert got.mu_k_window_s[0] <= got.mu_k_window_s[1]


# --------------------------------------------------------------------------- parameters


def test_reduction_params_come_from_the_config_table() -> None:
    s = settings_from_dict({"reduction": {"run_in_mm": 0.4, "median_window": 7}})
    assert s.reduction.run_in_mm == 0.4 and s.reduction.median_window == 7
    other = settings_from_dict({})
    assert s.config_hash != other.config_hash
    with pytest.raises(ConfigError, match="run_in_mn"):
        settings_from_dict({"reduction": {"run_in_mn": 0.4}})
    with pytest.raises(ConfigError, match="block_mm"):
        settings_from_dict({"reduction": {"block_mm": -1.0}})
    with pytest.raises(ConfigError, match="median_window"):
        ReductionParams(median_window=2.5)


def test_a_longer_run_in_moves_the_window() -> None:
    run = SyntheticRun(seed=61)
    late = reduce_run(run, replace(PARAMS, run_in_mm=1.0))
    assert late.mu_k_window_mm[0] >= 1.0
    assert late.parameters.settings.run_in_mm == 1.0
    assert late.mu_k == pytest.approx(run.mu_k, abs=0.01)

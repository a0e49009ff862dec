"""μ_S wherever the pins put it (issue 14): the static peak is the maximum before the
trace settles onto its plateau, from a stiff contact's 0.02 mm to a soft pin's 5 mm of
pre-sliding; no reading at a boundary passes silently; weak stick-slip is seen.

These runs use the development family (:mod:`generators.synthetic`, with its peak placed
where a pin would put it); the independent family is the benchmark's
(``bench/bench_validation.py``).
"""

from __future__ import annotations

from dataclasses import replace

import pytest

from generators.synthetic import SyntheticRun, make_intervals, truth
from tribopipe.config import InstrumentConfig, ReductionParams, settings_from_dict
from tribopipe.errors import ConfigError
from tribopipe.measurement import Measurement, MeasurementMeta
from tribopipe.reduction.detection import settling_block_mm
from tribopipe.reduction.intervals import select_friction_interval
from tribopipe.reduction.reduce import ReductionResult, reduce_measurement

INSTRUMENT = InstrumentConfig()
PARAMS = ReductionParams()
SPEED_MM_S = INSTRUMENT.nominal_sliding_speed_mm_s


def reduce_run(run: SyntheticRun, params: ReductionParams = PARAMS) -> ReductionResult:
    items = [
        Measurement(frame, MeasurementMeta(source_file="run.csv", file_format="synthetic",
                                           test="Friction", result="Friction 1", interval=i))
        for i, frame in enumerate(make_intervals(run), start=1)
    ]
    return reduce_measurement(select_friction_interval(items), INSTRUMENT, params)


def lasting(peak_mm: float, after_mm: float) -> float:
    """Duration [s] of a run that slides ``after_mm`` beyond a peak at ``peak_mm``."""
    return (peak_mm + after_mm) / SPEED_MM_S + 2.0


@pytest.mark.parametrize("shape", ["overshoot", "cliff"])
@pytest.mark.parametrize("peak_mm", [0.02, 0.05, 0.6, 1.5, 3.0, 5.0])
def test_the_static_peak_is_found_wherever_the_pins_put_it(shape: str, peak_mm: float) -> None:
    run = SyntheticRun(shape=shape, mu_s=0.8, mu_k=0.55, noise=0.008, peak_distance_mm=peak_mm,
                       duration_s=lasting(peak_mm, 2.0), seed=int(peak_mm * 100))
    want = truth(run)
    got = reduce_run(run)
    assert got.mu_s == pytest.approx(want.mu_s, abs=0.02)
    # a rounded peak is flat at its top: where it is read is known to ~10 %
    assert got.mu_s_distance_mm == pytest.approx(peak_mm, abs=max(0.01, 0.1 * peak_mm))
    assert got.mu_k == pytest.approx(want.mu_k, abs=0.01)
    assert got.flags == ()
    # the plateau starts after the peak, found from the trace alone
    assert got.mu_k_window_mm[0] > peak_mm


def test_a_creep_to_the_plateau_has_no_static_peak() -> None:
    run = SyntheticRun(shape="no_overshoot", mu_k=0.7, noise=0.008, peak_distance_mm=1.5,
                       duration_s=lasting(1.5, 4.0), seed=3)
    got = reduce_run(run)
    assert got.flags == ("static_not_distinct",)
    assert got.mu_s == got.mu_k == pytest.approx(0.7, abs=0.01)


def test_a_search_cap_short_of_the_peak_reads_low_and_says_so() -> None:
    run = SyntheticRun(mu_s=0.8, mu_k=0.55, noise=0.005, peak_distance_mm=1.5,
                       duration_s=lasting(1.5, 2.0), seed=4)
    # a cap on the rising flank above the plateau: a distinct μ_S read low, flagged
    capped = reduce_run(run, replace(PARAMS, static_search_mm=1.2))
    assert "peak_at_search_limit" in capped.flags
    assert capped.mu_s_distance_mm == pytest.approx(1.2, abs=0.002)
    assert capped.mu_s < 0.8 - 0.02
    # a cap below the plateau's level: nothing distinct, and still the limit is named
    low = reduce_run(run, replace(PARAMS, static_search_mm=0.5))
    assert {"static_not_distinct", "peak_at_search_limit"} <= set(low.flags)
    assert low.parameters.mu_s_peak_distance_mm == pytest.approx(0.5, abs=0.002)
    assert "peak_at_search_limit" not in reduce_run(run).flags  # no cap: no limit


def test_a_trace_that_ends_on_the_rising_flank_is_flagged() -> None:
    run = SyntheticRun(mu_s=0.8, mu_k=0.55, noise=0.005, peak_distance_mm=3.0,
                       duration_s=lasting(2.8, 0.0), seed=5)
    got = reduce_run(run)
    assert {"no_steady_state", "plateau_at_trace_end"} <= set(got.flags)


def test_a_plateau_cut_short_by_the_end_of_the_trace_is_flagged() -> None:
    # settles about 0.2 mm after a peak at 1 mm; the trace ends 0.45 mm later
    run = SyntheticRun(mu_s=0.8, mu_k=0.55, noise=0.005, peak_distance_mm=1.0,
                       duration_s=lasting(1.0, 0.65), seed=6)
    got = reduce_run(run)
    lo, hi = got.mu_k_window_mm
    assert hi - lo < PARAMS.plateau_confirm_mm
    assert "plateau_at_trace_end" in got.flags
    assert got.mu_k == pytest.approx(0.55, abs=0.01)
    long = reduce_run(replace(run, duration_s=lasting(1.0, 2.0)))
    assert "plateau_at_trace_end" not in long.flags


@pytest.mark.parametrize(("amplitude", "noise"), [(0.01, 0.003), (0.02, 0.008), (0.03, 0.015)])
def test_weak_stick_slip_is_flagged(amplitude: float, noise: float) -> None:
    run = SyntheticRun(shape="stick_slip", mu_s=0.8, mu_k=0.55, noise=noise,
                       stick_slip_amplitude=amplitude, stick_slip_period_mm=0.06,
                       duration_s=600.0, seed=7)
    got = reduce_run(run)
    assert "stick_slip" in got.flags
    assert got.mu_k == pytest.approx(0.55, abs=0.01)
    assert got.parameters.stick_slip_period_mm == pytest.approx(0.06, rel=0.1)


@pytest.mark.parametrize("noise", [0.003, 0.015])
def test_a_steady_plateau_is_not_called_stick_slip(noise: float) -> None:
    for seed in range(5):
        got = reduce_run(SyntheticRun(noise=noise, duration_s=600.0, seed=100 + seed))
        assert "stick_slip" not in got.flags
        assert got.parameters.stick_slip_line_ratio < got.parameters.stick_slip_line_threshold


def test_settling_blocks_hold_whole_stick_slip_cycles() -> None:
    assert settling_block_mm(0.05, None) == 0.05
    assert settling_block_mm(0.05, 0.03) == pytest.approx(0.06)
    assert settling_block_mm(0.05, 0.2) == pytest.approx(0.2)
    assert settling_block_mm(0.05, 0.025) == pytest.approx(0.05)


def test_an_unknown_torque_offset_is_flagged_and_widens_the_uncertainty() -> None:
    run = SyntheticRun(torque_offset_Nm=4e-4, setup_interval=False, rest_s=0.0,
                       normal_force_N=1.0, seed=8)
    got = reduce_run(run)
    assert "torque_offset_unknown" in got.flags
    known = reduce_run(replace(run, rest_s=2.0))
    assert "torque_offset_unknown" not in known.flags
    assert got.u_mu_k > known.u_mu_k + 0.009
    # the 0.4 mN·m offset stays in μ (0.030 at 1 N), inside the expanded uncertainty
    assert abs(got.mu_k - run.mu_k) <= 2 * got.u_mu_k


@pytest.mark.parametrize("cap", [0, -1.0, float("nan"), True, "0.5"])
def test_a_search_cap_must_be_a_positive_distance(cap: object) -> None:
    with pytest.raises(ConfigError, match="static_search_mm"):
        ReductionParams(static_search_mm=cap)  # type: ignore[arg-type]


def test_the_cap_is_off_by_default_and_set_in_the_config() -> None:
    assert ReductionParams().static_search_mm is None
    settings = settings_from_dict({"reduction": {"static_search_mm": 2.0}})
    assert settings.reduction.static_search_mm == 2.0
    with pytest.raises(ConfigError, match="stick_slip_false_alarm"):
        settings_from_dict({"reduction": {"stick_slip_false_alarm": 1.5}})

"""The third family: rate-and-state friction on the pins' spring, recorded imperfectly.

The family must be what it claims: the Dieterich–Ruina law with ageing (steady state
μ0 + (a − b)·ln(v/V), a peak that grows with the log of the hold), stable sliding above
k_c = (b − a)/D_c and stick-slip below it, peaks where the grid puts them, creep without
a peak; the instrument's effects must be there (quantised torque, jitter, pink noise,
spikes, a wandering normal force); it must be reproducible and read back as written.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from generators.instrument import (
    add_spikes,
    coloured_noise,
    pink_noise,
    sample_times,
    significant_digits,
)
from generators.ratestate import (
    RateStateRun,
    build_run,
    force_ratio,
    make_intervals,
    oscillation_pp,
    peak_distance_mm,
    pin_stiffness_per_mm,
    radiation_damping_s_per_mm,
    ratestate_grid,
    simulate,
    truth,
    write_export,
)
from tribopipe.readers import read_export


def _run(**kw: object) -> RateStateRun:
    base = dict(shape="peak", mu0=0.5, a=0.01, b=0.015, dc_mm=0.005, k_per_mm=10.0,
                eta_s_per_mm=1e-3, hold_s=60.0, duration_s=120.0)
    base.update(kw)
    return RateStateRun(**base)  # type: ignore[arg-type]


def test_ecoflex_pins_are_a_soft_spring() -> None:
    # n·G·π r² / (h·F_N): three 6-mm Ecoflex 00-50 pins (25 kPa) at 1 N
    k = pin_stiffness_per_mm(1.0, 25.0)
    assert k == pytest.approx(3 * 25e-3 * math.pi * 9 / 6.0, rel=1e-12)
    assert 1 / k == pytest.approx(2.83, abs=0.01)  # the contact family's c_pin
    # shear-wave impedance √(Gρ)/2 per area: G back from k, ρ = 1100 kg/m³
    g_pa = 25e3
    area = 3 * math.pi * 9e-6
    assert radiation_damping_s_per_mm(k, 1.0) == pytest.approx(
        area * math.sqrt(g_pa * 1100) / 2 * 1e-3, rel=1e-9)


def test_steady_sliding_follows_the_rate_law() -> None:
    # stiff and stable: μ settles on μ0 at the drive speed, and the law's rate dependence
    # shows in the speed it slides at under a constant normal force
    run = _run(k_per_mm=50.0)
    sol = simulate(run, 60.0, wander=False)
    assert sol.mu[-1] == pytest.approx(run.mu0, abs=1e-4)
    assert sol.v[-1] == pytest.approx(run.speed_mm_s, rel=1e-3)


def test_the_static_peak_grows_with_the_log_of_the_hold() -> None:
    # Dieterich's healing: Δμ_peak ≈ b·ln(t_hold) for a stiff spring
    short, long_ = (_run(k_per_mm=200.0, hold_s=h) for h in (30.0, 300.0))
    gain = peak_distance_mm(long_)[1] - peak_distance_mm(short)[1]
    assert gain == pytest.approx(short.b * math.log(10.0), rel=0.25)


def test_stiffness_above_critical_slides_steadily_below_it_sticks_and_slips() -> None:
    gap, dc = 0.002, 0.005
    kc = gap / dc
    stable = _run(a=0.01, b=0.01 + gap, dc_mm=dc, k_per_mm=1.5 * kc, duration_s=400.0)
    sticky = replace(stable, k_per_mm=0.7 * kc)
    assert stable.critical_stiffness_per_mm == pytest.approx(kc)
    late = slice(-5000, None)
    calm = simulate(stable, 400.0, wander=False).mu[late]
    slips = simulate(sticky, 400.0, wander=False).mu[late]
    assert np.ptp(calm) < 1e-3
    # the ageing law's limit cycle: a peak-to-peak of about 15·(b − a)
    assert 8 * gap < np.ptp(slips) < 25 * gap


def test_creep_rises_onto_its_plateau_without_a_peak() -> None:
    run = build_run("creep", 0.4, index=500)
    sol = simulate(run, run.duration_s, wander=False)
    assert np.all(np.diff(sol.mu) >= -1e-9)
    want = truth(run)
    assert want.static == "none" and want.mu_s == want.mu_k


@pytest.mark.parametrize("peak_mm", [0.02, 0.4, 2.5])
def test_the_static_peak_sits_at_the_grid_distance(peak_mm: float) -> None:
    run = build_run("peak_weakening", peak_mm, index=222)
    x, _ = peak_distance_mm(run)
    assert x == pytest.approx(peak_mm, rel=0.05)
    assert run.k_per_mm > run.critical_stiffness_per_mm  # stable by construction


def test_weak_stick_slip_has_the_drawn_amplitude() -> None:
    run = build_run("stick_slip", 2.5, index=700)
    assert run.k_per_mm < run.critical_stiffness_per_mm
    assert 0.01 * 0.9 <= oscillation_pp(run) <= 0.05 * 1.1
    want = truth(run)
    assert want.oscillating == (want.oscillation_pp >= 0.008)


def test_the_normal_force_wanders_by_at_most_three_percent() -> None:
    run = _run(force_wander=0.03, force_period_s=300.0)
    t = np.linspace(0, 2000, 20001)
    n, dn = force_ratio(run, t)
    assert np.max(np.abs(n - 1)) <= 0.03 + 1e-12
    assert np.allclose(dn[1:-1], np.gradient(n, t)[1:-1], atol=1e-6)


def test_instrument_effects() -> None:
    rng = np.random.default_rng(1)
    # RheoCompass writes five significant digits
    assert significant_digits(np.array([0.0570871, 132.3456, 0.0]), 5).tolist() == [
        0.057087, 132.35, 0.0]
    # pink noise: power falls as 1/f (slope −1 in log-log)
    x = pink_noise(rng, 2**15)
    f = np.fft.rfftfreq(x.size)[1:]
    p = np.abs(np.fft.rfft(x))[1:] ** 2
    slope = np.polyfit(np.log(f), np.log(p), 1)[0]
    assert -1.2 < slope < -0.8 and np.std(x) == pytest.approx(1.0, abs=0.3)
    assert np.std(coloured_noise(rng, 10000, "white")) == pytest.approx(1.0, abs=0.05)
    # jittered sample times stay ordered, at 10 Hz with the rate error
    t = sample_times(rng, 10.0, 100.0, rate_error=0.02, jitter_s=0.003)
    assert np.all(np.diff(t) > 0)
    assert np.median(np.diff(t)) == pytest.approx(0.102, abs=0.002)
    assert 0.002 < np.std(np.diff(t)) < 0.006
    spiked = add_spikes(np.zeros(1000), rng, 0.05, 100.0, 0.05, 0.3)
    assert 0 < np.count_nonzero(spiked) < 20 and np.all(np.abs(spiked) <= 0.3)


def test_the_recording_carries_the_instrument_effects() -> None:
    run = replace(build_run("peak", 0.15, index=100), noise_colour="pink", torque_digits=4,
                  spike_rate_hz=0.05, setup_interval=True)
    setup, friction = make_intervals(run)
    torque_mNm = np.abs(friction["torque_Nm"].to_numpy()) * 1e3
    big = torque_mNm[torque_mNm > 1.0]
    assert np.allclose(big, significant_digits(big, 4))
    steps = np.diff(friction["time_s"].to_numpy())
    assert np.std(steps) > 0.001  # jitter
    assert friction["normal_force_N"].max() > run.normal_force_N * (1 + run.force_wander * 0.5)


def test_the_grid_is_fixed_and_reproducible() -> None:
    grid = ratestate_grid()
    assert len(grid) == 3 * 7 * 30 + 5 * 42 + 4 * 14
    assert len({g.index for g in grid}) == len(grid)
    assert sum(g.set == "offset_unknown" for g in grid) == 56
    quick = ratestate_grid(1)
    assert set(quick) <= set(grid)
    point = next(g for g in grid if g.shape == "creep" and g.peak_mm == 0.15)
    a, b = point.build(), point.build()
    assert a == b
    for x, y in zip(make_intervals(a), make_intervals(b), strict=True):
        assert x.equals(y)


def test_offset_unknown_runs_have_no_set_up_and_no_rest() -> None:
    point = next(g for g in ratestate_grid(1) if g.set == "offset_unknown"
                 and g.shape == "creep")
    run = point.build()
    assert not run.setup_interval and run.rest_s == 0 and run.torque_offset_Nm != 0
    assert not truth(run).offset_estimable


def test_the_export_reads_back_as_generated(tmp_path) -> None:
    run = replace(build_run("creep", 0.05, index=640), duration_s=30.0, setup_interval=True)
    path = write_export(tmp_path / "run.csv", run, language="fr")
    read = read_export(path)
    frames = make_intervals(run)
    assert len(read) == len(frames) == 2
    for m, frame in zip(read, frames, strict=True):
        assert np.allclose(m.data["torque_Nm"], frame["torque_Nm"], atol=1e-8)
        assert np.allclose(m.data["angle_rad"], frame["angle_rad"], atol=1e-7)
        assert np.allclose(m.data["time_s"], frame["time_s"], atol=0.006)

"""The independent validation family: a pin–interface contact model with known truth.

The family must be what it claims (issue 14): a Dahl-type, elastic–plastic pre-sliding in
series with the pins' shear, peaks where the grid puts them (0.02–5 mm), sudden slips
where soft pins snap, creep without a peak, weak stick-slip of the stated amplitude; it
must be reproducible, and its exports must read back through the project's readers.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from generators.contact import (
    PEAK_DISTANCES_MM,
    ContactRun,
    build_run,
    integrate_interface,
    make_intervals,
    mu_curve,
    oscillation_pp,
    pin_compliance_mm,
    truth,
    validation_grid,
    write_export,
)
from tribopipe.readers import read_export


def test_ecoflex_pins_shear_millimetres_before_they_slide() -> None:
    # the estimate: h·τ/G with h = 6 mm, G ≈ 20–30 kPa, 1 N on three pins, μ ≈ 0.9
    c = pin_compliance_mm(1.0, 6.0, 25.0)
    assert c == pytest.approx(6.0 / (3 * 0.025 * math.pi * 9), rel=1e-12)
    assert 2.0 <= 0.9 * c <= 3.0
    # Dragon Skin 30 (G ≈ 0.2 MPa) at 9 N (106 kPa) and μ ≈ 0.3: about 1 mm
    assert 0.3 * pin_compliance_mm(9.0, 6.0, 200.0) == pytest.approx(0.95, abs=0.1)


def test_dahl_limit_is_an_exponential_creep_to_the_strength() -> None:
    run = ContactRun(shape="creep", mu_k=0.5, mu_s0=0.5, c_pin_mm=0.0, c_int_mm=0.1,
                     sharpness=1.0, weakening_mm=1.0)
    z, f, p = integrate_interface(run, p_max=0.5)
    ell = run.c_int_mm * run.mu_k
    assert np.allclose(f, 0.5 * (1 - np.exp(-z / ell)), atol=2e-3)
    assert np.all(np.diff(p) >= 0)


def test_a_sharp_flow_rule_yields_like_an_elastic_plastic_contact() -> None:
    run = ContactRun(shape="creep", mu_k=0.5, mu_s0=0.5, c_pin_mm=0.0, c_int_mm=0.1,
                     sharpness=30.0, weakening_mm=1.0)
    z, f, _ = integrate_interface(run, p_max=0.3)
    elastic = z < 0.8 * 0.05
    assert np.allclose(f[elastic], z[elastic] / run.c_int_mm, rtol=0.02)  # linear, then
    assert f[-1] == pytest.approx(0.5, abs=1e-3)  # flows at the strength


@pytest.mark.parametrize("peak_mm", PEAK_DISTANCES_MM)
def test_the_static_peak_sits_at_the_grid_distance(peak_mm: float) -> None:
    run = build_run("peak", peak_mm, 3.0, index=11)
    want = truth(run)
    assert want.static == "distinct"
    assert want.mu_s_distance_mm == pytest.approx(peak_mm, abs=max(0.002, 0.01 * peak_mm))
    ratio = want.mu_s / run.mu_k
    assert min(abs(ratio - r) for r in (1.15, 1.3, 1.5)) < 2e-3


def test_soft_pins_release_their_shear_in_a_sudden_slip() -> None:
    run = build_run("peak", 2.5, 12.0, index=4)
    x = np.arange(0.0, run.distance_mm, 0.0007)
    mu = mu_curve(run, x)
    drop = -np.diff(mu)
    assert drop.max() > 0.05  # a slip: μ falls by > 0.05 between two samples
    k = int(np.argmax(drop))
    # the force first eases off the peak along the contact's weakening, then the pins snap
    assert 0 <= x[k] - truth(run).mu_s_distance_mm < 0.05


def test_creep_rises_without_a_peak() -> None:
    for m in (1.0, 12.0):
        run = build_run("creep", 2.5, m, index=21)
        mu = mu_curve(run, np.arange(0.0, run.distance_mm, 0.0007))
        assert np.all(np.diff(mu) >= -1e-9)
        want = truth(run)
        assert want.static == "none" and want.mu_s == want.mu_k == run.mu_k


def test_a_run_in_settles_slowly_and_the_trace_covers_a_plateau_after_it() -> None:
    run = build_run("peak_run_in", 0.15, 3.0, index=30)
    want = truth(run)
    assert want.settle_mm > 0.5
    assert run.distance_mm - want.settle_mm == pytest.approx(1.0, abs=1e-3) or (
        run.distance_mm - want.settle_mm == pytest.approx(3.0, abs=1e-3)
    )
    mu = mu_curve(run, np.array([want.settle_mm, run.distance_mm]))
    assert np.all(np.abs(mu - run.mu_k) <= 0.0021)


def test_weak_stick_slip_has_the_drawn_amplitude_and_period() -> None:
    run = build_run("stick_slip", 1.0, 3.0, index=40)
    assert 0.01 <= oscillation_pp(run) <= 0.05 * 1.06
    want = truth(run)
    assert want.oscillating and want.oscillation_pp >= 0.008
    x = np.arange(want.settle_mm, run.distance_mm, 0.0007)
    mu = mu_curve(run, x) - want.mu_k
    spectrum = np.abs(np.fft.rfft(mu - mu.mean()))
    freq = np.fft.rfftfreq(mu.size, d=0.0007)
    period = 1.0 / freq[1 + int(np.argmax(spectrum[1:]))]
    assert period == pytest.approx(run.osc_period_mm, rel=0.15)


def test_a_truncated_run_ends_before_its_plateau() -> None:
    grid = [g for g in validation_grid(1) if g.set == "truncated"]
    run = grid[0].build()
    want = truth(run)
    assert want.truncated and run.distance_mm < want.settle_mm


def test_offset_unknown_runs_have_no_set_up_and_no_rest() -> None:
    grid = [g for g in validation_grid(1) if g.set == "offset_unknown"]
    run = grid[0].build()
    assert not run.setup_interval and run.rest_s == 0 and run.torque_offset_Nm != 0
    assert not truth(run).offset_estimable


def test_the_grid_is_fixed_and_reproducible() -> None:
    grid = validation_grid()
    assert len(grid) == 4 * 7 * 3 * 10 + 4 * 4 * 3 + 4 * 7 * 2
    assert len({g.index for g in grid}) == len(grid)
    quick = validation_grid(1)
    assert set(quick) <= set(grid)
    a, b = grid[5].build(), grid[5].build()
    assert a == b
    fa, fb = make_intervals(a), make_intervals(b)
    for x, y in zip(fa, fb, strict=True):
        assert x.equals(y)


def test_the_export_reads_back_as_generated(tmp_path) -> None:
    run = replace(build_run("peak", 0.4, 3.0, index=2), distance_mm=0.5, setup_interval=True)
    path = write_export(tmp_path / "run.csv", run, language="fr")
    read = read_export(path)
    frames = make_intervals(run)
    assert len(read) == len(frames) == 2
    for m, frame in zip(read, frames, strict=True):
        assert np.allclose(m.data["torque_Nm"], frame["torque_Nm"], atol=1e-8)
        assert np.allclose(m.data["angle_rad"], frame["angle_rad"], atol=1e-7)
        assert np.allclose(m.data["normal_force_N"], frame["normal_force_N"], atol=1e-4)

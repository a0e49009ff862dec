"""Transients the settling test must not take for settled sliding (found on the
rate-and-state family, ``bench/bench_ratestate.py``; each check here is built from the
physics of the trace, not from that family's runs).

A soft pin loads linearly until it slips: μ rises through the plateau's level up to the
static peak and falls back. Under noise that forces the settling test to lengthen its
blocks (correlated noise, a small normal force), one long block can hold the whole
ramp and its fall and average to the plateau's level.
"""

from __future__ import annotations

import numpy as np
import pytest

from tribopipe.config import InstrumentConfig, ReductionParams
from tribopipe.measurement import Measurement, MeasurementMeta
from tribopipe.reduction.detection import find_plateau_start
from tribopipe.reduction.reduce import reduce_measurement

INSTRUMENT = InstrumentConfig()
PARAMS = ReductionParams()
STEP_MM = INSTRUMENT.nominal_sliding_speed_mm_s / 10.0  # 10 Hz


def ramp_to_a_peak(peak_mm: float, mu_peak: float, mu_k: float, length_mm: float,
                   noise: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A soft pin's loading line from 0 up to ``mu_peak`` at ``peak_mm``, a sudden slip
    onto ``mu_k``, and steady sliding to ``length_mm``; white noise of ``noise``."""
    s = np.arange(0.0, length_mm, STEP_MM)
    mu = np.where(s <= peak_mm, mu_peak * s / peak_mm, mu_k)
    return s, mu + noise * np.random.default_rng(seed).standard_normal(s.size)


def test_a_loading_ramp_averaged_in_one_long_block_is_not_the_plateau() -> None:
    # a line from 0 to 0.985 at 0.4 mm averages to 0.80 over 0.25-0.40 mm: the block
    # that holds the ramp's last stretch is as high on average as the plateau
    s, mu = ramp_to_a_peak(0.40, 0.985, 0.80, 3.0, 0.004, seed=1)
    after = s >= PARAMS.run_in_mm
    # a per-sample noise of 0.03 (as correlated noise counts) lengthens the blocks 3×
    start, tol = find_plateau_start(s[after], mu[after], PARAMS.run_in_mm, 0.03, PARAMS)
    assert tol > PARAMS.settle_tol  # the lengthened test really ran
    assert start is not None
    assert start >= 0.40 - 1e-9  # not before the peak: the ramp is no plateau


def test_a_settled_trace_keeps_its_start_under_the_same_noise() -> None:
    # the refinement must not cut a plateau that was settled from the run-in on
    s = np.arange(0.0, 3.0, STEP_MM)
    mu = 0.8 + 0.004 * np.random.default_rng(2).standard_normal(s.size)
    after = s >= PARAMS.run_in_mm
    start, _ = find_plateau_start(s[after], mu[after], PARAMS.run_in_mm, 0.03, PARAMS)
    assert start == pytest.approx(PARAMS.run_in_mm, abs=1e-6)


def test_the_reduction_reads_the_peak_of_a_soft_pin_that_slips_after_the_run_in() -> None:
    # 1 N, torque noise that lengthens the settling blocks; the peak at 0.4 mm after a
    # linear loading: μ_S is the peak, the plateau starts after it
    s, mu = ramp_to_a_peak(0.40, 0.985, 0.80, 3.0, 0.0, seed=3)
    rng = np.random.default_rng(3)
    # correlated noise: white noise through a 20-sample moving average, 0.008 per sample
    white = rng.standard_normal(s.size + 19)
    noise = 0.008 * np.convolve(white, np.ones(20), "valid") / np.sqrt(20)
    R_m = INSTRUMENT.friction_radius_mm * 1e-3
    t = (np.arange(s.size) + 1) / 10.0
    frame = {
        "time_s": t,
        "torque_Nm": (mu + noise) * 1.0 * R_m,
        "normal_force_N": np.full(s.size, 1.0),
        "angle_rad": s / INSTRUMENT.friction_radius_mm,
    }
    import pandas as pd

    m = Measurement(pd.DataFrame(frame), MeasurementMeta(source_file="ramp.csv",
                                                         file_format="synthetic"))
    got = reduce_measurement(m, INSTRUMENT, PARAMS, torque_offset_Nm=0.0)
    assert got.mu_k_window_mm[0] >= 0.40 - 1e-9
    assert got.mu_s == pytest.approx(0.985, abs=0.02)
    assert got.mu_k == pytest.approx(0.80, abs=0.01)
    assert "static_not_distinct" not in got.flags

"""NumPy signal primitives of the reduction: the same numbers as SciPy's filters (where
SciPy is installed), and a periodic-line test that finds weak stick-slip in noise without
raising false alarms on white or coloured noise."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tribopipe.reduction.signals import (
    decreasing_root,
    gamma_q,
    line_threshold,
    periodic_line,
    power_law_trend,
    running_max,
    running_mean,
    running_median,
    savgol,
    taper_bin_correlation_sq,
    tukey,
    window_medians,
)

RNG = np.random.default_rng(7)
SERIES = [RNG.standard_normal(n).cumsum() * 0.01 + RNG.standard_normal(n) for n in (5, 21, 400)]


@pytest.mark.parametrize("v", SERIES)
@pytest.mark.parametrize("w", [3, 5, 21])
def test_running_filters_match_scipy(v: np.ndarray, w: int) -> None:
    ndimage = pytest.importorskip("scipy.ndimage")
    assert np.allclose(running_median(v, w), ndimage.median_filter(v, size=w, mode="nearest"),
                       rtol=0, atol=1e-15)
    assert np.allclose(running_mean(v, w), ndimage.uniform_filter1d(v, size=w, mode="nearest"),
                       rtol=0, atol=1e-12)
    assert np.array_equal(running_max(v, w),
                          ndimage.maximum_filter1d(v, size=w, mode="nearest"))
    trailing = ndimage.maximum_filter1d(v, size=w, mode="nearest", origin=(w - 1) // 2)
    assert np.array_equal(running_max(v, w, trailing=True), trailing)


@pytest.mark.parametrize("v", SERIES[1:])
@pytest.mark.parametrize("w", [5, 7, 21])
def test_savitzky_golay_matches_scipy(v: np.ndarray, w: int) -> None:
    signal = pytest.importorskip("scipy.signal")
    assert np.allclose(savgol(v, w, 2), signal.savgol_filter(v, w, 2, mode="interp"),
                       rtol=0, atol=1e-12)


def test_savitzky_golay_keeps_a_parabola_and_refuses_an_even_window() -> None:
    x = np.linspace(-1, 1, 101)
    assert np.allclose(savgol(3 * x**2 - x + 1, 21), 3 * x**2 - x + 1, atol=1e-12)
    with pytest.raises(ValueError, match="odd"):
        savgol(x, 20)


def test_no_primitive_modifies_its_input() -> None:
    v = SERIES[2].copy()
    v.setflags(write=False)
    for f in (lambda a: running_median(a, 3), lambda a: running_mean(a, 5),
              lambda a: running_max(a, 7), lambda a: savgol(a, 9),
              lambda a: periodic_line(a, min_cycles=4, max_period=100)):
        f(v)


def _sawtooth(n: int, period: float, amplitude: float) -> np.ndarray:
    return amplitude * (np.mod(np.arange(n) / period, 1.0) - 0.5)


def _ar1(rng: np.random.Generator, n: int, rho: float) -> np.ndarray:
    e = rng.standard_normal(n)
    for i in range(1, n):
        e[i] = rho * e[i - 1] + math.sqrt(1 - rho**2) * e[i]
    return e


def test_a_weak_stick_slip_stands_out_of_the_noise() -> None:
    rng = np.random.default_rng(1)
    n, sigma = 4000, 0.015
    mu = 0.5 + _sawtooth(n, 70.0, 0.02) + sigma * rng.standard_normal(n)
    line = periodic_line(mu, min_cycles=4, max_period=n / 4)
    assert line.ratio > line.threshold(1e-4)
    assert line.period == pytest.approx(70.0, rel=0.05)
    # the fundamental of a saw-tooth of peak-to-peak A has amplitude A/π: variance (A/π)²/2
    assert math.sqrt(line.variance) == pytest.approx(0.02 / math.pi / math.sqrt(2), rel=0.3)


def test_a_transient_at_the_start_is_not_a_line() -> None:
    # the tail of a decay left at the start of a plateau, in little noise
    rng = np.random.default_rng(3)
    n = 2600
    mu = 0.55 + 0.006 * np.exp(-np.arange(n) / 60.0) + 0.003 * rng.standard_normal(n)
    line = periodic_line(mu, min_cycles=4, max_period=n / 4)
    assert line.ratio < line.threshold(1e-4)


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.8])
def test_white_and_coloured_noise_rarely_pass_the_threshold(rho: float) -> None:
    rng = np.random.default_rng(2)
    passed = 0
    for _ in range(200):
        line = periodic_line(0.01 * _ar1(rng, 3000, rho), min_cycles=4, max_period=750)
        passed += line.ratio > line.threshold(1e-3)
    assert passed <= 2  # 1e-3 per series: 0.2 expected in 200


def _one_over_f(rng: np.random.Generator, n: int, beta: float = 1.0) -> np.ndarray:
    """Unit-variance noise of spectrum 1/f^β over a record twice as long as ``n`` (a
    drifting zero: power below the window's own length too), a random half of it kept."""
    m = 2 * n
    spectrum = np.fft.rfft(rng.standard_normal(m))
    f = np.fft.rfftfreq(m)
    f[0] = f[1]
    series = np.fft.irfft(spectrum / f ** (beta / 2), m)
    start = int(rng.integers(0, n))
    part = series[start : start + n]
    return part / np.std(part)


@pytest.mark.parametrize("beta", [0.5, 1.0, 1.5])
def test_a_drifting_zero_is_not_stick_slip(beta: float) -> None:
    # 1/f^β noise (a sensor's zero wandering) has no line, however much low-frequency
    # power it has; a level read as the median of ±48 bins lies far below the lowest
    # bins' own and made it pass for one (before the spectrum was flattened)
    rng = np.random.default_rng(11)
    passed = 0
    for _ in range(100):
        mu = 0.6 + 0.01 * _one_over_f(rng, 3000, beta)
        line = periodic_line(mu, min_cycles=4, max_period=750)
        passed += line.ratio > line.threshold(1e-3)
    assert passed <= 2  # 1e-3 per series: 0.1 expected in 100


def test_a_weak_stick_slip_stands_out_of_a_drifting_zero() -> None:
    # 0.02 peak-to-peak every 70 samples under pink noise of 0.008 (its power rises
    # tenfold towards the slowest candidates)
    rng = np.random.default_rng(12)
    n = 4000
    mu = 0.5 + _sawtooth(n, 70.0, 0.02) + 0.008 * _one_over_f(rng, n)
    line = periodic_line(mu, min_cycles=4, max_period=n / 4)
    assert line.ratio > line.threshold(1e-4)
    assert line.period == pytest.approx(70.0, rel=0.05)
    # its size is read on the true scale, not the flattened one
    assert math.sqrt(line.variance) == pytest.approx(0.02 / math.pi / math.sqrt(2), rel=0.3)


def test_the_power_law_of_white_noise_is_flat_and_of_pink_noise_falls_as_1_over_f() -> None:
    rng = np.random.default_rng(13)
    for beta, noise in ((0.0, rng.standard_normal(8192)), (1.0, _one_over_f(rng, 8192))):
        power = np.abs(np.fft.rfft(noise)) ** 2
        trend = power_law_trend(power)
        j = np.array([10, 1000])
        slope = math.log(trend[j[1]] / trend[j[0]]) / math.log(j[1] / j[0])
        assert slope == pytest.approx(-beta, abs=0.1)
    assert np.array_equal(power_law_trend(np.zeros(50)), np.ones(50))


def test_threshold_grows_with_the_candidates_and_the_bins_correlation() -> None:
    assert line_threshold(10, 1e-3) < line_threshold(10_000, 1e-3) < line_threshold(10_000, 1e-6)
    assert line_threshold(1000, 1e-3) < line_threshold(1000, 1e-3, correlation_sq=(0.4, 0.03))
    assert line_threshold(0, 1e-3) == math.inf


def test_gamma_survival_function() -> None:
    # integer shape: Q(k, x) = e^-x Σ_{i<k} x^i / i!
    for k, x in ((1, 0.5), (3, 10.0), (3, 2.0), (5, 30.0)):
        want = math.exp(-x) * sum(x**i / math.factorial(i) for i in range(k))
        assert gamma_q(k, x) == pytest.approx(want, rel=1e-10)
    assert gamma_q(2.5, 0.0) == 1.0


def test_tukey_taper_is_flat_in_the_middle_and_its_bins_are_nearly_independent() -> None:
    w = tukey(1000, 0.2)
    assert w[0] == 0 and np.all(w[100:900] == 1) and np.allclose(w, w[::-1])
    rho1, rho2 = taper_bin_correlation_sq(w)
    assert rho1 < 0.05 and rho2 < 0.05
    assert taper_bin_correlation_sq(np.ones(100)) == pytest.approx((0.0, 0.0), abs=1e-20)


# --------------------------------------------------------------------------- peak readings


def test_a_broad_peak_is_read_by_a_wide_quadratic_not_by_the_noise_maximum() -> None:
    from tribopipe.reduction.signals import quadratic_peak

    rng = np.random.default_rng(11)
    x = np.arange(6000.0)
    clean = 0.8 - 2e-8 * (x - 3000.0) ** 2  # 0.18 lower 3000 samples away
    values = clean + 0.015 * rng.standard_normal(x.size)
    k = 3000 + int(np.argmax(savgol(values, 21)[2900:3100])) - 100
    value, position, width = quadratic_peak(values, k, 0, x.size - 1, first_half_width=10,
                                            noise_sd=0.015, sample_sd=0.015)
    assert width > 1000
    assert value == pytest.approx(0.8, abs=0.004)
    assert savgol(values, 21).max() > 0.805  # what a 21-sample reading would have given
    assert position == pytest.approx(3000, abs=200)


def test_a_quadratic_is_not_laid_over_a_sudden_slip() -> None:
    from tribopipe.reduction.signals import quadratic_peak

    x = np.arange(2000.0)
    values = np.where(x < 1000, 0.8 - 1e-6 * (x - 950) ** 2, 0.55)  # a slip at 1000
    breaks = np.zeros(x.size, dtype=bool)
    breaks[999] = True
    value, position, width = quadratic_peak(values, 950, 0, x.size - 1, first_half_width=5,
                                            noise_sd=0.001, sample_sd=0.001, breaks=breaks)
    assert 40 < width <= 81  # it grew until the next window would reach the slip
    assert value == pytest.approx(0.8, abs=1e-6) and position == pytest.approx(950, abs=0.5)


def test_a_flank_is_read_at_its_end_from_as_much_of_it_as_fits() -> None:
    from tribopipe.reduction.signals import flank_peak

    rng = np.random.default_rng(12)
    x = np.arange(3000.0)
    values = 0.2 + 0.6 * x / 2999 + 0.01 * rng.standard_normal(x.size)  # linear rise to 0.8
    value, width = flank_peak(values, 2999, 0, first_window=64, noise_sd=0.01,
                              sample_sd=0.01)
    assert width >= 1024
    assert value == pytest.approx(0.8, abs=0.003)


def test_effective_noise_of_correlated_noise_counts_its_autocorrelation() -> None:
    from tribopipe.reduction.detection import effective_noise

    rng = np.random.default_rng(13)
    white = 0.01 * rng.standard_normal(20000)
    assert effective_noise(white, 71) == pytest.approx(0.01, rel=0.08)
    coloured = 0.01 * _ar1(rng, 20000, 0.5)  # τ = 3: √3 × the white estimate, less what
    # the running mean takes of the correlation (documented: ~18 % low here)
    assert 0.01 * math.sqrt(3) * 0.75 < effective_noise(coloured, 71) < 0.01 * math.sqrt(3)
    assert effective_noise(coloured, 71) > 1.3 * effective_noise(white, 71)


def test_gamma_survival_function_takes_an_array_as_it_takes_numbers() -> None:
    x = np.array([0.0, 1e-3, 0.5, 2.0, 3.9, 4.1, 12.0, 300.0])
    for a in (0.7, 2.6, 3.0):
        together = gamma_q(a, x)
        assert together.shape == x.shape
        # one by one each x stops at its own last term; together at the slowest one's
        assert together == pytest.approx([gamma_q(a, float(v)) for v in x], rel=1e-14)


@pytest.mark.parametrize("window", [1, 2, 7, 99, 100])
def test_window_medians_are_numpys_medians_of_every_window(window: int) -> None:
    rng = np.random.default_rng(window)
    v = rng.exponential(size=1000)
    v[500] = np.nan  # a gap spoils exactly the windows that hold it, as np.median does
    want = np.median(np.lib.stride_tricks.sliding_window_view(v, window), axis=1)
    got = window_medians(v, window)
    assert got.shape == want.shape
    np.testing.assert_array_equal(got, want)
    assert window_medians(v[: window - 1], window).size == 0


def test_decreasing_root_finds_the_crossing_to_the_tolerance_in_few_steps() -> None:
    calls = []

    def g(x: float) -> float:
        calls.append(x)
        return math.log(math.exp(-x) + 1e-9) - math.log(0.01)  # crosses at ~ln 100

    x = decreasing_root(g, 0.0, 500.0)
    assert x == pytest.approx(math.log(1.0 / (0.01 - 1e-9)), rel=1e-11)
    assert len(calls) <= 15  # bisection alone would need ~47 steps for this tolerance
    # no crossing inside: the bound on the side the crossing lies
    assert decreasing_root(lambda v: -1.0 - v, 0.0, 10.0) == 0.0
    assert decreasing_root(lambda v: 5.0 - v, 0.0, 1.0) == 1.0
    # a function that is -inf beyond a point still brackets by bisection
    assert decreasing_root(lambda v: 3.0 - v if v < 4 else -math.inf, 0.0, 100.0) == (
        pytest.approx(3.0, rel=1e-11))

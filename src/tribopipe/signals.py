"""Signal primitives of the reduction, in NumPy alone: running median, mean and maximum,
Savitzky–Golay smoothing, one-sided polynomial fits, and a test for a periodic line in
noise.

NumPy only, so that a batch worker does not pay for importing ``scipy.signal`` and
``scipy.ndimage`` (~0.9 s per process, issue 10). Edges follow SciPy's conventions
(``mode="nearest"`` for the running filters, ``mode="interp"`` for Savitzky–Golay), and
``tests/test_signals.py`` checks every function against SciPy where SciPy is installed.
All functions take NaN-free 1-D arrays and return new arrays; none modifies its input.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view


def _padded(v: np.ndarray, before: int, after: int) -> np.ndarray:
    """``v`` extended by its first value ``before`` times and its last ``after`` times."""
    return np.concatenate([np.full(before, v[0]), v, np.full(after, v[-1])])


def running_median(values: Any, window: int) -> np.ndarray:
    """Running median over ``window`` samples (odd; centred), edges by the nearest value
    (SciPy ``median_filter(..., mode="nearest")``). Shape (n,)."""
    v = np.asarray(values, dtype=float)
    w = int(window)
    if w <= 1 or v.size == 0:
        return v.copy()
    half = w // 2
    return np.median(sliding_window_view(_padded(v, half, w - 1 - half), w), axis=1)


def running_mean(values: Any, window: int) -> np.ndarray:
    """Running mean over ``window`` samples (centred), edges by the nearest value (SciPy
    ``uniform_filter1d(..., mode="nearest")``). Shape (n,)."""
    v = np.asarray(values, dtype=float)
    w = int(window)
    if w <= 1 or v.size == 0:
        return v.copy()
    half = w // 2
    padded = _padded(v, half, w - 1 - half)
    sums = np.cumsum(np.concatenate([[0.0], padded]))
    return (sums[w:] - sums[:-w]) / w


def running_max(values: Any, window: int, *, trailing: bool = False) -> np.ndarray:
    """Running maximum over ``window`` samples, edges by the nearest value. Centred
    (SciPy ``maximum_filter1d(..., mode="nearest")``), or ``trailing``: the highest of
    samples ``k-window+1 … k``. Shape (n,)."""
    v = np.asarray(values, dtype=float)
    w = int(window)
    if w <= 1 or v.size == 0:
        return v.copy()
    before = w - 1 if trailing else w // 2
    return sliding_window_view(_padded(v, before, w - 1 - before), w).max(axis=1)


@functools.lru_cache(maxsize=64)
def _savgol_matrix(window: int, degree: int) -> np.ndarray:
    """(window, window) matrix whose row j gives the value at sample j of the
    least-squares polynomial of ``degree`` through ``window`` equally spaced samples."""
    x = np.arange(window, dtype=float) - (window - 1) / 2
    basis = np.vander(x, degree + 1, increasing=True)
    matrix = basis @ np.linalg.pinv(basis)
    matrix.setflags(write=False)
    return matrix


def savgol(values: Any, window: int, degree: int = 2) -> np.ndarray:
    """Savitzky–Golay smoothing: the value at each sample of the least-squares polynomial
    of ``degree`` through the ``window`` samples (odd) centred on it; the first and last
    ``window // 2`` samples from the polynomial through the first and last ``window``
    samples (SciPy ``savgol_filter(..., mode="interp")``). Shape (n,); shorter input is
    returned unchanged."""
    v = np.asarray(values, dtype=float)
    w = int(window)
    if w % 2 == 0 or w <= degree:
        raise ValueError(f"window must be odd and larger than the degree, got {w}")
    if v.size < w:
        return v.copy()
    matrix = _savgol_matrix(w, degree)
    half = w // 2
    out = np.empty_like(v)
    # np.correlate with the centre row: out[k] = sum_j row[j] * v[k - half + j]
    out[half : v.size - half] = np.correlate(v, matrix[half], mode="valid")
    out[:half] = matrix[:half] @ v[:w]
    out[v.size - half :] = matrix[half + 1 :] @ v[-w:]
    return out


def end_point_weights(window: int, degree: int = 2) -> np.ndarray:
    """Weights (shape (window,)) that give the value at the last sample of the
    least-squares polynomial of ``degree`` through ``window`` equally spaced samples."""
    x = np.linspace(0.0, 1.0, int(window))
    basis = np.vander(x, degree + 1, increasing=True)
    return np.ones(degree + 1) @ np.linalg.solve(basis.T @ basis, basis.T)


def one_sided_fits(values: Any, window: int) -> tuple[np.ndarray, np.ndarray]:
    """Quadratic least-squares fits over ``window`` samples on one side only (shape (n,)
    each, -inf where the window does not fit): ``left[k]`` is the fit over samples
    ``k-window+1 … k`` read at ``k``, ``right[k]`` the fit over ``k … k+window-1`` read at
    ``k``. Unlike a centred smoothing, neither averages across a sudden slip."""
    v = np.asarray(values, dtype=float)
    w = int(window)
    left = np.full(v.size, -np.inf)
    right = np.full(v.size, -np.inf)
    if v.size >= w:
        weights = end_point_weights(w)
        left[w - 1 :] = np.correlate(v, weights, mode="valid")
        right[: v.size - w + 1] = np.correlate(v[::-1], weights, mode="valid")[::-1]
    return left, right


def periodic_line(
    values: Any, *, min_cycles: float, max_period: float, neighbours: int = 48,
    smooth_bins: int = 3, detrend_degree: int = 2,
) -> tuple[float, float, float, int]:
    """The strongest periodic line in ``values`` (shape (n,), evenly sampled) against the
    local level of the periodogram around it.

    The series is detrended (least-squares polynomial of ``detrend_degree``: a slow
    transient is not a line) and its periodogram ``I_j = |FFT_j|² / n`` taken: for white
    noise of variance σ², each ``I_j`` is σ² times an exponential variate. A candidate
    line sums ``smooth_bins`` adjacent bins (a line whose cycle length jitters spreads
    over a few bins) and is compared with the local level: the running median of
    ``2·neighbours + smooth_bins`` bins around it divided by ln 2 (the median of an
    exponential variate), which follows the slow change of a coloured noise's level but
    not a line. Candidates have at least ``min_cycles`` cycles in the series and a
    period of at least 2 and at most ``max_period`` samples.

    Returns ``(ratio, period, excess_variance, candidates)``: the largest summed power
    over its local level (in units of one bin's level), the period of that line
    [samples], the variance the line adds to the series above the local level (a
    sinusoid of amplitude a adds a²/2), and the number of candidate frequencies (for a
    false-alarm threshold). ``(0, nan, 0, 0)`` when no frequency qualifies.
    """
    v = np.asarray(values, dtype=float)
    n = v.size
    if n < 16:
        return 0.0, math.nan, 0.0, 0
    x = np.linspace(-1.0, 1.0, n)
    resid = v - np.polyval(np.polyfit(x, v, detrend_degree), x)
    power = np.abs(np.fft.rfft(resid)) ** 2 / n
    power[0] = 0.0
    j = np.arange(power.size)
    with np.errstate(divide="ignore"):
        period = np.where(j > 0, n / np.maximum(j, 1), np.inf)
    candidate = (j >= max(1, math.ceil(min_cycles))) & (period <= max_period) & (period >= 2)
    candidate &= (j - smooth_bins // 2 >= 1) & (j + smooth_bins // 2 < power.size)
    count = int(candidate.sum())
    if count == 0:
        return 0.0, math.nan, 0.0, 0
    line = np.convolve(power, np.ones(smooth_bins), mode="same")
    # the spectrum is mirrored at its ends, so the level there is still a median of bins
    width = 2 * neighbours + smooth_bins
    mirrored = np.pad(power[1:], width // 2, mode="symmetric")
    level = np.empty_like(power)
    level[0] = np.inf
    level[1:] = np.median(sliding_window_view(mirrored, width), axis=1) / math.log(2.0)
    ratio = np.where(candidate & (level > 0), line / np.where(level > 0, level, 1.0), 0.0)
    k = int(np.argmax(ratio))
    excess = max(0.0, float(line[k] - smooth_bins * level[k])) * 2.0 / n
    return float(ratio[k]), float(period[k]), excess, count


def line_threshold(candidates: int, false_alarm: float, smooth_bins: int = 3,
                   level_bins: int = 99) -> float:
    """The ratio :func:`periodic_line` must exceed for white noise to pass it with
    probability ``false_alarm`` over ``candidates`` frequencies.

    A sum of ``smooth_bins`` periodogram bins of noise is a Gamma(smooth_bins, 1) variate
    in units of the true level, with tail ``T(L) = e^{-L} Σ_{i<k} L^i/i!``. The level is
    estimated as the median of ``level_bins`` bins over ln 2, which is normally
    distributed about the true level with relative standard deviation
    δ = 1/(ln 2·√level_bins) (the sample median of exponential variates). The ratio's
    tail is ``E[T(L·M)]`` over that M ~ N(1, δ²), solved for
    ``false_alarm / candidates``.
    """
    if candidates <= 0:
        return math.inf
    target = false_alarm / candidates
    delta = 1.0 / (math.log(2.0) * math.sqrt(level_bins))
    m = np.linspace(max(0.05, 1.0 - 6 * delta), 1.0 + 6 * delta, 241)
    weights = np.exp(-0.5 * ((m - 1.0) / delta) ** 2)
    weights /= weights.sum()

    def tail(L: float) -> float:
        x = L * m
        poly = sum(x**i / math.factorial(i) for i in range(smooth_bins))
        return float(np.sum(weights * np.exp(-x) * poly))

    lo, hi = 0.0, 500.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if tail(mid) > target:
            lo = mid
        else:
            hi = mid
    return hi

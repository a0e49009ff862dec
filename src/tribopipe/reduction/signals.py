"""Signal primitives of the reduction, in NumPy (and pandas' rolling median): running
median, mean and maximum, Savitzky–Golay smoothing, one-sided polynomial fits, and a test
for a periodic line in noise.

No SciPy, so that a batch worker does not pay for importing ``scipy.signal`` and
``scipy.ndimage`` (~0.9 s per process; pandas is loaded by the readers
anyway). Edges follow SciPy's conventions (``mode="nearest"`` for the running filters,
``mode="interp"`` for Savitzky–Golay), and ``tests/test_signals.py`` checks every function
against SciPy where SciPy is installed.
All functions take NaN-free 1-D arrays and return new arrays; none modifies its input.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import ArrayLike, NDArray


def _padded(v: NDArray[np.float64], before: int, after: int) -> NDArray[np.float64]:
    """``v`` extended by its first value ``before`` times and its last ``after`` times."""
    return np.concatenate([np.full(before, v[0]), v, np.full(after, v[-1])])


def running_median(values: ArrayLike, window: int) -> NDArray[np.float64]:
    """Running median over ``window`` samples (odd; centred), edges by the nearest value
    (SciPy ``median_filter(..., mode="nearest")``). Shape (n,)."""
    v = np.asarray(values, dtype=float)
    w = int(window)
    if w <= 1 or v.size == 0:
        return v.copy()
    half = w // 2
    return window_medians(_padded(v, half, w - 1 - half), w)


def window_medians(values: ArrayLike, window: int) -> NDArray[np.float64]:
    """Median of every run of ``window`` consecutive samples of ``values`` (shape
    (n - window + 1,)): the same numbers as ``np.median`` over a sliding window view, by
    pandas' rolling median (a sorted window updated sample by sample, O(n log window)
    instead of a partition of n × window copied values)."""
    import pandas as pd

    v = np.asarray(values, dtype=float)
    w = int(window)
    if w < 1 or v.size < w:
        return np.empty(0)
    return pd.Series(v).rolling(w).median().to_numpy()[w - 1 :]


def running_mean(values: ArrayLike, window: int) -> NDArray[np.float64]:
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


def running_max(values: ArrayLike, window: int, *, trailing: bool = False) -> NDArray[np.float64]:
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
def _savgol_matrix(window: int, degree: int) -> NDArray[np.float64]:
    """(window, window) matrix whose row j gives the value at sample j of the
    least-squares polynomial of ``degree`` through ``window`` equally spaced samples."""
    x = np.arange(window, dtype=float) - (window - 1) / 2
    basis = np.vander(x, degree + 1, increasing=True)
    matrix = basis @ np.linalg.pinv(basis)
    matrix.setflags(write=False)
    return matrix


def savgol(values: ArrayLike, window: int, degree: int = 2) -> NDArray[np.float64]:
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


@functools.lru_cache(maxsize=512)
def end_point_weights(window: int, degree: int = 2) -> NDArray[np.float64]:
    """Weights (shape (window,), read-only) that give the value at the last sample of the
    least-squares polynomial of ``degree`` through ``window`` equally spaced samples."""
    x = np.linspace(0.0, 1.0, int(window))
    basis = np.vander(x, degree + 1, increasing=True)
    weights = np.ones(degree + 1) @ np.linalg.solve(basis.T @ basis, basis.T)
    weights.setflags(write=False)
    return weights


def one_sided_fits(
    values: ArrayLike, window: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
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


def tukey(n: int, alpha: float = 0.2) -> NDArray[np.float64]:
    """Tukey (split cosine bell) taper of ``n`` points: flat, with cosine edges over a
    fraction ``alpha`` of the series (``alpha/2`` at each end)."""
    w = np.ones(n)
    edge = int(math.floor(alpha * (n - 1) / 2.0))
    if edge >= 1:
        ramp = 0.5 * (1 - np.cos(np.pi * np.arange(edge) / edge))
        w[:edge] = ramp
        w[n - edge :] = ramp[::-1]
    return w


def taper_bin_correlation_sq(taper: ArrayLike, lags: int = 2) -> tuple[float, ...]:
    """Squared correlations of periodogram bins ``lags`` apart for white noise tapered
    by ``taper`` (shape (n,)): |Σ w² e^{-2πikt/n}|² / (Σ w²)² for k = 1 … lags."""
    w2 = np.asarray(taper, dtype=float) ** 2
    t = np.arange(w2.size)
    total = float(w2.sum())
    return tuple(
        float(abs(np.sum(w2 * np.exp(-2j * np.pi * k * t / w2.size))) / total) ** 2
        for k in range(1, lags + 1)
    )


@dataclass(frozen=True)
class Line:
    """The strongest periodic line of a series (:func:`periodic_line`).

    ``ratio``: its summed power over the local level, in units of one bin's level;
    ``period``: the period [samples] at which the series repeats (the strongest line's,
    or that of its fundamental when the strongest is a harmonic); ``variance``: what the
    line (and its fundamental) add to the series' variance above the level (a sinusoid
    of amplitude a adds a²/2); ``candidates``: the number of
    frequencies searched; ``correlation_sq``: squared correlations of neighbouring bins
    (from the taper), for :func:`line_threshold`."""

    ratio: float
    period: float
    variance: float
    candidates: int
    correlation_sq: tuple[float, ...] = (0.0, 0.0)

    def threshold(self, false_alarm: float) -> float:
        """The ratio noise alone exceeds with probability ``false_alarm`` (over all the
        candidates)."""
        return line_threshold(self.candidates, false_alarm, correlation_sq=self.correlation_sq)


def power_law_trend(power: ArrayLike) -> NDArray[np.float64]:
    """The power law c·j^β fitted to a periodogram (shape (m,), bin 0 the mean's, left
    out) by least squares of ln I_j over ln j, over the bins with power, as an array of
    the same shape (1 at bin 0; all ones when fewer than 8 bins have power). The
    logarithm of an exponential variate is its level's logarithm less Euler's constant,
    so the slope β is unbiased; the constant does not matter for a ratio."""
    p = np.asarray(power, dtype=float)
    out = np.ones(p.size)
    j = np.arange(1, p.size)
    good = p[1:] > 0
    if int(good.sum()) < 8:
        return out
    beta, c = np.polyfit(np.log(j[good]), np.log(p[1:][good]), 1)
    out[1:] = np.exp(c + beta * np.log(j))
    return out


def periodic_line(
    values: ArrayLike, *, min_cycles: float, max_period: float, neighbours: int = 48,
    smooth_bins: int = 3, detrend_degree: int = 2, taper_fraction: float = 0.2,
) -> Line:
    """The strongest periodic line in ``values`` (shape (n,), evenly sampled) against the
    local level of the periodogram around it.

    The series is detrended (least-squares polynomial of ``detrend_degree``: a slow
    transient is not a line) and tapered with a Tukey window whose cosine edges span
    ``taper_fraction`` of it, so that what is left of a transient at either end does not
    leak into a broad hump that would pass for a line. Its periodogram is
    ``I_j = |FFT_j(w·x)|² / Σw²``: for noise of spectral level S(f) each ``I_j`` is
    S(f_j) times an exponential variate (neighbours slightly correlated through the
    taper). A candidate line sums ``smooth_bins`` adjacent bins (a line whose cycle
    length jitters spreads over a few) and is compared with the local level: the median
    of the ``2·neighbours + smooth_bins`` bins around it (the spectrum mirrored at its
    ends) over ln 2, the median of an exponential variate; it follows the slow change of a
    coloured noise's level but not a line. The median is a fair level only where the
    spectrum is about flat over those bins; a sensor's drifting zero is 1/f^β noise
    (pink: β ≈ 1), whose level falls by a factor of ten or more across the neighbours
    of the lowest candidates, so the median there lies far below the bin's own level and
    the noise itself passes for a line. The periodogram is therefore first divided by
    the power law fitted to it (:func:`power_law_trend`: a line fills a few of thousands
    of bins and hardly moves the fit; white noise gives β ≈ 0 and changes nothing), the
    test run on that flattened spectrum, and the line's variance taken back on the true
    scale. Candidates have at least ``min_cycles`` cycles in the series and a period of 2
    to ``max_period`` samples. When the strongest
    line is the 2nd or 3rd harmonic of a line that also stands out (at 1 % for that one
    frequency), the period reported is the fundamental's.
    """
    v = np.asarray(values, dtype=float)
    n = v.size
    if n < 32:
        return Line(0.0, math.nan, 0.0, 0)
    x = np.linspace(-1.0, 1.0, n)
    resid = v - np.polyval(np.polyfit(x, v, detrend_degree), x)
    taper = tukey(n, taper_fraction)
    w2 = float(np.sum(taper**2))
    power = np.abs(np.fft.rfft(resid * taper)) ** 2 / w2
    power[0] = 0.0
    j = np.arange(power.size)
    trend = power_law_trend(power)
    power = power / trend
    with np.errstate(divide="ignore"):
        period = np.where(j > 0, n / np.maximum(j, 1), np.inf)
    candidate = (j >= max(1, math.ceil(min_cycles))) & (period <= max_period) & (period >= 2)
    candidate &= (j - smooth_bins // 2 >= 1) & (j + smooth_bins // 2 < power.size)
    count = int(candidate.sum())
    if count == 0:
        return Line(0.0, math.nan, 0.0, 0)
    line = np.convolve(power, np.ones(smooth_bins), mode="same")
    width = 2 * neighbours + smooth_bins
    mirrored = np.pad(power[1:], width // 2, mode="symmetric")
    level = np.empty_like(power)
    level[0] = np.inf
    level[1:] = window_medians(mirrored, width) / math.log(2.0)
    ratio = np.where(candidate & (level > 0), line / np.where(level > 0, level, 1.0), 0.0)
    k = int(np.argmax(ratio))
    # Parseval with the taper: a line's variance is its summed power × 2·Σw²/(Σw)²
    gain = 2.0 * w2 / float(np.sum(taper)) ** 2
    excess = max(0.0, float(line[k] - smooth_bins * level[k])) * gain * float(trend[k])
    rho = taper_bin_correlation_sq(taper)
    fundamental = k
    # a saw-tooth's harmonics are lines too: if the strongest is a harmonic, the series
    # repeats at the lowest frequency k/h (h = 2, 3) whose own line also stands out
    single = line_threshold(1, 0.01, correlation_sq=rho, smooth_bins=smooth_bins)
    for h in (3, 2):
        sub = int(round(k / h))
        if sub >= max(1, math.ceil(min_cycles)) and candidate[sub] and ratio[sub] > single:
            fundamental = sub
            excess += (max(0.0, float(line[sub] - smooth_bins * level[sub])) * gain
                       * float(trend[sub]))
            break
    return Line(float(ratio[k]), float(period[fundamental]), excess, count, rho)


def gamma_q(a: float, x: ArrayLike) -> float | NDArray[np.float64]:
    """Regularised upper incomplete gamma function Q(a, x) = Γ(a, x)/Γ(a) (a > 0): the
    survival function of a Gamma(a, 1) variate at x, for a number or an array of x (a
    float, or an array of x's shape). Series below a + 1, Lentz's continued fraction
    above, both evaluated for all x at once until every term is below 1e-15 of its sum."""
    xs = np.asarray(x, dtype=float)
    out = np.ones(xs.shape)
    positive = xs > 0
    low = positive & (xs < a + 1)
    high = positive & ~low
    if low.any():
        out[low] = _gamma_q_series(a, xs[low])
    if high.any():
        out[high] = _gamma_q_fraction(a, xs[high])
    return float(out) if out.ndim == 0 else out


def _gamma_log_front(a: float, x: NDArray[np.float64]) -> NDArray[np.float64]:
    """ln(x^a e^-x / Γ(a)), the factor both expansions of Q(a, x) share (x > 0)."""
    return -x + a * np.log(x) - math.lgamma(a)


def _gamma_q_series(a: float, x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Q(a, x) = 1 − P(a, x) from the series of P, for 0 < x < a + 1."""
    term = np.full(x.shape, 1.0 / a)
    total = term.copy()
    k = a
    for _ in range(1000):
        k += 1
        term = term * x / k
        total += term
        if np.all(np.abs(term) < np.abs(total) * 1e-15):
            break
    return np.maximum(0.0, 1.0 - total * np.exp(_gamma_log_front(a, x)))


def _gamma_q_fraction(a: float, x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Q(a, x) from its continued fraction (modified Lentz), for x ≥ a + 1."""
    tiny = 1e-300
    b = x + 1.0 - a
    c = np.full(x.shape, 1.0 / tiny)
    d = 1.0 / b
    h = d.copy()
    for i in range(1, 1000):
        an = -i * (i - a)
        b = b + 2.0
        d = an * d + b
        d = np.where(np.abs(d) < tiny, tiny, d)
        c = b + an / c
        c = np.where(np.abs(c) < tiny, tiny, c)
        d = 1.0 / d
        delta = d * c
        h = h * delta
        if np.all(np.abs(delta - 1.0) < 1e-15):
            break
    return np.exp(_gamma_log_front(a, x)) * h


def line_threshold(candidates: int, false_alarm: float, *,
                   correlation_sq: tuple[float, ...] = (0.0, 0.0), smooth_bins: int = 3,
                   level_bins: int = 99) -> float:
    """The ratio :func:`periodic_line` must exceed for noise to pass it with probability
    ``false_alarm`` over ``candidates`` frequencies.

    In units of the true level, the sum S of ``smooth_bins`` neighbouring periodogram
    bins of noise has mean k = ``smooth_bins`` and variance k + 2 Σ_{i<j} ρ²_{|i−j|}
    (``correlation_sq`` = ρ² at lags 1, 2 …, from the taper); it is taken as the Gamma
    variate of that mean and variance (Satterthwaite). The level is the median of
    ``level_bins`` bins over ln 2; its distribution is that of the median of N_eff
    exponential variates (exact: a binomial tail), N_eff being ``level_bins`` over the
    correlation's inflation of their variance. The ratio's tail E[Q(shape, L·M/scale)]
    over that level M is solved for ``false_alarm / candidates``.
    """
    if candidates <= 0:
        return math.inf
    rho = tuple(round(r, 3) for r in correlation_sq)
    return _threshold(round(math.log10(false_alarm / candidates), 2), rho, smooth_bins,
                      level_bins)


@functools.lru_cache(maxsize=1024)
def _threshold(log10_target: float, correlation_sq: tuple[float, ...], smooth_bins: int,
               level_bins: int) -> float:
    target = 10.0**log10_target
    k = smooth_bins
    variance = float(k)
    for lag, rho_sq in enumerate(correlation_sq, start=1):
        variance += 2.0 * max(0, k - lag) * rho_sq
    shape, scale = k * k / variance, variance / k
    # the level's distribution: the median of N_eff exponential bins over ln 2 is below m
    # when at least half of them are below m·ln 2
    n_eff = max(3, int(round(level_bins / (1.0 + 2.0 * sum(correlation_sq)))))
    half = (n_eff + 1) // 2
    edges = np.linspace(0.0, 4.0, 401)
    q = 1.0 - 2.0 ** (-edges)
    cdf = np.zeros(q.size)
    for i in range(half, n_eff + 1):
        cdf += math.comb(n_eff, i) * q**i * (1 - q) ** (n_eff - i)
    weights = np.diff(cdf)
    m = 0.5 * (edges[1:] + edges[:-1])
    keep = weights > 1e-15
    weights, m = weights[keep], m[keep]

    def tail(L: float) -> float:
        return float(weights @ gamma_q(shape, L * m / scale))

    return decreasing_root(lambda L: math.log(max(tail(L), 1e-300)) - math.log(target),
                           0.0, 500.0)


def decreasing_root(
    g: Callable[[float], float], lo: float, hi: float, *, rel_tol: float = 1e-12
) -> float:
    """The x in [lo, hi] where the decreasing function ``g`` crosses zero (g(lo) > 0 ≥
    g(hi) assumed; the bound itself when not), to ``rel_tol`` of x: regula falsi with the
    Illinois halving of a stuck end (a few evaluations for a smooth g), falling back to a
    bisection step whenever a value is not finite or the step stalls."""
    g_lo, g_hi = g(lo), g(hi)
    if not g_lo > 0:
        return lo
    if g_hi > 0:
        return hi
    side = 0
    for _ in range(200):
        if hi - lo <= rel_tol * max(abs(hi), 1e-300):
            break
        x = 0.5 * (lo + hi)
        if math.isfinite(g_lo) and math.isfinite(g_hi) and g_lo != g_hi:
            guess = hi - g_hi * (hi - lo) / (g_hi - g_lo)
            if lo < guess < hi:
                x = guess
        g_x = g(x)
        if g_x == 0:
            return x
        if g_x > 0:
            lo, g_lo = x, g_x
            if side == +1:
                g_hi *= 0.5
            side = +1
        else:
            hi, g_hi = x, g_x
            if side == -1:
                g_lo *= 0.5
            side = -1
    return hi


def quadratic_peak(
    values: ArrayLike, k: int, lo: int, hi: int, *, first_half_width: int, noise_sd: float,
    sample_sd: float, gamma: float = 2.0, breaks: ArrayLike | None = None,
) -> tuple[float, float, int]:
    """Read a rounded maximum near sample ``k`` of ``values`` (shape (n,)) by fitting
    quadratics over windows that double in width, keeping the widest one the data allow
    (the intersection-of-confidence-intervals rule).

    Window j spans ``k ± first_half_width·2^j`` within ``[lo, hi]`` (inclusive sample
    indices), re-centred each time on the previous fit's vertex. Windows too short to show
    a concave fit with its vertex inside (a broad peak under noise) are widened until one
    does; from then on a fit is used only while it is concave, its vertex lies inside its
    window, no sample of ``breaks`` (a boolean
    mask, e.g. sudden slips) lies inside, and its residuals scatter no more than the noise
    (standard deviation ≤ ``sample_sd``·(1 + 3/√(2(n−3)))): a quadratic laid over a rise
    and a sudden drop overshoots both. Its reading is the value at the vertex, with
    standard deviation ``noise_sd·√(9 / (4 n))`` for n samples (``noise_sd`` the per-sample
    noise with its autocorrelation counted). Windows grow while the intervals reading ±
    ``gamma``·sd of all windows so far still intersect: a wide fit averages the noise, so
    the reading is not the noise's maximum, and the first window whose quadratic no
    longer matches the peak's shape stops the growth.

    Returns ``(value, position, width)``: the reading, its position (fractional sample
    index) and the number of samples of the window used; ``(nan, nan, 0)`` when not even
    the first window qualifies.
    """
    v = np.asarray(values, dtype=float)
    barrier = None if breaks is None else np.asarray(breaks, dtype=bool)
    lower, upper = -math.inf, math.inf
    best = (math.nan, math.nan, 0)
    centre = float(k)
    half = int(first_half_width)
    while True:
        a = max(lo, int(round(centre)) - half)
        b = min(hi, int(round(centre)) + half)
        n = b - a + 1
        if n < 7 or (barrier is not None and barrier[a : b + 1].any()):
            break
        x = np.arange(a, b + 1, dtype=float) - centre
        c2, c1, c0 = np.polyfit(x, v[a : b + 1], 2)
        vertex = -c1 / (2 * c2) if c2 < 0 else math.inf
        if not (a - centre <= vertex <= b - centre):
            # a window too short to show a broad peak's curvature above the noise says
            # nothing yet: widen it (a wide one that shows no peak stops below)
            if (a == lo and b == hi) or best[2]:
                break
            half *= 2
            continue
        resid = v[a : b + 1] - np.polyval((c2, c1, c0), x)
        if float(np.std(resid, ddof=3)) > sample_sd * (1 + 3 / math.sqrt(2 * (n - 3))):
            break
        reading = c0 - c1 * c1 / (4 * c2)
        sd = noise_sd * math.sqrt(9.0 / (4.0 * n))
        lower, upper = max(lower, reading - gamma * sd), min(upper, reading + gamma * sd)
        if lower > upper:
            break
        best = (float(reading), float(centre + vertex), n)
        centre += vertex
        if a == lo and b == hi:
            break
        half *= 2
    return best


def flank_peak(
    values: ArrayLike, k: int, lo: int, *, first_window: int, noise_sd: float, sample_sd: float,
    gamma: float = 2.0,
) -> tuple[float, int]:
    """Read the top of a rising flank that ends in a sudden slip at sample ``k`` of
    ``values`` (shape (n,)): quadratic fits over windows ending at ``k`` that double in
    length backwards from ``first_window`` samples, read at ``k``;
    the widest window is kept while the readings' intervals ± ``gamma``·sd intersect and
    the residuals scatter no more than the noise (see :func:`quadratic_peak`). A reading
    over n samples has standard deviation ``noise_sd`` × that of a quadratic's end point.

    Returns ``(value, width)``; ``(nan, 0)`` when not even the first window qualifies.
    Windows reach back over at most the upper half of the flank (from ``lo``): its lower
    part is the elastic loading, steeper than the rounded top, and a quadratic over the
    whole rise would extrapolate past that top.
    """
    v = np.asarray(values, dtype=float)
    lower, upper = -math.inf, math.inf
    best = (math.nan, 0)
    n = int(first_window)
    # only the upper half of the flank: its start is the contact's elastic loading, steeper
    # than the rounded, elastic-plastic top a quadratic over it all would extrapolate past
    longest = max(int(first_window), (k - int(lo) + 1) // 2)
    while n <= longest:
        a = max(int(lo), k - n + 1)
        m = k - a + 1
        if m < 7:
            break
        x = np.arange(a, k + 1, dtype=float) - k
        coeffs = np.polyfit(x, v[a : k + 1], 2)
        resid = v[a : k + 1] - np.polyval(coeffs, x)
        if float(np.std(resid, ddof=3)) > sample_sd * (1 + 3 / math.sqrt(2 * (m - 3))):
            break
        reading = float(coeffs[-1])
        sd = noise_sd * math.sqrt(float(np.sum(end_point_weights(m) ** 2)))
        lower, upper = max(lower, reading - gamma * sd), min(upper, reading + gamma * sd)
        if lower > upper:
            break
        best = (reading, m)
        if a == lo:
            break
        n *= 2
    return best

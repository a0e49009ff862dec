"""The detection steps of the reduction: the filters and readings behind μ_S and μ_K.

The method — the order of the steps, their parameters and why — is described in the
module docstring of :mod:`tribopipe.reduction`, which calls :func:`run_detection` on the valid
samples of a run (in contact and moving) and builds the result from its
:class:`Detection`. Everything here is pure: arrays in, new values out.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace
from statistics import NormalDist
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..config import ReductionParams
from . import uncertainty
from .signals import (
    end_point_weights,
    flank_peak,
    one_sided_fits,
    periodic_line,
    quadratic_peak,
    running_max,
    running_mean,
    running_median,
    savgol,
)

# --------------------------------------------------------------------------- signal helpers


def noise_std(mu: Any) -> float:
    """Robust white-noise level of a signal (shape (n,)): 1.4826·MAD of its first
    differences / √2. Slow trends and rare jumps (slips) hardly affect it. NaN-free input."""
    d = np.diff(np.asarray(mu, dtype=float))
    if d.size < 2:
        return 0.0
    mad = np.median(np.abs(d - np.median(d)))
    return float(1.4826 * mad / math.sqrt(2))


def median_smooth(values: ArrayLike, window: int) -> NDArray[np.float64]:
    """Running median over ``window`` samples (made odd), edges by nearest value; a new
    array of the same shape (n,). NaN-free input."""
    v = np.asarray(values, dtype=float)
    w = max(1, int(window) | 1)
    if w <= 1 or v.size < w:
        return v.copy()
    return running_median(v, w)


def peak_smooth(values: ArrayLike, window: int) -> NDArray[np.float64]:
    """Quadratic Savitzky–Golay smoothing over ``window`` samples (made odd, ≥ 5); keeps
    rounded peaks while averaging noise. A new array of shape (n,). NaN-free input."""
    v = np.asarray(values, dtype=float)
    w = max(5, int(window) | 1)
    if v.size < w:
        return v.copy()
    return savgol(v, w, 2)


def static_peak_curve(values: ArrayLike, window: int) -> NDArray[np.float64]:
    """The curve whose maximum is read as μ_S (shape (n,), NaN-free input): a quadratic
    Savitzky–Golay smoothing over ``window`` samples, capped by the running maximum (same
    window) of a short moving average (a fifth of the window, at least 3 samples). The
    smoothing averages the noise without flattening a rounded peak; the cap stops the
    polynomial from overshooting where a peak ends in a sudden slip, so μ_S never exceeds
    what was (lightly averaged) measured."""
    v = np.asarray(values, dtype=float)
    w = max(5, int(window) | 1)
    smooth = peak_smooth(v, w)
    if v.size < w:
        return smooth
    averaged = running_mean(v, max(3, (w // 5) | 1))
    return np.minimum(smooth, running_max(averaged, w))


def cliff_peak_curve(
    values: ArrayLike, smooth_curve: ArrayLike, window: int, sigma: float, cliff_sigma: float
) -> NDArray[np.float64]:
    """``smooth_curve`` (shape (n,)) with the value at each sudden slip replaced by the
    one-sided fit of the rising flank when that is higher.

    A centred smoothing averages the low values after a slip into the peak and reads it
    low; the fit of the flank alone up to the last sample before the slip does not. A
    sample ``k`` is the top of a cliff when the left fit at ``k`` exceeds the right fit
    at ``k+1`` by more than ``cliff_sigma`` standard deviations of that difference (from
    the noise level ``sigma`` [COF]); elsewhere the smooth curve is kept unchanged, so
    rounded peaks read as before. The left fit is capped by the highest sample of its
    window, so a polynomial can never read above what was measured."""
    v = np.asarray(values, dtype=float)
    curve = np.array(smooth_curve, dtype=float)
    w = max(5, int(window))
    left, right = one_sided_fits(v, w)
    if v.size < w + 1:
        return curve
    left = np.minimum(left, running_max(v, w, trailing=True))
    # the flank of a stiff contact can be shorter than the window: near the start the
    # left fit uses the samples there are (at least MIN_FLANK_SAMPLES)
    width = np.full(v.size, w)
    for k in range(MIN_FLANK_SAMPLES - 1, w - 1):
        left[k] = min(float(end_point_weights(k + 1) @ v[: k + 1]), float(v[: k + 1].max()))
        width[k] = k + 1
    sd_left = np.array([_end_point_sd(int(n)) for n in range(w + 1)])[width]
    sd_difference = sigma * np.sqrt(sd_left**2 + _end_point_sd(w) ** 2)
    with np.errstate(invalid="ignore"):  # -inf - -inf where neither window fits: no cliff
        drop = left[:-1] - right[1:]
    cliff = np.zeros(v.size, dtype=bool)
    cliff[:-1] = np.isfinite(drop) & (drop > cliff_sigma * sd_difference[:-1])
    curve[cliff] = np.maximum(curve[cliff], left[cliff])
    return curve


#: the fewest samples a flank fit at a sudden slip uses (a quadratic through 7 points)
MIN_FLANK_SAMPLES = 7


@functools.lru_cache(maxsize=256)
def _end_point_sd(window: int) -> float:
    """Standard deviation, in units of the per-sample noise, of the end-point value of a
    quadratic least-squares fit over ``window`` samples (0 below 3 samples)."""
    if window < 3:
        return 0.0
    return math.sqrt(float(np.sum(end_point_weights(window) ** 2)))


def linear_slope(x: Any, y: Any) -> tuple[float, float]:
    """Least-squares slope of y over x and its standard error (white-noise model)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.size < 3 or np.ptp(x) == 0:
        return 0.0, math.inf
    xc = x - x.mean()
    sxx = float(np.dot(xc, xc))
    slope = float(np.dot(xc, y - y.mean()) / sxx)
    resid = y - y.mean() - slope * xc
    se = math.sqrt(float(np.dot(resid, resid)) / (x.size - 2) / sxx)
    return slope, se


def settling_block_mm(block_mm: float, period_mm: float | None) -> float:
    """Block length [mm] of the settling test: ``block_mm``, or, when the trace oscillates
    with period ``period_mm`` [mm], the smallest whole number of periods at least that
    long, so that every block averages whole cycles (the means of blocks that cut cycles
    beat against the period and never look settled)."""
    if period_mm is None or not math.isfinite(period_mm) or period_mm <= 0:
        return block_mm
    return math.ceil(block_mm / period_mm - 1e-9) * period_mm


def effective_noise(values: Any, window: int) -> float:
    """Per-sample noise [COF] of ``values`` (shape (n,)) as it matters for means: the
    robust standard deviation (1.4826·MAD) of what a running mean over ``window`` samples
    leaves (slow trends, transients and the plateau's level removed) times √τ_int, its
    integrated autocorrelation time (correlated noise averages down more slowly). The
    running mean takes the slowest part of the noise's correlation with it, so τ_int and
    the result are somewhat low for strongly correlated noise (by ~18 % for AR(1) noise
    with ρ = 0.5 and 71-sample windows); the settling test backs it with the scatter of
    the block means themselves."""
    v = np.asarray(values, dtype=float)
    if v.size < 8:
        return noise_std(v)
    r = v - running_mean(v, max(3, int(window)))
    spread = 1.4826 * float(np.median(np.abs(r - np.median(r))))
    return spread * math.sqrt(uncertainty.integrated_autocorrelation_time(r))


#: most blocks the settling test cuts a trace into (each needs 3 samples to count)
MAX_PLATEAU_BLOCKS = 1_000_000


def _block_means(
    s: NDArray[np.float64], m: NDArray[np.float64], start_mm: float, block: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int_]]:
    """Means, centres [mm] and sample counts of the blocks of ``block`` mm from
    ``start_mm`` (the last block runs to the end); blocks with fewer than 3 samples are
    left out."""
    end = float(s[-1])
    span_blocks = (end - start_mm) / block
    if not 2 <= span_blocks <= MAX_PLATEAU_BLOCKS:
        # too short to settle; or more blocks than a trace can fill (each needs 3
        # samples): nothing settles (flagged), never an unbounded allocation
        return np.empty(0), np.empty(0), np.empty(0, dtype=int)
    n_blocks = int(span_blocks)
    edges = start_mm + block * np.arange(n_blocks + 1)
    edges[-1] = end + 1e-12
    idx = np.searchsorted(s, edges)
    counts = np.diff(idx)
    sums = np.add.reduceat(m, idx[:-1])
    means = np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)
    good = counts >= 3
    return means[good], (0.5 * (edges[:-1] + edges[1:]))[good], counts[good]


def _block_scatter(means: NDArray[np.float64]) -> float:
    """Block-to-block scatter [COF] from second differences of the block means: a
    stationary scatter (noise, stick-slip) raises them, a smooth transient (a peak, a
    run-in, a creep) hardly; the median is deaf to a few blocks across a sudden slip."""
    if means.size < 6:
        return 0.0
    d2 = means[2:] - 2 * means[1:-1] + means[:-2]
    return 1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(6.0)


def find_plateau_start(
    s_mm: Any, mu: Any, start_mm: float, noise: float, params: ReductionParams,
    *, block_mm: float | None = None,
) -> tuple[float | None, float]:
    """Start [mm] of the settled plateau in ``mu`` over ``s_mm`` (both shape (n,), valid
    samples only) searched from ``start_mm`` on, and the tolerance used [COF]; ``noise``
    is the per-sample noise with its autocorrelation counted (:func:`effective_noise`:
    a block mean of n samples scatters by noise/√n). Blocks
    of ``block_mm`` (default ``params.block_mm``), lengthened by a whole factor when the
    block means scatter so much that the noise allowance would exceed ``settle_tol`` (the
    scatter of a mean falls with its length), up to half of ``plateau_min_mm``.

    Returns ``(None, tol)`` when no run of blocks reaching to the end and at least
    ``plateau_min_mm`` long stays within the tolerance.
    """
    block = params.block_mm if block_mm is None else float(block_mm)
    s = np.asarray(s_mm, dtype=float)
    m = np.asarray(mu, dtype=float)
    if s.size < 3:
        return None, params.settle_tol
    means, centres, counts = _block_means(s, m, start_mm, block)
    if means.size < 2:
        return None, params.settle_tol

    def allowance(means: NDArray[np.float64], counts: NDArray[np.int_]) -> float:
        # every block is compared: the noise allowance grows with their number so that a
        # settled plateau of pure noise fails the test with probability settle_alpha only;
        # the scatter is read where a plateau would be, the later half of the blocks
        z = NormalDist().inv_cdf(1.0 - params.settle_alpha / (2.0 * means.size))
        se_block = noise / math.sqrt(float(np.median(counts)))
        return z * max(se_block, _block_scatter(means[means.size // 2 :]))

    noise_tol = allowance(means, counts)
    base = (block, means, centres, max(params.settle_tol, noise_tol))
    longest = 0.5 * params.plateau_min_mm
    if noise_tol > params.settle_tol and block < longest:
        factor = min(math.ceil((noise_tol / params.settle_tol) ** 2),
                     int(longest / block + 1e-9))
        if factor > 1:
            longer = _block_means(s, m, start_mm, block * factor)
            if longer[0].size >= 2:
                block = block * factor
                means, centres, counts = longer
                noise_tol = allowance(means, counts)
    tol = max(params.settle_tol, noise_tol)
    min_blocks = max(2, math.ceil(params.plateau_min_mm / block - 1e-9))
    for k in range(means.size - min_blocks + 1):
        rest = means[k:]
        level = float(np.median(rest))
        if np.all(np.abs(rest - level) <= tol):
            start = float(centres[k] - 0.5 * block)
            return _settled_within(start, block, level, base), tol
    return None, tol


def _settled_within(
    start_mm: float, block_mm: float, level: float,
    base: tuple[float, NDArray[np.float64], NDArray[np.float64], float],
) -> float:
    """The plateau's start [mm] refined inside its first block of ``block_mm``: a
    lengthened block averages what lies inside it, so a loading ramp that rises through
    the plateau's level up to a peak and drops back (or a peak and its fall) can average
    to the level itself and pass as settled. ``base`` holds the settling test's own
    blocks (length [mm], means, centres [mm], tolerance [COF]); the start moves past the
    last of them in the first block whose mean lies further from ``level`` than that
    tolerance (a single base block of noise does so with probability ``settle_alpha``
    over all blocks: the tolerance is the base test's)."""
    base_mm, means, centres, tol = base
    if block_mm <= base_mm * (1 + 1e-9):
        return start_mm
    inside = (centres > start_mm) & (centres < start_mm + block_mm)
    off = np.flatnonzero(inside & (np.abs(means - level) > tol))
    if off.size == 0:
        return start_mm
    return float(centres[off[-1]] + 0.5 * base_mm)


@dataclass(frozen=True)
class StickSlipTest:
    """The periodic-line test of a plateau (step 7 of the module docstring).

    ``ratio`` is the strongest line's power over the local noise level, ``threshold`` what
    white noise exceeds with probability ``stick_slip_false_alarm``; ``std`` the
    standard deviation the line adds to μ [COF]; ``period_mm`` its period [mm]."""

    ratio: float
    threshold: float
    std: float
    period_mm: float

    @property
    def oscillates(self) -> bool:
        """A line above the false-alarm threshold (its size is judged separately)."""
        return self.ratio > self.threshold


@dataclass(frozen=True)
class Detection:
    """μ_S / μ_K detection on the valid samples (arrays of the valid samples)."""

    mu_s: float
    k_s: int
    mu_peak: float
    s_peak: float
    peak_at_limit: bool
    search_end_mm: float
    prominence: float
    distinct: bool
    sigma_peak: float
    peak_reading_u: float
    mu_k: float
    window: NDArray[np.bool_]
    settled: bool
    tol: float
    plateau_std: float
    drift: float
    drift_se: float
    sigma: float
    stick_slip: StickSlipTest
    mu_med: NDArray[np.float64]


def stick_slip_test(s_mm: Any, mu: Any, params: ReductionParams) -> StickSlipTest:
    """Look for a periodic oscillation of μ (shape (n,), evenly sampled in time, over
    distances ``s_mm`` [mm]) with at least ``stick_slip_min_cycles`` cycles in the
    window: :func:`tribopipe.reduction.signals.periodic_line` against
    :func:`tribopipe.reduction.signals.line_threshold` at ``stick_slip_false_alarm``."""
    s = np.asarray(s_mm, dtype=float)
    m = np.asarray(mu, dtype=float)
    if m.size < 32:
        return StickSlipTest(0.0, math.inf, 0.0, math.nan)
    line = periodic_line(
        m, min_cycles=params.stick_slip_min_cycles,
        max_period=m.size / params.stick_slip_min_cycles,
    )
    step_mm = float(s[-1] - s[0]) / max(m.size - 1, 1)
    return StickSlipTest(
        ratio=line.ratio,
        threshold=line.threshold(params.stick_slip_false_alarm),
        std=math.sqrt(line.variance),
        period_mm=line.period * step_mm if math.isfinite(line.period) else math.nan,
    )


def _detrended(values: NDArray[np.float64]) -> NDArray[np.float64]:
    """``values`` (shape (n,)) minus their least-squares quadratic trend."""
    if values.size < 4:
        return values - values.mean()
    x = np.linspace(-1.0, 1.0, values.size)
    return values - np.polyval(np.polyfit(x, values, 2), x)


def _oscillation_block_mm(
    s_mm: NDArray[np.float64], mu: NDArray[np.float64], params: ReductionParams
) -> float:
    """Block length [mm] of the settling test for the trace after the run-in (shape
    (n,)): whole cycles of a stick-slip oscillation found in its second half with at least
    twice ``stick_slip_min_cycles`` cycles (so that what is left of a transient, which
    looks like a line of a few cycles at most, cannot set the blocks), when its period is
    at most ``plateau_min_mm``; else ``block_mm``."""
    late = s_mm >= 0.5 * (float(s_mm[0]) + float(s_mm[-1]))
    strict = replace(params, stick_slip_min_cycles=2 * params.stick_slip_min_cycles)
    line = stick_slip_test(s_mm[late], mu[late], strict)
    if (
        line.oscillates
        and line.std > params.stick_slip_min_std
        and line.period_mm <= params.plateau_min_mm
    ):
        return settling_block_mm(params.block_mm, line.period_mm)
    return params.block_mm


def _find_plateau(
    s_v: NDArray[np.float64], mu_v: NDArray[np.float64], step_mm: float, params: ReductionParams
) -> tuple[NDArray[np.bool_], bool, float]:
    """Step 3 on the valid samples (distance [mm], μ; shape (n,)): the μ_K window (a
    boolean mask), whether it settled, and the settling tolerance [COF]. Not settled: the
    last ``plateau_min_mm`` of the trace (or its second half when that is all there is)."""
    post = s_v >= params.run_in_mm
    tol = params.settle_tol
    plateau_start: float | None = None
    if post.sum() >= 3:
        block_mm = _oscillation_block_mm(s_v[post], mu_v[post], params)
        # a window wider than the trace means the same as the trace: capped, so a hostile
        # time or distance column cannot make it allocate without bound
        block_samples = min(max(3, int(round(block_mm / step_mm))), mu_v.size + 1)
        plateau_start, tol = find_plateau_start(
            s_v[post], mu_v[post], params.run_in_mm,
            effective_noise(mu_v[post], block_samples), params, block_mm=block_mm,
        )
    settled = plateau_start is not None
    if plateau_start is None:
        end = float(s_v[-1])
        plateau_start = max(params.run_in_mm, end - params.plateau_min_mm)
        if plateau_start >= end:
            plateau_start = end / 2
    window = s_v >= plateau_start
    if window.sum() < 3:
        window = np.arange(s_v.size) >= s_v.size // 2
    return window, settled, tol


def _plateau_noise(
    mu_w: NDArray[np.float64], sigma: float, oscillating: bool
) -> tuple[float, float]:
    """The per-sample noise of the plateau's μ (shape (n,)) [COF]: its scatter about a
    quadratic trend, and that times √τ_int (its autocorrelation counted, for averages).
    Where the plateau oscillates its scatter is stick-slip, not noise: both are then
    ``sigma``, the noise from sample-to-sample differences."""
    if oscillating:
        return sigma, sigma
    resid = _detrended(mu_w)
    sample_sd = float(np.std(resid))
    return sample_sd, sample_sd * math.sqrt(uncertainty.integrated_autocorrelation_time(resid))


def _read_peak(
    mu_v: NDArray[np.float64], mu_med: NDArray[np.float64], curve: NDArray[np.float64],
    smooth: NDArray[np.float64], searched: NDArray[np.intp], *, peak_n: int, cliff_n: int,
    noise_sd: float, sample_sd: float, params: ReductionParams,
) -> tuple[int, float, float]:
    """Step 4's reading of the static peak among the ``searched`` samples: the sample,
    the value [COF] and its standard uncertainty from the noise [COF]. The maximum of the
    peak curve, re-read from as many samples as the peak's shape allows: a flank ending in
    a sudden slip (where the curve holds a flank fit) by :func:`flank_peak`, a rounded
    peak by :func:`quadratic_peak`; a fractional vertex position is returned as the
    nearest sample."""
    k = int(searched[np.argmax(curve[searched])])
    value = float(curve[k])
    u = noise_sd * math.sqrt(9.0 / (4.0 * peak_n))
    lo, hi = int(searched[0]), int(searched[-1])
    if curve[k] > smooth[k]:
        u = max(u, noise_sd * _end_point_sd(min(cliff_n, k + 1)))
        flank, width = flank_peak(mu_v, k, lo, first_window=cliff_n, noise_sd=noise_sd,
                                  sample_sd=sample_sd, gamma=params.peak_ici_gamma)
        if width > cliff_n and math.isfinite(flank):
            # never above what was measured (the flank fits' own cap, cliff_peak_curve)
            value = min(flank, float(mu_v[k - width + 1 : k + 1].max()))
            u = noise_sd * _end_point_sd(width)
        return k, value, u
    top, position, width = quadratic_peak(
        mu_med, k, lo, hi, first_half_width=peak_n // 2, noise_sd=noise_sd,
        sample_sd=sample_sd, gamma=params.peak_ici_gamma, breaks=curve > smooth,
    )
    if width > peak_n and math.isfinite(top):
        k = int(min(max(round(position), lo), hi))
        value, u = float(top), noise_sd * math.sqrt(9.0 / (4.0 * width))
    return k, value, u


def run_detection(
    s_v: np.ndarray, t_v: np.ndarray, mu_v: np.ndarray, total_mm: float, params: ReductionParams
) -> Detection:
    """Steps 1–7 of the module docstring on the valid samples: distance [mm], time [s]
    and μ, all shape (n,), in contact and moving."""
    mu_med = median_smooth(mu_v, params.median_window)
    sigma = noise_std(mu_v)
    step_mm = float(np.median(np.diff(s_v))) if s_v.size > 1 else 0.0
    if step_mm <= 0:
        step_mm = max(total_mm / max(s_v.size, 1), 1e-9)
    # windows wider than the trace act as the whole trace: capped (see _find_plateau)
    peak_n = max(5, min(int(round(params.peak_window_mm / step_mm)), s_v.size + 2) | 1)
    cliff_n = max(5, min(int(round(params.cliff_window_mm / step_mm)), s_v.size + 2))
    # noise left by a quadratic SG of width w at its centre: ~ sqrt(9 / (4 w)) σ
    sigma_peak = sigma * math.sqrt(min(1.0, 9.0 / (4.0 * peak_n)))

    # step 3: the plateau, from the trace alone (it does not depend on the peak); step 7's
    # test on it, and its noise
    window, settled, tol = _find_plateau(s_v, mu_v, step_mm, params)
    stick_slip = stick_slip_test(s_v[window], mu_v[window], params)
    oscillating = stick_slip.oscillates and stick_slip.std > params.stick_slip_min_std
    sample_sd, noise_sd = _plateau_noise(mu_v[window], sigma, oscillating)

    # step 2, the peak curve: a slip is a drop between two fits that each average many
    # samples, judged against that noise (correlated noise averages down more slowly)
    smooth = static_peak_curve(mu_med, peak_n)
    curve = cliff_peak_curve(mu_v, smooth, cliff_n, max(sigma, noise_sd), params.cliff_sigma)

    # step 4: the static peak is the maximum before the plateau (and within the cap)
    search = ~window
    if params.static_search_mm is not None:
        search &= s_v <= params.static_search_mm
    if not search.any():
        search = np.zeros(s_v.size, dtype=bool)
        search[0] = True
    searched = np.flatnonzero(search)
    k_peak, mu_peak, peak_u = _read_peak(
        mu_v, mu_med, curve, smooth, searched, peak_n=peak_n, cliff_n=cliff_n,
        noise_sd=noise_sd, sample_sd=sample_sd, params=params,
    )
    s_peak = float(s_v[k_peak])
    # a maximum at the first searched sample (within half a smoothing window, the
    # reading's resolution) may lie before the trace; at the last, beyond the search when
    # that ended at a plateau that never settled, or at a cap before the plateau (then
    # whether or not it stands out). A settled plateau holds no value as high as a
    # distinct peak, so a peak right before it lies inside the search.
    reach = peak_n // 2
    at_start = k_peak - int(searched[0]) <= reach
    at_end = int(searched[-1]) - k_peak <= reach
    on_edge = (at_start or (at_end and not settled)) and searched.size > 2 * reach + 1
    last = int(searched[-1])
    at_cap = (
        params.static_search_mm is not None and at_end
        and last + 1 < s_v.size and not window[last + 1]
    )

    # step 5: μ_K and the drift test
    mu_w = mu_v[window]
    mu_k = float(np.mean(mu_w))
    drift, drift_se = linear_slope(s_v[window], mu_w)

    # step 6: is the peak distinct from the plateau?
    plateau_high = float(np.percentile(curve[window], 99))
    prominence = mu_peak - max(plateau_high, mu_k)
    distinct = prominence > max(
        params.static_min_prominence, params.static_prominence_sigma * sigma_peak
    )
    if distinct:
        mu_s, k_s = mu_peak, k_peak
    else:
        # μ_S = μ_K; its place is where the smoothed trace first reaches μ_K
        mu_s = mu_k
        reached = np.flatnonzero(curve >= mu_k)
        k_s = int(reached[0]) if reached.size else k_peak

    return Detection(
        mu_s=float(mu_s), k_s=k_s, mu_peak=mu_peak, s_peak=s_peak,
        peak_at_limit=bool((on_edge and distinct) or at_cap),
        search_end_mm=float(s_v[searched[-1]]),
        prominence=prominence, distinct=bool(distinct), sigma_peak=sigma_peak,
        peak_reading_u=peak_u,
        mu_k=mu_k, window=window, settled=settled, tol=tol,
        plateau_std=float(np.std(mu_w, ddof=1)) if mu_w.size > 1 else 0.0,
        drift=drift, drift_se=drift_se, sigma=sigma,
        stick_slip=stick_slip, mu_med=mu_med,
    )

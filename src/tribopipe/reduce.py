"""The reduction of a pin-on-disc run: the COF trace, μ_S and μ_K with their evidence.

Physics (formulas in :mod:`tribopipe.physics`; ``n_pins`` pins of radius ``r``, R_eff)
-----------------------------------------------------------------------------------------
* contact pressure per pin ``p = (F_N / n_pins) / (π r²)``: N/mm² = MPa, ×1000 → kPa
  (1 N on three pins of r = 3 mm → 11.79 kPa);
* friction force ``F_R = M / R_eff`` (M in N·m, R_eff in m), COF ``μ = F_R / F_N``;
* sliding distance ``s = φ · R_eff`` from the deflection angle (rad × mm → mm); else the
  integral of the rotational speed; else nominal speed × time.

Signs. The rotation direction decides the signs of angle, speed and torque. Distance is
counted along the direction of travel (``s`` grows from 0); the friction force takes the
sign that makes the median offset-corrected torque of the sliding part positive. We use
that sign, not ``|M|``, so that noise around zero is not rectified into a positive bias.
A negative median normal force (compression written as negative) is flipped likewise.

Torque zero offset. A torque offset shows up as torque while the disc does not move. It is
estimated (:func:`robust_mean` of the torque: efficient on noise, deaf to spikes) from, in
this order: an explicit value; the set-up interval before the friction interval (attached
by :func:`select_friction_interval` as ``meta.torque_offset``); the
samples of the friction interval before the disc starts to move (at least
``ReductionParams.offset_min_samples``). If neither exists the offset is taken as 0 and
``parameters["torque_offset_source"]`` says it could not be estimated.

Contact. Samples with ``F_N`` below ``InstrumentConfig.contact_threshold_N`` are masked
(``in_contact`` False, ``mu`` NaN in the trace) and take no part in any statistic.

Detection of μ_S and μ_K (method ``"tribopipe-v1"``)
----------------------------------------------------
1. Light median filter (``median_window`` samples) on μ removes spikes → ``mu_smooth``.
2. Noise level σ: robust (MAD) standard deviation of the first differences of μ / √2.
3. μ_S is the static peak at the start of sliding — the maximum transmittable friction
   force before gross sliding, the reading "at the instant the block slips" of ASTM D1894
   and ISO 8295. It is the maximum, within the first ``static_search_mm`` of sliding, of
   a quadratic Savitzky–Golay smoothing of ``mu_smooth`` (``peak_window_mm`` wide: it
   averages the noise and keeps a rounded peak) capped by the running maximum of a
   3-sample moving average (so the polynomial cannot overshoot a peak that ends in a
   sudden slip). The window is short (0.015 mm ≈ 21 samples at 0.007 mm/s and 10 Hz)
   because a static peak can be sharp: wider smoothing shaves it, narrower lets the
   noise lift it (bias ≤ ~0.015 at noise 0.015 on rounded peaks). A peak that ends in a
   sudden slip would still read low (the window reaches past the slip): where the
   quadratic fit of the ``cliff_window_mm`` before a sample exceeds the fit of the
   ``cliff_window_mm`` after it by more than ``cliff_sigma`` standard deviations, the
   sample is the top of a cliff and its value is the left fit's (when higher).
4. μ_K is the mean of μ over the steady sliding plateau, the "average during uniform
   sliding" of ASTM D1894; as in ASTM D2534 the plateau starts only after a run-in
   distance (``run_in_mm``) and after the static peak. Its start is where the transient
   has settled: the post-run-in trace is cut in blocks of ``block_mm``; the plateau starts
   at the first block from which every later block mean lies within a tolerance of their
   median (tolerance = the largest of ``settle_tol``, 3× the standard error of a block
   mean, and 3× the detrended block-to-block scatter of the second half, which is what
   stick-slip produces). It ends at the end of the trace. When nothing settles, the
   last ``plateau_min_mm`` after the peak is used (and flagged).
5. Drift test: least-squares slope of μ over s in the plateau [1/mm]; a slope larger than
   ``max_drift_per_mm`` and than 3 standard errors means the plateau is not steady.
6. μ_S is *distinct* when the peak stands above the plateau's own highs (its 99th
   percentile after the same smoothing) by more than ``static_min_prominence`` and
   ``static_prominence_sigma`` × the smoothed noise. Otherwise μ_S is reported equal to
   μ_K (the peak is not resolved), placed where the smoothed trace first reaches μ_K,
   and ``static_not_distinct`` is flagged; the raw peak is kept in
   ``parameters["mu_s_peak_raw"]``. So μ_S ≥ μ_K always.

Flags (thresholds in :class:`ReductionParams`)
----------------------------------------------
``static_not_distinct``  step 6 failed.
``no_steady_state``      no plateau of at least ``plateau_min_mm`` settles (step 4), or
                         the drift test fails (step 5).
``stick_slip``           the plateau oscillates: the standard deviation of μ averaged over
                         ``stick_slip_average_s`` and detrended exceeds both
                         ``stick_slip_min_std`` and ``stick_slip_ratio`` × what white
                         noise of level σ would give.
``normal_force_unstable`` the coefficient of variation of F_N over the sliding contact
                         samples exceeds ``normal_force_cv_max``.
``short_trace``          the sliding distance is below ``run_in_mm + plateau_min_mm`` or
                         the plateau holds fewer than ``min_plateau_samples`` samples.

References: ASTM D1894 (static and kinetic COF of plastic film: static = initial peak,
kinetic = average during uniform sliding); ISO 8295 (same principle for plastics film);
ASTM D2534 (kinetic COF of wax coatings: averaging after a run-in distance).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .config import InstrumentConfig, ReductionParams
from .errors import ReductionError
from .intervals import (  # noqa: F401 - interval choice is importable from here too
    IntervalSamples,
    choose_torque_offset,
    estimate_torque_offset_Nm,
    interval_samples,
    leading_rest,
    robust_mean,
    select_friction_interval,
    setup_torque_offset_Nm,
)
from .measurement import (
    NORMAL_FORCE,
    TIME,
    TORQUE,
    Measurement,
    require_columns,
)
from .physics import (  # noqa: F401 - the formulas are importable from here too
    coefficient_of_friction,
    contact_pressure_kPa,
    distance_from_angle_mm,
    distance_from_nominal_mm,
    distance_from_speed_mm,
    friction_force_N,
    rpm_to_rad_s,
    sliding_distance_mm,
    sliding_speed_mm_s,
)
from .signals import (
    end_point_weights,
    one_sided_fits,
    running_max,
    running_mean,
    running_median,
    savgol,
)

if TYPE_CHECKING:

    import pandas as pd

METHOD = "tribopipe-v1: median filter + Savitzky-Golay static peak; settled-plateau mean"

FLAGS: tuple[str, ...] = (
    "static_not_distinct",
    "no_steady_state",
    "stick_slip",
    "normal_force_unstable",
    "short_trace",
)


@dataclass(frozen=True)
class ReductionResult:
    """μ_S and μ_K of one run with the evidence behind them.

    Distances in mm along the sliding path, times in s of the measurement's ``time_s``,
    forces in N (total on all pins), pressure in kPa per pin. ``plateau_std`` is the
    standard deviation of μ in the μ_K window (not an error of the mean);
    ``plateau_drift_per_mm`` the slope of μ over s there [1/mm]. ``trace`` has the columns
    ``time_s, sliding_distance_mm, normal_force_N, pressure_kPa, friction_force_N, mu,
    mu_smooth, in_contact`` (one row per complete sample, time-ordered; μ is NaN where
    not in contact).
    """

    mu_s: float
    mu_s_distance_mm: float
    mu_s_time_s: float
    mu_k: float
    mu_k_window_mm: tuple[float, float]
    mu_k_window_s: tuple[float, float]
    plateau_std: float
    plateau_drift_per_mm: float
    normal_force_mean_N: float
    pressure_kPa: float
    temperature_C: float | None
    sliding_speed_mm_s: float
    sliding_distance_mm: float
    flags: tuple[str, ...]
    method: str
    parameters: dict[str, Any]
    trace: pd.DataFrame = field(repr=False)


# --------------------------------------------------------------------------- signal helpers


def noise_std(mu: Any) -> float:
    """Robust white-noise level of a signal (shape (n,)): 1.4826·MAD of its first
    differences / √2. Slow trends and rare jumps (slips) hardly affect it. NaN-free input."""
    d = np.diff(np.asarray(mu, dtype=float))
    if d.size < 2:
        return 0.0
    mad = np.median(np.abs(d - np.median(d)))
    return float(1.4826 * mad / math.sqrt(2))


def median_smooth(values: Any, window: int) -> np.ndarray:
    """Running median over ``window`` samples (made odd), edges by nearest value; a new
    array of the same shape (n,). NaN-free input."""
    v = np.asarray(values, dtype=float)
    w = max(1, int(window) | 1)
    if w <= 1 or v.size < w:
        return v.copy()
    return running_median(v, w)


def peak_smooth(values: Any, window: int) -> np.ndarray:
    """Quadratic Savitzky–Golay smoothing over ``window`` samples (made odd, ≥ 5); keeps
    rounded peaks while averaging noise. A new array of shape (n,). NaN-free input."""
    v = np.asarray(values, dtype=float)
    w = max(5, int(window) | 1)
    if v.size < w:
        return v.copy()
    return savgol(v, w, 2)


def static_peak_curve(values: Any, window: int) -> np.ndarray:
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
    values: Any, smooth_curve: Any, window: int, sigma: float, cliff_sigma: float
) -> np.ndarray:
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
    sd_difference = sigma * math.sqrt(2.0 * float(np.sum(end_point_weights(w) ** 2)))
    drop = left[:-1] - right[1:]
    cliff = np.zeros(v.size, dtype=bool)
    cliff[:-1] = np.isfinite(drop) & (drop > cliff_sigma * sd_difference)
    curve[cliff] = np.maximum(curve[cliff], left[cliff])
    return curve


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


def find_plateau_start(
    s_mm: Any, mu: Any, start_mm: float, noise: float, params: ReductionParams
) -> tuple[float | None, float]:
    """Start [mm] of the settled plateau in ``mu`` over ``s_mm`` (both shape (n,), valid
    samples only) searched from ``start_mm`` on, and the tolerance used [COF].

    Returns ``(None, tol)`` when no run of blocks reaching to the end and at least
    ``plateau_min_mm`` long stays within the tolerance.
    """
    s = np.asarray(s_mm, dtype=float)
    m = np.asarray(mu, dtype=float)
    end = float(s[-1]) if s.size else start_mm
    n_blocks = int((end - start_mm) // params.block_mm)
    if n_blocks < 2:
        return None, params.settle_tol
    edges = start_mm + params.block_mm * np.arange(n_blocks + 1)
    edges[-1] = end + 1e-12
    idx = np.searchsorted(s, edges)
    counts = np.diff(idx)
    sums = np.add.reduceat(m, idx[:-1]) if m.size else np.zeros(n_blocks)
    means = np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)
    good = counts >= 3
    centres = 0.5 * (edges[:-1] + edges[1:])
    means, centres, counts = means[good], centres[good], counts[good]
    if means.size < 2:
        return None, params.settle_tol
    half = means[means.size // 2 :]
    scatter = 0.0
    if half.size >= 4:
        x = np.arange(half.size, dtype=float)
        resid = half - np.polyval(np.polyfit(x, half, 1), x)
        scatter = float(np.std(resid, ddof=2))
    se_block = noise / math.sqrt(float(np.median(counts)))
    tol = max(params.settle_tol, 3 * se_block, 3 * scatter)
    min_blocks = max(2, math.ceil(params.plateau_min_mm / params.block_mm - 1e-9))
    for k in range(means.size - min_blocks + 1):
        rest = means[k:]
        if np.all(np.abs(rest - np.median(rest)) <= tol):
            return float(centres[k] - 0.5 * params.block_mm), tol
    return None, tol


# --------------------------------------------------------------------------- the reduction


@dataclass(frozen=True)
class _Detection:
    """μ_S / μ_K detection on the valid samples (arrays of the valid samples)."""

    mu_s: float
    k_s: int
    mu_peak: float
    s_peak: float
    prominence: float
    distinct: bool
    mu_k: float
    window: np.ndarray
    settled: bool
    tol: float
    plateau_std: float
    drift: float
    drift_se: float
    sigma: float
    stick_slip_std: float
    n_average: int
    mu_med: np.ndarray


def _detect(
    s_v: np.ndarray, t_v: np.ndarray, mu_v: np.ndarray, total_mm: float, params: ReductionParams
) -> _Detection:
    """Steps 1–6 of the module docstring on the valid samples: distance [mm], time [s]
    and μ, all shape (n,), in contact and moving."""
    mu_med = median_smooth(mu_v, params.median_window)
    sigma = noise_std(mu_v)
    step_mm = float(np.median(np.diff(s_v))) if s_v.size > 1 else 0.0
    if step_mm <= 0:
        step_mm = max(total_mm / max(s_v.size, 1), 1e-9)
    peak_n = max(5, int(round(params.peak_window_mm / step_mm)) | 1)
    cliff_n = max(5, int(round(params.cliff_window_mm / step_mm)))
    curve = cliff_peak_curve(
        mu_v, static_peak_curve(mu_med, peak_n), cliff_n, sigma, params.cliff_sigma
    )
    # noise left by a quadratic SG of width w at its centre: ~ sqrt(9 / (4 w)) σ
    sigma_peak = sigma * math.sqrt(min(1.0, 9.0 / (4.0 * peak_n)))

    search = s_v <= params.static_search_mm
    if not search.any():
        search = np.arange(s_v.size) < max(1, s_v.size // 4)
    k_peak = int(np.argmax(np.where(search, curve, -np.inf)))
    mu_peak, s_peak = float(curve[k_peak]), float(s_v[k_peak])

    start_from = max(params.run_in_mm, s_peak)
    post = s_v >= start_from
    tol = params.settle_tol
    plateau_start: float | None = None
    if post.sum() >= 3:
        plateau_start, tol = find_plateau_start(s_v[post], mu_v[post], start_from, sigma, params)
    settled = plateau_start is not None
    if plateau_start is None:
        # not settled: the last plateau_min_mm after the peak (or the second half of the
        # trace when that is all there is); flagged below
        end = float(s_v[-1])
        plateau_start = max(start_from, end - params.plateau_min_mm)
        if plateau_start >= end:
            plateau_start = max(s_peak, end / 2) if s_peak < end else end / 2
    window = s_v >= plateau_start
    if window.sum() < 3:
        window = np.arange(s_v.size) >= s_v.size // 2
    mu_w = mu_v[window]
    mu_k = float(np.mean(mu_w))
    drift, drift_se = linear_slope(s_v[window], mu_w)

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

    dt_s = float(np.median(np.diff(t_v))) if t_v.size > 1 else 1.0
    n_average = max(1, int(round(params.stick_slip_average_s / max(dt_s, 1e-9))))
    ss_std = stick_slip_std(s_v[window], mu_w, n_average)
    return _Detection(
        mu_s=float(mu_s), k_s=k_s, mu_peak=mu_peak, s_peak=s_peak, prominence=prominence,
        distinct=bool(distinct), mu_k=mu_k, window=window, settled=settled, tol=tol,
        plateau_std=float(np.std(mu_w, ddof=1)) if mu_w.size > 1 else 0.0,
        drift=drift, drift_se=drift_se, sigma=sigma, stick_slip_std=ss_std,
        n_average=n_average, mu_med=mu_med,
    )


def stick_slip_std(s_mm: Any, mu: Any, n_average: int) -> float:
    """Standard deviation of μ (shape (n,)) after a moving average over ``n_average``
    samples and removal of a linear trend in s [mm]: the slow oscillation left once white
    noise is averaged out. 0 when the window is too short to tell."""
    s = np.asarray(s_mm, dtype=float)
    m = np.asarray(mu, dtype=float)
    if m.size < max(10, 3 * n_average):
        return 0.0
    averaged = np.convolve(m, np.ones(n_average) / n_average, mode="valid")
    x = s[n_average // 2 : n_average // 2 + averaged.size]
    trend = np.polyval(np.polyfit(x, averaged, 1), x)
    return float(np.std(averaged - trend))


def _flags(
    det: _Detection, s_v: np.ndarray, total_mm: float, force_cv: float,
    params: ReductionParams,
) -> list[str]:
    """The QC flags of a detection (definitions in the module docstring); ``force_cv`` is
    the normal force's coefficient of variation over the sliding contact samples."""
    flags: list[str] = []
    n_window = int(det.window.sum())
    w_s = s_v[det.window]
    short = total_mm < params.run_in_mm + params.plateau_min_mm
    if not det.distinct:
        flags.append("static_not_distinct")
    drifting = abs(det.drift) > params.max_drift_per_mm and abs(det.drift) > 3 * det.drift_se
    too_short = float(w_s[-1] - w_s[0]) < params.plateau_min_mm * 0.999
    if not det.settled or drifting or too_short:
        flags.append("no_steady_state")
    white = det.sigma / math.sqrt(det.n_average)
    # only a settled plateau can tell an oscillation from a transient
    if (
        det.settled
        and det.stick_slip_std > params.stick_slip_min_std
        and det.stick_slip_std > params.stick_slip_ratio * white
    ):
        flags.append("stick_slip")
    if force_cv > params.normal_force_cv_max:
        flags.append("normal_force_unstable")
    if short or n_window < params.min_plateau_samples:
        flags.append("short_trace")
    return flags


def _in_contact(x: IntervalSamples, instrument: InstrumentConfig, label: str) -> np.ndarray:
    """Boolean mask (shape (n,)) of the samples with F_N ≥ the contact threshold [N];
    :class:`ReductionError` when there is none."""
    threshold = instrument.contact_threshold_N
    in_contact = x.force >= threshold
    if not in_contact.any() or x.force.max() <= 0:
        raise ReductionError(
            f"{label}: the normal force never reaches the contact threshold "
            f"{threshold:g} N (largest {x.force.max():.3g} N): no contact, no friction",
            hint="check the normal-force column or lower contact_threshold_N",
        )
    return in_contact


def _travel(
    x: IntervalSamples, instrument: InstrumentConfig, params: ReductionParams, label: str
) -> tuple[np.ndarray, str, np.ndarray]:
    """Sliding distance [mm] (shape (n,)), its source (``angle``, ``speed``, ``nominal``)
    and the mask of the samples at rest before the disc moves; :class:`ReductionError`
    when a measured distance shows no rotation."""
    s, distance_source = sliding_distance_mm(
        x.t, instrument.friction_radius_mm, angle_rad=x.angle, speed_rad_s=x.speed,
        nominal_speed_rpm=instrument.nominal_speed_rpm,
    )
    if distance_source != "nominal" and float(s.max()) < params.min_travel_mm:
        raise ReductionError(
            f"{label}: no rotation: the disc travelled {float(s.max()):.3g} mm "
            f"(< {params.min_travel_mm:g} mm); this is not a friction interval"
        )
    if distance_source == "nominal":
        at_rest = np.zeros(s.size, dtype=bool)
    else:
        at_rest = leading_rest(s, params.motion_tol_mm)
    return s, distance_source, at_rest


def _mean_temperature(x: IntervalSamples, in_contact: np.ndarray) -> float | None:
    """Mean measured temperature [°C] of the contact samples (``None`` without any)."""
    temperature_mean: float | None = None
    if x.temperature is not None:
        tc = x.temperature[in_contact & np.isfinite(x.temperature)]
        temperature_mean = float(np.mean(tc)) if tc.size else None
    return temperature_mean


def _measured_speed(
    x: IntervalSamples, s: np.ndarray, at_rest: np.ndarray, instrument: InstrumentConfig
) -> float:
    """Mean sliding speed [mm/s] while moving; the nominal speed when it cannot be told."""
    moving_t, moving_s = x.t[~at_rest], s[~at_rest]
    if moving_t.size >= 2 and moving_t[-1] > moving_t[0]:
        return float((moving_s[-1] - moving_s[0]) / (moving_t[-1] - moving_t[0]))
    return instrument.nominal_sliding_speed_mm_s


def _trace_frame(
    x: IntervalSamples, s: np.ndarray, f_r: np.ndarray, mu: np.ndarray, in_contact: np.ndarray,
    idx: np.ndarray, det: _Detection, instrument: InstrumentConfig,
) -> pd.DataFrame:
    """The reduced trace (columns of :class:`ReductionResult`), one row per sample."""
    import pandas as pd

    mu_smooth = np.full(x.t.size, np.nan)
    mu_smooth[idx] = det.mu_med
    return pd.DataFrame(
        {
            "time_s": x.t,
            "sliding_distance_mm": s,
            "normal_force_N": x.force,
            "pressure_kPa": contact_pressure_kPa(x.force, instrument.n_pins,
                                                 instrument.pin_radius_mm),
            "friction_force_N": f_r,
            "mu": mu,
            "mu_smooth": mu_smooth,
            "in_contact": in_contact,
        }
    )


def _parameters(
    params: ReductionParams, instrument: InstrumentConfig, x: IntervalSamples, det: _Detection, *,
    distance_source: str, offset: float, offset_source: str, torque_sign: float,
    cv: float, in_contact: np.ndarray,
) -> dict[str, Any]:
    """``ReductionResult.parameters``: the method's parameters and the diagnostics of
    this run."""
    parameters: dict[str, Any] = dict(asdict(params))
    parameters.update(
        {
            "contact_threshold_N": instrument.contact_threshold_N,
            "friction_radius_mm": instrument.friction_radius_mm,
            "n_pins": instrument.n_pins,
            "pin_radius_mm": instrument.pin_radius_mm,
            "distance_source": distance_source,
            "torque_offset_Nm": offset,
            "torque_offset_source": offset_source,
            "torque_sign": torque_sign,
            "normal_force_sign": x.force_sign,
            "noise_std": det.sigma,
            "settle_tolerance": det.tol,
            "plateau_settled": det.settled,
            "plateau_drift_se_per_mm": det.drift_se if math.isfinite(det.drift_se) else None,
            "mu_s_peak_raw": det.mu_peak,
            "mu_s_peak_distance_mm": det.s_peak,
            "static_prominence": det.prominence,
            "stick_slip_std": det.stick_slip_std,
            "normal_force_cv": cv,
            "n_samples": x.n_total,
            "n_dropped_incomplete": x.n_dropped,
            "n_in_contact": int(in_contact.sum()),
            "n_plateau": int(det.window.sum()),
        }
    )
    return parameters


def reduce_measurement(
    m: Measurement,
    instrument: InstrumentConfig,
    params: ReductionParams,
    *,
    torque_offset_Nm: float | None = None,
) -> ReductionResult:
    """Reduce one friction interval to μ_S and μ_K with their evidence (see module doc).

    ``m.data`` needs ``time_s`` [s], ``torque_Nm`` [N·m], ``normal_force_N`` [N] and uses
    ``angle_rad`` or ``speed_rad_s`` (else the nominal speed) and ``temperature_C`` when
    present. ``torque_offset_Nm`` [N·m] overrides the offset estimate. ``m`` is not
    modified.

    Raises :class:`ReductionError` (naming ``m.meta.label``) for zero normal force, more
    than half of torque or normal force missing, no rotation, or too few contact samples.
    """
    require_columns(m, TIME, TORQUE, NORMAL_FORCE)
    label = m.meta.label
    x = interval_samples(m, params)
    in_contact = _in_contact(x, instrument, label)
    s, distance_source, at_rest = _travel(x, instrument, params, label)
    total_mm = float(s[-1] - s[0])
    offset, offset_source = choose_torque_offset(m, x, at_rest, torque_offset_Nm, params)

    corrected = x.torque - offset
    sliding = ~at_rest & in_contact
    n_sliding = int(sliding.sum())
    if n_sliding < params.min_contact_samples:
        raise ReductionError(
            f"{label}: only {n_sliding} samples in contact "
            f"(F_N ≥ {instrument.contact_threshold_N:g} N) while "
            f"sliding; need at least {params.min_contact_samples}"
        )
    torque_sign = -1.0 if np.median(corrected[sliding]) < 0 else 1.0
    f_r = torque_sign * friction_force_N(corrected, instrument.friction_radius_mm)
    mu = np.where(in_contact, coefficient_of_friction(f_r, x.force), np.nan)

    idx = np.flatnonzero(sliding)
    s_v, t_v, mu_v = s[idx], x.t[idx], mu[idx]
    det = _detect(s_v, t_v, mu_v, total_mm, params)
    f_slide = x.force[sliding]
    f_mean = float(np.mean(f_slide))
    cv = float(np.std(f_slide) / f_mean) if f_mean > 0 else math.inf
    flags = _flags(det, s_v, total_mm, cv, params)

    w_s, w_t = s_v[det.window], t_v[det.window]
    return ReductionResult(
        mu_s=det.mu_s,
        mu_s_distance_mm=float(s_v[det.k_s]),
        mu_s_time_s=float(t_v[det.k_s]),
        mu_k=det.mu_k,
        mu_k_window_mm=(float(w_s[0]), float(w_s[-1])),
        mu_k_window_s=(float(w_t[0]), float(w_t[-1])),
        plateau_std=det.plateau_std,
        plateau_drift_per_mm=float(det.drift),
        normal_force_mean_N=f_mean,
        pressure_kPa=float(
            contact_pressure_kPa(f_mean, instrument.n_pins, instrument.pin_radius_mm)
        ),
        temperature_C=_mean_temperature(x, in_contact),
        sliding_speed_mm_s=_measured_speed(x, s, at_rest, instrument),
        sliding_distance_mm=total_mm,
        flags=tuple(f for f in FLAGS if f in flags),
        method=METHOD,
        parameters=_parameters(
            params, instrument, x, det, distance_source=distance_source, offset=offset,
            offset_source=offset_source, torque_sign=torque_sign, cv=cv,
            in_contact=in_contact,
        ),
        trace=_trace_frame(x, s, f_r, mu, in_contact, idx, det, instrument),
    )

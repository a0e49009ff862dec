"""The reduction of one run: ``reduce_measurement`` → ``ReductionResult``.

The method (its steps, parameters and flags) is described once, in the docstring of
:mod:`tribopipe.reduction`; this module carries it out in short steps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from ..config import REDUCTION_METHOD, InstrumentConfig, ReductionParams
from ..errors import MissingQuantityError, ReductionError
from ..measurement import (
    NORMAL_FORCE,
    TIME,
    TORQUE,
    Measurement,
    MeasurementMeta,
    require_columns,
)
from ..physics import (
    coefficient_of_friction,
    contact_pressure_kPa,
    friction_force_N,
    sliding_distance_mm,
)
from ..validate import FORCE_N, MU, TEMPERATURE_C
from . import uncertainty
from .detection import (
    Detection,
    noise_std,
    run_detection,
    static_peak_curve,
)
from .intervals import (
    IntervalSamples,
    ZeroChoice,
    choose_zero,
    end_stop,
    interval_samples,
    leading_rest,
    tangential_column,
    trailing_rest,
)
from .parameters import (
    Budgets,
    InstrumentSide,
    ReciprocatingParameters,
    RotaryParameters,
)
from .reciprocating import reciprocating_cycles, stroke_path

if TYPE_CHECKING:

    import pandas as pd


METHOD = (
    f"{REDUCTION_METHOD}: settled-plateau mean; static peak = maximum before the plateau "
    "(median filter + Savitzky-Golay, cliff fits, widening quadratics); periodic-line "
    "stick-slip test"
)

FLAGS: tuple[str, ...] = (
    "no_friction_signal",
    "static_not_distinct",
    "peak_at_search_limit",
    "no_steady_state",
    "plateau_at_trace_end",
    "stick_slip",
    "normal_force_unstable",
    "short_trace",
    "torque_offset_unknown",
    "zero_under_load",
    "zero_drift",
    "run_out",
)

#: the lever of a force channel [mm]: a friction force F [N] read as a torque F·1 m, so
#: that one set of formulas serves both channels (F_R = M / R with R = 1 m exactly)
FORCE_LEVER_MM = 1000.0


@dataclass(frozen=True)
class ReductionResult:
    """μ_S and μ_K of one run with the evidence behind them.

    Distances in mm along the sliding path, times in s of the measurement's ``time_s``,
    forces in N (total on all pins), pressure in kPa per pin. ``plateau_std`` is the
    standard deviation of μ in the μ_K window (not an error of the mean);
    ``plateau_drift_per_mm`` the slope of μ over s there [1/mm]. ``u_mu_k`` and
    ``u_mu_s`` are the combined standard uncertainties (GUM, k = 1) of μ_K and μ_S, their
    budgets in ``parameters.uncertainty`` (:mod:`tribopipe.reduction.uncertainty`);
    ``parameters`` is typed per method (:mod:`tribopipe.reduction.parameters`). ``trace`` has
    the columns ``time_s, sliding_distance_mm, normal_force_N, pressure_kPa,
    friction_force_N, mu, mu_smooth, in_contact`` (one row per complete sample,
    time-ordered; μ is NaN where not in contact).
    """

    mu_s: float
    mu_s_distance_mm: float
    mu_s_time_s: float
    mu_k: float
    mu_k_window_mm: tuple[float, float]
    mu_k_window_s: tuple[float, float]
    plateau_std: float
    plateau_drift_per_mm: float
    u_mu_k: float
    u_mu_s: float
    normal_force_mean_N: float
    pressure_kPa: float
    temperature_C: float | None
    sliding_speed_mm_s: float
    sliding_distance_mm: float
    flags: tuple[str, ...]
    method: str
    parameters: RotaryParameters | ReciprocatingParameters
    trace: pd.DataFrame = field(repr=False)
    #: the interval's rotational-speed set point [rpm]: the median |rotational speed| of
    #: the moving samples; ``None`` where the export has no speed column
    speed_set_point_rpm: float | None = None


def _flags(
    det: Detection, s_v: np.ndarray, total_mm: float, force_cv: float,
    offset_known: bool, params: ReductionParams, *, no_signal: bool = False,
    zero: ZeroChoice | None = None, run_out: bool = False,
) -> list[str]:
    """The QC flags of a detection (definitions in the module docstring); ``force_cv`` is
    the normal force's coefficient of variation over the sliding contact samples,
    ``offset_known`` whether the torque zero offset could be estimated or was given,
    ``no_signal`` whether the torque carries no friction, ``zero`` the zero's choice,
    ``run_out`` whether the plateau's oscillation is locked to the rotation."""
    flags: list[str] = ["no_friction_signal"] if no_signal else []
    n_window = int(det.window.sum())
    w_s = s_v[det.window]
    short = total_mm < params.run_in_mm + params.plateau_min_mm
    if not det.distinct:
        flags.append("static_not_distinct")
    if det.peak_at_limit:
        flags.append("peak_at_search_limit")
    drifting = abs(det.drift) > params.max_drift_per_mm and abs(det.drift) > 3 * det.drift_se
    length = float(w_s[-1] - w_s[0])
    too_short = length < params.plateau_min_mm * 0.999
    if not det.settled or drifting or too_short:
        flags.append("no_steady_state")
    if not det.settled or length < params.plateau_confirm_mm * 0.999:
        flags.append("plateau_at_trace_end")
    # only a settled plateau can tell an oscillation from a transient
    if (
        det.settled
        and det.stick_slip.oscillates
        and det.stick_slip.std > params.stick_slip_min_std
    ):
        flags.append("run_out" if run_out else "stick_slip")
    if force_cv > params.normal_force_cv_max:
        flags.append("normal_force_unstable")
    if short or n_window < params.min_plateau_samples:
        flags.append("short_trace")
    if not offset_known and not (zero is not None and zero.under_load):
        flags.append("torque_offset_unknown")
    if zero is not None and zero.under_load:
        flags.append("zero_under_load")
    if zero is not None and zero.disagree:
        flags.append("zero_drift")
    return flags


def force_lever(instrument: InstrumentConfig) -> InstrumentConfig:
    """The instrument as the torque formulas and the uncertainty budget see a force
    channel: the friction force F [N] is a torque F·1 m at an exact lever of
    :data:`FORCE_LEVER_MM` (u = 0), with the force channel's calibration, resolution and
    unknown-zero size in the torque's place (N × 1 m = N·m)."""
    return replace(
        instrument, friction_radius_mm=FORCE_LEVER_MM, friction_radius_u_mm=0.0,
        torque_u_rel=instrument.friction_force_u_rel,
        torque_resolution_Nm=instrument.friction_force_resolution_N,
        torque_offset_unknown_Nm=instrument.friction_force_offset_unknown_N,
    )


def with_sled_force(m: Measurement, instrument: InstrumentConfig) -> tuple[Measurement, str]:
    """``m`` with its normal force, and where it came from: ``"measured"``, or, for a run
    without a normal-force column, the sled's weight (``sled_mass_g`` · g or
    ``sled_weight_N``) as a constant column. :class:`MissingQuantityError` when neither
    exists."""
    if m.has(NORMAL_FORCE):
        return m, "measured"
    weight = instrument.sled_normal_force_N
    if weight is None:
        require_columns(m, NORMAL_FORCE)  # raises, naming the columns found
        raise MissingQuantityError(f"{m.meta.label}: no normal force")  # pragma: no cover
    data = m.data.copy()
    data[NORMAL_FORCE] = weight
    source = (f"sled weight {instrument.sled_weight_N:g} N" if instrument.sled_weight_N
              is not None else f"sled mass {instrument.sled_mass_g:g} g × g = {weight:.6g} N")
    return Measurement(data=data, meta=m.meta), source


def revolution_locked(period_mm: float, window_mm: float, revolution_mm: float | None,
                      tolerance: float) -> bool:
    """Whether an oscillation of period ``period_mm`` [mm], seen over ``window_mm`` [mm]
    of sliding, is locked to the rotation: its period lies within ``tolerance`` (relative)
    plus the periodogram's resolution (one cycle over the window: period/window) of one
    revolution ``revolution_mm`` [mm] or of its 2nd or 3rd harmonic. Run-out (a disc not
    flat, a pin not centred) repeats with every turn; stick-slip has its own period."""
    if revolution_mm is None or not (math.isfinite(period_mm) and period_mm > 0):
        return False
    slack = tolerance + period_mm / window_mm if window_mm > 0 else tolerance
    return any(abs(period_mm / (revolution_mm / h) - 1.0) <= slack for h in (1, 2, 3))


def _check_physical(meta: MeasurementMeta, force_N: float, temperature_C: float | None,
                    det: Detection) -> None:
    """:class:`ReductionError` when the measured mean normal force [N], temperature [°C],
    μ_K or μ_S lies outside its physical range (:mod:`tribopipe.validate`)."""
    for what, value, bounds in (("mean normal force", force_N, FORCE_N), ("mu_k", det.mu_k, MU),
                                ("mean temperature", temperature_C, TEMPERATURE_C),
                                ("mu_s", det.mu_s, MU)):
        if value is not None and value not in bounds:
            raise ReductionError(
                f"measured {what} {value:.4g} is outside the physical range "
                f"({bounds.describe()}): the column is not what its name and unit say",
                hint="check the export's columns and units",
                path=meta.source_file, place=meta.place,
            )


def _in_contact(x: IntervalSamples, instrument: InstrumentConfig,
                meta: MeasurementMeta) -> np.ndarray:
    """Boolean mask (shape (n,)) of the samples with F_N ≥ the contact threshold [N];
    :class:`ReductionError` when there is none."""
    threshold = instrument.contact_threshold_N
    in_contact = x.force >= threshold
    if not in_contact.any() or x.force.max() <= 0:
        raise ReductionError(
            f"the normal force never reaches the contact threshold "
            f"{threshold:g} N (largest {x.force.max():.3g} N): no contact, no friction",
            hint="check the normal-force column or lower contact_threshold_N",
            path=meta.source_file, place=meta.place,
        )
    return in_contact


def _travel(
    x: IntervalSamples, instrument: InstrumentConfig, params: ReductionParams,
    meta: MeasurementMeta,
) -> tuple[np.ndarray, str, np.ndarray]:
    """Sliding distance [mm] (shape (n,)), its source (``position``, ``angle``,
    ``speed``, ``nominal``) and the mask of the samples at rest before the disc moves;
    :class:`ReductionError` when a measured distance shows no rotation. A position,
    crosshead or distance column [m] gives the distance directly (counted along the
    direction of travel); a linear instrument without one slides at
    ``nominal_speed_mm_s``."""
    if x.position is not None and np.isfinite(x.position).sum() >= 2:
        ok = np.isfinite(x.position)
        pos = np.interp(x.t, x.t[ok], x.position[ok]) if not ok.all() else x.position
        travel = (pos - pos[0]) * 1e3
        s = travel if travel[-1] >= 0 else -travel
        distance_source = "position"
    elif instrument.nominal_speed_mm_s is not None and x.angle is None and x.speed is None:
        s = (x.t - x.t[0]) * float(instrument.nominal_speed_mm_s)
        distance_source = "nominal"
    else:
        s, distance_source = sliding_distance_mm(
            x.t, instrument.friction_radius_mm, angle_rad=x.angle, speed_rad_s=x.speed,
            nominal_speed_rpm=instrument.nominal_speed_rpm,
        )
    if not np.isfinite(s).all():
        raise ReductionError(
            f"the sliding distance from the {distance_source} column is not finite "
            "(values too large for their unit?)",
            hint="check the angle or speed column and its unit",
            path=meta.source_file, place=meta.place,
        )
    if distance_source != "nominal" and float(s.max()) < params.min_travel_mm:
        what = ("no sliding: the position moved" if distance_source == "position" else
                "no rotation: the disc travelled")
        raise ReductionError(
            f"{what} {float(s.max()):.3g} mm "
            f"(< {params.min_travel_mm:g} mm); this is not a friction interval",
            path=meta.source_file, place=meta.place,
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


def _speed_set_point_rpm(x: IntervalSamples, at_rest: np.ndarray) -> float | None:
    """The interval's rotational-speed set point [rpm]: the median |rotational speed| of
    the samples after the leading rest (all samples where none is at rest); ``None``
    without a speed column or a positive median."""
    if x.speed is None:
        return None
    moving = x.speed[~at_rest] if (~at_rest).any() else x.speed
    moving = np.abs(moving[np.isfinite(moving)])
    if not moving.size:
        return None
    rpm = float(np.median(moving)) * 60.0 / (2.0 * math.pi)
    return rpm if rpm > 0 else None


def _trace_frame(
    x: IntervalSamples, s: np.ndarray, f_r: np.ndarray, mu: np.ndarray, in_contact: np.ndarray,
    idx: np.ndarray, det: Detection, instrument: InstrumentConfig,
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
    params: ReductionParams, instrument: InstrumentConfig, x: IntervalSamples, det: Detection, *,
    distance_source: str, offset: float, offset_source: str, torque_sign: float,
    cv: float, in_contact: np.ndarray, uncertainties: Budgets, side: InstrumentSide,
) -> RotaryParameters:
    """``ReductionResult.parameters`` of a run over one sliding path: the method's
    settings, the diagnostics of this run, its uncertainty budgets (``uncertainties``)
    and the instrument's side (``side``)."""
    return RotaryParameters(
        settings=params,
        instrument=side,
        uncertainty=uncertainties,
        contact_threshold_N=instrument.contact_threshold_N,
        friction_radius_mm=instrument.friction_radius_mm,
        n_pins=instrument.n_pins,
        pin_radius_mm=instrument.pin_radius_mm,
        distance_source=distance_source,
        torque_offset_Nm=offset,
        torque_offset_source=offset_source,
        torque_sign=torque_sign,
        normal_force_sign=x.force_sign,
        noise_std=det.sigma,
        settle_tolerance=det.tol,
        plateau_settled=det.settled,
        plateau_drift_se_per_mm=det.drift_se if math.isfinite(det.drift_se) else None,
        mu_s_peak_raw=det.mu_peak,
        mu_s_peak_distance_mm=det.s_peak,
        static_prominence=det.prominence,
        mu_s_search_end_mm=det.search_end_mm,
        stick_slip_line_ratio=det.stick_slip.ratio,
        stick_slip_line_threshold=det.stick_slip.threshold,
        stick_slip_std=det.stick_slip.std,
        stick_slip_period_mm=(
            det.stick_slip.period_mm if math.isfinite(det.stick_slip.period_mm) else None
        ),
        normal_force_cv=cv,
        n_samples=x.n_total,
        n_dropped_incomplete=x.n_dropped,
        n_in_contact=int(in_contact.sum()),
        n_plateau=int(det.window.sum()),
    )


def reduce_measurement(
    m: Measurement,
    instrument: InstrumentConfig,
    params: ReductionParams,
    *,
    torque_offset_Nm: float | None = None,
) -> ReductionResult:
    """Reduce one friction interval to μ_S and μ_K with their evidence (see module doc).

    ``m.data`` needs ``time_s`` [s], a tangential reading — ``torque_Nm`` [N·m] (a
    rheometer) or ``friction_force_N`` [N] (a force-based tribometer) — and
    ``normal_force_N`` [N] (or, for a sled, ``instrument.sled_mass_g``); it uses
    ``position_m``, ``angle_rad`` or ``speed_rad_s`` (else the nominal speed) and
    ``temperature_C`` when present. ``torque_offset_Nm`` [N·m, or N for a friction force]
    overrides ``instrument.zero_offset``. A ``"linear reciprocating"`` instrument is
    reduced stroke by stroke (:mod:`tribopipe.reduction.reciprocating`). ``m`` is not
    modified.

    Raises :class:`ReductionError` (naming the file and the interval's place) for zero
    normal force, more than half of torque or normal force missing, no rotation, or too
    few contact samples.
    """
    tangential = tangential_column(m)
    m, normal_force_source = with_sled_force(m, instrument)
    require_columns(m, TIME, tangential, NORMAL_FORCE)
    lever = instrument if tangential == TORQUE else force_lever(instrument)
    meta = m.meta
    x = interval_samples(m, params, tangential)
    in_contact = _in_contact(x, instrument, meta)
    if instrument.test_method == "linear reciprocating":
        return _reduce_reciprocating(m, x, in_contact, instrument, lever, params,
                                     torque_offset_Nm, normal_force_source)
    s, distance_source, at_rest = _travel(x, instrument, params, m.meta)
    total_mm = float(s[-1] - s[0])
    stop = end_stop(x.t, s, ~at_rest, params.stop_speed_fraction) & ~at_rest
    sliding = ~at_rest & ~stop & in_contact
    after = (trailing_rest(s, params.motion_tol_mm) & ~at_rest
             if instrument.rest_after_sliding else None)
    f_guess = float(np.mean(x.force[sliding])) if sliding.any() else 1.0
    given = torque_offset_Nm if torque_offset_Nm is not None else instrument.zero_offset
    zero = choose_zero(
        m, x, at_rest, given, params, unknown_u=uncertainty.unknown_offset_u_Nm(lever),
        sliding=sliding, after=after, lever_N_per_unit=1.0 / (lever.friction_radius_mm * 1e-3),
        force_N=f_guess,
    )
    offset, offset_source, offset_u = zero.offset, zero.source, zero.u

    corrected = x.torque - offset
    n_sliding = int(sliding.sum())
    if n_sliding < params.min_contact_samples:
        raise ReductionError(
            f"only {n_sliding} samples in contact "
            f"(F_N ≥ {instrument.contact_threshold_N:g} N) while "
            f"sliding; need at least {params.min_contact_samples}",
            path=meta.source_file, place=meta.place,
        )
    torque_sign = -1.0 if np.median(corrected[sliding]) < 0 else 1.0
    f_r = torque_sign * friction_force_N(corrected, lever.friction_radius_mm)
    mu = np.where(in_contact, coefficient_of_friction(f_r, x.force), np.nan)

    idx = np.flatnonzero(sliding)
    s_v, t_v, mu_v = s[idx], x.t[idx], mu[idx]
    det = run_detection(s_v, t_v, mu_v, total_mm, params)
    f_slide = x.force[sliding]
    f_mean = float(np.mean(f_slide))
    cv = float(np.std(f_slide) / f_mean) if f_mean > 0 else math.inf
    temperature = _mean_temperature(x, in_contact)
    _check_physical(m.meta, f_mean, temperature, det)
    se_k, tau = uncertainty.mean_standard_error(mu_v[det.window])
    no_signal = bool(np.ptp(x.torque[sliding]) == 0) or det.mu_k <= 3 * se_k
    w_s, w_t = s_v[det.window], t_v[det.window]
    revolution = _revolution_mm(instrument, distance_source)
    run_out = revolution_locked(det.stick_slip.period_mm, float(w_s[-1] - w_s[0]), revolution,
                                params.run_out_tolerance)
    flags = _flags(det, s_v, total_mm, cv, zero.known, params, no_signal=no_signal,
                   zero=zero, run_out=run_out)
    u_k = uncertainty.budget(det.mu_k, se_k, normal_force_N=f_mean, instrument=lever,
                             offset_u_Nm=offset_u)
    u_s = u_k
    if det.distinct:
        u_s = uncertainty.budget(det.mu_s, det.peak_reading_u, normal_force_N=f_mean,
                                 instrument=lever, offset_u_Nm=offset_u)
    uncertainties = Budgets(
        mu_k=u_k,
        mu_s=u_s,
        plateau_tau_int_samples=tau,
        torque_offset_u_Nm=offset_u,
        friction_radius_u_mm=lever.friction_radius_u_mm,
        terms=uncertainty.budget_terms(normal_force_N=f_mean, instrument=lever,
                                       offset_u_Nm=offset_u),
    )
    parameters = _parameters(
        params, instrument, x, det, distance_source=distance_source, offset=offset,
        offset_source=offset_source, torque_sign=torque_sign, cv=cv,
        in_contact=in_contact, uncertainties=uncertainties,
        side=_instrument_side(instrument, tangential, normal_force_source, zero, s, stop,
                              revolution, run_out and "run_out" in flags),
    )
    return ReductionResult(
        mu_s=det.mu_s,
        mu_s_distance_mm=float(s_v[det.k_s]),
        mu_s_time_s=float(t_v[det.k_s]),
        mu_k=det.mu_k,
        mu_k_window_mm=(float(w_s[0]), float(w_s[-1])),
        mu_k_window_s=(float(w_t[0]), float(w_t[-1])),
        plateau_std=det.plateau_std,
        plateau_drift_per_mm=float(det.drift),
        u_mu_k=float(u_k["combined"]),
        u_mu_s=float(u_s["combined"]),
        normal_force_mean_N=f_mean,
        pressure_kPa=float(
            contact_pressure_kPa(f_mean, instrument.n_pins, instrument.pin_radius_mm)
        ),
        temperature_C=temperature,
        sliding_speed_mm_s=_measured_speed(x, s, at_rest | stop, instrument),
        sliding_distance_mm=total_mm,
        flags=tuple(f for f in FLAGS if f in flags),
        method=METHOD,
        parameters=parameters,
        trace=_trace_frame(x, s, f_r, mu, in_contact, idx, det, instrument),
        speed_set_point_rpm=_speed_set_point_rpm(x, at_rest),
    )


def _revolution_mm(instrument: InstrumentConfig, distance_source: str) -> float | None:
    """One revolution's sliding distance [mm], 2π·R, for a rotating instrument (the
    rheometer's cell, a rotary tribometer); ``None`` for a sled or a linear stroke."""
    if instrument.test_method in ("rheometer pin-on-disc", "rotary pin-on-disc"):
        return 2.0 * math.pi * instrument.friction_radius_mm
    return None


def _instrument_side(
    instrument: InstrumentConfig, tangential: str, normal_force_source: str, zero: ZeroChoice,
    s: np.ndarray, stop: np.ndarray, revolution_mm: float | None, run_out: bool,
) -> InstrumentSide:
    """The diagnostics of the instrument's side of a run: its method and channel, where
    the normal force and the zero came from, a stop trimmed at the end, the rotation."""
    trimmed = float(s[-1] - s[int(np.argmax(stop))]) if stop.any() else 0.0
    return InstrumentSide(
        test_method=instrument.test_method,
        tangential_channel=tangential,
        normal_force_source=normal_force_source,
        zero_load_fraction=zero.load_fraction,
        zero_second=zero.second,
        end_stop_samples=int(stop.sum()),
        end_stop_trimmed_mm=trimmed,
        revolution_mm=revolution_mm,
        run_out=run_out,
    )


def _reduce_reciprocating(
    m: Measurement, x: IntervalSamples, in_contact: np.ndarray, instrument: InstrumentConfig,
    lever: InstrumentConfig, params: ReductionParams, given: float | None,
    normal_force_source: str,
) -> ReductionResult:
    """A linear reciprocating run (ASTM G133), stroke by stroke: the module docstring of
    :mod:`tribopipe.reduction`, "Reciprocating runs"."""
    label = m.meta.label
    lever_m = lever.friction_radius_mm * 1e-3
    p, s, at_rest = stroke_path(x, label, params.motion_tol_mm)
    moving = ~at_rest & in_contact
    f_guess = float(np.mean(x.force[moving])) if moving.any() else 1.0
    zero = choose_zero(
        m, x, at_rest, given if given is not None else instrument.zero_offset, params,
        unknown_u=uncertainty.unknown_offset_u_Nm(lever), sliding=None,
        lever_N_per_unit=1.0 / lever_m, force_N=f_guess,
    )
    c = reciprocating_cycles(x, p, s, at_rest, in_contact, zero.offset, lever_m,
                             params.stroke_core_fraction, label)
    total_mm = float(s[-1] - s[0])
    det = run_detection(c.s_cycle_mm, c.t_cycle_s, c.mu_cycle, total_mm, params)
    window = det.window
    mu_k = float(np.mean(c.mu_cycle[window]))
    se_k, tau = uncertainty.mean_standard_error(c.mu_cycle[window])
    in_window = [row for row, w in zip(c.table, window, strict=True) if w]
    # μ_S: the breakaway of the first stroke, the static peak before the pin first slides
    head = c.first_stroke
    mu_head = c.mu[head]
    sigma = noise_std(mu_head) if head.size > 2 else 0.0
    curve = static_peak_curve(mu_head, 5) if head.size >= 5 else mu_head
    k_rel = int(np.argmax(curve)) if head.size else 0
    mu_peak = float(curve[k_rel]) if head.size else math.nan
    prominence = mu_peak - max(c.first_level, mu_k)
    sigma_peak = sigma * math.sqrt(9.0 / 20.0)
    distinct = bool(prominence > max(params.static_min_prominence,
                                     params.static_prominence_sigma * sigma_peak))
    mu_s = mu_peak if distinct else mu_k
    k_s = int(head[k_rel]) if head.size else 0
    sliding = ~at_rest & in_contact
    f_slide = x.force[sliding]
    f_mean = float(np.mean([row.normal_force_N for row in c.table]))
    cv = float(np.std(f_slide) / np.mean(f_slide))
    temperature = _mean_temperature(x, in_contact)
    flag_det = replace(det, mu_k=mu_k, mu_s=mu_s, distinct=distinct, peak_at_limit=False)
    _check_physical(m.meta, f_mean, temperature, flag_det)
    no_signal = bool(np.ptp(x.torque[sliding]) == 0) or mu_k <= 3 * se_k
    flags = _flags(flag_det, c.s_cycle_mm, total_mm, cv, True, params, no_signal=no_signal,
                   zero=replace(zero, under_load=False))
    # each cycle's forward − backward mean holds no zero: no offset term for μ_K
    u_k = uncertainty.budget(mu_k, se_k, normal_force_N=f_mean, instrument=lever,
                             offset_u_Nm=0.0)
    u_s = u_k if not distinct else uncertainty.budget(
        mu_s, sigma_peak, normal_force_N=f_mean, instrument=lever, offset_u_Nm=zero.u)
    w_s, w_t = c.s_cycle_mm[window], c.t_cycle_s[window]
    import pandas as pd

    trace = pd.DataFrame({
        "time_s": x.t, "sliding_distance_mm": s, "normal_force_N": x.force,
        "pressure_kPa": contact_pressure_kPa(x.force, instrument.n_pins,
                                             instrument.pin_radius_mm),
        "friction_force_N": c.friction_N, "mu": c.mu,
        "mu_smooth": np.full(x.t.size, np.nan), "in_contact": in_contact,
    })
    parameters = ReciprocatingParameters(
        settings=params,
        instrument=_instrument_side(instrument, tangential_column(m), normal_force_source,
                                    zero, s, np.zeros(s.size, dtype=bool), None, False),
        uncertainty=Budgets(mu_k=u_k, mu_s=u_s, plateau_tau_int_samples=tau,
                            torque_offset_u_Nm=0.0),
        distance_source="position (strokes)",
        torque_offset_Nm=zero.offset,
        torque_offset_source=zero.source + " (per stroke only: each cycle's forward − "
                                           "backward mean cancels it)",
        friction_sign=c.sign,
        n_strokes=c.n_strokes,
        n_cycles=len(c.table),
        stroke_length_mm=c.stroke_length_mm,
        mu_k_forward=float(np.mean([row.mu_forward for row in in_window])),
        mu_k_backward=float(np.mean([row.mu_backward for row in in_window])),
        cycles=c.table,
        plateau_first_cycle=int(np.flatnonzero(window)[0]) + 1,
        plateau_settled=det.settled,
        mu_s_peak_raw=mu_peak,
        static_prominence=prominence,
        normal_force_cv=cv,
        n_samples=x.n_total,
    )
    moving_t, moving_s = x.t[~at_rest], s[~at_rest]
    speed = (float((moving_s[-1] - moving_s[0]) / (moving_t[-1] - moving_t[0]))
             if moving_t.size >= 2 and moving_t[-1] > moving_t[0]
             else instrument.nominal_sliding_speed_mm_s)
    return ReductionResult(
        mu_s=float(mu_s), mu_s_distance_mm=float(s[k_s]), mu_s_time_s=float(x.t[k_s]),
        mu_k=mu_k, mu_k_window_mm=(float(w_s[0]), float(w_s[-1])),
        mu_k_window_s=(float(w_t[0]), float(w_t[-1])),
        plateau_std=float(np.std(c.mu_cycle[window], ddof=1)) if window.sum() > 1 else 0.0,
        plateau_drift_per_mm=float(det.drift),
        u_mu_k=float(u_k["combined"]), u_mu_s=float(u_s["combined"]),
        normal_force_mean_N=f_mean,
        pressure_kPa=float(contact_pressure_kPa(f_mean, instrument.n_pins,
                                                instrument.pin_radius_mm)),
        temperature_C=temperature, sliding_speed_mm_s=speed, sliding_distance_mm=total_mm,
        flags=tuple(f for f in FLAGS if f in flags),
        method=METHOD + "; reciprocating (ASTM G133): μ per cycle = (forward − backward)/2 "
        "over each stroke's core, plateau over cycles",
        parameters=parameters, trace=trace, speed_set_point_rpm=None,
    )

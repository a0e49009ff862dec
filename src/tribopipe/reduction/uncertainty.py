"""Standard uncertainty (GUM, k = 1) of a run's μ_K and μ_S.

The measurand is μ = (M − M₀) / (R_eff · F_N) averaged over the plateau (μ_K) or read at
the static peak (μ_S). Its combined standard uncertainty is the root sum of squares of
uncorrelated contributions, each in COF units (sensitivity × standard uncertainty):

``reading``            μ_K: the standard error of the plateau mean, with the samples'
                       autocorrelation (:func:`mean_standard_error`: n/τ_int effective
                       samples, not σ/√n of correlated samples). μ_S: the scatter of the
                       peak curve about its trend over the plateau, i.e. how much the
                       smoothed reading moves with this run's noise.
``friction_radius``    μ · u(R_eff)/R_eff: μ ∝ 1/R_eff. The founding R_eff = 13.37 mm comes
                       from "0.005 rpm ↔ 0.007 mm/s", one significant figure: 0.007 may be
                       anything in [0.0065, 0.0075), so R_eff in [12.4, 14.3) mm,
                       rectangular, u = 0.55 mm (4.1 %). Unless a lab states its radius,
                       this is the largest term.
``torque_calibration`` μ · u_rel(M) of the torque transducer.
``torque_resolution``  the transducer's resolution / √12, over R_eff·F_N.
``torque_offset``      u(M₀) / (R_eff·F_N): the standard error of the zero estimate, or,
                       when it could not be estimated, the plausible offset ``b`` as a
                       rectangular half-width (u = b/√3).
``normal_force``       μ · √(u_rel(F)² + (u(F)/F)² + (resolution/√12/F)²).

The expanded uncertainty is U = k·u with k = 2 (about 95 % for a normal distribution).
What is not in it: the detection's own errors (where a plateau starts, how a sharp peak is
shaved), which the benchmarks measure (``bench/README.md``), and a torque zero that drifts
during the run.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np

if TYPE_CHECKING:
    from ..config import InstrumentConfig

COVERAGE_FACTOR = 2.0


class Budget(TypedDict):
    """The uncertainty budget of one μ (:func:`budget`): each source's contribution
    [COF, k = 1] (the module docstring names them) and ``combined``, their root sum of
    squares."""

    reading: float
    friction_radius: float
    torque_calibration: float
    torque_resolution: float
    torque_offset: float
    normal_force: float
    combined: float


def integrated_autocorrelation_time(values: Any, c: float = 5.0) -> float:
    """Integrated autocorrelation time τ_int = 1 + 2 Σ ρ_k [samples] of a series (shape
    (n,)), summed up to the smallest lag W ≥ c·τ_int(W) (Sokal's automatic window: long
    enough to catch the correlation, short enough to keep the noise of the far lags
    out). 1 for white noise; (1 + ρ)/(1 − ρ) for an AR(1) series. At least 1."""
    x = np.asarray(values, dtype=float)
    n = x.size
    if n < 4:
        return 1.0
    x = x - x.mean()
    variance = float(np.dot(x, x)) / n
    if variance == 0:
        return 1.0
    size = 1 << (2 * n - 1).bit_length()
    spectrum = np.fft.rfft(x, size)
    acf = np.fft.irfft(spectrum * np.conj(spectrum), size)[:n] / (n * variance)
    tau = 1.0
    for lag in range(1, n):
        tau += 2.0 * float(acf[lag])
        if lag >= c * tau:
            break
    return max(1.0, tau)


def mean_standard_error(values: Any) -> tuple[float, float]:
    """Standard error of the mean of a correlated series (shape (n,)) and τ_int [samples]:
    ``s · √(τ_int / n)`` with s the sample standard deviation."""
    x = np.asarray(values, dtype=float)
    if x.size < 2:
        return math.nan, 1.0
    tau = integrated_autocorrelation_time(x)
    return float(np.std(x, ddof=1)) * math.sqrt(tau / x.size), tau


def zero_offset_standard_error(torque_Nm: Any) -> float:
    """Standard error [N·m] of a torque zero read as the robust mean of at-rest samples
    (shape (n,)): the mean standard error (with autocorrelation) of the samples within 4
    robust standard deviations of their median, the ones that mean averages."""
    v = np.asarray(torque_Nm, dtype=float)
    v = v[np.isfinite(v)]
    if v.size < 2:
        return math.nan
    centre = float(np.median(v))
    spread = 1.4826 * float(np.median(np.abs(v - centre)))
    inliers = v if spread == 0 else v[np.abs(v - centre) <= 4 * spread]
    se, _ = mean_standard_error(inliers)
    return se


def budget(
    mu: float,
    reading: float,
    *,
    normal_force_N: float,
    instrument: InstrumentConfig,
    offset_u_Nm: float,
) -> Budget:
    """The uncertainty budget of one μ (module doc): each source's contribution [COF,
    k = 1] and ``combined`` (root sum of squares). ``reading`` is the statistical part
    [COF], ``normal_force_N`` the mean normal force [N], ``offset_u_Nm`` the standard
    uncertainty of the torque zero [N·m]."""
    R_m = instrument.friction_radius_mm * 1e-3
    force = max(float(normal_force_N), 1e-12)
    parts = (
        float(reading),
        abs(mu) * instrument.friction_radius_u_mm / instrument.friction_radius_mm,
        abs(mu) * instrument.torque_u_rel,
        instrument.torque_resolution_Nm / math.sqrt(12) / (R_m * force),
        float(offset_u_Nm) / (R_m * force),
        abs(mu) * math.sqrt(
            instrument.normal_force_u_rel**2
            + (instrument.normal_force_u_N / force) ** 2
            + (instrument.normal_force_resolution_N / math.sqrt(12) / force) ** 2
        ),
    )
    return Budget(reading=parts[0], friction_radius=parts[1], torque_calibration=parts[2],
                  torque_resolution=parts[3], torque_offset=parts[4], normal_force=parts[5],
                  combined=math.sqrt(sum(v * v for v in parts)))


def budget_terms(
    *, normal_force_N: float, instrument: InstrumentConfig, offset_u_Nm: float
) -> tuple[float, float]:
    """The parts of :func:`budget` that do not depend on the reading, folded in two:
    ``(relative, absolute)`` such that the combined standard uncertainty [COF, k = 1] of
    a μ read with statistical part ``reading`` is ``√(reading² + (μ·relative)² +
    absolute²)``. ``relative`` [1] holds the friction radius, torque calibration and
    normal force terms (∝ μ); ``absolute`` [COF] the torque resolution and zero. A μ
    read over a window or at a peak a reviewer chose takes the run's terms
    (:mod:`tribopipe.reduction.manual`)."""
    parts = budget(1.0, 0.0, normal_force_N=normal_force_N, instrument=instrument,
                   offset_u_Nm=offset_u_Nm)
    relative = math.hypot(parts["friction_radius"], parts["torque_calibration"],
                          parts["normal_force"])
    absolute = math.hypot(parts["torque_resolution"], parts["torque_offset"])
    return relative, absolute


def unknown_offset_u_Nm(instrument: InstrumentConfig) -> float:
    """Standard uncertainty [N·m] of a torque zero that could not be estimated: the
    plausible offset ``torque_offset_unknown_Nm`` as a rectangular half-width, b/√3."""
    return instrument.torque_offset_unknown_Nm / math.sqrt(3)

"""μ_K over a window and μ_S at a position that a reviewer chose, read the way the
reduction reads them.

The automatic method (:mod:`tribopipe.reduction`) finds the plateau and the static peak;
a reviewer who judges a run otherwise gives the μ_K window ``[from_mm, to_mm]`` and,
optionally, the peak's position ``peak_mm`` (distances along the sliding path, mm).
Both readings use the run's sliding samples (in contact and moving: the rows of the
reduced trace whose ``mu_smooth`` is finite) and the run's own uncertainty terms
(:func:`tribopipe.reduction.uncertainty.budget_terms`, kept in the trace file's metadata
by the pipeline, :data:`TRACE_META_KEY`):

* μ_K is the mean of μ over the samples with ``from_mm ≤ s ≤ to_mm`` (step 5 of the
  method); its reading uncertainty the standard error of that mean with the samples'
  autocorrelation (:func:`tribopipe.reduction.uncertainty.mean_standard_error`), combined
  with the run's other terms exactly as the automatic μ_K. A window needs at least
  ``min_plateau_samples`` samples (below that the automatic window is flagged
  ``short_trace``): a shorter one is refused.
* μ_S at ``peak_mm`` is the value at ``peak_mm`` of the least-squares quadratic in s
  through the samples within ``peak_window_mm / 2`` of it (the width of the method's
  peak curve, step 2); its reading uncertainty the standard error of that value from the
  fit's residuals (at least :data:`PEAK_MIN_SAMPLES` samples).

The review page's script (``export/assets/review.js``) computes the same numbers in the
browser; ``tests/test_review_browser.py`` holds the two equal.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ReductionError
from .uncertainty import mean_standard_error

if TYPE_CHECKING:
    import pandas as pd

#: Parquet key-value metadata key of a trace file: the run's uncertainty terms and the
#: estimator's parameters (JSON), written by :func:`tribopipe.pipeline.write_trace`
TRACE_META_KEY = b"tribopipe.trace"
#: the fewest samples a quadratic through a peak is read from (3 coefficients + 2 for
#: its residual scatter)
PEAK_MIN_SAMPLES = 5


@dataclass(frozen=True)
class TraceTerms:
    """What a reading over a reviewer's window needs besides the samples: the run's
    uncertainty terms ``u_relative`` [1] and ``u_absolute`` [COF]
    (:func:`~tribopipe.reduction.uncertainty.budget_terms`), and the estimator's
    parameters ``min_plateau_samples`` and ``peak_window_mm`` [mm]."""

    u_relative: float
    u_absolute: float
    min_plateau_samples: int
    peak_window_mm: float

    def to_json(self) -> bytes:
        return json.dumps(
            {"u_relative": self.u_relative, "u_absolute": self.u_absolute,
             "min_plateau_samples": self.min_plateau_samples,
             "peak_window_mm": self.peak_window_mm}, sort_keys=True).encode()

    @classmethod
    def from_json(cls, raw: bytes) -> TraceTerms | None:
        """The terms in a trace's metadata; ``None`` when they are absent or malformed."""
        try:
            data = json.loads(raw)
            terms = cls(float(data["u_relative"]), float(data["u_absolute"]),
                        int(data["min_plateau_samples"]), float(data["peak_window_mm"]))
        except (ValueError, TypeError, KeyError):
            return None
        ok = all(math.isfinite(v) and v >= 0 for v in (terms.u_relative, terms.u_absolute,
                                                      terms.peak_window_mm))
        return terms if ok and terms.min_plateau_samples >= 0 else None


@dataclass(frozen=True)
class SlidingSamples:
    """A run's sliding samples, in time order: distance ``s_mm`` [mm], time ``t_s`` [s]
    and ``mu`` (each shape (n,))."""

    s_mm: np.ndarray
    t_s: np.ndarray
    mu: np.ndarray

    @classmethod
    def of_trace(cls, trace: pd.DataFrame) -> SlidingSamples:
        """The rows of a reduced trace (:class:`~tribopipe.reduction.reduce.ReductionResult`'s
        columns) that the reduction read: those with a finite ``mu_smooth``."""
        keep = np.isfinite(trace["mu_smooth"].to_numpy(dtype=float))
        return cls(trace["sliding_distance_mm"].to_numpy(dtype=float)[keep],
                   trace["time_s"].to_numpy(dtype=float)[keep],
                   trace["mu"].to_numpy(dtype=float)[keep])


@dataclass(frozen=True)
class KineticReading:
    """μ_K over a window with its evidence: ``mu_k``, ``u_mu_k`` (k = 1), the first and
    last sample's distance [mm] and time [s], the number of samples, the standard
    deviation of μ there and its slope over s [1/mm]."""

    mu_k: float
    u_mu_k: float
    start_mm: float
    end_mm: float
    start_s: float
    end_s: float
    n: int
    std: float
    drift_per_mm: float


@dataclass(frozen=True)
class StaticReading:
    """μ_S read at a position: ``mu_s``, ``u_mu_s`` (k = 1), the position [mm], the time
    of the nearest sample [s] and the number of samples fitted."""

    mu_s: float
    u_mu_s: float
    distance_mm: float
    time_s: float
    n: int


def combined(mu: float, reading: float, terms: TraceTerms) -> float:
    """The combined standard uncertainty [COF, k = 1] of ``mu`` with statistical part
    ``reading``: √(reading² + (μ·u_relative)² + u_absolute²)."""
    return math.sqrt(reading * reading + (mu * terms.u_relative) ** 2 + terms.u_absolute ** 2)


def kinetic_over(samples: SlidingSamples, from_mm: float, to_mm: float,
                 terms: TraceTerms, *, where: str = "window") -> KineticReading:
    """μ_K over ``[from_mm, to_mm]`` (module doc). :class:`ReductionError` (naming
    ``where``) when the window is empty or reversed, outside the sliding samples, or
    holds fewer samples than ``terms.min_plateau_samples`` (and 2)."""
    s = samples.s_mm
    if not (math.isfinite(from_mm) and math.isfinite(to_mm)) or to_mm <= from_mm:
        raise ReductionError(f"{where}: the window {from_mm:g}–{to_mm:g} mm must end after "
                             "it starts")
    if s.size == 0 or from_mm > float(s[-1]) or to_mm < float(s[0]) or from_mm < 0:
        raise ReductionError(
            f"{where}: the window {from_mm:g}–{to_mm:g} mm lies outside the trace "
            f"(sliding from {float(s[0]) if s.size else 0:.4g} to "
            f"{float(s[-1]) if s.size else 0:.4g} mm)")
    inside = (s >= from_mm) & (s <= to_mm)
    n = int(inside.sum())
    need = max(2, terms.min_plateau_samples)
    if n < need:
        raise ReductionError(
            f"{where}: the window {from_mm:g}–{to_mm:g} mm holds {n} samples; the μ_K "
            f"estimator needs at least {need} (min_plateau_samples)")
    mu_w = samples.mu[inside]
    mu_k = float(np.mean(mu_w))
    se, _ = mean_standard_error(mu_w)
    s_w, t_w = s[inside], samples.t_s[inside]
    std = float(np.std(mu_w, ddof=1))
    d = s_w - s_w.mean()
    sxx = float(np.dot(d, d))
    drift = float(np.dot(d, mu_w - mu_k) / sxx) if sxx > 0 else 0.0
    return KineticReading(mu_k=mu_k, u_mu_k=combined(mu_k, se, terms),
                          start_mm=float(s_w[0]), end_mm=float(s_w[-1]),
                          start_s=float(t_w[0]), end_s=float(t_w[-1]), n=n, std=std,
                          drift_per_mm=drift)


def quadratic_at(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """The value at x = 0 of the least-squares quadratic through ``(x, y)`` (shape (n,),
    n ≥ :data:`PEAK_MIN_SAMPLES`) and its standard error from the residuals. The normal
    equations are solved by Cramer's rule on x scaled to [−1, 1], as the page's script
    does."""
    scale = float(np.max(np.abs(x))) or 1.0
    u = x / scale
    s0, s1, s2 = float(u.size), float(u.sum()), float((u * u).sum())
    s3, s4 = float((u ** 3).sum()), float((u ** 4).sum())
    t0, t1, t2 = float(y.sum()), float((u * y).sum()), float((u * u * y).sum())
    det = s0 * (s2 * s4 - s3 * s3) - s1 * (s1 * s4 - s3 * s2) + s2 * (s1 * s3 - s2 * s2)
    if det == 0 or not math.isfinite(det):
        return math.nan, math.nan
    c0 = (t0 * (s2 * s4 - s3 * s3) - s1 * (t1 * s4 - s3 * t2) + s2 * (t1 * s3 - s2 * t2)) / det
    c1 = (s0 * (t1 * s4 - t2 * s3) - t0 * (s1 * s4 - s3 * s2) + s2 * (s1 * t2 - t1 * s2)) / det
    c2 = (s0 * (s2 * t2 - s3 * t1) - s1 * (s1 * t2 - s3 * t0) + t0 * (s1 * s3 - s2 * s2)) / det
    resid = y - (c0 + c1 * u + c2 * u * u)
    sigma2 = float(np.dot(resid, resid)) / (u.size - 3)
    inv00 = (s2 * s4 - s3 * s3) / det
    return float(c0), math.sqrt(max(sigma2 * inv00, 0.0))


def static_at(samples: SlidingSamples, peak_mm: float, terms: TraceTerms, *,
              where: str = "peak") -> StaticReading:
    """μ_S read at ``peak_mm`` (module doc). :class:`ReductionError` (naming ``where``)
    when the position lies outside the sliding samples or fewer than
    :data:`PEAK_MIN_SAMPLES` samples lie within ``peak_window_mm / 2`` of it."""
    s = samples.s_mm
    if not math.isfinite(peak_mm) or s.size == 0 or not float(s[0]) <= peak_mm <= float(s[-1]):
        raise ReductionError(
            f"{where}: the static peak at {peak_mm:g} mm lies outside the trace (sliding "
            f"from {float(s[0]) if s.size else 0:.4g} to {float(s[-1]) if s.size else 0:.4g} mm)")
    half = terms.peak_window_mm / 2
    near = np.abs(s - peak_mm) <= half
    n = int(near.sum())
    if n < PEAK_MIN_SAMPLES:
        raise ReductionError(
            f"{where}: {n} samples lie within {half:g} mm of the static peak at {peak_mm:g} mm; "
            f"reading a peak needs at least {PEAK_MIN_SAMPLES}")
    value, se = quadratic_at(s[near] - peak_mm, samples.mu[near])
    nearest = int(np.argmin(np.abs(s - peak_mm)))
    return StaticReading(mu_s=value, u_mu_s=combined(value, se, terms), distance_mm=peak_mm,
                         time_s=float(samples.t_s[nearest]), n=n)

"""μ between measured conditions: the one interpolation rule every output reads.

A pair is measured at a few contact pressures [kPa] and temperatures [°C]. Between them:

* **temperature**: linear between the two measured temperatures that bracket the
  request (maps hold two or three temperatures, too few to know a shape; a straight line
  claims the least);
* **pressure**, at each of those temperatures: between the two measured pressures
  p₀ < p < p₁ that bracket the request, linear in log p – log μ::

      ln μ = (1 − w)·ln μ₀ + w·ln μ₁,   w = ln(p/p₀) / ln(p₁/p₀)

  Elastomer friction falls as a power of the contact pressure, μ = k·p^(n−1) (the map's
  own fits reach R² ≈ 0.99), and this rule is exact for any power law. Where a μ or p₀ is
  not positive (no logarithm) the segment is linear in p and μ instead;
* **sliding speed**, where a pair is measured at several nominal speeds: linear in
  ln v between the two measured speeds that bracket the request (:func:`speed_bracket`;
  elastomer friction changes by a similar step per decade of speed, the shape of
  Grosch's master curves on the side of the peak where maps are measured), the value at
  each speed read by the rules above;
* **outside the measured range** the edge value is held (as ABAQUS and Ansys hold a
  table's ends), the value is marked extrapolated and its U is withdrawn
  (:data:`EXTRAPOLATED`, :func:`held_u`): the repeats and the curvature say how well μ is
  known where it was measured, nothing says how μ moves beyond the last measured
  pressure, temperature or speed, so no number could be an honest U there.

The interpolation's own standard uncertainty: between p₀ and p₁ the rule misses the
curve by its bend, ln μ − ln μ̂ ≈ (κ/2)·(x − x₀)(x₁ − x) with x = ln p and κ = d²ln μ/dx²
(zero for a power law). κ is estimated from the map itself — the second divided
difference of ln μ over ln p at every interior measured pressure, pooled as an RMS like
the repeatability s_r (:func:`curvature`) — so u_interp = μ·(κ/2)·w(1 − w)·Δ² with
Δ = ln(p₁/p₀): zero at a measured pressure, largest mid-segment, and scaled to the gap.
Leave-one-out on the published map (``bench/bench_interpolation.py``) shows it is the
size of the errors actually made. A map with no three pressures at one temperature uses
the published map's κ (:data:`PUBLISHED_CURVATURE`, held equal to it by a test).

:func:`densify` adds pressure rows to a table for engines that read it linearly in p.

The explorer page carries a copy of this rule in ``export/assets/js/query.js``; a test
runs it in node on a grid and compares it with :func:`tribopipe.query.query`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from .errors import ExportError
from .rounding import FILE_DIGITS, round_significant

if TYPE_CHECKING:
    import numpy as np
    import numpy.typing as npt

#: κ (RMS second derivative of ln μ_K over ln p) of the published map's group means: the
#: stand-in where a map cannot estimate its own (``tests/test_interpolation.py`` recomputes it)
PUBLISHED_CURVATURE = 0.6274
#: the largest gap [in μ] promised between an engine's linear reading of a densified table
#: and :func:`tribopipe.query.query`
ENGINE_TOLERANCE = 0.005
#: what :func:`densify` aims at (half the promise: the check between rows is sampled)
DENSIFY_TARGET = 0.0025
#: samples per sub-interval that :func:`densify` checks the linear reading on
DENSIFY_SAMPLES = 64
#: significant digits of an added pressure row [kPa]
DENSIFY_DIGITS = 4


#: what every output writes in place of U for a value read outside the measured range
EXTRAPOLATED = "extrapolated: U not valid"


def held_u(expanded: float | None, clamped: bool) -> float | None:
    """U (k = 2) of a value, ``None`` when the value was ``clamped`` (held at the edge of
    the measured pressures, temperatures or speeds): outside the measured range the rule
    holds a value but knows nothing of its error, so U is withdrawn, never extrapolated
    (every output then writes :data:`EXTRAPOLATED`)."""
    return None if clamped else expanded


def temperature_needed(temperatures_C: Sequence[float]) -> str:
    """What a request without a temperature is told for a pair measured at several
    (sorted) ``temperatures_C`` [°C]."""
    listed = ", ".join(f"{v:g}" for v in temperatures_C)
    return f"temperature needed: this pair is measured at {listed} °C"


@dataclass(frozen=True)
class Segment:
    """The part of a value read at one measured temperature.

    ``t_weight`` is that temperature's linear weight; ``lo`` (and ``hi``, ``None`` when
    the value is held at or equal to one point) index the points; ``w`` is the fraction
    of the way from ``lo`` to ``hi`` (in ln p for a ``log`` segment, else in p); ``span``
    is Δ = ln(p_hi/p_lo) (0 for a single point or a linear segment).
    """

    t_weight: float
    lo: int
    hi: int | None
    w: float
    log: bool
    span: float


@dataclass(frozen=True)
class Stencil:
    """Which measured points a value is read from, and how (:func:`stencil`)."""

    segments: tuple[Segment, ...]
    clamped_pressure: bool
    clamped_temperature: bool

    def weights(self, n: int) -> np.ndarray:
        """Each of ``n`` points' share of the value (shape ``(n,)``, ≥ 0, summing to 1):
        temperature weight × pressure weight (the exponent of a log segment)."""
        import numpy as np

        out = np.zeros(n)
        for s in self.segments:
            out[s.lo] += s.t_weight * (1.0 - s.w if s.hi is not None else 1.0)
            if s.hi is not None:
                out[s.hi] += s.t_weight * s.w
        return out


def bracket(xs: Sequence[float], x: float) -> tuple[list[tuple[int, float]], bool]:
    """Indices into sorted unique ``xs`` with linear weights for ``x``, held at the ends.

    Returns ``([(i, w), ...], clamped)``; the weights are positive and sum to 1.
    """
    n = len(xs)
    if n == 1:
        return [(0, 1.0)], bool(x != xs[0])
    if x <= xs[0]:
        return [(0, 1.0)], bool(x < xs[0])
    if x >= xs[-1]:
        return [(n - 1, 1.0)], bool(x > xs[-1])
    hi = next(i for i, v in enumerate(xs) if v > x)
    lo = hi - 1
    if x == xs[lo]:
        return [(lo, 1.0)], False
    w_hi = (x - xs[lo]) / (xs[hi] - xs[lo])
    return [(lo, 1.0 - w_hi), (hi, w_hi)], False


def speed_bracket(
    speeds_mm_s: Sequence[float], speed_mm_s: float
) -> tuple[list[tuple[int, float]], bool]:
    """Indices into sorted unique positive ``speeds_mm_s`` [mm/s] with weights linear in
    ln v for ``speed_mm_s`` [mm/s] (> 0), held at the ends: ``([(i, w), ...], clamped)``
    as :func:`bracket`."""
    return bracket([math.log(v) for v in speeds_mm_s], math.log(speed_mm_s))


def _pressure_segment(
    ps: Sequence[float], mus: Sequence[float], p: float
) -> tuple[int, int | None, float, bool, float, bool]:
    """``(lo, hi, w, log, span, clamped)`` for pressure ``p`` [kPa] among sorted unique
    ``ps`` with values ``mus`` (positions into ``ps``)."""
    brackets, clamped = bracket(ps, p)
    if len(brackets) == 1:
        return brackets[0][0], None, 0.0, False, 0.0, clamped
    (lo, w_lin), (hi, _) = brackets[0], brackets[1]
    p0, p1 = ps[lo], ps[hi]
    if p0 > 0 and mus[lo] > 0 and mus[hi] > 0:
        span = math.log(p1 / p0)
        return lo, hi, math.log(p / p0) / span, True, span, False
    return lo, hi, 1.0 - w_lin, False, 0.0, False


def stencil(
    pressures_kPa: npt.ArrayLike,
    temperatures_C: npt.ArrayLike,
    means: npt.ArrayLike,
    pressure_kPa: float,
    temperature_C: float | None,
) -> Stencil:
    """How a value at (``pressure_kPa``, ``temperature_C``) is read from ``n`` measured
    points with unique (pressure [kPa], temperature [°C]) and values ``means`` (each of
    shape ``(n,)``; a NaN temperature means unknown, used only when no point has one).

    ``temperature_C=None`` is allowed when at most one temperature is measured; else an
    :class:`ExportError` names the temperatures.
    """
    import numpy as np

    p = np.asarray(pressures_kPa, dtype=float)
    t = np.asarray(temperatures_C, dtype=float)
    mu = np.asarray(means, dtype=float)
    known_t = np.isfinite(t)
    sets: list[tuple[np.ndarray, float]] = [(np.arange(len(p)), 1.0)]
    clamped_t = False
    if known_t.any():
        temps = [float(v) for v in np.unique(t[known_t])]
        if temperature_C is None:
            if len(temps) > 1:
                raise ExportError(temperature_needed(temps), hint="pass --temperature")
            t_brackets = [(0, 1.0)]
        else:
            t_brackets, clamped_t = bracket(temps, float(temperature_C))
        sets = [(np.flatnonzero(t == temps[ti]), wt) for ti, wt in t_brackets]
    segments = []
    clamped_p = False
    for idx, wt in sets:
        idx = idx[np.argsort(p[idx], kind="stable")]
        lo, hi, w, log, span, clamped = _pressure_segment(
            [float(v) for v in p[idx]], [float(v) for v in mu[idx]], float(pressure_kPa))
        clamped_p = clamped_p or clamped
        segments.append(Segment(wt, int(idx[lo]), None if hi is None else int(idx[hi]),
                                w, log, span))
    return Stencil(tuple(segments), clamped_p, clamped_t)


def segment_value(segment: Segment, means: npt.ArrayLike) -> float:
    """The value of one segment (at its temperature) from the points' ``means``."""
    import numpy as np

    mu = np.asarray(means, dtype=float)
    mu_lo = float(mu[segment.lo])
    if segment.hi is None:
        return mu_lo
    mu_hi = float(mu[segment.hi])
    if segment.log:
        return math.exp((1.0 - segment.w) * math.log(mu_lo) + segment.w * math.log(mu_hi))
    return (1.0 - segment.w) * mu_lo + segment.w * mu_hi


def evaluate(st: Stencil, means: npt.ArrayLike) -> float:
    """The interpolated value: the temperature-weighted sum of the segments' values."""
    return sum(s.t_weight * segment_value(s, means) for s in st.segments)


def interpolation_u(st: Stencil, means: npt.ArrayLike, kappa: float) -> float:
    """The interpolation's own standard uncertainty (module docstring):
    Σ_T w_T · |μ_T|·(κ/2)·w(1 − w)·Δ² over the segments (0 at a measured pressure,
    outside the range, and on a linear segment, where no bend can be estimated)."""
    total = 0.0
    for s in st.segments:
        if s.hi is None or not s.log:
            continue
        bend = 0.5 * kappa * s.w * (1.0 - s.w) * s.span**2
        total += s.t_weight * abs(segment_value(s, means)) * bend
    return total


def curve(
    pressures_kPa: npt.ArrayLike,
    temperatures_C: npt.ArrayLike,
    means: npt.ArrayLike,
    temperature_C: float | None,
) -> Callable[[float], float]:
    """The rule at one temperature as a fast function of pressure [kPa]: equal to
    ``evaluate(stencil(..., p, temperature_C), means)`` (points as for :func:`stencil`),
    with the temperature bracket and the sorted pressures worked out once (for
    :func:`densify`, which reads it thousands of times)."""
    import numpy as np

    p = np.asarray(pressures_kPa, dtype=float)
    probe = stencil(p, temperatures_C, means, float(p[0]), temperature_C)
    t = np.asarray(temperatures_C, dtype=float)
    mu = np.asarray(means, dtype=float)
    parts = []
    for seg in probe.segments:
        t_seg = t[seg.lo]
        at = np.flatnonzero(t == t_seg) if math.isfinite(t_seg) else np.arange(len(p))
        at = at[np.argsort(p[at], kind="stable")]
        parts.append((seg.t_weight, [float(v) for v in p[at]], [float(v) for v in mu[at]]))

    def value_at(pressure_kPa: float) -> float:
        """The interpolated value at ``pressure_kPa``."""
        total = 0.0
        for weight, ps, mus in parts:
            lo, hi, w, log, span, _ = _pressure_segment(ps, mus, pressure_kPa)
            total += weight * segment_value(Segment(weight, lo, hi, w, log, span), mus)
        return total

    return value_at


def curvature_terms(series: Iterable[tuple[Sequence[float], Sequence[float]]]) -> list[float]:
    """κ at every interior point of each series (pressures [kPa] sorted ascending, values
    μ): twice the second divided difference of ln μ over ln p, for consecutive triples
    whose pressures and values are all positive and whose ln p strictly increase (two
    pressures a rounding apart have one ln p, and no second difference between them)."""
    terms = []
    for ps, mus in series:
        for i in range(1, len(ps) - 1):
            p3, m3 = ps[i - 1:i + 2], mus[i - 1:i + 2]
            if min(p3) <= 0 or min(m3) <= 0:
                continue
            x = [math.log(v) for v in p3]
            if not x[0] < x[1] < x[2]:
                continue
            y = [math.log(v) for v in m3]
            slope_hi = (y[2] - y[1]) / (x[2] - x[1])
            slope_lo = (y[1] - y[0]) / (x[1] - x[0])
            terms.append(2.0 * (slope_hi - slope_lo) / (x[2] - x[0]))
    return terms


def curvature(series: Iterable[tuple[Sequence[float], Sequence[float]]]) -> float:
    """κ of a map: the RMS of :func:`curvature_terms`; :data:`PUBLISHED_CURVATURE` when
    there is no interior point to estimate it from."""
    terms = curvature_terms(series)
    if not terms:
        return PUBLISHED_CURVATURE
    return math.sqrt(sum(k * k for k in terms) / len(terms))


def _rounded_inside(p: float, a: float, b: float, digits: int) -> float:
    """``p`` to ``digits`` significant digits where that stays strictly between ``a``
    and ``b``, else to :data:`~tribopipe.rounding.FILE_DIGITS` where that does, else
    ``p`` itself."""
    for n in (digits, FILE_DIGITS):
        rounded = round_significant(p, n)
        if a < rounded < b:
            return rounded
    return p


def _chord_error(value_at: Callable[[float], float], a: float, b: float) -> float:
    """The largest gap between ``value_at`` and its chord from ``a`` to ``b`` [kPa],
    sampled at :data:`DENSIFY_SAMPLES` inner points."""
    fa, fb = value_at(a), value_at(b)
    worst = 0.0
    for k in range(1, DENSIFY_SAMPLES):
        p = a + (b - a) * k / DENSIFY_SAMPLES
        chord = fa + (fb - fa) * (p - a) / (b - a)
        worst = max(worst, abs(value_at(p) - chord))
    return worst


def densify(
    measured: Sequence[float],
    value_at: Callable[[float], float],
    target: float = DENSIFY_TARGET,
) -> list[float]:
    """Rows of a table axis read in log (pressures [kPa], sliding speeds [mm/s]): the
    measured ones and added ones, sorted, such that reading ``value_at`` linearly between
    consecutive rows, as ABAQUS and Ansys read a table, stays within ``target`` of
    ``value_at`` (checked on samples between the rows).

    Each gap between measured values is cut into the fewest parts equal in ln x whose
    chords all pass the check; added rows are rounded to :data:`DENSIFY_DIGITS`
    significant digits (and the check is made on the rounded rows); in a gap too narrow
    for that (a row would leave the gap, or two would merge) to the digits a simulator
    file carries (:data:`~tribopipe.rounding.FILE_DIGITS`), so that a row's value is the
    value at the pressure as written.
    """
    rows = sorted({float(p) for p in measured})
    out = rows[:1]
    for a, b in zip(rows, rows[1:], strict=False):
        for parts in range(1, 257):
            if a > 0:
                inner = [a * (b / a) ** (k / parts) for k in range(1, parts)]
            else:
                inner = [a + (b - a) * k / parts for k in range(1, parts)]
            cuts = sorted({_rounded_inside(p, a, b, DENSIFY_DIGITS) for p in inner})
            if len(cuts) < len(inner):  # rounding merged rows of a narrow gap
                cuts = sorted({_rounded_inside(p, a, b, FILE_DIGITS) for p in inner})
            edges = [a, *cuts, b]
            if all(_chord_error(value_at, lo, hi) <= target
                   for lo, hi in zip(edges, edges[1:], strict=False)):
                break
        out += [*cuts, b]
    return out


# ---------------------------------------------------------------------------- validation

#: the methods :func:`leave_one_out` compares: linear in p (the rule before this one) and
#: the rule of this module
LOO_METHODS = ("linear in p", "log p - log mu")


@dataclass(frozen=True)
class HeldOut:
    """One interior measured point predicted from its two neighbours at its temperature.

    ``predicted`` maps each of :data:`LOO_METHODS` to its prediction; ``u_interpolation``
    is what :func:`interpolation_u` says the rule's standard uncertainty is there.
    """

    label: str
    pressure_kPa: float
    measured: float
    predicted: dict[str, float]
    u_interpolation: float


def leave_one_out(
    series: Sequence[tuple[str, Sequence[float], Sequence[float]]],
    kappa: float | None = None,
) -> list[HeldOut]:
    """Hold out each interior point of each series (``label``, pressures [kPa] ascending,
    values μ) and predict it from its neighbours by each of :data:`LOO_METHODS`.

    ``kappa`` defaults to :func:`curvature` of the series themselves (the held-out point
    included, as a map's own κ includes all of its points).
    """
    if kappa is None:
        kappa = curvature((ps, mus) for _, ps, mus in series)
    cases = []
    for label, ps, mus in series:
        for i in range(1, len(ps) - 1):
            p0, p1, m0, m1 = ps[i - 1], ps[i + 1], mus[i - 1], mus[i + 1]
            w = (ps[i] - p0) / (p1 - p0)
            st = stencil([p0, p1], [math.nan, math.nan], [m0, m1], ps[i], None)
            cases.append(HeldOut(
                label, float(ps[i]), float(mus[i]),
                {LOO_METHODS[0]: (1.0 - w) * m0 + w * m1, LOO_METHODS[1]: evaluate(st, [m0, m1])},
                interpolation_u(st, [m0, m1], kappa),
            ))
    return cases

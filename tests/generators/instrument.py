"""What an imperfect instrument does to a synthetic signal: coloured noise, quantisation,
sample-time jitter, spikes.

Pure functions on NumPy arrays for the synthetic families (:mod:`generators.ratestate`
first); each draws from the generator it is given, so a seeded run
stays reproducible. None of them knows about friction.
"""

from __future__ import annotations

import math

import numpy as np

NOISE_COLOURS: tuple[str, ...] = ("white", "pink", "white+pink")


def pink_noise(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` samples of unit-variance 1/f ("pink") noise: white noise shaped by 1/√f in
    frequency over twice the length, so that the record holds power at frequencies below
    its own length (a drifting sensor zero), and a random half of it kept."""
    m = 2 * max(int(n), 2)
    spectrum = np.fft.rfft(rng.standard_normal(m))
    f = np.fft.rfftfreq(m)
    f[0] = f[1]
    series = np.fft.irfft(spectrum / np.sqrt(f), m)
    series /= np.std(series)
    start = int(rng.integers(0, m - n + 1))
    return series[start : start + n]


def coloured_noise(rng: np.random.Generator, n: int, colour: str) -> np.ndarray:
    """``n`` samples of unit-variance noise of ``colour`` (:data:`NOISE_COLOURS`): white,
    pink, or the two in equal parts of the variance."""
    if colour not in NOISE_COLOURS:
        raise ValueError(f"colour must be one of {', '.join(NOISE_COLOURS)}, got {colour!r}")
    white = rng.standard_normal(n)
    if colour == "white":
        return white
    pink = pink_noise(rng, n)
    if colour == "pink":
        return pink
    return math.sqrt(0.5) * (white + pink)


def significant_digits(values: np.ndarray, digits: int) -> np.ndarray:
    """``values`` rounded to ``digits`` significant digits each (how RheoCompass writes
    its numbers: five, ``0.057087`` mN·m); a new array, zeros stay zero."""
    v = np.asarray(values, dtype=float)
    magnitude = np.floor(np.log10(np.where(v == 0, 1.0, np.abs(v))))
    scale = 10.0 ** (int(digits) - 1 - magnitude)
    return np.round(v * scale) / scale


def sample_times(rng: np.random.Generator, rate_Hz: float, span_s: float, *,
                 rate_error: float = 0.0, jitter_s: float = 0.0) -> np.ndarray:
    """Sample instants [s] over ``span_s`` from one interval after 0: nominally at
    ``rate_Hz``, the interval longer by ``rate_error`` (relative), each instant off by
    normal jitter of standard deviation ``jitter_s`` [s] (clipped to 30 % of an interval,
    so the order holds)."""
    step = (1.0 + rate_error) / rate_Hz
    n = max(2, int(span_s / step))
    t = np.arange(1, n + 1) * step
    if jitter_s > 0:
        t = t + np.clip(rng.normal(0.0, jitter_s, n), -0.3 * step, 0.3 * step)
    return t


def add_spikes(values: np.ndarray, rng: np.random.Generator, count_rate: float,
               span: float, low: float, high: float, *, scale: float = 1.0,
               relative: bool = False) -> np.ndarray:
    """A copy of ``values`` with single-sample spikes at random samples: their number is
    Poisson with mean ``count_rate`` × ``span``, their sizes uniform in [low, high] times
    ``scale`` with random sign, added — or, ``relative``, multiplying by 1 + size."""
    out = np.array(values, dtype=float)
    count = int(rng.poisson(count_rate * span))
    where = rng.integers(0, out.size, count)
    size = rng.uniform(low, high, count) * rng.choice([-1.0, 1.0], count)
    if relative:
        out[where] *= 1.0 + size
    else:
        out[where] += size * scale
    return out

"""A second, independent family of synthetic runs: a quasi-static pin–interface model.

This family validates the μ_S / μ_K detection on traces whose loading physics differs from
:mod:`generators.synthetic` (the shapes the detection was developed on). Its model, its
grid (:func:`validation_runs`) and its seeds were written and fixed before the detection
of issue 14 was changed, and the detection is not tuned on it (see ``bench/README.md``).

Model
-----
Lengths in mm along the sliding path at the friction radius; forces as COF, i.e. divided
by the normal force F_N. The rheometer drives the pin holder through ``x`` (the measured
sliding distance s = φ·R_eff). Between holder and disc sit, in series:

* the pins, sheared elastically by ``c_pin·f``: ``c_pin = F_N·h / (n·G·A)`` [mm per unit
  COF] for n pins of height h, area A and shear modulus G. Three Ecoflex 00-50 pins
  (G ≈ 25 kPa, h = 6 mm, r = 3 mm) at 1 N give c_pin ≈ 2.8 mm: at μ ≈ 0.9 they shear
  2.5 mm before the contact slides; Dragon Skin 30 (G ≈ 0.2 MPa) at 9 N and μ ≈ 0.3
  about 1 mm; a stiff contact a few hundredths of a millimetre;
* the contact interface, displaced by ``z = c_int·f + p``: an elastic micro-slip
  ``c_int·f`` and a plastic (gross) slip ``p``.

Plastic slip follows the elastic–plastic flow rule ``dp/dz = (f / f_c(p))^m``, so
``df/dz = (1 − (f/f_c)^m) / c_int``. For m = 1 this is Dahl's friction model (an
exponential creep towards the strength); a large m approaches an elastic–perfectly
plastic contact with a sharp yield. The strength weakens with plastic slip
(slip-weakening, as rate-and-state friction after a hold) and may run in slowly::

    f_c(p) = μ_K + R·exp(−p/L_run) + (μ_S0 − μ_K − R)·exp(−p/D_c) + oscillation(p)

with the weakening length D_c (µm) and a run-in of excess R over L_run (mm). An
oscillating plateau has a strength that varies with slip as a saw-tooth of
peak-to-peak amplitude A (rising over 85 % of a cycle, falling over 15 %) with cycle
lengths λ·(1 ± 5 %), faded in over D_c. Quasi-statically ``x = c_pin·f + z``. Where the
force falls faster with interface slip than the pins unload (dx/dz < 0) the pins snap
forward: the recorded trace drops at constant x, a sudden slip. Each sample shows the
branch the system is on (:func:`mu_curve`).

Recording: the disc turns at 0.005 rpm (0.0070 mm/s at R_eff = 13.37 mm), 10 Hz; an
optional normal-force set-up interval (20 s, no rotation) and an optional rest before
motion; torque ``dir·μ·F_N(t)·R + offset + noise``, where the noise is white or AR(1)
(ρ = 0.5: a low-passed sensor) with the per-sample standard deviation ``noise`` in COF
units at the nominal force; F_N wanders ±0.5 % over 60 s with 0.2 % noise; temperature
±0.05 °C. Written through :func:`generators.synthetic.write_intervals_export`.

Truth (:class:`generators.truth.Truth`): μ_K is the strength's asymptote, or for an oscillating
plateau the mean of the noise-free μ over whole cycles of the settled plateau; the
plateau is settled from the first distance after which the noise-free μ (averaged over
a cycle where it oscillates) stays within 0.002 of μ_K; μ_S is the largest noise-free μ
before it. A static peak is ``distinct`` when it stands ≥ 0.03 above the plateau's
highest noise-free value, ``none`` when it does not rise more than 0.005 above it, and
``ambiguous`` in between (reported, not scored).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from tribopipe.measurement import ANGLE, NORMAL_FORCE, SPEED, TEMPERATURE, TIME, TORQUE
from tribopipe.physics import FOUNDING_FRICTION_RADIUS_MM

from .synthetic import write_intervals_export
from .truth import OSCILLATION_MIN_PP, Truth, static_kind

if TYPE_CHECKING:
    from os import PathLike

    import pandas as pd

SHAPES: tuple[str, ...] = ("peak", "peak_run_in", "creep", "stick_slip")
#: extra sets of the validation grid, scored on their own
SPECIAL_SETS: tuple[str, ...] = ("truncated", "offset_unknown")

#: the grid, fixed before the detection was changed (issue 14); do not adjust it to results
BASE_SEED = 20261123
PEAK_DISTANCES_MM: tuple[float, ...] = (0.02, 0.05, 0.15, 0.4, 1.0, 2.5, 5.0)
SHARPNESS: tuple[float, ...] = (1.0, 3.0, 12.0)
DRAWS_PER_CELL = 10

SETTLE_TOL = 0.002  # noise-free μ within this of μ_K: the plateau has settled [COF]
MAX_WEAKENING_MM = 0.25  # slip-weakening is an interface property: at most 0.25 mm
_SAW_RISE = 0.85  # the oscillation's strength rises over this fraction of a cycle
_CYCLE_JITTER = 0.05  # cycle lengths λ·(1 ± 5 %)


@dataclass(frozen=True)
class ContactRun:
    """One run of the contact model, every parameter explicit (see module doc).

    Lengths in mm, COF dimensionless. ``mu_s0`` is the strength at zero slip (the
    realised static peak is lower where plastic slip starts before it); ``c_pin_mm``
    and ``c_int_mm`` are compliances [mm per unit COF]; ``sharpness`` is m of the flow
    rule; ``run_in`` and ``run_in_mm`` are R and L_run; ``osc_amplitude`` and
    ``osc_period_mm`` are A (peak-to-peak) and λ of an oscillating plateau (0: none).
    ``distance_mm`` is the sliding distance recorded after the rest;
    ``nominal_peak_mm`` the grid's pre-sliding distance the run was built for.
    """

    shape: str
    mu_k: float
    mu_s0: float
    c_pin_mm: float
    c_int_mm: float
    sharpness: float
    weakening_mm: float
    run_in: float = 0.0
    run_in_mm: float = 1.0
    osc_amplitude: float = 0.0
    osc_period_mm: float = 0.05
    distance_mm: float = 2.0
    noise: float = 0.005
    noise_rho: float = 0.0
    torque_offset_Nm: float = 0.0
    setup_interval: bool = True
    rest_s: float = 2.0
    normal_force_N: float = 3.0
    temperature_C: float = 20.0
    direction: int = 1
    seed: int = 0
    speed_rpm: float = 0.005
    sample_rate_Hz: float = 10.0
    friction_radius_mm: float = FOUNDING_FRICTION_RADIUS_MM
    setup_s: float = 20.0
    label: str = ""
    nominal_peak_mm: float = 0.0

    @property
    def speed_mm_s(self) -> float:
        """Sliding speed at the friction radius [mm/s]."""
        return self.speed_rpm * 2 * math.pi / 60 * self.friction_radius_mm


def pin_compliance_mm(
    normal_force_N: float, height_mm: float, shear_modulus_kPa: float, n_pins: int = 3,
    pin_radius_mm: float = 3.0,
) -> float:
    """Shear compliance of the pins in mm per unit COF: the holder travel that loads
    ``n_pins`` pins of height ``height_mm`` [mm], radius ``pin_radius_mm`` [mm] and shear
    modulus ``shear_modulus_kPa`` [kPa] to a friction force of μ·F_N is μ·c_pin, with
    ``c_pin = F_N·h / (n·G·π r²)`` (N·mm / (kPa·mm²) = N·mm / (1e-3 N/mm²·mm²) → ×1e3 mm).
    Ecoflex 00-50 (25 kPa, 6 mm) at 1 N: 2.83 mm."""
    area_mm2 = math.pi * pin_radius_mm**2
    return normal_force_N * height_mm / (n_pins * shear_modulus_kPa * 1e-3 * area_mm2)


# --------------------------------------------------------------------------- the model


class _Strength:
    """f_c(p) of a run: weakening, run-in and the oscillation's saw-tooth (with cycles)."""

    def __init__(self, run: ContactRun, p_max: float) -> None:
        self.run = run
        self.fast = run.mu_s0 - run.mu_k - run.run_in
        edges = [0.0]
        if run.osc_amplitude > 0:
            rng = np.random.default_rng([run.seed, 7])
            n = int(p_max / (run.osc_period_mm * (1 - _CYCLE_JITTER))) + 2
            lengths = run.osc_period_mm * (1 + _CYCLE_JITTER * rng.uniform(-1, 1, n))
            edges = [0.0, *np.cumsum(lengths).tolist()]
        self.edges = edges
        self._cycle = 0

    def __call__(self, p: float) -> float:
        run = self.run
        value = run.mu_k + self.fast * math.exp(-p / run.weakening_mm)
        if run.run_in:
            value += run.run_in * math.exp(-p / run.run_in_mm)
        if run.osc_amplitude > 0:
            edges = self.edges
            while self._cycle + 2 < len(edges) and p >= edges[self._cycle + 1]:
                self._cycle += 1
            a, b = edges[self._cycle], edges[self._cycle + 1]
            u = min(max((p - a) / (b - a), 0.0), 1.0)
            tooth = u / _SAW_RISE if u < _SAW_RISE else (1.0 - u) / (1.0 - _SAW_RISE)
            fade = 1.0 - math.exp(-p / run.weakening_mm)
            value += run.osc_amplitude * (tooth - 0.5) * fade
        return value


def _p_resolution(run: ContactRun, p: float) -> float:
    """Largest plastic-slip step that resolves the strength's features near p [mm]."""
    step = 0.004
    if p < 10 * run.weakening_mm:
        step = min(step, run.weakening_mm / 25)
    if run.run_in:
        step = min(step, run.run_in_mm / 100)
    if run.osc_amplitude > 0:
        step = min(step, run.osc_period_mm * (1 - _SAW_RISE) / 8)
    return step


def integrate_interface(
    run: ContactRun, *, x_max: float | None = None, p_max: float | None = None,
    stop_after_peak: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Integrate the interface over its displacement z [mm]: arrays ``z, f, p`` (shape
    (n,)) from z = 0, until the holder travel c_pin·f + z reaches ``x_max`` or the
    plastic slip ``p_max`` [mm], or (``stop_after_peak``) until f has fallen 10 % of the
    way from its maximum towards μ_K after at least 8 weakening lengths of slip.

    Semi-implicit Euler in f (stable however stiff the contact), with steps that keep
    each change of f below 0.002 and each plastic step below the strength's resolution.
    """
    strength = _Strength(run, p_max if p_max is not None else (x_max or 10.0) + 1.0)
    m, c_int = run.sharpness, run.c_int_mm
    z = f = p = 0.0
    zs, fs, ps = [0.0], [0.0], [0.0]
    f_top = 0.0
    while True:
        fc = strength(p)
        ratio = f / fc
        r = ratio**m
        g = (1.0 - r) / c_int
        dg = -m * ratio ** (m - 1.0) / (fc * c_int)
        h = 0.004
        if g != 0.0:
            h = min(h, 0.002 / abs(g))
        if r > 0.0:
            h = min(h, _p_resolution(run, p) / r)
        f = f + h * g / (1.0 - h * dg)
        p += h * r
        z += h
        zs.append(z)
        fs.append(f)
        ps.append(p)
        f_top = max(f_top, f)
        if x_max is not None and run.c_pin_mm * f + z >= x_max:
            break
        if p_max is not None and p >= p_max:
            break
        if stop_after_peak and p > 8 * run.weakening_mm and (
            f < f_top - 0.1 * (f_top - run.mu_k) or f_top <= run.mu_k
        ):
            break
    return np.array(zs), np.array(fs), np.array(ps)


def branch_values(x_curve: Any, f_curve: Any, x_samples: Any) -> np.ndarray:
    """The force (shape of ``x_samples``) at holder positions ``x_samples`` [mm] of a
    curve ``(x_curve, f_curve)`` parametrised by the interface slip (x may fall back
    where the pins snap). At each x the system sits on the first branch that reaches it
    (the running maximum of x): after a snap, on the branch beyond the jump."""
    x = np.asarray(x_curve, dtype=float)
    f = np.asarray(f_curve, dtype=float)
    reach = np.maximum.accumulate(x)
    idx = np.searchsorted(reach, np.asarray(x_samples, dtype=float), side="left")
    idx = np.clip(idx, 1, x.size - 1)
    x0, x1, f0, f1 = x[idx - 1], x[idx], f[idx - 1], f[idx]
    span = np.where(x1 > x0, x1 - x0, 1.0)
    w = np.clip((np.asarray(x_samples, dtype=float) - x0) / span, 0.0, 1.0)
    return f0 + w * (f1 - f0)


def _sample_distance_mm(run: ContactRun) -> np.ndarray:
    n = max(2, int(round((run.rest_s + run.distance_mm / run.speed_mm_s) * run.sample_rate_Hz)))
    t = np.arange(1, n + 1) / run.sample_rate_Hz
    return np.maximum(t - run.rest_s, 0.0) * run.speed_mm_s


def mu_curve(run: ContactRun, x_mm: Any, *, margin_mm: float = 0.05) -> np.ndarray:
    """The noise-free μ at holder positions ``x_mm`` [mm] (shape (n,), non-decreasing)."""
    x = np.asarray(x_mm, dtype=float)
    z, f, _ = integrate_interface(run, x_max=float(x.max()) + margin_mm)
    return branch_values(run.c_pin_mm * f + z, f, x)


def _cycle_edges_x(run: ContactRun, x_curve: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Holder positions [mm] where the oscillation's cycles begin (empty if none)."""
    if run.osc_amplitude <= 0:
        return np.empty(0)
    edges = np.asarray(_Strength(run, float(p[-1]) + 1.0).edges)
    edges = edges[edges <= p[-1]]
    reach = np.maximum.accumulate(x_curve)
    return np.interp(edges, p, reach)


def _settle(x: np.ndarray, values: np.ndarray, level: float) -> float:
    """First position [mm] of ``x`` from which every later value stays within SETTLE_TOL
    of ``level`` (``x`` and ``values`` of shape (n,); positions of points or of cycle
    starts)."""
    off = np.flatnonzero(np.abs(values - level) > SETTLE_TOL)
    if off.size == 0:
        return float(x[0])
    return float(x[min(int(off[-1]) + 1, x.size - 1)])


def _analyse(run: ContactRun, x_end: float) -> dict[str, float]:
    """Settle distance, μ_K, static peak and plateau highs of the noise-free curve up to
    ``x_end`` [mm] (on a 0.0005-mm grid). An oscillating plateau is judged by its cycle
    means (whole cycles only)."""
    z, f, p = integrate_interface(run, x_max=x_end + 0.05)
    xc = run.c_pin_mm * f + z
    grid = np.arange(0.0, x_end + 1e-12, 0.0005)
    mu = branch_values(xc, f, grid)
    level = run.mu_k
    if run.osc_amplitude > 0:
        starts = _cycle_edges_x(run, xc, p)
        starts = starts[starts <= x_end]
        which = np.searchsorted(starts, grid, side="right") - 1
        whole = (which >= 0) & (which < starts.size - 1)  # inside a complete cycle
        sums = np.bincount(which[whole], weights=mu[whole], minlength=starts.size)
        counts = np.bincount(which[whole], minlength=starts.size)
        n_cycles = starts.size - 1
        means = sums[:n_cycles] / np.maximum(counts[:n_cycles], 1)
        settle = float(grid[-1])
        if n_cycles >= 1:
            for _ in range(5):  # the plateau's level and its start depend on each other
                first = int(np.searchsorted(starts[:n_cycles], settle, side="left"))
                first = min(first, n_cycles - 1)
                level = float(np.mean(means[first:]))
                settle = _settle(starts[:n_cycles], means, level)
    else:
        settle = _settle(grid, mu, level)
    before = grid < settle
    k = int(np.argmax(np.where(before, mu, -np.inf))) if before.any() else 0
    plateau = mu[grid >= settle]
    return {
        "settle_mm": settle,
        "mu_k": level,
        "mu_s": float(mu[k]),
        "mu_s_distance_mm": float(grid[k]),
        "plateau_high": float(plateau.max()) if plateau.size else float(mu[-1]),
        "oscillation_pp": float(np.percentile(plateau, 99.5) - np.percentile(plateau, 0.5))
        if plateau.size else 0.0,
    }


def truth(run: ContactRun) -> Truth:
    """The known answer for ``run`` (see module doc)."""
    full = _analyse(run, run.distance_mm)
    truncated = full["settle_mm"] >= run.distance_mm - 1e-9 or (
        run.distance_mm - full["settle_mm"] < 0.05
    )
    mu_s, high = full["mu_s"], full["plateau_high"]
    if truncated:
        # the plateau is not in the trace: the true values are those of the full run
        whole = _analyse(run, run.distance_mm + _settle_estimate(run) + 1.0)
        mu_s, high = whole["mu_s"], whole["plateau_high"]
        full = {**whole, "settle_mm": whole["settle_mm"]}
    static = static_kind(mu_s, high)
    return Truth(
        mu_s=mu_s if static != "none" else full["mu_k"],
        mu_k=full["mu_k"],
        mu_s_distance_mm=full["mu_s_distance_mm"],
        static=static,
        oscillating=run.osc_amplitude > 0 and full["oscillation_pp"] >= OSCILLATION_MIN_PP,
        oscillation_pp=full["oscillation_pp"],
        settle_mm=full["settle_mm"],
        plateau_high=high,
        sliding_distance_mm=run.distance_mm,
        truncated=truncated,
        offset_estimable=run.setup_interval or run.rest_s * run.sample_rate_Hz >= 5,
    )


def _settle_estimate(run: ContactRun) -> float:
    """A generous guess of the settle distance [mm], to size the integration."""
    lengths = [run.weakening_mm * math.log(max(abs(run.mu_s0 - run.mu_k), 1e-6) / 5e-4)]
    if run.run_in:
        lengths.append(run.run_in_mm * math.log(max(run.run_in, 1e-6) / 5e-4))
    lengths.append(run.c_int_mm * run.mu_k * math.log(max(run.mu_k, 1e-6) / 5e-4))
    return run.c_pin_mm * run.mu_s0 + 1.3 * max(lengths) + 0.1


# --------------------------------------------------------------------------- the recording


def make_intervals(run: ContactRun) -> list[pd.DataFrame]:
    """The intervals the instrument records for ``run``: [set-up,] friction, each with
    ``time_s, torque_Nm, normal_force_N, angle_rad, speed_rad_s, temperature_C``."""
    import pandas as pd

    rng = np.random.default_rng([run.seed, 3])
    R_m = run.friction_radius_mm * 1e-3
    omega = run.speed_rpm * 2 * math.pi / 60
    torque_noise = run.noise * run.normal_force_N * R_m
    force_noise = 0.002 * run.normal_force_N
    frames: list[pd.DataFrame] = []

    def coloured(n: int) -> np.ndarray:
        white = rng.standard_normal(n)
        if run.noise_rho <= 0:
            return white
        out = np.empty(n)
        scale = math.sqrt(1 - run.noise_rho**2)
        out[0] = white[0]
        for i in range(1, n):
            out[i] = run.noise_rho * out[i - 1] + scale * white[i]
        return out

    if run.setup_interval:
        n = max(2, int(round(run.setup_s * run.sample_rate_Hz)))
        t = np.arange(1, n + 1) / run.sample_rate_Hz
        ramp = np.clip(t / (0.6 * run.setup_s), 0.0, 1.0)
        frames.append(pd.DataFrame({
            TIME: t,
            TORQUE: run.torque_offset_Nm + torque_noise * coloured(n),
            NORMAL_FORCE: run.normal_force_N * ramp + force_noise * rng.standard_normal(n),
            ANGLE: np.zeros(n),
            SPEED: np.zeros(n),
            TEMPERATURE: run.temperature_C + 0.05 * rng.standard_normal(n),
        }))

    x = _sample_distance_mm(run)
    n = x.size
    t = np.arange(1, n + 1) / run.sample_rate_Hz
    mu = mu_curve(run, x)
    wander = 0.005 * np.sin(2 * math.pi * t / 60.0 + rng.uniform(0, 2 * math.pi))
    force_true = run.normal_force_N * (1.0 + wander)
    torque = (
        run.direction * mu * force_true * R_m + run.torque_offset_Nm + torque_noise * coloured(n)
    )
    frames.append(pd.DataFrame({
        TIME: t,
        TORQUE: torque,
        NORMAL_FORCE: force_true + force_noise * rng.standard_normal(n),
        ANGLE: run.direction * x / run.friction_radius_mm,
        SPEED: run.direction * np.where(t > run.rest_s, omega, 0.0),
        TEMPERATURE: run.temperature_C + 0.05 * rng.standard_normal(n),
    }))
    return frames


def write_export(
    path: str | PathLike[str], run: ContactRun, *, language: str = "en"
) -> Path:
    """Write ``run`` as a RheoCompass export through the project's export writer."""
    return write_intervals_export(
        path, make_intervals(run), project="validation", test=run.shape,
        sample=run.label or "pin", language=language,
    )


# --------------------------------------------------------------------------- building runs


def _peak_of(run: ContactRun) -> tuple[float, float]:
    """(largest f, interface displacement z there) of the run's interface alone."""
    z, f, _ = integrate_interface(run, stop_after_peak=True)
    k = int(np.argmax(f))
    return float(f[k]), float(z[k])


def _tune_mu_s0(run: ContactRun, mu_s_target: float) -> ContactRun:
    """The run with μ_S0 chosen so the realised static peak is ``mu_s_target`` (bisection;
    plastic slip before the peak makes the peak lower than μ_S0)."""
    lo, hi = mu_s_target, run.mu_k + 20 * (mu_s_target - run.mu_k)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        peak, _ = _peak_of(replace(run, mu_s0=mid))
        if peak < mu_s_target:
            lo = mid
        else:
            hi = mid
        if hi - lo < 2e-5:
            break
    return replace(run, mu_s0=0.5 * (lo + hi))


def oscillation_pp(run: ContactRun, cycles: int = 12) -> float:
    """Peak-to-peak of the noise-free μ [COF] over ``cycles`` oscillation cycles after the
    peak has weakened (0 for a run without oscillation)."""
    if run.osc_amplitude <= 0:
        return 0.0
    p_start = 10 * run.weakening_mm
    z, f, p = integrate_interface(run, p_max=p_start + cycles * run.osc_period_mm)
    x = run.c_pin_mm * f + z
    late = p >= p_start + 2 * run.osc_period_mm
    grid = np.linspace(float(x[late][0]), float(x[-1]), 4000)
    mu = branch_values(x, f, grid)
    return float(np.percentile(mu, 99.5) - np.percentile(mu, 0.5))


def _calibrate_oscillation(run: ContactRun, pp_target: float) -> ContactRun:
    """The run with the strength's saw-tooth scaled so the force oscillates with
    peak-to-peak ``pp_target`` (the contact's compliance smooths a strength oscillation
    shorter than its micro-slip length)."""
    for _ in range(4):
        pp = oscillation_pp(run)
        if pp <= 0 or abs(pp - pp_target) < 0.05 * pp_target:
            break
        run = replace(run, osc_amplitude=min(0.5, run.osc_amplitude * pp_target / pp))
    return run


def build_run(
    shape: str, peak_mm: float, sharpness: float, index: int, *,
    special: str | None = None,
) -> ContactRun:
    """The validation run number ``index`` of ``shape`` with its static peak (or, for
    creep, its 95 % rise) at ``peak_mm`` [mm] and flow-rule sharpness m; everything else
    is drawn from the seeded stream ``[BASE_SEED, index]``. ``special`` is
    ``"truncated"`` (the trace ends before the plateau settles) or ``"offset_unknown"``
    (no set-up interval, no rest before motion).

    The interface takes a drawn share (10–70 %) of the pre-sliding distance (a soft pin's
    contact slips partially over a length comparable to its shear, as in Mindlin's
    partial slip), the pins the rest; the weakening length is 0.5–4 interface lengths,
    at most 0.25 mm.
    """
    if shape not in SHAPES:
        raise ValueError(f"shape must be one of {', '.join(SHAPES)}, got {shape!r}")
    rng = np.random.default_rng([BASE_SEED, index])
    mu_k = float(rng.uniform(0.2, 1.1))
    ratio = float(rng.choice([1.15, 1.3, 1.5]))
    noise = float(rng.uniform(0.003, 0.015))
    rho = 0.5 if rng.uniform() < 0.5 else 0.0
    force = float(rng.choice([1.0, 3.0, 5.0, 9.0]))
    temperature = float(rng.choice([10.0, 20.0, 40.0]))
    offset = float(rng.choice([0.0, 2e-4, -3e-4, 5e-4]))
    setup = bool(rng.uniform() < 0.5)
    rest = float(rng.choice([0.0, 2.0, 10.0])) if setup else float(rng.choice([2.0, 10.0]))
    plateau_mm = float(rng.choice([1.0, 3.0]))
    direction = 1 if rng.uniform() < 0.5 else -1
    share = float(rng.uniform(0.1, 0.7))
    dc_ratio = float(math.exp(rng.uniform(math.log(0.5), math.log(4.0))))
    run_in_frac = float(rng.uniform(0.3, 0.6))
    run_in_mm = float(math.exp(rng.uniform(math.log(0.5), math.log(3.0))))
    amplitude = float(rng.uniform(0.01, 0.05))
    period = float(math.exp(rng.uniform(math.log(0.02), math.log(0.2))))
    cut = float(rng.uniform(0.3, 0.85))
    if special == "offset_unknown":
        setup, rest = False, 0.0
        offset = float(rng.choice([2e-4, -3e-4, 5e-4]))

    mu_s = mu_k * ratio if shape != "creep" else mu_k
    run = ContactRun(
        shape=shape, mu_k=mu_k, mu_s0=mu_s, c_pin_mm=0.0, c_int_mm=1.0 / mu_s,
        sharpness=sharpness, weakening_mm=dc_ratio,
        run_in=run_in_frac * (mu_s - mu_k) if shape == "peak_run_in" else 0.0,
        run_in_mm=run_in_mm,
        osc_amplitude=amplitude if shape == "stick_slip" else 0.0, osc_period_mm=period,
        noise=noise, noise_rho=rho, torque_offset_Nm=offset, setup_interval=setup,
        rest_s=rest, normal_force_N=force, temperature_C=temperature, direction=direction,
        seed=int(np.random.SeedSequence([BASE_SEED, index]).generate_state(1)[0]),
        label=f"{special or shape}-{index}", nominal_peak_mm=peak_mm,
    )
    if shape == "creep":
        # the interface creeps over its share of the 95 % rise, the pins take the rest
        z, f, _ = integrate_interface(run, p_max=40.0 / sharpness)
        z95_unit = float(np.interp(0.95 * mu_k, f, z))
        run = replace(run, c_int_mm=share * peak_mm / z95_unit / mu_k, weakening_mm=1.0)
        run = replace(run, c_pin_mm=(1 - share) * peak_mm / (0.95 * mu_k))
    else:
        for _ in range(2):  # scale the interface to its share of the peak distance
            run = _tune_mu_s0(run, mu_s)
            _, z_pk = _peak_of(run)
            k = share * peak_mm / z_pk
            run = replace(run, c_int_mm=run.c_int_mm * k,
                          weakening_mm=min(MAX_WEAKENING_MM, run.weakening_mm * k))
        run = _tune_mu_s0(run, mu_s)
        if shape == "stick_slip":
            run = _tune_mu_s0(_calibrate_oscillation(run, amplitude), mu_s)
        _, z_pk = _peak_of(run)
        run = replace(run, c_pin_mm=max(0.0, (peak_mm - z_pk) / mu_s))
    settle = _analyse(run, _settle_estimate(run) + plateau_mm)["settle_mm"]
    distance = settle + plateau_mm
    if special == "truncated":
        distance = max(0.3, cut * settle)
    return replace(run, distance_mm=round(distance, 4))


@dataclass(frozen=True)
class GridPoint:
    """One run of the validation grid before it is built: its set (a shape or a special
    set), shape, nominal peak distance [mm], sharpness m and seed index."""

    set: str
    shape: str
    peak_mm: float
    sharpness: float
    index: int

    def build(self) -> ContactRun:
        """The run (see :func:`build_run`)."""
        special = self.set if self.set in SPECIAL_SETS else None
        return build_run(self.shape, self.peak_mm, self.sharpness, self.index, special=special)


def validation_grid(limit_per_cell: int | None = None) -> list[GridPoint]:
    """The fixed validation grid: each shape of :data:`SHAPES` × 7 peak distances ×
    3 sharpnesses × 10 draws; "truncated": 4 shapes × peaks 0.4–5 mm × 3;
    "offset_unknown": 4 shapes × 7 peaks × 2. ``limit_per_cell`` keeps the first draws of
    each cell (a quick subset of the same runs)."""
    draws = DRAWS_PER_CELL if limit_per_cell is None else min(limit_per_cell, DRAWS_PER_CELL)
    points: list[GridPoint] = []
    index = 0
    for shape in SHAPES:
        for peak in PEAK_DISTANCES_MM:
            for m in SHARPNESS:
                for d in range(DRAWS_PER_CELL):
                    if d < draws:
                        points.append(GridPoint(shape, shape, peak, m, index))
                    index += 1
    for shape in SHAPES:
        for peak in PEAK_DISTANCES_MM[3:]:
            for d in range(3):
                if d < draws:
                    points.append(GridPoint("truncated", shape, peak, SHARPNESS[d % 3], index))
                index += 1
    for shape in SHAPES:
        for peak in PEAK_DISTANCES_MM:
            for d in range(2):
                if d < draws:
                    points.append(
                        GridPoint("offset_unknown", shape, peak, SHARPNESS[(d + 1) % 3], index)
                    )
                index += 1
    return points


def validation_runs(limit_per_cell: int | None = None) -> list[tuple[str, ContactRun]]:
    """The validation grid built: ``(set, run)`` pairs (see :func:`validation_grid`)."""
    return [(g.set, g.build()) for g in validation_grid(limit_per_cell)]


def describe(run: ContactRun) -> dict[str, Any]:
    """The run's parameters as a JSON-ready dict."""
    return asdict(run)

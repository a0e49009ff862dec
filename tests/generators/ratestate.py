"""A third, unseen family of synthetic runs: rate-and-state friction on a spring, recorded
by an imperfect instrument.

Its grid and seeds were fixed before any change of the detection after issue 14's
validation (``bench/README.md`` says what was seen when); neither the development family
(:mod:`generators.synthetic`) nor the validation family (:mod:`generators.contact`)
has this physics or these instrument effects.

Model (lengths in mm along the sliding path at the friction radius, time in s, forces
divided by the nominal normal force F_N0, i.e. in COF units)
-----------------------------------------------------------------------------------------
The rheometer drives the pin holder at V = 0.005 rpm · R_eff ≈ 0.0070 mm/s (x = V·t after
the rest). The pins' shear is a spring of stiffness k [COF per mm] — three pins of height
h and area A in shear: k = n·G·A / (h·F_N0), 0.35 /mm for 6-mm Ecoflex 00-50 at 1 N, tens
per mm for a stiff contact — between the holder and the contact, which slides at v
[mm/s] and obeys the Dieterich–Ruina law with the ageing ("slowness") evolution::

    μ_f = μ0 + a·ln(v/V) + b·ln(V·θ/Dc),      dθ/dt = 1 − v·θ/Dc.

Quasi-dynamically (radiation damping η, the pins' shear impedance √(Gρ)/2 per area): the
spring force ``f_s = k·(x − δ)`` balances ``n(t)·μ_f + η·v``, where δ is the contact's
slip and n(t) = F_N(t)/F_N0 the wandering normal force. Differentiating gives the ODE in
(δ, ln(v/V), ln(V·θ/Dc)) integrated with LSODA (:func:`simulate`). The contact has aged
θ0 = t_hold + Dc/V at the start of motion (t_hold: the time in contact at rest, set-up
interval and rest included), so a run starts with a static peak b·ln(V·θ/Dc) above the
steady state μ_ss = μ0 (the reference speed is V); the peak comes where v first reaches V
(there f_s is largest). Steady sliding is stable when k exceeds k_c = (b − a)/Dc and
oscillates in stick-slip below it (Ruina 1983; Rice & Ruina 1983): the ageing law's limit
cycle has a peak-to-peak of ~15·(b − a) however far below k_c, so a weak stick-slip is a
small b − a, and its cycle length is about peak-to-peak / k.

Shapes: ``peak`` (velocity-strengthening, a > b: stable, a peak after the hold; a soft
spring snaps off it), ``peak_weakening`` (b > a but k > k_c: stable, a peak whose decay
can ring), ``creep`` (b = 0: no healing, no peak — the loading curve bends onto the
plateau over a width ~a; small a is a sharp kink), ``stick_slip`` (b > a, k below k_c,
peak-to-peak 0.01–0.05).

Recording (instrument effects the other families lack): sample times at 10 Hz with a
rate error of 0–2 % and 3-ms jitter (written to 0.01 s); torque written with 4 or 5
significant digits in mN·m (RheoCompass writes 5: :file:`../shared/real-exports`);
noise white, pink (1/f from below the record's length up to 5 Hz) or both, per-sample
0.003–0.015 in COF at F_N0, continuous from the set-up interval into the friction
interval (a drifting zero); occasional single-sample spikes in torque (±0.05–0.3 in μ)
and in normal force (±5–15 %); the normal force wandering slowly by up to ±3 % (and
the friction force with it: the spring must follow) with 0.2 % noise; friction intervals
of 120, 300, 600 or 1,100 s; with a set-up interval of 20–60 s or without, a rest before
motion of 0–10 s; torque offsets 0, 0.2, −0.3, 0.5 mN·m.

Truth (:class:`generators.truth.Truth`): μ_K is the mean of the noise-free μ = f_s/n over the
settled plateau (over whole stick-slip cycles when it oscillates); the plateau settles at
the first distance after which the noise-free μ of the same run without the normal
force's wander (cycle means where it oscillates) stays within 0.002 of its level; μ_S the
largest noise-free μ before it. A static peak is ``distinct`` ≥ 0.02 above the plateau's
highest noise-free value, ``none`` ≤ 0.005 above it, ``ambiguous`` between (not scored),
as in the validation family. A run is ``truncated`` when less than
``SCORED_PLATEAU_MM`` (0.5 mm, about 70 s) of settled plateau is in the trace; its truth
is then that of the run continued.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from tribopipe.measurement import ANGLE, NORMAL_FORCE, SPEED, TEMPERATURE, TIME, TORQUE
from tribopipe.physics import FOUNDING_FRICTION_RADIUS_MM

from .instrument import (
    NOISE_COLOURS,
    add_spikes,
    coloured_noise,
    sample_times,
    significant_digits,
)
from .synthetic import write_intervals_export
from .truth import OSCILLATION_MIN_PP, Truth, static_kind

if TYPE_CHECKING:
    from collections.abc import Callable
    from os import PathLike

    import pandas as pd

SHAPES: tuple[str, ...] = ("peak", "peak_weakening", "creep", "stick_slip")
SPECIAL_SETS: tuple[str, ...] = ("offset_unknown",)
DURATIONS_S: tuple[float, ...] = (120.0, 300.0, 600.0, 1100.0)

#: the grid, fixed before this family was first reduced; do not adjust it to results
BASE_SEED = 20261124
PEAK_DISTANCES_MM: tuple[float, ...] = (0.02, 0.05, 0.15, 0.4, 1.0, 2.5, 5.0)
#: a stick-slip cycle lasts ~peak-to-peak/k: with a spring stiff enough for a peak within
#: 0.05 mm it is shorter than 3 samples at 10 Hz, so not resolved; none below 0.15 mm
STICK_SLIP_DISTANCES_MM: tuple[float, ...] = (0.15, 0.4, 1.0, 2.5, 5.0)
DRAWS = 30  # per (shape, distance); stick-slip 42 (fewer distances, the same 210 runs)
STICK_SLIP_DRAWS = 42
OFFSET_UNKNOWN_PER_SHAPE = 14

SETTLE_TOL = 0.002  # noise-free μ within this of its level: settled [COF]
SCORED_PLATEAU_MM = 0.5  # at least this much settled plateau in the trace, else truncated
SLIP_SPEED_FACTOR = 10.0  # a stick-slip cycle starts where v passes 10·V
SILICONE_DENSITY_KG_M3 = 1100.0
PIN_HEIGHT_MM = 6.0
_FINE_DT_S = 0.01  # the noise-free curve is evaluated on this time grid for the truth


@dataclass(frozen=True)
class RateStateRun:
    """One run of the family, every parameter explicit (module doc for the model).

    ``k_per_mm``: spring stiffness [COF/mm]; ``a``, ``b``: rate-and-state parameters;
    ``dc_mm``: D_c [mm]; ``eta_s_per_mm``: radiation damping [COF·s/mm]; ``hold_s``: time
    in contact before motion; ``duration_s``: the friction interval after the rest.
    ``force_wander`` and ``force_period_s``: amplitude (relative) and period of the normal
    force's slow wander (a second term of a third the amplitude at 0.37 of the period).
    ``rate_error``: relative error of the sampling interval; ``jitter_s``: its standard
    deviation per sample; ``spike_rate_hz``: torque spikes per second (force spikes at
    half that); ``torque_digits``: significant digits the torque is written with [mN·m].
    ``nominal_peak_mm`` is the grid's peak (creep: 95 % rise) distance.
    """

    shape: str
    mu0: float
    a: float
    b: float
    dc_mm: float
    k_per_mm: float
    eta_s_per_mm: float = 1e-3
    hold_s: float = 60.0
    duration_s: float = 300.0
    noise: float = 0.005
    noise_colour: str = "white"
    torque_offset_Nm: float = 0.0
    setup_interval: bool = True
    setup_s: float = 30.0
    rest_s: float = 2.0
    normal_force_N: float = 3.0
    force_wander: float = 0.0
    force_period_s: float = 400.0
    force_phase: float = 0.0
    rate_error: float = 0.0
    jitter_s: float = 0.0
    spike_rate_hz: float = 0.0
    torque_digits: int = 5
    temperature_C: float = 20.0
    direction: int = 1
    seed: int = 0
    speed_rpm: float = 0.005
    sample_rate_Hz: float = 10.0
    friction_radius_mm: float = FOUNDING_FRICTION_RADIUS_MM
    label: str = ""
    nominal_peak_mm: float = 0.0

    @property
    def speed_mm_s(self) -> float:
        """Sliding speed V at the friction radius [mm/s]."""
        return self.speed_rpm * 2 * math.pi / 60 * self.friction_radius_mm

    @property
    def distance_mm(self) -> float:
        """Sliding distance of the friction interval after the rest [mm]."""
        return self.duration_s * self.speed_mm_s

    @property
    def critical_stiffness_per_mm(self) -> float:
        """k_c = (b − a)/D_c [COF/mm]: steady sliding is unstable for k below it."""
        return (self.b - self.a) / self.dc_mm


def pin_stiffness_per_mm(normal_force_N: float, shear_modulus_kPa: float,
                         height_mm: float = PIN_HEIGHT_MM, n_pins: int = 3,
                         pin_radius_mm: float = 3.0) -> float:
    """Shear stiffness of the pins in COF per mm of holder travel: n·G·π r² / (h·F_N)
    (kPa·mm² = 1e-3 N, so ×1e-3). Ecoflex 00-50 (25 kPa), 6 mm, at 1 N: 0.353 /mm."""
    return n_pins * shear_modulus_kPa * 1e-3 * math.pi * pin_radius_mm**2 / (
        height_mm * normal_force_N)


def radiation_damping_s_per_mm(k_per_mm: float, normal_force_N: float,
                               height_mm: float = PIN_HEIGHT_MM, n_pins: int = 3,
                               pin_radius_mm: float = 3.0) -> float:
    """Radiation damping η [COF·s/mm] of pins of that stiffness: the shear-wave impedance
    √(G·ρ)/2 per area (G from the stiffness, ρ of silicone) times the pins' area, over
    F_N. Ecoflex pins at 1 N: 2.2e-4 s/mm (a slip of 0.05 in μ runs at ~200 mm/s)."""
    area_m2 = n_pins * math.pi * (pin_radius_mm * 1e-3) ** 2
    g_pa = k_per_mm * normal_force_N * height_mm / (area_m2 * 1e6) * 1e6
    impedance = area_m2 * math.sqrt(g_pa * SILICONE_DENSITY_KG_M3) / 2.0  # N·s/m
    return impedance * 1e-3 / normal_force_N


# --------------------------------------------------------------------------- the model


def _wander_terms(run: RateStateRun) -> tuple[float, float, float, float, float]:
    """(a1, ω1, a2, ω2, φ): n(t) = 1 + a1·sin(ω1·t + φ) + a2·sin(ω2·t + 2.1·φ)."""
    w1 = 2 * math.pi / run.force_period_s
    return 0.75 * run.force_wander, w1, 0.25 * run.force_wander, w1 / 0.37, run.force_phase


def force_ratio(run: RateStateRun, t: Any) -> tuple[np.ndarray, np.ndarray]:
    """n(t) = F_N(t)/F_N0 and dn/dt [1/s] at times ``t`` [s from the start of motion]."""
    t = np.asarray(t, dtype=float)
    a1, w1, a2, w2, ph = _wander_terms(run)
    n = 1.0 + a1 * np.sin(w1 * t + ph) + a2 * np.sin(w2 * t + 2.1 * ph)
    dn = a1 * w1 * np.cos(w1 * t + ph) + a2 * w2 * np.cos(w2 * t + 2.1 * ph)
    return n, dn


@dataclass(frozen=True)
class Solution:
    """A simulated friction interval: ``t`` [s from the start of motion], holder ``x``
    [mm], slip speed ``v`` [mm/s] and the spring force over the normal force, ``mu``
    (what an ideal instrument measures), all shape (n,)."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    mu: np.ndarray


def _rhs(run: RateStateRun, wander: bool) -> Callable[[float, np.ndarray], list[float]]:
    """The right-hand side of the ODE in (δ, ln(v/V), ln(Vθ/Dc)) for ``solve_ivp``: from
    f_s = k·(x − δ) = n·μ_f + η·v differentiated in time (module doc)."""
    V, a, b, dc, k, eta = (run.speed_mm_s, run.a, run.b, run.dc_mm, run.k_per_mm,
                           run.eta_s_per_mm)
    a1, w1, a2, w2, ph = _wander_terms(run)

    def rhs(t: float, state: np.ndarray) -> list[float]:
        _, y, psi = state
        v = V * math.exp(min(y, 300.0))
        dpsi = (V / dc) * (math.exp(min(-psi, 300.0)) - math.exp(min(y, 300.0)))
        mu_f = run.mu0 + a * y + b * psi
        n, dn = 1.0, 0.0
        if wander:  # force_ratio, in scalars (called ~10^5 times per run)
            n += a1 * math.sin(w1 * t + ph) + a2 * math.sin(w2 * t + 2.1 * ph)
            dn = a1 * w1 * math.cos(w1 * t + ph) + a2 * w2 * math.cos(w2 * t + 2.1 * ph)
        dy = (k * (V - v) - dn * mu_f - n * b * dpsi) / (n * a + eta * v)
        return [v, dy, dpsi]

    return rhs


def _initial_state(run: RateStateRun) -> list[float]:
    """(δ, ln(v/V), ln(Vθ/Dc)) at the start of motion: no slip, the spring unloaded, θ
    aged over the hold."""
    psi0 = math.log1p(run.speed_mm_s * run.hold_s / run.dc_mm)
    return [0.0, (0.0 - run.mu0 - run.b * psi0) / run.a, psi0]


def simulate(run: RateStateRun, t_end: float, *, wander: bool = True,
             dt: float = _FINE_DT_S) -> Solution:
    """Integrate the run from the start of motion to ``t_end`` [s] and sample it every
    ``dt`` [s] (LSODA, rtol 1e-8); ``wander=False`` holds the normal force constant."""
    from scipy.integrate import solve_ivp

    t_eval = np.arange(0.0, t_end + 0.5 * dt, dt)
    sol = solve_ivp(
        _rhs(run, wander), (0.0, float(t_eval[-1])), _initial_state(run), method="LSODA",
        t_eval=t_eval, rtol=1e-8, atol=[1e-10, 1e-7, 1e-7], max_step=2.0,
    )
    if sol.status < 0:
        raise RuntimeError(f"{run.label}: rate-and-state integration failed: {sol.message}")
    t = sol.t
    x = run.speed_mm_s * t
    n = force_ratio(run, t)[0] if wander else np.ones_like(t)
    mu = run.k_per_mm * (x - sol.y[0]) / n
    return Solution(t=t, x=x, v=run.speed_mm_s * np.exp(np.minimum(sol.y[1], 300.0)), mu=mu)


@functools.lru_cache(maxsize=4)
def recorded_span(run: RateStateRun, wander: bool = True) -> Solution:
    """:func:`simulate` over the run's friction interval (``duration_s`` and a margin for
    the sampling's jitter), kept for the truth and the recording of the same run."""
    return simulate(run, run.duration_s + 0.5, wander=wander)


def sample_mu(run: RateStateRun, t: Any) -> np.ndarray:
    """The noise-free μ at times ``t`` [s from the start of motion; ≤ 0 at rest: 0]."""
    t = np.asarray(t, dtype=float)
    out = np.zeros(t.size)
    moving = t > 0
    if not moving.any():
        return out
    fine = recorded_span(run)
    if float(t[moving].max()) > fine.t[-1]:
        fine = simulate(run, float(t[moving].max()) + _FINE_DT_S)
    out[moving] = np.interp(t[moving], fine.t, fine.mu)
    return out


def _event_speed_reaches_drive(t: float, state: np.ndarray) -> float:
    return float(state[1])


_event_speed_reaches_drive.terminal = True  # type: ignore[attr-defined]
_event_speed_reaches_drive.direction = 1.0  # type: ignore[attr-defined]


def peak_distance_mm(run: RateStateRun, t_max: float = 4000.0) -> tuple[float, float]:
    """(distance [mm], μ) of the static peak: where the slip speed first reaches V (no
    wander; there the spring force is largest); (inf, nan) when it does not within
    ``t_max`` [s] (a creep)."""
    from scipy.integrate import solve_ivp

    res = solve_ivp(_rhs(run, False), (0.0, t_max), _initial_state(run), method="LSODA",
                    rtol=1e-8, atol=[1e-10, 1e-7, 1e-7], max_step=2.0,
                    events=_event_speed_reaches_drive)
    if res.t_events[0].size == 0:
        return math.inf, math.nan
    x = run.speed_mm_s * float(res.t_events[0][0])
    return x, run.k_per_mm * (x - float(res.y_events[0][0][0]))


def rise_distance_mm(run: RateStateRun, fraction: float = 0.95) -> float:
    """Distance [mm] where the noise-free μ (no wander) first reaches ``fraction`` of μ0."""
    t_guess = (run.mu0 / run.k_per_mm + 50 * run.a / run.k_per_mm + 0.1) / run.speed_mm_s
    sol = simulate(run, min(4000.0, 3 * t_guess), wander=False, dt=0.05)
    hit = np.flatnonzero(sol.mu >= fraction * run.mu0)
    return float(sol.x[hit[0]]) if hit.size else math.inf


# --------------------------------------------------------------------------- the truth


def _until(sol: Solution, t_end: float) -> Solution:  # the solution up to t_end [s]
    keep = sol.t <= t_end + 1e-9
    return Solution(t=sol.t[keep], x=sol.x[keep], v=sol.v[keep], mu=sol.mu[keep])


def _cycle_starts(sol: Solution, run: RateStateRun) -> np.ndarray:
    """Indices where a stick-slip cycle starts (v passes SLIP_SPEED_FACTOR·V upward)."""
    fast = sol.v > SLIP_SPEED_FACTOR * run.speed_mm_s
    return np.flatnonzero(fast[1:] & ~fast[:-1]) + 1


def _settle_index(values: np.ndarray, level: float) -> int:
    off = np.flatnonzero(np.abs(values - level) > SETTLE_TOL)
    return 0 if off.size == 0 else int(off[-1]) + 1


def _analyse(run: RateStateRun, t_end: float) -> dict[str, float]:
    """Settle distance, μ_K, μ_S and the plateau's highs and peak-to-peak of the run
    simulated to ``t_end`` [s] (the module doc's definitions)."""
    if t_end == run.duration_s:
        calm, real = recorded_span(run, False), recorded_span(run)
        calm, real = _until(calm, t_end), _until(real, t_end)
    else:
        calm, real = simulate(run, t_end, wander=False), simulate(run, t_end)
    starts = _cycle_starts(calm, run)
    if run.shape == "stick_slip" and starts.size >= 4:
        means = np.array([calm.mu[i:j].mean() for i, j in zip(starts[:-1], starts[1:],
                                                               strict=True)])
        level = float(np.mean(means[means.size // 2 :]))
        first = _settle_index(means, level)
        settle_idx = int(starts[min(first, starts.size - 2)])
        if first >= means.size:
            settle_idx = calm.t.size - 1
    else:
        settle_idx = min(_settle_index(calm.mu, run.mu0), calm.t.size - 1)
    settle_mm = float(calm.x[settle_idx])
    plateau = real.x >= settle_mm
    real_starts = _cycle_starts(real, run)
    whole = real_starts[real.x[real_starts] >= settle_mm]
    if run.shape == "stick_slip" and whole.size >= 2:
        mu_k = float(real.mu[whole[0] : whole[-1]].mean())
    else:
        mu_k = float(real.mu[plateau].mean()) if plateau.any() else run.mu0
    before = ~plateau
    k = int(np.argmax(np.where(before, real.mu, -np.inf))) if before.any() else 0
    on = real.mu[plateau]
    # the oscillation's size is that of the established cycle: the later half of the
    # plateau (the first slip after the peak overshoots)
    late = real.mu[real.x >= 0.5 * (settle_mm + float(real.x[-1]))]
    return {
        "settle_mm": settle_mm,
        "mu_k": mu_k,
        "mu_s": float(real.mu[k]),
        "mu_s_distance_mm": float(real.x[k]),
        "plateau_high": float(on.max()) if on.size else float(real.mu[-1]),
        "oscillation_pp": float(np.percentile(late, 99.5) - np.percentile(late, 0.5))
        if late.size else 0.0,
    }


def truth(run: RateStateRun) -> Truth:
    """The known answer for ``run`` (module doc)."""
    found = _analyse(run, run.duration_s)
    truncated = run.distance_mm - found["settle_mm"] < SCORED_PLATEAU_MM
    if truncated:
        extra = max(run.duration_s, 1.5 * run.mu0 / run.k_per_mm / run.speed_mm_s) + 300.0
        found = _analyse(run, run.duration_s + extra)
    mu_s, high = found["mu_s"], found["plateau_high"]
    static = static_kind(mu_s, high)
    return Truth(
        mu_s=mu_s if static != "none" else found["mu_k"],
        mu_k=found["mu_k"],
        mu_s_distance_mm=found["mu_s_distance_mm"],
        static=static,
        oscillating=run.shape == "stick_slip" and found["oscillation_pp"] >= OSCILLATION_MIN_PP,
        oscillation_pp=found["oscillation_pp"],
        settle_mm=found["settle_mm"],
        plateau_high=high,
        sliding_distance_mm=run.distance_mm,
        truncated=truncated,
        offset_estimable=run.setup_interval or run.rest_s * run.sample_rate_Hz >= 5,
    )


# --------------------------------------------------------------------------- the recording


def make_intervals(run: RateStateRun) -> list[pd.DataFrame]:
    """The intervals the instrument records for ``run``: [set-up,] friction, each with
    ``time_s, torque_Nm, normal_force_N, angle_rad, speed_rad_s, temperature_C`` and its
    own clock. The noise runs on from the set-up into the friction interval."""
    import pandas as pd

    rng = np.random.default_rng([run.seed, 3])
    R_m = run.friction_radius_mm * 1e-3
    omega = run.speed_rpm * 2 * math.pi / 60

    def clock(span_s: float) -> np.ndarray:
        return sample_times(rng, run.sample_rate_Hz, span_s, rate_error=run.rate_error,
                            jitter_s=run.jitter_s)

    t_setup = clock(run.setup_s) if run.setup_interval else np.empty(0)
    t_run = clock(run.rest_s + run.duration_s)
    n_setup = t_setup.size
    # time from the start of motion, over both intervals
    t_motion = np.concatenate([t_setup - run.setup_s, t_run]) - run.rest_s
    noise = run.noise * run.normal_force_N * R_m * coloured_noise(rng, t_motion.size,
                                                                   run.noise_colour)
    mu = np.zeros(t_motion.size)
    mu[n_setup:] = sample_mu(run, t_motion[n_setup:])
    force = run.normal_force_N * force_ratio(run, t_motion)[0]
    force[:n_setup] *= np.clip(t_setup / (0.6 * run.setup_s), 0.0, 1.0)
    torque = run.direction * mu * force * R_m + run.torque_offset_Nm + noise
    force_read = force * (1.0 + 0.002 * rng.standard_normal(t_motion.size))
    span = float(t_motion[-1] - t_motion[0])
    torque = add_spikes(torque, rng, run.spike_rate_hz, span, 0.05, 0.3,
                        scale=run.normal_force_N * R_m)
    force_read = add_spikes(force_read, rng, 0.5 * run.spike_rate_hz, span, 0.05, 0.15,
                            relative=True)
    torque = significant_digits(torque * 1e3, run.torque_digits) * 1e-3
    angle = run.direction * np.maximum(t_motion, 0.0) * run.speed_mm_s / run.friction_radius_mm
    speed = run.direction * np.where(t_motion > 0, omega, 0.0)
    temperature = run.temperature_C + 0.05 * rng.standard_normal(t_motion.size)
    frames: list[pd.DataFrame] = []
    for part, times in ((slice(0, n_setup), t_setup), (slice(n_setup, None), t_run)):
        if times.size == 0:
            continue
        frames.append(pd.DataFrame({
            TIME: times, TORQUE: torque[part], NORMAL_FORCE: force_read[part],
            ANGLE: angle[part], SPEED: speed[part], TEMPERATURE: temperature[part],
        }))
    return frames


def write_export(path: str | PathLike[str], run: RateStateRun, *, language: str = "en") -> Path:
    """Write ``run`` as a RheoCompass export through the project's export writer."""
    return write_intervals_export(path, make_intervals(run), project="ratestate",
                                  test=run.shape, sample=run.label or "pin",
                                  language=language)


# --------------------------------------------------------------------------- building runs


def _bisect_log(fn: Any, target: float, lo: float, hi: float, rounds: int = 40) -> float:
    """The x in [lo, hi] (log scale) where the decreasing function ``fn`` meets
    ``target``."""
    for _ in range(rounds):
        mid = math.sqrt(lo * hi)
        if fn(mid) > target:
            lo = mid
        else:
            hi = mid
        if hi / lo < 1.003:
            break
    return math.sqrt(lo * hi)


def _with_stiffness_for(run: RateStateRun, peak_mm: float) -> RateStateRun:
    """The run with k (and η with it) chosen so its peak (creep: its 95 % rise) lies at
    ``peak_mm`` [mm]; the larger D_c is halved while the slip before the peak alone
    reaches past it."""
    def at(k: float) -> RateStateRun:
        return replace(run, k_per_mm=k, eta_s_per_mm=radiation_damping_s_per_mm(
            k, run.normal_force_N))

    def position(k: float) -> float:
        r = at(k)
        return rise_distance_mm(r) if run.shape == "creep" else peak_distance_mm(r)[0]

    for _ in range(6):
        if position(5e3) < 0.8 * peak_mm:
            break
        run = replace(run, dc_mm=run.dc_mm / 2)
    return at(_bisect_log(position, peak_mm, 1e-3, 5e3))


def oscillation_pp(run: RateStateRun, cycles: int = 12) -> float:
    """Peak-to-peak of the noise-free μ (no wander) over the second half of about
    ``cycles`` stick-slip cycles after the peak (~0 when it does not oscillate)."""
    x_peak, _ = peak_distance_mm(run)
    start = x_peak if math.isfinite(x_peak) else run.mu0 / run.k_per_mm
    cycle_mm = max(15.0 * (run.b - run.a) / run.k_per_mm, 0.001)
    t_end = (start + 2 * cycles * cycle_mm + 0.3) / run.speed_mm_s
    sol = simulate(run, t_end, wander=False, dt=0.02)
    late = sol.x >= start + 0.5 * (sol.x[-1] - start)
    return float(np.ptp(sol.mu[late]))


def _with_oscillation(run: RateStateRun, pp_target: float, ratio: float) -> RateStateRun:
    """The run with b − a scaled (D_c with it, so k/k_c stays ``ratio``) until its limit
    cycle has peak-to-peak ``pp_target``."""
    gap = pp_target / 15.0
    for _ in range(5):
        run = replace(run, b=run.a + gap, dc_mm=gap * ratio / run.k_per_mm)
        pp = oscillation_pp(run)
        if pp <= 0 or abs(pp - pp_target) < 0.05 * pp_target:
            break
        gap *= pp_target / pp
    return run


def build_run(shape: str, peak_mm: float, index: int, *, special: str | None = None
              ) -> RateStateRun:
    """Run number ``index`` of ``shape`` with its peak (creep: 95 % rise) at ``peak_mm``
    (k is solved for it), everything else drawn from the seeded stream
    ``[BASE_SEED, index]``: μ0 0.2–1.1; b 0.005–0.08 and D_c 0.002–0.05 mm (at most a
    fifth of the peak distance), log-uniform; ``peak``: a = b + 0.001–0.02;
    ``peak_weakening``: b − a = 0.2–0.8 of k·D_c; ``creep``: b = 0, a 0.001–0.03;
    ``stick_slip``: a 0.002–0.03, b − a for a peak-to-peak of 0.01–0.05 at k/k_c
    0.5–0.9; a hold of 10–300 s before the set-up; the instrument's draws as in the
    module doc. ``special="offset_unknown"``: no set-up interval and no rest."""
    if shape not in SHAPES:
        raise ValueError(f"shape must be one of {', '.join(SHAPES)}, got {shape!r}")
    rng = np.random.default_rng([BASE_SEED, index])
    mu0 = float(rng.uniform(0.2, 1.1))
    noise = float(rng.uniform(0.003, 0.015))
    colour = str(rng.choice(NOISE_COLOURS))
    force = float(rng.choice([1.0, 3.0, 5.0, 9.0]))
    offset = float(rng.choice([0.0, 2e-4, -3e-4, 5e-4]))
    setup = bool(rng.uniform() < 0.5)
    rest = float(rng.choice([0.0, 2.0, 5.0, 10.0] if setup else [2.0, 5.0, 10.0]))
    setup_s = float(rng.uniform(20.0, 60.0))
    hold = float(rng.uniform(10.0, 300.0))
    duration = float(rng.choice(DURATIONS_S))
    a = float(math.exp(rng.uniform(math.log(0.002), math.log(0.03))))
    b = float(math.exp(rng.uniform(math.log(0.005), math.log(0.08))))
    dc = float(math.exp(rng.uniform(math.log(0.002), math.log(0.05))))
    gap_frac = float(rng.uniform(0.2, 0.8))
    strengthening = float(rng.uniform(0.001, 0.02))
    creep_a = float(math.exp(rng.uniform(math.log(0.001), math.log(0.03))))
    pp = float(rng.uniform(0.01, 0.05))
    ratio = float(rng.uniform(0.5, 0.9))
    extras = {
        "force_wander": float(rng.uniform(0.005, 0.03)),
        "force_period_s": float(rng.uniform(150.0, 900.0)),
        "force_phase": float(rng.uniform(0.0, 2 * math.pi)),
        "rate_error": float(rng.uniform(0.0, 0.02)),
        "jitter_s": 0.003,
        "spike_rate_hz": float(rng.uniform(0.0, 1.0 / 60.0)),
        "torque_digits": int(rng.choice([4, 5])),
        "temperature_C": float(rng.choice([10.0, 20.0, 40.0])),
        "direction": 1 if rng.uniform() < 0.5 else -1,
    }
    if special == "offset_unknown":
        setup, rest = False, 0.0
        offset = float(rng.choice([2e-4, -3e-4, 5e-4]))
    hold_total = hold + rest + (setup_s if setup else 0.0)
    dc = min(dc, peak_mm / 5.0)
    if shape == "peak":
        a = b + strengthening
    elif shape == "creep":
        a, b = creep_a, 0.0
    elif shape == "stick_slip":
        b, dc = a + pp / 15.0, pp / 15.0 * ratio  # k_c = k/ratio at k = 1 (solved below)
    run = RateStateRun(
        shape=shape, mu0=mu0, a=a, b=b, dc_mm=dc, k_per_mm=1.0, hold_s=hold_total,
        duration_s=duration, noise=noise, noise_colour=colour, torque_offset_Nm=offset,
        setup_interval=setup, setup_s=setup_s, rest_s=rest, normal_force_N=force,
        seed=int(np.random.SeedSequence([BASE_SEED, index]).generate_state(1)[0]),
        label=f"{special or shape}-{index}", nominal_peak_mm=peak_mm, **extras,
    )
    if shape == "peak_weakening":
        # stable: k above k_c = (b − a)/D_c by the drawn margin, whatever k the peak needs
        run = _with_stiffness_for(replace(run, a=max(0.001, 0.5 * b)), peak_mm)
        gap = min(gap_frac * run.k_per_mm * run.dc_mm, b - 0.001)
        run = _with_stiffness_for(replace(run, a=b - gap), peak_mm)
        gap = min(gap_frac * run.k_per_mm * run.dc_mm, b - 0.001)
        return replace(run, a=b - gap)
    if shape == "stick_slip":
        for _ in range(2):
            run = _with_stiffness_for(run, peak_mm)
            run = _with_oscillation(run, pp, ratio)
        return run
    return _with_stiffness_for(run, peak_mm)


@dataclass(frozen=True)
class GridPoint:
    """One run of the grid before it is built: its set, shape, nominal peak distance
    [mm] and seed index."""

    set: str
    shape: str
    peak_mm: float
    index: int

    def build(self) -> RateStateRun:
        """The run (:func:`build_run`)."""
        special = self.set if self.set in SPECIAL_SETS else None
        return build_run(self.shape, self.peak_mm, self.index, special=special)


def ratestate_grid(limit_per_cell: int | None = None) -> list[GridPoint]:
    """The fixed grid: ``peak``, ``peak_weakening`` and ``creep`` × 7 distances × 30
    draws, ``stick_slip`` × 5 distances × 42 (840 runs); ``offset_unknown``: 14 per shape
    over the distances in turn (56). ``limit_per_cell`` keeps the first draws of each
    cell (a quick subset of the same runs)."""
    points: list[GridPoint] = []
    index = 0
    for shape in SHAPES:
        distances = STICK_SLIP_DISTANCES_MM if shape == "stick_slip" else PEAK_DISTANCES_MM
        draws = STICK_SLIP_DRAWS if shape == "stick_slip" else DRAWS
        for peak in distances:
            for d in range(draws):
                if limit_per_cell is None or d < limit_per_cell:
                    points.append(GridPoint(shape, shape, peak, index))
                index += 1
    for shape in SHAPES:
        distances = STICK_SLIP_DISTANCES_MM if shape == "stick_slip" else PEAK_DISTANCES_MM
        for d in range(OFFSET_UNKNOWN_PER_SHAPE):
            if limit_per_cell is None or d < 2 * limit_per_cell:
                points.append(GridPoint("offset_unknown", shape, distances[d % len(distances)],
                                        index))
            index += 1
    return points

"""Force-based friction rigs from their physics: a D1894 sled on a universal testing
machine, a linear reciprocating tribometer, a rotary pin-on-disc tribometer.

Three families for the force-based reductions, each generated from the mechanics of its
rig (not from the shapes the reduction looks for) with a known answer, and their fixed
grid and seeds (:func:`forcerig_grid`). The reduction was not tuned on them: the grid and
seeds were committed before the first reduction.

``sled``           ASTM D1894 / ISO 8295: a sled of mass m (200 g in the standard) on a
                   plane, pulled through a compliant string (stiffness k, damping ζ) by a
                   crosshead at 150 mm/min. Coulomb friction with a static coefficient
                   μ_S at breakaway and a kinetic μ_K plus a small velocity-strengthening
                   term; a stuck sled regains its static friction with the time it has
                   stuck (aging, time constant θ): a soft string and a fast aging give
                   stick-slip, a stiff, damped string steady sliding. The load cell reads
                   the string's tension (the friction force the sled transmits) with
                   noise, a zero offset and, in the ``preloaded`` variant, a record that
                   starts with the string already pulled taut. The crosshead stops before
                   the record ends (a motor stop). No normal-force column: the sled's
                   weight is the normal force.
``reciprocating``  ASTM G133: a pin on a flat driven by a crank, x = (L/2)·sin(2πft); the
                   friction force F = μ_c·F_N·tanh(v/v₀) opposes the motion; the flat is
                   tilted (a constant tangential share δ·F_N, the same sign both ways) and
                   μ_c runs in over cycles, μ_c = μ_ss + (μ_0 − μ_ss)·exp(−c/c₀). The load
                   cell has a zero offset; the record starts at rest.
``rotary``         ASTM G99 on a force tribometer: a pin on a disc turning at n rpm on a
                   track of radius R. The disc is not flat: the track's slope along the
                   sliding direction, a₁·sin(θ+φ₁) + a₂·sin(2θ+φ₂), adds to the measured
                   tangential force (run-out, locked to the rotation); some runs also
                   stick-slip (a saw-tooth whose period is not locked to the rotation).
                   The friction rises from rest to μ_S and weakens to μ_K over a slip
                   distance d_c; the motor ramps up at the start and down at the end.

Truth (:class:`ForceTruth`): μ_K is the mean of the noise-free friction over the settled
sliding (sled: the string force from 40 % of the travel to the crosshead's stop, over
whole cycles where it stick-slips; reciprocating: μ_ss; rotary: μ_K plus the mean of its
saw-tooth, which is 0), μ_S the breakaway peak (sled and rotary: μ_S; reciprocating: not
defined, ``None``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

#: standard gravity [m/s²]
G = 9.80665


@dataclass(frozen=True)
class ForceTruth:
    """What a correct reduction of a force-rig run finds: μ_K, μ_S (``None`` where the
    method defines none), whether it stick-slips, whether its disc runs out, whether the
    record starts under load."""

    mu_k: float
    mu_s: float | None
    stick_slip: bool
    run_out: bool
    preloaded: bool


@dataclass(frozen=True)
class SledRun:
    """A D1894 sled pull; forces in N, lengths in mm, times in s (see module docstring)."""

    mu_s: float = 0.35
    mu_k: float = 0.25
    mass_g: float = 200.0
    string_k_N_per_mm: float = 0.5
    damping_ratio: float = 0.5
    aging_s: float = 1e9             # time to regain static friction; 1e9: never
    velocity_strengthening: float = 0.002   # μ per (mm/s) above the drive speed
    speed_mm_min: float = 150.0
    travel_mm: float = 130.0
    rest_s: float = 2.0              # at rest before the crosshead starts
    stop_s: float = 3.0              # at rest after it stops
    rate_Hz: float = 100.0
    noise_N: float = 0.003
    offset_N: float = 0.0
    preload_fraction: float = 0.0    # string tension at the start, × μ_S·F_N
    seed: int = 0

    @property
    def normal_force_N(self) -> float:
        return self.mass_g * 1e-3 * G


def simulate_sled(run: SledRun, dt: float = 2e-4) -> dict[str, np.ndarray]:
    """Integrate the sled's motion (semi-implicit Euler, ``dt`` [s]); returns time [s],
    crosshead [mm], sled [mm], string force [N] (noise-free), stuck (bool), at the
    recording rate."""
    m = run.mass_g * 1e-3
    k = run.string_k_N_per_mm * 1e3  # N/m
    c = 2.0 * run.damping_ratio * math.sqrt(k * m)
    n_force = run.normal_force_N
    v_drive = run.speed_mm_min / 60.0 * 1e-3  # m/s
    t_move = run.travel_mm * 1e-3 / v_drive
    t_end = run.rest_s + t_move + run.stop_s
    steps = int(t_end / dt)
    every = max(1, int(round(1.0 / (run.rate_Hz * dt))))
    xc = 0.0
    xs = -run.preload_fraction * run.mu_s * n_force / k  # the string pre-stretched
    vs = 0.0
    stuck = True
    stuck_since = 0.0
    slid = False  # the first breakaway meets the full static friction μ_S
    out_t, out_c, out_s, out_f, out_stuck = [], [], [], [], []
    for i in range(steps + 1):
        t = i * dt
        # the crosshead: at rest, then at v_drive, then it stops (decelerating over 0.1 s)
        if t < run.rest_s:
            vc = 0.0
        elif t < run.rest_s + t_move:
            vc = v_drive
        else:
            vc = v_drive * max(0.0, 1.0 - (t - run.rest_s - t_move) / 0.1)
        xc += vc * dt
        stretch = xc - xs
        tension = k * stretch + c * (vc - vs) if stretch > 0 else 0.0
        tension = max(tension, 0.0)
        if stuck:
            held = run.mu_s if not slid else run.mu_k + (run.mu_s - run.mu_k) * (
                1.0 - math.exp(-(t - stuck_since) / run.aging_s))
            if tension > held * n_force:
                stuck, slid = False, True
            else:
                vs = 0.0
        if not stuck:
            mu = run.mu_k + run.velocity_strengthening * max(0.0, vs * 1e3 - v_drive * 1e3)
            vs_new = vs + (tension - mu * n_force) / m * dt
            if vs_new <= 0.0:
                vs, stuck, stuck_since = 0.0, True, t
            else:
                vs = vs_new
        xs += vs * dt
        if i % every == 0:
            out_t.append(t)
            out_c.append(xc * 1e3)
            out_s.append(xs * 1e3)
            out_f.append(tension)
            out_stuck.append(stuck)
    return {"t": np.array(out_t), "crosshead_mm": np.array(out_c),
            "sled_mm": np.array(out_s), "force_N": np.array(out_f),
            "stuck": np.array(out_stuck)}


def _sled_plateau(run: SledRun, sim: dict[str, np.ndarray]) -> np.ndarray:
    """The truth's plateau: from 40 % of the crosshead's travel to its stop."""
    t_move_end = run.rest_s + run.travel_mm / (run.speed_mm_min / 60.0)
    return (sim["crosshead_mm"] >= 0.4 * run.travel_mm) & (sim["t"] <= t_move_end)


def sled_truth(run: SledRun) -> ForceTruth:
    """μ_K: the mean string force over the plateau / F_N; μ_S: the breakaway, the largest
    string force before the sled first slides / F_N (as simulated, at the recording
    rate); stick-slip when the sled sticks again at least 4 times on the plateau."""
    sim = simulate_sled(run)
    first_slide = int(np.argmin(sim["stuck"][1:])) + 1
    plateau = _sled_plateau(run, sim)
    sticks = np.flatnonzero(np.diff(sim["stuck"][plateau].astype(int)) == 1).size
    force = sim["force_N"][plateau]
    stick_slip = sticks >= 4
    if stick_slip:  # over whole cycles: from the first re-stick to the last
        starts = np.flatnonzero(np.diff(sim["stuck"][plateau].astype(int)) == 1)
        force = force[starts[0] : starts[-1]]
    breakaway = float(np.max(sim["force_N"][: first_slide + 1]))
    return ForceTruth(mu_k=float(np.mean(force)) / run.normal_force_N,
                      mu_s=breakaway / run.normal_force_N, stick_slip=stick_slip, run_out=False,
                      preloaded=run.preload_fraction > 0)


def sled_table(run: SledRun) -> dict[str, np.ndarray]:
    """What the testing machine records: time [s], crosshead extension [mm], load [N]
    (noise, zero offset; the load cell tared before the string was attached)."""
    sim = simulate_sled(run)
    rng = np.random.default_rng(run.seed)
    load = sim["force_N"] + run.offset_N + rng.normal(0.0, run.noise_N, sim["t"].size)
    return {"time_s": sim["t"], "extension_mm": sim["crosshead_mm"], "load_N": load}


@dataclass(frozen=True)
class ReciprocatingRun:
    """A G133 reciprocating run; forces in N, lengths in mm, times in s."""

    mu_ss: float = 0.3
    mu_0: float = 0.45
    run_in_cycles: float = 10.0
    normal_force_N: float = 10.0
    stroke_mm: float = 10.0
    frequency_Hz: float = 2.0
    cycles: int = 150
    tilt: float = 0.02               # tangential share of the normal force from the tilt
    offset_N: float = 0.05
    noise_N: float = 0.02
    rate_Hz: float = 500.0
    rest_s: float = 1.0
    seed: int = 0


def reciprocating_truth(run: ReciprocatingRun) -> ForceTruth:
    """μ_K = μ_ss (the run-in has died out over the later cycles: the grid keeps
    ``cycles`` ≥ 10 × ``run_in_cycles``); no μ_S defined."""
    return ForceTruth(mu_k=run.mu_ss, mu_s=None, stick_slip=False, run_out=False,
                      preloaded=False)


def reciprocating_table(run: ReciprocatingRun) -> dict[str, np.ndarray]:
    """Time [s], position [mm], friction force [N], normal force [N]."""
    rng = np.random.default_rng(run.seed)
    t = np.arange(0.0, run.rest_s + run.cycles / run.frequency_Hz, 1.0 / run.rate_Hz)
    moving = t >= run.rest_s
    phase = 2.0 * math.pi * run.frequency_Hz * np.where(moving, t - run.rest_s, 0.0)
    x = 0.5 * run.stroke_mm * np.sin(phase)
    v = np.where(moving, math.pi * run.frequency_Hz * run.stroke_mm * np.cos(phase), 0.0)
    v0 = 0.01 * math.pi * run.frequency_Hz * run.stroke_mm
    cycle = np.where(moving, (t - run.rest_s) * run.frequency_Hz, 0.0)
    mu_c = run.mu_ss + (run.mu_0 - run.mu_ss) * np.exp(-cycle / run.run_in_cycles)
    fn = run.normal_force_N * (1.0 + 0.005 * rng.standard_normal(t.size))
    friction = mu_c * fn * np.tanh(v / v0) + run.tilt * fn
    friction = friction + run.offset_N + rng.normal(0.0, run.noise_N, t.size)
    return {"time_s": t, "position_mm": x, "friction_N": friction, "normal_N": fn}


@dataclass(frozen=True)
class RotaryRun:
    """A force pin-on-disc run; forces in N, lengths in mm, times in s."""

    mu_s: float = 0.5
    mu_k: float = 0.35
    slip_mm: float = 2.0             # slip-weakening distance d_c
    normal_force_N: float = 5.0
    radius_mm: float = 10.0
    rpm: float = 60.0
    revolutions: float = 60.0
    run_out_1: float = 0.02          # slope amplitude at 1× the rotation
    run_out_2: float = 0.01          # and at 2×
    stick_slip_pp: float = 0.0       # saw-tooth peak-to-peak [μ] (0: none)
    stick_slip_period_mm: float = 3.3
    noise_N: float = 0.01
    offset_N: float = 0.02
    rate_Hz: float = 50.0
    rest_s: float = 1.0
    ramp_s: float = 0.5
    stop_s: float = 2.0
    seed: int = 0


def rotary_truth(run: RotaryRun) -> ForceTruth:
    """μ_K: the kinetic level (the run-out's slope and the saw-tooth average to 0 over
    whole turns and teeth); μ_S the breakaway peak."""
    return ForceTruth(mu_k=run.mu_k, mu_s=run.mu_s, stick_slip=run.stick_slip_pp > 0,
                      run_out=run.run_out_1 > 0 or run.run_out_2 > 0, preloaded=False)


def rotary_table(run: RotaryRun) -> dict[str, np.ndarray]:
    """Time [s], revolutions [rev], friction force [N], normal force [N]."""
    rng = np.random.default_rng(run.seed)
    omega = run.rpm / 60.0  # rev/s
    t_turn = run.revolutions / omega
    t = np.arange(0.0, run.rest_s + run.ramp_s + t_turn + run.ramp_s + run.stop_s,
                  1.0 / run.rate_Hz)
    # speed [rev/s]: ramps up, holds, ramps down
    a = t - run.rest_s
    up = np.clip(a / run.ramp_s, 0.0, 1.0)
    down = np.clip((run.ramp_s + t_turn + run.ramp_s - a) / run.ramp_s, 0.0, 1.0)
    speed = omega * np.minimum(up, down) * (a > 0)
    rev = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(t))])
    s = rev * 2.0 * math.pi * run.radius_mm
    theta = 2.0 * math.pi * rev
    phases = rng.uniform(0.0, 2.0 * math.pi, 2)
    slope = (run.run_out_1 * np.sin(theta + phases[0])
             + run.run_out_2 * np.sin(2.0 * theta + phases[1]))
    # friction: elastic rise to μ_S over the first 0.05 mm, then slip-weakening to μ_K
    rise = np.clip(s / 0.05, 0.0, 1.0)
    weakening = np.where(s > 0.05, np.exp(-(s - 0.05) / run.slip_mm), 1.0)
    mu = rise * (run.mu_k + (run.mu_s - run.mu_k) * weakening)
    if run.stick_slip_pp > 0:
        tooth = (s / run.stick_slip_period_mm) % 1.0  # slow rise, sudden drop
        mu = mu + run.stick_slip_pp * (tooth - 0.5) * (s > 5 * run.slip_mm)
    moving = speed > 0
    mu = np.where(moving | (s > 0), mu, 0.0)
    # after the stop the pin holds a share of the last friction (elastic, not sliding)
    stopped = (a > run.ramp_s + t_turn + run.ramp_s)
    fn = run.normal_force_N * (1.0 + 0.003 * rng.standard_normal(t.size))
    friction = (mu + slope * (s > 0)) * fn
    friction = np.where(stopped, 0.6 * run.mu_k * fn, friction)
    friction = friction + run.offset_N + rng.normal(0.0, run.noise_N, t.size)
    return {"time_s": t, "revolutions": rev, "friction_N": friction, "normal_N": fn}


# ------------------------------------------------------------------------ the exports


def _number(v: float, decimal: str) -> str:
    text = f"{v:.6g}"
    return text.replace(".", ",") if decimal == "," else text


def write_sled_export(path: str | Path, run: SledRun, *, layout: str = "bluehill") -> Path:
    """Write the testing machine's export: ``bluehill`` (comma CSV, a header block, units
    in the header: ``Time (s)``) or ``testxpert`` (semicolon, decimal comma, a header
    block, a unit row, a trailing separator, a repeated header line and a footer)."""
    table = sled_table(run)
    p = Path(path)
    rows = zip(table["time_s"], table["extension_mm"], table["load_N"], strict=True)
    if layout == "bluehill":
        lines = ['"Sample","D1894 film"', '"Test speed","150 mm/min"',
                 f'"Sled mass","{run.mass_g:g} g"', "",
                 '"Time (s)","Extension (mm)","Load (N)"']
        lines += [f"{t:.4f},{x:.5f},{f:.6f}" for t, x, f in rows]
    else:
        lines = ["Prüfprogramm;Reibung D1894;", "Prüfgeschwindigkeit;150;mm/min;", "",
                 "Prüfzeit;Standardweg;Standardkraft;", "[s];[mm];[N];"]
        body = [f"{_number(t, ',')};{_number(x, ',')};{_number(f, ',')};" for t, x, f in rows]
        half = len(body) // 2
        lines += body[:half] + ["Prüfzeit;Standardweg;Standardkraft;"] + body[half:]
        lines += ["", "Ende der Prüfung;", f"Fmax;{_number(max(table['load_N']), ',')};N;"]
    p.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return p


def write_reciprocating_export(path: str | Path, run: ReciprocatingRun) -> Path:
    """A TAB-separated export with a header block and units in the header."""
    table = reciprocating_table(run)
    lines = [f"Stroke length\t{run.stroke_mm:g} mm", f"Frequency\t{run.frequency_Hz:g} Hz",
             "", "Time [s]\tPosition [mm]\tFriction Force [N]\tNormal Force [N]"]
    lines += [f"{t:.4f}\t{x:.5f}\t{f:.5f}\t{n:.5f}" for t, x, f, n in zip(
        table["time_s"], table["position_mm"], table["friction_N"], table["normal_N"],
        strict=True)]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
    return Path(path)


def write_rotary_export(path: str | Path, run: RotaryRun) -> Path:
    """A plain CSV: time in ms, revolutions, friction force in gf, normal force in N."""
    table = rotary_table(run)
    lines = ["Time [ms],Revolutions [rev],Friction Force [gf],Normal Force [N]"]
    lines += [f"{t * 1e3:.2f},{r:.6f},{f / G * 1e3:.4f},{n:.5f}" for t, r, f, n in zip(
        table["time_s"], table["revolutions"], table["friction_N"], table["normal_N"],
        strict=True)]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
    return Path(path)


# -------------------------------------------------------------------- the fixed grid


@dataclass(frozen=True)
class ForceGridPoint:
    """One run of the grid: its family, the set it belongs to, its index and the run."""

    family: str
    set: str
    index: int
    run: Any

    def truth(self) -> ForceTruth:
        if self.family == "sled":
            return sled_truth(self.run)
        if self.family == "reciprocating":
            return reciprocating_truth(self.run)
        return rotary_truth(self.run)

    def write(self, path: str | Path) -> Path:
        if self.family == "sled":
            layout = "testxpert" if self.index % 2 else "bluehill"
            return write_sled_export(path, self.run, layout=layout)
        if self.family == "reciprocating":
            return write_reciprocating_export(path, self.run)
        return write_rotary_export(path, self.run)


#: the grid's pairs of (μ_S, μ_K)
MU_PAIRS: tuple[tuple[float, float], ...] = ((0.30, 0.22), (0.45, 0.32), (0.80, 0.60))
#: seeds per grid cell
SEEDS: tuple[int, ...] = (0, 1)


def forcerig_grid() -> list[ForceGridPoint]:
    """The fixed grid of the three families (committed before the first reduction)."""
    points: list[ForceGridPoint] = []

    def add(family: str, group: str, run: Any) -> None:
        points.append(ForceGridPoint(family, group, len(points), run))

    for (mu_s, mu_k), seed in ((p, s) for p in MU_PAIRS for s in SEEDS):
        base = SledRun(mu_s=mu_s, mu_k=mu_k, seed=seed, noise_N=0.002 + 0.004 * seed)
        # steady: a stiff, damped string
        add("sled", "sled steady", replace(base, string_k_N_per_mm=1.0, damping_ratio=0.7,
                                           mu_s=mu_k + 0.6 * (mu_s - mu_k)))
        # stick-slip: a compliant string, fast aging
        add("sled", "sled stick-slip", replace(base, string_k_N_per_mm=0.05,
                                               damping_ratio=0.05, aging_s=0.05,
                                               velocity_strengthening=0.0))
        # a compliant string that damps out (with and without a load-cell offset)
        add("sled", "sled compliant", replace(base, string_k_N_per_mm=0.1, damping_ratio=0.6,
                                              offset_N=0.02 * seed))
        # pre-loaded: the record starts with the string pulled to 50-90 % of breakaway
        add("sled", "sled preloaded", replace(base, string_k_N_per_mm=1.0, damping_ratio=0.7,
                                              preload_fraction=0.5 + 0.4 * seed,
                                              mu_s=mu_k + 0.6 * (mu_s - mu_k)))
    for (_, mu_k), seed in ((p, s) for p in MU_PAIRS for s in SEEDS):
        add("reciprocating", "reciprocating", ReciprocatingRun(
            mu_ss=mu_k, mu_0=mu_k * 1.4, run_in_cycles=5.0 + 5.0 * seed,
            stroke_mm=5.0 + 10.0 * seed, frequency_Hz=1.0 + 2.0 * seed,
            cycles=120, tilt=0.01 + 0.02 * seed, seed=seed))
    for (mu_s, mu_k), seed in ((p, s) for p in MU_PAIRS for s in SEEDS):
        base_r = RotaryRun(mu_s=mu_s, mu_k=mu_k, seed=seed, radius_mm=5.0 + 10.0 * seed,
                           rpm=60.0 + 120.0 * seed)
        add("rotary", "rotary run-out", base_r)
        add("rotary", "rotary run-out + stick-slip",
            replace(base_r, stick_slip_pp=0.06, stick_slip_period_mm=2.3 + 1.1 * seed))
        add("rotary", "rotary flat", replace(base_r, run_out_1=0.0, run_out_2=0.0))
    return points

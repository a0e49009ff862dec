"""A seeded stepped-speed campaign with a known time–temperature shift (Arrhenius).

Each test is what a lab runs on a rheometer tribology cell: a normal-force set-up
interval, then four friction intervals at rising rotational speed, 0.005, 0.015, 0.05 and
0.15 rpm, one after the other without a set-up in between. The grid (:func:`speed_grid`):
4 pairs × 2 forces × 3 temperatures × 2 repeats = 48 tests, 192 friction intervals.

The truth, independent of the reduction code (nothing here imports
``tribopipe.reduction``): a master curve in the reduced speed x = log10(a_T · v / v_ref)
(v the sliding speed at the friction radius [mm/s]) and a power law in pressure::

    μ_K(p, T, v) = k · (p / 10 kPa)^(n − 1) · (1 + A · tanh((x − x₀) / W))
    log10 a_T    = Ea / (R · ln 10) · (1/T − 1/T_ref)          (T in K)

with Ea = :data:`EA_KJ_MOL` kJ/mol and T_ref = :data:`T_REF_C` °C: colder is slower
(a_T > 1 below T_ref), so a colder run sits further up the curve. k, n, A, x₀ are each
pair's own (:data:`PAIRS`). Every test adds its own repeat offset (normal, SD
:data:`REPEAT_SD`) to every step, as a remounted sample would; the per-step truth
(:attr:`StepTruth.mu_k`) includes it, the condition's truth (:func:`mu_k_true`) does not.

Each step is a :class:`generators.synthetic.SyntheticRun` (overshoot to μ_S = 1.25 μ_K
then a plateau) at its speed, written through the project's RheoCompass writer. The grid
and seeds were fixed and committed before the pipeline first reduced this campaign.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from generators.synthetic import (
    SyntheticRun,
    SyntheticTest,
    write_rheocompass_session,
)
from tribopipe.physics import FOUNDING_FRICTION_RADIUS_MM

if TYPE_CHECKING:
    from os import PathLike

#: the rotational-speed steps of every test [rpm]
SPEEDS_RPM: tuple[float, ...] = (0.005, 0.015, 0.05, 0.15)
#: total normal forces [N] (1 N: 11.8 kPa, 9 N: 106 kPa on three 3 mm pins)
FORCES_N: tuple[float, ...] = (1.0, 9.0)
#: chamber temperatures [°C]
TEMPERATURES_C: tuple[float, ...] = (10.0, 25.0, 40.0)
#: a temperature the campaign does not measure, for predictions
UNMEASURED_TEMPERATURE_C = 32.5
REPEATS: tuple[int, ...] = (1, 2)
#: the true activation energy of the shift [kJ/mol]
EA_KJ_MOL = 60.0
#: the reference temperature of the true shift [°C]
T_REF_C = 25.0
#: reference speed of the reduced-speed axis [mm/s]
V_REF_MM_S = 0.01
#: width of the master curve's rise [decades of reduced speed]
W_DECADES = 1.2
#: SD of the per-test repeat offset of μ_K
REPEAT_SD = 0.003
#: torque noise per sample in COF units
NOISE = 0.004
GAS_CONSTANT_J_MOL_K = 8.314462618
#: the campaign's base seed
SEED = 20_2611


@dataclass(frozen=True)
class PairTruth:
    """One pair's master curve: ``k`` (μ_K at 10 kPa on the curve's middle), ``n``
    (pressure exponent of the power law), ``amplitude`` A and ``x0`` (centre of the rise,
    decades of reduced speed)."""

    pin: str
    disc: str
    k: float
    n: float
    amplitude: float
    x0: float


PAIRS: tuple[PairTruth, ...] = (
    PairTruth("Ecoflex 00-30", "steel", 0.95, 0.80, 0.22, 0.3),
    PairTruth("Ecoflex 00-30", "PTFE", 0.55, 0.85, 0.18, 0.0),
    PairTruth("Dragonskin 30", "steel", 0.75, 0.78, 0.25, 0.6),
    PairTruth("Dragonskin 30", "acrylic glass", 0.65, 0.82, 0.20, -0.2),
)


def log10_shift(temperature_C: float, ea_kJ_mol: float = EA_KJ_MOL,
                reference_C: float = T_REF_C) -> float:
    """log10 a_T of the true Arrhenius shift at ``temperature_C`` [°C]."""
    inv = 1.0 / (temperature_C + 273.15) - 1.0 / (reference_C + 273.15)
    return ea_kJ_mol * 1e3 / (GAS_CONSTANT_J_MOL_K * math.log(10)) * inv


def sliding_speed_mm_s(speed_rpm: float) -> float:
    """Sliding speed at the founding friction radius [mm/s] of ``speed_rpm``."""
    return speed_rpm * 2 * math.pi / 60 * FOUNDING_FRICTION_RADIUS_MM


def pressure_kPa(force_N: float) -> float:
    """Nominal pressure per pin [kPa] of a total force on three 3 mm pins."""
    return force_N / 3 / (math.pi * 9.0) * 1e3


def mu_k_true(pair: PairTruth, force_N: float, temperature_C: float, speed_mm_s: float) -> float:
    """The condition's true μ_K (without a test's repeat offset)."""
    x = math.log10(10 ** log10_shift(temperature_C) * speed_mm_s / V_REF_MM_S)
    base = pair.k * (pressure_kPa(force_N) / 10.0) ** (pair.n - 1.0)
    return base * (1.0 + pair.amplitude * math.tanh((x - pair.x0) / W_DECADES))


@dataclass(frozen=True)
class StepTruth:
    """One friction interval (a speed step) and what a correct reduction finds."""

    speed_rpm: float
    speed_mm_s: float
    mu_k: float
    mu_k_condition: float


@dataclass(frozen=True)
class SpeedTest:
    """One test of the grid: labels, seed and its four steps."""

    pair: PairTruth
    force_N: float
    temperature_C: float
    repeat: int
    seed: int
    offset: float
    steps: tuple[StepTruth, ...]

    @property
    def name(self) -> str:
        """The test's name, in the campaign's ``test_pattern`` spelling."""
        return (f"{self.pair.pin} on {self.pair.disc}, {self.force_N:g} N, "
                f"{self.temperature_C:g} °C, #{self.repeat}")

    def runs(self) -> tuple[SyntheticRun, ...]:
        """The steps as synthetic runs: a set-up before the first only."""
        out = []
        for i, step in enumerate(self.steps):
            v = step.speed_mm_s
            # a step lasts long enough for 2 mm of sliding at 0.005 rpm, and at least
            # 40 s at the faster steps (the plateau then spans many mm)
            duration = max(40.0, 2.2 / v) if i else max(300.0, 2.2 / v)
            out.append(SyntheticRun(
                mu_s=1.25 * step.mu_k, mu_k=step.mu_k, shape="overshoot", noise=NOISE,
                setup_interval=i == 0, normal_force_N=self.force_N,
                temperature_C=self.temperature_C, duration_s=duration,
                sample_rate_Hz=10.0 if v < 0.05 else 40.0, speed_rpm=step.speed_rpm,
                seed=self.seed * 10 + i,
            ))
        return tuple(out)


def speed_grid() -> list[SpeedTest]:
    """The fixed campaign: every pair × force × temperature × repeat, seeded."""
    rng = np.random.default_rng(SEED)
    tests = []
    for pi, pair in enumerate(PAIRS):
        for force in FORCES_N:
            for temperature in TEMPERATURES_C:
                for repeat in REPEATS:
                    offset = float(REPEAT_SD * rng.standard_normal())
                    seed = int(rng.integers(1, 2**31 - 1))
                    steps = []
                    for rpm in SPEEDS_RPM:
                        v = sliding_speed_mm_s(rpm)
                        condition = mu_k_true(pair, force, temperature, v)
                        steps.append(StepTruth(rpm, v, condition + offset, condition))
                    tests.append(SpeedTest(pair, force, temperature, repeat, seed + pi,
                                           offset, tuple(steps)))
    return tests


def write_test(path: str | PathLike[str], test: SpeedTest) -> Path:
    """Write one test as a RheoCompass export (UTF-16, TAB) and return its path."""
    synthetic = SyntheticTest(test.name, "pin", test.runs())
    return write_rheocompass_session(path, [synthetic], project="stepped speed")


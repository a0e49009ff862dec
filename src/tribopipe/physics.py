"""The physics of a pin-on-disc cell: the few formulas every step needs, with their units.

T-PID/44 cell: ``n_pins`` pins of radius ``r`` on a disc turning at ω, friction radius
R_eff (the radius at which the friction force acts):

* contact pressure per pin ``p = (F_N / n_pins) / (π r²)``: N/mm² = MPa, ×1000 → kPa
  (1 N on three pins of r = 3 mm → 11.79 kPa);
* friction force ``F_R = M / R_eff`` (M in N·m, R_eff in m), COF ``μ = F_R / F_N``;
* rotational speed ``ω = n · 2π/60`` (rpm → rad/s), sliding speed ``v = ω · R_eff``;
* sliding distance ``s = φ · R_eff`` from the deflection angle (rad × mm → mm); else the
  integral of the rotational speed; else nominal speed × time.

The founding paper sets the disc to 0.005 rpm and reports 0.007 mm/s of sliding; these
two numbers are defined here once (:data:`FOUNDING_SPEED_RPM`,
:data:`FOUNDING_SLIDING_SPEED_MM_S`) and the friction radius follows from them.

All functions are pure: they take scalars or arrays and return new values.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: The founding paper sets the disc to 0.005 rpm and reports 0.007 mm/s of sliding.
#: v = ω·R  ⇒  R = 0.007 mm/s / (0.005 · 2π / 60 s⁻¹) = 13.37 mm.
FOUNDING_SPEED_RPM = 0.005
FOUNDING_SLIDING_SPEED_MM_S = 0.007
FOUNDING_FRICTION_RADIUS_MM = round(
    FOUNDING_SLIDING_SPEED_MM_S / (FOUNDING_SPEED_RPM * 2 * math.pi / 60), 2
)


def contact_pressure_kPa(normal_force_N: ArrayLike, n_pins: int, pin_radius_mm: float) -> Any:
    """Contact pressure per pin [kPa] of a total normal force [N] shared by ``n_pins`` pins
    of radius ``pin_radius_mm`` [mm]: ``(F/n) / (π r²)`` N/mm² × 1000. Scalar or array."""
    return np.asarray(normal_force_N, dtype=float) / n_pins / (math.pi * pin_radius_mm**2) * 1e3


def friction_force_N(torque_Nm: ArrayLike, friction_radius_mm: float) -> Any:
    """Friction force [N] from a torque [N·m] at the friction radius [mm]: ``M / R``."""
    return np.asarray(torque_Nm, dtype=float) / (friction_radius_mm * 1e-3)


def coefficient_of_friction(friction_force_N: ArrayLike, normal_force_N: ArrayLike) -> Any:
    """COF μ = F_R / F_N (both in N; arrays of the same shape). NaN where F_N is 0."""
    f_r = np.asarray(friction_force_N, dtype=float)
    f_n = np.asarray(normal_force_N, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        mu = f_r / f_n
    return np.where(f_n != 0, mu, np.nan)


def rpm_to_rad_s(speed_rpm: ArrayLike) -> Any:
    """Rotational speed: revolutions per minute → rad/s (× 2π/60)."""
    return np.asarray(speed_rpm, dtype=float) * (2 * math.pi / 60)


def sliding_speed_mm_s(speed_rpm: float, friction_radius_mm: float) -> float:
    """Sliding speed [mm/s] at the friction radius [mm] of a disc turning at ``speed_rpm``
    (0.005 rpm at 13.37 mm → 0.0070 mm/s)."""
    return float(rpm_to_rad_s(speed_rpm)) * friction_radius_mm


def distance_from_angle_mm(angle_rad: ArrayLike, friction_radius_mm: float) -> NDArray[np.float64]:
    """Sliding distance [mm] from a deflection angle [rad] (shape (n,)): ``(φ − φ₀)·R``,
    counted along the direction of travel (so it grows whichever way the disc turns)."""
    phi = np.asarray(angle_rad, dtype=float)
    travel = phi - phi[0]
    direction = 1.0 if travel[-1] >= 0 else -1.0
    return direction * travel * friction_radius_mm


def distance_from_speed_mm(
    time_s: ArrayLike, speed_rad_s: ArrayLike, friction_radius_mm: float
) -> NDArray[np.float64]:
    """Sliding distance [mm] by integrating the rotational speed [rad/s] over time [s]
    (trapezoids, shape (n,), 0 at the first sample) times the friction radius [mm]."""
    t = np.asarray(time_s, dtype=float)
    w = np.asarray(speed_rad_s, dtype=float)
    if np.nanmedian(w) < 0:
        w = -w
    steps = 0.5 * (w[1:] + w[:-1]) * np.diff(t)
    return np.concatenate([[0.0], np.cumsum(steps)]) * friction_radius_mm


def distance_from_nominal_mm(
    time_s: ArrayLike, speed_rpm: float, friction_radius_mm: float
) -> NDArray[np.float64]:
    """Sliding distance [mm] assuming the nominal speed [rpm] from the first sample on."""
    t = np.asarray(time_s, dtype=float)
    return (t - t[0]) * sliding_speed_mm_s(speed_rpm, friction_radius_mm)


def sliding_distance_mm(
    time_s: ArrayLike,
    friction_radius_mm: float,
    *,
    angle_rad: ArrayLike | None = None,
    speed_rad_s: ArrayLike | None = None,
    nominal_speed_rpm: float | None = None,
) -> tuple[NDArray[np.float64], str]:
    """Sliding distance [mm] (shape (n,)) and its source: ``"angle"`` when a finite angle
    [rad] is given, else ``"speed"`` (integrated rad/s), else ``"nominal"`` (rpm × time).
    Missing angle/speed values are interpolated over time."""
    t = np.asarray(time_s, dtype=float)
    for values, source in ((angle_rad, "angle"), (speed_rad_s, "speed")):
        if values is None:
            continue
        v = np.asarray(values, dtype=float)
        ok = np.isfinite(v)
        if ok.sum() < 2:
            continue
        v = np.interp(t, t[ok], v[ok]) if not ok.all() else v
        if source == "angle":
            return distance_from_angle_mm(v, friction_radius_mm), source
        return distance_from_speed_mm(t, v, friction_radius_mm), source
    if nominal_speed_rpm is None:
        raise ValueError("no angle, no speed and no nominal speed: sliding distance unknown")
    return distance_from_nominal_mm(t, nominal_speed_rpm, friction_radius_mm), "nominal"

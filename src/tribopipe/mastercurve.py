"""A master curve of one pair over sliding speed and temperature (time–temperature
superposition of elastomer friction, Grosch 1963).

Rubber friction is a viscoelastic loss: what a run at temperature T and sliding speed v
measures depends on v·a_T, the speed on the material's own clock. Shifting each
temperature's μ_K(log v) horizontally by log a_T lays them onto one curve μ_K(log a_T·v),
which then predicts any temperature and speed inside the reduced-speed range it covers.

The shift (one per temperature, shared by every pressure of the pair: it is the
material's clock, not the contact's):

* ``arrhenius`` (default): log10 a_T = Ea / (R·ln 10) · (1/T − 1/T_ref), T in K. Silicone
  elastomers are measured 150 K and more above their glass transition (T_g ≈ −120 °C),
  where WLF's free-volume term has flattened and the shift over a few tens of kelvin is
  an activation law; one parameter, Ea [kJ/mol];
* ``wlf``: log10 a_T = −C1·(T − T_ref) / (C2 + T − T_ref), for materials measured
  nearer their glass transition; C1 and C2 [K].

The curve: one smooth curve per nominal pressure, a polynomial in
x = log10(a_T·v / 1 mm/s) (quadratic where the pressure has at least 5 points at 3 or
more speeds, else linear). Pressure is *not* folded in as a vertical factor: that would
assume μ(p, x) = b(p)·g(x), a separability the map cannot check with two or three
pressures, while a curve per pressure assumes nothing across pressures; only the shift
is shared. Shift and curves are fitted jointly by least squares on the group means
(:func:`scipy.optimize.least_squares`); u(Ea) (or u(C1), u(C2)) from the fit's
covariance, scaled by the residual variance.

:func:`master_curve` refuses (:class:`~tribopipe.errors.ExportError`, one line) with
fewer than 2 temperatures or 2 speeds at a pressure, or where the shifted speed ranges
do not overlap (then no shift is measured). :func:`predict` reads the curve at any
temperature and speed whose reduced speed lies inside the range the shifted data cover,
and refuses outside it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from .errors import ExportError
from .frictionmap.snapshot import MapSource
from .query import load_groups, pair_speeds, select_pair
from .stats import NOMINAL_SPEED

if TYPE_CHECKING:
    import numpy as np
    import pandas as pd

SHIFTS: tuple[str, ...] = ("arrhenius", "wlf")
GAS_CONSTANT_J_MOL_K = 8.314462618
#: the WLF "universal" constants, the fit's starting point [-, K]
WLF_START: tuple[float, float] = (8.86, 101.6)
#: points per pressure from which the curve is quadratic in x (else linear)
QUADRATIC_FROM = 5
#: a pressure within this fraction of a curve's is that curve's
PRESSURE_MATCH_REL = 0.01


@dataclass(frozen=True)
class PressureCurve:
    """The master curve at one nominal pressure [kPa]: μ_K = Σ cᵢ·xⁱ (``coefficients``
    ascending) for x = log10(a_T·v / 1 mm/s) in ``x_range`` (the shifted data's span)."""

    pressure_kPa: float
    coefficients: tuple[float, ...]
    x_range: tuple[float, float]
    n_points: int

    def value(self, x: float) -> float:
        """μ_K on the curve at reduced speed ``x``."""
        return sum(c * x**i for i, c in enumerate(self.coefficients))


@dataclass(frozen=True)
class ShiftedPoint:
    """One group mean with its place on the master curve."""

    pressure_kPa: float
    temperature_C: float
    speed_mm_s: float
    mu_k: float
    n: int
    x: float


@dataclass(frozen=True)
class MasterCurve:
    """A pair's master curve (module docstring). ``log10_aT`` maps each measured
    temperature [°C] to its shift; ``residual_sd`` is the SD of the group means about
    the curves (dof = points − parameters)."""

    pin: str
    disc: str
    shift: str
    reference_temperature_C: float
    parameters: dict[str, float]
    uncertainties: dict[str, float]
    log10_aT: dict[float, float]
    curves: tuple[PressureCurve, ...]
    residual_sd: float
    points: tuple[ShiftedPoint, ...] = field(repr=False)

    def log10_shift(self, temperature_C: float) -> float:
        """log10 a_T at any temperature [°C] by the fitted law."""
        return shift_law(self.shift, self.parameters, self.reference_temperature_C,
                         temperature_C)

    def to_dict(self, samples: int = 25) -> dict[str, Any]:
        """A JSON-ready dict: ``shift``, ``Ea_kJ_mol`` and ``u_Ea_kJ_mol`` (Arrhenius) or
        ``C1, u_C1, C2_K, u_C2_K`` (WLF), ``reference_temperature_C``, ``log10_aT`` (per
        temperature), ``curve`` (per pressure: coefficients, the x range and ``samples``
        points ``[x, mu_k]``), ``residual_sd`` and the shifted ``points``."""
        import numpy as np

        out: dict[str, Any] = {"pin": self.pin, "disc": self.disc, "shift": self.shift}
        if self.shift == "arrhenius":
            out["Ea_kJ_mol"] = self.parameters["Ea_kJ_mol"]
            out["u_Ea_kJ_mol"] = self.uncertainties.get("Ea_kJ_mol")
        else:
            out["C1"] = self.parameters["C1"]
            out["u_C1"] = self.uncertainties.get("C1")
            out["C2"] = self.parameters["C2_K"]
            out["u_C2"] = self.uncertainties.get("C2_K")
        out["reference_temperature_C"] = self.reference_temperature_C
        out["log10_aT"] = [{"temperature_C": t, "log10_aT": v}
                           for t, v in sorted(self.log10_aT.items())]
        out["x_axis"] = "log10(a_T * v / (1 mm/s))"
        out["curve"] = []
        for c in self.curves:
            xs = np.linspace(c.x_range[0], c.x_range[1], samples)
            out["curve"].append({
                "pressure_kPa": c.pressure_kPa,
                "coefficients": list(c.coefficients),
                "x_range": list(c.x_range),
                "n_points": c.n_points,
                "samples": [[float(x), float(c.value(float(x)))] for x in xs],
            })
        out["residual_sd"] = self.residual_sd
        out["points"] = [{"pressure_kPa": p.pressure_kPa, "temperature_C": p.temperature_C,
                          "speed_mm_s": p.speed_mm_s, "mu_k": p.mu_k, "n": p.n, "x": p.x}
                         for p in self.points]
        return out


def shift_law(shift: str, parameters: dict[str, float], reference_C: float,
              temperature_C: float) -> float:
    """log10 a_T at ``temperature_C`` [°C] of the law ``shift`` with ``parameters``
    (``Ea_kJ_mol``; or ``C1``, ``C2_K``) about ``reference_C`` [°C]."""
    if shift == "arrhenius":
        inv = 1.0 / (temperature_C + 273.15) - 1.0 / (reference_C + 273.15)
        return parameters["Ea_kJ_mol"] * 1e3 / (GAS_CONSTANT_J_MOL_K * math.log(10)) * inv
    dt = temperature_C - reference_C
    return -parameters["C1"] * dt / (parameters["C2_K"] + dt)


def _pair_points(pair: pd.DataFrame) -> list[ShiftedPoint]:
    """The pair's group means (finite μ_K, known temperature) as unshifted points."""
    import pandas as pd

    def col(name: str) -> Any:
        return pd.to_numeric(pair[name], errors="coerce").to_numpy(dtype=float)

    speeds = col(NOMINAL_SPEED) if NOMINAL_SPEED in pair.columns else \
        [pair_speeds(pair)[0]] * len(pair)
    out = []
    for p, t, v, mu, n in zip(col("pressure_kPa"), col("temperature_C"), speeds,
                              col("mu_k_mean"), col("mu_k_n"), strict=True):
        if all(math.isfinite(float(a)) for a in (p, t, v, mu)) and v > 0:
            out.append(ShiftedPoint(float(p), float(t), float(v), float(mu),
                                    int(n) if math.isfinite(n) else 1, math.log10(v)))
    return out


def _pressure_levels(points: Sequence[ShiftedPoint]) -> list[float]:
    """The distinct nominal pressures [kPa] (within :data:`PRESSURE_MATCH_REL`), sorted."""
    levels: list[float] = []
    for p in sorted(q.pressure_kPa for q in points):
        if not levels or p > levels[-1] * (1 + PRESSURE_MATCH_REL):
            levels.append(p)
    return levels


def _level_of(levels: Sequence[float], pressure_kPa: float) -> int | None:
    for i, p in enumerate(levels):
        if abs(pressure_kPa - p) <= PRESSURE_MATCH_REL * p:
            return i
    return None


def master_curve(
    groups: pd.DataFrame,
    pin: str,
    disc: str,
    *,
    shift: str = "arrhenius",
    reference_temperature_C: float | None = None,
) -> MasterCurve:
    """Fit the master curve of ``pin`` on ``disc`` from a group table with the nominal
    speed shown (:func:`tribopipe.query.groups_of`). ``reference_temperature_C``
    defaults to the measured temperature in the middle (the lower of two middles).
    Raises :class:`ExportError` in one line for an unknown pair or shift, fewer than 2
    temperatures, fewer than 2 speeds at a pressure, or non-overlapping shifted ranges.
    """
    import numpy as np
    from scipy.optimize import least_squares

    if shift not in SHIFTS:
        raise ExportError(f"unknown shift {shift!r}; expected one of {', '.join(SHIFTS)}")
    pair = select_pair(groups, pin, disc)
    name = f"{pair['pin'].iloc[0]} on {pair['disc'].iloc[0]}"
    points = _pair_points(pair)
    temps = sorted({q.temperature_C for q in points})
    if len(temps) < 2:
        raise ExportError(f"{name}: a master curve needs at least 2 temperatures, the map "
                          f"holds {len(temps)}", hint="measure at 3 or more temperatures")
    levels = _pressure_levels(points)
    by_level: list[list[ShiftedPoint]] = [[] for _ in levels]
    for q in points:
        level = _level_of(levels, q.pressure_kPa)
        assert level is not None
        by_level[level].append(q)
    for p, members in zip(levels, by_level, strict=True):
        speeds = {round(q.speed_mm_s, 12) for q in members}
        if len(speeds) < 2:
            raise ExportError(f"{name}: a master curve needs at least 2 sliding speeds, "
                              f"{p:.4g} kPa holds {len(speeds)}",
                              hint="measure 2-4 speeds per pressure")
    t_ref = (temps[(len(temps) - 1) // 2] if reference_temperature_C is None
             else float(reference_temperature_C))
    degrees = [2 if len(m) >= QUADRATIC_FROM and len({q.speed_mm_s for q in m}) >= 3 else 1
               for m in by_level]
    n_shift = 1 if shift == "arrhenius" else 2
    start = [50.0] if shift == "arrhenius" else list(WLF_START)
    if shift == "wlf":
        # C2 + (T − T_ref) > 0 at every temperature measured
        low = [-1e3, max(1e-3, -(min(temps) - t_ref) + 1.0)]
        start[1] = max(start[1], low[1] + 1.0)
        bounds = (low + [-np.inf] * sum(d + 1 for d in degrees),
                  [1e3, 1e5] + [np.inf] * sum(d + 1 for d in degrees))
    else:
        bounds = ([-1e4] + [-np.inf] * sum(d + 1 for d in degrees),
                  [1e4] + [np.inf] * sum(d + 1 for d in degrees))

    def params_of(theta: np.ndarray) -> dict[str, float]:
        if shift == "arrhenius":
            return {"Ea_kJ_mol": float(theta[0])}
        return {"C1": float(theta[0]), "C2_K": float(theta[1])}

    def residuals(theta: np.ndarray) -> np.ndarray:
        law = params_of(theta)
        out = []
        at = n_shift
        for members, d in zip(by_level, degrees, strict=True):
            coef = theta[at:at + d + 1]
            at += d + 1
            for q in members:
                x = q.x + shift_law(shift, law, t_ref, q.temperature_C)
                out.append(sum(c * x**i for i, c in enumerate(coef)) - q.mu_k)
        return np.asarray(out)

    theta0 = list(start)
    for members, d in zip(by_level, degrees, strict=True):
        # the unshifted points start the curve: a line (two speeds fix no more)
        fit = np.polyfit([q.x for q in members], [q.mu_k for q in members], 1)[::-1]
        theta0 += [float(c) for c in fit] + [0.0] * (d - 1)
    solution = least_squares(residuals, np.asarray(theta0, dtype=float), bounds=bounds,
                             x_scale="jac")
    theta = solution.x
    res = solution.fun
    dof = max(1, len(res) - len(theta))
    s2 = float(np.sum(res**2)) / dof
    law = params_of(theta)
    uncertainties: dict[str, float] = {}
    try:
        cov = np.linalg.inv(solution.jac.T @ solution.jac) * s2
        names = list(law)
        uncertainties = {names[i]: float(math.sqrt(max(cov[i, i], 0.0)))
                         for i in range(n_shift)}
    except np.linalg.LinAlgError:
        uncertainties = {}
    log10_aT = {t: shift_law(shift, law, t_ref, t) for t in temps}
    shifted = tuple(ShiftedPoint(q.pressure_kPa, q.temperature_C, q.speed_mm_s, q.mu_k, q.n,
                                 q.x + log10_aT[q.temperature_C]) for q in points)
    curves = []
    at = n_shift
    for p, members, d in zip(levels, by_level, degrees, strict=True):
        xs_by_t: dict[float, list[float]] = {}
        for q in members:
            xs_by_t.setdefault(q.temperature_C, []).append(q.x + log10_aT[q.temperature_C])
        _check_overlap(name, p, xs_by_t)
        all_x = [x for xs in xs_by_t.values() for x in xs]
        curves.append(PressureCurve(p, tuple(float(c) for c in theta[at:at + d + 1]),
                                    (min(all_x), max(all_x)), len(members)))
        at += d + 1
    return MasterCurve(
        pin=str(pair["pin"].iloc[0]), disc=str(pair["disc"].iloc[0]), shift=shift,
        reference_temperature_C=t_ref, parameters=law, uncertainties=uncertainties,
        log10_aT=log10_aT, curves=tuple(curves), residual_sd=math.sqrt(s2),
        points=shifted,
    )


def _check_overlap(name: str, pressure_kPa: float, xs_by_t: dict[float, list[float]]) -> None:
    """Refuse where a temperature's shifted speed range meets no other's at a pressure
    (its shift is then not measured, only extrapolated)."""
    spans = {t: (min(xs), max(xs)) for t, xs in xs_by_t.items()}
    for t, (lo, hi) in spans.items():
        others = [(a, b) for u, (a, b) in spans.items() if u != t]
        if others and not any(lo <= b and a <= hi for a, b in others):
            raise ExportError(
                f"{name}: at {pressure_kPa:.4g} kPa the shifted speed range of {t:g} °C "
                "overlaps no other temperature's: the shift is not measured",
                hint="measure more speeds, or temperatures closer together")


@dataclass(frozen=True)
class ModelPrediction:
    """μ_K read from a master curve: ``model_based`` always; ``x`` the reduced speed,
    ``x_range`` the range covered at the pressure(s) used; ``u`` the curve's residual
    SD (k = 1) and ``expanded`` 2u."""

    pin: str
    disc: str
    pressure_kPa: float
    temperature_C: float
    speed_mm_s: float
    mu_k: float
    x: float
    x_range: tuple[float, float]
    u: float
    shift: str
    log10_aT: float
    model_based: bool = True

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict; ``mu_k`` as ``{"value", "u", "expanded"}``."""
        return {
            "pin": self.pin, "disc": self.disc, "pressure_kPa": self.pressure_kPa,
            "temperature_C": self.temperature_C, "speed_mm_s": self.speed_mm_s,
            "mu_k": {"value": self.mu_k, "u": self.u, "expanded": 2.0 * self.u},
            "model_based": True, "shift": self.shift, "log10_aT": self.log10_aT,
            "x": self.x, "x_range": list(self.x_range),
            "notes": ["model-based: read from the master curve (time-temperature "
                      "superposition), not interpolated between measured groups"],
        }


def predict(mc: MasterCurve, pressure_kPa: float, temperature_C: float,
            speed_mm_s: float) -> ModelPrediction:
    """μ_K at (pressure [kPa], temperature [°C], speed [mm/s]) from ``mc``.

    The pressure must be a measured one or lie between two (then ln μ is linear in ln p
    between the two curves, the map's pressure rule); the reduced speed must lie inside
    the range the shifted data cover at each curve used. Raises :class:`ExportError`
    otherwise."""
    for value, what in ((pressure_kPa, "pressure"), (temperature_C, "temperature"),
                        (speed_mm_s, "speed")):
        if not math.isfinite(value):
            raise ExportError(f"{what} must be a finite number, got {value}")
    if speed_mm_s <= 0 or pressure_kPa <= 0:
        raise ExportError("speed and pressure must be > 0 for a master-curve prediction")
    a = mc.log10_shift(temperature_C)
    x = math.log10(speed_mm_s) + a
    levels = [c.pressure_kPa for c in mc.curves]
    at = _level_of(levels, pressure_kPa)
    if at is not None:
        used = [(mc.curves[at], 1.0)]
    else:
        hi = next((i for i, p in enumerate(levels) if p > pressure_kPa), None)
        if hi is None or hi == 0:
            raise ExportError(
                f"{pressure_kPa:.4g} kPa is outside the pressures of the master curve "
                f"({levels[0]:.4g}-{levels[-1]:.4g} kPa): refused")
        lo_c, hi_c = mc.curves[hi - 1], mc.curves[hi]
        w = math.log(pressure_kPa / lo_c.pressure_kPa) / math.log(
            hi_c.pressure_kPa / lo_c.pressure_kPa)
        used = [(lo_c, 1.0 - w), (hi_c, w)]
    lo = max(c.x_range[0] for c, _ in used)
    hi_x = min(c.x_range[1] for c, _ in used)
    if not lo <= x <= hi_x:
        raise ExportError(
            f"reduced speed log10(a_T·v) = {x:.3g} at {temperature_C:g} °C, "
            f"{speed_mm_s:g} mm/s is outside the range the master curve covers "
            f"({lo:.3g} to {hi_x:.3g}): refused")
    values = [c.value(x) for c, _ in used]
    if len(used) == 1:
        mu = values[0]
    elif min(values) > 0:
        mu = math.exp(sum(w * math.log(v) for (_, w), v in zip(used, values, strict=True)))
    else:
        mu = sum(w * v for (_, w), v in zip(used, values, strict=True))
    return ModelPrediction(mc.pin, mc.disc, float(pressure_kPa), float(temperature_C),
                           float(speed_mm_s), float(mu), x, (lo, hi_x), mc.residual_sd,
                           mc.shift, a)


def map_master_curve(map_path: MapSource, pin: str, disc: str, *,
                     shift: str = "arrhenius") -> MasterCurve:
    """:func:`master_curve` of the friction map (Parquet) at ``map_path``."""
    return master_curve(load_groups(map_path), pin, disc, shift=shift)

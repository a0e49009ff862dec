"""A pair's μ_K over sliding speed as the engines take it: the curve at its measured
speeds (LS-DYNA's decay fit) and the table over pressure, temperature and slip rate with
rows added between measured speeds (ABAQUS, Ansys), so that an engine's linear reading
stays within the tolerance of :func:`tribopipe.query.query`, which reads μ linearly in
ln v."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from ..interpolation import densify
from ..query import groups_at_speed, pair_speeds, query, select_pair, speed_weights
from .engine_tables import PairGroups, table_at

if TYPE_CHECKING:
    import pandas as pd


def speed_curve(groups: pd.DataFrame, pin: str, disc: str, pressure_kPa: float,
                temperature_C: float | None) -> list[tuple[float, float]]:
    """``[(v [mm/s], μ_K)]`` of a pair at one pressure [kPa] and temperature [°C], one per
    measured nominal speed (ascending; :func:`tribopipe.query.query` at each)."""
    pair = select_pair(groups, pin, disc)
    speeds = pair_speeds(pair)
    if len(speeds) < 2:
        return []
    return [(v, query(groups, pin, disc, pressure_kPa, temperature_C, v).mu_k.value)
            for v in speeds]


def _steepest(speeds: list[float], rows: list[list[float]]) -> Callable[[float], float]:
    """μ [-] over speed [mm/s] that is, between each two measured ``speeds``, linear in
    ln v with the steepest slope of any of ``rows`` (μ at the measured speeds) there: the
    error of reading a function linear in ln v linearly in v scales with its slope, so
    speed rows that keep this one within a target keep every row within it."""
    logs = [math.log(v) for v in speeds]
    slopes = [max(abs(r[i + 1] - r[i]) for r in rows) / (logs[i + 1] - logs[i])
              for i in range(len(speeds) - 1)]

    def value_at(v: float) -> float:
        x = math.log(v)
        total = 0.0
        for i, slope in enumerate(slopes):
            total += slope * (min(max(x, logs[i]), logs[i + 1]) - logs[i])
        return total

    return value_at


def speed_rows(groups: pd.DataFrame | PairGroups, pin: str, disc: str,
               temperature_C: float | None) -> pd.DataFrame | None:
    """A pair's μ_K table over pressure, temperature and sliding speed where it is
    measured at several nominal speeds (else ``None``): ``pressure_kPa, temperature_C,
    speed_mm_s, mu_k, measured, added, speed_added``, temperature outer, pressure, then
    speed inner (ABAQUS wants the first variable, the slip rate, to vary fastest).
    Pressures are every speed's rows of :func:`table_at` (measured and densified), so the
    grid is rectangular; each cell is :func:`tribopipe.query.query` at its speed (between
    measured speeds by query's own weights, :func:`tribopipe.query.speed_weights`).

    Speeds: the measured ones, and between them the rows of
    :func:`tribopipe.interpolation.densify` (``speed_added``): :func:`~tribopipe.query.query`
    reads μ linearly in ln v between measured speeds, an engine reads the table linearly
    in v, so rows are added until the engine's reading of every pressure and temperature
    row stays within :data:`~tribopipe.interpolation.DENSIFY_TARGET` of it; with the
    pressure rows' own margin the engine stays within
    :data:`~tribopipe.interpolation.ENGINE_TOLERANCE` of ``query`` over the table.
    ``groups`` may be a :class:`~tribopipe.export.engine_tables.PairGroups` (a writer over
    every pair): then only the pair's groups are read, with the map's κ."""
    import pandas as pd

    split = groups if isinstance(groups, PairGroups) else PairGroups(groups)
    pair = split.pair(pin, disc)
    measured_speeds = pair_speeds(pair)
    if len(measured_speeds) < 2:
        return None
    pressures: set[float] = set()
    temps: set[float] = set()
    measured: set[tuple[float, float, float]] = set()
    measured_p: set[float] = set()
    for v in measured_speeds:
        part = table_at(groups_at_speed(pair, v), pin, disc, temperature_C, dense=True,
                        curvature=split.curvature(v))
        pressures |= {float(p) for p in part["pressure_kPa"]}
        temps |= {float(t) for t in part["temperature_C"]}
        for p_row, t_row, was_measured, added in zip(
                part["pressure_kPa"].to_numpy(dtype=float),
                part["temperature_C"].to_numpy(dtype=float),
                part["measured"].to_numpy(dtype=bool), part["added"].to_numpy(dtype=bool),
                strict=True):
            if was_measured:
                measured.add((float(p_row), float(t_row), v))
            if not added:
                measured_p.add(float(p_row))
    ordered_t = sorted(temps, key=lambda x: (math.isnan(x), x))
    cells = [(t, p) for t in ordered_t for p in sorted(pressures)]
    # μ_K of every pressure and temperature row at the measured speeds (query)
    whole = split.curvature()
    at_measured = [[query(pair, pin, disc, p, None if math.isnan(t) else t, v,
                          curvature=whole).mu_k.value
                    for v in measured_speeds] for t, p in cells]
    grid = densify(measured_speeds, _steepest(measured_speeds, at_measured))
    rows = []
    for (t, p), mus in zip(cells, at_measured, strict=True):
        for v in grid:
            # query's rule between measured speeds (its weights, linear in ln v)
            weights, _ = speed_weights(measured_speeds, v)
            rows.append({"pressure_kPa": p, "temperature_C": t, "speed_mm_s": v,
                         "mu_k": sum(w * mus[i] for i, w in weights),
                         "measured": (p, t, v) in measured, "added": p not in measured_p,
                         "speed_added": v not in measured_speeds})
    return pd.DataFrame(rows)

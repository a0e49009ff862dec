"""The μ_K tables an engine reads: the pairs a selection names, a pair's table over
pressure and temperature (or its slice at one temperature, with rows added between
measured pressures for engines that read it linearly), and the comment lines that say
which cells were filled and which rows added.

A writer over every pair reads the group table through :class:`PairGroups`: each pair's
groups selected once and the map's curvature computed once, so that a pair costs its own
groups, not the map's."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING

from ..errors import ExportError
from ..interpolation import ENGINE_TOLERANCE
from ..query import (
    friction_table,
    groups_at_speed,
    map_curvature,
    name_key,
    pairs,
    query,
    select_pair,
)
from .unit_systems import UnitSystem, num

if TYPE_CHECKING:
    import pandas as pd


def selected_pairs(
    groups: pd.DataFrame, pin: str | None, disc: str | None
) -> list[tuple[str, str]]:
    """The pairs matching ``pin`` / ``disc`` (either may be ``None`` = all)."""
    held = pairs(groups)
    if pin is not None and disc is not None:
        first = select_pair(groups, pin, disc).iloc[0]
        return [(str(first["pin"]), str(first["disc"]))]
    chosen = [
        (p, d)
        for p, d in held
        if (pin is None or p.casefold() == pin.strip().casefold())
        and (disc is None or d.casefold() == disc.strip().casefold())
    ]
    if not chosen:
        wanted = f"pin {pin!r}" if pin is not None else f"disc {disc!r}"
        listing = "; ".join(f"{p} on {d}" for p, d in held) or "nothing"
        raise ExportError(f"no pair with {wanted}; the map holds: {listing}")
    return chosen


class PairGroups:
    """A group table as a writer over every pair reads it: each pair's groups (names
    matched as :func:`tribopipe.query.select_pair` matches them) selected in one pass, and
    the map's curvature κ (:func:`tribopipe.query.map_curvature`, of the whole table or of
    its groups at one nominal speed [mm/s]) computed once and kept."""

    def __init__(self, groups: pd.DataFrame) -> None:
        self.groups = groups
        self._pairs: dict[tuple[str, str], pd.DataFrame] | None = None
        self._curvature: dict[float | None, dict[str, float]] = {}

    def pair(self, pin: str, disc: str) -> pd.DataFrame:
        """The groups of one pair (in the table's order); :func:`~tribopipe.query.select_pair`
        on the whole table (its message) for a pair it does not hold."""
        if self._pairs is None:
            keys = list(zip(self.groups["pin"].map(name_key),
                            self.groups["disc"].map(name_key), strict=True))
            rows: dict[tuple[str, str], list[int]] = {}
            for i, key in enumerate(keys):
                rows.setdefault(key, []).append(i)
            self._pairs = {key: self.groups.iloc[at] for key, at in rows.items()}
        found = self._pairs.get((name_key(pin), name_key(disc)))
        return select_pair(self.groups, pin, disc) if found is None else found.copy()

    def curvature(self, speed_mm_s: float | None = None) -> dict[str, float]:
        """κ of ``mu_k`` and ``mu_s`` over the whole table, or over its groups at one
        nominal speed [mm/s] (:func:`~tribopipe.query.groups_at_speed`)."""
        if speed_mm_s not in self._curvature:
            frame = (self.groups if speed_mm_s is None
                     else groups_at_speed(self.groups, speed_mm_s))
            self._curvature[speed_mm_s] = {q: map_curvature(frame, q)
                                           for q in ("mu_k", "mu_s")}
        return self._curvature[speed_mm_s]


def table_at(
    groups: pd.DataFrame, pin: str, disc: str, temperature_C: float | None,
    *, dense: bool = False, curvature: Mapping[str, float] | None = None,
) -> pd.DataFrame:
    """The pair's μ_K table (``pressure_kPa, temperature_C, mu_k, uncertainty, u_combined,
    expanded, measured, added``), or its single-temperature slice interpolated at
    ``temperature_C`` [°C]; ``dense`` adds the pressure rows of
    :func:`tribopipe.interpolation.densify` (for engines that read a table linearly).
    ``curvature``: the map's κ (:meth:`PairGroups.curvature`) where ``groups`` are the
    pair's own groups (:meth:`PairGroups.pair`)."""
    import pandas as pd

    table = friction_table(groups, pin, disc, "mu_k", dense=dense,
                           curvature=None if curvature is None else curvature["mu_k"])
    if temperature_C is None:
        return table
    rows = []
    for p in sorted(set(table["pressure_kPa"])):
        res = query(groups, pin, disc, p, temperature_C, curvature=curvature)
        measured = any(
            u.weight == 1.0 and u.temperature_C == temperature_C for u in res.mu_k.used
        )
        rows.append(
            {
                "pressure_kPa": p,
                "temperature_C": temperature_C,
                "mu_k": res.mu_k.value,
                "uncertainty": math.nan if res.mu_k.uncertainty is None else res.mu_k.uncertainty,
                "u_combined": math.nan if res.mu_k.u_combined is None else res.mu_k.u_combined,
                "expanded": math.nan if res.mu_k.expanded is None else res.mu_k.expanded,
                "measured": measured,
                "added": bool(table.loc[table["pressure_kPa"] == p, "added"].iloc[0]),
            }
        )
    return pd.DataFrame(rows)


def filled_lines(table: pd.DataFrame, units: UnitSystem) -> list[str]:
    """Comment bodies listing the table cells filled by interpolation (the rows added by
    :func:`densify_lines` aside, and in a table over sliding speed the speed rows added
    between measured speeds: each cell then names its speed)."""
    over_speed = "speed_mm_s" in table.columns
    keep = ~table["measured"] & ~table["added"]
    if over_speed:
        keep &= ~table["speed_added"]
    filled = table[keep]
    if filled.empty:
        return ["every cell of this table was measured"]
    lines = [
        f"{len(filled)} cell(s) not measured, filled by tribopipe's interpolation (linear in "
        "temperature, log p - log mu in pressure; held constant outside the measured range):"
    ]
    for _, row in filled.iterrows():
        t = row["temperature_C"]
        t_text = "" if math.isnan(t) else f", T = {t:g} C"
        v_text = ""
        if over_speed:
            v = float(row["speed_mm_s"])
            v_text = f", v = {v:g} mm/s ({num(v * units.speed_per_mm_s)} {units.speed_unit})"
        lines.append(
            f"  p = {row['pressure_kPa']:g} kPa "
            f"({num(row['pressure_kPa'] * units.pressure_per_kPa)} {units.pressure_unit})"
            f"{t_text}{v_text}: mu = {num(row['mu_k'])}"
        )
    return lines


def densify_lines(table: pd.DataFrame, engine: str) -> list[str]:
    """Comment bodies saying which pressure rows were added to ``table`` and why."""
    added = sorted(set(table.loc[table["added"], "pressure_kPa"]))
    if not added:
        return []
    return [
        f"{len(added)} pressure row(s) added between the measured pressures: {engine} reads "
        "the table linearly in pressure, tribopipe interpolates in log p - log mu (friction "
        "falls as a power of pressure); with the added rows the two differ by at most "
        f"{ENGINE_TOLERANCE:g} in mu over the measured range. Added at (kPa): "
        + ", ".join(f"{p:g}" for p in added),
    ]

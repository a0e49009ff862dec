"""The μ_K tables an engine reads: the pairs a selection names, a pair's table over
pressure and temperature (or its slice at one temperature, with rows added between
measured pressures for engines that read it linearly), and the comment lines that say
which cells were filled and which rows added."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ..errors import ExportError
from ..interpolation import ENGINE_TOLERANCE
from ..query import friction_table, pairs, query, select_pair
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


def table_at(
    groups: pd.DataFrame, pin: str, disc: str, temperature_C: float | None,
    *, dense: bool = False,
) -> pd.DataFrame:
    """The pair's μ_K table (``pressure_kPa, temperature_C, mu_k, uncertainty, u_combined,
    expanded, measured, added``), or its single-temperature slice interpolated at
    ``temperature_C`` [°C]; ``dense`` adds the pressure rows of
    :func:`tribopipe.interpolation.densify` (for engines that read a table linearly)."""
    import pandas as pd

    table = friction_table(groups, pin, disc, "mu_k", dense=dense)
    if temperature_C is None:
        return table
    rows = []
    for p in sorted(set(table["pressure_kPa"])):
        res = query(groups, pin, disc, p, temperature_C)
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
    :func:`densify_lines` aside)."""
    filled = table[~table["measured"] & ~table["added"]]
    if filled.empty:
        return ["every cell of this table was measured"]
    lines = [
        f"{len(filled)} cell(s) not measured, filled by tribopipe's interpolation (linear in "
        "temperature, log p - log mu in pressure; held constant outside the measured range):"
    ]
    for _, row in filled.iterrows():
        t = row["temperature_C"]
        t_text = "" if math.isnan(t) else f", T = {t:g} C"
        lines.append(
            f"  p = {row['pressure_kPa']:g} kPa "
            f"({num(row['pressure_kPa'] * units.pressure_per_kPa)} {units.pressure_unit})"
            f"{t_text}: mu = {num(row['mu_k'])}"
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

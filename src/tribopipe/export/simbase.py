"""What every simulator writer shares: units, the pair selection, slip rates, safe text.

Nothing here writes a file. The formats, and which writer function writes each, are
listed in :data:`tribopipe.export.registry.WRITERS`; :mod:`tribopipe.export.simulators`
runs them.

Unit systems (``units``): the map stores contact pressure in kPa and sliding speed in mm/s.

==========  ===================  ==============  ======================
``units``   contact pressure     slip rate       decay coefficient d_c
==========  ===================  ==============  ======================
mm-N-s      MPa (kPa × 1e-3)     mm/s (× 1)      s/mm (× 1)
m-N-s       Pa  (kPa × 1e3)      m/s (× 1e-3)    s/m  (× 1e3)
==========  ===================  ==============  ======================

Names that come from the map (pin, disc, the map's path) are data, never code: every
writer passes them through :func:`tribopipe.escape.sim_comment` (Python-repr escapes: no
newline, no control character survives) before they reach a comment, and they appear
nowhere else except as a quoted literal (:func:`repr` in Python, XML-escaped attributes)
or as a sanitised identifier (letters, digits, underscores).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING
from xml.sax.saxutils import quoteattr

from .. import __version__
from ..errors import ExportError
from ..escape import sim_comment
from ..interpolation import ENGINE_TOLERANCE, densify
from ..physics import FOUNDING_SLIDING_SPEED_MM_S
from ..query import (
    QueryResult,
    friction_table,
    groups_at_speed,
    pair_speeds,
    pairs,
    query,
    select_pair,
    speed_weights,
)
from .registry import COEFFICIENT

if TYPE_CHECKING:
    import pandas as pd

#: Which measured coefficient a single-coefficient engine gets for the onset of slip.
COEFFICIENTS = COEFFICIENT.choices


@dataclass(frozen=True)
class UnitSystem:
    """Conversion factors from the map's units (kPa, mm/s, s/mm) to a simulator's."""

    name: str
    pressure_unit: str
    pressure_per_kPa: float
    speed_unit: str
    speed_per_mm_s: float
    decay_unit: str
    decay_per_s_per_mm: float


UNIT_SYSTEMS: dict[str, UnitSystem] = {
    "mm-N-s": UnitSystem("mm-N-s", "MPa", 1e-3, "mm/s", 1.0, "s/mm", 1.0),
    "m-N-s": UnitSystem("m-N-s", "Pa", 1e3, "m/s", 1e-3, "s/m", 1e3),
}


def unit_system(units: str) -> UnitSystem:
    """The :class:`UnitSystem` named ``units`` (``mm-N-s`` or ``m-N-s``)."""
    try:
        return UNIT_SYSTEMS[units]
    except KeyError:
        raise ExportError(
            f"unknown unit system {units!r}; expected one of {', '.join(UNIT_SYSTEMS)}"
        ) from None


def convert_pressure_kPa(pressure_kPa: float, units: str) -> float:
    """Contact pressure [kPa] in the unit system's pressure unit (MPa or Pa)."""
    return pressure_kPa * unit_system(units).pressure_per_kPa


def num(value: float) -> str:
    """A number as the solvers read it: up to 10 significant digits, no separators.

    10 digits keep the grid's pressures exact enough that a solver's interpolation
    between them matches ours; short values (0.01179) stay short.
    """
    return f"{value:.10g}"


# ---------------------------------------------------------------------------- XML


def xml_comment(text: str, *, ascii_only: bool = False) -> str:
    """``text`` as one XML comment that no content can close or break (``ascii_only``:
    every non-ASCII character escaped too)."""
    return "<!-- " + sim_comment(text, "<!--", ascii_only=ascii_only) + " -->"


def xml_name(name: str, what: str) -> str:
    """An XML attribute value for a user-given element name, or an :class:`ExportError`
    when it holds a control character (which XML cannot carry)."""
    if any(not ch.isprintable() for ch in name):
        raise ExportError(
            f"{what} {name!r} holds a control character; a name must be printable"
        )
    return quoteattr(name)


# ---------------------------------------------------------------------------- headers


@dataclass(frozen=True)
class Engine:
    """What a writer's header says about its engine (one line each)."""

    name: str
    checked: str
    combination: str


def header_bodies(
    engine: Engine,
    holds: str,
    source: str | None,
    safe: Callable[[object], str] = sim_comment,
) -> list[str]:
    """The comment bodies every file opens with: engine, version checked against,
    coefficient held, how the engine combines two surfaces' values, and where the
    numbers came from (``source``, the map's path, made inert by ``safe``)."""
    origin = f" {safe(source)}" if source else ""
    return [
        f"{engine.name} input written by tribopipe {__version__} from the friction "
        f"map{origin}",
        f"checked against: {engine.checked}",
        f"holds: {holds}",
        f"two surfaces: {engine.combination}",
        "values: group means of the runs (repeats) at each nominal condition",
    ]


#: :func:`condition_lines`' words for a pair without μ_S and for a value held at an edge
MU_S_UNKNOWN = "unknown (not in the map)"
HELD_LINE = "outside the measured range: edge value held constant"
#: :func:`condition_lines`' first line, naming the pair (the names escaped for the file)
PAIR_LINE = "pair: pin {pin} on disc {disc}"


def condition_lines(res: QueryResult, safe: Callable[[object], str] = sim_comment) -> list[str]:
    """Comment bodies naming the pair, the condition, both coefficients and the measured
    groups they were interpolated from."""
    t = "unknown" if res.temperature_C is None else f"{res.temperature_C:g} C"
    lines = [
        PAIR_LINE.format(pin=safe(res.pin), disc=safe(res.disc)),
        f"condition: contact pressure {res.pressure_kPa:g} kPa, temperature {t}",
        f"mu_k = {num(res.mu_k.value)}; {res.mu_k.text(ascii_only=True)}"
        + ("" if res.mu_k.expanded is None else " (U, k = 2)"),
        "mu_s = " + (MU_S_UNKNOWN if res.mu_s is None else
                     f"{num(res.mu_s.value)}; {res.mu_s.text(ascii_only=True)}"
                     + ("" if res.mu_s.expanded is None else " (U, k = 2)")),
    ]
    used = ", ".join(
        f"{u.pressure_kPa:g} kPa"
        + ("" if u.temperature_C is None else f"/{u.temperature_C:g} C")
        + f" (w={u.weight:.3g})"
        for u in res.mu_k.used
    )
    lines.append(f"from measured groups: {used}")
    if res.clamped:
        lines.append(HELD_LINE)
    return lines


# ---------------------------------------------------------------------------- coefficients


def check_coefficient(coefficient: str) -> str:
    """``coefficient`` when it is one of :data:`COEFFICIENTS`, else an :class:`ExportError`."""
    if coefficient not in COEFFICIENTS:
        raise ExportError(
            f"unknown coefficient {coefficient!r}; expected one of {', '.join(COEFFICIENTS)}"
        )
    return coefficient


def breakaway(res: QueryResult, coefficient: str, engine: str) -> float:
    """The coefficient for the onset of slip: μ_K, or μ_S where asked (``"mu_s"``).

    Refuses ``"mu_s"`` in one line when the map holds no μ_S for the pair (a published map
    holds μ_K only): never a silent μ_K in its place.
    """
    if check_coefficient(coefficient) == "mu_k":
        return res.mu_k.value
    if res.mu_s is None:
        raise ExportError(
            f"pin {res.pin!r} on disc {res.disc!r} has no mu_s in the "
            f"map (e.g. an imported published map holds mu_k only): {engine} cannot get the "
            "breakaway coefficient",
            hint="leave out --coefficient mu_s to write mu_k",
        )
    return res.mu_s.value


#: where :func:`static_and_dynamic`'s static coefficient came from, worded once (the
#: explorer page receives these texts; ``{mu_s}`` is the map's μ_S)
STATIC_WHY = {
    "no_mu_s": "static = mu_k: the map holds no mu_s for this pair (an imported published map "
               "holds mu_k only), so the onset of slip takes the kinetic coefficient; the "
               "static coefficient is written all the same, never left to the engine's default",
    "raised": "static = mu_k: the map's mu_s ({mu_s}) is below mu_k at this condition and "
              "the engine needs static >= dynamic, so static is raised to mu_k",
    "mu_s": "static = mu_s (breakaway), dynamic = mu_k (sliding)",
}


def static_and_dynamic(res: QueryResult) -> tuple[float, float, str]:
    """The static and dynamic coefficients for an engine that takes both, and one line
    saying where the static one came from.

    Static is μ_S where the map holds it, else μ_K (a published map holds μ_K only): the
    onset of slip then takes the kinetic coefficient, and the static coefficient is still
    written, never left to the engine's default. Where the map's μ_S is below μ_K at the
    condition, static is raised to μ_K (engines want static ≥ dynamic: PhysX raises it
    itself, Drake refuses the file).
    """
    mu_k = res.mu_k.value
    if res.mu_s is None:
        return mu_k, mu_k, STATIC_WHY["no_mu_s"]
    if res.mu_s.value < mu_k:
        return mu_k, mu_k, STATIC_WHY["raised"].format(mu_s=num(res.mu_s.value))
    return res.mu_s.value, mu_k, STATIC_WHY["mu_s"]


def default_decay_s_per_mm(slip_rate_mm_s: float = FOUNDING_SLIDING_SPEED_MM_S) -> float:
    """d_c [s/mm] that lets μ decay 99 % of the way from μ_S to μ_K at the measured slip rate.

    The exponential model (ABAQUS, LS-DYNA) is μ = μ_k + (μ_s − μ_k)·exp(−d_c·v); a
    single-speed test cannot measure d_c, so we pick the value for which the measured
    μ_K holds at the test's sliding speed v: exp(−d_c·v) = 0.01.
    """
    return math.log(100.0) / slip_rate_mm_s


def check_decay(decay_s_per_mm: float) -> float:
    """``decay_s_per_mm`` when it is a positive finite number, else an :class:`ExportError`."""
    if not (math.isfinite(decay_s_per_mm) and decay_s_per_mm > 0):
        raise ExportError(
            f"decay coefficient must be a positive number of s/mm, got {decay_s_per_mm}"
        )
    return decay_s_per_mm


# ---------------------------------------------------------------------------- slip rates


@dataclass(frozen=True)
class SlipRate:
    """One pair's sliding speed [mm/s]: the median of its runs, with their range.

    ``n_runs == 0`` means no run of the pair records a speed and the founding paper's
    0.007 mm/s stands in (said so in the file).
    """

    value_mm_s: float
    n_runs: int
    min_mm_s: float
    max_mm_s: float

    @property
    def measured(self) -> bool:
        """True when the value comes from the pair's own runs."""
        return self.n_runs > 0

    def describe(self) -> str:
        """One comment line saying where the slip rate came from."""
        if not self.measured:
            return (f"slip rate {self.value_mm_s:g} mm/s: no run of this pair records its "
                    "sliding speed, the founding paper's speed stands in")
        spread = (f"all at {self.min_mm_s:.4g} mm/s" if self.min_mm_s == self.max_mm_s
                  else f"{self.min_mm_s:.4g}-{self.max_mm_s:.4g} mm/s")
        text = (f"slip rate {self.value_mm_s:.4g} mm/s: median recorded sliding speed of this "
                f"pair's {self.n_runs} run(s), {spread}")
        if self.max_mm_s > 1.25 * self.min_mm_s:
            text += ("; FLAG: runs at speeds more than 25 % apart, the file holds no "
                     "slip-rate dependence")
        return text


FOUNDING_SLIP_RATE = SlipRate(FOUNDING_SLIDING_SPEED_MM_S, 0, math.nan, math.nan)


def slip_rate_of(rates: Mapping[tuple[str, str], SlipRate] | None, pin: str, disc: str) -> SlipRate:
    """The pair's :class:`SlipRate` from ``rates`` (keyed by the map's pin and disc names),
    or the founding paper's speed where the pair has none."""
    if rates is None:
        return FOUNDING_SLIP_RATE
    return rates.get((pin, disc), FOUNDING_SLIP_RATE)


def pair_slip_rates(runs: pd.DataFrame) -> dict[tuple[str, str], SlipRate]:
    """Each pair's :class:`SlipRate` from friction-map ``runs`` (excluded runs left out;
    runs without a positive finite ``sliding_speed_mm_s`` do not count)."""
    import numpy as np

    if runs.empty or "sliding_speed_mm_s" not in runs.columns:
        return {}
    if "excluded" in runs.columns:
        runs = runs[~runs["excluded"].fillna(False).astype(bool)]
    rates = {}
    for (pin, disc), group in runs.groupby(["pin", "disc"], sort=True):
        speed = group["sliding_speed_mm_s"].to_numpy(dtype=float)
        speed = speed[np.isfinite(speed) & (speed > 0)]
        if speed.size:
            rates[(str(pin), str(disc))] = SlipRate(
                float(np.median(speed)), int(speed.size), float(speed.min()), float(speed.max())
            )
    return rates


# ---------------------------------------------------------------------------- selection


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


def comment_block(comment: str, bodies: list[str], width: int = 100) -> list[str]:
    """``bodies`` as comment lines of at most ``width`` characters (long ones wrapped,
    continuation lines indented), each starting with ``comment`` and a space."""
    import textwrap

    lines = []
    for body in bodies:
        indent = " " * (len(body) - len(body.lstrip(" ")))
        # words (a path, a name) are split only when longer than a whole line
        wrapped = textwrap.wrap(body, width=width - len(comment) - 1,
                                subsequent_indent=indent + "  ",
                                break_on_hyphens=False) or [""]
        lines += [f"{comment} {w}".rstrip() for w in wrapped]
    return lines



# ---------------------------------------------------------------------------- speeds


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


def speed_rows(groups: pd.DataFrame, pin: str, disc: str,
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
    :data:`~tribopipe.interpolation.ENGINE_TOLERANCE` of ``query`` over the table."""
    import pandas as pd

    measured_speeds = pair_speeds(select_pair(groups, pin, disc))
    if len(measured_speeds) < 2:
        return None
    pressures: set[float] = set()
    temps: set[float] = set()
    measured: set[tuple[float, float, float]] = set()
    measured_p: set[float] = set()
    for v in measured_speeds:
        part = table_at(groups_at_speed(groups, v), pin, disc, temperature_C, dense=True)
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
    at_measured = [[query(groups, pin, disc, p, None if math.isnan(t) else t, v).mu_k.value
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

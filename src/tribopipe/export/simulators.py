"""Simulator input from the friction map: ABAQUS, Ansys, MuJoCo, SOFA, PyElastica.

Every writer takes the group-statistics table (see :mod:`tribopipe.query`) and returns
the text of the input file; nothing here touches the file system. Values are the group
means of μ_K (and μ_S where measured); cells of a table that were not measured are filled
by :func:`tribopipe.query.query`'s interpolation and say so in a comment.

Unit systems (``units``): the map stores contact pressure in kPa and sliding speed in mm/s.

==========  ===================  ==============  ======================
``units``   contact pressure     slip rate       decay coefficient d_c
==========  ===================  ==============  ======================
mm-N-s      MPa (kPa × 1e-3)     mm/s (× 1)      s/mm (× 1)
m-N-s       Pa  (kPa × 1e3)      m/s (× 1e-3)    s/m  (× 1e3)
==========  ===================  ==============  ======================
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from html import escape
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import __version__
from ..errors import ExportError
from ..frictionmap import PUBLISHED_SLIDING_SPEED_MM_S
from ..query import friction_table, pairs, query, select_pair

if TYPE_CHECKING:
    import pandas as pd

#: The founding paper's sliding speed [mm/s]: the slip rate when no run records one.
FOUNDING_SLIP_RATE_MM_S = PUBLISHED_SLIDING_SPEED_MM_S


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

FORMATS = ("abaqus", "ansys", "mujoco", "sofa", "pyelastica")


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


def _num(value: float) -> str:
    """A number as ABAQUS/Ansys read it: up to 10 significant digits, no separators.

    10 digits keep the grid's pressures exact enough that a solver's interpolation
    between them matches ours; short values (0.01179) stay short.
    """
    return f"{value:.10g}"


def _selected_pairs(
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


def _table_at(
    groups: pd.DataFrame, pin: str, disc: str, temperature_C: float | None
) -> pd.DataFrame:
    """The pair's μ_K table, or its single-temperature slice interpolated at ``temperature_C``."""
    import pandas as pd

    table = friction_table(groups, pin, disc, "mu_k")
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
                "measured": measured,
            }
        )
    return pd.DataFrame(rows)


def abaqus_name(pin: str, disc: str) -> str:
    """An ABAQUS-safe interaction name for a pair (letters, digits, underscores; ≤ 80 chars)."""
    text = re.sub(r"[^A-Za-z0-9]+", "_", f"{pin}__ON__{disc}").strip("_").upper()
    return ("FRIC_" + text)[:80]


def _provenance(comment: str, source: str | None, what: str) -> list[str]:
    """Comment lines saying what the file is and where its values came from."""
    lines = [
        f"{comment} {what}",
        f"{comment} written by tribopipe {__version__} from the friction map"
        + (f" {source}" if source else ""),
        f"{comment} values: group means of the runs (repeats) at each nominal condition",
    ]
    return lines


def _filled_comments(comment: str, table: pd.DataFrame, units: UnitSystem) -> list[str]:
    """Comment lines listing the table cells filled by interpolation."""
    filled = table[~table["measured"]]
    if filled.empty:
        return [f"{comment} every cell of this table was measured"]
    lines = [
        f"{comment} {len(filled)} cell(s) not measured, filled by linear interpolation in "
        "temperature and pressure (held constant outside the measured range):"
    ]
    for _, row in filled.iterrows():
        t = row["temperature_C"]
        t_text = "" if math.isnan(t) else f", T = {t:g} C"
        lines.append(
            f"{comment}   p = {row['pressure_kPa']:g} kPa "
            f"({_num(row['pressure_kPa'] * units.pressure_per_kPa)} {units.pressure_unit})"
            f"{t_text}: mu = {_num(row['mu_k'])}"
        )
    return lines


def write_abaqus(
    groups: pd.DataFrame,
    *,
    pin: str | None = None,
    disc: str | None = None,
    temperature_C: float | None = None,
    units: str = "mm-N-s",
    slip_rate_mm_s: float = FOUNDING_SLIP_RATE_MM_S,
    source: str | None = None,
) -> str:
    """ABAQUS ``*SURFACE INTERACTION`` + ``*FRICTION`` tables of μ_K, one per selected pair.

    Data lines follow the *FRICTION keyword's documented order: friction coefficient,
    slip rate, contact pressure, average temperature (then field variables, which we do
    not use: ``DEPENDENCIES`` counts field variables only, temperature is always column 4,
    so the parameter is omitted). The grid is full and rectangular — every measured
    pressure at every measured temperature, temperature outer and pressure inner (ABAQUS
    wants the first variable to vary fastest). ``temperature_C`` restricts the table to
    one interpolated temperature. The slip rate is the single measured sliding speed
    (``slip_rate_mm_s``): one value means no slip-rate dependence.
    """
    u = unit_system(units)
    lines = _provenance("**", source, "ABAQUS friction input (kinetic coefficient mu_k)")
    lines += [
        f"** units {u.name}: contact pressure in {u.pressure_unit}, slip rate in "
        f"{u.speed_unit}, temperature in C",
        "** data-line order (Abaqus Keywords Reference, *FRICTION): friction coefficient, "
        "slip rate, contact pressure, temperature",
        "** outside the table ABAQUS holds the end values constant (as tribopipe query does)",
    ]
    for pin_name, disc_name in _selected_pairs(groups, pin, disc):
        table = _table_at(groups, pin_name, disc_name, temperature_C)
        lines += [
            "**",
            f"** pair: pin {pin_name} on disc {disc_name}",
            f"** measured at a sliding speed of {slip_rate_mm_s:g} mm/s",
        ]
        lines += _filled_comments("**", table, u)
        lines += [f"*SURFACE INTERACTION, NAME={abaqus_name(pin_name, disc_name)}", "*FRICTION"]
        slip = slip_rate_mm_s * u.speed_per_mm_s
        for _, row in table.iterrows():
            fields = [_num(row["mu_k"]), _num(slip), _num(row["pressure_kPa"] * u.pressure_per_kPa)]
            if not math.isnan(row["temperature_C"]):
                fields.append(_num(row["temperature_C"]))
            lines.append(", ".join(fields))
    return "\n".join(lines) + "\n"


def default_decay_s_per_mm(slip_rate_mm_s: float = FOUNDING_SLIP_RATE_MM_S) -> float:
    """d_c [s/mm] that lets μ decay 99 % of the way from μ_S to μ_K at the measured slip rate.

    ABAQUS's exponential model is μ = μ_k + (μ_s − μ_k)·exp(−d_c·γ̇); a single-speed test
    cannot measure d_c, so we pick the value for which the measured μ_K holds at the
    test's sliding speed: exp(−d_c·v) = 0.01.
    """
    return math.log(100.0) / slip_rate_mm_s


def write_abaqus_decay(
    groups: pd.DataFrame,
    *,
    pin: str,
    disc: str,
    pressure_kPa: float,
    temperature_C: float | None = None,
    units: str = "mm-N-s",
    decay_s_per_mm: float | None = None,
    slip_rate_mm_s: float = FOUNDING_SLIP_RATE_MM_S,
    source: str | None = None,
) -> str:
    """ABAQUS ``*FRICTION, EXPONENTIAL DECAY`` (μ_s, μ_k, d_c) for one condition.

    Needs μ_S in the map (raises :class:`ExportError` otherwise). ``decay_s_per_mm``
    defaults to :func:`default_decay_s_per_mm`; it is written in the unit system's
    1/slip-rate unit (s/mm or s/m).
    """
    u = unit_system(units)
    res = query(groups, pin, disc, pressure_kPa, temperature_C)
    if res.mu_s is None:
        raise ExportError(
            f"pin {res.pin!r} on disc {res.disc!r} has no mu_s in the map: "
            "EXPONENTIAL DECAY needs a static coefficient",
            hint="export the mu_k table instead (leave out --exponential-decay)",
        )
    d_c = default_decay_s_per_mm(slip_rate_mm_s) if decay_s_per_mm is None else decay_s_per_mm
    if not (math.isfinite(d_c) and d_c > 0):
        raise ExportError(f"decay coefficient must be a positive number of s/mm, got {d_c}")
    lines = _provenance("**", source, "ABAQUS exponential-decay friction (static -> kinetic)")
    lines += _condition_comments("**", res)
    lines += [
        f"** model: mu = mu_k + (mu_s - mu_k) * exp(-d_c * slip rate), d_c in {u.decay_unit}",
        f"** d_c = {_num(d_c)} s/mm"
        + (" (default: 99 % of the decay reached at the measured sliding speed)"
           if decay_s_per_mm is None else " (given)"),
        f"*SURFACE INTERACTION, NAME={abaqus_name(res.pin, res.disc)}",
        "*FRICTION, EXPONENTIAL DECAY",
        ", ".join(
            [_num(res.mu_s.value), _num(res.mu_k.value), _num(d_c * u.decay_per_s_per_mm)]
        ),
    ]
    return "\n".join(lines) + "\n"


def write_ansys(
    groups: pd.DataFrame,
    *,
    pin: str | None = None,
    disc: str | None = None,
    temperature_C: float | None = None,
    units: str = "mm-N-s",
    material_id: int = 1,
    source: str | None = None,
) -> str:
    """Ansys MAPDL ``TB,FRIC,mat,,,ISO`` tables with ``TBFIELD`` on temperature and pressure.

    One material per selected pair, numbered from ``material_id``. Per the MAPDL
    reference the field name for contact (normal) pressure is ``NPRES``; fields are given
    in ascending order, temperature (rows) outer and pressure inner.
    """
    u = unit_system(units)
    lines = _provenance("!", source, "Ansys MAPDL friction input (kinetic coefficient mu_k)")
    lines.append(f"! units {u.name}: NPRES in {u.pressure_unit}, TEMP in C")
    for offset, (pin_name, disc_name) in enumerate(_selected_pairs(groups, pin, disc)):
        mat = material_id + offset
        table = _table_at(groups, pin_name, disc_name, temperature_C)
        lines += ["!", f"! material {mat}: pin {pin_name} on disc {disc_name}"]
        lines += _filled_comments("!", table, u)
        lines.append(f"TB,FRIC,{mat},,,ISO")
        last_t: float | None = None
        for _, row in table.iterrows():
            t = row["temperature_C"]
            if not math.isnan(t) and t != last_t:
                lines.append(f"TBFIELD,TEMP,{_num(t)}")
                last_t = t
            lines.append(f"TBFIELD,NPRES,{_num(row['pressure_kPa'] * u.pressure_per_kPa)}")
            lines.append(f"TBDATA,1,{_num(row['mu_k'])}")
    return "\n".join(lines) + "\n"


def _condition_comments(comment: str, res: object) -> list[str]:
    """Comment lines naming the condition, the values, and what they were interpolated from."""
    t = "unknown" if res.temperature_C is None else f"{res.temperature_C:g} C"
    lines = [
        f"{comment} pair: pin {res.pin} on disc {res.disc}",
        f"{comment} condition: contact pressure {res.pressure_kPa:g} kPa, temperature {t}",
        f"{comment} mu_k = {_num(res.mu_k.value)}"
        + ("" if res.mu_k.uncertainty is None else f" +/- {_num(res.mu_k.uncertainty)} (95 % CI)"),
        f"{comment} mu_s = "
        + ("unknown (not in the map)" if res.mu_s is None else _num(res.mu_s.value)),
    ]
    used = ", ".join(
        f"{u.pressure_kPa:g} kPa"
        + ("" if u.temperature_C is None else f"/{u.temperature_C:g} C")
        + f" (w={u.weight:.3g})"
        for u in res.mu_k.used
    )
    lines.append(f"{comment} from measured groups: {used}")
    if res.clamped:
        lines.append(f"{comment} outside the measured range: edge value held constant")
    return lines


def _xml_comment(text: str) -> str:
    """``text`` as one XML comment."""
    # "--" may not appear inside an XML comment
    return "<!-- " + text.replace("--", "- -") + " -->"


def write_mujoco(
    groups: pd.DataFrame,
    *,
    pin: str,
    disc: str,
    pressure_kPa: float,
    temperature_C: float | None = None,
    geom1: str = "pin",
    geom2: str = "disc",
    source: str | None = None,
) -> str:
    """A MuJoCo MJCF fragment: a ``<contact><pair>`` with the pair's sliding friction μ_K.

    MuJoCo has one Coulomb coefficient per contact (no static/kinetic split) and, for
    geoms of equal priority, combines the two geoms' ``friction`` by the element-wise
    maximum; an explicit ``<pair>`` bypasses that. Torsional and rolling coefficients are
    not measured: MuJoCo's defaults (0.005, 0.0001) are written.
    """
    res = query(groups, pin, disc, pressure_kPa, temperature_C)
    mu = _num(res.mu_k.value)
    comments = [c.lstrip("# ") for c in _condition_comments("#", res)]
    lines = [_xml_comment(f"tribopipe {__version__}: MuJoCo contact pair" + (
        f" from {source}" if source else ""))]
    lines += [_xml_comment(c) for c in comments]
    lines += [
        _xml_comment("MuJoCo uses one Coulomb coefficient: sliding friction = mu_k"),
        _xml_comment(
            "MuJoCo combines two geoms' friction by the maximum (Bullet-style engines by the "
            "product): set the pair explicitly so neither rule applies"
        ),
        _xml_comment("torsional 0.005 and rolling 0.0001 are MuJoCo defaults, not measured"),
        "<mujoco>",
        "  <contact>",
        f'    <pair geom1="{escape(geom1)}" geom2="{escape(geom2)}" condim="3" '
        f'friction="{mu} {mu} 0.005 0.0001 0.0001"/>',
        "  </contact>",
        "</mujoco>",
    ]
    return "\n".join(lines) + "\n"


def write_sofa(
    groups: pd.DataFrame,
    *,
    pin: str,
    disc: str,
    pressure_kPa: float,
    temperature_C: float | None = None,
    source: str | None = None,
) -> str:
    """A SOFA scene fragment: ``CollisionResponse`` with ``FrictionContactConstraint`` and mu.

    SOFA's frictional contact takes one Coulomb μ for the response (μ_K is written);
    older SOFA versions name the component ``DefaultContactManager`` and the response
    ``FrictionContact``.
    """
    res = query(groups, pin, disc, pressure_kPa, temperature_C)
    lines = [_xml_comment(f"tribopipe {__version__}: SOFA contact response" + (
        f" from {source}" if source else ""))]
    lines += [_xml_comment(c.lstrip("# ")) for c in _condition_comments("#", res)]
    lines += [
        _xml_comment("SOFA takes one Coulomb coefficient per response: mu = mu_k"),
        _xml_comment(
            "per-pair values need a RuleBasedContactManager rule "
            "'group1 group2 FrictionContactConstraint?mu=...'; engines differ in how they "
            "combine two materials (MuJoCo: maximum, Bullet-style: product)"
        ),
        '<Node name="root">',
        '  <CollisionResponse name="response" response="FrictionContactConstraint" '
        f'responseParams="mu={_num(res.mu_k.value)}"/>',
        "</Node>",
    ]
    return "\n".join(lines) + "\n"


def write_pyelastica(
    groups: pd.DataFrame,
    *,
    pin: str,
    disc: str,
    pressure_kPa: float,
    temperature_C: float | None = None,
    source: str | None = None,
) -> str:
    """Python for PyElastica: ``static_mu_array`` and ``kinetic_mu_array`` (forward,
    backward, sideways) for ``AnisotropicFrictionalPlane``; isotropic, so all three equal.

    When the map holds no μ_S the static array is set to μ_K and a comment says so.
    """
    res = query(groups, pin, disc, pressure_kPa, temperature_C)
    mu_k = _num(res.mu_k.value)
    mu_s = mu_k if res.mu_s is None else _num(res.mu_s.value)
    lines = [f"# tribopipe {__version__}: PyElastica friction" + (
        f" from {source}" if source else "")]
    lines += _condition_comments("#", res)
    if res.mu_s is None:
        lines.append("# mu_s unknown: the static array is set to mu_k (no breakaway peak)")
    lines += [
        "# arrays are [forward, backward, sideways]; the pin-on-disc data are isotropic",
        "# use: simulator.add_forcing_to(rod).using(AnisotropicFrictionalPlane, k=..., nu=...,",
        "#      plane_origin=..., plane_normal=..., slip_velocity_tol=...,",
        "#      static_mu_array=static_mu_array, kinetic_mu_array=kinetic_mu_array)",
        "# engines differ in combining two materials (MuJoCo: maximum, Bullet-style: product);",
        "# these are already the pair's values",
        "import numpy as np",
        "",
        f"static_mu_array = np.array([{mu_s}, {mu_s}, {mu_s}])",
        f"kinetic_mu_array = np.array([{mu_k}, {mu_k}, {mu_k}])",
    ]
    return "\n".join(lines) + "\n"


#: single-condition writers (need pin, disc and a pressure)
SINGLE_VALUE_WRITERS: dict[str, Callable[..., str]] = {
    "mujoco": write_mujoco,
    "sofa": write_sofa,
    "pyelastica": write_pyelastica,
}


def export_simulator_input(
    groups: pd.DataFrame,
    fmt: str,
    *,
    pin: str | None = None,
    disc: str | None = None,
    pressure_kPa: float | None = None,
    temperature_C: float | None = None,
    units: str = "mm-N-s",
    exponential_decay: bool = False,
    decay_s_per_mm: float | None = None,
    material_id: int = 1,
    geom1: str = "pin",
    geom2: str = "disc",
    slip_rate_mm_s: float = FOUNDING_SLIP_RATE_MM_S,
    source: str | None = None,
) -> str:
    """The input text for simulator ``fmt`` (one of :data:`FORMATS`).

    Tables (``abaqus``, ``ansys``) take any selection of pairs; single-value formats
    (``mujoco``, ``sofa``, ``pyelastica``) and ABAQUS's exponential decay need ``pin``,
    ``disc`` and ``pressure_kPa`` [kPa] (a missing one is an :class:`ExportError` that
    lists what the map holds).
    """
    if fmt not in FORMATS:
        raise ExportError(f"unknown simulator {fmt!r}; expected one of {', '.join(FORMATS)}")
    unit_system(units)
    table = fmt == "ansys" or (fmt == "abaqus" and not exponential_decay)
    if table and pressure_kPa is not None:
        raise ExportError(
            f"the {fmt} table covers every measured pressure; a single pressure is for "
            "mujoco, sofa, pyelastica or abaqus --exponential-decay",
            hint="leave out --pressure",
        )
    if decay_s_per_mm is not None and not (fmt == "abaqus" and exponential_decay):
        raise ExportError("a decay coefficient only applies to abaqus --exponential-decay")
    if fmt == "abaqus" and not exponential_decay:
        return write_abaqus(groups, pin=pin, disc=disc, temperature_C=temperature_C,
                            units=units, slip_rate_mm_s=slip_rate_mm_s, source=source)
    if fmt == "ansys":
        return write_ansys(groups, pin=pin, disc=disc, temperature_C=temperature_C,
                           units=units, material_id=material_id, source=source)
    what = "ABAQUS EXPONENTIAL DECAY" if fmt == "abaqus" else fmt
    if pin is None or disc is None:
        listing = "; ".join(f"{p} on {d}" for p, d in pairs(groups)) or "nothing"
        raise ExportError(
            f"{what} takes one condition: give the pin and the disc; the map holds: {listing}",
            hint="pass --pin and --disc",
        )
    if pressure_kPa is None:
        pair = select_pair(groups, pin, disc)
        measured = ", ".join(f"{p:g}" for p in sorted(set(pair["pressure_kPa"])))
        raise ExportError(
            f"{what} takes one condition: give the contact pressure; "
            f"{pin} on {disc} is measured at {measured} kPa",
            hint="pass --pressure KPA",
        )
    if fmt == "abaqus":
        return write_abaqus_decay(groups, pin=pin, disc=disc, pressure_kPa=pressure_kPa,
                                  temperature_C=temperature_C, units=units,
                                  decay_s_per_mm=decay_s_per_mm,
                                  slip_rate_mm_s=slip_rate_mm_s, source=source)
    extra = {"geom1": geom1, "geom2": geom2} if fmt == "mujoco" else {}
    return SINGLE_VALUE_WRITERS[fmt](groups, pin=pin, disc=disc, pressure_kPa=pressure_kPa,
                                     temperature_C=temperature_C, source=source, **extra)


def measured_slip_rate_mm_s(runs: pd.DataFrame) -> float:
    """The median sliding speed [mm/s] of the included runs; the founding 0.007 mm/s when
    no run records one."""
    import numpy as np

    speed = runs["sliding_speed_mm_s"].to_numpy(dtype=float)
    if "excluded" in runs.columns:
        speed = speed[~runs["excluded"].fillna(False).astype(bool).to_numpy()]
    speed = speed[np.isfinite(speed) & (speed > 0)]
    return float(np.median(speed)) if speed.size else FOUNDING_SLIP_RATE_MM_S


def export_from_map(map_path: str | Path, fmt: str, **options: Any) -> str:
    """:func:`export_simulator_input` on the friction map (Parquet) at ``map_path``; the
    slip rate of ABAQUS tables is the runs' median sliding speed."""
    from ..frictionmap import read_map
    from ..query import groups_of

    runs = read_map(map_path)
    groups = groups_of(runs, map_path)
    slip = measured_slip_rate_mm_s(runs)
    return export_simulator_input(groups, fmt, source=str(map_path), slip_rate_mm_s=slip,
                                  **options)

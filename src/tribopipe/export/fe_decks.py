"""Friction input for the finite-element solvers: ABAQUS, Ansys MAPDL, LS-DYNA.

Each writer returns the text of one input file (nothing here touches the file system);
every header says which engine and version the format was checked against, which
coefficient the file holds and how the engine combines two surfaces' values. Names from
the map reach these decks only as ASCII comments (:func:`tribopipe.escape.sim_comment`) or as
sanitised identifiers (:func:`abaqus_name`, :func:`deck_names`).
"""

from __future__ import annotations

import hashlib
import math
import re
from collections.abc import Mapping
from functools import partial
from typing import TYPE_CHECKING

from ..errors import ExportError
from ..escape import sim_comment
from ..fit import DecayFit, fit_decay
from ..interpolation import ENGINE_TOLERANCE
from ..query import QueryResult
from .coefficients import breakaway, check_decay
from .engine_tables import PairGroups, densify_lines, filled_lines, selected_pairs, table_at
from .headers import Engine, comment_block, condition_lines, header_bodies
from .slip_rates import FOUNDING_SLIP_RATE, SlipRate, default_decay_s_per_mm, slip_rate_of
from .speed_tables import speed_rows
from .unit_systems import num, unit_system

if TYPE_CHECKING:
    import pandas as pd

#: inert text for a comment of the fixed-format decks (ABAQUS ``**``; LS-DYNA's ``$``
#: comments take the same ASCII escapes)
deck_safe = partial(sim_comment, syntax="**")

ABAQUS = Engine(
    name="ABAQUS",
    checked=(
        "Abaqus Keywords Reference 2017-2024, *FRICTION (data lines: friction coefficient, "
        "slip rate, contact pressure, temperature; EXPONENTIAL DECAY: mu_s, mu_k, d_c); "
        "not run in Abaqus"
    ),
    combination=(
        "*FRICTION belongs to a *SURFACE INTERACTION, one per contact pair: the value is "
        "the pair's own, nothing is combined"
    ),
)

#: Said in every ABAQUS file: the same keyword means something else to CalculiX.
CALCULIX_WARNING = (
    "Abaqus input only, not for CalculiX: ccx 2.x (src/frictions.f) reads just the first two "
    "columns of a *FRICTION data line, as mu and stick slope [force/volume], keeps only the "
    "last data line, takes no pressure or temperature dependence and ignores EXPONENTIAL "
    "DECAY - it would read this file's slip rate (or mu_k) as a stick slope"
)

ANSYS = Engine(
    name="Ansys MAPDL",
    checked=(
        "Ansys MAPDL 2025 R1 Command Reference, TB,FRIC,mat,,,ISO with TBFIELD,TEMP and "
        "TBFIELD,NPRES; not run in Ansys"
    ),
    combination=(
        "TB,FRIC is the material of a contact pair's contact elements: the value is the "
        "pair's own, nothing is combined"
    ),
)

LSDYNA = Engine(
    name="LS-DYNA",
    checked=(
        "LS-DYNA Keyword User's Manual R14, *CONTACT_AUTOMATIC_SURFACE_TO_SURFACE_ID "
        "(ID card CID/HEADING; card 1 SURFA SURFB SURFATYP SURFBTYP; card 2 FS FD DC; "
        "standard format, 10-character fields); not run in LS-DYNA"
    ),
    combination=(
        "FS/FD/DC belong to the *CONTACT definition, not to a part: the values are the "
        "pair's own, nothing is combined (FS = -1 would take *PART friction instead; "
        "not used here)"
    ),
)


# ---------------------------------------------------------------------------- names


def abaqus_name(pin: str, disc: str) -> str:
    """An ABAQUS-safe interaction name for a pair (letters, digits, underscores; ≤ 80 chars)."""
    text = re.sub(r"[^A-Za-z0-9]+", "_", f"{pin}__ON__{disc}").strip("_").upper()
    return ("FRIC_" + text)[:80]


def deck_names(selected: list[tuple[str, str]], limit: int = 80) -> dict[tuple[str, str], str]:
    """:func:`abaqus_name` of every pair, made unique: pairs whose sanitised names collide
    ("a b" and "a_b") get a short hash of their exact names appended; ≤ ``limit`` chars."""
    base = {pair: abaqus_name(*pair)[:limit] for pair in selected}
    counts: dict[str, int] = {}
    for name in base.values():
        counts[name] = counts.get(name, 0) + 1
    names = {}
    for pair, name in base.items():
        if counts[name] > 1:
            tag = hashlib.sha256("\0".join(pair).encode()).hexdigest()[:8].upper()
            name = name[: limit - 9] + "_" + tag
        names[pair] = name
    return names


# ---------------------------------------------------------------------------- ABAQUS


def write_abaqus(
    groups: pd.DataFrame,
    *,
    pin: str | None = None,
    disc: str | None = None,
    temperature_C: float | None = None,
    units: str = "mm-N-s",
    slip_rates: Mapping[tuple[str, str], SlipRate] | None = None,
    source: str | None = None,
) -> str:
    """ABAQUS ``*SURFACE INTERACTION`` + ``*FRICTION`` tables of μ_K, one per selected pair
    (one condition's constant μ_K is :func:`condition_snippet`, what the explorer copies).

    Data lines follow the *FRICTION keyword's documented order: friction coefficient,
    slip rate, contact pressure, average temperature (then field variables, which we do
    not use: ``DEPENDENCIES`` counts field variables only, temperature is always column 4,
    so the parameter is omitted). The grid is full and rectangular — every measured
    pressure at every measured temperature, temperature outer and pressure inner (ABAQUS
    wants the first variable to vary fastest). ``temperature_C`` restricts the table to
    one interpolated temperature. The slip rate is each pair's own measured sliding speed
    (``slip_rates``, keyed by the map's pin and disc names; the founding 0.007 mm/s where
    a pair records none): one value per pair means no slip-rate dependence.
    """
    u = unit_system(units)
    selected = selected_pairs(groups, pin, disc)
    names = deck_names(selected)
    bodies = header_bodies(ABAQUS, "mu_k, the kinetic (sliding) Coulomb coefficient",
                           source, deck_safe)
    bodies += [
        CALCULIX_WARNING,
        f"units {u.name}: contact pressure in {u.pressure_unit}, slip rate in "
        f"{u.speed_unit}, temperature in C",
        "outside the table ABAQUS holds the end values constant (as tribopipe query does)",
    ]
    lines = comment_block("**", bodies)
    split = PairGroups(groups)  # each pair's groups selected once, κ computed once
    for pin_name, disc_name in selected:
        table, by_speed = pair_table(split, pin_name, disc_name, temperature_C)
        rate = slip_rate_of(slip_rates, pin_name, disc_name)
        pair_bodies = [
            "",
            f"pair: pin {deck_safe(pin_name)} on disc {deck_safe(disc_name)}",
            rate.describe(),
            *filled_lines(table, u),
            *densify_lines(table, "ABAQUS"),
        ]
        if by_speed is not None:
            pair_bodies[2] = speed_table_note(by_speed, u.speed_per_mm_s, u.speed_unit,
                                              "ABAQUS")
        lines += comment_block("**", pair_bodies)
        lines += [f"*SURFACE INTERACTION, NAME={names[(pin_name, disc_name)]}", "*FRICTION"]
        if by_speed is not None:
            for _, row in by_speed.iterrows():
                fields = [num(row["mu_k"]), num(row["speed_mm_s"] * u.speed_per_mm_s),
                          num(row["pressure_kPa"] * u.pressure_per_kPa)]
                if not math.isnan(row["temperature_C"]):
                    fields.append(num(row["temperature_C"]))
                lines.append(", ".join(fields))
            continue
        slip = rate.value_mm_s * u.speed_per_mm_s
        for _, row in table.iterrows():
            fields = [num(row["mu_k"]), num(slip), num(row["pressure_kPa"] * u.pressure_per_kPa)]
            if not math.isnan(row["temperature_C"]):
                fields.append(num(row["temperature_C"]))
            lines.append(", ".join(fields))
    return "\n".join(lines) + "\n"


def pair_table(
    split: PairGroups, pin: str, disc: str, temperature_C: float | None
) -> tuple[pd.DataFrame, pd.DataFrame | None]:
    """The μ_K table a deck writes for one pair, and the same table where it runs over
    sliding speed (else ``None``): over pressure, temperature and slip rate where the pair
    is measured at several nominal speeds (:func:`speed_rows`, each speed's groups read
    apart), else over pressure and temperature (:func:`table_at`). ``temperature_C`` [°C]
    slices either at one interpolated temperature."""
    by_speed = speed_rows(split, pin, disc, temperature_C)
    if by_speed is not None:
        return by_speed, by_speed
    return table_at(split.pair(pin, disc), pin, disc, temperature_C, dense=True,
                    curvature=split.curvature()), None


def speed_table_note(rows: pd.DataFrame, per_mm_s: float, unit: str, engine: str) -> str:
    """The comment of a table over slip rate: the measured nominal speeds, and how the
    engine reads between them."""
    speeds = sorted(set(float(v) for v in rows.loc[~rows["speed_added"], "speed_mm_s"]))
    added = sorted(set(float(v) for v in rows.loc[rows["speed_added"], "speed_mm_s"]))
    listed = ", ".join(num(v * per_mm_s) for v in speeds)
    text = (f"slip rates {listed} {unit}: this pair's measured nominal sliding speeds; "
            f"{engine} interpolates linearly in slip rate between rows and holds the ends, "
            "tribopipe query interpolates in log v")
    if not added:
        return text + " (the two agree at the measured speeds)"
    return (text + f"; with {len(added)} slip rate(s) added between the measured speeds "
            f"the two differ by at most {ENGINE_TOLERANCE:g} in mu over the measured range. "
            f"Added at ({unit}): " + ", ".join(num(v * per_mm_s) for v in added))


def write_abaqus_decay(
    res: QueryResult,
    *,
    units: str = "mm-N-s",
    decay_s_per_mm: float | None = None,
    slip_rate: SlipRate = FOUNDING_SLIP_RATE,
    source: str | None = None,
) -> str:
    """ABAQUS ``*FRICTION, EXPONENTIAL DECAY`` (μ_s, μ_k, d_c) for one condition, the
    query result ``res`` (one pair at one contact pressure [kPa] and temperature [°C]).

    Needs μ_S in the map (raises :class:`ExportError` otherwise). ``decay_s_per_mm``
    [s/mm] defaults to :func:`default_decay_s_per_mm` at the pair's ``slip_rate``; it is
    written, and said in the comments, in the unit system's 1/slip-rate unit (s/mm or s/m).
    """
    u = unit_system(units)
    if res.mu_s is None:
        raise ExportError(
            f"pin {res.pin!r} on disc {res.disc!r} has no mu_s in the "
            "map: EXPONENTIAL DECAY needs a static coefficient",
            hint="export the mu_k table instead (leave out --exponential-decay)",
        )
    d_c = check_decay(
        default_decay_s_per_mm(slip_rate.value_mm_s) if decay_s_per_mm is None
        else decay_s_per_mm
    )
    d_c_out = d_c * u.decay_per_s_per_mm
    how = ("default: 99 % of the decay reached at this pair's sliding speed"
           if decay_s_per_mm is None else "given")
    bodies = header_bodies(ABAQUS, "mu_s (static, breakaway) decaying to mu_k (kinetic)",
                           source, deck_safe)
    bodies += [CALCULIX_WARNING, *condition_lines(res, deck_safe), slip_rate.describe()]
    bodies += [
        f"model: mu = mu_k + (mu_s - mu_k) * exp(-d_c * slip rate), slip rate in "
        f"{u.speed_unit}",
        f"d_c = {num(d_c_out)} {u.decay_unit} ({how})",
    ]
    lines = comment_block("**", bodies)
    lines += [
        f"*SURFACE INTERACTION, NAME={abaqus_name(res.pin, res.disc)}",
        "*FRICTION, EXPONENTIAL DECAY",
        ", ".join([num(res.mu_s.value), num(res.mu_k.value), num(d_c_out)]),
    ]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------- Ansys


def ansys_safe(value: object) -> str:
    """ASCII inert text for an MAPDL ``!`` comment (``$``, the command separator, escaped)."""
    return sim_comment(value, "!")


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
    """Ansys MAPDL ``TB,FRIC,mat,,,ISO`` tables with ``TBFIELD`` on temperature and pressure
    (one condition's constant μ_K is :func:`condition_snippet`, what the explorer copies).

    One material per selected pair, numbered from ``material_id``. Per the MAPDL
    reference the field name for contact (normal) pressure is ``NPRES``; fields are given
    in ascending order, temperature (rows) outer and pressure inner.
    """
    u = unit_system(units)
    if material_id < 1:
        raise ExportError(f"material number must be >= 1, got {material_id}")
    bodies = header_bodies(ANSYS, "mu_k, the kinetic (sliding) Coulomb coefficient (MU)",
                           source, ansys_safe)
    bodies.append(f"units {u.name}: NPRES in {u.pressure_unit}, TEMP in C")
    lines = comment_block("!", bodies)
    split = PairGroups(groups)  # each pair's groups selected once, κ computed once
    for offset, (pin_name, disc_name) in enumerate(selected_pairs(groups, pin, disc)):
        mat = material_id + offset
        table, by_speed = pair_table(split, pin_name, disc_name, temperature_C)
        lines += comment_block("!", [
            "",
            f"material {mat}: pin {ansys_safe(pin_name)} on disc {ansys_safe(disc_name)}",
            *filled_lines(table, u),
            *densify_lines(table, "Ansys"),
            *([] if by_speed is None else [
                speed_table_note(by_speed, u.speed_per_mm_s, u.speed_unit, "Ansys") +
                " (TBFIELD,SLRV: sliding velocity, innermost field)"]),
        ])
        lines.append(f"TB,FRIC,{mat},,,ISO")
        if by_speed is not None:
            lines += _ansys_speed_rows(by_speed, u.pressure_per_kPa, u.speed_per_mm_s)
            continue
        last_t: float | None = None
        for _, row in table.iterrows():
            t = row["temperature_C"]
            if not math.isnan(t) and t != last_t:
                lines.append(f"TBFIELD,TEMP,{num(t)}")
                last_t = t
            lines.append(f"TBFIELD,NPRES,{num(row['pressure_kPa'] * u.pressure_per_kPa)}")
            lines.append(f"TBDATA,1,{num(row['mu_k'])}")
    return "\n".join(lines) + "\n"


def _ansys_speed_rows(rows: pd.DataFrame, per_kPa: float, per_mm_s: float) -> list[str]:
    """TBFIELD/TBDATA lines of a table over temperature, pressure and sliding velocity
    (fields in ascending order, temperature outer, velocity inner)."""
    out = []
    last_t: float | None = None
    last_p: float | None = None
    for _, row in rows.iterrows():
        t, p = row["temperature_C"], row["pressure_kPa"]
        if not math.isnan(t) and t != last_t:
            out.append(f"TBFIELD,TEMP,{num(t)}")
            last_t, last_p = t, None
        if p != last_p:
            out.append(f"TBFIELD,NPRES,{num(p * per_kPa)}")
            last_p = p
        out.append(f"TBFIELD,SLRV,{num(row['speed_mm_s'] * per_mm_s)}")
        out.append(f"TBDATA,1,{num(row['mu_k'])}")
    return out


# ---------------------------------------------------------------------------- LS-DYNA


def field10(value: float | int) -> str:
    """``value`` right-aligned in one 10-character LS-DYNA field (standard format), with
    as many significant digits as leave a blank before it (at least 3)."""
    if isinstance(value, int):
        text = str(value)
    else:
        if not math.isfinite(value):
            raise ExportError(f"LS-DYNA field must be a finite number, got {value}")
        for digits in range(8, 2, -1):
            text = f"{value:.{digits}g}"
            if len(text) <= 9:
                break
        if "." not in text and "e" not in text:
            text += "."  # a real, not an integer
    if len(text) > 10:
        raise ExportError(f"{value} does not fit a 10-character LS-DYNA field")
    return text.rjust(10)


def write_lsdyna(
    res: QueryResult,
    *,
    units: str = "mm-N-s",
    coefficient: str = "mu_k",
    decay_s_per_mm: float | None = None,
    slip_rate: SlipRate = FOUNDING_SLIP_RATE,
    contact_id: int = 1,
    pin_part: int = 1,
    disc_part: int = 2,
    source: str | None = None,
    speed_curve: list[tuple[float, float]] | None = None,
) -> str:
    """LS-DYNA ``*CONTACT_AUTOMATIC_SURFACE_TO_SURFACE_ID`` with the pair's FS, FD, DC at
    the condition of the query result ``res``.

    Where the pair is measured at three or more sliding speeds (``speed_curve``: μ_K at
    each, [mm/s]) and ``coefficient="mu_k"``, FS, FD and DC are fitted to μ_K(v)
    (:func:`tribopipe.fit.fit_decay`) and the header gives the fit's
    residuals; otherwise as follows, and the header says no speed dependence was
    measured.

    LS-DYNA's friction is μ_c = FD + (FS − FD)·exp(−DC·|v_rel|), with DC in 1/velocity.
    ``coefficient="mu_k"`` (default) writes FS = FD = μ_K and DC = 0 (kinetic Coulomb
    friction, no breakaway peak); ``"mu_s"`` writes FS = μ_S, FD = μ_K and DC from
    ``decay_s_per_mm`` [s/mm] (default :func:`default_decay_s_per_mm` at the pair's
    ``slip_rate``), in the unit system's s/mm or s/m. SURFA and SURFB are the part IDs
    ``pin_part`` and ``disc_part`` (SURFATYP = SURFBTYP = 3). Standard format: every
    field 10 characters wide, blank fields take LS-DYNA's defaults.
    """
    u = unit_system(units)
    for what, value in (("contact id", contact_id), ("pin part", pin_part),
                        ("disc part", disc_part)):
        if not 1 <= value < 10**10:
            raise ExportError(f"LS-DYNA {what} must be an integer from 1 to 9999999999, "
                              f"got {value}")
    fs = breakaway(res, coefficient, "LS-DYNA FS")
    fd = res.mu_k.value
    fit: DecayFit | None = fit_decay(speed_curve or [])
    if coefficient == "mu_k" and fit is not None:
        if decay_s_per_mm is not None:
            raise ExportError("DC is fitted from the measured speeds of this pair",
                              hint="leave out --decay")
        fs, fd, dc = fit.fs, fit.fd, fit.dc_s_per_mm * u.decay_per_s_per_mm
        listed = ", ".join(f"{num(v)} mm/s: {num(m)}" for v, m in speed_curve or [])
        holds = ("FS, FD, DC fitted to mu_k over the measured sliding speeds (kinetic "
                 "friction as a function of slip speed)")
        model = [f"mu_k at the measured speeds: {listed}",
                 f"fit: FS = {num(fit.fs)}, FD = {num(fit.fd)}, DC = {num(dc)} {u.decay_unit}; "
                 f"residuals rms {fit.rms:.2g}, max {fit.max_abs:.2g} in mu over {fit.n} "
                 "speeds" + ("; mu rises with speed (FS < FD)" if fit.rising else "")]
    elif coefficient == "mu_k":
        if decay_s_per_mm is not None:
            raise ExportError("a decay coefficient needs FS = mu_s",
                              hint="add --coefficient mu_s, or leave out --decay")
        dc = 0.0
        holds = "FS = FD = mu_k (kinetic Coulomb friction, no breakaway peak), DC = 0"
        model = ["--coefficient mu_s writes FS = mu_s (breakaway) with a decay to FD = mu_k"]
    else:
        d_c = check_decay(
            default_decay_s_per_mm(slip_rate.value_mm_s) if decay_s_per_mm is None
            else decay_s_per_mm
        )
        dc = d_c * u.decay_per_s_per_mm
        measured = ("the speed dependence measured for this pair is written by "
                    "--coefficient mu_k" if fit is not None else
                    "fewer than 3 speeds measured: no speed dependence to fit"
                    if speed_curve else "no speed dependence measured")
        how = (f"default: 99 % of the decay reached at this pair's sliding speed; {measured}"
               if decay_s_per_mm is None else "given")
        holds = "FS = mu_s (static, breakaway), FD = mu_k (kinetic), DC = decay coefficient"
        model = [slip_rate.describe(),
                 f"DC = {num(dc)} {u.decay_unit} ({how}); for a model in ms, DC in ms/mm is "
                 "this s/mm value x 1000"]
    heading = deck_names([(res.pin, res.disc)], limit=70)[(res.pin, res.disc)]
    bodies = header_bodies(LSDYNA, holds, source, deck_safe)
    bodies += condition_lines(res, deck_safe)
    bodies += [
        "model: mu_c = FD + (FS - FD) * exp(-DC * |v_rel|), DC in 1/velocity "
        f"({u.decay_unit} with units {u.name})",
        *model,
        f"SURFA = part {pin_part} (pin), SURFB = part {disc_part} (disc), both by part ID "
        "(type 3): set them to your model's parts",
    ]
    lines = comment_block("$", bodies, width=80)
    lines += [
        "*KEYWORD",
        "*CONTACT_AUTOMATIC_SURFACE_TO_SURFACE_ID",
        "$#     cid   heading",
        field10(contact_id) + heading,
        "$#   surfa     surfb  surfatyp  surfbtyp",
        field10(pin_part) + field10(disc_part) + field10(3) + field10(3),
        "$#      fs        fd        dc",
        field10(fs) + field10(fd) + field10(dc),
        "$#    sfsa      sfsb      sast      sbst     sfsat     sfsbt       fsf       vsf",
        "",
        "*END",
    ]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------- one condition

#: formats of :func:`condition_snippet`: a constant μ_K at one condition
CONDITION_FORMATS = ("abaqus", "ansys")

#: the Ansys single-condition file's last comment line, naming the pair's material
MATERIAL_LINE = "material {number}: pin {pin} on disc {disc}"
#: said in every single-condition file, after the condition
CONSTANT_NOTE = (
    "a constant coefficient: the solver uses it at every pressure and temperature; for the "
    "dependence export the pair's table (tribopipe export {fmt} --pin PIN --disc DISC)"
)


def condition_header(fmt: str, source: str | None = None) -> list[str]:
    """The comment lines that open :func:`condition_snippet` for ``fmt`` (``abaqus`` or
    ``ansys``): engine, version checked, coefficient held, combination, provenance.
    They do not depend on the condition (the explorer page embeds them as they are)."""
    if fmt == "abaqus":
        bodies = header_bodies(
            ABAQUS, "mu_k, the kinetic (sliding) Coulomb coefficient, held constant at one "
            "condition", source, deck_safe)
        return comment_block("**", [*bodies, CALCULIX_WARNING])
    if fmt == "ansys":
        return comment_block("!", header_bodies(
            ANSYS, "mu_k, the kinetic (sliding) Coulomb coefficient (MU), held constant at "
            "one condition", source, ansys_safe))
    raise ExportError(
        f"unknown single-condition format {fmt!r}; expected one of {', '.join(CONDITION_FORMATS)}"
    )


def condition_snippet(
    res: QueryResult, fmt: str, *, source: str | None = None, material_id: int = 1
) -> str:
    """ABAQUS or Ansys input holding the constant μ_K of one query result ``res`` (one pair
    at one contact pressure [kPa] and temperature [°C]): what the explorer page copies.

    ``abaqus``: ``*SURFACE INTERACTION`` + ``*FRICTION`` with one coefficient; ``ansys``:
    ``TB,FRIC,mat,,,ISO`` + ``TBDATA,1,mu``. The comments are :func:`condition_header`
    and the single-condition writers' :func:`~tribopipe.export.headers.condition_lines`
    (pair, condition, μ_K ± CI, μ_S, the measured groups used with their weights,
    clamping). A constant carries no pressure or temperature dependence, so no unit
    system enters.
    """
    lines = condition_header(fmt, source)
    note = CONSTANT_NOTE.format(fmt=fmt)
    mu = num(res.mu_k.value)
    if fmt == "abaqus":
        lines += comment_block("**", [*condition_lines(res, deck_safe), note])
        lines += [f"*SURFACE INTERACTION, NAME={abaqus_name(res.pin, res.disc)}", "*FRICTION", mu]
    else:
        if material_id < 1:
            raise ExportError(f"material number must be >= 1, got {material_id}")
        lines += comment_block("!", [
            *condition_lines(res, ansys_safe), note,
            MATERIAL_LINE.format(number=material_id, pin=ansys_safe(res.pin),
                                 disc=ansys_safe(res.disc)),
        ])
        lines += [f"TB,FRIC,{material_id},,,ISO", f"TBDATA,1,{mu}"]
    return "\n".join(lines) + "\n"


def abaqus_snippet(res: QueryResult, *, source: str | None = None) -> str:
    """:func:`condition_snippet` in ABAQUS: the explorer's copy for one condition."""
    return condition_snippet(res, "abaqus", source=source)


def ansys_snippet(res: QueryResult, *, source: str | None = None, material_id: int = 1) -> str:
    """:func:`condition_snippet` in Ansys MAPDL (material number ``material_id``)."""
    return condition_snippet(res, "ansys", source=source, material_id=material_id)


def abaqus_snippet_header(*, source: str | None = None) -> list[str]:
    """:func:`condition_header` of :func:`abaqus_snippet`."""
    return condition_header("abaqus", source)


def ansys_snippet_header(*, source: str | None = None) -> list[str]:
    """:func:`condition_header` of :func:`ansys_snippet`."""
    return condition_header("ansys", source)

"""Simulator input from the friction map: ABAQUS, Ansys, LS-DYNA, MuJoCo, SOFA, PyElastica.

:func:`export_from_map` reads a map and writes one format; :func:`export_simulator_input`
does the same from a group-statistics table (see :mod:`tribopipe.query`). Nothing here
touches the file system beyond reading the map. Values are the group means of μ_K (and
μ_S where measured); table cells that were not measured are filled by
:func:`tribopipe.query.query`'s interpolation and say so in a comment.

========== ==================== ============================================= ==========
format     engine (checked)     holds                                         condition
========== ==================== ============================================= ==========
abaqus     Abaqus Keywords Ref. μ_K table (μ, slip rate, p, T); or μ_S→μ_K     all / one
                                exponential decay (``exponential_decay``)
ansys      MAPDL 2025 R1        μ_K table (TB,FRIC + TBFIELD NPRES, TEMP)     all
lsdyna     LS-DYNA R14 manual   FS = FD = μ_K; or FS = μ_S, FD = μ_K, DC      one
mujoco     mujoco 4.0.0         μ_K or μ_S (``coefficient``)                  one
sofa       SOFA v24.12–v25.x    μ_K or μ_S (``coefficient``)                  one
pyelastica pyelastica 1.0.0     static μ_K or μ_S, kinetic μ_K                one
========== ==================== ============================================= ==========

The writers live in :mod:`tribopipe.export.fe_decks` and :mod:`tribopipe.export.scenes`;
units, slip rates and the text safety they share in :mod:`tribopipe.export.simbase`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import ExportError
from ..frictionmap import read_map
from ..query import groups_of, pairs, select_pair
from .fe_decks import abaqus_name, write_abaqus, write_abaqus_decay, write_ansys, write_lsdyna
from .scenes import write_mujoco, write_pyelastica, write_sofa
from .simbase import (
    COEFFICIENTS,
    FOUNDING_SLIP_RATE_MM_S,
    UNIT_SYSTEMS,
    SlipRate,
    check_coefficient,
    convert_pressure_kPa,
    default_decay_s_per_mm,
    pair_slip_rates,
    slip_rate_of,
    unit_system,
)

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "COEFFICIENTS", "FORMATS", "FOUNDING_SLIP_RATE_MM_S", "UNIT_SYSTEMS", "SlipRate",
    "abaqus_name", "convert_pressure_kPa", "default_decay_s_per_mm", "export_from_map",
    "export_simulator_input", "pair_slip_rates", "unit_system", "write_abaqus",
    "write_abaqus_decay", "write_ansys", "write_lsdyna", "write_mujoco", "write_pyelastica",
    "write_sofa",
]

FORMATS = ("abaqus", "ansys", "lsdyna", "mujoco", "sofa", "pyelastica")

#: single-condition writers that take ``coefficient`` (need pin, disc and a pressure)
SINGLE_VALUE_WRITERS: dict[str, Callable[..., str]] = {
    "mujoco": write_mujoco,
    "sofa": write_sofa,
    "pyelastica": write_pyelastica,
}


def _refuse_unused(fmt: str, exponential_decay: bool, options: Mapping[str, Any]) -> None:
    """An :class:`ExportError` for an option that ``fmt`` would silently ignore."""
    decay_fmt = (fmt == "abaqus" and exponential_decay) or fmt == "lsdyna"
    if options.get("decay_s_per_mm") is not None and not decay_fmt:
        raise ExportError(
            "a decay coefficient only applies to abaqus --exponential-decay and lsdyna"
        )
    if options.get("coefficient", "mu_k") != "mu_k" and fmt not in (*SINGLE_VALUE_WRITERS,
                                                                     "lsdyna"):
        raise ExportError(
            f"--coefficient is for mujoco, sofa, pyelastica and lsdyna; {fmt} "
            + ("--exponential-decay holds mu_s and mu_k already" if fmt == "abaqus"
               else "writes a mu_k table"),
        )


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
    coefficient: str = "mu_k",
    material_id: int = 1,
    geom1: str = "pin",
    geom2: str = "disc",
    contact_id: int = 1,
    pin_part: int = 1,
    disc_part: int = 2,
    slip_rates: Mapping[tuple[str, str], SlipRate] | None = None,
    source: str | None = None,
) -> str:
    """The input text for simulator ``fmt`` (one of :data:`FORMATS`).

    Tables (``abaqus``, ``ansys``) take any selection of pairs, or with ``pressure_kPa``
    one pair's constant μ_K at one condition (as the explorer copies it); single-condition formats
    (``lsdyna``, ``mujoco``, ``sofa``, ``pyelastica``) and ABAQUS's exponential decay need
    ``pin``, ``disc`` and ``pressure_kPa`` [kPa] (a missing one is an :class:`ExportError`
    that lists what the map holds). ``coefficient`` (``"mu_k"`` or ``"mu_s"``) is the
    coefficient a single-condition engine gets for the onset of slip. ``slip_rates``
    holds each pair's measured sliding speed (:func:`pair_slip_rates`); pairs without one
    get the founding paper's 0.007 mm/s.
    """
    if fmt not in FORMATS:
        raise ExportError(f"unknown simulator {fmt!r}; expected one of {', '.join(FORMATS)}")
    unit_system(units)
    check_coefficient(coefficient)
    _refuse_unused(fmt, exponential_decay,
                   {"decay_s_per_mm": decay_s_per_mm, "coefficient": coefficient})
    # abaqus and ansys: the pair's table, or with a pressure one condition's constant
    if fmt == "abaqus" and not exponential_decay:
        return write_abaqus(groups, pin=pin, disc=disc, temperature_C=temperature_C,
                            units=units, slip_rates=slip_rates, source=source,
                            pressure_kPa=pressure_kPa)
    if fmt == "ansys":
        return write_ansys(groups, pin=pin, disc=disc, temperature_C=temperature_C,
                           units=units, material_id=material_id, source=source,
                           pressure_kPa=pressure_kPa)
    what = "ABAQUS EXPONENTIAL DECAY" if fmt == "abaqus" else fmt
    if pin is None or disc is None:
        listing = "; ".join(f"{p} on {d}" for p, d in pairs(groups)) or "nothing"
        raise ExportError(
            f"{what} takes one condition: give the pin and the disc; the map holds: {listing}",
            hint="pass --pin and --disc",
        )
    pair = select_pair(groups, pin, disc)
    if pressure_kPa is None:
        measured = ", ".join(f"{p:g}" for p in sorted(set(pair["pressure_kPa"])))
        raise ExportError(
            f"{what} takes one condition: give the contact pressure; "
            f"{pin} on {disc} is measured at {measured} kPa",
            hint="pass --pressure KPA",
        )
    first = pair.iloc[0]
    rate = slip_rate_of(slip_rates, str(first["pin"]), str(first["disc"]))
    condition = {"pin": pin, "disc": disc, "pressure_kPa": pressure_kPa,
                 "temperature_C": temperature_C, "source": source}
    if fmt == "abaqus":
        return write_abaqus_decay(groups, units=units, decay_s_per_mm=decay_s_per_mm,
                                  slip_rate=rate, **condition)
    if fmt == "lsdyna":
        return write_lsdyna(groups, units=units, coefficient=coefficient,
                            decay_s_per_mm=decay_s_per_mm, slip_rate=rate,
                            contact_id=contact_id, pin_part=pin_part, disc_part=disc_part,
                            **condition)
    extra = {"geom1": geom1, "geom2": geom2} if fmt == "mujoco" else {}
    return SINGLE_VALUE_WRITERS[fmt](groups, coefficient=coefficient, **condition, **extra)


def export_from_map(map_path: str | Path, fmt: str, **options: Any) -> str:
    """:func:`export_simulator_input` on the friction map (Parquet) at ``map_path``; every
    pair's slip rate is the median sliding speed of its own runs."""
    runs = read_map(map_path)
    groups = groups_of(runs, map_path)
    return export_simulator_input(groups, fmt, source=str(map_path),
                                  slip_rates=pair_slip_rates(runs), **options)

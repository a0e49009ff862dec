"""Simulator input from the friction map: the one place that queries the map for a
format of :data:`tribopipe.export.registry.WRITERS`.

:func:`export_simulator_input` checks the options against what the format declares, runs
:func:`tribopipe.query.query` once for a single-condition format and hands the writer the
result (table formats get the group table); :func:`export_from_map` does the same on a map
file. :func:`snippet` is what the explorer page copies for one condition. Nothing here
touches the file system beyond reading the map.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from ..errors import ExportError
from ..escape import markdown_cell
from ..frictionmap.snapshot import MapSource, as_snapshot
from ..query import QueryResult, load_groups, pairs, query, select_pair
from .registry import (
    FORMATS,
    WRITERS,
    Option,
    Writer,
    condition_labels,
    function,
    load,
    option_named,
    users,
    writer_named,
)
from .simbase import Engine, SlipRate, pair_slip_rates, slip_rate_of, speed_curve

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["FORMATS", "export_from_map", "export_simulator_input", "formats_table", "snippet"]


def _mode_options(
    writer: Writer, condition: bool, options: Mapping[str, Any]
) -> dict[str, Any]:
    """The options the chosen writer takes, checked; an :class:`ExportError` for one given
    that it would silently ignore."""
    declared: tuple[Option, ...] = (writer.condition_options if condition
                                    else writer.table_options)
    names = {o.name for o in declared}
    for name, value in options.items():
        option = option_named(name)
        if name in names or value is None or value == option.default:
            continue
        raise ExportError(f"{option.flag} is for {', '.join(users(name))}; "
                          f"not for {writer.label(condition)}")
    chosen = {}
    for option in declared:
        value = options.get(option.name)
        value = option.default if value is None else value
        if option.check is not None and value is not None:
            load(option.check)(value)
        chosen[option.name] = value
    return chosen


def export_simulator_input(
    groups: pd.DataFrame,
    fmt: str,
    *,
    pin: str | None = None,
    disc: str | None = None,
    pressure_kPa: float | None = None,
    temperature_C: float | None = None,
    slip_rates: Mapping[tuple[str, str], SlipRate] | None = None,
    source: str | None = None,
    speed_mm_s: float | None = None,
    **options: Any,
) -> str:
    """The input text for simulator ``fmt`` (one of :data:`FORMATS`).

    Table formats take any selection of pairs (``pin``/``disc`` ``None`` = all) and every
    measured pressure; single-condition formats need ``pin``, ``disc`` and
    ``pressure_kPa`` [kPa] (a missing one is an :class:`ExportError` that lists what the
    map holds), at ``temperature_C`` [°C]. ``options`` are the format's own (its
    :class:`~tribopipe.export.registry.Writer` declares them, e.g. ``coefficient``,
    ``units``); one it does not take is refused. ``slip_rates`` holds each pair's
    measured sliding speed (:func:`~tribopipe.export.simbase.pair_slip_rates`); pairs
    without one get the founding paper's 0.007 mm/s. ``source`` (the map's path) is named
    in the file's header. ``speed_mm_s`` [mm/s] is the sliding speed of a single
    condition (needed where the pair is measured at several; tables carry every speed).
    """
    writer = writer_named(fmt)
    switch = writer.switch
    switched = bool(switch is not None and options.pop(switch.name, False))
    # a table format given one pressure writes that condition's constant, as the
    # explorer copies it (its snippet writer), where the format has one
    constant = (writer.table is not None and not switched and pressure_kPa is not None
                and writer.snippet is not None)
    condition = writer.table is None or switched or constant
    chosen = _mode_options(writer, condition and not constant, options)
    if not condition:
        if pressure_kPa is not None:
            raise ExportError(
                f"the {fmt} table covers every measured pressure; a single pressure is for "
                f"{', '.join(condition_labels())}",
                hint="leave out --pressure",
            )
        if speed_mm_s is not None:
            raise ExportError(f"the {fmt} table carries every measured speed; a single speed "
                              "is for one condition", hint="leave out --speed, or add --pressure")
        if writer.slip_rate:
            chosen["slip_rates"] = slip_rates
        return function(writer.table)(groups, pin=pin, disc=disc,
                                      temperature_C=temperature_C, source=source, **chosen)
    what = f"{fmt} --pressure" if constant else writer.label(True)
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
    res = query(groups, pin, disc, pressure_kPa, temperature_C, speed_mm_s)
    if constant:
        write = function(writer.snippet)
        takes = inspect.signature(write).parameters
        # a constant has no pressure or temperature dependence: no unit system enters
        kept = {k: v for k, v in chosen.items() if k in takes}
        return str(write(res, source=source, **dict(writer.snippet_options), **kept))
    if writer.slip_rate:
        first = pair.iloc[0]
        chosen["slip_rate"] = slip_rate_of(slip_rates, str(first["pin"]), str(first["disc"]))
    if writer.speed_curve:
        chosen["speed_curve"] = speed_curve(groups, pin, disc, pressure_kPa, temperature_C)
    return function(writer.condition)(res, source=source, **chosen)


def export_from_map(map_path: MapSource, fmt: str, **options: Any) -> str:
    """:func:`export_simulator_input` on the friction map (Parquet) at ``map_path``; every
    pair's slip rate is the median sliding speed of its own runs."""
    writer_named(fmt)  # an unknown format is refused before the map is read
    snap = as_snapshot(map_path)
    groups = load_groups(snap)
    return export_simulator_input(groups, fmt, source=str(snap.path),
                                  slip_rates=pair_slip_rates(snap.runs), **options)


def snippet(fmt: str, res: QueryResult, source: str | None = None) -> str:
    """The text the explorer page copies for format ``fmt`` at one query result ``res``
    (an :class:`ExportError` for a format the page does not offer)."""
    writer = writer_named(fmt)
    return function(writer.snippet)(res, source=source, **dict(writer.snippet_options))


def snippet_header(fmt: str, source: str | None = None) -> list[str]:
    """The lines of :func:`snippet` that do not depend on the condition."""
    writer = writer_named(fmt)
    return list(function(writer.snippet_header)(source=source, **dict(writer.snippet_options)))


def formats_table() -> str:
    """The formats as a Markdown table (``docs/simulators.md`` holds it; a test keeps it
    current): format, engine, what the file holds, one condition or a table, how the
    engine combines two bodies' values and what the file was checked against."""
    rows = ["| format | engine | holds | takes | two bodies | checked against |",
            "|---|---|---|---|---|---|"]
    for w in WRITERS:
        engine: Engine = load(w.engine)
        kind = " or ".join(k for k, f in (("a table", w.table), ("one condition", w.condition))
                           if f)
        # the engines' texts are plain: a keyword's "*" must not start an emphasis
        cells = [markdown_cell(engine.combination), markdown_cell(engine.checked)]
        rows.append(f"| `{w.name}` | {engine.name} | {w.holds} | {kind} | "
                    f"{cells[0]} | {cells[1]} |")
    return "\n".join(rows) + "\n"

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
import math
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from ..errors import ExportError
from ..escape import markdown_cell
from ..frictionmap.snapshot import MapSource, as_snapshot
from ..query import QueryResult, load_groups, one_method, pair_speeds, query, select_pair
from ..stats import GROUP_INPUT_COLUMNS
from .formats import FORMATS, Option, condition_labels, option_named, users
from .registry import WRITERS, Writer, writer_named
from .slip_rates import SlipRate, pair_slip_rates, slip_rate_of
from .speed_tables import speed_curve

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["FORMATS", "export_from_map", "export_simulator_input", "formats_table", "snippet"]


def _mode_options(
    writer: Writer, condition: bool, options: Mapping[str, Any]
) -> dict[str, Any]:
    """The options the chosen writer takes, checked; an :class:`ExportError` for one given
    that it would silently ignore."""
    declared: tuple[Option, ...] = (writer.format.condition_options if condition
                                    else writer.format.table_options)
    names = {o.name for o in declared}
    for name, value in options.items():
        option = option_named(name)
        if name in names or value is None or value == option.default:
            continue
        raise ExportError(f"{option.flag} is for {', '.join(users(name))}; "
                          f"not for {writer.format.label(condition)}")
    chosen = {}
    for option in declared:
        value = options.get(option.name)
        value = option.default if value is None else value
        if option.check is not None and value is not None:
            option.check(value)
        chosen[option.name] = value
    return chosen


def _narrowed(groups: pd.DataFrame, column: str, value: str | None) -> pd.DataFrame:
    """The groups whose ``column`` is ``value`` (case-insensitive); all of them when
    ``value`` is not given or matches none (the pair's own check names it then)."""
    if value is None:
        return groups
    sel = groups[groups[column].astype(str).str.strip().str.casefold()
                 == value.strip().casefold()]
    return groups if sel.empty else sel


def _numbers(values: Any) -> list[float]:
    """The distinct finite numbers of a column, sorted."""
    return sorted({float(v) for v in values if v is not None and math.isfinite(float(v))})


def one_condition(
    groups: pd.DataFrame,
    what: str,
    pin: str | None,
    disc: str | None,
    pressure_kPa: float | None,
    temperature_C: float | None,
    speed_mm_s: float | None,
    on_note: Callable[[str], None] | None = None,
) -> tuple[str, str, float, float | None, float | None]:
    """The condition a single-condition output is written for: ``(pin, disc, pressure
    [kPa], temperature [°C], speed [mm/s])``. A choice not given where the map holds
    one value (among the groups the given choices leave) takes that value, said through
    ``on_note``; every choice still missing is named in ONE :class:`ExportError` with the
    values the map holds for it, so that one more command is enough."""
    missing: list[str] = []
    for column, given in (("pin", pin), ("disc", disc)):
        names = sorted({str(v) for v in groups[column]}) if not groups.empty else []
        if given is not None and given.strip().casefold() not in {n.casefold() for n in names}:
            missing.append(f"--{column} that the map holds ({', '.join(names)}; "
                           f"{given!r} is not one)")
    held = _narrowed(_narrowed(groups, "pin", pin), "disc", disc)

    def choose(flag: str, given: Any, values: list[Any], shown: list[str], unit: str) -> Any:
        if given is not None or not values:
            return given
        if len(values) == 1:
            if on_note is not None:
                on_note(f"{flag} {shown[0]}{unit}: the only value the map holds here; taken")
            return values[0]
        missing.append(f"{flag} ({', '.join(shown)}{unit})")
        return None

    pins = sorted({str(v) for v in held["pin"]})
    pin = choose("--pin", pin, pins, pins, "")
    discs = sorted({str(v) for v in _narrowed(held, "pin", pin)["disc"]})
    disc = choose("--disc", disc, discs, discs, "")
    held = _narrowed(_narrowed(held, "pin", pin), "disc", disc)
    pressures = _numbers(held["pressure_kPa"])
    pressure_kPa = choose("--pressure", pressure_kPa, pressures,
                          [f"{p:.4g}" for p in pressures], " kPa")
    temps = _numbers(held["temperature_C"]) if "temperature_C" in held.columns else []
    temperature_C = choose("--temperature", temperature_C, temps,
                           [f"{t:g}" for t in temps], " °C")
    speeds = pair_speeds(held) if not held.empty else []
    if speed_mm_s is None and len(speeds) > 1:
        missing.append(f"--speed ({', '.join(f'{v:g}' for v in speeds)} mm/s)")
    if missing or pin is None or disc is None or pressure_kPa is None:
        if held.empty:
            raise ExportError(f"{what} takes one condition, and the friction map is empty",
                              hint="reduce runs first (tribopipe batch)")
        raise ExportError(
            f"{what} takes one condition; give " + "; ".join(missing)
            + (" (the values the map holds; a pressure or temperature between them is "
               "interpolated)"))
    return pin, disc, float(pressure_kPa), temperature_C, speed_mm_s


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
    on_note: Callable[[str], None] | None = None,
    method: str | None = None,
    **options: Any,
) -> str:
    """The input text for simulator ``fmt`` (one of :data:`FORMATS`).

    Table formats take any selection of pairs (``pin``/``disc`` ``None`` = all) and every
    measured pressure; single-condition formats need ``pin``, ``disc`` and
    ``pressure_kPa`` [kPa], at ``temperature_C`` [°C]: :func:`one_condition` takes a
    choice the map holds one value for (said through ``on_note``) and names every one
    still missing in one :class:`ExportError`. ``options`` are the format's own (its
    :class:`~tribopipe.export.formats.Format` declares them, e.g. ``coefficient``,
    ``units``); one it does not take is refused. ``slip_rates`` holds each pair's
    measured sliding speed (:func:`~tribopipe.export.slip_rates.pair_slip_rates`); pairs
    without one get the founding paper's 0.007 mm/s. ``source`` (the map's path) is named
    in the file's header. ``speed_mm_s`` [mm/s] is the sliding speed of a single
    condition (needed where the pair is measured at several; tables carry every speed).
    ``method`` is the test method a single condition is read from
    (:func:`tribopipe.query.one_method`: needed where the pair is measured by several).
    """
    writer = writer_named(fmt)
    spec = writer.format
    switch = spec.switch
    switched = bool(switch is not None and options.pop(switch.name, False))
    # a table format given one pressure writes that condition's constant, as the
    # explorer copies it (its snippet writer), where the format has one
    constant = (writer.table is not None and not switched and pressure_kPa is not None
                and writer.snippet is not None)
    condition = writer.table is None or switched or constant
    chosen = _mode_options(writer, condition and not constant, options)
    if writer.table is not None and not condition:
        if pressure_kPa is not None:
            raise ExportError(
                f"the {fmt} table covers every measured pressure; a single pressure is for "
                f"{', '.join(condition_labels())}",
                hint="leave out --pressure",
            )
        if speed_mm_s is not None:
            raise ExportError(f"the {fmt} table carries every measured speed; a single speed "
                              "is for one condition", hint="leave out --speed, or add --pressure")
        if method is not None:
            raise ExportError(f"the {fmt} table carries every group with its own method; "
                              "a single method is for one condition",
                              hint="leave out --method, or add --pressure")
        if spec.slip_rate:
            chosen["slip_rates"] = slip_rates
        return writer.table(groups, pin=pin, disc=disc, temperature_C=temperature_C,
                            source=source, **chosen)
    what = f"{fmt} --pressure" if constant else spec.label(True)
    pin, disc, pressure_kPa, temperature_C, speed_mm_s = one_condition(
        groups, what, pin, disc, pressure_kPa, temperature_C, speed_mm_s, on_note)
    groups, method = one_method(groups, pin, disc, method)
    pair = select_pair(groups, pin, disc)
    res = query(groups, pin, disc, pressure_kPa, temperature_C, speed_mm_s, method)
    if constant and writer.snippet is not None:
        takes = inspect.signature(writer.snippet).parameters
        # a constant has no pressure or temperature dependence: no unit system enters
        kept = {k: v for k, v in chosen.items() if k in takes}
        return writer.snippet(res, source=source, **kept)
    if writer.condition is None:
        raise ExportError(f"{fmt} has no single-condition writer")
    if spec.slip_rate:
        first = pair.iloc[0]
        chosen["slip_rate"] = slip_rate_of(slip_rates, str(first["pin"]), str(first["disc"]))
    if spec.speed_curve:
        chosen["speed_curve"] = speed_curve(groups, pin, disc, pressure_kPa, temperature_C)
    return writer.condition(res, source=source, **chosen)


#: the map columns :func:`export_from_map` reads: those of the statistics (where the map
#: stores no groups) and the measured speed of the slip rates
MAP_COLUMNS: tuple[str, ...] = (*GROUP_INPUT_COLUMNS, "sliding_speed_mm_s")


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
    write = writer_named(fmt).snippet
    if write is None:
        raise ExportError(f"the explorer page offers no {fmt} text")
    return write(res, source=source)


def snippet_header(fmt: str, source: str | None = None) -> list[str]:
    """The lines of :func:`snippet` that do not depend on the condition."""
    header = writer_named(fmt).snippet_header
    if header is None:
        raise ExportError(f"the explorer page offers no {fmt} text")
    return list(header(source=source))


def formats_table() -> str:
    """The formats as a Markdown table (``docs/simulators.md`` holds it; a test keeps it
    current): format, engine, what the file holds, one condition or a table, how the
    engine combines two bodies' values and what the file was checked against."""
    rows = ["| format | engine | holds | takes | two bodies | checked against |",
            "|---|---|---|---|---|---|"]
    for w in WRITERS:
        engine = w.engine
        kind = " or ".join(k for k, f in (("a table", w.table), ("one condition", w.condition))
                           if f is not None)
        # the engines' texts are plain: a keyword's "*" must not start an emphasis
        cells = [markdown_cell(engine.combination), markdown_cell(engine.checked)]
        rows.append(f"| `{w.name}` | {engine.name} | {w.format.holds} | {kind} | "
                    f"{cells[0]} | {cells[1]} |")
    return "\n".join(rows) + "\n"

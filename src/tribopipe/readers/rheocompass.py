"""Anton Paar RheoCompass table exports (text and Excel).

Layout (labels translated in French/German exports)::

    Project:<S>name
    Test:<S>name
    Result:<S>name
    Interval and data points:<S>i<S>n
    Interval data:<S>Point No.<S>Time<S>Torque ...
    <S><S><S>...                 meaning row (often empty)
    <S><S>[s]<S>[mN·m] ...       unit row
    <S>1<S>0.1<S>2.3981 ...      data rows: first cell empty

Several tests, results and intervals per file; every interval repeats its own header, and
columns and units may change between intervals. A labelled line of Anton Paar's
measurement fields (``Device:``, ``Application:``, ``Measuring Date/Time:`` ...: the
labels of :data:`~tribopipe.readers.interval.HEADER_FIELDS`) is kept in the metadata of
the intervals it heads (above the first ``Test:``: every test's; below a ``Test:``: that
test's), where the reporting items are read from it. The table export as the six real
exports show it holds none: only ``Project:``, ``Test:`` and ``Result:``, whose texts
are kept as they are (the project's is not taken apart: its parts are documented
nowhere). Point numbers like ``1  (invalid)`` mark
invalid points; rows with an empty point number are raw-waveform sub-rows. Both are
counted in the metadata, not returned as data.
"""

from __future__ import annotations

from dataclasses import replace

from ..errors import ReadError
from .aliases import builtin_aliases, name_key
from .interval import HEADER_FIELDS, UNIT_CELL, RawInterval, label_value
from .spec import Reader
from .textio import DataLine, Row, Run, peel

FORMAT = "rheocompass"
FORMAT_XLSX = "rheocompass-xlsx"

PROJECT = frozenset({"project", "projet", "projekt", "proyecto", "progetto"})
TEST = frozenset({"test", "essai", "versuch"})
RESULT = frozenset({"result", "resultat", "ergebnis", "resultado", "risultato"})
INTERVAL_POINTS = frozenset(
    {
        "intervalanddatapoints",
        "intervalleetpointsdedonnees",
        "intervallunddatenpunkte",
        "intervallundmesspunkte",
    }
)
INTERVAL_DATA = frozenset(
    {"intervaldata", "intervaldonnees", "intervalledonnees", "intervalldaten"}
)
LABELS = PROJECT | TEST | RESULT | INTERVAL_POINTS | INTERVAL_DATA


def data_line(delimiter: str) -> DataLine:
    """How a data line starts: an empty first cell, then the point number (any other
    line is read as a row, and decided there)."""
    return DataLine(delimiter, "0123456789")


def looks_like(rows: list[Row]) -> bool:
    """True when the first rows carry RheoCompass labels (``Project:``, ``Interval data:``…)."""
    for _, cells in rows[:60]:
        if cells and cells[0].endswith(":") and name_key(cells[0]) in LABELS:
            return True
    return False


def _int(cell: str, what: str, path: str, line: int) -> int:
    try:
        return int(cell.replace(",", "").replace(".", "").strip())
    except ValueError:
        raise ReadError(f"expected {what} as a whole number, got {cell[:30]!r}", path=path,
                        line=line) from None


def _is_blank(cells: list[str]) -> bool:
    return not any(cells)


def parse_intervals(rows: list[Row | Run], path: str) -> list[RawInterval]:
    """Find every interval of a RheoCompass export (rows of stripped cells with their line
    numbers, and runs of data lines, see ``textio.scan_lines``) and return its header and
    rows, in file order."""
    project = test = result = None
    shared: dict[str, str] = {}  # the measurement fields above the first test
    fields: dict[str, str] = {}  # those of the current test
    interval: int | None = None
    declared: int | None = None
    out: list[RawInterval] = []
    n = len(rows)
    i = 0
    while i < n:
        item = rows[i]
        if isinstance(item, Run):
            raise ReadError(
                "data row outside an interval (no 'Interval data:' header above it)",
                path=path,
                line=item.first_line,
            )
        line, cells = item
        first = cells[0] if cells else ""
        if not first:
            if not _is_blank(cells):
                raise ReadError(
                    "data row outside an interval (no 'Interval data:' header above it)",
                    path=path,
                    line=line,
                )
            i += 1
            continue
        key = name_key(first)
        if key in PROJECT:
            project = label_value(cells)
        elif key in TEST:
            test, result, interval, declared = label_value(cells), None, None, None
            fields = dict(shared)
        elif key in RESULT:
            result, interval, declared = label_value(cells), None, None
        elif key in INTERVAL_POINTS:
            if len(cells) < 3 or not cells[1] or not cells[2]:
                raise ReadError(
                    "expected 'interval number<TAB>number of points' after the label",
                    path=path,
                    line=line,
                )
            interval = _int(cells[1], "the interval number", path, line)
            declared = _int(cells[2], "the number of points", path, line)
        elif key in INTERVAL_DATA:
            raw, i = _read_table(rows, i, item, path)
            n = len(rows)  # peeling a run's first line may have added an item
            raw.project, raw.test, raw.result = project, test, result
            raw.extra.update(fields)
            raw.interval = interval if interval is not None else len(out) + 1
            raw.n_declared = declared
            out.append(raw)
            interval, declared = None, None
            continue
        elif first.endswith(":") and key in HEADER_FIELDS:
            value = label_value(cells)
            if value is not None:
                fields[HEADER_FIELDS[key]] = value
                if test is None:
                    shared[HEADER_FIELDS[key]] = value
        # other labelled lines (comments) carry nothing we need
        i += 1
    if not out:
        raise ReadError(
            "no 'Interval data:' table found: a header without data?", path=path,
            hint="export the intervals' tables, not only the test description",
        )
    return out


def _read_table(
    rows: list[Row | Run], start: int, header_row: Row, path: str
) -> tuple[RawInterval, int]:
    """Read one ``Interval data:`` header (``header_row``, ``rows[start]``), its meaning
    and unit rows, and its rows."""
    header_line, header = header_row
    names = header[1:]
    while names and not names[-1]:
        names.pop()
    if not names:
        raise ReadError("'Interval data:' header names no columns", path=path, line=header_line)
    i = start + 1
    meanings: list[str] = []
    units: list[str] | None = None
    for _ in range(2):
        if i >= len(rows):
            break
        _, cells = peel(rows, i)
        if cells and cells[0]:
            break
        rest = cells[1:]
        if any(UNIT_CELL.match(c) for c in rest):
            units = rest
            i += 1
            break
        if meanings or any(c and c[0].isdigit() for c in rest[:1]):
            break
        meanings = rest
        i += 1
    if units is None:
        raise ReadError(
            "expected a unit row ([s], [mN·m], ...) under the 'Interval data:' header",
            path=path,
            line=header_line,
            hint="the file is truncated or not a RheoCompass table export",
        )
    data: list[Row | Run] = []
    while i < len(rows):
        item = rows[i]
        if isinstance(item, Run):  # data lines: an empty first cell, then the point number
            data.append(replace(item, skip=1))
            i += 1
            continue
        line, cells = item
        if (cells and cells[0]) or _is_blank(cells):
            break
        data.append((line, cells[1:]))
        i += 1
    known = builtin_aliases().names
    point_col = next(
        (j for j, nm in enumerate(names) if known.get(name_key(nm)) == "point_no"), None
    )
    raw = RawInterval(
        names=names,
        units=list(units[: len(names)]),
        meanings=list(meanings[: len(names)]),
        rows=data,
        point_col=point_col,
        header_line=header_line,
    )
    return raw, i


READER = Reader(
    name=FORMAT,
    suffixes=(".csv", ".txt", ".tsv"),
    expects="a RheoCompass table export ('Project:' ... 'Interval data:')",
    parse=lambda rows, path, aliases: parse_intervals(rows, path),
    looks_like=lambda rows, aliases: looks_like(rows),
    data_line=data_line,
    decimal=",",
)

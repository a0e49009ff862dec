"""Anton Paar Rheoplus "Data Series Information" exports (older installations).

Layout: a metadata block per data series (``Name:``, ``Device:``, ``Measuring System:``…,
key and value separated by several delimiters), then per interval ``Interval:`` and
``Number of Data Points:`` lines, a profile description, and a table: a ``Meas. Pts.``
header row, a unit row, data rows starting with the point number. ``******`` marks a
missing value, numbers may carry English thousands separators (``1,460``), and column
names repeat (two ``Relaxation Modulus`` columns).

A table that went through Excel loses the header block of its first interval and shows
``#NAME?`` where Excel evaluated profile lines as formulas; such a file is read (the
damage is noted in the metadata) unless a data cell itself was destroyed.
"""

from __future__ import annotations

import re

from ..errors import ReadError
from .aliases import name_key
from .interval import HEADER_FIELDS, RawInterval, label_value
from .spec import Reader
from .textio import DataLine, Row, Run

FORMAT = "rheoplus"

SERIES = "dataseriesinformation"
POINT_HEADERS = frozenset({"measpts", "measpt", "messpkt", "messpunkte", "ptsdemesure"})
#: the series header's labels: the sample's ``Name:`` and the shared measurement fields
_META_KEYS = {"name": "name", **HEADER_FIELDS}
_DIGITS = re.compile(r"^\d+$")


def data_line(delimiter: str) -> DataLine:
    """How a data line starts: with a digit, the point number's first. (A line whose
    first cell is not all digits ends a table; in a run it is found where its point
    number is classified, and the file is read row by row.)"""
    return DataLine("", "0123456789")


def looks_like(rows: list[Row]) -> bool:
    """True when the first rows hold a Rheoplus series title or ``Meas. Pts.`` header."""
    for _, cells in rows[:80]:
        if cells and name_key(cells[0]) in POINT_HEADERS | {SERIES}:
            return True
    return False


def _whole(cell: str | None, what: str, path: str, line: int) -> int:
    try:
        return int((cell or "").replace(",", ""))
    except ValueError:
        raise ReadError(
            f"expected {what} as a whole number, got {cell!r}", path=path, line=line
        ) from None


def parse_intervals(rows: list[Row | Run], path: str) -> list[RawInterval]:
    """Find every table of a Rheoplus export (rows, and runs of data lines, see
    ``textio.scan_lines``) and return its header and rows in file order."""
    out: list[RawInterval] = []
    meta: dict[str, str] = {}
    sample: str | None = None
    interval: int | None = None
    declared: int | None = None
    last_interval = 0
    saw_series = False
    excel_cells = 0
    n = len(rows)
    i = 0
    while i < n:
        item = rows[i]
        if isinstance(item, Run):  # data lines outside a table: nothing to read
            item.check_line_ends()
            i += 1
            continue
        line, cells = item
        first = cells[0] if cells else ""
        key = name_key(first)
        if first == "#NAME?":
            excel_cells += 1
        if key == SERIES:
            saw_series = True
            meta, sample, interval, declared, last_interval = {}, None, None, None, 0
        elif first.endswith(":") and key in _META_KEYS:
            value = label_value(cells)
            if key == "name":
                sample = value
            elif value is not None:
                meta[_META_KEYS[key]] = value
        elif first.endswith(":") and key == "interval":
            interval = _whole(label_value(cells), "the interval number", path, line)
        elif first.endswith(":") and key == "numberofdatapoints":
            declared = _whole(label_value(cells), "the number of data points", path, line)
        elif key in POINT_HEADERS:
            raw, i = _read_table(rows, i, item, path)
            # a Rheoplus series is one test; its name is the sample's
            raw.sample = raw.test = sample
            raw.extra = dict(meta)
            if interval is None:
                # the header block was lost (an Excel round trip): number on from the last
                raw.interval = last_interval + 1
                raw.extra["interval_header"] = "missing; number inferred"
            else:
                raw.interval = interval
                raw.n_declared = declared
            last_interval = raw.interval
            out.append(raw)
            interval, declared = None, None
            continue
        i += 1
    if not out:
        raise ReadError(
            "no 'Meas. Pts.' table found: a Rheoplus header without data?", path=path
        )
    if excel_cells or not saw_series:
        note = []
        if not saw_series:
            note.append("'Data Series Information' block missing")
        if excel_cells:
            note.append(f"{excel_cells} '#NAME?' cell(s) in the profile lines")
        for raw in out:
            raw.extra["excel_damage"] = "; ".join(note)
    return out


def _read_table(
    rows: list[Row | Run], start: int, header_row: Row, path: str
) -> tuple[RawInterval, int]:
    """Read one ``Meas. Pts.`` header (``header_row``, ``rows[start]``), its unit row and
    its rows."""
    header_line, header = header_row
    names = list(header)
    while names and not names[-1]:
        names.pop()
    i = start + 1
    unit_row = rows[i] if i < len(rows) else None
    # a run starts with a point number: not a unit row
    if unit_row is None or isinstance(unit_row, Run) or (unit_row[1] and unit_row[1][0]):
        raise ReadError(
            "expected a unit row ([s], [µNm], ...) under the 'Meas. Pts.' header",
            path=path,
            line=header_line,
            hint="the file is truncated or its header was edited",
        )
    units = list(unit_row[1][: len(names)])
    i += 1
    data: list[Row | Run] = []
    while i < len(rows):
        item = rows[i]
        if isinstance(item, Run):  # data lines: each starts with its point number
            data.append(item)
            i += 1
            continue
        line, cells = item
        first = cells[0] if cells else ""
        if not any(cells) or (first and not _DIGITS.match(first) and "(" not in first):
            break
        data.append((line, cells))
        i += 1
    raw = RawInterval(
        names=names, units=units, rows=data, point_col=0, header_line=header_line
    )
    return raw, i


READER = Reader(
    name=FORMAT,
    suffixes=(".txt", ".csv"),
    expects="a Rheoplus export ('Meas. Pts.')",
    parse=lambda rows, path, aliases: parse_intervals(rows, path),
    looks_like=lambda rows, aliases: looks_like(rows),
    data_line=data_line,
    decimal=".",
)

"""An interval as a format reader finds it, before any cell is converted.

A format module (``rheocompass``, ``rheoplus``, ``plaincsv``) walks a file's rows and runs
of data lines (``textio.scan_lines``) and returns one :class:`RawInterval` per table:
its header (names, meaning row, units), its rows and where it sits in the file.
:class:`FileInfo` holds what the whole file shares.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from .textio import Row, Run

#: a unit cell as instrument software writes it under a header: ``[s]``, ``[mN·m]``
UNIT_CELL = re.compile(r"^\[.*\]$")


@dataclass
class RawInterval:
    """One interval's header and rows as a format reader found them.

    ``names``, ``units`` and ``meanings`` are aligned with the cells of ``rows``; each row
    carries the 1-based line number it came from. ``point_col`` is the index of the point
    number column (``None`` when the format has none).
    """

    names: list[str]
    units: list[str]
    rows: list[Row | Run]
    meanings: list[str] = field(default_factory=list)
    point_col: int | None = None
    project: str | None = None
    test: str | None = None
    result: str | None = None
    interval: int | None = None
    sample: str | None = None
    n_declared: int | None = None
    header_line: int | None = None
    extra: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class FileInfo:
    """How the whole file was read (shared by all its intervals)."""

    path: str
    fmt: str
    encoding: str | None
    delimiter: str | None
    decimal: str | None


#: The labelled header lines of Anton Paar's software that describe the measurement, by
#: their label's :func:`~tribopipe.readers.aliases.name_key`, and the ``meta.extra`` key
#: each becomes (what :func:`tribopipe.reporting.from_export` reads). The labels are
#: those Rheoplus writes in its "Data Series Information" block (``Device:``,
#: ``Application:``, ``Measuring Date/Time:`` ...); a RheoCompass export that holds a line
#: with one of these labels is read the same way. ``Name:`` (Rheoplus: the data series,
#: i.e. the sample) is the format's own business and not listed here.
HEADER_FIELDS: dict[str, str] = {
    "numberofintervals": "number_of_intervals",
    "application": "application",
    "device": "device",
    "measuringdatetime": "measuring_date_time",
    "measuringsystem": "measuring_system",
    "accessories": "accessories",
}


def label_value(cells: list[str]) -> str | None:
    """The value of a labelled line (``Test:<TAB><TAB>name``): its first non-empty cell
    after the label."""
    return next((c for c in cells[1:] if c), None)

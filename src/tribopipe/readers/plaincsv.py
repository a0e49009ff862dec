"""Plain CSV from any instrument: one header row naming the columns with their units.

Accepted headers: ``Time [s]``, ``Torque (mN·m)``, ``normal force / N``, or the canonical
names themselves (``time_s``, ``torque_Nm``, ``torque_mNm``); alternatively a second row
holding only the units (``[s]``, ``[mN·m]``). At least one column must be a canonical
quantity (time, torque, normal force, angle, speed, temperature, friction force,
position), otherwise the file is not an export we can read.

Testing-machine and tribometer software writes the same table with more around it, and
each of these is read:

* a header block above the table (``Sample: PE film``, ``Speed;150;mm/min``): the header
  is the first row naming at least two canonical quantities (the first non-empty row when
  no row does);
* a trailing separator after every cell (an empty last column);
* repeated header (and unit) lines inside the table, as software writes them at every
  page or segment: skipped;
* a footer below the table (``End of test``, a results block): the table ends at the
  first row after its data that is not a data row.
"""

from __future__ import annotations

import re

from ..errors import ReadError
from ..units import parse_unit
from .aliases import AliasTable
from .interval import UNIT_CELL, RawInterval
from .spec import Reader
from .textio import DataLine, Row, Run, first_row, peel

FORMAT = "csv"

_BRACKETED = re.compile(r"^(?P<name>.*?)\s*[\[(](?P<unit>[^\[\]()]*)[\])]\s*$")
_SLASHED = re.compile(r"^(?P<name>.*?)\s+/\s*(?P<unit>\S+)$")


def split_header(cell: str, aliases: AliasTable) -> tuple[str, str]:
    """``"Torque [mN·m]"`` → ``("Torque", "[mN·m]")``; ``"torque_mNm"`` → ``("torque",
    "[mNm]")`` when ``torque`` is a known name; otherwise ``(cell, "")``."""
    for pattern in (_BRACKETED, _SLASHED):
        m = pattern.match(cell)
        if m and m.group("name"):
            return m.group("name"), f"[{m.group('unit').strip()}]"
    # snake_case with a unit suffix: split at the last underscore(s) that leave a unit
    parts = cell.split("_")
    for k in range(len(parts) - 1, 0, -1):
        base, unit = "_".join(parts[:k]), "_".join(parts[k:])
        if aliases.quantity(base) or base in aliases.names.values():
            quantity = aliases.quantity(base)
            if parse_unit(unit.replace("_", "/"), quantity) is not None:
                return base, f"[{unit.replace('_', '/')}]"
    return cell, ""


def data_line(delimiter: str) -> DataLine:
    """How a data line starts: with a number's first character (any other line is read
    as a row, and decided there)."""
    return DataLine("", "-+.0123456789")


def _quantities(cells: list[str], aliases: AliasTable) -> int:
    """How many cells of a row name a canonical quantity."""
    return sum(1 for c in cells if c and aliases.quantity(split_header(c, aliases)[0]))


#: a header found below a header block names at least this many canonical quantities
HEADER_MIN_QUANTITIES = 2


def _header_index(rows: list[Row | Run], aliases: AliasTable) -> int:
    """Index in ``rows`` of the header row: the first line naming at least
    :data:`HEADER_MIN_QUANTITIES` canonical quantities, whatever its first cell (a header
    block above it may hold lines that start like numbers: dates, counts); else the first
    non-empty item (the header of a file without a header block).

    One rule for both read paths: a line in a run of data lines (a header whose first
    cell was made a number) is a header as it would be as a row; such a run is cut there
    in place, so that ``rows[index]`` is the header row."""
    for i, item in enumerate(rows):
        if isinstance(item, Run):
            header = next((number for number, cells in item.lines_with_letters()
                           if _quantities(cells, aliases) >= HEADER_MIN_QUANTITIES), None)
            if header is None:
                continue
            before, row, after = item.split_at(header)
            rows[i : i + 1] = [r for r in (before, row, after) if r is not None]
            return i + (before is not None)
        if _quantities(item[1], aliases) >= HEADER_MIN_QUANTITIES:
            return i
    return next(i for i, item in enumerate(rows) if isinstance(item, Run) or any(item[1]))


def looks_like(rows: list[Row], aliases: AliasTable) -> bool:
    """True when the first non-empty row names at least one canonical quantity, or a row
    below a header block names at least two."""
    header = next((cells for _, cells in rows if any(cells)), None)
    if header is None:
        return False
    if _quantities(header, aliases):
        return True
    return any(_quantities(cells, aliases) >= HEADER_MIN_QUANTITIES for _, cells in rows)


def _table_rows(data: list[Row | Run], header: list[str], unit_row: list[str] | None
                ) -> tuple[list[Row | Run], int]:
    """The table's data: runs and rows up to the first row that is neither data nor a
    repeat of the header or unit row (a footer), without the repeats; and how many
    repeated header lines were skipped."""
    repeats = {tuple(header)} | ({tuple(unit_row)} if unit_row else set())
    kept: list[Row | Run] = []
    skipped = 0
    for item in data:
        if isinstance(item, Run):
            kept.append(item)
            continue
        cells = item[1]
        if not any(cells):
            continue
        if tuple(cells) in repeats:
            skipped += 1
            continue
        first = next((c for c in cells if c), "")
        if kept and first[:1] not in "-+.0123456789":
            break  # a footer
        kept.append(item)
    return kept, skipped


def parse_intervals(
    rows: list[Row | Run], path: str, aliases: AliasTable
) -> list[RawInterval]:
    """The one table of a plain CSV: header (names with units) and its data rows (rows,
    and runs of data lines, see ``textio.scan_lines``)."""
    body = [item for item in rows if isinstance(item, Run) or any(item[1])]
    if not body:
        raise ReadError("empty file", path=path)
    above = _header_index(body, aliases)
    preamble = [item for item in body[:above] if not isinstance(item, Run)]
    body = body[above:]
    header_line, header = first_row(body[0])
    peel(body, 0)
    names: list[str] = []
    units: list[str] = []
    for cell in header:
        name, unit = split_header(cell, aliases)
        names.append(name)
        units.append(unit)
    found = [aliases.quantity(nm) for nm in names]
    if not any(found):
        raise ReadError(
            "not an export: no column is named like time, torque, normal force, angle, "
            f"speed or temperature (columns found: {', '.join(header)[:200]})",
            path=path,
            line=header_line,
            hint="name the columns with units, e.g. 'Time [s],Torque [mN·m],Normal Force [N]',"
            " or add your names to configs/aliases.toml",
        )
    data = body[1:]
    unit_row = first_row(data[0])[1] if data else None
    if unit_row is not None and all(UNIT_CELL.match(c) or not c for c in unit_row):
        units = [c or u for c, u in zip(unit_row, units, strict=False)] + units[len(unit_row) :]
        peel(data, 0)
        data = data[1:]
    else:
        unit_row = None
    data, repeated = _table_rows(data, header, unit_row)
    extra: dict[str, str] = {}
    if preamble:
        extra["header_block_lines"] = str(len(preamble))
    if repeated:
        extra["repeated_header_lines"] = str(repeated)
    if not data:
        raise ReadError("header without data rows", path=path, line=header_line)
    point_col = next(
        (j for j, nm in enumerate(names) if aliases.base_name(nm) == "point_no"), None
    )
    return [
        RawInterval(
            names=names,
            units=units,
            rows=data,
            point_col=point_col,
            interval=1,
            header_line=header_line,
            extra=extra,
        )
    ]


READER = Reader(
    name=FORMAT,
    suffixes=(".csv", ".txt", ".tsv"),
    expects="a CSV naming time, torque (or friction force) and normal-force columns with units",
    parse=parse_intervals,
    looks_like=looks_like,
    data_line=data_line,
    decimal=",",
)

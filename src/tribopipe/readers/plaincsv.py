"""Plain CSV from any instrument: one header row naming the columns with their units.

Accepted headers: ``Time [s]``, ``Torque (mN·m)``, ``normal force / N``, or the canonical
names themselves (``time_s``, ``torque_Nm``, ``torque_mNm``); alternatively a second row
holding only the units (``[s]``, ``[mN·m]``). Every following non-empty row is a data row.
At least one column must be a canonical quantity (time, torque, normal force, angle,
speed, temperature), otherwise the file is not an export we can read.
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


def looks_like(rows: list[Row], aliases: AliasTable) -> bool:
    """True when the first non-empty row names at least one canonical quantity."""
    header = next((cells for _, cells in rows if any(cells)), None)
    if header is None:
        return False
    return any(aliases.quantity(split_header(c, aliases)[0]) for c in header if c)


def parse_intervals(
    rows: list[Row | Run], path: str, aliases: AliasTable
) -> list[RawInterval]:
    """The one table of a plain CSV: header (names with units) and its data rows (rows,
    and runs of data lines, see ``textio.scan_lines``)."""
    body = [item for item in rows if isinstance(item, Run) or any(item[1])]
    if not body:
        raise ReadError("empty file", path=path)
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
        )
    ]


READER = Reader(
    name=FORMAT,
    suffixes=(".csv", ".txt", ".tsv"),
    expects="a CSV naming time, torque and normal-force columns with units",
    parse=parse_intervals,
    looks_like=looks_like,
    data_line=data_line,
    decimal=",",
)

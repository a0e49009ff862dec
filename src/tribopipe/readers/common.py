"""The part every table reader shares: one interval's cells → a :class:`Measurement`.

A format reader finds the intervals of a file and their header (names, meaning row,
units); :func:`build_measurement` classifies the rows (data point, invalid point, raw
waveform sub-row), converts each column in bulk to SI and names it.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from ..errors import ReadError
from ..measurement import Measurement, MeasurementMeta
from ..units import canonical_unit, parse_unit, sanitize_suffix
from .aliases import CANONICAL_COLUMN, AliasTable, snake_case
from .textio import EXCEL_ERRORS, is_missing, to_numbers

#: the value RheoCompass writes for a loss factor it could not determine (status ``taD``)
LOSS_FACTOR_PLACEHOLDER = 20000.0

#: a unit cell as instrument software writes it under a header: ``[s]``, ``[mN·m]``
UNIT_CELL = re.compile(r"^\[.*\]$")

_INVALID_POINT = re.compile(r"\((?:invalid|invalide|ung[üu]ltig|non valide)\)", re.IGNORECASE)
# Rheoplus writes the point number, then this text in the next cell
_INVALID_CELL = re.compile(
    r"^(?:invalid point|point invalide|ung[üu]ltiger (?:mess)?punkt)$", re.IGNORECASE
)


@dataclass
class RawInterval:
    """One interval's header and rows as a format reader found them.

    ``names``, ``units`` and ``meanings`` are aligned with the cells of ``rows``; each row
    carries the 1-based line number it came from. ``point_col`` is the index of the point
    number column (``None`` when the format has none).
    """

    names: list[str]
    units: list[str]
    rows: list[tuple[int, list[str]]]
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


def label_value(cells: list[str]) -> str | None:
    """The value of a labelled line (``Test:<TAB><TAB>name``): its first non-empty cell
    after the label."""
    return next((c for c in cells[1:] if c), None)


def _classify_rows(raw: RawInterval, info: FileInfo) -> tuple[list[int], int, int]:
    """Indices of the data rows, and the counts of invalid points and waveform sub-rows."""
    if raw.point_col is None:
        return list(range(len(raw.rows))), 0, 0
    data: list[int] = []
    invalid = waveform = 0
    pc = raw.point_col
    for i, (line, cells) in enumerate(raw.rows):
        cell = cells[pc] if pc < len(cells) else ""
        if cell.isascii() and cell.isdigit() and len(cell) < 16:
            after = cells[pc + 1] if pc + 1 < len(cells) else ""
            if after and after[0].isalpha() and _INVALID_CELL.match(after):
                invalid += 1
            else:
                data.append(i)
        elif _INVALID_POINT.search(cell):
            invalid += 1
        elif not cell:
            waveform += 1
        else:
            raise ReadError(
                f"expected a point number, got {cell[:40]!r}",
                path=info.path,
                line=line,
                column=raw.names[pc],
            )
    return data, invalid, waveform


def _free(base: str, suffix: str, used: set[str]) -> str:
    """``base_suffix``, or ``base_2_suffix``, ``base_3_suffix``... when already taken."""
    name = _column_name(base, suffix)
    k = 2
    while name in used:
        name = _column_name(f"{base}_{k}", suffix)
        k += 1
    return name


def _column_name(base: str, suffix: str) -> str:
    return f"{base}_{suffix}" if suffix else base


def build_measurement(raw: RawInterval, info: FileInfo, aliases: AliasTable) -> Measurement:
    """Convert one interval to a :class:`Measurement` with SI, unit-suffixed columns.

    Raises :class:`ReadError` for a cell that is not a number where one is expected, a
    canonical quantity in an unknown unit, or an interval holding fewer points than it
    declares (a truncated file).
    """
    import pandas as pd

    data_idx, n_invalid, n_waveform = _classify_rows(raw, info)
    n_points_found = len(data_idx) + n_invalid
    if raw.n_declared is not None and n_points_found < raw.n_declared:
        last = raw.rows[-1][0] if raw.rows else raw.header_line
        raise ReadError(
            f"interval {raw.interval} declares {raw.n_declared} points but holds "
            f"{n_points_found}: truncated file?",
            path=info.path,
            line=last,
            hint="export the measurement again",
        )
    rows = [raw.rows[i] for i in data_idx]
    lines = [ln for ln, _ in rows]
    width = len(raw.names)
    for line, cells in rows:
        if len(cells) < width:
            # instrument software always writes every cell (empty ones too)
            raise ReadError(
                f"row has {len(cells)} of the header's {width} cells: truncated file?",
                path=info.path,
                line=line,
            )
        extra_cells = [c for c in cells[width:] if c]
        if extra_cells:
            raise ReadError(
                f"row has {len(cells)} cells but the header names {width} columns",
                path=info.path,
                line=line,
            )

    # transpose once (C speed); every data row has at least `width` cells (checked above)
    by_column = list(zip(*(cells[:width] for _, cells in rows), strict=True)) if rows else []
    columns: dict[str, object] = {}
    column_map: list[tuple[str, str]] = []
    used: set[str] = set()
    extra = dict(raw.extra)
    missing_cells = 0
    for j, name in enumerate(raw.names):
        unit = raw.units[j] if j < len(raw.units) else ""
        meaning = raw.meanings[j] if j < len(raw.meanings) else ""
        cells = list(by_column[j]) if by_column else []
        if j == raw.point_col:
            points = np.array([int(c) for c in cells], dtype=np.int64)
            columns["point_no"] = points
            used.add("point_no")
            column_map.append((name, "point_no"))
            continue
        if not name and not unit and not any(cells):
            continue  # padding column
        damaged = EXCEL_ERRORS.intersection(cells)
        if damaged:
            k = next(k for k, c in enumerate(cells) if c in damaged)
            raise ReadError(
                f"cell {cells[k]!r} where a value was expected: the table went through "
                "Excel, which replaced it by an error",
                path=info.path,
                line=lines[k],
                column=name,
                hint="re-export from the instrument software and do not open it in Excel",
            )
        quantity = aliases.quantity(name)
        base = aliases.base_name(name)
        if quantity is not None:
            spec = canonical_unit(quantity, unit, column=name, path=info.path)
            target = CANONICAL_COLUMN[quantity]
            if target in used:
                target = _free(quantity, spec.suffix, used)
        else:
            spec = parse_unit(unit)
            suffix = spec.suffix if spec is not None else sanitize_suffix(unit)
            # a repeated name takes its meaning row (when there is one) before a number
            taken = meaning and _column_name(base, suffix) in used
            target = _free(f"{base}_{snake_case(meaning)}" if taken else base, suffix, used)
        values, bad = to_numbers(cells, info.decimal or ".")
        if bad is not None:
            textual = quantity is None and (base == "status" or spec is None or not spec.suffix)
            if not textual:
                raise ReadError(
                    f"expected a number, got {cells[bad][:40]!r}",
                    path=info.path,
                    line=lines[bad],
                    column=name,
                )
            target = _free(base, "", used)
            columns[target] = pd.array(cells, dtype="string")
        elif base == "status":
            target = _free(base, "", used)
            columns[target] = pd.array(cells, dtype="string")
        else:
            if "*" in "".join(cells):
                missing_cells += sum(1 for c in cells if c and is_missing(c))
            # an unknown unit keeps its values and a sanitised unit suffix
            si = spec.to_si(values) if spec is not None else values
            if base == "loss_factor":
                placeholder = si == LOSS_FACTOR_PLACEHOLDER
                if placeholder.any():
                    si = np.where(placeholder, np.nan, si)
                    extra["loss_factor_placeholders"] = str(int(placeholder.sum()))
            columns[target] = si
        used.add(target)
        column_map.append((name, target))
    if missing_cells:
        extra["missing_cells"] = str(missing_cells)

    frame = pd.DataFrame(columns, index=pd.RangeIndex(len(rows)))
    meta = MeasurementMeta(
        source_file=info.path,
        file_format=info.fmt,
        encoding=info.encoding,
        delimiter=info.delimiter,
        decimal=info.decimal,
        project=raw.project,
        test=raw.test,
        result=raw.result,
        interval=raw.interval,
        sample=raw.sample,
        original_columns=tuple(raw.names),
        original_units=tuple(raw.units[: len(raw.names)])
        + ("",) * max(0, len(raw.names) - len(raw.units)),
        column_map=tuple(column_map),
        n_points_declared=raw.n_declared,
        n_invalid_points=n_invalid,
        n_waveform_rows=n_waveform,
        header_line=raw.header_line,
        extra=tuple(extra.items()),
    )
    return Measurement(data=frame, meta=meta)

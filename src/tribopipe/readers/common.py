"""The part every table reader shares: one interval's cells → a :class:`Measurement`.

A format reader finds the intervals of a file and their header (names, meaning row,
units: :class:`~.interval.RawInterval`); :func:`build_measurement` has the rows
classified (data point, invalid point, raw waveform sub-row, see :mod:`.cells`), converts
each column in bulk to SI and names it.
"""

from __future__ import annotations

import numpy as np

from ..errors import ReadError
from ..measurement import Measurement, MeasurementMeta
from ..units import UnitSpec, canonical_unit, parse_unit, sanitize_suffix
from .aliases import CANONICAL_COLUMN, AliasTable, snake_case
from .arrowcells import ArrowCells
from .cells import RowCells
from .interval import FileInfo, RawInterval
from .textio import declines

#: the value RheoCompass writes for a loss factor it could not determine (status ``taD``)
LOSS_FACTOR_PLACEHOLDER = 20000.0


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


def build_measurement(
    raw: RawInterval, info: FileInfo, aliases: AliasTable, cells: ArrowCells | None = None
) -> Measurement:
    """Convert one interval to a :class:`Measurement` with SI, unit-suffixed columns.

    ``cells``: the interval's data rows already read column-wise by a C parser
    (:func:`~.arrowcells.arrow_cells`); without them, or where that path cannot vouch for a
    result, the rows are read one by one (:class:`~.cells.RowCells`). Both give the same
    table to the bit.

    Raises :class:`ReadError` for a cell that is not a number where one is expected, a
    canonical quantity in an unknown unit, or an interval holding fewer points than it
    declares (a truncated file).
    """
    if cells is not None:
        try:
            return _measurement(raw, info, aliases, cells)
        except declines(ReadError):
            pass  # the general path decides, and names the line of any error
    return _measurement(raw, info, aliases, RowCells(raw, info))


def _measurement(
    raw: RawInterval, info: FileInfo, aliases: AliasTable, cells: ArrowCells | RowCells
) -> Measurement:
    """Name, convert and assemble every column of ``cells``; the metadata from ``raw``."""
    import pandas as pd

    columns: dict[str, object] = {}
    column_map: list[tuple[str, str]] = []
    used: set[str] = set()
    extra = dict(raw.extra)
    missing_cells = 0
    for j, name in enumerate(raw.names):
        unit = raw.units[j] if j < len(raw.units) else ""
        meaning = raw.meanings[j] if j < len(raw.meanings) else ""
        if j == raw.point_col:
            columns["point_no"] = cells.point_numbers(j)
            used.add("point_no")
            column_map.append((name, "point_no"))
            continue
        if not name and not unit and cells.is_empty(j):
            continue  # padding column
        cells.check_damage(j, name)
        quantity = aliases.quantity(name)
        base = aliases.base_name(name)
        spec: UnitSpec | None
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
        # a Status column is text; so is a column without a known unit holding words
        textual = quantity is None and (base == "status" or spec is None or not spec.suffix)
        values = None if base == "status" else cells.numbers(j, name, textual)
        if values is None:
            target = _free(base, "", used)
            columns[target] = cells.strings(j)
        else:
            missing_cells += cells.missing(j)
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

    frame = pd.DataFrame(columns, index=pd.RangeIndex(cells.n_rows))
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
        n_invalid_points=cells.n_invalid,
        n_waveform_rows=cells.n_waveform,
        header_line=raw.header_line,
        extra=tuple(extra.items()),
    )
    return Measurement(data=frame, meta=meta)

"""The cells of one interval's data rows, column by column, for ``common.build_measurement``.

Two sources answer the same questions (is a column empty, does it hold an Excel error,
its numbers, its text):

:class:`RowCells` (here)
    the general path: every row a list of stripped cells (``textio.split_cells``).
    Exact for any input; raises :class:`~tribopipe.errors.ReadError` for bad cells,
    naming line and column.
:class:`~.arrowcells.ArrowCells`
    the fast path for runs of plain data lines: parsed by ``pyarrow.csv`` and converted
    column-wise, to the same result; it declines where it could differ.

Rows: a point number marks a data row; ``1  (invalid)`` (or a Rheoplus ``invalid point``
in the next cell) an invalid point, an empty point number a raw-waveform sub-row. Both
are counted and left out (:func:`classify`).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import ReadError
from .interval import FileInfo, RawInterval
from .textio import (
    EXCEL_ERRORS,
    Row,
    expand_runs,
    is_missing,
    to_numbers,
)

_INVALID_POINT = re.compile(r"\((?:invalid|invalide|ung[üu]ltig|non valide)\)", re.IGNORECASE)
# Rheoplus writes the point number, then this text in the next cell
_INVALID_CELL = re.compile(
    r"^(?:invalid point|point invalide|ung[üu]ltiger (?:mess)?punkt)$", re.IGNORECASE
)


def classify(point_cell: str, next_cell: str) -> str:
    """What a row is, from its stripped point-number cell and the cell after it:
    ``"data"``, ``"invalid"``, ``"waveform"`` or ``"bad"`` (not a point number)."""
    if point_cell.isascii() and point_cell.isdigit() and len(point_cell) < 16:
        if next_cell and next_cell[0].isalpha() and _INVALID_CELL.match(next_cell):
            return "invalid"
        return "data"
    if _INVALID_POINT.search(point_cell):
        return "invalid"
    return "bad" if point_cell else "waveform"


# --------------------------------------------------------------------------- general


class RowCells:
    """The data rows of an interval as lists of stripped cells (the general path)."""

    def __init__(self, raw: RawInterval, info: FileInfo) -> None:
        rows = expand_runs(raw.rows)
        data, self.n_invalid, self.n_waveform = _classify_rows(rows, raw, info)
        if raw.n_declared is not None and len(data) + self.n_invalid < raw.n_declared:
            last = rows[-1][0] if rows else raw.header_line
            raise ReadError(
                f"interval {raw.interval} declares {raw.n_declared} points but holds "
                f"{len(data) + self.n_invalid}: truncated file?",
                path=info.path,
                line=last,
                hint="export the measurement again",
            )
        rows = [rows[i] for i in data]
        width = len(raw.names)
        for line, cells in rows:
            if len(cells) < width:
                # instrument software always writes every cell (empty ones too)
                raise ReadError(
                    f"row has {len(cells)} of the header's {width} cells: truncated file?",
                    path=info.path,
                    line=line,
                )
            if any(cells[width:]):
                raise ReadError(
                    f"row has {len(cells)} cells but the header names {width} columns",
                    path=info.path,
                    line=line,
                )
        self.path, self.decimal = info.path, info.decimal or "."
        self.n_rows = len(rows)
        self.lines = [line for line, _ in rows]
        # transpose once (C speed); every data row has at least `width` cells
        self.columns = list(zip(*(cells[:width] for _, cells in rows), strict=True))

    def _cells(self, j: int) -> Sequence[str]:
        return self.columns[j] if self.columns else ()

    def point_numbers(self, j: int) -> NDArray[np.int64]:
        """The point numbers (int64) of column ``j``."""
        return np.array([int(c) for c in self._cells(j)], dtype=np.int64)

    def is_empty(self, j: int) -> bool:
        return not any(self._cells(j))

    def check_damage(self, j: int, name: str) -> None:
        """Raise for an Excel error (``#NAME?``) in column ``j``."""
        cells = self._cells(j)
        damaged = EXCEL_ERRORS.intersection(cells)
        if damaged:
            k = next(k for k, c in enumerate(cells) if c in damaged)
            raise ReadError(
                f"cell {cells[k]!r} where a value was expected: the table went through "
                "Excel, which replaced it by an error",
                path=self.path,
                line=self.lines[k],
                column=name,
                hint="re-export from the instrument software and do not open it in Excel",
            )

    def numbers(self, j: int, name: str, textual: bool) -> NDArray[np.float64] | None:
        """Column ``j`` as floats (empty and ``******`` cells NaN); ``None`` when a cell is
        not a number and the column may hold text, else :class:`ReadError`."""
        cells = self._cells(j)
        values, bad = to_numbers(cells, self.decimal)
        if bad is None:
            return values
        if not textual:
            raise ReadError(
                f"expected a number, got {cells[bad][:40]!r}",
                path=self.path,
                line=self.lines[bad],
                column=name,
            )
        return None

    def missing(self, j: int) -> int:
        """How many cells of column ``j`` are ``******`` (no value)."""
        cells = self._cells(j)
        if "*" not in "".join(cells):
            return 0
        return sum(1 for c in cells if c and is_missing(c))

    def strings(self, j: int) -> Any:
        """Column ``j`` as a pandas string array."""
        import pandas as pd

        return pd.array(list(self._cells(j)), dtype="string")


def _classify_rows(rows: list[Row], raw: RawInterval, info: FileInfo) -> tuple[list[int], int, int]:
    """Indices of the data rows, and the counts of invalid points and waveform sub-rows."""
    if raw.point_col is None:
        return list(range(len(rows))), 0, 0
    data: list[int] = []
    invalid = waveform = 0
    pc = raw.point_col
    for i, (line, cells) in enumerate(rows):
        cell = cells[pc] if pc < len(cells) else ""
        after = cells[pc + 1] if pc + 1 < len(cells) else ""
        kind = classify(cell, after)
        if kind == "data":
            data.append(i)
        elif kind == "invalid":
            invalid += 1
        elif kind == "waveform":
            waveform += 1
        else:
            raise ReadError(
                f"expected a point number, got {cell[:40]!r}",
                path=info.path,
                line=line,
                column=raw.names[pc],
            )
    return data, invalid, waveform

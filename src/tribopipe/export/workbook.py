"""The friction map as a spreadsheet (``.xlsx``), for colleagues who open results in Excel.

One sheet per table layout of :mod:`tribopipe.export.tables` (``paper``, ``group``,
``abstract``) and a ``notes`` sheet (where the numbers come from, what ± U and each flag
mean). Numbers are numbers: a rounded value is the number as rounded, shown with its
decimals by the cell's number format (``0.740`` stays ``0.740``), never text. Units are in
the column heads (``pressure [kPa]``). Text from the map (names, flags, sources) is one
printable line (:func:`tribopipe.escape.printable`) stored as a text cell, so a name that
starts with ``=`` is never a formula.
"""

from __future__ import annotations

import io
import math
import os
import re
from collections.abc import Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import __version__
from ..errors import ExportError
from ..escape import display_path, printable
from ..files import write_bytes_atomic
from ..frictionmap import read_map
from ..frictionmap.synthetic_rows import synthetic_note
from .tables import PAPER_NOTE, abstract_table, group_table, paper_table, runs_of_methods

if TYPE_CHECKING:
    import pandas as pd
    from openpyxl.worksheet.worksheet import Worksheet

#: column-name suffix -> unit, longest first (the map's unit-suffixed names)
_UNITS: tuple[tuple[str, str], ...] = (
    ("_mm_s", "mm/s"), ("_kPa", "kPa"), ("_Nm", "N·m"), ("_mm", "mm"), ("_N", "N"),
    ("_C", "°C"), ("_s", "s"),
)
#: heads of the paper sheet's own columns
_PAPER_HEADS = {"n": "n", "mu_s": "μ_S", "mu_s_U": "U of μ_S (k = 2)", "mu_k": "μ_K",
                "mu_k_U": "U of μ_K (k = 2)", "flags": "flags"}
_DECIMAL = re.compile(r"^-?\d+(?:\.(\d+))?$")
#: what each sheet holds (the notes sheet says it)
SHEETS: tuple[tuple[str, str], ...] = (
    ("paper", "one row per condition group: n, μ_S and μ_K with U (expanded, k = 2), "
              "rounded the GUM way (U to two significant digits), and flags"),
    ("group", "one row per condition group: every repeat statistic of μ_K and μ_S"),
    ("abstract", "the founding paper's Table 2: the mean μ_K per condition, two decimals"),
)
FLAG_NOTES: tuple[tuple[str, str], ...] = (
    ("range > r", "the repeats of the group differ by more than the pooled repeatability "
                  "limit r = 2.8·s_r (ISO 5725)"),
    ("labs disagree", "two labs' means differ beyond the critical difference of R "
                      "(ISO 5725-6)"),
    ("flagged run", "the group holds a run with a QC flag (see the runs in the map)"),
    ("stated u", "some runs carry no uncertainty budget of their own (imported rows): "
                 "theirs is the stated estimate of the founding cell at the run's μ and "
                 "force"),
    ("n = 1", "a single run: no repeat scatter"),
    ("repeats identical", "no scatter to estimate U from"),
)


def unit_head(column: str) -> str:
    """The head of a map column with its unit: ``pressure_kPa`` → ``pressure [kPa]``,
    ``temperature_C`` → ``temperature [°C]``; a name without a unit suffix is kept."""
    for suffix, unit in _UNITS:
        if column.endswith(suffix) and len(column) > len(suffix):
            return f"{column[: -len(suffix)].replace('_', ' ')} [{unit}]"
    return column


def _number_format(text: str) -> str:
    """The Excel number format that shows a rounded number as it was rounded."""
    m = _DECIMAL.match(text)
    decimals = len(m.group(1) or "") if m else 0
    return "0." + "0" * decimals if decimals else "0"


def _cell_value(value: Any) -> tuple[Any, str | None]:
    """``(value, number format)`` for one cell: finite numbers as numbers, missing as
    empty, booleans as booleans, a rounded number's text as the number, other text as
    one printable line."""
    import numpy as np

    if value is None:
        return None, None
    if isinstance(value, bool | np.bool_):
        return bool(value), None
    if isinstance(value, int | np.integer):
        return int(value), None
    if isinstance(value, float | np.floating):
        return (float(value), None) if math.isfinite(value) else (None, None)
    text = str(value)
    if text in ("", "nan", "NaT", "<NA>"):
        return None, None
    if _DECIMAL.match(text):
        return float(text), _number_format(text)
    return printable(text), None


def _fill(sheet: Worksheet, table: pd.DataFrame, heads: Sequence[str],
          formats: dict[str, str] | None = None) -> None:
    """Write ``table`` to ``sheet`` under ``heads``: numbers as numbers, text as text;
    ``formats``: a column's number format (by its head) where the layout rounds it."""
    formats = formats or {}
    sheet.append([printable(h) for h in heads])
    for row in table.itertuples(index=False, name=None):
        sheet.append([None] * len(heads))
        r = sheet.max_row
        for c, value in enumerate(row, start=1):
            v, fmt = _cell_value(value)
            cell = sheet.cell(row=r, column=c)
            cell.value = v
            if isinstance(v, str):
                cell.data_type = "s"  # a name starting with "=" stays text
            fmt = formats.get(heads[c - 1], fmt)
            if fmt is not None and v is not None:
                cell.number_format = fmt
    sheet.freeze_panes = "A2"
    for c, head in enumerate(heads, start=1):
        width = max([len(str(head))] + [len(str(sheet.cell(row=r, column=c).value or ""))
                                         for r in range(2, min(sheet.max_row, 200) + 1)])
        sheet.column_dimensions[sheet.cell(row=1, column=c).column_letter].width = min(
            max(8, width + 2), 60)


def workbook_bytes(
    runs: pd.DataFrame,
    *,
    source: str,
    pin: Sequence[str] | None = None,
    disc: Sequence[str] | None = None,
    temperature_C: Sequence[float] | None = None,
    by_speed: bool = False,
    method: Sequence[str] | None = None,
) -> bytes:
    """The ``.xlsx`` file of the map's ``runs`` (filtered like ``map table``): sheets
    ``paper``, ``group``, ``abstract`` and ``notes``. :class:`ExportError` when no group
    matches the filters."""
    from openpyxl import Workbook

    if method:
        runs = runs_of_methods(runs, method)
    filters: dict[str, Any] = {"pin": pin, "disc": disc, "temperature_C": temperature_C}
    paper = paper_table(runs, machine=True, **filters)
    if paper.empty:
        raise ExportError(f"no rows to tabulate (the map holds {len(runs)} runs)",
                          hint="check `tribopipe map show` for the pins, discs and "
                          "temperatures")
    book = Workbook()
    sheet = book.active
    assert sheet is not None
    sheet.title = "paper"
    _fill(sheet, paper, [_PAPER_HEADS.get(c, unit_head(c)) for c in paper.columns])
    group = group_table(runs, by_speed=by_speed, **filters)
    _fill(book.create_sheet("group"), group, [unit_head(str(c)) for c in group.columns])
    abstract = abstract_table(runs, **filters)
    # the paper's Table 2 prints μ_K with two decimals: 0.30, not 0.3
    _fill(book.create_sheet("abstract"), abstract,
          [unit_head(str(c)) if c != "mu_k" else "mean μ_K" for c in abstract.columns],
          {"mean μ_K": "0.00"})
    notes = book.create_sheet("notes")
    synthetic = synthetic_note(runs)
    lines: list[tuple[str, str]] = [
        ("source", display_path(source)),
        ("written", datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")),
        ("by", f"tribopipe {__version__}"),
        *((("note", synthetic),) if synthetic else ()),
        ("± U", PAPER_NOTE),
        *((f"sheet {name}", what) for name, what in SHEETS),
        *((f"flag {flag}", what) for flag, what in FLAG_NOTES),
    ]
    for key, text in lines:
        notes.append([printable(key), printable(text)])
        for cell in notes[notes.max_row]:
            cell.data_type = "s"
    notes.column_dimensions["A"].width = 22
    notes.column_dimensions["B"].width = 110
    buffer = io.BytesIO()
    book.save(buffer)
    return buffer.getvalue()


def export_workbook(
    map_path: str | os.PathLike[str], output: str | os.PathLike[str], **options: Any
) -> Path:
    """Read the map at ``map_path`` and write its workbook (:func:`workbook_bytes`,
    ``options`` its filters) to ``output`` atomically; returns the path."""
    if not Path(map_path).exists():
        raise ExportError("friction map not found", path=map_path, hint="pass --map PATH")
    data = workbook_bytes(read_map(map_path), source=str(map_path), **options)
    return write_bytes_atomic(output, data)

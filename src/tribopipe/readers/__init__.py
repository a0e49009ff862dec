"""Readers: raw instrument exports → :class:`tribopipe.measurement.Measurement` objects.

Every vendor quirk lives in this package. :func:`read_export` detects the format (one of
:data:`READERS`: RheoCompass text or Excel, Rheoplus, plain CSV), the encoding, the cell
delimiter and the decimal mark (each can be forced), and returns one Measurement per
interval, in file order, with canonical SI columns (``time_s``, ``torque_Nm``, ``normal_force_N``,
``angle_rad``, ``speed_rad_s``, ``temperature_C``), ``point_no`` and the other columns
snake_cased with an SI unit suffix. :func:`describe_export` tells what a file holds
(``tribopipe inspect``); :func:`require_columns` (from :mod:`tribopipe.measurement`) is
the check a reduction makes.

Quirks handled (each seen in a real export, see ``tests/data/README.md``):

- UTF-16 LE + BOM, UTF-8 + BOM, cp1252 re-saves; TAB, ';' or ',' cells, quoted and padded;
- decimal comma vs English thousands separators (``2,3981`` vs ``1,460``/``9,945.692``);
- invalid points (``1  (invalide)``, Rheoplus ``invalid point``) and raw-waveform sub-rows
  with an empty point number: counted in ``meta``, not data;
- ``******`` (no value) → NaN, counted in ``meta.extra["missing_cells"]``; a Loss Factor
  of exactly 20000 (RheoCompass's placeholder when tan δ is undetermined, status ``taD``)
  → NaN, counted in ``meta.extra["loss_factor_placeholders"]``;
- duplicate column names (``relaxation_modulus_Pa``, ``relaxation_modulus_2_Pa``; a
  non-empty meaning row names the duplicate instead);
- Excel round trips: a lost Rheoplus header block is noted (``excel_damage``); an Excel
  error (``#NAME?``) in a data cell is refused.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from itertools import chain, islice
from os import PathLike
from pathlib import Path
from typing import Any

from ..errors import ReadError, TribopipeError
from ..escape import display_path
from ..measurement import (
    FRICTION_FORCE,
    NORMAL_FORCE,
    TORQUE,
    Measurement,
    interval_label,
    require_columns,
)
from . import plaincsv, rheocompass, rheoplus, xlsx
from .aliases import AliasTable, load_aliases, resolve_aliases
from .arrowcells import arrow_cells
from .common import build_measurement
from .interval import FileInfo, RawInterval
from .spec import Reader
from .textio import (
    DecodedText,
    NotSimple,
    Row,
    Run,
    declines,
    decode,
    detect_decimal,
    detect_delimiter,
    foreign_kind,
    head_lines,
    plain_line_ends,
    read_bytes,
    scan_lines,
    simple_quotes,
    split_cells,
    split_plain,
)

__all__ = [
    "EXPORT_SUFFIXES",
    "export_kind",
    "FORMATS",
    "READERS",
    "AliasTable",
    "ColumnSummary",
    "ExportSummary",
    "IntervalSummary",
    "describe_export",
    "load_aliases",
    "read_export",
    "require_columns",
]

#: every export format, in the order detection tries them: binary formats by their first
#: bytes, then text formats by their first rows (a RheoCompass or Rheoplus label before a
#: plain CSV's header). A new format is one module with a :class:`Reader` and one entry here.
READERS: tuple[Reader, ...] = (
    rheocompass.READER,
    xlsx.READER,
    rheoplus.READER,
    plaincsv.READER,
)

#: format names accepted by ``fmt=`` / ``--format``
FORMATS: tuple[str, ...] = tuple(r.name for r in READERS)

#: file suffixes (lower case) of what the readers take, and a legacy .xls, which is
#: recognised and refused with the reason (save it as .xlsx). Formats are detected from
#: the content, so a campaign's folder discovery is all these suffixes stand for.
EXPORT_SUFFIXES: tuple[str, ...] = (
    *dict.fromkeys(suffix for r in READERS for suffix in r.suffixes), ".xls")


def _text_readers() -> tuple[Reader, ...]:
    """The text formats of :data:`READERS`, in detection order."""
    return tuple(r for r in READERS if r.looks_like is not None)

_OLE_MAGIC = b"\xd0\xcf\x11\xe0"  # legacy .xls
#: lines detection reads: format labels sit in the first 60-80 rows, the decimal mark is
#: read from the first 300
_HEAD_LINES = 300


def _normalise_delimiter(delimiter: str | None, path: str) -> str | None:
    if delimiter is None:
        return None
    named = {"tab": "\t", "\\t": "\t", "comma": ",", "semicolon": ";", "space": " "}
    value = named.get(delimiter.lower(), delimiter)
    if len(value) != 1:
        raise ReadError(
            f"delimiter must be one character, got {delimiter!r}",
            path=path,
            hint="use 'tab', ';' or ','",
        )
    return value


def _read(
    path: str,
    encoding: str | None,
    delimiter: str | None,
    decimal: str | None,
    fmt: str | None,
    aliases: AliasTable,
) -> list[Measurement]:
    """Detect format, encoding, delimiter and decimal mark; read every interval."""
    if decimal not in (None, ".", ","):
        raise ReadError(f"decimal mark must be '.' or ',', got {decimal!r}", path=path)
    names = [r.name for r in READERS]
    if fmt is not None and fmt not in names:
        raise ReadError(
            f"unknown format {fmt!r}", path=path, hint=f"expected one of {', '.join(names)}"
        )
    delimiter = _normalise_delimiter(delimiter, path)
    raw = read_bytes(path)
    if raw.startswith(_OLE_MAGIC):
        raise ReadError(
            "legacy Excel .xls workbook", path=path, hint="save it as .xlsx or export text"
        )
    for reader in READERS:
        if reader.magic is None or reader.rows is None:
            continue
        if fmt == reader.name or (fmt is None and raw.startswith(reader.magic)):
            info = FileInfo(path, reader.name, None, None, decimal or reader.decimal)
            rows: list[Row | Run] = list(reader.rows(path))
            intervals = reader.parse(rows, path, aliases)
            return [build_measurement(interval, info, aliases) for interval in intervals]

    decoded = decode(raw, path, encoding)
    if plain_line_ends(decoded.text):
        try:
            info, intervals = _parse_text(path, decoded, delimiter, decimal, fmt, aliases,
                                          plain=True)
            cells = arrow_cells(intervals, info, aliases)
            return [build_measurement(interval, info, aliases, c)
                    for interval, c in zip(intervals, cells, strict=True)]
        except declines(ReadError):
            pass  # read it row by row, which also words any error
    info, intervals = _parse_text(path, decoded, delimiter, decimal, fmt, aliases, plain=False)
    return [build_measurement(interval, info, aliases) for interval in intervals]


def _parse_text(
    path: str,
    decoded: DecodedText,
    delimiter: str | None,
    decimal: str | None,
    fmt: str | None,
    aliases: AliasTable,
    *,
    plain: bool,
) -> tuple[FileInfo, list[RawInterval]]:
    """Detect delimiter, format and decimal mark of a decoded text; find its intervals.

    ``plain``: the text has plain line ends; detection reads its first lines only, and
    the format reader gets its labelled lines as rows and its data lines as runs
    (``textio.scan_lines``). Raises :class:`NotSimple` where that could differ from the
    row-by-row parse of every line (``plain=False``).
    """
    text = decoded.text
    lines = head_lines(text, _HEAD_LINES) if plain else text.splitlines()
    delim = delimiter or detect_delimiter(lines)
    if delim is None:
        raise ReadError(
            "no cell delimiter (TAB, ';' or ',') found: not a table export",
            path=path,
            hint="pass --delimiter if the file uses another one",
        )
    if plain and not simple_quotes(text, delim):
        raise NotSimple
    rows = split_plain(lines, delim) if plain else split_cells(lines, delim, path)
    if fmt is None:
        found = next((r for r in _text_readers() if r.looks_like and r.looks_like(rows, aliases)),
                     None)
        if found is not None:
            fmt = found.name
        elif plain:
            raise NotSimple  # the header may lie past the first lines
        else:
            first = next((ln for ln in lines if ln.strip()), "")[:60]
            expects = [r.expects for r in _text_readers()]
            raise ReadError(
                f"not a recognised export (first line {first!r})",
                path=path,
                hint=f"expected {', '.join(expects[:-1])} or {expects[-1]}",
            )
    reader = next(r for r in _text_readers() if r.name == fmt)
    if decimal is None and delim == ",":
        decimal = "."
    elif decimal is None:
        cells = chain.from_iterable(row[1:] for _, row in rows[:300])
        sample = list(islice(filter(None, cells), 2000))  # the first 2000 non-empty cells
        decimal = detect_decimal(sample, default=reader.decimal)
    info = FileInfo(path, fmt, decoded.encoding, delim, decimal)
    assert reader.data_line is not None  # a text reader's
    items: list[Row | Run] = (
        scan_lines(text, delim, reader.data_line(delim)) if plain else list(rows)
    )
    return info, reader.parse(items, path, aliases)


#: bytes of a file's start that :func:`export_kind` looks at
_SNIFF_BYTES = 256 * 1024


def export_kind(path: str | PathLike[str], aliases: AliasTable | None = None) -> str | None:
    """What a file is when it is surely not an instrument export, from its first bytes,
    else ``None`` (an export, or maybe one: the reader decides).

    Not an export: a document, an image or an archive by its magic bytes ("a PDF
    document"), a binary file, an empty file, a text with no cell delimiter in its
    first lines (a note), or a text that no format recognises when the whole file was
    looked at. A file that cannot be opened is ``None`` too: the reader says why. Cheap
    (one read of at most 256 KiB): a campaign asks it of the files it is about to read
    and of those no label source describes, before it names their labels."""
    name = str(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read(_SNIFF_BYTES + 1)
    except OSError:
        return None
    whole = len(raw) <= _SNIFF_BYTES
    raw = raw[:_SNIFF_BYTES]
    if not raw.strip():
        return "an empty file"
    if raw.startswith(_OLE_MAGIC) or any(
            r.magic is not None and raw.startswith(r.magic) for r in READERS):
        return None
    kind = foreign_kind(raw, name)
    if kind is not None:
        return kind[0]
    try:
        decoded = decode(raw, name)
    except ReadError:
        return "a binary file" if whole else None
    lines = head_lines(decoded.text, _HEAD_LINES)
    delim = detect_delimiter(lines)
    if delim is None:
        return "a text with no table: no TAB, ';' or ',' between cells"
    rows = split_plain(lines, delim)
    table = aliases if aliases is not None else load_aliases(None)
    if any(r.looks_like and r.looks_like(rows, table) for r in _text_readers()):
        return None
    return "a text that no export format recognises" if whole else None


def read_export(
    path: str | PathLike[str],
    *,
    encoding: str | None = None,
    delimiter: str | None = None,
    decimal: str | None = None,
    fmt: str | None = None,
    aliases: AliasTable | str | PathLike[str] | None = None,
) -> list[Measurement]:
    """Read a raw export into one :class:`Measurement` per interval, in file order.

    Parameters
    ----------
    path
        The export (RheoCompass ``.csv``/``.txt``/``.xlsx``, Rheoplus ``.txt``/``.csv``, or
        a plain CSV with units in the header).
    encoding, delimiter, decimal
        Force the text encoding (``"utf-16"``, ``"cp1252"``…), the cell delimiter
        (``"\\t"``/``"tab"``, ``";"``, ``","``) or the decimal mark (``"."``, ``","``);
        ``None`` detects them.
    fmt
        Force the format, one of :data:`FORMATS`.
    aliases
        An :class:`AliasTable` or a user alias file extending the built-in names;
        ``None`` uses ``configs/aliases.toml`` in the working directory when it exists.

    Returns
    -------
    list of Measurement
        Never empty. Data columns are SI (``torque_Nm`` in N·m ...); invalid points and
        raw-waveform sub-rows are counted in ``meta``, not returned as rows.

    Raises
    ------
    ReadError
        For every problem of the file, as one line naming it (and line/column).
    """
    p = str(path)
    table = resolve_aliases(aliases)
    measurements = _read(p, encoding, delimiter, decimal, fmt, table)
    if not any(len(m.data) for m in measurements):
        raise ReadError(
            f"header without data: {len(measurements)} interval(s), no valid data point",
            path=p,
        )
    return measurements


@dataclass(frozen=True)
class ColumnSummary:
    """One column of an interval: its name and unit in the file and what it became."""

    original: str
    unit: str
    column: str | None


@dataclass(frozen=True)
class IntervalSummary:
    """What one interval holds."""

    test: str | None
    result: str | None
    interval: int | None
    n_points: int
    n_points_declared: int | None
    n_invalid_points: int
    n_waveform_rows: int
    header_line: int | None
    columns: tuple[ColumnSummary, ...]
    notes: tuple[tuple[str, str], ...]
    #: numeric cells that hold no finite value (empty, ``******``, NaN, ±inf)
    n_invalid_values: int = 0

    @property
    def friction_ready(self) -> bool:
        """True when the interval has what reduce needs: torque and normal force columns,
        or a friction-force column (a sled's normal force may come from its weight in the
        instrument file)."""
        names = {c.column for c in self.columns}
        return (TORQUE in names and NORMAL_FORCE in names) or FRICTION_FORCE in names


@dataclass(frozen=True)
class ExportSummary:
    """What an export holds, as :func:`read_export` reads it."""

    path: str
    file_format: str
    encoding: str | None
    delimiter: str | None
    decimal: str | None
    project: str | None
    intervals: tuple[IntervalSummary, ...]
    #: index in ``intervals`` of the interval a reduction would read (see describe_export)
    chosen: int | None = None
    #: indices of every interval a reduction reads (one run each), when it reads several
    chosen_all: tuple[int, ...] = ()
    #: why no interval would be chosen, when a chooser refused
    chosen_note: str | None = None

    @property
    def tests(self) -> tuple[str, ...]:
        """Distinct test names, in file order."""
        return tuple(dict.fromkeys(i.test for i in self.intervals if i.test))

    @property
    def results(self) -> tuple[tuple[str | None, str | None], ...]:
        """``(test, result)`` per result, in file order; a result ends where the names
        change or the interval numbering restarts (two tests may hold equal names)."""
        runs: list[tuple[str | None, str | None]] = []
        previous: IntervalSummary | None = None
        for i in self.intervals:
            key = (i.test, i.result)
            restarted = (
                previous is not None
                and i.interval is not None
                and previous.interval is not None
                and i.interval <= previous.interval
            )
            if previous is None or key != (previous.test, previous.result) or restarted:
                runs.append(key)
            previous = i
        return tuple(runs)

    @property
    def n_points(self) -> int:
        """Data points over all intervals (invalid points and waveform rows excluded)."""
        return sum(i.n_points for i in self.intervals)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict: file facts, counts and every interval with its columns."""
        return {
            "file": display_path(self.path),
            "format": self.file_format,
            "encoding": self.encoding,
            "delimiter": self.delimiter,
            "decimal": self.decimal,
            "project": self.project,
            "n_tests": len(self.tests),
            "n_results": len(self.results),
            "n_intervals": len(self.intervals),
            "n_points": self.n_points,
            "friction_interval": self.chosen,
            "friction_intervals": list(self.chosen_all or
                                       (() if self.chosen is None else (self.chosen,))),
            "friction_interval_note": self.chosen_note,
            "intervals": [
                {
                    "test": i.test,
                    "result": i.result,
                    "interval": i.interval,
                    "n_points": i.n_points,
                    "n_points_declared": i.n_points_declared,
                    "n_invalid_points": i.n_invalid_points,
                    "n_waveform_rows": i.n_waveform_rows,
                    "n_invalid_values": i.n_invalid_values,
                    "header_line": i.header_line,
                    "friction_ready": i.friction_ready,
                    "columns": [
                        {"original": c.original, "unit": c.unit, "column": c.column}
                        for c in i.columns
                    ],
                    "notes": dict(i.notes),
                }
                for i in self.intervals
            ],
        }

    def to_text(self) -> str:
        """A human-readable listing (what ``tribopipe inspect`` prints)."""
        delim = {"\t": "TAB", None: "-"}.get(self.delimiter, repr(self.delimiter))
        invalid = sum(i.n_invalid_points for i in self.intervals)
        values = sum(i.n_invalid_values for i in self.intervals)
        waveform = sum(i.n_waveform_rows for i in self.intervals)
        lines = [
            f"file:      {display_path(self.path)}",
            f"format:    {self.file_format}",
            f"encoding:  {self.encoding or '-'}   delimiter: {delim}   "
            f"decimal: {self.decimal or '-'}",
        ]
        if self.project:
            lines.append(f"project:   {self.project}")
        lines.append(
            f"contents:  {len(self.tests)} test(s), {len(self.results)} result(s), "
            f"{len(self.intervals)} interval(s), {self.n_points} point(s)"
            f" ({invalid} invalid, {waveform} waveform rows skipped;"
            f" {values} missing or invalid values)"
        )
        previous: tuple[ColumnSummary, ...] | None = None
        previous_notes: set[tuple[str, str]] = set()
        for i in self.intervals:
            label = interval_label(i.test, i.result, i.interval)
            declared = "" if i.n_points_declared is None else f" of {i.n_points_declared}"
            skipped = []
            if i.n_invalid_points:
                skipped.append(f"{i.n_invalid_points} invalid")
            if i.n_waveform_rows:
                skipped.append(f"{i.n_waveform_rows} waveform rows")
            if i.n_invalid_values:
                skipped.append(f"{i.n_invalid_values} missing or invalid values")
            names = {c.column for c in i.columns}
            ready = ("" if not i.friction_ready else "  [torque + normal force]"
                     if TORQUE in names else "  [friction force + normal force]"
                     if NORMAL_FORCE in names else "  [friction force]")
            lines.append("")
            lines.append(
                f"{label}: {i.n_points}{declared} points"
                f"{' (' + ', '.join(skipped) + ')' if skipped else ''}"
                f", header at line {i.header_line}{ready}"
            )
            for key, value in i.notes:
                if (key, value) not in previous_notes:
                    lines.append(f"  note: {key.replace('_', ' ')}: {value}")
            previous_notes = set(i.notes)
            if i.columns == previous:
                lines.append("  columns as above")
                continue
            previous = i.columns
            width = max((len(c.original) + len(c.unit) for c in i.columns), default=0) + 1
            for c in i.columns:
                shown = f"{c.original} {c.unit}".strip()
                lines.append(f"  {shown:<{width}} → {c.column or '(dropped)'}")
        if len(self.chosen_all) > 1:
            lines += ["", f"reduce reads {len(self.chosen_all)} runs:"]
            for k in self.chosen_all:
                i = self.intervals[k]
                lines.append(f"  {interval_label(i.test, i.result, i.interval)}")
        elif self.chosen is not None:
            i = self.intervals[self.chosen]
            lines += ["", f"reduce reads: {interval_label(i.test, i.result, i.interval)}"]
        elif self.chosen_note:
            lines += ["", f"reduce would stop: {self.chosen_note}"]
        return "\n".join(lines)


def _invalid_values(m: Measurement) -> int:
    """Numeric cells of ``m`` that hold no finite value (empty, ``******``, NaN, ±inf)."""
    import numpy as np

    total = 0
    for name in m.data.columns:
        values = m.data[name]
        if name != "point_no" and values.dtype.kind == "f":
            total += int((~np.isfinite(values.to_numpy())).sum())
    return total


def describe_export(
    path: str | PathLike[str],
    *,
    encoding: str | None = None,
    delimiter: str | None = None,
    decimal: str | None = None,
    fmt: str | None = None,
    aliases: AliasTable | str | PathLike[str] | None = None,
    choose: Callable[[Sequence[Measurement]], Measurement | Sequence[Measurement]]
    | None = None,
) -> ExportSummary:
    """Read an export (as :func:`read_export` does) and summarise what it holds: format,
    encoding, delimiter, decimal mark, tests, results, intervals, points and every column
    with its original unit and the column it maps to.

    ``choose`` (e.g. :func:`tribopipe.reduction.intervals.all_friction_intervals`) picks the
    interval(s) a reduction reads; its pick(s), or the one-line reason it refuses, go into
    the summary.
    """
    measurements = read_export(
        path, encoding=encoding, delimiter=delimiter, decimal=decimal, fmt=fmt, aliases=aliases
    )
    first = measurements[0].meta
    intervals = []
    for m in measurements:
        meta = m.meta
        mapped = dict.fromkeys(range(len(meta.original_columns)))
        targets = list(meta.column_map)
        k = 0
        for j, name in enumerate(meta.original_columns):
            if k < len(targets) and targets[k][0] == name:
                mapped[j] = targets[k][1]
                k += 1
        columns = tuple(
            ColumnSummary(name, meta.original_units[j], mapped[j])
            for j, name in enumerate(meta.original_columns)
        )
        intervals.append(
            IntervalSummary(
                test=meta.test,
                result=meta.result,
                interval=meta.interval,
                n_points=len(m.data),
                n_points_declared=meta.n_points_declared,
                n_invalid_points=meta.n_invalid_points,
                n_waveform_rows=meta.n_waveform_rows,
                header_line=meta.header_line,
                columns=columns,
                notes=meta.extra,
                n_invalid_values=_invalid_values(m),
            )
        )
    chosen_all: list[int] = []
    note: str | None = None
    if choose is not None:
        try:
            picked = choose(measurements)
        except TribopipeError as exc:
            note = exc.problem
        else:
            # the chooser may return copies with notes added to their meta: match the place
            places = {
                (m.meta.test, m.meta.result, m.meta.interval, m.meta.header_line)
                for m in ([picked] if isinstance(picked, Measurement) else picked)
            }
            chosen_all = [
                k for k, m in enumerate(measurements)
                if (m.meta.test, m.meta.result, m.meta.interval, m.meta.header_line) in places
            ]
    return ExportSummary(
        chosen=chosen_all[0] if chosen_all else None,
        chosen_all=tuple(chosen_all),
        chosen_note=note,
        path=str(Path(path)),
        file_format=first.file_format,
        encoding=first.encoding,
        delimiter=first.delimiter,
        decimal=first.decimal,
        project=first.project,
        intervals=tuple(intervals),
    )

"""An interval's data rows parsed column-wise by ``pyarrow.csv``: the reader's fast path.

For intervals whose data rows are runs of plain lines (``textio.Run``, at least
:data:`MIN_RUN` of them), :func:`arrow_cells` parses the runs with delimiter and decimal
mark given (runs of one layout in one call), and :class:`ArrowCells` answers what
:class:`~.cells.RowCells` answers — rows classified, ``******`` cells, thousands
separators and decimal commas converted column-wise with Arrow compute kernels, text
stripped — with no Python object per cell. Both round decimal strings correctly to the
nearest double, so the numbers are the same to the bit. Wherever the result could differ
from the row-by-row path (a cell that is not a plain number, a ``nan`` cell, an error to
report, a CR that ends no line ...) it raises :class:`~.textio.NotSimple` (or lets a
pyarrow error through, see ``textio.declines``), and the caller takes that path.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .aliases import AliasTable
from .cells import classify
from .interval import FileInfo, RawInterval
from .textio import NotSimple, Run, declines, plain_lines, split_cells

# the number patterns of ``textio._normalise_number`` in RE2 syntax; RE2's \d is ASCII
# only, so they match a subset of what Python's do (a cell they miss fails to convert
# and sends the interval to the general path)
_COMMA_THOUSANDS = r"^[-+]?[1-9]\d{0,2}(?:,\d{3})+(?:\.\d*)?(?:[eE][-+]?\d+)?$"
_DOT_THOUSANDS = r"^[-+]?[1-9]\d{0,2}(?:\.\d{3})+(?:,\d*)?(?:[eE][-+]?\d+)?$"
# a cell that may start with a letter once stripped (Rheoplus's "invalid point")
_MAYBE_WORD = r"^[^0-9+\-.*]"
#: what str.strip() removes from a cell (every character whose str.isspace() is true)
SPACES = (
    "\t\n\x0b\x0c\r\x1c\x1d\x1e\x1f \x85\xa0\u1680\u2000\u2001\u2002\u2003\u2004\u2005"
    "\u2006\u2007\u2008\u2009\u200a\u2028\u2029\u202f\u205f\u3000"
)


#: one run's columns, and the ``******`` masks of its number columns read as text
_Parsed = tuple[list[Any], dict[int, Any]]

#: the shortest run of data lines read column-wise; below it, row by row is cheaper
#: (measured crossover ~100-150 lines: a C parse and a DataFrame cost ~0.5 ms per interval)
MIN_RUN = 150


def arrow_cells(
    intervals: Sequence[RawInterval], info: FileInfo, aliases: AliasTable
) -> list[ArrowCells | None]:
    """The cells of every interval whose data rows are runs of plain lines (at least
    :data:`MIN_RUN` of them), read column-wise; ``None`` for the other intervals and
    wherever the fast path declines. Runs of one layout (cells per line and what each
    holds: RheoCompass's set-up and friction intervals) are parsed in one call."""
    out: list[ArrowCells | None] = [None] * len(intervals)
    groups: dict[tuple[str, int, tuple[str, ...]], list[tuple[int, Run]]] = {}
    for i, raw in enumerate(intervals):
        runs = [item for item in raw.rows if isinstance(item, Run)]
        if not runs or len(runs) != len(raw.rows):
            continue
        if sum(run.n_lines for run in runs) < MIN_RUN:
            continue
        try:
            layouts = {(run.delimiter, run.skip, tuple(_kinds(run, raw, aliases)))
                       for run in runs}
        except NotSimple:
            continue
        if len(layouts) == 1:
            groups.setdefault(layouts.pop(), []).extend((i, run) for run in runs)
    decimal = info.decimal or "."
    for (_, _, kinds), members in groups.items():
        parsed = _parse([run for _, run in members], list(kinds), decimal)
        pieces: dict[int, list[_Parsed | None]] = {}
        for (i, _), part in zip(members, parsed, strict=True):
            pieces.setdefault(i, []).append(part)
        for i, parts in pieces.items():
            complete = [part for part in parts if part is not None]
            if len(complete) != len(parts):
                continue
            try:
                out[i] = ArrowCells(*_joined(complete), list(kinds), intervals[i], decimal)
            except declines():
                pass
    return out


def _joined(parts: list[_Parsed]) -> _Parsed:
    """The columns and ``******`` masks of an interval's runs, one after the other."""
    import pyarrow as pa

    if len(parts) == 1:
        return parts[0]
    first_columns, first_stars = parts[0]
    for columns, stars in parts[1:]:  # runs parsed one by one may differ: no mixing
        if stars.keys() != first_stars.keys() or any(
                a.type != b.type for a, b in zip(columns, first_columns, strict=True)):
            raise NotSimple
    columns = [pa.chunked_array([chunk for part in parts for chunk in part[0][k].chunks],
                                type=parts[0][0][k].type)
               for k in range(len(parts[0][0]))]
    stars = {k: pa.chunked_array([chunk for part in parts for chunk in part[1][k].chunks])
             for k in parts[0][1]}
    return columns, stars


class ArrowCells:
    """The data rows of an interval held in one :class:`~.textio.Run`, parsed by
    ``pyarrow.csv`` (:func:`arrow_cells`): ``columns`` holds one Arrow column per cell of
    a line (text stripped; numbers as float64, or as text still to convert), ``stars``
    the ``******`` cells of number columns converted from text, ``kinds`` what each cell
    holds. Raises :class:`NotSimple` where the general path is needed."""

    def __init__(
        self,
        columns: list[Any],
        stars: dict[int, Any],
        kinds: list[str],
        raw: RawInterval,
        decimal: str,
    ) -> None:
        import pyarrow.compute as pc

        n_lines = len(columns[0])
        mask, self.n_invalid, self.n_waveform = _classify_arrow(columns, raw.point_col)
        self.n_rows = n_lines if mask is None else int(pc.sum(mask).as_py() or 0)
        if raw.n_declared is not None and self.n_rows + self.n_invalid < raw.n_declared:
            raise NotSimple  # truncated: the general path reports it
        if mask is not None:
            columns = [c.filter(mask) for c in columns]
            stars = {k: c.filter(mask) for k, c in stars.items()}
        if any(kind == "extra" and not _all_empty(c) for c, kind in zip(columns, kinds,
                                                                        strict=True)):
            raise NotSimple  # a cell past the header's columns: the general path reports it
        self.kinds, self.columns, self.decimal = kinds, columns, decimal
        self.is_missing = {k: int(pc.sum(c).as_py() or 0) for k, c in stars.items()}

    def point_numbers(self, j: int) -> NDArray[np.int64]:
        import pyarrow as pa
        import pyarrow.compute as pc

        return np.asarray(pc.cast(self.columns[j], pa.int64()).to_numpy(), dtype=np.int64)

    def is_empty(self, j: int) -> bool:
        return _all_empty(self.columns[j]) and not self.is_missing.get(j)

    def check_damage(self, j: int, name: str) -> None:
        import pyarrow as pa

        # every Excel error starts with "#"; numbers parsed as such hold none
        column = self.columns[j]
        if pa.types.is_string(column.type) and _column_holds(column, b"#"):
            raise NotSimple

    def numbers(self, j: int, name: str, textual: bool) -> NDArray[np.float64] | None:
        import pyarrow as pa
        import pyarrow.compute as pc

        if self.kinds[j] != "number":
            raise NotSimple  # text in a column other than Status: rare, take the rows
        values = self.columns[j]
        if pa.types.is_string(values.type):
            values, stars = _to_float(values, self.decimal)
            self.is_missing[j] = int(pc.sum(stars).as_py() or 0) if stars is not None else 0
        out = values.to_numpy()
        if np.count_nonzero(np.isnan(out)) != values.null_count:
            raise NotSimple  # a "nan" cell: its bits are Python's float() to decide
        return out

    def missing(self, j: int) -> int:
        return self.is_missing.get(j, 0)

    def strings(self, j: int) -> Any:
        import pandas as pd
        import pyarrow as pa

        # what pd.array(cells, dtype="string") holds: large_string in a StringDtype array
        return pd.arrays.ArrowStringArray(self.columns[j].cast(pa.large_string()))


def _kinds(run: Run, raw: RawInterval, aliases: AliasTable) -> list[str]:
    """What each cell of the run's lines holds (counted on its first line): ``"point"``
    (the point number), ``"number"``, ``"text"`` (a Status column) or ``"extra"`` (past
    the header's columns: must be empty). :class:`NotSimple` for rows shorter than the
    header."""
    first = _line_at(run.text, run.start, run.end)
    n_cells = len(split_cells([first], run.delimiter)[0][1]) - run.skip
    width = len(raw.names)
    if n_cells < width:
        raise NotSimple  # short rows: the general path names the line
    kinds = []
    for j in range(n_cells):
        if j >= width:
            kinds.append("extra")
        elif j == raw.point_col:
            kinds.append("point")
        elif aliases.base_name(raw.names[j]) == "status":
            kinds.append("text")
        else:
            kinds.append("number")
    return kinds


def _parse(runs: list[Run], kinds: list[str], decimal: str) -> Sequence[_Parsed | None]:
    """Every run's columns and ``******`` cells (``None`` for a run the C parser
    refuses): all runs in one parse, or one by one when that fails."""
    if len(runs) > 1:
        try:
            return _parse_together(runs, kinds, decimal)
        except declines():
            pass
    out: list[_Parsed | None] = []
    for run in runs:
        try:
            out += _parse_together([run], kinds, decimal)
        except declines():
            out.append(None)
    return out


def _parse_together(runs: list[Run], kinds: list[str], decimal: str) -> list[_Parsed]:
    """The runs' lines parsed in one ``pyarrow.csv`` call, cut back into runs. Number
    columns read as text are converted here when every cell of them converts (those of
    invalid points and waveform rows too: the conversion goes cell by cell, so the data
    rows' values are the same); else each interval converts its data rows."""
    import pyarrow as pa
    import pyarrow.compute as pc

    try:
        data = b"\n".join(run.utf8() for run in runs)
    except UnicodeEncodeError:  # a lone surrogate from an exotic forced encoding
        raise NotSimple from None
    limit = csv.field_size_limit()  # process-wide, and settable: read it each time
    if limit < _FIELD_LIMIT_MIN or not _lines_within(data, limit):
        raise NotSimple  # the csv module refuses a cell that long: let it say so
    # numbers parse as float64 in the C parser, unless a sample line shows a cell it
    # would refuse (******, 1,460, a decimal point in a decimal-comma file): such a
    # column is read as text and converted column-wise; when a refused cell shows up in
    # another column all the same, every column is read as text
    as_text = set().union(*(_text_columns(run, kinds, decimal) for run in runs))
    table = _read(data, runs[0], kinds, decimal, as_text)
    if table is None and len(as_text) < kinds.count("number"):
        table = _read(data, runs[0], kinds, decimal, set(range(len(kinds))))
    # a CR that ends no line is a line end to the C parser: one row more than lines
    if table is None or table.num_rows != sum(run.n_lines for run in runs):
        raise NotSimple
    columns, stars = [], {}
    for k, kind in enumerate(kinds):
        column = table.column(k)
        if pa.types.is_string(column.type):
            column = _strip(column, empty_is_null=kind == "number")
            if kind != "number":
                column = pc.fill_null(column, "")
            else:
                try:
                    column, starred = _to_float(column, decimal)
                except NotSimple:
                    pass
                else:
                    if starred is not None:
                        stars[k] = starred
        columns.append(column)
    out, offset = [], 0
    for run in runs:
        out.append(([column.slice(offset, run.n_lines) for column in columns],
                    {k: mask.slice(offset, run.n_lines) for k, mask in stars.items()}))
        offset += run.n_lines
    return out


#: below this limit of the csv module's cell size (default 131072), checking the lines
#: costs more than reading row by row
_FIELD_LIMIT_MIN = 65536


def _lines_within(data: bytes, limit: int) -> bool:
    """True when no line of ``data`` is ``limit`` bytes long or longer (a few ``find``
    calls: a line that long would hold one of the windows of ``limit // 2`` bytes the
    loop looks into, and none of them is free of a line end)."""
    step = limit // 2
    return all(data.find(b"\n", k, k + step) >= 0 for k in range(0, len(data) - step + 1, step))


def _text_columns(run: Run, kinds: list[str], decimal: str) -> set[int]:
    """The number columns to read as text: those whose cell in the first, middle or last
    line of the run holds ``*``, or the mark that is not the decimal mark."""
    text, start, end = run.text, run.start, run.end
    middle = text.find("\n", (start + end) // 2, end) + 1 or start
    last = text.rfind("\n", start, end) + 1 or start
    sample = [_line_at(text, line, end) for line in (start, middle, last)]
    alien = "," if decimal == "." else "."
    text_columns = set()
    for _, cells in split_cells(sample, run.delimiter):
        for k, cell in enumerate(cells[run.skip : run.skip + len(kinds)]):
            if kinds[k] == "number" and ("*" in cell or alien in cell):
                text_columns.add(k)
    return text_columns


def _line_at(text: str, start: int, end: int | None = None) -> str:
    """The line of ``text`` that starts at ``start`` (a plain line, see ``plain_lines``),
    not past ``end``."""
    end = len(text) if end is None else end
    stop = text.find("\n", start, end)
    return plain_lines(text[start : end if stop < 0 else stop])[0]


def _read(data: bytes, run: Run, kinds: list[str], decimal: str, as_text: set[int]) -> Any:
    """The run's UTF-8 bytes parsed by ``pyarrow.csv`` (the ``skip`` leading cells left
    out), or ``None`` when it does not parse (a row of another length, a cell that is not
    a number ...). Number columns not in ``as_text`` are float64 (empty cells null);
    other columns are text, empty cells null where some number column is text, else
    empty strings."""
    import pyarrow as pa
    import pyarrow.csv as pacsv

    names = [f"c{k}" for k in range(run.skip + len(kinds))]
    kept = names[run.skip :]
    types = {n: pa.float64() if kind == "number" and k not in as_text else pa.string()
             for k, (n, kind) in enumerate(zip(kept, kinds, strict=True))}
    try:
        return pacsv.read_csv(
            pa.py_buffer(data),
            read_options=pacsv.ReadOptions(column_names=names, use_threads=False,
                                           block_size=len(data) + 1),
            parse_options=pacsv.ParseOptions(
                delimiter=run.delimiter,
                quote_char='"' if b'"' in data else False,
                double_quote=True,
                newlines_in_values=False,
                ignore_empty_lines=False,
            ),
            convert_options=pacsv.ConvertOptions(
                column_types=types,
                include_columns=kept,
                null_values=[""],
                strings_can_be_null=bool(as_text),
                quoted_strings_can_be_null=True,
                decimal_point=decimal,
            ),
        )
    except (pa.ArrowInvalid, pa.ArrowNotImplementedError):
        return None


def _strip(column: Any, *, empty_is_null: bool) -> Any:
    """A text column with every cell stripped of white space, as the general path strips
    cells (``str.strip``); a cell stripped to nothing becomes null if ``empty_is_null``.
    A column of ASCII cells without a blank is returned as it is."""
    import pyarrow as pa
    import pyarrow.compute as pc

    if not any(_may_hold_blank(chunk) for chunk in column.chunks):
        return column
    column = pc.utf8_trim(column, characters=SPACES)
    if empty_is_null:
        column = pc.if_else(pc.equal(column, ""), pa.scalar(None, pa.string()), column)
    return column


def _may_hold_blank(chunk: Any) -> bool:
    """False when the cells of an Arrow string array are ASCII without a space, a TAB or a
    unit separator (the other ASCII white space ends a line, so no cell holds it); for
    other text, looking costs more than stripping (``utf8_trim``)."""
    raw = _text_bytes(chunk)
    return not raw.isascii() or any(blank in raw for blank in (b" ", b"\t", b"\x1f"))


def _holds(chunk: Any, needle: bytes) -> bool:
    """True when the text bytes of an Arrow string array hold ``needle``."""
    return needle in _text_bytes(chunk)


def _column_holds(column: Any, needle: bytes) -> bool:
    """True when some cell of an Arrow string column may hold ``needle`` (its bytes do)."""
    return any(_holds(chunk, needle) for chunk in column.chunks)


def _text_bytes(chunk: Any) -> bytes:
    """The UTF-8 bytes of an Arrow string array's cells, one after the other (possibly
    with those of cells sliced or filtered away: a superset)."""
    buffer = chunk.buffers()[2]
    return b"" if buffer is None else buffer.to_pybytes()


def _classify_arrow(columns: list[Any], point_col: int | None) -> tuple[Any, int, int]:
    """The data-row mask (``None``: every row), invalid points, waveform sub-rows.

    Point numbers of ASCII digits are data rows; every other point cell (rare) and a
    possible Rheoplus ``invalid point`` in the next cell are classified in Python by
    :func:`classify`, as the general path does."""
    import pyarrow as pa
    import pyarrow.compute as pc

    if point_col is None:
        return None, 0, 0
    points = columns[point_col]
    digits = pc.ascii_is_decimal(points)
    after = columns[point_col + 1] if point_col + 1 < len(columns) else None
    suspects = None
    if after is not None and pa.types.is_string(after.type):
        maybe_word = pc.fill_null(pc.match_substring_regex(after, _MAYBE_WORD), False)
        suspects = pc.and_(digits, maybe_word)
    if (pc.all(digits).as_py() and pc.max(pc.binary_length(points)).as_py() < 16
            and (suspects is None or not pc.any(suspects).as_py())):
        return None, 0, 0
    plain = pc.and_(digits, pc.less(pc.binary_length(points), 16))
    if suspects is not None:
        suspects = pc.and_(plain, suspects)
    keep = plain.to_numpy(zero_copy_only=False).astype(bool)
    invalid = waveform = 0
    for i in np.flatnonzero(~keep):
        kind = classify(points[int(i)].as_py(), "")
        if kind == "bad":  # not a point number: the general path names the line
            raise NotSimple
        if kind == "invalid":
            invalid += 1
        else:
            waveform += 1
    if suspects is not None and after is not None:
        for i in np.flatnonzero(suspects.to_numpy(zero_copy_only=False).astype(bool)):
            if classify(points[int(i)].as_py(), after[int(i)].as_py()) == "invalid":
                keep[i] = False
                invalid += 1
    return pa.array(keep), invalid, waveform


def _all_empty(column: Any) -> bool:
    """True when every cell of an Arrow column is null or empty text."""
    import pyarrow as pa
    import pyarrow.compute as pc

    if column.null_count == len(column):
        return True
    if not pa.types.is_string(column.type):
        return False
    return bool(pc.all(pc.equal(pc.fill_null(column, ""), "")).as_py())


def _to_float(column: Any, decimal: str) -> tuple[Any, Any]:
    """A text column (empty cells null) as float64 the way ``textio.to_numbers`` reads it
    (``******`` cells null, thousands separators dropped, a decimal comma made a point),
    and the mask of its ``******`` cells (``None``: none). :class:`NotSimple` when a cell
    still is not a plain number."""
    import pyarrow as pa
    import pyarrow.compute as pc

    only_stars = None
    if _column_holds(column, b"*"):
        only_stars = pc.fill_null(pc.equal(column, "******"), False)  # what Rheoplus writes
        stars = int(pc.sum(only_stars).as_py() or 0)
        values = len(column) - column.null_count
        if stars < values and stars != pc.sum(pc.match_substring(column, "*")).as_py():
            # stars in other numbers: a cell of stars only is still no value
            only_stars = pc.fill_null(pc.match_substring_regex(column, r"^\*+$"), False)
            stars = int(pc.sum(only_stars).as_py() or 0)
        if stars == values:  # no value at all in the column
            return pa.chunked_array([pa.nulls(len(column), pa.float64())]), only_stars
        if stars:
            column = pc.if_else(only_stars, pa.scalar(None, pa.string()), column)
    if decimal == ",":
        if _column_holds(column, b"."):
            grouped = pc.fill_null(pc.match_substring_regex(column, _DOT_THOUSANDS), False)
            column = pc.if_else(grouped, pc.replace_substring(column, ".", ""), column)
        column = pc.replace_substring(column, ",", ".")
    elif _column_holds(column, b","):
        # every cell with a comma must be grouped in thousands: else the cell is no
        # number, and leaving it whole lets the cast below refuse it
        commas = pc.sum(pc.match_substring(column, ",")).as_py()
        grouped = pc.match_substring_regex(column, _COMMA_THOUSANDS)
        if pc.sum(grouped).as_py() == commas:
            column = pc.replace_substring(column, ",", "")
        else:
            grouped = pc.fill_null(grouped, False)
            column = pc.if_else(grouped, pc.replace_substring(column, ",", ""), column)
    # a cell that is still no number makes the cast fail (slowly, but rarely)
    try:
        return pc.cast(column, pa.float64()), only_stars
    except pa.ArrowInvalid:
        raise NotSimple from None

"""Text-level I/O shared by the readers: encoding, delimiter and decimal-mark detection,
splitting into cells, and bulk conversion of a column of cells to numbers.

Every function here either returns a result or raises :class:`tribopipe.errors.ReadError`
naming the file (and line) and what was expected.
"""

from __future__ import annotations

import codecs
import csv
import functools
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from ..errors import ReadError
from ..files import read_regular

#: the largest export read [bytes] (hours of a test at 10 Hz are a few tens of MB)
MAX_EXPORT_BYTES = 512 * 1024 * 1024

#: delimiters we try, in order of preference (Anton Paar writes TAB)
DELIMITERS: tuple[str, ...] = ("\t", ";", ",")

_BOMS: tuple[tuple[bytes, str], ...] = (
    (codecs.BOM_UTF8, "utf-8-sig"),
    (codecs.BOM_UTF16_LE, "utf-16"),
    (codecs.BOM_UTF16_BE, "utf-16"),
)

# a number with a decimal point / comma, optionally in E notation
_DOT_DECIMAL = re.compile(r"^[-+]?\d*\.\d+(?:[eE][-+]?\d+)?$")
_COMMA_DECIMAL = re.compile(r"^[-+]?\d*,\d+(?:[eE][-+]?\d+)?$")
# thousands grouping: 1,460 or 9,945.692 (never 0,005, which is a decimal comma)
_COMMA_THOUSANDS = re.compile(r"^[-+]?[1-9]\d{0,2}(?:,\d{3})+(?:\.\d*)?(?:[eE][-+]?\d+)?$")
_DOT_THOUSANDS = re.compile(r"^[-+]?[1-9]\d{0,2}(?:\.\d{3})+(?:,\d*)?(?:[eE][-+]?\d+)?$")
_BOTH = re.compile(r"^[-+]?[\d.,]*\d(?:[eE][-+]?\d+)?$")

#: cells Excel writes when it could not evaluate a formula
EXCEL_ERRORS = frozenset({"#NAME?", "#VALUE!", "#DIV/0!", "#REF!", "#N/A", "#NUM!", "#NULL!"})


@dataclass(frozen=True)
class DecodedText:
    """A file's text and how it was decoded."""

    text: str
    encoding: str


def read_bytes(path: str) -> bytes:
    """A file's bytes; :class:`ReadError` for a missing, unreadable or empty file, and for
    anything that is not a regular file (refused before it is opened:
    :func:`tribopipe.files.read_regular`) or is larger than :data:`MAX_EXPORT_BYTES`."""
    try:
        raw = read_regular(path, max_bytes=MAX_EXPORT_BYTES, what="an export file")
    except ReadError as exc:
        if not os.path.isdir(path):
            raise
        raise ReadError(exc.problem, path=path,
                        hint="to reduce every export in a folder, run `tribopipe batch "
                             "FOLDER`") from None
    if not raw.strip():
        raise ReadError("empty file", path=path, hint="export the measurement again")
    kind = foreign_kind(raw, path)
    if kind is not None:
        what, hint = kind
        raise ReadError(f"is {what}, not an instrument export", path=path, hint=hint)
    return raw


_TABLE_HINT = ("export the test's data from the instrument software as a table "
               "(.csv, .txt) or an .xlsx workbook")
_ARCHIVE_HINT = "unpack it and reduce the exports inside (or pass their folder to batch)"
#: leading bytes of files that are never an export: (magic, what it is, hint)
_MAGIC: tuple[tuple[bytes, str, str], ...] = (
    (b"%PDF-", "a PDF document", _TABLE_HINT),
    (b"\x89PNG\r\n\x1a\n", "a PNG image", _TABLE_HINT),
    (b"\xff\xd8\xff", "a JPEG image", _TABLE_HINT),
    (b"GIF87a", "a GIF image", _TABLE_HINT),
    (b"GIF89a", "a GIF image", _TABLE_HINT),
    (b"II*\x00", "a TIFF image", _TABLE_HINT),
    (b"MM\x00*", "a TIFF image", _TABLE_HINT),
    (b"\x1f\x8b", "a gzip archive", _ARCHIVE_HINT),
    (b"7z\xbc\xaf\x27\x1c", "a 7-Zip archive", _ARCHIVE_HINT),
    (b"Rar!\x1a\x07", "a RAR archive", _ARCHIVE_HINT),
    (b"\xfd7zXZ\x00", "an xz archive", _ARCHIVE_HINT),
)


def foreign_kind(raw: bytes, name: str = "") -> tuple[str, str] | None:
    """``(what it is, hint)`` for bytes that are a document, an image or an archive by
    their magic bytes (a PDF, PNG, JPEG, GIF, TIFF; a ZIP that is not an Excel workbook,
    gzip, 7-Zip, RAR, xz, tar), ``None`` for anything else. A ZIP whose ``name`` ends
    in ``.xlsx`` is left to the workbook reader (a broken workbook is said as such)."""
    for magic, what, hint in _MAGIC:
        if raw.startswith(magic):
            return what, hint
    if raw.startswith(b"PK\x03\x04") and b"xl/" not in raw and \
            not name.lower().endswith((".xlsx", ".xlsm")):
        return "a ZIP archive (not an Excel workbook)", _ARCHIVE_HINT
    if raw[257:262] == b"ustar":
        return "a tar archive", _ARCHIVE_HINT
    return None


def _utf16_without_bom(raw: bytes) -> str | None:
    sample = raw[:4000]
    if len(sample) < 4:
        return None
    even, odd = sample[0::2], sample[1::2]
    if odd.count(0) > 0.4 * len(odd) and even.count(0) < 0.05 * len(even):
        return "utf-16-le"
    if even.count(0) > 0.4 * len(even) and odd.count(0) < 0.05 * len(odd):
        return "utf-16-be"
    return None


def decode(raw: bytes, path: str, encoding: str | None = None) -> DecodedText:
    """Decode an export's bytes.

    Without ``encoding``: a BOM decides (UTF-8, UTF-16), then UTF-16 without BOM, then
    strict UTF-8, then cp1252 (Windows programs re-saving exports), then Latin-1. Binary
    content (NUL bytes, control characters) is refused.
    """
    if encoding is not None:
        try:
            codecs.lookup(encoding)
        except LookupError:
            raise ReadError(
                f"unknown encoding {encoding!r}", path=path, hint="try utf-16, utf-8 or cp1252"
            ) from None
        try:
            text = _trim_utf16(raw, codecs.lookup(encoding).name).decode(encoding)
        except UnicodeDecodeError as exc:
            guess = _guess_encoding(raw)
            raise ReadError(
                f"cannot decode as {encoding} at byte {exc.start}",
                path=path,
                hint=f"the file looks {guess}; pass --encoding {guess}" if guess else None,
            ) from None
        text = text.removeprefix("\ufeff")
        _refuse_binary(text, path, forced=encoding)
        return DecodedText(text, encoding)
    detected = _detect(raw)
    if detected is None:
        raise ReadError(
            "binary file (NUL bytes), expected a text or Excel export", path=path
        )
    text = detected.text.removeprefix("\ufeff")
    _refuse_binary(text, path, forced=None)
    return DecodedText(text, detected.encoding)


def _detect(raw: bytes) -> DecodedText | None:
    """The bytes decoded with the detected encoding (decoded once), or ``None`` for binary
    data: a BOM decides, then UTF-16 without BOM, NUL bytes, strict UTF-8, cp1252, Latin-1."""
    for bom, name in _BOMS:
        if raw.startswith(bom):
            try:
                return DecodedText(_trim_utf16(raw, name).decode(name), name)
            except UnicodeDecodeError:
                return None
    utf16 = _utf16_without_bom(raw)
    if utf16 is not None:
        try:
            return DecodedText(_trim_utf16(raw, utf16).decode(utf16), utf16)
        except UnicodeDecodeError:
            return None
    if b"\x00" in raw:
        return None
    for name in ("utf-8", "cp1252"):
        try:
            return DecodedText(raw.decode(name), name)
        except UnicodeDecodeError:
            continue
    return DecodedText(raw.decode("latin-1"), "latin-1")


def _guess_encoding(raw: bytes) -> str | None:
    """The detected encoding name, or ``None`` for binary data."""
    detected = _detect(raw)
    return None if detected is None else detected.encoding


def _trim_utf16(raw: bytes, encoding: str) -> bytes:
    """A UTF-16 file cut after an odd number of bytes loses its half character, so that
    the reader can report the truncation itself (declared vs found points)."""
    if encoding.startswith("utf-16") and len(raw) % 2:
        return raw[:-1]
    return raw


def _count_control(text: str) -> int:
    """How many characters of ``text`` are control characters other than TAB, LF and
    CR (U+0000-U+0008, U+000B, U+000C, U+000E-U+001F) or U+FFFD (what a wrong decoding
    leaves), counted with numpy."""
    cp, _ = _code_units(text)
    control = (cp <= 8) | (cp == 11) | (cp == 12) | ((cp >= 14) & (cp <= 31)) | (cp == 0xFFFD)
    return int(np.count_nonzero(control))


def _refuse_binary(text: str, path: str, *, forced: str | None) -> None:
    sample = text[:20000]
    if not sample:
        raise ReadError("empty file", path=path)
    if "\x00" in sample or _count_control(sample) > 0.01 * len(sample):
        if forced:
            raise ReadError(
                f"decoding as {forced} gives binary garbage",
                path=path,
                hint="wrong encoding? leave --encoding out to detect it",
            )
        raise ReadError("binary file, expected a text or Excel export", path=path)


def detect_delimiter(lines: Sequence[str]) -> str | None:
    """The cell delimiter: the first of TAB, ';', ',' found on at least half of the first
    non-empty lines; ``None`` when no line has any of them."""
    sample = [ln for ln in lines[:200] if ln.strip()][:60]
    if not sample:
        return None
    for delim in DELIMITERS:
        if sum(delim in ln for ln in sample) >= 0.5 * len(sample):
            return delim
    for delim in DELIMITERS:
        if any(delim in ln for ln in sample):
            return delim
    return None


def split_plain(lines: Sequence[str], delimiter: str) -> list[Row]:
    """:func:`split_cells` for the lines of a plain text (no NUL, no CR; see
    :func:`plain_line_ends`), faster: a line without quotes is split with ``str.split``,
    and stripped only where it holds white space."""
    tab = delimiter == "\t"  # else a TAB in a line is white space to strip
    rows: list[Row] = []
    for number, line in enumerate(lines, start=1):
        if not line:
            rows.append((number, []))  # what the csv module gives for an empty line
        elif '"' in line:
            rows.append((number, split_cells([line], delimiter)[0][1]))
        elif (line.isascii() and " " not in line and "\x1f" not in line
              and (tab or "\t" not in line)):
            rows.append((number, line.split(delimiter)))
        else:
            rows.append((number, list(map(str.strip, line.split(delimiter)))))
    return rows


def split_cells(
    lines: Sequence[str], delimiter: str, path: str | None = None
) -> list[tuple[int, list[str]]]:
    """Split lines into stripped cells (double quotes honoured); each row comes with the
    1-based number of the line it starts on."""
    rows: list[tuple[int, list[str]]] = []
    reader = csv.reader(lines, delimiter=delimiter, quotechar='"', strict=False)
    start = 1
    try:
        for cells in reader:
            rows.append((start, list(map(str.strip, cells))))
            start = reader.line_num + 1
    except csv.Error as exc:
        raise ReadError(f"cannot split into cells: {exc}", path=path, line=start) from None
    return rows


# ------------------------------------------------------------------ lines and data runs
#
# A long export is a few labelled lines and long runs of data lines. Splitting every line
# into cells with the csv module costs one Python list per row and one str per cell; the
# scan below splits only the labelled lines and keeps each run of data lines as a slice of
# the decoded text, which a C parser reads in one call (``readers.arrowcells``). It applies to
# "plain" texts: lines end in LF or CRLF only, and every double quote encloses one whole
# cell on one line; there a line is a row, and the csv module and a C parser split a line
# into the same cells. A CR that ends no line is found where the line holding it is used
# (:func:`plain_lines`; the C parser sees one row more), and raises :class:`NotSimple`:
# the file is then read row by row as ``str.splitlines`` and the csv module split it.

#: characters besides CR and LF at which ``str.splitlines`` also ends a line
_OTHER_LINE_ENDS = ("\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\x85", "\u2028", "\u2029")

#: one row: its 1-based line number and its stripped cells
Row = tuple[int, list[str]]


class NotSimple(Exception):  # noqa: N818 - a signal between two paths, not an error
    """The fast path cannot vouch for an exact result here; take the row-by-row path."""


def declines(*also: type[Exception]) -> tuple[type[Exception], ...]:
    """What ends an attempt of the fast path (the caller then reads row by row):
    :class:`NotSimple`, and any error of pyarrow, which the fast path uses; ``also``
    the caller's own exception types (one tuple for an ``except`` clause)."""
    import pyarrow as pa

    return (*also, NotSimple, pa.ArrowException)


def plain_line_ends(text: str) -> bool:
    """True when ``text`` has no NUL and no line end other than LF and CR (a lone CR, one
    not before an LF, is only found line by line, see :func:`plain_lines`)."""
    return "\x00" not in text and not any(c in text for c in _OTHER_LINE_ENDS)


def plain_lines(block: str) -> list[str]:
    """The lines of a block of a plain text (LF or CRLF line ends), as ``str.splitlines``
    gives them; :class:`NotSimple` for a CR that ends no line."""
    return _without_cr(block.split("\n"))


def _without_cr(parts: list[str]) -> list[str]:
    """Lines split at LF, less the CR of a CRLF; :class:`NotSimple` for any other CR."""
    lines = [ln[:-1] if ln.endswith("\r") else ln for ln in parts]
    if "\r" in "".join(lines):
        raise NotSimple
    return lines


@functools.lru_cache(maxsize=8)
def _quoted_cell(delimiter: str) -> tuple[re.Pattern[str], re.Pattern[str]]:
    d = re.escape(delimiter)
    cell = rf'[^"\r\n]*"(?=[{d}\r\n]|$)'
    # the opening quote first, so that the search jumps from quote to quote
    return re.compile(rf'"(?<=[\n{d}]"){cell}'), re.compile(rf'"{cell}')


def simple_quotes(text: str, delimiter: str) -> bool:
    """True when every double quote of ``text`` opens or closes a whole cell on one line
    (``"ME-,taD"``), with no quote inside; then quoting never joins two lines."""
    if '"' not in text:
        return True
    n = text.count('"')
    inner, at_start = _quoted_cell(delimiter)
    found = len(inner.findall(text)) + (1 if at_start.match(text) else 0)
    return 2 * found == n


def head_lines(text: str, n: int) -> list[str]:
    """The first ``n`` lines of a plain text, as ``str.splitlines`` gives them
    (:class:`NotSimple` for a CR that ends no line)."""
    prefix = text[: 256 * n]  # mostly enough: splitting it copies no long tail
    parts = prefix.split("\n", n)
    if len(parts) <= n and len(prefix) < len(text):
        parts = text.split("\n", n)  # long lines: split the whole text
    if len(parts) > n:
        del parts[n:]
    elif parts and not parts[-1]:
        parts.pop()  # the text ends with a line end
    return _without_cr(parts)


#: a letter in any script (what a column name holds and a number does not)
_LETTER = re.compile(r"[^\W\d_]")


@dataclass(frozen=True)
class Run:
    """Consecutive data lines of a plain text, not yet split: ``n_lines`` lines from the
    1-based line ``first_line``, the slice ``text[start:end]`` (no line end after the last
    line). ``skip`` leading cells of every line belong to no column (RheoCompass's empty
    first cell)."""

    text: str = field(repr=False)
    start: int
    end: int
    first_line: int
    n_lines: int
    delimiter: str
    skip: int = 0
    #: the whole text in Latin-1, when every character fits (``None`` otherwise)
    narrow: bytes | None = field(default=None, repr=False, compare=False)

    def block(self) -> str:
        """The run's lines as one string (LF or CRLF between them)."""
        return self.text[self.start : self.end]

    def utf8(self) -> bytes:
        """:meth:`block` in UTF-8 (an ASCII run is cut from the Latin-1 text as it is)."""
        if self.narrow is not None:
            chunk = self.narrow[self.start : self.end]
            if chunk.isascii():
                return chunk
        return self.block().encode("utf-8")

    def check_line_ends(self) -> None:
        """:class:`NotSimple` when a CR in the run ends no line (for a run that is skipped,
        not parsed: a parse finds such a CR itself)."""
        block = self.block()
        if block.count("\r") != block.count("\r\n"):
            raise NotSimple

    def rows(self) -> list[Row]:
        """The run's lines split into stripped cells, each with its line number (what
        :func:`split_cells` gives for these lines), less the ``skip`` leading cells."""
        lines = plain_lines(self.block())
        offset = self.first_line - 1
        return [(offset + k, cells[self.skip :]) for k, cells in split_cells(lines, self.delimiter)]

    def lines_with_letters(self) -> list[Row]:
        """The run's lines that hold a letter, split as :meth:`rows` splits them: the
        only lines of a run that can name a column (a line of numbers names none)."""
        block = self.block()
        if not _LETTER.search(block):
            return []
        offset = self.first_line
        return [(offset + k, split_cells([line], self.delimiter)[0][1][self.skip :])
                for k, line in enumerate(plain_lines(block)) if _LETTER.search(line)]

    def split_at(self, line: int) -> tuple[Run | None, Row, Run | None]:
        """The run cut at its 1-based file line ``line``: the run of the lines before it
        (``None`` if none), that line as a row, the run of the lines after it."""
        k = line - self.first_line
        if not 0 <= k < self.n_lines:
            raise ValueError(f"line {line} is not in the run")
        start = self.start
        for _ in range(k):
            start = self.text.index("\n", start, self.end) + 1
        before = None
        if k:
            end = start - 1
            end -= self.text[end - 1] == "\r"
            before = replace(self, end=end, n_lines=k)
        row, after = replace(self, start=start, first_line=line,
                             n_lines=self.n_lines - k).split_first()
        return before, row, after

    def split_first(self) -> tuple[Row, Run | None]:
        """The first line as a row, and the run of the lines after it (``None`` if none)."""
        newline = self.text.find("\n", self.start, self.end)
        stop = self.end if newline < 0 else newline
        (line,) = plain_lines(self.text[self.start : stop])
        row = (self.first_line, split_cells([line], self.delimiter)[0][1][self.skip :])
        if newline < 0:
            return row, None
        rest = replace(self, start=newline + 1, first_line=self.first_line + 1,
                       n_lines=self.n_lines - 1)
        return row, rest


@dataclass(frozen=True)
class DataLine:
    """How a format's data lines start: with ``lead`` (exact text, maybe empty), then one
    of the characters of ``first`` (RheoCompass: the delimiter, then a digit)."""

    lead: str
    first: str


def scan_lines(text: str, delimiter: str, data_line: DataLine) -> list[Row | Run]:
    """A plain text (see :func:`plain_line_ends`, :func:`simple_quotes`) as rows and runs.

    Every maximal sequence of lines that start as ``data_line`` says becomes a
    :class:`Run`, every other line a row of stripped cells. Expanding the runs
    (:func:`expand_runs`) gives exactly ``split_cells(text.splitlines(), delimiter)``, or
    :class:`NotSimple` where a CR ends no line. The lines are found with numpy on the
    text's code points: no Python object per line.
    """
    units, narrow = _code_units(text)
    size = len(text)
    crs = np.flatnonzero(units == 13)
    if crs.size and (crs[-1] == size - 1 or (units[np.minimum(crs + 1, size - 1)] != 10).any()):
        raise NotSimple  # a CR that ends no line (not before an LF): str.splitlines's line
    ends = np.flatnonzero(units == 10)  # the LF of every line but maybe the last
    starts = np.concatenate(([0], ends + 1))
    if starts[-1] == size:  # the text ends with a line end: no line after it
        starts = starts[:-1]
    n_lines = len(starts)
    # the characters at each line's start (a line too short to hold them is no data line)
    lead, first = data_line.lead, data_line.first
    is_data = starts + len(lead) < size
    at = np.minimum(starts + len(lead), size - 1)
    is_data &= np.isin(units[at], [ord(c) for c in first])
    for k, c in enumerate(lead):
        is_data &= units[np.minimum(starts + k, size - 1)] == ord(c)

    def stop(i: int) -> int:  # where line i stops: at its LF, or at the end of the text
        return int(ends[i]) if i < len(ends) else size

    items: list[Row | Run | None] = []
    labelled: list[tuple[int, int, str]] = []  # (index in items, line number, text)
    done = 0  # the lines before this one are in items
    for i in [*np.flatnonzero(~is_data).tolist(), n_lines]:
        if i > done:  # the data lines before line i, less the last one's CR
            end = stop(i - 1)
            end -= units[end - 1] == 13
            items.append(Run(text, int(starts[done]), end, done + 1, i - done, delimiter,
                             narrow=narrow))
        if i == n_lines:
            break
        (line,) = plain_lines(text[int(starts[i]) : stop(i)])
        labelled.append((len(items), i + 1, line))
        items.append(None)
        done = i + 1
    rows = split_plain([line for _, _, line in labelled], delimiter)
    for (k, number, _), (_, cells) in zip(labelled, rows, strict=True):
        items[k] = (number, cells)
    return [item for item in items if item is not None]  # every None was filled above


def _code_units(
    text: str,
) -> tuple[NDArray[np.uint8] | NDArray[np.uint16] | NDArray[np.uint32], bytes | None]:
    """The code points of ``text`` as a numpy array, one per character, made without a
    Python object per character: the text encoded as Latin-1, UTF-16 or UTF-32, the
    narrowest that holds every character as one unit; and the Latin-1 bytes (``None``
    when a character is beyond U+00FF)."""
    if text.isascii():
        narrow = text.encode("ascii")
        return np.frombuffer(narrow, dtype=np.uint8), narrow
    try:
        narrow = text.encode("latin-1")
        return np.frombuffer(narrow, dtype=np.uint8), narrow
    except UnicodeEncodeError:
        pass
    wide = text.encode("utf-16-le", errors="surrogatepass")
    if len(wide) == 2 * len(text):  # no character beyond U+FFFF
        return np.frombuffer(wide, dtype="<u2"), None
    return np.frombuffer(text.encode("utf-32-le", errors="surrogatepass"), dtype="<u4"), None


def expand_runs(items: Sequence[Row | Run]) -> list[Row]:
    """Rows and runs as rows only (every run split into its lines' cells)."""
    rows: list[Row] = []
    for item in items:
        if isinstance(item, Run):
            rows.extend(item.rows())
        else:
            rows.append(item)
    return rows


def first_row(item: Row | Run) -> Row:
    """A row, or the first line of a run as a row."""
    return item.split_first()[0] if isinstance(item, Run) else item


def peel(items: list[Row | Run], i: int) -> Row:
    """Make ``items[i]`` a row: a run there is split into its first line and the rest.
    Returns that row."""
    item = items[i]
    if not isinstance(item, Run):
        return item
    row, rest = item.split_first()
    items[i : i + 1] = [row] if rest is None else [row, rest]
    return row


def detect_decimal(cells: Sequence[str], default: str = ".") -> str:
    """The decimal mark of numeric cells: ``","`` or ``"."``.

    Cells with both marks decide by the last mark (``9,945.692``); a comma followed by
    other than exactly three digits is a decimal comma (``2,3981``); ``1,460`` alone is
    ambiguous and leaves ``default``.
    """
    numeric = [c for c in cells if c and c[0] in "+-.0123456789,"]
    joined = "".join(numeric)
    # one mark only (the usual case): the first cell that reads as a number decides
    if "," not in joined:
        return "." if any(_DOT_DECIMAL.match(c) for c in numeric if "." in c) else default
    if "." not in joined:
        decimal_comma = (
            _COMMA_DECIMAL.match(c) and not _COMMA_THOUSANDS.match(c) for c in numeric
        )
        return "," if any(decimal_comma) else default
    dot = comma = 0
    ambiguous_dot = 0  # 2.398: a decimal point, or (rarely) a dotted thousands group
    for cell in numeric:
        has_dot, has_comma = "." in cell, "," in cell
        if has_dot and has_comma:
            if _BOTH.match(cell):
                if cell.rfind(",") > cell.rfind("."):
                    comma += 1
                else:
                    dot += 1
        elif has_dot:
            if _DOT_DECIMAL.match(cell):
                if _DOT_THOUSANDS.match(cell):
                    ambiguous_dot += 1
                else:
                    dot += 1
        elif has_comma:
            if _COMMA_DECIMAL.match(cell) and not _COMMA_THOUSANDS.match(cell):
                comma += 1
    if comma > dot:
        return ","
    if dot > comma:
        return "."
    if ambiguous_dot and not comma:
        # instrument software does not group thousands with dots: 2.398 is 2.398
        return "."
    return default


def _normalise_number(cell: str, decimal: str) -> str:
    if decimal == ".":
        if "," in cell and _COMMA_THOUSANDS.match(cell):
            return cell.replace(",", "")
        return cell
    if "." in cell and _DOT_THOUSANDS.match(cell):
        cell = cell.replace(".", "")
    return cell.replace(",", ".")


def is_missing(cell: str) -> bool:
    """True for an empty cell or Rheoplus's ``******`` (no value)."""
    return not cell or (cell[0] == "*" and cell.strip("*") == "")


def to_numbers(cells: Sequence[str], decimal: str) -> tuple[NDArray[np.float64], int | None]:
    """Convert cells to floats in bulk; empty and ``******`` cells become NaN.

    Returns ``(values, None)``, or ``(partial, i)`` where ``i`` is the index of the first
    cell that is not a number (the caller names it in its error).
    """
    joined = "".join(cells)
    if "*" in joined:
        # only cells made of stars are "no value"; "*5" stays an error below
        cells = ["" if c[:1] == "*" and is_missing(c) else c for c in cells]
    if decimal == "." and "," not in joined:
        cleaned = [c or "nan" for c in cells]
    elif decimal == ".":
        cleaned = [(_normalise_number(c, ".") if "," in c else c) or "nan" for c in cells]
    else:
        cleaned = [_normalise_number(c, decimal) or "nan" for c in cells]
    try:
        return np.array(cleaned, dtype=float), None
    except ValueError:
        pass
    for i, c in enumerate(cleaned):
        try:
            float(c)
        except ValueError:
            return np.full(len(cells), np.nan), i
    return np.full(len(cells), np.nan), 0  # pragma: no cover - numpy and float disagree


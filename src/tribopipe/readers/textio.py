"""Text-level I/O shared by the readers: encoding, delimiter and decimal-mark detection,
splitting into cells, and bulk conversion of a column of cells to numbers.

Every function here either returns a result or raises :class:`tribopipe.errors.ReadError`
naming the file (and line) and what was expected.
"""

from __future__ import annotations

import codecs
import csv
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ReadError

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

_CONTROL = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffd]")

#: cells Excel writes when it could not evaluate a formula
EXCEL_ERRORS = frozenset({"#NAME?", "#VALUE!", "#DIV/0!", "#REF!", "#N/A", "#NUM!", "#NULL!"})


@dataclass(frozen=True)
class DecodedText:
    """A file's text and how it was decoded."""

    text: str
    encoding: str


def read_bytes(path: str) -> bytes:
    """A file's bytes; :class:`ReadError` for a missing, unreadable or empty file."""
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except FileNotFoundError:
        raise ReadError("file not found", path=path) from None
    except IsADirectoryError:
        raise ReadError("is a directory, expected an export file", path=path) from None
    except OSError as exc:
        raise ReadError(f"cannot read file: {exc.strerror or exc}", path=path) from None
    if not raw.strip():
        raise ReadError("empty file", path=path, hint="export the measurement again")
    return raw


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
    guess = _guess_encoding(raw)
    if guess is None:
        raise ReadError(
            "binary file (NUL bytes), expected a text or Excel export", path=path
        )
    text = _trim_utf16(raw, guess).decode(guess, errors="strict").removeprefix("\ufeff")
    _refuse_binary(text, path, forced=None)
    return DecodedText(text, guess)


def _guess_encoding(raw: bytes) -> str | None:
    """The detected encoding name, or ``None`` for binary data."""
    for bom, name in _BOMS:
        if raw.startswith(bom):
            try:
                _trim_utf16(raw, name).decode(name)
            except UnicodeDecodeError:
                return None
            return name
    utf16 = _utf16_without_bom(raw)
    if utf16 is not None:
        try:
            _trim_utf16(raw, utf16).decode(utf16)
            return utf16
        except UnicodeDecodeError:
            return None
    if b"\x00" in raw:
        return None
    for name in ("utf-8", "cp1252"):
        try:
            raw.decode(name)
            return name
        except UnicodeDecodeError:
            continue
    return "latin-1"


def _trim_utf16(raw: bytes, encoding: str) -> bytes:
    """A UTF-16 file cut after an odd number of bytes loses its half character, so that
    the reader can report the truncation itself (declared vs found points)."""
    if encoding.startswith("utf-16") and len(raw) % 2:
        return raw[:-1]
    return raw


def _refuse_binary(text: str, path: str, *, forced: str | None) -> None:
    sample = text[:20000]
    if not sample:
        raise ReadError("empty file", path=path)
    control = len(_CONTROL.findall(sample))
    if "\x00" in sample or control > 0.01 * len(sample):
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
            rows.append((start, [c.strip() for c in cells]))
            start = reader.line_num + 1
    except csv.Error as exc:
        raise ReadError(f"cannot split into cells: {exc}", path=path, line=start) from None
    return rows


def detect_decimal(cells: Sequence[str], default: str = ".") -> str:
    """The decimal mark of numeric cells: ``","`` or ``"."``.

    Cells with both marks decide by the last mark (``9,945.692``); a comma followed by
    other than exactly three digits is a decimal comma (``2,3981``); ``1,460`` alone is
    ambiguous and leaves ``default``.
    """
    dot = comma = 0
    ambiguous_dot = 0  # 2.398: a decimal point, or (rarely) a dotted thousands group
    for cell in cells:
        if not cell or cell[0] not in "+-.0123456789,":
            continue
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


def to_numbers(cells: Sequence[str], decimal: str) -> tuple[np.ndarray, int | None]:
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


"""Text from outside written where it cannot become a formula, markup or a second line.

Anything a user or another lab hands us (file names, pin and disc names, cells, reasons)
may be hostile. Validation (:mod:`tribopipe.validate`) refuses what can never be a name;
the escapes here make the rest inert where it is written:

===================  ===========================================================================
:func:`printable`    one line for a message or a terminal: control and format characters
                     as Python escapes (``\\n``, ``\\x1b``, ``\\u202e``), undecodable bytes of
                     a file name as ``\\xff``
:func:`display_path` a path (``str``, ``bytes`` or path-like) as :func:`printable` text
:func:`csv_cell`     a text cell of a CSV a spreadsheet may open: the OWASP rule, a leading
                     ``'`` before ``=``, ``+``, ``-``, ``@``, TAB or CR (and before ``'``, so
                     :func:`csv_uncell` can undo it exactly)
:func:`markdown_cell` a Markdown table cell: ``\\``, ``|`` and backticks backslash-escaped,
                     ``<``, ``>`` and ``&`` as HTML entities, one line
===================  ===========================================================================

The HTML report and the explorer page escape with :mod:`html` and JSON, LaTeX with
:func:`tribopipe.export.tables.latex_escape`, simulator files with
:func:`tribopipe.export.simbase.safe_text`.
"""

from __future__ import annotations

import os
from typing import Any

#: first characters a spreadsheet reads as the start of a formula (OWASP, CSV injection)
FORMULA_TRIGGERS = frozenset("=+-@\t\r")
_QUOTE = "'"

_MARKDOWN = {
    "\\": "\\\\",
    "|": "\\|",
    "`": "\\`",
    "<": "&lt;",
    ">": "&gt;",
    "&": "&amp;",
    "\n": " ",
    "\r": " ",
}


def printable(text: str) -> str:
    """``text`` as one line of printable characters: every character Python does not call
    printable (controls, format characters such as U+202E, line and paragraph separators)
    becomes its escape (``\\n``, ``\\x1b``, ``\\u202e``), and a byte of a file name that was
    not valid UTF-8 (decoded by Python as a lone surrogate U+DC80–U+DCFF) becomes ``\\xNN``.
    Printable text, accents and symbols included, is returned unchanged."""
    if text.isprintable():
        return text
    out = []
    for ch in text:
        code = ord(ch)
        if ch.isprintable():
            out.append(ch)
        elif 0xDC80 <= code <= 0xDCFF:
            out.append(f"\\x{code - 0xDC00:02x}")
        else:
            out.append(repr(ch)[1:-1])
    return "".join(out)


def display_path(path: Any) -> str:
    """A path for a message: :func:`os.fsdecode` (bytes kept as escapes, never an
    encoding error), then :func:`printable`."""
    try:
        text = os.fsdecode(path)
    except TypeError:
        text = str(path)
    return printable(text)


def csv_cell(text: str) -> str:
    """A text cell for a CSV file: prefixed with ``'`` when it starts with a formula
    trigger (``=``, ``+``, ``-``, ``@``, TAB, CR) or with ``'`` itself. Spreadsheets show
    the cell as text without the quote; :func:`csv_uncell` undoes the prefix exactly."""
    if text and (text[0] in FORMULA_TRIGGERS or text[0] == _QUOTE):
        return _QUOTE + text
    return text


def csv_uncell(text: str) -> str:
    """The text a :func:`csv_cell` cell was made from (a cell that :func:`csv_cell` would
    not have written is returned unchanged)."""
    if len(text) >= 2 and text[0] == _QUOTE and (
        text[1] in FORMULA_TRIGGERS or text[1] == _QUOTE
    ):
        return text[1:]
    return text


def markdown_cell(text: str) -> str:
    """A Markdown table cell that stays one inert cell: ``\\``, ``|`` and backticks
    escaped, ``<``, ``>``, ``&`` as entities (no raw HTML), line breaks as spaces, then
    :func:`printable`."""
    return printable("".join(_MARKDOWN.get(ch, ch) for ch in text))

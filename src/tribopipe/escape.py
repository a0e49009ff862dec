"""Text from outside written where it cannot become a formula, markup, code or a second line.

Anything a user or another lab hands us (file names, pin and disc names, cells, reasons)
may be hostile. Validation (:mod:`tribopipe.validate`) refuses what can never be a name;
data and in-memory records keep the rest as it is (raw), and every writer makes it inert
at the point of writing with the one function of its output kind:

=======================  =====================================================================
output kind              function
=======================  =====================================================================
terminal line, message   :func:`printable` (a path: :func:`display_path`): control and
                         format characters as Python escapes (``\\n``, ``\\x1b``,
                         ``\\u202e``), undecodable bytes of a file name as ``\\xff``
CSV cell                 :func:`csv_cell`: one printable line, and the OWASP rule: a leading
                         ``'`` before ``=``, ``+``, ``-``, ``@``, TAB or CR (and before
                         ``'``, so :func:`csv_uncell` can undo it exactly)
Markdown cell or line    :func:`markdown_cell`: Markdown punctuation backslash-escaped
                         (``<`` and ``&`` too: no raw HTML, no entity), one printable line
HTML text or attribute   :func:`html_text`: one printable line with ``&``, ``<``, ``>``,
                         ``"`` and ``'`` as entities (inert in element text and in a quoted
                         attribute value)
JSON in an HTML page     :func:`script_json`: JSON that no ``</script>`` or ``<!--`` can
                         close, read back as the same data
YAML scalar              :func:`yaml_text`: a double-quoted scalar, read back unchanged
LaTeX table cell         :func:`latex_cell`: one printable line, LaTeX specials escaped,
                         beyond Latin-1 a code point (compiles in a default document)
simulator comment        :func:`sim_comment`: one line for a comment of the given syntax
                         (``**`` ABAQUS/CalculiX, ``$`` LS-DYNA, ``!`` Ansys MAPDL, ``#``
                         Python, ``<!--`` XML)
picture text             :func:`picture_text`: one printable line for a figure (Pillow or
                         matplotlib), ``$`` kept from starting mathtext
=======================  =====================================================================

Nothing else in the package escapes text for an output (a test holds every writer to
these functions). Names kept whole for a program to read back (a Python literal by
:func:`repr`, an XML attribute by :func:`xml.sax.saxutils.quoteattr`, a data package's
CSV) and identifiers made of letters and digits only are not escapes of this kind.
"""

from __future__ import annotations

import json
import os
import re
from typing import Any

#: first characters a spreadsheet reads as the start of a formula (OWASP, CSV injection)
FORMULA_TRIGGERS = frozenset("=+-@\t\r")
_QUOTE = "'"

#: Markdown: the ASCII punctuation that makes code, emphasis, links and images (``[``),
#: cells, math and strike-through, backslash-escaped (CommonMark shows an escaped
#: punctuation mark as itself), and so are ``<`` (no raw HTML, no autolink) and ``&`` (no
#: character reference): the text carries no HTML entity, and a reader of the Markdown
#: source sees ``range > r``. ``>`` makes markup only at the start of a line (a quote),
#: where a cell never is; ``_`` is left alone (GitHub never reads it as emphasis inside a
#: word, ``pressure_kPa``), and so are ``(``, ``#`` and ``!``, which make no markup
#: without an escaped ``[`` or a line start.
_MARKDOWN = {
    **{ch: "\\" + ch for ch in "\\`*[]|~$<&"},
    "\n": " ",
    "\r": " ",
}

_HTML = {"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#x27;"}

#: the characters that must not appear literally in JSON inside a <script> element, each
#: with its JSON escape (no escape holds a character of the table: replacing them one
#: after another is one translation)
_SCRIPT_JSON = (("<", "\\u003c"), (">", "\\u003e"), ("&", "\\u0026"), ("\u2028", "\\u2028"),
                ("\u2029", "\\u2029"))

_LATEX = {
    "\\": r"\textbackslash{}",
    "&": r"\&",
    "%": r"\%",
    "$": r"\$",
    "#": r"\#",
    "_": r"\_",
    "{": r"\{",
    "}": r"\}",
    "~": r"\textasciitilde{}",
    "^": r"\textasciicircum{}",
    # OT1, pdflatex's default font encoding, prints these two as ¡ and ¿ in text
    "<": r"\textless{}",
    ">": r"\textgreater{}",
    # the symbols of the tables' notes; other characters beyond Latin-1 have no glyph in
    # a default pdflatex document and are written as their code point (latex_cell)
    "μ": r"\ensuremath{\mu}",
    "±": r"\ensuremath{\pm}",
    "−": r"\ensuremath{-}",
    "°": r"\textdegree{}",
}

#: what YAML may hold literally in a quoted scalar, less NEL (U+0085, a line break in YAML 1.1)
_YAML_PRINTABLE = re.compile(
    "[^\t\n\r\x20-\x7e\xa0-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")

#: comment syntaxes of the simulator files (:func:`sim_comment`)
SIM_COMMENTS = ("**", "$", "!", "#", "<!--")


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
    """A text cell for a CSV file: one printable line (:func:`printable`), prefixed with
    ``'`` when it starts with a formula trigger (``=``, ``+``, ``-``, ``@``, TAB, CR) or
    with ``'`` itself. Spreadsheets show the cell as text without the quote;
    :func:`csv_uncell` undoes the prefix exactly."""
    text = printable(text)
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
    """Markdown text (a table cell, or a line after a fixed prefix) that stays inert:
    the punctuation that can make markup there (``\\``, ``|``, backticks, ``*``, ``[``,
    ``]``, ``~``, ``$``, ``<``, ``&``) backslash-escaped (no raw HTML, no entity), line
    breaks as spaces, then :func:`printable`."""
    return printable("".join(_MARKDOWN.get(ch, ch) for ch in text))


def html_text(text: str) -> str:
    """Text for an HTML page, in an element or in a quoted attribute value: one printable
    line (:func:`printable`: no bidi override reorders what follows) with ``&``, ``<``,
    ``>``, ``"`` and ``'`` as character references."""
    return "".join(_HTML.get(ch, ch) for ch in printable(text))


def script_json(data: Any) -> str:
    """``data`` as JSON text that is safe inside a ``<script>`` element.

    ``<``, ``>`` and ``&`` (so no ``</script>`` or ``<!--`` can appear) and the line
    separators U+2028/U+2029 are written as ``\\uXXXX`` escapes, which JSON reads back
    as the same characters. These characters can only occur inside JSON strings, so the
    document parses to ``data`` unchanged. NaN and infinities are refused (``None`` is
    the missing value).
    """
    text = json.dumps(data, ensure_ascii=False, allow_nan=False, separators=(",", ":"))
    for char, escaped in _SCRIPT_JSON:  # str.replace scans in C: a page of MB at once
        if char in text:
            text = text.replace(char, escaped)
    return text


def yaml_text(text: str) -> str:
    """``text`` as a YAML double-quoted scalar (``CITATION.cff``): JSON's escapes (valid
    YAML) plus ``\\uXXXX`` for what YAML does not allow literally or reads as a line
    break (C1 controls with NEL, U+2028/9, surrogates, U+FFFE/F); read back unchanged."""
    quoted = json.dumps(text, ensure_ascii=False)
    quoted = quoted.replace("\u2028", "\\u2028").replace("\u2029", "\\u2029")
    return _YAML_PRINTABLE.sub(lambda m: f"\\u{ord(m.group()):04x}", quoted)


def latex_cell(text: str) -> str:
    """Plain text for LaTeX (a ``tabular`` cell) that compiles in a default pdflatex
    document: one printable line (no blank line can end the row's paragraph), LaTeX's
    special characters escaped, ``<`` and ``>`` as the characters they are, μ ± − °
    as their LaTeX symbols, and any other character beyond Latin-1 written as its code
    point (``[U+4E2D]``) rather than one pdflatex has no glyph for."""
    return "".join(_LATEX.get(ch) or (ch if ord(ch) < 0x100 else f"[U+{ord(ch):04X}]")
                   for ch in printable(text))


def sim_comment(value: object, syntax: str = "#", *, ascii_only: bool = False) -> str:
    """``value`` as one line of inert text for a simulator file's comment of ``syntax``.

    Python's string escapes (``repr`` without the quotes) turn newlines, carriage
    returns, tabs, every other control or format character and the Unicode line
    separators into visible ``\\n``, ``\\x1b``, ``\\u2028`` …, so nothing leaves the
    comment's line. Per syntax: ``**`` (ABAQUS, CalculiX), ``$`` (LS-DYNA) and ``!``
    (Ansys MAPDL) are fixed-format ASCII decks, so every non-ASCII character is escaped
    too, and MAPDL's command separator ``$`` becomes ``\\x24`` in a ``!`` comment;
    ``<!--`` (XML) gets a space after every hyphen that precedes one (``--`` may not occur
    inside an XML comment); ``#`` (Python) keeps other text as it is. ``ascii_only``
    escapes every non-ASCII character in the other syntaxes too (files read as ASCII).
    """
    if syntax not in SIM_COMMENTS:
        raise ValueError(f"unknown comment syntax {syntax!r}; expected one of {SIM_COMMENTS}")
    text = str(value)
    escaped = (ascii(text) if ascii_only or syntax in ("**", "$", "!") else repr(text))[1:-1]
    # repr picks its quote character by content; what is inside is the text itself
    if syntax == "!":
        escaped = escaped.replace("$", "\\x24")
    elif syntax == "<!--":
        escaped = escaped.replace("--", "- -").replace("--", "- -")
    return escaped


def picture_text(text: str, *, mathtext: bool = True) -> str:
    """A text for a figure as one printable line (:func:`printable`): no newline or
    carriage return for the text layout (Pillow's raqm fails on them), no bidi override.
    With ``mathtext`` (a matplotlib text that parses ``$...$``, the default) every ``$``
    is written ``\\$``, which matplotlib shows as a dollar sign, so a name never starts
    mathtext (a lone ``$`` or ``$\\frac$`` would fail the whole plot); texts drawn as
    they are (``parse_math=False``, Pillow) pass ``mathtext=False``."""
    line = printable(text)
    return line.replace("$", "\\$") if mathtext else line

"""One escape per output kind (tribopipe.escape): a hostile name comes out inert in each.

Each test writes the same hostile names through its kind's function and reads the result
back as the program that opens that output would (a CSV reader, an HTML parser, YAML,
JSON, a figure), or checks what that program would act on.
"""

from __future__ import annotations

import csv
import io
import json
import re
from html.parser import HTMLParser
from pathlib import Path

import pandas as pd
import pytest
import yaml
from PIL import Image

from hostile import good_export, invoke
from tribopipe.escape import (
    FORMULA_TRIGGERS,
    SIM_COMMENTS,
    csv_cell,
    csv_uncell,
    display_path,
    html_text,
    latex_cell,
    markdown_cell,
    picture_text,
    printable,
    script_json,
    sim_comment,
    yaml_text,
)

#: names a user or another lab could hand us, one per trick
HOSTILE = [
    "steel\u202etxt.exe",                      # a bidi override reverses what follows
    "two\nlines",
    "cr\rreturn",
    "<script>alert(1)</script>",
    "=cmd|' /C calc'!A0",
    "+1+2",
    "-2+3",
    "@SUM(1)",
    "**HEADING",
    "*FRICTION",
    "back\\slash \\n",
    "`rm -rf /`",
    "$\\frac{a}{b}$ and a lone $",
    "a--b --> <!-- c",
    "x\x00y\x1b[31mred\u2028sep\u0085nel",
    "[x](javascript:alert(3)) ![i](http://e/i.png)",
    "'quoted' \"double\" & amp",
    "L" * 5000,
]


def _one_printable_line(text: str) -> None:
    assert text.isprintable(), repr(text[:80])


@pytest.mark.parametrize("name", HOSTILE)
def test_terminal_line(name: str) -> None:
    line = printable(name)
    _one_printable_line(line)
    assert printable(line) == line                          # idempotent on its output
    _one_printable_line(display_path(Path("/d") / name.replace("\x00", "")))


def test_terminal_line_keeps_printable_text_as_it_is() -> None:
    assert printable("Ecoflex 00-50 on steel · 20 °C") == "Ecoflex 00-50 on steel · 20 °C"


@pytest.mark.parametrize("name", HOSTILE)
def test_csv_cell(name: str) -> None:
    cell = csv_cell(name)
    _one_printable_line(cell)
    assert cell[0] not in FORMULA_TRIGGERS                  # no formula
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([cell, "next"])
    assert buf.getvalue().count("\n") == 1                  # one record
    (row,) = csv.reader(io.StringIO(buf.getvalue()))
    assert row == [cell, "next"] and csv_uncell(row[0]) == printable(name)


def test_csv_cell_undone_exactly_for_printable_text() -> None:
    for text in ("=1+1", "'quoted", "-3", "plain", ""):
        assert csv_uncell(csv_cell(text)) == text


@pytest.mark.parametrize("name", HOSTILE)
def test_markdown_cell(name: str) -> None:
    cell = markdown_cell(name)
    _one_printable_line(cell)
    for mark in "|`*[]$~<&":          # no cell break, code, emphasis, link, math, raw HTML,
        assert re.search(r"(?<!\\)(?:\\\\)*" + re.escape(mark), cell) is None  # reference


class _Parser(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[str] = []
        self.attrs: list[tuple[str, str | None]] = []
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        self.attrs += attrs

    def handle_data(self, data):
        self.text.append(data)

    def handle_comment(self, data):
        self.tags.append("!--")


@pytest.mark.parametrize("name", HOSTILE)
def test_html_text_and_attribute(name: str) -> None:
    escaped = html_text(name)
    _one_printable_line(escaped)
    parser = _Parser()
    parser.feed(f'<p title="{escaped}" data-x=\'{escaped}\'>{escaped}</p>')
    parser.close()
    assert parser.tags == ["p"]                             # no element, no comment
    assert parser.attrs == [("title", printable(name)), ("data-x", printable(name))]
    assert "".join(parser.text) == printable(name)


@pytest.mark.parametrize("name", HOSTILE)
def test_json_in_a_script_element(name: str) -> None:
    text = script_json({"file": name, "pin": [name]})
    assert "<" not in text and ">" not in text and "&" not in text
    assert "\u2028" not in text
    assert json.loads(text) == {"file": name, "pin": [name]}   # the same data back


@pytest.mark.parametrize("name", HOSTILE)
def test_yaml_scalar(name: str) -> None:
    assert yaml.safe_load(f"k: {yaml_text(name)}")["k"] == name


_LATEX_SPECIALS = set("\\&%$#_{}~^")


@pytest.mark.parametrize("name", HOSTILE)
def test_latex_cell(name: str) -> None:
    cell = latex_cell(name)
    _one_printable_line(cell)
    # every special character is escaped: strip the escapes, none may remain
    bare = re.sub(r"\\(textbackslash|textasciitilde|textasciicircum|textless|textgreater"
                  r"|textdegree)\{\}", "", cell)
    bare = re.sub(r"\\ensuremath\{\\(mu|pm|-)\}|\\ensuremath\{-\}", "", bare)
    bare = re.sub(r"\\[&%$#_{}]", "", bare)
    assert not (_LATEX_SPECIALS & set(bare)), cell


_OPENERS = {"**": "**", "$": "$", "!": "!", "#": "#", "<!--": "<!--"}


@pytest.mark.parametrize("syntax", SIM_COMMENTS)
@pytest.mark.parametrize("name", HOSTILE)
def test_simulator_comment(name: str, syntax: str) -> None:
    body = sim_comment(name, syntax)
    _one_printable_line(body)
    line = f"{_OPENERS[syntax]} pair: {body}" + (" -->" if syntax == "<!--" else "")
    assert len(line.splitlines()) == 1
    if syntax in ("**", "$", "!"):
        assert body.isascii()                                # fixed-format decks
    if syntax == "!":
        assert "$" not in body                               # MAPDL's command separator
    if syntax == "<!--":
        assert "--" not in body and "-->" not in body


def test_simulator_comment_refuses_an_unknown_syntax() -> None:
    with pytest.raises(ValueError, match="unknown comment syntax"):
        sim_comment("x", "//")


@pytest.mark.parametrize("name", HOSTILE)
def test_picture_text(name: str) -> None:
    from matplotlib.text import Text

    for mathtext in (True, False):
        text = picture_text(name, mathtext=mathtext)
        _one_printable_line(text)
    drawn = picture_text(name)
    assert not Text(text=drawn)._preprocess_math(drawn)[1]   # never mathtext
    assert Text(text=drawn)._preprocess_math(drawn)[0] == printable(name)


# ---------------------------------------------------------------------------- figures

PICTURE_NAMES = ("line\nbreak", "car\rriage", "rlo\u202e", "$\\frac{$", "L" * 400)


def _assert_png(data: bytes) -> None:
    with Image.open(io.BytesIO(data)) as image:
        image.verify()
    with Image.open(io.BytesIO(data)) as image:
        assert image.size[0] > 300 and len(image.getcolors(1 << 16) or []) > 10


@pytest.fixture(scope="module")
def hostile_reduced(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """A file named with LF, CR and U+202E, reduced with ``--plot`` through the CLI:
    (the export, the map, the output folder)."""
    root = tmp_path_factory.mktemp("picture")
    export = good_export(root / "a\nb\rc\u202ed.csv")
    map_path, out = root / "m.parquet", root / "out"
    result = invoke("reduce", str(export), "--pin", "DS30", "--disc", "steel", "--force", "3",
                    "--temperature", "20", "--plot", "--map", str(map_path),
                    "--output", str(out))
    assert result.exit_code == 0, result.output
    for line in result.output.splitlines():
        assert line.isprintable(), repr(line)
    return export, map_path, out


def test_reduce_plot_of_a_file_named_with_line_breaks_writes_a_png(hostile_reduced) -> None:
    _, map_path, out = hostile_reduced
    plots = list((out / "plots" / "traces").glob("*.png"))
    assert len(plots) == 1
    _assert_png(plots[0].read_bytes())
    assert list(pd.read_parquet(map_path)["source_file"]) == ["a\nb\rc\u202ed.csv"]


@pytest.mark.parametrize("name", PICTURE_NAMES)
def test_trace_plot_of_hostile_file_and_pin_names(hostile_reduced, name: str) -> None:
    from tribopipe.figures import plot_trace_row, trace_figure

    _, map_path, out = hostile_reduced
    from dataclasses import replace

    from tribopipe.frictionmap.schema import frame_rows
    from tribopipe.frictionmap.store import read_map

    row = replace(frame_rows(read_map(map_path))[0], source_file=name, pin=name, disc=name)
    trace = pd.read_parquet(next((out / "traces").glob("*.parquet")))
    for fmt in ("png", "svg"):
        buf = plot_trace_row(trace, row, io.BytesIO(), fmt=fmt)
        if fmt == "png":
            _assert_png(buf.getvalue())
    figure = trace_figure()
    assert figure.title.get_text().isprintable() and figure.conditions.get_text().isprintable()


def test_map_plots_of_hostile_names(hostile_reduced, tmp_path: Path) -> None:
    from dataclasses import replace

    from tribopipe.export.plots import plot_group_overlay, plot_pair
    from tribopipe.frictionmap.schema import frame_rows
    from tribopipe.frictionmap.store import read_map

    _, map_path, out = hostile_reduced
    runs = pd.read_parquet(map_path)
    trace = pd.read_parquet(next((out / "traces").glob("*.parquet")))
    for name in PICTURE_NAMES:
        row = replace(frame_rows(read_map(map_path))[0], measurement_id=name)
        _assert_png(plot_group_overlay([(row, trace)], io.BytesIO(), title=name,
                                       fmt="png").getvalue())
        pair = runs.assign(pin=name, disc=name)
        _assert_png(plot_pair(pair, name, name, io.BytesIO(), fmt="png").getvalue())


# ---------------------------------------------------------------------------- architecture

SRC = Path(__file__).resolve().parents[1] / "src" / "tribopipe"
#: characters whose replacement is escaping for some output kind
_ESCAPED = set("<>&`|$*\\\"'") | {chr(c) for c in range(32)} | {"\x7f", "\u2028", "\u2029"}
#: what an escape table maps to: entities, JSON/Python/LaTeX escapes
_ESCAPE_OUTPUT = re.compile(r"&(lt|gt|amp|quot|#x?[0-9a-f]+);|\\u00[0-9a-f]{2}|\\x[0-9a-f]{2}"
                            r"|\\text[a-z]+\{\}|^\\.$", re.IGNORECASE)
#: replacements that are not an output's escape, each with its reason
_NOT_ESCAPES = {
    ("campaign/metadata.py", "'\\\\'"),   # a Windows path separator read as '/'
    ("campaign/spec.py", "'\\\\'"),       # the same, in a filename pattern
    ("errors.py", "'\\n'"),               # a library's multi-line message joined, then printable
    ("units.py", repr("(?<=[A-Za-zµ])[·.*](?=[A-Za-z])")),  # 'N·m' read as 'Nm', no output
    ("synthetic.py", "'\"'"),           # test data: a vendor's CSV quoting, written by hand
}


def _escape_copies(path: Path) -> list[str]:
    import ast

    rel = path.relative_to(SRC).as_posix()
    found: list[str] = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        where = f"{rel}:{getattr(node, 'lineno', '?')}"
        if isinstance(node, ast.Import | ast.ImportFrom):
            modules = [a.name for a in node.names] + [getattr(node, "module", None) or ""]
            if any(m == "html" or m.startswith("html.") for m in modules):
                found.append(f"{where}: imports html (use tribopipe.escape.html_text)")
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and \
                node.func.attr in ("replace", "sub", "subn", "translate", "maketrans") and \
                node.args and isinstance(node.args[0], ast.Constant) and \
                isinstance(node.args[0].value, str):
            pattern = node.args[0].value
            if (set(pattern) & _ESCAPED or "\\x" in pattern or "\\u" in pattern) and \
                    (rel, repr(pattern)) not in _NOT_ESCAPES:
                found.append(f"{where}: {ast.unparse(node)[:80]}")
        elif isinstance(node, ast.Dict):
            values = [v.value for v in node.values
                      if isinstance(v, ast.Constant) and isinstance(v.value, str)]
            if sum(bool(_ESCAPE_OUTPUT.search(v)) for v in values) >= 2:
                found.append(f"{where}: an escape table")
        elif isinstance(node, ast.Subscript) and isinstance(node.value, ast.Call) and \
                isinstance(node.value.func, ast.Name) and \
                node.value.func.id in ("repr", "ascii") and \
                ast.unparse(node.slice) == "1:-1":
            found.append(f"{where}: {ast.unparse(node)} (a copy of printable/sim_comment)")
    return found


def test_writers_escape_only_through_the_escape_module() -> None:
    """No copy of an escape outside tribopipe.escape: no html module, no replacement of
    markup or control characters, no table of entities or escapes, no repr-slicing."""
    found = [hit for path in sorted(SRC.rglob("*.py")) if path.name != "escape.py"
             for hit in _escape_copies(path)]
    assert not found, "\n".join(found)


def test_the_escape_check_finds_a_copy(tmp_path: Path) -> None:
    """The check above fails on the kinds of copies the package once held."""
    copy = SRC / "_escape_copy_probe.py"
    assert not copy.exists()
    try:
        copy.write_text(
            "from html import escape\nimport re\n"
            "_LATEX = {'\\\\': r'\\textbackslash{}', '~': r'\\textasciitilde{}'}\n"
            "def md(t):\n    return re.sub(r'[\\x00-\\x1f]', ' ', t).replace('|', '\\\\|')\n"
            "def safe(t):\n    return repr(t)[1:-1]\n", encoding="utf-8")
        found = _escape_copies(copy)
    finally:
        copy.unlink()
    assert len(found) == 5, found

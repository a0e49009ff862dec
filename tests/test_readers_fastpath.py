"""The reader's two paths agree: the column-wise fast path (labelled lines scanned, data
lines parsed by pyarrow) gives exactly what the row-by-row path gives — the same tables to
the bit, the same metadata, the same one-line errors — on generated exports full of the
cells real exports hold and a few they should not; and the pieces the fast path is built
from keep the row-by-row semantics they stand in for."""

from __future__ import annotations

import csv
import re
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import tribopipe.readers as readers
from test_readers_golden import SYNTHETIC
from tribopipe.readers import arrowcells, common, read_export
from tribopipe.readers.textio import (
    DataLine,
    NotSimple,
    detect_decimal,
    expand_runs,
    plain_line_ends,
    scan_lines,
    simple_quotes,
    split_cells,
    split_plain,
)

SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])

#: cells as exports write them, and cells they should not hold
NUMBERS = ["0.1", "-2.5", "1e5", "2,21E+04", "0,005", "1,460", "9,945.692", "1.234,5",
           "20000.000", "3", "-0", ".5", "5.", "+7"]
ODD = ["", " ", "******", "*5", "#NAME?", "nan", "-nan", "inf", "1_000", "１２", " 1.5 ",
       "1.5\xa0", "x", '"a,b"', '"ME-,taD"', "Dy_auto", "M- ", "TruStrain™", "invalid point",
       "Invalid Point", "ınvalid point"]
POINTS = ["1", "2", "007", "3  (invalid)", "4  (invalide)", "", " 5", "7b",
          "99999999999999999999"]


def outcome(path: Path, **kwargs: object) -> tuple:
    """What read_export gives: the tables as comparable values (float bits, dtypes,
    metadata), or the error's class and message."""
    try:
        measurements = read_export(path, **kwargs)
    except Exception as exc:
        return ("error", type(exc).__name__, str(exc))
    tables = []
    for m in measurements:
        columns = []
        for name in m.data.columns:
            series = m.data[name]
            if isinstance(series.dtype, np.dtype):
                values = series.to_numpy().tobytes()
            else:
                values = (repr(series.dtype), tuple(series.array._pa_array.to_pylist()),
                          str(series.array._pa_array.type))
            columns.append((name, str(series.dtype), values))
        tables.append((columns, type(m.data.index).__name__, m.meta))
    return ("ok", tables)


def both_paths(path: Path, monkeypatch: pytest.MonkeyPatch, **kwargs: object) -> tuple:
    """The outcome of the fast path (every run read column-wise, however short) and of
    the row-by-row path."""
    with monkeypatch.context() as m:
        m.setattr(arrowcells, "MIN_RUN", 0)
        fast = outcome(path, **kwargs)
    with monkeypatch.context() as m:
        m.setattr(readers, "plain_line_ends", lambda text: False)
        rows = outcome(path, **kwargs)
    return fast, rows


def rheocompass_text(rows: list[list[str]], sep: str, *, unnamed: bool = False) -> str:
    """One interval; ``unnamed``: the third column has neither name nor unit."""
    names = ["Point No.", "Time", "", "Normal Force", "Status"] if unnamed else [
        "Point No.", "Time", "Torque", "Normal Force", "Status"]
    units = ["", "[s]", "", "[N]", ""] if unnamed else ["", "[s]", "[mN·m]", "[N]", ""]
    lines = ["Project:" + sep + "P", "", "Test:" + sep + "T", "",
             f"Interval and data points:{sep}1{sep}{len(rows)}",
             "Interval data:" + sep + sep.join(names), sep * len(names), sep + sep.join(units)]
    lines += [sep + sep.join(r) for r in rows]
    return "\r\n".join(lines) + "\r\n"


def rheoplus_text(rows: list[list[str]], sep: str) -> str:
    lines = ["Data Series Information", f"Name:{sep * 3}s1", f"Interval:{sep * 3}1",
             f"Number of Data Points:{sep * 3}{len(rows)}", "",
             sep.join(["Meas. Pts.", "Time", "Torque", "Normal Force", "Status"]),
             sep.join(["", "[s]", "[µNm]", "[N]", "[]"])]
    lines += [sep.join(r) for r in rows]
    return "\n".join(lines) + "\n"


def plain_text(rows: list[list[str]], sep: str) -> str:
    """A plain CSV with units in the header, a blank line after every seventh row."""
    lines = [sep.join(["Point No.", "Time [s]", "Torque [mN·m]", "Normal Force [N]",
                       "Status"])]
    for k, row in enumerate(rows):
        lines += [sep.join(row)] + ([""] if k % 7 == 6 else [])
    return "\n".join(lines) + "\n"


_row = st.tuples(
    st.sampled_from(POINTS[:3] * 6 + POINTS),
    st.sampled_from(NUMBERS * 3 + ODD),
    st.sampled_from(NUMBERS * 3 + ODD),
    st.sampled_from(NUMBERS * 3 + ODD),
    st.sampled_from(["Dy_auto", "", '"ME-,taD,TruStrain™"', "M- ", "#N/A"]),
).map(list)


@SETTINGS
@given(rows=st.lists(_row, min_size=1, max_size=40),
       layout=st.sampled_from(["rheocompass", "rheoplus", "plain"]),
       sep=st.sampled_from(["\t", ";", ","]),
       encoding=st.sampled_from(["utf-16", "utf-8", "cp1252"]),
       decimal=st.sampled_from([None, ".", ","]))
def test_fast_and_row_by_row_paths_agree_on_generated_exports(
    rows: list[list[str]], layout: str, sep: str, encoding: str, decimal: str | None
) -> None:
    write = {"rheocompass": rheocompass_text, "rheoplus": rheoplus_text, "plain": plain_text}
    text = write[layout](rows, sep)
    with tempfile.TemporaryDirectory() as tmp, pytest.MonkeyPatch.context() as mp:
        path = Path(tmp) / "run.csv"
        path.write_bytes(text.encode(encoding, errors="replace"))
        fast, slow = both_paths(path, mp, decimal=decimal)
    assert fast == slow


@pytest.mark.parametrize("layout", ["rheocompass", "rheocompass-unnamed", "rheoplus",
                                    "plain"])
@pytest.mark.parametrize("decimal", [None, ".", ","])
@pytest.mark.parametrize("column", [0, 1, 2, 4])
def test_fast_and_row_by_row_paths_agree_on_every_odd_cell(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, layout: str, decimal: str | None,
    column: int
) -> None:
    """Each odd cell, once in a column of plain rows: point number, the cell after it
    (where Rheoplus marks an invalid point), torque or a column without name and unit,
    status. In the unnamed column, also a run of ``******`` (a column of no values)."""
    def write(rows: list[list[str]]) -> bytes:
        if layout == "rheoplus":
            return rheoplus_text(rows, "\t").encode("utf-16")
        if layout == "plain":
            return plain_text(rows, ";").encode("utf-8")
        return rheocompass_text(rows, "\t", unnamed=layout.endswith("unnamed")).encode("utf-16")

    base = [[str(k), f"{k / 10:.1f}", f"{k * 0.37:.3f}", "3.0", "Dy_auto"] for k in range(1, 30)]
    values = POINTS + ODD[:5] if column == 0 else NUMBERS + ODD
    for k, value in enumerate(values):
        rows = [list(r) for r in base]
        rows[k % 20 + 3][column] = value
        path = tmp_path / f"{k}.txt"
        path.write_bytes(write(rows))
        fast, slow = both_paths(path, monkeypatch, decimal=decimal)
        assert fast == slow, value
    for value in ("******", "", " "):
        path = tmp_path / "column.txt"
        path.write_bytes(write([r[:column] + [value] + r[column + 1 :] for r in base]))
        fast, slow = both_paths(path, monkeypatch, decimal=decimal)
        assert fast == slow, value


@SETTINGS
@given(data=st.data(), name=st.sampled_from(["rheocompass_en_utf16_two_tests.csv",
                                              "rheocompass_resaved_cp1252.txt",
                                              "rheoplus_mcr302_stress_relaxation.txt",
                                              "rheoplus_after_excel_roundtrip.csv"]))
@pytest.mark.slow  # a real process or a larger data set: `pytest -m slow`
def test_fast_and_row_by_row_paths_agree_on_edited_real_exports(
    data_dir: Path, data: st.DataObject, name: str
) -> None:
    """Real exports with a few lines edited: a cell replaced, a line end changed into a
    lone CR or a CR CR LF, a line doubled."""
    raw = (data_dir / name).read_bytes()
    encoding = "utf-16" if raw.startswith(b"\xff\xfe") else "cp1252"
    lines = raw.decode(encoding).split("\n")
    for _ in range(data.draw(st.integers(1, 3))):
        k = data.draw(st.integers(0, len(lines) - 1))
        action = data.draw(st.sampled_from(["cell", "cr", "crcr", "double", "quote"]))
        if action == "cell":
            sep = "," if name.endswith("roundtrip.csv") else "\t"
            cells_ = lines[k].split(sep)
            cells_[data.draw(st.integers(0, len(cells_) - 1))] = data.draw(
                st.sampled_from(NUMBERS + ODD + POINTS))
            lines[k] = sep.join(cells_)
        elif action == "cr":
            lines[k] = lines[k].removesuffix("\r") + "\r" + lines[k]
        elif action == "crcr":
            lines[k] += "\r"
        elif action == "double":
            lines.insert(k, lines[k])
        else:
            lines[k] = '"' + lines[k]
    with tempfile.TemporaryDirectory() as tmp, pytest.MonkeyPatch.context() as mp:
        path = Path(tmp) / name
        path.write_bytes("\n".join(lines).encode(encoding, errors="replace"))
        fast, slow = both_paths(path, mp)
    assert fast == slow


def test_a_header_whose_first_cell_is_a_number_is_the_header_on_both_paths(
    data_dir: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The case hypothesis found: the Rheoplus Excel round-trip with its first cell made a
    number ('Meas. Pts.' -> '0.1'). Line 1 still names time, torque, temperature ... and is
    the header on both paths (the fast path once took the header block's table at line
    92, dropping the first table)."""
    lines = (data_dir / "rheoplus_after_excel_roundtrip.csv").read_bytes().decode(
        "cp1252").split("\n")
    assert lines[0].startswith("Meas. Pts.,Time,")
    lines[0] = "0.1" + lines[0].removeprefix("Meas. Pts.")
    path = tmp_path / "edited.csv"
    path.write_bytes("\n".join(lines).encode("cp1252"))
    fast, slow = both_paths(path, monkeypatch)
    assert fast == slow
    assert fast[0] == "ok"
    (columns, _, meta), = fast[1]
    assert meta.header_line == 1
    assert meta.original_columns[:3] == ("0.1", "Time", "Storage Modulus")
    assert "header_block_lines" not in dict(meta.extra)


# --------------------------------------------------------------------------- the pieces

_TEXT_CELLS = st.sampled_from(["", "a", "1,5", " x ", '"q"', '"a\tb"', '""', "\t", ";",
                               '"', "1.5", "\xa0", "Interval data:", "\r", "™", "😀", "\n"])


@SETTINGS
@given(lines=st.lists(st.lists(_TEXT_CELLS, max_size=5), max_size=20),
       sep=st.sampled_from(["\t", ";", ","]),
       ending=st.sampled_from(["\n", "\r\n"]),
       data_line=st.sampled_from([DataLine("\t", "0123456789"), DataLine("", "0123456789"),
                                  DataLine("", "-+.0123456789"), DataLine("", "a"),
                                  DataLine(";", "1a")]))
# a data run holding CR + CRLF: two lines for str.splitlines, so the fast scan declines
@example(lines=[["1,5", "\r"], []], sep="\t", ending="\r\n",
         data_line=DataLine("", "0123456789"))
def test_scanned_lines_expand_to_the_rows_of_every_line(
    lines: list[list[str]], sep: str, ending: str, data_line: DataLine
) -> None:
    text = ending.join(sep.join(cells_) for cells_ in lines)
    if not (plain_line_ends(text) and simple_quotes(text, sep)):
        return
    want = split_cells(text.splitlines(), sep)
    try:
        got = expand_runs(scan_lines(text, sep, data_line))
    except NotSimple:
        assert "\r" in text.replace("\r\n", "")  # only a CR that ends no line declines
        return
    assert got == want


@SETTINGS
@given(lines=st.lists(st.lists(st.sampled_from(["1", "2,5", "-3", "1e5", "x", "Time [s]",
                                                 "Torque", "\xa0", "µ", ""]),
                               min_size=1, max_size=4).map(lambda c: ["7", *c]),
                      min_size=1, max_size=8),
       ending=st.sampled_from(["\n", "\r\n"]), cut=st.integers(0, 7))
def test_a_run_cut_at_a_line_keeps_every_row(lines: list[list[str]], ending: str,
                                             cut: int) -> None:
    """``Run.split_at`` (the header search cutting a run of data lines) gives back the
    run's rows, and ``Run.lines_with_letters`` the rows of the lines holding a letter."""
    text = ending.join(";".join(cells_) for cells_ in lines)
    (run,) = scan_lines(text, ";", DataLine("", "7"))
    rows = run.rows()
    assert run.lines_with_letters() == [
        r for r, line in zip(rows, text.split(ending), strict=True)
        if any(ch.isalpha() for ch in line)]
    line = run.first_line + cut % run.n_lines
    before, row, after = run.split_at(line)
    got = (before.rows() if before else []) + [row] + (after.rows() if after else [])
    assert got == rows
    assert row[0] == line


@SETTINGS
@given(line=st.text(alphabet=list('ab1,;\t "\x1f\xa0\u2003é'), max_size=12),
       sep=st.sampled_from(["\t", ";", ","]))
def test_plain_lines_split_as_the_csv_module_splits_them(line: str, sep: str) -> None:
    assert split_plain([line], sep) == split_cells([line], sep)


def test_quoted_cells_are_simple_only_when_whole_and_on_one_line() -> None:
    assert simple_quotes('a,"b,c",d\r\n"e",f', ",")
    assert simple_quotes("no quotes", ",")
    assert not simple_quotes('a,"b\nc",d', ",")  # a cell over two lines
    assert not simple_quotes('a,x"b",d', ",")  # a quote inside a cell
    assert not simple_quotes('a,"b""c",d', ",")  # a doubled quote


def test_white_space_stripped_from_cells_is_what_str_strip_removes() -> None:
    spaces = "".join(chr(c) for c in range(sys.maxunicode + 1) if chr(c).isspace())
    assert arrowcells.SPACES == spaces


@pytest.mark.parametrize("size", [0, 10, 65535, 65536, 131071, 131072, 200000])
def test_the_longest_line_check_never_lets_a_too_long_line_through(size: int) -> None:
    limit = 131072
    for data in (b"x" * size, b"ab\n" + b"x" * size + b"\ncd", (b"y" * 100 + b"\n") * 3000):
        longest = max(len(part) for part in data.split(b"\n"))
        if arrowcells._lines_within(data, limit):
            assert longest < limit


def _decimal_by_counting(cells_: list[str], default: str) -> str:
    """The decimal-mark rule counted over every cell (what detect_decimal shortens)."""
    dot_decimal = re.compile(r"^[-+]?\d*\.\d+(?:[eE][-+]?\d+)?$")
    comma_decimal = re.compile(r"^[-+]?\d*,\d+(?:[eE][-+]?\d+)?$")
    comma_thousands = re.compile(r"^[-+]?[1-9]\d{0,2}(?:,\d{3})+(?:\.\d*)?(?:[eE][-+]?\d+)?$")
    dot_thousands = re.compile(r"^[-+]?[1-9]\d{0,2}(?:\.\d{3})+(?:,\d*)?(?:[eE][-+]?\d+)?$")
    both = re.compile(r"^[-+]?[\d.,]*\d(?:[eE][-+]?\d+)?$")
    dot = comma = ambiguous = 0
    for cell in cells_:
        if not cell or cell[0] not in "+-.0123456789,":
            continue
        if "." in cell and "," in cell:
            if both.match(cell):
                comma += cell.rfind(",") > cell.rfind(".")
                dot += cell.rfind(",") < cell.rfind(".")
        elif "." in cell and dot_decimal.match(cell):
            ambiguous += bool(dot_thousands.match(cell))
            dot += not dot_thousands.match(cell)
        elif "," in cell and comma_decimal.match(cell) and not comma_thousands.match(cell):
            comma += 1
    if comma != dot:
        return "," if comma > dot else "."
    return "." if ambiguous and not comma else default


@SETTINGS
@given(cells_=st.lists(st.sampled_from(NUMBERS + ODD + ["Point No.", "2.398", "12,5.3"]),
                       max_size=30),
       default=st.sampled_from([".", ","]))
def test_decimal_mark_detection_gives_what_counting_every_cell_gives(
    cells_: list[str], default: str
) -> None:
    assert detect_decimal(cells_, default) == _decimal_by_counting(cells_, default)


#: which path builds each interval of the golden synthetic exports: column-wise ("fast")
#: for long runs of plain data lines, row by row for short ones (< MIN_RUN lines), for a
#: table with raw-waveform sub-rows among its lines, and for a "nan" cell
PATHS = {
    "en_utf16.csv": ["rows", "fast"],
    "fr_utf16.csv": ["rows", "rows"],
    "utf8_comma.csv": ["rows", "fast"],
    "cp1252_resaved.txt": ["rows", "fast"],
    "nan_cell.csv": ["rows", "rows"],
    "rheoplus.txt": ["fast", "fast"],
    "rheoplus_excel.csv": ["fast", "fast"],
    "plain_semicolon.csv": ["fast"],
    "plain_units.csv": ["fast"],
    "short.csv": ["rows", "rows"],
    "padded_number.csv": ["rows", "fast"],
    "thousands_in_torque.csv": ["rows", "fast"],
}


@pytest.mark.parametrize("name", list(PATHS))
def test_long_plain_runs_take_the_fast_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, name: str
) -> None:
    """The fast path really builds the long intervals (else the tests above would compare
    the row-by-row path with itself), with ******, thousands separators, quoted status
    cells, Rheoplus's invalid points and blank lines in a plain CSV."""
    built: list[str] = []
    original = common._measurement

    def spy(*args: object) -> object:
        result = original(*args)
        built.append("fast" if isinstance(args[-1], arrowcells.ArrowCells) else "rows")
        return result

    monkeypatch.setattr(common, "_measurement", spy)
    read_export(SYNTHETIC[name](tmp_path / name))
    assert built == PATHS[name]


def test_a_cell_longer_than_the_csv_modules_limit_is_refused_on_both_paths(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The csv module's cell-size limit is process-wide and settable; the fast path reads
    it each time and leaves a line that long to the csv module, which refuses it."""
    rows = [[str(k), f"{k / 10:.1f}", "1.5", "3.0", "Dy_auto"] for k in range(1, 300)]
    rows[200][4] = "x" * 100_000
    path = tmp_path / "long.csv"
    path.write_bytes(rheocompass_text(rows, "\t").encode("utf-16"))
    limit = csv.field_size_limit()
    try:
        csv.field_size_limit(70_000)
        fast, slow = both_paths(path, monkeypatch)
    finally:
        csv.field_size_limit(limit)
    assert fast == slow
    assert fast[0] == "error" and "field larger than field limit" in fast[2]

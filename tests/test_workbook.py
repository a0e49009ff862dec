"""Spreadsheets: `map table --format xlsx` (one sheet per layout, numbers as numbers,
units in the heads, a notes sheet) read back with openpyxl, and a CSV for decimal-comma
locales (';' between cells, ',' in numbers) read back as such a locale reads it."""

from __future__ import annotations

import io
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner
from openpyxl import load_workbook

from published_map import PUBLISHED_CSV, published_runs, write_published_map
from tribopipe.cli import main
from tribopipe.export.tables import PAPER_NOTE, render_table
from tribopipe.export.workbook import unit_head, workbook_bytes

FORMULA = '=HYPERLINK("http://x.example","click")'


@pytest.fixture(scope="module")
def runs() -> pd.DataFrame:
    return published_runs(PUBLISHED_CSV)


@pytest.fixture(scope="module")
def map_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_published_map(PUBLISHED_CSV,
                               tmp_path_factory.mktemp("map") / "friction_map.parquet")


def _book(data: bytes):
    return load_workbook(io.BytesIO(data))


def test_one_sheet_per_layout_and_notes(runs) -> None:
    book = _book(workbook_bytes(runs, source="m.parquet"))
    assert book.sheetnames == ["paper", "group", "abstract", "notes"]
    notes = {row[0].value: row[1].value for row in book["notes"].iter_rows()}
    assert notes["source"] == "m.parquet" and notes["± U"] == PAPER_NOTE
    assert notes["by"].startswith("tribopipe ")
    assert {"flag range > r", "flag stated u", "sheet paper"} <= set(notes)


def test_numbers_are_numbers_shown_as_rounded(runs) -> None:
    book = _book(workbook_bytes(runs, source="m.parquet", disc=["steel"]))
    paper = book["paper"]
    heads = [c.value for c in paper[1]]
    assert heads[:5] == ["pin", "disc", "pressure [kPa]", "temperature [°C]", "n"]
    assert "μ_K" in heads and "U of μ_K (k = 2)" in heads
    text = pd.read_csv(io.StringIO(render_table(runs, fmt="csv", layout="paper",
                                                disc=["steel"])), dtype=str,
                       keep_default_na=False)
    k, u = heads.index("μ_K") + 1, heads.index("U of μ_K (k = 2)") + 1
    for r, (value, expanded) in enumerate(zip(text["mu_k"], text["mu_k_U"], strict=True),
                                          start=2):
        cell = paper.cell(row=r, column=k)
        assert isinstance(cell.value, float) and cell.value == float(value)
        decimals = len(value.split(".")[1]) if "." in value else 0
        assert cell.number_format == ("0." + "0" * decimals if decimals else "0")
        if expanded:
            assert paper.cell(row=r, column=u).value == float(expanded)
    group = book["group"]
    gheads = [c.value for c in group[1]]
    assert "pressure [kPa]" in gheads and "temperature [°C]" in gheads
    col = gheads.index("mu_k_mean") + 1
    assert all(isinstance(group.cell(row=r, column=col).value, float)
               for r in range(2, group.max_row + 1))
    abstract = book["abstract"]
    assert abstract.cell(row=2, column=5).number_format == "0.00"


def test_a_name_that_looks_like_a_formula_stays_text(runs) -> None:
    hostile = runs.copy()
    hostile["pin"] = hostile["pin"].where(hostile["pin"] != "Dragonskin 30", FORMULA + "\x1b")
    book = _book(workbook_bytes(hostile, source="m.parquet"))
    cells = [c for row in book["paper"].iter_rows(min_row=2) for c in row[:1]]
    odd = [c for c in cells if str(c.value).startswith("=HYPERLINK")]
    assert odd and all(c.data_type == "s" for c in odd)
    assert all("\x1b" not in str(c.value) for c in odd)


def test_unit_heads() -> None:
    assert unit_head("pressure_kPa") == "pressure [kPa]"
    assert unit_head("nominal_speed_mm_s") == "nominal speed [mm/s]"
    assert unit_head("normal_force_N") == "normal force [N]"
    assert unit_head("mu_k_mean") == "mu_k_mean"


def test_the_cli_writes_xlsx_and_asks_for_a_file(map_path: Path, tmp_path: Path) -> None:
    out = tmp_path / "map.xlsx"
    done = CliRunner().invoke(main, ["map", "table", "--format", "xlsx", "--map", str(map_path),
                                     "-o", str(out)])
    assert done.exit_code == 0, done.output
    assert _book(out.read_bytes()).sheetnames[0] == "paper"
    refused = CliRunner().invoke(main, ["map", "table", "--format", "xlsx", "--map",
                                        str(map_path)])
    assert refused.exit_code == 2 and "give -o FILE.xlsx" in refused.stderr


@pytest.mark.parametrize("layout", ["paper", "group"])
def test_a_decimal_comma_csv_reads_back_in_its_locale(runs, layout: str) -> None:
    dot = render_table(runs, fmt="csv", layout=layout)
    comma = render_table(runs, fmt="csv", layout=layout, decimal=",")
    assert comma.splitlines()[0] == dot.splitlines()[0].replace(",", ";")
    a = pd.read_csv(io.StringIO(dot), dtype=str, keep_default_na=False)
    b = pd.read_csv(io.StringIO(comma), sep=";", dtype=str, keep_default_na=False)
    assert list(a.columns) == list(b.columns)
    def number(v: str) -> bool:
        try:
            float(v)
        except ValueError:
            return v == ""
        return True

    numeric = [c for c in a.columns if all(number(v) for v in a[c])]
    assert "mu_k" in numeric or "mu_k_mean" in numeric
    for column in numeric:
        assert list(b[column]) == [v.replace(".", ",") for v in a[column]], column
    assert list(b["pin"]) == list(a["pin"])
    # as a decimal-comma locale reads it: the same numbers
    c = pd.read_csv(io.StringIO(comma), sep=";", decimal=",")
    d = pd.read_csv(io.StringIO(dot))
    if layout == "group":
        pd.testing.assert_series_equal(c["mu_k_mean"], d["mu_k_mean"])
    else:
        assert list(c["mu_k"]) == list(d["mu_k"])


def test_a_decimal_comma_is_for_csv(runs) -> None:
    from tribopipe.errors import ExportError

    with pytest.raises(ExportError, match="a decimal comma is for --format csv"):
        render_table(runs, fmt="markdown", decimal=",")

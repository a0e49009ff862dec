"""Names stay data in every output, through the real command line.

A name that is one printable line passes every edge (validation refuses the rest: a
newline through ``--pin``, a manifest cell, ``[names]``, ``map import`` or ``map merge`` is
refused in one line — see test_hostile_inputs and test_hostile_map). Such a name may still
be hostile: a spreadsheet formula, HTML, Markdown, a simulator keyword, Python. Here it
reaches the map through ``tribopipe batch`` (via ``[names]``) and ``tribopipe reduce``, and
every output is read back as the program that opens it would read it.
"""

from __future__ import annotations

import csv
import io
import json
import re
from dataclasses import replace
from pathlib import Path

import pytest

from hostile import GOOD_RUN, good_export, invoke
from sim_files import (
    lsdyna_contact,
    mujoco_pair,
    parse_abaqus,
    parse_ansys,
    pyelastica_values,
    sofa_response,
)
from tribopipe.escape import FORMULA_TRIGGERS, latex_cell

PIN = ('=HYPERLINK("http://evil","x") <script>alert(1)</script> | `rm -rf` & *HEADING '
       '$ import os; os.system("id") -- </pair>')
DISC = "@SUM(1+1)*cmd|' /C calc'!A0 <img src=x onerror=alert(2)>"
PLUS = "+1+2 -- [x](javascript:alert(3))"


@pytest.fixture(scope="module")
def campaign(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A campaign whose [names] turn short names in file names into hostile full names;
    batch-reduced, so its map, runs.csv and outputs hold them."""
    root = tmp_path_factory.mktemp("injection")
    raw = root / "raw"
    raw.mkdir()
    for i, (short, force) in enumerate((("P1_D1", 3), ("P1_D1", 9), ("P2_D1", 3))):
        for repeat in (1, 2):
            run = replace(GOOD_RUN, normal_force_N=float(force), seed=100 + 10 * i + repeat)
            good_export(raw / f"{short}_{force}N_20C_r{repeat}.csv", run)
    cfg = root / "c.toml"
    cfg.write_text(
        '[campaign]\nname = "injection"\nraw_dir = "raw"\noutput_dir = "out"\n'
        'filename_pattern = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"\nplots = false\n'
        f"[names]\nP1 = {json.dumps(PIN)}\nP2 = {json.dumps(PLUS)}\nD1 = {json.dumps(DISC)}\n",
        encoding="utf-8")
    # a hostile lab's materials file names them (an unknown name refuses the campaign)
    (root / "materials.toml").write_text(
        "[materials]\n" + "".join(f'{json.dumps(n)} = {{ class = "other" }}\n'
                                   for n in (PIN, PLUS, DISC)), encoding="utf-8")
    result = invoke("batch", str(cfg), "--jobs", "1")
    assert result.exit_code == 0, result.output
    return cfg


def _map(campaign: Path) -> str:
    return str(campaign.parent / "out" / "friction_map.parquet")


def _text_cells_are_safe(text: str) -> list[list[str]]:
    rows = list(csv.reader(io.StringIO(text)))
    for row in rows[1:]:
        for cell in row:
            if cell and cell[0] in FORMULA_TRIGGERS:
                # a number may start with '-' or '+'; text never does
                float(cell)
    return rows


def test_runs_csv_holds_no_formula(campaign: Path) -> None:
    text = (campaign.parent / "out" / "runs.csv").read_text(encoding="utf-8")
    rows = _text_cells_are_safe(text)
    column = rows[0].index("pin")
    pins = {row[column] for row in rows[1:]}
    assert pins == {"'" + PIN, "'" + PLUS}


@pytest.mark.parametrize("fmt", ["csv", "frictionmap"])
def test_map_tables_as_csv_hold_no_formula(campaign: Path, fmt: str) -> None:
    result = invoke("map", "table", "--format", fmt, "--map", _map(campaign))
    assert result.exit_code == 0, result.output
    rows = _text_cells_are_safe(result.stdout)
    header = rows[0]
    pins = {row[header.index("pin")] for row in rows[1:]}
    assert pins == {"'" + PIN, "'" + PLUS}
    assert {row[header.index("disc")] for row in rows[1:]} == {"'" + DISC}


def test_markdown_table_cells_stay_cells(campaign: Path) -> None:
    result = invoke("map", "table", "--format", "markdown", "--map", _map(campaign))
    assert result.exit_code == 0, result.output
    text = result.stdout
    assert re.search(r"(?<!\\)<", text) is None            # every < escaped: no raw HTML
    assert re.search(r"(?<!\\)`", text) is None           # every backtick escaped
    assert "\\<script>" in text and "&lt;" not in text
    lines = text.splitlines()
    width = len(re.findall(r"(?<!\\)\|", lines[0]))
    assert all(len(re.findall(r"(?<!\\)\|", ln)) == width for ln in lines)


def test_latex_table_escapes_the_names(campaign: Path) -> None:
    result = invoke("map", "table", "--format", "latex", "--map", _map(campaign))
    assert result.exit_code == 0, result.output
    assert latex_cell(PIN) in result.stdout
    lines = result.stdout.splitlines()
    columns = lines[lines.index("\\toprule") + 1].count(" & ")
    body = [ln for ln in result.stdout.splitlines() if ln.endswith("\\\\")]
    assert all(ln.count(" & ") == columns for ln in body)


def test_fe_decks_read_back_strictly(campaign: Path) -> None:
    abaqus = invoke("export", "abaqus", "--map", _map(campaign))
    assert abaqus.exit_code == 0, abaqus.output
    interactions = parse_abaqus(abaqus.stdout)           # comments, keywords, numbers only
    assert len(interactions) == 2
    assert all(name.replace("_", "").isalnum() for name in interactions)
    ansys = invoke("export", "ansys", "--map", _map(campaign))
    assert ansys.exit_code == 0, ansys.output
    assert len(parse_ansys(ansys.stdout)) == 2


@pytest.mark.parametrize("fmt", ["lsdyna", "mujoco", "sofa", "pyelastica"])
def test_single_condition_files_read_back_strictly(campaign: Path, fmt: str) -> None:
    result = invoke("export", fmt, "--map", _map(campaign), "--pin", PIN, "--disc", DISC,
                    "--pressure", "35.37", "--temperature", "20")
    assert result.exit_code == 0, result.output
    text = result.stdout
    if fmt == "lsdyna":
        assert 0.3 < lsdyna_contact(text)["fd"] < 0.8
    elif fmt == "mujoco":
        assert mujoco_pair(text) is not None
    elif fmt == "sofa":
        assert sofa_response(text) is not None
    else:
        assert pyelastica_values(text)["PAIR"] == (PIN, DISC)   # a literal, never code


def test_explorer_page_and_report_keep_names_as_text(campaign: Path, tmp_path: Path) -> None:
    page = tmp_path / "explorer.html"
    assert invoke("explore", "--map", _map(campaign), "-o", str(page)).exit_code == 0
    report = tmp_path / "report.html"
    result = invoke("report", str(campaign), "-o", str(report))
    assert result.exit_code == 0, result.output
    for html in (page.read_text(encoding="utf-8"), report.read_text(encoding="utf-8")):
        assert "<script>alert(1)" not in html and "<img src=x" not in html


def test_reduce_labels_reach_the_map_as_data(tmp_path: Path) -> None:
    export = good_export(tmp_path / "run.csv")
    map_path = tmp_path / "m.parquet"
    lab = tmp_path / "materials.toml"  # a hostile lab's materials file names them
    lab.write_text("[materials]\n" + "".join(f'{json.dumps(n)} = {{ class = "other" }}\n'
                                             for n in (PIN, DISC)), encoding="utf-8")
    result = invoke("reduce", str(export), "--pin", PIN, "--disc", DISC, "--force", "3",
                    "--temperature", "20", "--materials", str(lab), "--map", str(map_path),
                    "--output", str(tmp_path / "o"))
    assert result.exit_code == 0, result.output
    table = invoke("map", "table", "--format", "frictionmap", "--map", str(map_path)).stdout
    assert _text_cells_are_safe(table)[1][:2] == ["'" + PIN, "'" + DISC]

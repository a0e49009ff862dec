"""``tribopipe map``: import, merge, table, show, exclude, include, run as a user would
(click's CliRunner, and real processes for the installed entry point)."""

from __future__ import annotations

import io
import subprocess
import sys

import pandas as pd
import pytest
from click.testing import CliRunner

from conftest import shared_file
from map_files import map_bytes
from test_frictionmap import run_record
from tribopipe import frictionmap as fm
from tribopipe.cli import main


def invoke(*args: str):
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


@pytest.fixture()
def published_map(tmp_path):
    path = tmp_path / "processed" / "friction_map.parquet"
    result = invoke("map", "import", "--published", "--map", str(path))
    assert result.exit_code == 0, result.output
    return path


def test_import_published_then_again_changes_nothing(published_map):
    assert len(fm.read_map(published_map)) == 169
    before = map_bytes(published_map)
    again = invoke("map", "import", "--published", "--map", str(published_map))
    assert again.exit_code == 0
    assert "0 added, 169 unchanged" in again.output
    assert map_bytes(published_map) == before


def test_import_the_mat_file_into_a_map_holding_the_csv_rows(published_map):
    mat = shared_file("reference", "FrictionMap.mat")
    result = invoke("map", "import", str(mat), "--map", str(published_map))
    assert result.exit_code == 0 and "0 added, 169 unchanged" in result.output


def test_import_needs_exactly_one_of_file_or_published(tmp_path):
    result = CliRunner().invoke(main, ["map", "import", "--map", str(tmp_path / "m.parquet")])
    assert result.exit_code == 2 and "give a FILE or --published" in result.output


def test_a_bad_csv_is_one_line_naming_file_line_and_column(tmp_path):
    bad = tmp_path / "lab.csv"
    bad.write_text("pin,disc,contactForce,contactPressure,temperature,measurementNo,cof\n"
                   "Ecoflex 00-50,steel,3,35.37,20,1,zero\n")
    map_path = tmp_path / "m.parquet"
    result = CliRunner().invoke(main, ["map", "import", str(bad), "--map", str(map_path)])
    assert result.exit_code == 1
    assert f"Error: {bad}:2: 'zero' is not a finite number (column 'cof')" in result.output
    assert "Traceback" not in result.output and not map_path.exists()


def test_table_group_csv_reproduces_the_published_group_means(published_map):
    result = invoke("map", "table", "--map", str(published_map))
    assert result.exit_code == 0
    groups = pd.read_csv(io.StringIO(result.output))
    assert len(groups) == 76 and "pressure_kPa" in groups.columns
    steel = groups[(groups["pin"] == "Dragonskin 30") & (groups["disc"] == "steel")
                   & (groups["temperature_C"] == 20)]
    assert steel["mu_k_mean"].round(2).tolist() == [0.63, 0.45, 0.36, 0.30, 0.26]


def test_table_abstract_markdown_with_filters_to_a_file(published_map, tmp_path):
    out = tmp_path / "tables" / "steel.md"
    result = invoke("map", "table", "--map", str(published_map), "--format", "markdown",
                    "--layout", "abstract", "--pin", "Dragonskin 30", "--disc", "steel",
                    "--temperature", "20", "-o", str(out))
    assert result.exit_code == 0
    lines = out.read_text().splitlines()
    assert lines[0] == "| pin | disc | pressure_kPa | temperature_C | mu_k |"
    assert [line.split("|")[-2].strip() for line in lines[2:]] == [
        "0.63", "0.45", "0.36", "0.30", "0.26"
    ]


def test_table_frictionmap_is_the_published_schema(published_map):
    result = invoke("map", "table", "--map", str(published_map), "--format", "frictionmap")
    assert result.output == fm.published.published_csv_path().read_text()


def test_table_latex(published_map):
    result = invoke("map", "table", "--map", str(published_map), "--format", "latex",
                    "--disc", "cardboard")
    assert result.stdout.startswith("% tribopipe friction-map table\n% Needs in the preamble:")
    assert "\\begin{tabular}" in result.stdout
    assert "pressure\\_kPa" in result.stdout and result.stdout.count("cardboard") == 8


def test_table_with_no_matching_rows_is_a_clean_error(published_map):
    result = CliRunner().invoke(main, ["map", "table", "--map", str(published_map),
                                       "--pin", "PTFE"])
    assert result.exit_code == 1 and "no rows to tabulate" in result.output


def test_show_groups_prints_the_paper_table(published_map):
    from tribopipe.export.tables import paper_text

    show = invoke("map", "show", "--groups", "--map", str(published_map))
    assert show.exit_code == 0
    assert show.output.endswith(paper_text(fm.read_map(published_map)))
    assert "Ecoflex 00-50  steel" in show.output and "0.903 ± 0.092" in show.output
    assert "0.903 ± 0.027" not in invoke("map", "show", "--map", str(published_map)).output


def test_show_exclude_include_cycle(published_map):
    ids = fm.read_map(published_map)["measurement_id"]
    target = ids.iloc[0]
    missing_reason = CliRunner().invoke(
        main, ["map", "exclude", target, "--map", str(published_map)]
    )
    assert missing_reason.exit_code == 2 and "--reason" in missing_reason.output

    result = invoke("map", "exclude", target[:10], "--reason", "pin debonded",
                    "--map", str(published_map))
    assert result.exit_code == 0 and target in result.output
    show = invoke("map", "show", "--map", str(published_map))
    assert "runs: 169 (1 excluded)" in show.output
    assert f"{target}  Dragonskin 30 / acrylic glass" in show.output
    assert "pin debonded" in show.output
    table = invoke("map", "table", "--map", str(published_map))
    groups = pd.read_csv(io.StringIO(table.output)).set_index(
        ["pin", "disc", "temperature_C", "normal_force_N"]
    )
    assert groups.loc[("Dragonskin 30", "acrylic glass", 10, 1), "mu_k_n"] == 1

    back = invoke("map", "include", target, "--map", str(published_map))
    assert back.exit_code == 0 and "included 1 run(s)" in back.output
    assert "runs: 169 (0 excluded)" in invoke("map", "show", "--map",
                                               str(published_map)).output


def test_merge_reports_conflicts_with_exit_code_1(tmp_path):
    ours, theirs = tmp_path / "ours.parquet", tmp_path / "theirs.parquet"
    fm.append_records(ours, [run_record(1), run_record(2)])
    fm.append_records(theirs, [run_record(2), run_record(3), run_record(1, mu_k=0.47)])
    result = CliRunner().invoke(main, ["map", "merge", str(theirs), "--map", str(ours)])
    assert result.exit_code == 1
    assert "1 added, 1 unchanged, 0 replaced, 1 kept conflicting" in result.output
    assert "differs in mu_k" in result.output
    result = invoke("map", "merge", str(theirs), "--replace", "--map", str(ours))
    assert result.exit_code == 0 and "1 replaced" in result.output
    assert len(fm.read_map(ours)) == 3


def test_a_foreign_file_at_the_map_path_is_refused_in_one_line(tmp_path):
    foreign = tmp_path / "friction_map.parquet"
    pd.DataFrame({"x": [1.0]}).to_parquet(foreign)
    before = foreign.read_bytes()
    for args in (["map", "show"], ["map", "import", "--published"], ["map", "table"]):
        result = CliRunner().invoke(main, [*args, "--map", str(foreign)])
        assert result.exit_code == 1, args
        assert "not a tribopipe friction map" in result.output
        assert len(result.output.strip().splitlines()) == 1
    assert foreign.read_bytes() == before


@pytest.mark.slow
def test_the_installed_command_imports_and_tabulates_in_real_processes(tmp_path):
    map_path = tmp_path / "friction_map.parquet"
    cmd = [sys.executable, "-m", "tribopipe", "map"]
    imported = subprocess.run([*cmd, "import", "--published", "--map", str(map_path)],
                              capture_output=True, text=True, timeout=120)
    assert imported.returncode == 0, imported.stderr
    assert "169 added" in imported.stdout
    shown = subprocess.run([*cmd, "show", "--map", str(map_path)],
                           capture_output=True, text=True, timeout=120)
    assert shown.returncode == 0 and "condition groups: 76" in shown.stdout
    bad = subprocess.run([*cmd, "exclude", "0000000000", "--reason", "x", "--map",
                          str(map_path)], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 1 and "no run with measurement id" in bad.stderr
    assert "Traceback" not in bad.stderr


def test_the_map_cli_module_imports_no_heavy_library():
    code = ("import sys, tribopipe.cli.map; "
            "print(sorted(m for m in ('pandas', 'numpy', 'pyarrow', 'scipy') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"

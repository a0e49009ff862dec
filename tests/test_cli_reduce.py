"""`tribopipe reduce` end to end: a RheoCompass export in, μ_S/μ_K, trace, summary, map out."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe.cli import main

RUN = SyntheticRun(
    mu_s=0.80, mu_k=0.55, shape="overshoot", noise=0.005, torque_offset_Nm=0.0,
    setup_interval=True, normal_force_N=3.0, temperature_C=20.0, seed=7,
)


@pytest.fixture()
def export(tmp_path: Path) -> Path:
    path = tmp_path / "DS30_steel_3N_20C_r1.csv"
    write_rheocompass_export(path, RUN, project="cli test", test="DS30 steel", sample="DS30")
    return path


def _invoke(args: list[str], cwd: Path):
    runner = CliRunner()
    with runner.isolated_filesystem(temp_dir=cwd):
        result = runner.invoke(main, args, catch_exceptions=False)
        files = sorted(str(p) for p in Path(".").rglob("*") if p.is_file())
        return result, files


def test_reduce_json_reports_the_known_truth(export: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = CliRunner().invoke(
        main, ["reduce", str(export), "--json", "--no-map", "--output", str(out)]
    )
    assert result.exit_code == 0, result.output
    rows = json.loads(result.stdout)
    assert len(rows) == 1
    row = rows[0]
    for key in ("file", "mu_s", "mu_k", "pressure_kPa", "normal_force_N", "temperature_C",
                "flags"):
        assert key in row
    assert row["mu_k"] == pytest.approx(RUN.mu_k, abs=0.01)
    assert row["mu_s"] == pytest.approx(RUN.mu_s, abs=0.02)
    # 3 N on three pins of r = 3 mm: 35.37 kPa each
    assert row["pressure_kPa"] == pytest.approx(35.37, abs=0.5)
    assert isinstance(row["flags"], list)
    traces = list((out / "traces").glob("*.parquet"))
    assert len(traces) == 1
    trace = pd.read_parquet(traces[0])
    assert {"sliding_distance_mm", "mu", "pressure_kPa"} <= set(trace.columns)
    summary = json.loads(next((out / "summaries").glob("*.json")).read_text())
    assert summary["mu_k"] == row["mu_k"]
    assert summary["mu_k_window_mm"][0] < summary["mu_k_window_mm"][1]
    # each coefficient with its standard and expanded uncertainty, and the budget
    for q in ("mu_k", "mu_s"):
        assert 0 < row[f"u_{q}"] < 0.1
        assert row[f"U95_{q}"] == pytest.approx(2 * row[f"u_{q}"])
        budget = summary["parameters"]["uncertainty"][q]
        assert budget["combined"] == pytest.approx(row[f"u_{q}"])
        assert budget["friction_radius"] == pytest.approx(row[q] * 0.55 / 13.37, rel=1e-6)
    assert summary["method"].startswith("tribopipe-v2")


def test_reduce_appends_to_the_map_once(export: Path, tmp_path: Path) -> None:
    map_path = tmp_path / "map.parquet"
    args = ["reduce", str(export), "--pin", "Dragonskin 30", "--disc", "steel", "--force", "3",
            "--temperature", "20", "--repeat", "1", "--map", str(map_path),
            "--output", str(tmp_path / "out")]
    first = CliRunner().invoke(main, args)
    assert first.exit_code == 0, first.output
    second = CliRunner().invoke(main, args)
    assert second.exit_code == 0, second.output
    runs = pd.read_parquet(map_path)
    assert len(runs) == 1
    assert runs.loc[0, "pin"] == "Dragonskin 30"
    assert runs.loc[0, "pressure_kPa"] == pytest.approx(35.37, abs=0.01)


def test_reduce_without_pin_and_disc_does_not_touch_the_map(export: Path, tmp_path: Path) -> None:
    map_path = tmp_path / "map.parquet"
    result = CliRunner().invoke(
        main, ["reduce", str(export), "--map", str(map_path), "--output", str(tmp_path / "o")]
    )
    assert result.exit_code == 0, result.output
    assert "pin and disc unknown" in result.stderr
    assert not map_path.exists()


def test_bad_file_gives_one_line_and_exit_1_but_good_files_still_reduce(
    export: Path, tmp_path: Path
) -> None:
    bad = tmp_path / "notes.csv"
    bad.write_text("this is a lab note, not an export\n", encoding="utf-8")
    empty = tmp_path / "empty.csv"
    empty.write_bytes(b"")
    result = CliRunner().invoke(
        main, ["reduce", str(bad), str(export), str(empty), "--no-map", "--json",
               "--output", str(tmp_path / "o")]
    )
    assert result.exit_code == 1
    errors = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 2
    assert "notes.csv" in errors[0] and "empty.csv" in errors[1]
    assert "Traceback" not in result.output
    assert len(json.loads(result.stdout)) == 1


def test_missing_file_is_one_line(tmp_path: Path) -> None:
    result = CliRunner().invoke(main, ["reduce", str(tmp_path / "nope.csv"), "--no-map"])
    assert result.exit_code == 1
    assert "nope.csv" in result.stderr
    assert "Traceback" not in result.output


def test_plot_writes_a_png(export: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = CliRunner().invoke(
        main, ["reduce", str(export), "--no-map", "--plots", "--output", str(out)]
    )
    assert result.exit_code == 0, result.output
    pngs = list((out / "plots" / "traces").glob("*.png"))
    assert len(pngs) == 1
    assert pngs[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow  # a real process or a larger data set: `pytest -m slow`
def test_reduce_as_a_subprocess(export: Path, tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "tribopipe", "reduce", str(export), "--no-map",
         "--output", str(tmp_path / "o")],
        capture_output=True, text=True,
    )
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.strip().splitlines()
    assert lines[0].split()[:5] == ["file", "mu_s", "±U95", "mu_k", "±U95"]
    assert export.name in lines[1]


def test_an_export_without_contact_is_refused_naming_the_file_once(tmp_path: Path) -> None:
    run = SyntheticRun(normal_force_N=0.05, seed=11)  # below the 0.2 N contact threshold
    path = tmp_path / "lifted.csv"
    write_rheocompass_export(path, run, project="p", test="t", sample="s")
    result = CliRunner().invoke(main, ["reduce", str(path), "--no-map",
                                       "--output", str(tmp_path / "o")])
    assert result.exit_code == 1
    line = result.stderr.splitlines()[0]
    assert line.count(str(path)) == 1
    assert "contact threshold" in line


def test_forced_reader_settings_reach_the_reader(export: Path, tmp_path: Path) -> None:
    ok = CliRunner().invoke(main, ["reduce", str(export), "--no-map", "--json",
                                   "--encoding", "utf-16", "--delimiter", "tab",
                                   "--decimal", ".", "--output", str(tmp_path / "o")])
    assert ok.exit_code == 0, ok.output
    assert json.loads(ok.stdout)[0]["mu_k"] == pytest.approx(RUN.mu_k, abs=0.01)
    wrong = CliRunner().invoke(main, ["reduce", str(export), "--no-map",
                                      "--delimiter", ";", "--output", str(tmp_path / "o")])
    assert wrong.exit_code == 1
    assert str(export) in wrong.stderr and "Traceback" not in wrong.output


def test_the_table_shows_each_coefficient_with_u_as_every_output_rounds_it(
        tmp_path: Path) -> None:
    """The table's μ and ±U95 cells are the JSON's values rounded the GUM way
    (:func:`tribopipe.rounding.round_gum`), as the trace plot and the map's tables print
    them, not to a fixed 3 decimals (a high μ_S has U ≥ 0.1: two decimals)."""
    from dataclasses import replace

    from tribopipe.rounding import round_gum

    export = tmp_path / "high.csv"
    write_rheocompass_export(export, replace(RUN, mu_s=1.9, mu_k=1.4), project="p",
                             test="t", sample="s")
    args = ["reduce", str(export), "--no-map", "--output", str(tmp_path / "o")]
    shown = CliRunner().invoke(main, args)
    data = CliRunner().invoke(main, [*args, "--json"])
    assert shown.exit_code == 0 and data.exit_code == 0, shown.output + data.output
    run = json.loads(data.stdout)[0]
    cells = shown.stdout.splitlines()[1].split()[1:5]
    expected = [*round_gum(run["mu_s"], run["U95_mu_s"]), *round_gum(run["mu_k"], run["U95_mu_k"])]
    assert cells == expected
    assert run["U95_mu_s"] >= 0.1 and len(cells[0].split(".")[1]) == 2

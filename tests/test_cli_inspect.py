"""``tribopipe inspect``: real files through the real command line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from tribopipe.cli import main
from tribopipe.readers import FORMATS

VENV_BIN = Path(sys.executable).parent


def run(*args: str):
    return CliRunner().invoke(main, ["inspect", *args])


def test_inspect_lists_format_intervals_and_column_mapping(data_dir: Path) -> None:
    result = run(str(data_dir / "rheocompass_en_utf16_two_tests.csv"))
    assert result.exit_code == 0, result.output
    out = result.output
    assert "format:    rheocompass" in out
    assert "encoding:  utf-16" in out and "delimiter: TAB" in out and "decimal: ." in out
    assert "2 test(s), 2 result(s), 2 interval(s), 606 point(s)" in out
    assert "Stress Relaxation 1 / Step strain 1 / interval 1: 451 of 451 points" in out
    assert "Torque [mN·m]" in out and "→ torque_Nm" in out
    assert "Relaxation Modulus [Pa]" in out and "→ relaxation_modulus_Pa" in out


def test_inspect_json_matches_the_file(data_dir: Path) -> None:
    result = run(str(data_dir / "rheoplus_mcr302_stress_relaxation.txt"), "--json")
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert summary["format"] == "rheoplus" and summary["n_intervals"] == 6
    assert [i["n_points"] for i in summary["intervals"]] == [100, 100, 100, 99, 100, 100]
    columns = {c["original"]: c for c in summary["intervals"][0]["columns"][:10]}
    assert columns["Torque"] == {"original": "Torque", "unit": "[µNm]", "column": "torque_Nm"}
    assert columns["Deflection Angle"]["column"] == "angle_rad"


def test_forced_options_reach_the_reader(tmp_path: Path) -> None:
    path = tmp_path / "plain.csv"
    path.write_text("Time [s];Torque [mN·m];Normal Force [N]\n0,5;1,25;3\n", encoding="utf-8")
    ok = run(str(path), "--delimiter", ";", "--decimal", ",", "--format", "csv",
             "--encoding", "utf-8", "--json")
    assert ok.exit_code == 0, ok.output
    summary = json.loads(ok.output)
    assert (summary["delimiter"], summary["decimal"], summary["encoding"]) == (";", ",", "utf-8")
    assert summary["intervals"][0]["friction_ready"] is True
    bad = run(str(path), "--decimal", ".")
    assert bad.exit_code != 0
    assert "expected a number" in bad.output and "Traceback" not in bad.output


def test_user_alias_file_option(tmp_path: Path) -> None:
    aliases = tmp_path / "aliases.toml"
    aliases.write_text('[canonical.torque]\nnames = ["Momento"]\n', encoding="utf-8")
    path = tmp_path / "it.csv"
    path.write_text("Time [s],Momento [mN·m]\n0,1\n", encoding="utf-8")
    result = run(str(path), "--aliases", str(aliases))
    assert result.exit_code == 0, result.output
    assert "Momento [mN·m]" in result.output and "→ torque_Nm" in result.output


@pytest.mark.parametrize(
    ("content", "problem"),
    [(b"", "empty file"), (b"\x00\x01\x02\x03" * 50, "binary file"),
     (b"item,price\napple,1\n", "not a recognised export")],
)
def test_bad_files_give_one_line_and_a_nonzero_exit(
    tmp_path: Path, content: bytes, problem: str
) -> None:
    path = tmp_path / "bad.csv"
    path.write_bytes(content)
    result = run(str(path))
    assert result.exit_code == 1
    lines = [ln for ln in result.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and problem in lines[0] and str(path) in lines[0]


def test_wrong_encoding_gives_a_hint(data_dir: Path) -> None:
    result = run(str(data_dir / "rheocompass_en_utf16_small.txt"), "--encoding", "utf-8")
    assert result.exit_code == 1
    assert "--encoding utf-16" in result.output


def test_an_unknown_format_is_refused_with_the_readers_formats(data_dir: Path) -> None:
    result = run(str(data_dir / "rheocompass_en_utf16_small.txt"), "--format", "tribo")
    assert result.exit_code == 1
    assert "unknown format 'tribo'" in result.output
    assert f"expected one of {', '.join(FORMATS)}" in result.output


@pytest.mark.slow
def test_inspect_in_a_subprocess(data_dir: Path) -> None:
    exe = VENV_BIN / "tribopipe"
    ok = subprocess.run(
        [str(exe), "inspect", str(data_dir / "rheocompass_en_two_tests.xlsx")],
        capture_output=True, text=True, check=False,
    )
    assert ok.returncode == 0, ok.stderr
    assert "format:    rheocompass-xlsx" in ok.stdout and "606 point(s)" in ok.stdout
    bad = subprocess.run(
        [str(exe), "inspect", str(data_dir / "README.md")],
        capture_output=True, text=True, check=False,
    )
    assert bad.returncode != 0
    assert "Traceback" not in bad.stderr
    assert len(bad.stderr.strip().splitlines()) == 1 and "not a recognised export" in bad.stderr


@pytest.mark.slow
def test_the_command_module_loads_no_heavy_library() -> None:
    code = (
        "import sys, tribopipe.cli.inspect\n"
        "heavy = {'numpy', 'pandas', 'scipy', 'matplotlib', 'openpyxl'} & set(sys.modules)\n"
        "print(sorted(heavy))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"


@pytest.mark.parametrize("language", ["en", "fr"])
def test_inspect_names_the_interval_reduce_will_read(tmp_path: Path, language: str) -> None:
    from generators.synthetic import SyntheticRun, write_rheocompass_export

    run_ = SyntheticRun(normal_force_N=3.0, duration_s=60.0, setup_interval=True, seed=3)
    path = write_rheocompass_export(
        tmp_path / f"run_{language}.csv", run_, project="P", test="Ecoflex on steel",
        sample="Ecoflex", language=language,
    )
    result = run(str(path), "--json")
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert summary["decimal"] == ("," if language == "fr" else ".")
    assert summary["n_intervals"] == 2
    assert summary["friction_interval"] == 1  # the set-up interval comes first
    text = run(str(path)).output
    assert "reduce reads: Ecoflex on steel / Ecoflex 1 / interval 2" in text


def test_inspect_says_why_reduce_would_stop(data_dir: Path) -> None:
    result = run(str(data_dir / "rheocompass_en_utf16_small.txt"))
    assert result.exit_code == 0
    assert "reduce would stop: not a pin-on-disc friction test: it looks like a flow curve" \
        in result.output


def test_inspect_of_a_plain_csv_names_the_interval_reduce_reads(tmp_path) -> None:
    # a plain CSV has no test or result name: the line must not start with " / "
    from click.testing import CliRunner

    from tribopipe.cli import main

    path = tmp_path / "other_instrument.csv"
    rows = "\n".join(f"{t / 10},{0.02 + 1e-5 * t},3.0" for t in range(600))
    path.write_text("Time [s],Torque [N·m],Normal Force [N]\n" + rows + "\n", encoding="utf-8")
    result = CliRunner().invoke(main, ["inspect", str(path)])
    assert result.exit_code == 0, result.output
    assert "reduce reads: interval 1" in result.output


def test_inspect_lists_every_run_of_a_session_export(tmp_path: Path) -> None:
    from multi_exports import SESSION_TRUTH, write_session

    path = write_session(tmp_path / "session.txt")
    result = run(str(path))
    assert result.exit_code == 0, result.output
    assert "contents:  3 test(s), 3 result(s), 5 interval(s)" in result.output
    assert "reduce reads 3 runs:" in result.output
    for name in SESSION_TRUTH:
        assert f"  {name} / DS30 1 / interval" in result.output
    summary = json.loads(run(str(path), "--json").output)
    assert summary["friction_intervals"] == [1, 2, 4]  # set-up, friction, friction, set-up, …
    assert summary["friction_interval"] == 1

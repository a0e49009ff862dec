"""Hints that point the right way: each wrong input gets one line saying what the file is
and what to do (an export that is no friction test, a document or archive, a folder given
to reduce, an export given to batch, a placeholder or manifest name that is a near miss)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from tribopipe.cli import main

DATA = Path(__file__).resolve().parent / "data"
EXAMPLE = Path(__file__).resolve().parents[1] / "raw" / "example"


def invoke(*args: str):
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


def error_lines(output: str) -> list[str]:
    return [ln for ln in output.splitlines() if ln.startswith(("error:", "Error:"))]


@pytest.mark.parametrize(("name", "what"), [
    ("rheoplus_mcr302_stress_relaxation.txt", "stress relaxation"),   # 6 tests in one file
    ("rheocompass_resaved_cp1252.txt", "flow curve"),                 # 12 tests
    ("rheocompass_en_utf16_amplitude_sweep.csv", "oscillation"),
])
def test_an_export_that_is_no_friction_test_is_named_once_per_file(
        tmp_path: Path, name: str, what: str) -> None:
    result = invoke("reduce", str(DATA / name), "--pin", "DS30", "--disc", "steel", "--no-map",
                    "--output", str(tmp_path))
    assert result.exit_code == 1
    lines = error_lines(result.output)
    assert len(lines) == 1, result.output
    assert "not a pin-on-disc friction test" in lines[0] and what in lines[0]
    assert "alias" not in lines[0]


def _oscillation_csv(path: Path) -> Path:
    """A plain-CSV oscillation under a normal force well above any threshold: the angle
    swings ±20 mrad at 1 Hz, the torque follows it."""
    t = np.arange(0, 60, 0.05)
    angle_mrad = 20 * np.sin(2 * np.pi * t)
    torque_mNm = 2.0 * np.cos(2 * np.pi * t)
    rows = ["Time [s],Torque [mN·m],Normal Force [N],Angle [mrad]"]
    rows += [f"{a:.3f},{b:.5f},3.0,{c:.5f}" for a, b, c in zip(t, torque_mNm, angle_mrad,
                                                             strict=True)]
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


def test_an_oscillation_under_normal_force_is_refused_even_with_a_low_threshold(
        tmp_path: Path) -> None:
    export = _oscillation_csv(tmp_path / "osc.csv")
    config = tmp_path / "low.toml"
    config.write_text("[instrument]\ncontact_threshold_N = 0.001\n", encoding="utf-8")
    result = invoke("reduce", str(export), "--pin", "DS30", "--disc", "steel", "--no-map",
                    "--instrument", str(config), "--output", str(tmp_path / "out"))
    assert result.exit_code == 1
    lines = error_lines(result.output)
    assert len(lines) == 1 and "not a pin-on-disc friction test" in lines[0], result.output
    assert "back and forth" in lines[0]
    assert "mu_k" not in result.output.split("error:")[0]  # no result row was printed


def test_a_one_way_slide_is_still_reduced(tmp_path: Path) -> None:
    """The same file turning one way is a friction test: the rule refuses only what is not."""
    t = np.arange(0, 60, 0.05)
    rows = ["Time [s],Torque [mN·m],Normal Force [N],Angle [mrad]"]
    rows += [f"{a:.3f},{12.0 + 0.01 * np.sin(a):.5f},3.0,{0.5 * a:.5f}" for a in t]
    export = tmp_path / "slide.csv"
    export.write_text("\n".join(rows) + "\n", encoding="utf-8")
    result = invoke("reduce", str(export), "--pin", "DS30", "--disc", "steel", "--no-map",
                    "--output", str(tmp_path / "out"))
    assert "not a pin-on-disc friction test" not in result.output


@pytest.mark.parametrize(("head", "what"), [
    (b"%PDF-1.7\n%\xe2\xe3\n1 0 obj", "a PDF document"),
    (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", "a PNG image"),
    (b"\xff\xd8\xff\xe0\x00\x10JFIF", "a JPEG image"),
    (b"\x1f\x8b\x08\x00\x00\x00\x00\x00", "a gzip archive"),
    (b"PK\x03\x04\x14\x00\x00\x00x.csv", "a ZIP archive"),
])
def test_a_document_image_or_archive_is_named_as_such(tmp_path: Path, head: bytes,
                                                       what: str) -> None:
    path = tmp_path / "run.csv"  # the suffix lies: the bytes decide
    path.write_bytes(head + b"\x00" * 64)
    result = invoke("reduce", str(path), "--pin", "DS30", "--disc", "steel", "--no-map",
                    "--output", str(tmp_path / "out"))
    assert result.exit_code == 1
    (line,) = error_lines(result.output)
    assert f"is {what}" in line and "delimiter" not in line


def test_reduce_a_folder_points_to_batch_and_batch_a_file_points_to_reduce(
        tmp_path: Path) -> None:
    result = invoke("reduce", str(tmp_path), "--no-map", "--output", str(tmp_path / "out"))
    assert result.exit_code == 1
    assert "tribopipe batch" in result.output
    export = tmp_path / "run.csv"
    export.write_bytes((EXAMPLE / "DS30_steel_1N_10C_r1.csv").read_bytes())
    result = invoke("batch", str(export))
    assert result.exit_code == 1
    assert "not a campaign config" in result.output and "tribopipe reduce" in result.output
    assert "UTF-8" not in result.output
    pdf = tmp_path / "notes.pdf"
    pdf.write_bytes(b"%PDF-1.7\n" + bytes(range(256)))
    result = invoke("batch", str(pdf))
    assert result.exit_code == 1
    assert "is a PDF document, not a campaign config" in result.output


def test_a_placeholder_typo_gets_a_did_you_mean(tmp_path: Path) -> None:
    (tmp_path / "raw").mkdir()
    config = tmp_path / "c.toml"
    config.write_text('[campaign]\nraw_dir = "raw"\n'
                      'filename_pattern = "{pin}_{dsic}_{force}N_{temperature}C_r{repeat}"\n',
                      encoding="utf-8")
    result = invoke("campaign", "list", str(config))
    assert result.exit_code == 1
    assert "{dsic}" in result.output and "did you mean {disc}" in result.output


def test_a_manifest_name_without_its_suffix_gets_a_did_you_mean(tmp_path: Path) -> None:
    raw = tmp_path / "raw"
    raw.mkdir()
    name = "DS30_steel_1N_10C_r1.csv"
    (raw / name).write_bytes((EXAMPLE / name).read_bytes())
    (raw / "manifest.csv").write_text(
        "file,pin,disc,normal_force_N,temperature_C,repeat\n"
        "DS30_steel_1N_10C_r1,Dragonskin 30,steel,1,10,1\n", encoding="utf-8")
    config = tmp_path / "c.toml"
    config.write_text('[campaign]\nraw_dir = "raw"\nmanifest = "raw/manifest.csv"\n'
                      'output_dir = "out"\n', encoding="utf-8")
    result = invoke("batch", str(config))
    assert result.exit_code == 1
    assert "did you mean its row 'DS30_steel_1N_10C_r1'" in result.output


def test_the_missing_column_hint_names_a_file_that_works(tmp_path: Path, monkeypatch) -> None:
    """The hint for an unknown column name points to configs/aliases.toml in the folder
    tribopipe runs from; following it makes the same file reduce."""
    t = np.arange(0, 120, 0.1)
    rows = ["Time [s],Torque [mN·m],Auflast [N],Angle [mrad]"]
    rows += [f"{a:.2f},{12.0 + 0.01 * np.sin(a):.5f},3.0,{0.5 * a:.4f}" for a in t]
    export = tmp_path / "run.csv"
    export.write_text("\n".join(rows) + "\n", encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    args = ("reduce", "run.csv", "--pin", "DS30", "--disc", "steel", "--no-map", "--output", "out")
    result = invoke(*args)
    assert result.exit_code == 1
    assert "missing: normal_force_N" in result.output
    assert "configs/aliases.toml" in result.output and "alias table" not in result.output
    (tmp_path / "configs").mkdir()
    (tmp_path / "configs" / "aliases.toml").write_text(
        '[canonical.normal_force]\nnames = ["Auflast"]\n', encoding="utf-8")
    result = invoke(*args)
    assert "missing" not in result.output, result.output

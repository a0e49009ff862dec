"""Content before labels, and a dry run for a folder.

A file that is no instrument export (a note, a PDF, an image) is set aside as "not an
export: skipped" and never fails a batch; an export that holds no friction test is named
for what it is, whatever its labels' source; a pattern mismatch says where the match broke,
once for every file that broke alike; ``campaign list FOLDER`` is a dry run that writes
nothing; ``campaign manifest FOLDER`` writes a manifest to fill in.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest
from click.testing import CliRunner

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe.campaign import read_manifest
from tribopipe.campaign.patterns import pattern_break
from tribopipe.cli import main
from tribopipe.readers import export_kind

PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
DATA = Path(__file__).resolve().parent / "data"
#: the real exports in tests/data, none of them a friction test (tests/data/README.md)
NOT_FRICTION = sorted(p.name for p in DATA.iterdir()
                      if p.suffix in (".csv", ".txt", ".xlsx") and p.name != "README.md")


def _run(force: float, seed: int) -> SyntheticRun:
    return SyntheticRun(mu_s=0.8, mu_k=0.55, normal_force_N=force, temperature_C=20.0,
                        duration_s=60.0, noise=0.004, seed=seed)


@pytest.fixture()
def workdir(tmp_path: Path) -> Iterator[Path]:
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        yield tmp_path
    finally:
        os.chdir(cwd)


def _exports(folder: Path, stems: list[str]) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for i, stem in enumerate(stems):
        force = float(stem.replace("-", "_").split("_")[2].rstrip("N").rstrip("k"))
        write_rheocompass_export(folder / f"{stem}.csv", _run(force, i), project="p",
                                 test="t", sample="s")


def test_export_kind_names_what_is_no_export(tmp_path: Path) -> None:
    note = tmp_path / "notes.txt"
    note.write_text("disc re-polished before the 5 N runs\n", encoding="utf-8")
    pdf = tmp_path / "DS30_steel_1N_20C_r1.csv"
    pdf.write_bytes(b"%PDF-1.7\n" + b"x" * 200)
    png = tmp_path / "photo.csv"
    png.write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 100)
    prose = tmp_path / "readme.csv"
    prose.write_text("These runs, measured in May, are fine; see the lab book.\n" * 3,
                     encoding="utf-8")
    assert export_kind(note) == "a text with no table: no TAB, ';' or ',' between cells"
    assert export_kind(pdf) == "a PDF document"
    assert export_kind(png) == "a PNG image"
    assert export_kind(prose) == "a text that no export format recognises"
    for name in NOT_FRICTION:  # real exports, friction or not, are exports
        assert export_kind(DATA / name) is None, name


def test_a_note_a_pdf_and_an_image_are_skipped_and_do_not_fail_the_batch(
        workdir: Path) -> None:
    raw = workdir / "raw"
    _exports(raw, ["DS30_steel_1N_20C_r1", "DS30_steel_5N_20C_r1"])
    (raw / "notes.txt").write_text("pin slipped at 5 N, re-mounted\n", encoding="utf-8")
    (raw / "DS30_steel_9N_20C_r1.csv").write_bytes(b"%PDF-1.4\n" + b"x" * 300)
    (raw / "photo.tsv").write_bytes(b"\xff\xd8\xff\xe0" + b"\0" * 300)
    result = CliRunner().invoke(main, ["batch", "raw", "--pattern", PATTERN, "--no-plots"])
    assert result.exit_code == 0, result.output
    notes = [ln for ln in result.stderr.splitlines() if "not an export" in ln]
    assert notes == [
        "note: not an export: skipped: DS30_steel_9N_20C_r1.csv (a PDF document)",
        "note: not an export: skipped: notes.txt (a text that no export format recognises)",
        "note: not an export: skipped: photo.tsv (a JPEG image)",
    ]
    assert "raw: 2 file(s) found (2 read)" in result.stdout
    assert "failed:" not in result.stderr
    failures = (workdir / "processed" / "failures.csv").read_text(encoding="utf-8")
    assert failures == "file,reason\n"
    listed = CliRunner().invoke(main, ["campaign", "list", "raw", "--pattern", PATTERN])
    assert "skipped (not an export)" in listed.stdout
    assert "3 skipped (not an export)" in listed.stdout


@pytest.mark.parametrize("name", NOT_FRICTION)
def test_a_non_friction_export_is_named_for_what_it_is_whatever_the_labels(
        workdir: Path, name: str) -> None:
    """With a pattern its name does not match, as with a manifest: what it looks like."""
    raw = workdir / "raw"
    raw.mkdir()
    shutil.copy(DATA / name, raw / name)
    by_pattern = CliRunner().invoke(main, ["batch", "raw", "--pattern", PATTERN,
                                           "--no-plots", "-o", "a"])
    (raw / "m.csv").write_text("file,pin,disc,normal_force_N,temperature_C,repeat\n"
                               f"{name},DS30,steel,1,20,1\n", encoding="utf-8")
    by_manifest = CliRunner().invoke(main, ["batch", "raw", "--manifest", str(raw / "m.csv"),
                                            "--no-plots", "-o", "b"])
    for result in (by_pattern, by_manifest):
        assert result.exit_code == 1
        failed = [ln for ln in result.stderr.splitlines() if ln.startswith("failed:")]
        assert len(failed) == 1, result.stderr
        assert "not a pin-on-disc friction test" in failed[0] and "look" in failed[0]
        assert "metadata missing" not in failed[0]


@pytest.mark.parametrize(("stem", "said"), [
    ("DS30-steel-5N-20C-r1", "it follows '{pin}', then the pattern expects '_'"),
    ("DS30_steel_5kN_20C_r1", "it follows '{pin}_{disc}_{force}', then the pattern expects "
                              "'N'"),
    ("DS30_steel_5N_20C_1", "it follows '{pin}_{disc}_{force}N_{temperature}C_', then the "
                            "pattern expects 'r'"),
    ("DS30_steel_5N_twentyC_r1", "it follows '{pin}_{disc}_{force}N_', then the pattern "
                                 "expects {temperature} (a number)"),
    ("DS30_steel_5N_20C_r1_x", "it follows the whole pattern, then goes on"),
])
def test_pattern_break_says_where(stem: str, said: str) -> None:
    assert pattern_break(PATTERN, stem) == said


def test_a_pattern_mismatch_is_said_once_with_the_count(workdir: Path) -> None:
    stems = [f"DS30-steel-{f}N-20C-r{r}" for f in (1, 5, 9) for r in (1, 2)]
    _exports(workdir / "raw", stems)
    _exports(workdir / "raw", ["DS30_steel_5kN_20C_r1"])
    result = CliRunner().invoke(main, ["batch", "raw", "--pattern", PATTERN, "--no-plots"])
    assert result.exit_code == 1
    failed = [ln for ln in result.stderr.splitlines() if ln.startswith("failed:")]
    assert len(failed) == 2
    alike = next(ln for ln in failed if "alike" in ln)
    assert alike.startswith("failed: 6 files alike, e.g. DS30-steel-1N-20C-r1.csv: "
                            "metadata missing")
    assert alike.endswith("it follows '{pin}', then the pattern expects '_'")
    (other,) = (ln for ln in failed if ln != alike)
    assert other.startswith("failed: DS30_steel_5kN_20C_r1.csv: ")
    assert "then the pattern expects 'N'" in other
    listed = CliRunner().invoke(main, ["campaign", "list", "raw", "--pattern", PATTERN])
    lines = listed.stdout.splitlines()
    assert sum("it follows '{pin}', then" in ln for ln in lines) == 1
    assert "6 file(s), e.g. DS30-steel-1N-20C-r1.csv: metadata missing" in listed.stdout


def test_campaign_list_of_a_folder_is_a_dry_run(workdir: Path) -> None:
    _exports(workdir / "raw", ["DS30_steel_1N_20C_r1", "DS30_steel_5N_20C_r2"])
    before = sorted(workdir.rglob("*"))
    result = CliRunner().invoke(main, ["campaign", "list", "raw", "--pattern", PATTERN])
    assert result.exit_code == 0, result.output
    assert "2 row(s) in 2 file(s): 2 new" in result.stdout
    assert "DS30  steel  5    20   2" in " ".join(result.stdout.split("  ")).replace("   ", "  ") \
        or "steel" in result.stdout
    assert sorted(workdir.rglob("*")) == before  # nothing written, no output folder
    refused = CliRunner().invoke(main, ["campaign", "list", "raw"])
    assert refused.exit_code == 1 and "no metadata source" in refused.stderr


def test_campaign_manifest_writes_a_template_that_reads_back(workdir: Path) -> None:
    raw = workdir / "raw"
    _exports(raw, ["DS30_steel_1N_20C_r1", "DS30_steel_5N_20C_r2"])
    write_rheocompass_export(raw / "=cmd_steel_1N_20C_r3.csv", _run(1.0, 9), project="p",
                             test="t", sample="s")
    (raw / "notes.txt").write_text("pin slipped\n", encoding="utf-8")
    done = CliRunner().invoke(main, ["campaign", "manifest", "raw", "--pattern", PATTERN])
    assert done.exit_code == 0, done.output
    assert "not an export: skipped: notes.txt" in done.stderr
    assert "wrote raw/manifest.csv: 3 export(s) to label" in done.stdout
    text = (raw / "manifest.csv").read_text(encoding="utf-8")
    assert text.startswith("\ufefffile,pin,disc,normal_force_N,temperature_C,repeat\n")
    assert "'=cmd_steel_1N_20C_r3.csv,'=cmd,steel,1,20,3" in text  # never a formula
    assert "DS30_steel_5N_20C_r2.csv,DS30,steel,5,20,2" in text
    manifest = read_manifest(raw / "manifest.csv")
    assert manifest.for_file("=cmd_steel_1N_20C_r3.csv", "=cmd_steel_1N_20C_r3.csv")[0] \
        is not None
    again = CliRunner().invoke(main, ["campaign", "manifest", "raw"])
    assert again.exit_code == 2 and "exists: pass --overwrite" in again.stderr
    # the template, as written (labels from the names), is checked against the materials
    # vocabulary before any work: '=cmd' is no material, and nothing is reduced
    batch = CliRunner().invoke(main, ["batch", "raw", "--manifest", "raw/manifest.csv",
                                      "--no-plots"])
    assert batch.exit_code != 0
    assert "unknown pin '=cmd'" in batch.output and "nothing reduced" in batch.output
    assert not (workdir / "processed" / "friction_map.parquet").exists()
    # once the lab fills in the material, the template reduces
    (raw / "manifest.csv").write_text(text.replace("'=cmd,steel", "Dragonskin 30,steel"),
                                      encoding="utf-8")
    batch = CliRunner().invoke(main, ["batch", "raw", "--manifest", "raw/manifest.csv",
                                      "--no-plots"])
    assert "3 reduced" in batch.stdout, batch.output

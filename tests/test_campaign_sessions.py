"""A lab's folder as it really is: session exports of several tests, .txt, .csv and .xlsx
side by side (any case), a manifest with a ``test`` column, a test-name pattern, stray
files, copies under other names. Every run lands or is named; nothing is left out without
a word. Real synthetic exports, real Parquet maps, the CLI through click and as a process.
"""

from __future__ import annotations

import csv
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from generators.synthetic import write_rheocompass_export
from helpers import write_campaign_config
from map_files import map_bytes
from multi_exports import (
    SESSION_TRUTH,
    TEST_PATTERN,
    run,
    steps_test,
    write_session,
    write_xlsx_twin,
)
from tribopipe.campaign import campaign_listing, load_campaign, run_campaign
from tribopipe.campaign.ledger import Tally
from tribopipe.campaign.spec import folder_campaign
from tribopipe.campaign.table import discover_files
from tribopipe.cli import main

#: force [N] -> true mu_k of the session's tests
MU_K = {force: mu_k for _, mu_k, force, _, _ in SESSION_TRUTH.values()}
NAMES = list(SESSION_TRUTH)  # the Test names of repeat 1
HEADER = "file,test,pin,disc,normal_force_N,temperature_C,repeat,operator\n"


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """session.txt (manifest rows per test), SESSION_FR.CSV (French, repeat 2: Test names
    only), session.xlsx (the Excel twin of a repeat-3 session), single.csv (one test, a
    whole-file manifest row), notes.txt (no export), legacy.xls (old Excel)."""
    raw = tmp_path_factory.mktemp("lab") / "raw"
    raw.mkdir()
    write_session(raw / "session.txt", seed=0)
    write_session(raw / "SESSION_FR.CSV", language="fr", seed=10, repeat=2)
    text_twin = write_session(raw.parent / "twin.txt", seed=20, repeat=3)
    write_xlsx_twin(text_twin, raw / "session.xlsx")
    write_rheocompass_export(raw / "single.csv", run(0.5, 0.33, 7.0, 30), project="p",
                             test="friction", sample="DS30")
    (raw / "notes.txt").write_text("disc re-polished before the 5 N runs\n", encoding="utf-8")
    (raw / "legacy.xls").write_bytes(b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1" + b"\0" * 504)
    rows = [["session.txt", name, "Dragonskin 30", "steel", f"{force:g}", "20", "1", "RB"]
            for name, (_, _, force, _, _) in SESSION_TRUTH.items()]
    rows.append(["session.txt", "DS30 on steel, 9 N, 20 °C, #1", "Dragonskin 30", "steel",
                 "9", "20", "1", "RB"])
    rows.append(["single.csv", "", "Dragonskin 30", "steel", "7", "20", "1", "RB"])
    rows.append(["ghost.txt", "", "Dragonskin 30", "steel", "1", "20", "3", "RB"])
    with (raw / "manifest.csv").open("w", encoding="utf-8", newline="") as fh:
        fh.write(HEADER)
        csv.writer(fh, lineterminator="\n").writerows(rows)
    return raw


def write_config(root: Path, extra: str = "", *, manifest: bool = True,
                 test_pattern: bool = True) -> Path:
    lines = ['name = "sessions"', 'raw_dir = "raw"', 'output_dir = "out"', "plots = false"]
    if manifest:
        lines.append('manifest = "raw/manifest.csv"')
    if test_pattern:
        lines.append(f'test_pattern = "{TEST_PATTERN}"')
    return write_campaign_config(root, lines, extra)


@pytest.fixture()
def lab(folder: Path, tmp_path: Path) -> Path:
    shutil.copytree(folder, tmp_path / "raw")
    write_config(tmp_path)
    return tmp_path


def runs_csv(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as fh:
        return list(csv.DictReader(fh))


def test_the_manifest_reads_with_its_test_column(folder: Path) -> None:
    from tribopipe.campaign import read_manifest

    manifest = read_manifest(folder / "manifest.csv")
    assert len(manifest) == 6
    row = manifest.get("session.txt", NAMES[2])
    assert row.fields["normal_force_N"] == 5.0 and row.test == NAMES[2]
    assert manifest.get("single.csv").fields["normal_force_N"] == 7.0
    whole, tests = manifest.for_file("session.txt", "session.txt")
    assert whole is None
    assert sorted(r.test for r in tests) == sorted([*NAMES, "DS30 on steel, 9 N, 20 °C, #1"])


def test_every_export_of_the_folder_is_found_and_nothing_else(lab: Path) -> None:
    raw = lab / "raw"
    # the tool's own outputs and configs beside the exports are never runs
    (raw / "runs.csv").write_text("file,test,result\n", encoding="utf-8")
    (raw / "campaign.toml").write_text("[campaign]\n", encoding="utf-8")
    (raw / "map.parquet.lock").write_text("", encoding="utf-8")
    campaign = load_campaign(lab / "campaign.toml")
    found = [p.name for p in discover_files(campaign)]
    assert found == ["SESSION_FR.CSV", "legacy.xls", "notes.txt", "session.txt",
                     "session.xlsx", "single.csv"]
    # a glob that takes everything, with the output folder inside the raw folder
    (raw / "out" / "traces").mkdir(parents=True)
    (raw / "out" / "traces" / "x_1234abcd.parquet").write_bytes(b"PAR1")
    (raw / "out" / "runs.csv").write_text("file,status\n", encoding="utf-8")
    config = write_config(lab, 'glob = "**/*"')
    text = config.read_text(encoding="utf-8").replace('output_dir = "out"',
                                                      'output_dir = "raw/out"')
    config.write_text(text, encoding="utf-8")
    everything = load_campaign(config)
    assert [p.name for p in discover_files(everything)] == found


def test_a_mixed_folder_lands_every_run_and_names_what_it_left_out(lab: Path) -> None:
    campaign = load_campaign(lab / "campaign.toml")
    report = run_campaign(campaign, jobs=1)

    assert report.files == 5  # notes.txt is no export: set aside, never a failure
    assert report.tests == 3 + 3 + 3 + 1  # legacy.xls is not read: it holds none
    assert len(report.reduced) == 10 and report.skipped == []
    failed = dict(report.failures)
    assert set(failed) == {"legacy.xls"}
    assert "not an export: skipped: notes.txt (a text with no table: no TAB, ';' or ',' " \
        "between cells)" in report.notes
    assert "legacy Excel .xls workbook" in failed["legacy.xls"]
    assert report.unmatched == [
        "file: manifest.csv line 7 (ghost.txt)",
        "test: manifest.csv line 5 (session.txt, test 'DS30 on steel, 9 N, 20 °C, #1')",
    ]
    assert not report.ok  # the user named ghost.txt and a 9 N test: not reduced
    assert report.undescribed == []

    runs = pd.read_parquet(campaign.map_path)
    assert len(runs) == 10
    assert set(runs["pin"]) == {"Dragonskin 30"} and set(runs["disc"]) == {"steel"}
    sessions = runs[runs["source_file"] != "single.csv"]
    by_file = {f: g for f, g in sessions.groupby("source_file")}
    assert {f: sorted(g["repeat"]) for f, g in by_file.items()} == {
        "session.txt": [1, 1, 1], "SESSION_FR.CSV": [2, 2, 2], "session.xlsx": [3, 3, 3]}
    for row in sessions.itertuples():
        assert row.mu_k == pytest.approx(MU_K[row.normal_force_N], abs=0.01)
    single = runs[runs["source_file"] == "single.csv"].iloc[0]
    assert (single["normal_force_N"], single["repeat"]) == (7.0, 1)
    assert single["mu_k"] == pytest.approx(0.33, abs=0.01)

    table = runs_csv(campaign.runs_csv)
    assert len(table) == 11  # 10 runs + legacy.xls, which failed
    session = [r for r in table if r["file"] == "session.txt"]
    assert [(r["test"], r["interval"], r["status"]) for r in session] == [
        (NAMES[0], "2", "reduced"), (NAMES[1], "1", "reduced"), (NAMES[2], "2", "reduced")]
    assert [r["status"] for r in table if r["file"] == "notes.txt"] == []


def test_a_rerun_skips_every_run_and_a_changed_row_redoes_only_its_file(lab: Path) -> None:
    campaign = load_campaign(lab / "campaign.toml")
    run_campaign(campaign, jobs=1)
    before = map_bytes(campaign.map_path)
    again = run_campaign(campaign, jobs=1)
    assert again.reduced == [] and len(again.skipped) == 10
    assert again.tests == 10 and again.files == 5
    assert map_bytes(campaign.map_path) == before
    assert len(again.unmatched) == 2  # still named, still exit 1

    manifest = lab / "raw" / "manifest.csv"
    text = manifest.read_text(encoding="utf-8").replace("single.csv,,Dragonskin 30,steel,7,20,1",
                                                        "single.csv,,Dragonskin 30,steel,7,20,2")
    manifest.write_text(text, encoding="utf-8")
    changed = run_campaign(load_campaign(lab / "campaign.toml"), jobs=1)
    assert changed.reduced == ["single.csv"] and len(changed.skipped) == 9
    runs = pd.read_parquet(campaign.map_path)
    assert runs.loc[runs["source_file"] == "single.csv", "repeat"].tolist() == [2]


def test_a_contradictory_test_fails_alone(lab: Path) -> None:
    manifest = lab / "raw" / "manifest.csv"
    lines = manifest.read_text(encoding="utf-8").splitlines()
    # the manifest says 4 N where the Test name says 5 N
    lines[3] = lines[3].replace("steel,5,20", "steel,4,20")
    manifest.write_text("\n".join(lines) + "\n", encoding="utf-8")
    report = run_campaign(load_campaign(lab / "campaign.toml"), jobs=1)
    name = f"session.txt [{NAMES[2]} / DS30 1 / interval 2]"
    reason = dict(report.failures)[name]
    assert "contradictory normal_force_N" in reason and "manifest line 4 says 4.0" in reason
    assert "export Test name" in reason and "says 5.0" in reason
    assert f"session.txt [{NAMES[0]} / DS30 1 / interval 2]" in report.reduced
    assert len(report.reduced) == 9


def test_the_ledger_adds_up_with_duplicates_conflicts_and_failures(lab: Path) -> None:
    """Every file found is read, a duplicate, a conflict or failed; every test is in one
    of those files; every run of a file read is reduced, skipped or failed: the ledger's
    parts add up to its totals, in the first batch and in the next that skips."""
    raw = lab / "raw"
    shutil.copy(raw / "SESSION_FR.CSV", raw / "session_fr (copy).txt")  # 3 tests, same labels
    shutil.copy(raw / "single.csv", raw / "single_r2.csv")               # 1 test, other repeat
    manifest = raw / "manifest.csv"
    text = manifest.read_text(encoding="utf-8").replace("steel,5,20", "steel,4,20")
    manifest.write_text(text + "single_r2.csv,,Dragonskin 30,steel,7,20,2,RB\n",
                        encoding="utf-8")  # the 5 N test of session.txt now contradicts
    campaign = load_campaign(lab / "campaign.toml")
    for batch in (1, 2):
        report = run_campaign(campaign, jobs=1)
        # what the folder holds, counted by hand
        assert report.file_tally == Tally(read=4, duplicate=1, conflict=1, failed=1)
        assert report.files == report.file_tally.found == 7  # notes.txt: not an export
        assert report.test_tally == Tally(read=3 + 3 + 3 + 1, duplicate=3, conflict=1)
        assert report.tests == report.test_tally.found == 14
        reduced, skipped = (9, 0) if batch == 1 else (0, 9)
        assert (len(report.reduced), len(report.skipped), report.runs_failed) == (
            reduced, skipped, 1)
        assert report.total == len(report.reduced) + len(report.skipped) + report.runs_failed
        # every failure listed is a failed file, a conflict or a failed run, once
        assert len(report.failures) == (report.file_tally.failed + report.file_tally.conflict
                                        + report.runs_failed) == 3
        assert [f for f, _ in report.conflicts] == ["single_r2.csv"]
        assert [f for f, _ in report.duplicates] == ["session_fr (copy).txt"]
        assert report.summary() == (
            "sessions: 7 file(s) found (4 read, 1 duplicate, 1 conflict, 1 failed), 14 test(s) "
            "(10 in files read, 3 in duplicates, 1 in conflicts); 10 run(s) in the files read: "
            f"{reduced} reduced, {skipped} skipped (unchanged), 1 failed; "
            f"{4 if batch == 1 else 0} condition group(s) updated")  # 1, 3, 5 N; 7 N
        ledger = report.ledger()
        assert sum(ln.startswith("  conflict: single_r2.csv: same content as single.csv")
                   for ln in ledger) == 1
        assert sum(ln.startswith("  duplicate: session_fr (copy).txt") for ln in ledger) == 1
    assert len(pd.read_parquet(campaign.map_path)) == 9


STEPS = "DS30 on steel, steps, 20 °C"


def steps_folder(root: Path, interval_rows: str) -> Path:
    """A folder holding one export of one test with two force steps (set-up, then 3 N as
    interval 2, then 5 N as interval 3) and a manifest with an ``interval`` column."""
    from generators.synthetic import write_rheocompass_session

    raw = root / "raw"
    raw.mkdir(parents=True)
    write_rheocompass_session(raw / "steps.txt", [steps_test()], project="steps")
    (raw / "manifest.csv").write_text(
        "file,test,interval,pin,disc,normal_force_N,temperature_C,repeat\n"
        "steps.txt,,,Dragonskin 30,steel,,20,1\n" + interval_rows, encoding="utf-8")
    return raw


def test_each_force_step_of_a_test_gets_its_own_manifest_row(tmp_path: Path) -> None:
    raw = steps_folder(tmp_path, "steps.txt,,2,,,3,,\n"
                                 f'steps.txt,"{STEPS}",3,,,5,,\n'
                                 "steps.txt,,7,,,9,,\n")
    args = ["batch", str(raw), "--manifest", str(raw / "manifest.csv"),
            "--output", str(tmp_path / "out"), "--no-plots", "--jobs", "1"]
    # before any batch the listing shows the rows the manifest names, with their steps
    listed = campaign_listing(folder_campaign(raw, manifest=raw / "manifest.csv",
                                              output_dir=tmp_path / "out"))
    assert [(r["interval"], r["normal_force_N"], r["status"]) for r in listed] == [
        (2, 3.0, "new"), (3, 5.0, "new"), (7, 9.0, "new")]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 1, result.output  # the row of interval 7 matched no run
    assert "  manifest row matching no interval: manifest.csv line 5 (steps.txt, " \
           "interval 7)" in result.stdout
    assert "1 file(s) found (1 read), 1 test(s); 2 run(s) in the files read: 2 reduced" \
        in result.stdout
    runs = pd.read_parquet(tmp_path / "out" / "friction_map.parquet").sort_values("interval")
    assert runs["interval"].tolist() == [2, 3]
    assert runs["normal_force_N"].tolist() == [3.0, 5.0]  # each step its own nominal force
    assert runs["mu_k"].tolist() == pytest.approx([0.47, 0.36], abs=0.01)
    assert not runs["flags"].str.contains("normal_force_off_nominal").any()
    assert set(runs["test"]) == {STEPS} and set(runs["repeat"]) == {1}
    # run again: nothing to redo; the interval rows are part of the file's recipe
    again = CliRunner().invoke(main, args)
    assert "0 reduced, 2 skipped (unchanged)" in again.stdout, again.output
    manifest = raw / "manifest.csv"
    manifest.write_text(manifest.read_text(encoding="utf-8").replace(",3,,,5,,", ",3,,,6,,"),
                        encoding="utf-8")
    changed = CliRunner().invoke(main, args)
    assert "2 reduced, 0 skipped (unchanged)" in changed.stdout, changed.output
    runs = pd.read_parquet(tmp_path / "out" / "friction_map.parquet").sort_values("interval")
    assert runs["normal_force_N"].tolist() == [3.0, 6.0]
    assert "normal_force_off_nominal" in runs["flags"].iloc[1]  # 5 N measured, 6 N said


def test_an_interval_row_contradicting_its_test_row_fails_that_step_alone(tmp_path: Path
                                                                          ) -> None:
    raw = steps_folder(tmp_path, f'steps.txt,"{STEPS}",,,,3,,\nsteps.txt,,3,,,5,,\n')
    campaign = folder_campaign(raw, manifest=raw / "manifest.csv",
                               output_dir=tmp_path / "out", plots=False)
    report = run_campaign(campaign, jobs=1)
    name = f"steps.txt [{STEPS} / DS30 1 / interval 3]"
    reason = dict(report.failures)[name]
    assert "contradictory normal_force_N: manifest line 4 says 5.0, manifest line 3 says " \
           "3.0" in reason
    assert report.reduced == [f"steps.txt [{STEPS} / DS30 1 / interval 2]"]
    assert (report.total, report.runs_failed) == (2, 1)


def test_a_bad_interval_cell_is_one_line_naming_the_manifest_line_and_column(tmp_path: Path
                                                                             ) -> None:
    from tribopipe.campaign import read_manifest
    from tribopipe.errors import ConfigError

    raw = steps_folder(tmp_path, "steps.txt,,2.5,,,3,,\n")
    with pytest.raises(ConfigError) as bad:
        read_manifest(raw / "manifest.csv")
    line = str(bad.value)
    assert "manifest.csv:3" in line and "interval" in line and "'2.5' is not an interval " \
        "number" in line and "\n" not in line
    (raw / "manifest.csv").write_text(
        "file,interval,pin,disc,normal_force_N,temperature_C,repeat\n"
        "steps.txt,2,DS30,steel,3,20,1\nsteps.txt,2,DS30,steel,5,20,1\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"manifest\.csv:3: file 'steps\.txt' and interval "
                                          r"2 listed twice \(first on line 2\)"):
        read_manifest(raw / "manifest.csv")


def test_file_level_metadata_cannot_tell_the_tests_of_a_session_apart(tmp_path: Path,
                                                                       folder: Path) -> None:
    raw = tmp_path / "raw"
    raw.mkdir()
    shutil.copy(folder / "session.txt", raw)
    shutil.copy(folder / "single.csv", raw)
    (raw / "manifest.csv").write_text(
        HEADER + "session.txt,,Dragonskin 30,steel,3,20,1,RB\n"
                 "single.csv,,Dragonskin 30,steel,7,20,1,RB\n", encoding="utf-8")
    report = run_campaign(load_campaign(write_config(tmp_path, test_pattern=False)), jobs=1)
    assert report.reduced == ["single.csv"]
    assert len(report.failures) == 3
    for _, reason in report.failures:
        assert "holds 3 tests with runs and only file-level metadata (manifest line 2)" in reason
        assert "'test' column" in reason
    assert report.undescribed == [f"session.txt [{n}]" for n in NAMES]


def test_the_real_two_test_export_in_a_campaign_fails_once_saying_what_it_is(
        tmp_path: Path, data_dir: Path) -> None:
    raw = tmp_path / "raw"
    raw.mkdir()
    shutil.copy(data_dir / "rheocompass_en_utf16_two_tests.csv", raw / "relaxation.csv")
    (raw / "manifest.csv").write_text(HEADER + "relaxation.csv,,DS30,steel,3,20,1,\n",
                                      encoding="utf-8")
    report = run_campaign(load_campaign(write_config(tmp_path, test_pattern=False)), jobs=1)
    assert report.reduced == []
    # one failure for the file (not one per test), saying what its tests are
    [(name, reason)] = report.failures
    assert name == "relaxation.csv"
    assert reason.startswith("relaxation.csv: not a pin-on-disc friction test: its 2 tests")
    assert "stress relaxation" in reason


# --------------------------------------------------------------------------- same content


def test_a_copy_with_the_same_labels_is_a_duplicate_stored_once(lab: Path) -> None:
    raw = lab / "raw"
    shutil.copy(raw / "SESSION_FR.CSV", raw / "session_fr (copy).txt")
    campaign = load_campaign(lab / "campaign.toml")
    report = run_campaign(campaign, jobs=1)
    assert len(report.reduced) == 10  # the copy's runs are the original's
    assert report.duplicates == [(
        "session_fr (copy).txt",
        "session_fr (copy).txt: same content as SESSION_FR.CSV (a duplicate): its runs are "
        "SESSION_FR.CSV's, stored once")]
    runs = pd.read_parquet(campaign.map_path)
    assert len(runs) == 10 and "session_fr (copy).txt" not in set(runs["source_file"])
    statuses = [r["status"] for r in runs_csv(campaign.runs_csv)
                if r["file"] == "session_fr (copy).txt"]
    assert statuses == ["duplicate"] * 3
    assert not list((campaign.output_dir / "traces").glob("session_fr (copy)*"))
    again = run_campaign(campaign, jobs=1)  # unchanged: still named, not reduced again
    assert again.reduced == [] and [f for f, _ in again.duplicates] == ["session_fr (copy).txt"]


def test_a_copy_with_other_labels_is_refused_as_a_conflict(lab: Path) -> None:
    raw = lab / "raw"
    shutil.copy(raw / "single.csv", raw / "single_r2.csv")
    manifest = raw / "manifest.csv"
    manifest.write_text(manifest.read_text(encoding="utf-8")
                        + "single_r2.csv,,Dragonskin 30,steel,7,20,2,RB\n", encoding="utf-8")
    campaign = load_campaign(lab / "campaign.toml")
    report = run_campaign(campaign, jobs=1)
    reason = dict(report.failures)["single_r2.csv"]
    assert reason == ("single_r2.csv: same content as single.csv but other labels (repeat 1 vs "
                      "2): refused as a conflict, the map keeps single.csv's")
    runs = pd.read_parquet(campaign.map_path)
    assert runs.loc[runs["measurement_id"].isin(
        runs.loc[runs["source_file"] == "single.csv", "measurement_id"]), "repeat"].tolist() == [1]
    assert "single_r2.csv" not in set(runs["source_file"])


def test_a_copy_of_a_file_the_map_holds_from_elsewhere_is_named(lab: Path) -> None:
    """The map already holds single.csv from `tribopipe reduce`; the campaign's copy under
    another name with other labels is a conflict against the map."""
    campaign = load_campaign(lab / "campaign.toml")
    elsewhere = lab / "elsewhere" / "DS30_steel_7N.csv"
    elsewhere.parent.mkdir()
    shutil.copy(lab / "raw" / "single.csv", elsewhere)
    result = CliRunner().invoke(main, [
        "reduce", str(elsewhere), "--pin", "Dragonskin 30", "--disc", "steel", "--force", "7",
        "--temperature", "20", "--repeat", "5", "--map", str(campaign.map_path),
        "--output", str(lab / "o")])
    assert result.exit_code == 0, result.output
    report = run_campaign(campaign, jobs=1)
    reason = dict(report.failures)["single.csv"]
    assert "same content as DS30_steel_7N.csv but other labels (repeat 5 vs 1)" in reason


def test_a_renamed_and_relabelled_file_takes_its_runs_along(lab: Path) -> None:
    """A file named with the wrong repeat is renamed and its manifest row corrected: the
    same content under a new name whose old name left the folder is a rename, not a
    conflict; its run keeps its id and takes the new labels."""
    campaign = load_campaign(lab / "campaign.toml")
    run_campaign(campaign, jobs=1)
    old = pd.read_parquet(campaign.map_path)
    old_id = old.loc[old["source_file"] == "single.csv", "measurement_id"].item()
    raw = lab / "raw"
    (raw / "single.csv").rename(raw / "single_r2.csv")
    manifest = raw / "manifest.csv"
    manifest.write_text(manifest.read_text(encoding="utf-8").replace(
        "single.csv,,Dragonskin 30,steel,7,20,1", "single_r2.csv,,Dragonskin 30,steel,7,20,2"),
        encoding="utf-8")
    report = run_campaign(campaign, jobs=1)
    assert report.reduced == ["single_r2.csv"]
    assert sorted(dict(report.failures)) == ["legacy.xls"]
    assert any("single_r2.csv: same content as single.csv, which left the folder: taken as "
               "renamed" in n for n in report.notes)
    runs = pd.read_parquet(campaign.map_path)
    assert len(runs) == 10
    row = runs.loc[runs["measurement_id"] == old_id].iloc[0]
    assert (row["source_file"], row["repeat"]) == ("single_r2.csv", 2)


# --------------------------------------------------------------------------- the CLI


def test_batch_folder_with_a_test_manifest_and_a_test_pattern(lab: Path) -> None:
    raw = lab / "raw"
    manifest = raw / "manifest.csv"  # a folder campaign has no [names]: short names
    manifest.write_text(manifest.read_text(encoding="utf-8").replace("Dragonskin 30", "DS30"),
                        encoding="utf-8")
    result = CliRunner().invoke(main, [
        "batch", str(raw), "--manifest", str(manifest), "--test-pattern",
        TEST_PATTERN, "--output", str(lab / "proc"), "--no-plots", "--jobs", "1"])
    assert result.exit_code == 1, result.output
    out = result.stdout
    assert "raw: 5 file(s) found (4 read, 1 failed), 10 test(s); 10 run(s) in the files " \
           "read: 10 reduced, 0 skipped (unchanged), 0 failed" in out
    assert "  manifest row matching no file: manifest.csv line 7 (ghost.txt)" in out
    assert "  manifest row matching no test: manifest.csv line 5 (session.txt, test " \
           "'DS30 on steel, 9 N, 20 °C, #1')" in out
    assert "2 manifest row(s) matched nothing" in result.stderr
    assert "Traceback" not in result.output
    runs = pd.read_parquet(lab / "proc" / "friction_map.parquet")
    assert len(runs) == 10 and set(runs["pin"]) == {"Dragonskin 30"}
    assert set(runs["pin_as_given"]) == {"DS30"}


def test_campaign_list_shows_one_row_per_run(lab: Path) -> None:
    config = lab / "campaign.toml"
    listing = {(r["file"], r["test"]): r for r in campaign_listing(load_campaign(config))}
    # before any batch: the manifest's test rows, else the file
    assert listing[("session.txt", NAMES[1])]["status"] == "new"
    assert listing[("session.txt", NAMES[1])]["normal_force_N"] == 3.0
    assert listing[("session.xlsx", None)]["status"] == "new"
    CliRunner().invoke(main, ["batch", str(config)])
    result = CliRunner().invoke(main, ["campaign", "list", str(config)])
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    fr = [ln for ln in lines if ln.startswith("SESSION_FR.CSV")]
    assert len(fr) == 3 and all("reduced" in ln for ln in fr)
    assert any("DS30 on steel, 5 N, 20 °C, #2" in ln for ln in fr)
    assert "12 row(s) in 6 file(s): 1 failed, 10 reduced, 1 skipped (not an export)" \
        in result.stdout


@pytest.mark.slow  # a real process or a larger data set: `pytest -m slow`
def test_batch_a_session_folder_in_a_real_process(lab: Path) -> None:
    env = {**os.environ, "PYTHONIOENCODING": "utf-8"}
    cmd = [sys.executable, "-m", "tribopipe", "batch", str(lab / "campaign.toml"), "--jobs", "2"]
    first = subprocess.run(cmd, capture_output=True, text=True, encoding="utf-8", env=env,
                           timeout=300)
    assert first.returncode == 1, first.stderr
    assert "10 reduced" in first.stdout and "ghost.txt" in first.stdout
    for name in ("notes.txt", "legacy.xls"):
        (lab / "raw" / name).unlink()
    manifest = lab / "raw" / "manifest.csv"
    kept = [ln for ln in manifest.read_text(encoding="utf-8").splitlines()
            if "ghost.txt" not in ln and "9 N" not in ln]
    manifest.write_text("\n".join(kept) + "\n", encoding="utf-8")
    second = subprocess.run(cmd, capture_output=True, text=True, encoding="utf-8", env=env,
                            timeout=300)
    assert second.returncode == 0, second.stdout + second.stderr
    # session.txt's manifest rows changed (the 9 N row went): its runs only are redone
    assert "4 file(s) found (4 read), 10 test(s); 10 run(s) in the files read: 3 reduced, " \
           "7 skipped (unchanged), 0 failed" in second.stdout


def test_a_test_name_with_a_control_character_fails_its_run_alone(tmp_path: Path) -> None:
    """The Test name now lands in the map's ``test`` column: a name that is not one line of
    printable text (an escape sequence, a terminal could run it) refuses that run in one
    line; the other file lands and the map stays readable."""
    raw = tmp_path / "raw"
    raw.mkdir()
    write_rheocompass_export(raw / "a.txt", run(0.6, 0.47, 3.0, 41), project="p",
                             test="friction\x1b[2J", sample="DS30")
    write_rheocompass_export(raw / "b.txt", run(0.6, 0.47, 3.0, 42), project="p",
                             test="friction", sample="DS30")
    (raw / "manifest.csv").write_text(
        "file,pin,disc,normal_force_N,temperature_C,repeat\n"
        "a.txt,Dragonskin 30,steel,3,20,1\nb.txt,Dragonskin 30,steel,3,20,2\n",
        encoding="utf-8")
    result = CliRunner().invoke(main, ["batch", str(raw), "--manifest",
                                       str(raw / "manifest.csv"), "--output", str(tmp_path / "o"),
                                       "--no-plots", "--jobs", "1"])
    assert result.exit_code == 1 and "Traceback" not in result.output
    (line,) = [ln for ln in result.stderr.splitlines() if ln.startswith("failed: a.txt")]
    assert "test: expected one line of printable text" in line and "\\x1b" in line
    assert "\x1b" not in result.output
    runs = pd.read_parquet(tmp_path / "o" / "friction_map.parquet")
    assert runs["source_file"].tolist() == ["b.txt"] and runs["test"].tolist() == ["friction"]

"""`tribopipe batch` / `tribopipe campaign list|run` end to end, as a user types them."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe.cli import main

PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
GOOD = {"DS30_steel_1N_20C_r1": 0.62, "DS30_steel_5N_20C_r1": 0.36, "DS30_steel_5N_20C_r2": 0.37}
BAD = "DS30_steel_9N_20C_r1.csv"


@pytest.fixture(scope="module")
def exports(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("cli_exports")
    for seed, (stem, mu_k) in enumerate(GOOD.items()):
        force = float(stem.split("_")[2].rstrip("N"))
        run = SyntheticRun(mu_s=1.3 * mu_k, mu_k=mu_k, normal_force_N=force, temperature_C=20.0,
                           duration_s=150.0, noise=0.004, seed=seed)
        write_rheocompass_export(folder / f"{stem}.csv", run, project="cli", test="t",
                                 sample="DS30")
    # an export cut off mid-file (a note is no export: tests/test_content_first.py)
    whole = next(iter(sorted(folder.glob("*.csv")))).read_bytes()
    (folder / BAD).write_bytes(whole[: len(whole) // 2 // 2 * 2])
    return folder


@pytest.fixture()
def config(exports: Path, tmp_path: Path) -> Path:
    shutil.copytree(exports, tmp_path / "raw")
    cfg = tmp_path / "campaign.toml"
    cfg.write_text(
        f'[campaign]\nname = "cli"\nraw_dir = "raw"\noutput_dir = "out"\n'
        f'filename_pattern = "{PATTERN}"\nplots = false\n[names]\nDS30 = "Dragonskin 30"\n',
        encoding="utf-8",
    )
    return cfg


def invoke(*args: str):
    return CliRunner().invoke(main, list(args))


def test_batch_config_lands_good_runs_and_lists_the_bad_one(config: Path) -> None:
    result = invoke("batch", str(config))
    assert result.exit_code == 1, result.output
    # the bad file is a file that failed (not read), not a run
    assert "4 file(s) found (3 read, 1 failed), 3 test(s); 3 run(s) in the files read: " \
           "3 reduced, 0 skipped (unchanged), 0 failed" in result.stdout
    assert f"failed: {BAD}: " in result.stderr
    assert "Traceback" not in result.output
    out = config.parent / "out"
    runs = pd.read_parquet(out / "friction_map.parquet")
    assert sorted(Path(f).stem for f in runs["source_file"]) == sorted(GOOD)
    assert (out / "failures.csv").read_text(encoding="utf-8").splitlines()[1].startswith(BAD)
    assert len(list((out / "traces").glob("*.parquet"))) == len(GOOD)
    # the groups as the compact paper table, before the account of the run
    from tribopipe.export.tables import paper_text

    assert paper_text(runs) in result.stdout
    assert result.stdout.index(paper_text(runs)) < result.stdout.index("file(s) found")

    again = invoke("batch", str(config))
    assert again.exit_code == 1  # the bad file still fails and is still listed
    assert "(3 read, 1 failed)" in again.stdout
    assert "0 reduced, 3 skipped (unchanged), 0 failed" in again.stdout
    assert f"failed: {BAD}: " in again.stderr


def test_campaign_run_is_batch(config: Path) -> None:
    (config.parent / "raw" / BAD).unlink()
    result = invoke("campaign", "run", str(config), "--jobs", "2")
    assert result.exit_code == 0, result.output
    assert "3 reduced" in result.stdout
    assert invoke("campaign", "run", str(config)).stdout.count("3 skipped") == 1


def test_campaign_list_shows_metadata_and_status(config: Path) -> None:
    before = invoke("campaign", "list", str(config))
    assert before.exit_code == 0, before.output
    lines = before.stdout.splitlines()
    assert lines[0].split()[:6] == ["file", "test", "interval", "status", "pin", "disc"]
    row = next(line for line in lines if line.startswith("DS30_steel_5N_20C_r2.csv"))
    # not read yet: its tests are not known
    assert row.split()[1:4] == ["-", "-", "new"] and "Dragonskin 30" in row
    assert "4 row(s) in 4 file(s): 4 new" in before.stdout

    invoke("batch", str(config))
    after = invoke("campaign", "list", str(config), "--json")
    rows = {r["file"]: r for r in json.loads(after.stdout)}
    assert rows[BAD]["status"] == "failed" and rows[BAD]["reason"]
    assert rows["DS30_steel_5N_20C_r1.csv"]["status"] == "reduced"
    assert rows["DS30_steel_5N_20C_r1.csv"]["mu_k"] == pytest.approx(0.36, abs=0.02)
    assert rows["DS30_steel_5N_20C_r1.csv"]["normal_force_N"] == 5.0


def test_quick_batch_of_a_folder_with_a_manifest(exports: Path, tmp_path: Path) -> None:
    folder = tmp_path / "runs"
    shutil.copytree(exports, folder)
    manifest = tmp_path / "manifest.csv"
    manifest.write_text(
        "file,pin,disc,normal_force_N,temperature_C,repeat,operator\n"
        "DS30_steel_1N_20C_r1.csv,Dragonskin 30,steel,1,20,1,RB\n"
        "DS30_steel_5N_20C_r1.csv,Dragonskin 30,steel,5,20,1,RB\n",
        encoding="utf-8",
    )
    map_path = tmp_path / "lab" / "map.parquet"
    result = invoke("batch", str(folder), "--manifest", str(manifest), "--map", str(map_path),
                    "--output", str(tmp_path / "proc"), "--no-plots")
    assert result.exit_code == 1  # two files have no manifest row
    assert "2 reduced" in result.stdout and "2 failed" in result.stdout
    assert "no row for it in manifest manifest.csv" in result.stderr
    runs = pd.read_parquet(map_path)
    assert sorted(runs["normal_force_N"]) == [1.0, 5.0]
    # the default instrument: 3 pins of r = 3 mm, 5 N -> 58.95 kPa per pin
    assert sorted(runs["pressure_kPa"].round(2)) == [11.79, 58.95]


def test_folder_without_metadata_source_is_one_clear_line(exports: Path) -> None:
    result = invoke("batch", str(exports))
    assert result.exit_code == 1
    assert "no metadata source" in result.output and "--manifest" in result.output
    assert "Traceback" not in result.output


def test_folder_options_are_refused_with_a_config(config: Path) -> None:
    result = invoke("batch", str(config), "--manifest", str(config))
    assert result.exit_code == 2
    assert "--manifest: only with a FOLDER" in result.output


def test_bad_config_names_the_file_and_key(tmp_path: Path) -> None:
    cfg = tmp_path / "bad.toml"
    cfg.write_text('[campaign]\nraw_dir = "."\nfilename_pattern = "{pin}"\nglobb = "*"\n',
                   encoding="utf-8")
    result = invoke("campaign", "list", str(cfg))
    assert result.exit_code == 1
    assert str(cfg) in result.output and "globb" in result.output
    assert "Traceback" not in result.output


@pytest.mark.slow  # a real process or a larger data set: `pytest -m slow`
def test_batch_in_a_real_process(config: Path) -> None:
    """The installed entry point, as `make demo` calls it: no TTY, so no progress bar."""
    env = {**os.environ, "PYTHONIOENCODING": "utf-8"}
    cmd = [sys.executable, "-m", "tribopipe", "batch", str(config), "--jobs", "2"]
    first = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=300)
    assert first.returncode == 1, first.stderr
    assert "3 reduced" in first.stdout and "1 failed" in first.stdout
    assert BAD in first.stderr and "Traceback" not in first.stderr
    assert "reducing" not in first.stderr  # the progress bar is for terminals only

    (config.parent / "raw" / BAD).unlink()
    second = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=300)
    assert second.returncode == 0, second.stderr
    assert "0 reduced, 3 skipped (unchanged), 0 failed" in second.stdout


def _imported(importtime_stderr: str) -> set[str]:
    """The modules a ``python -X importtime`` process imported (from its stderr)."""
    names = set()
    for line in importtime_stderr.splitlines():
        if line.startswith("import time:") and line.count("|") == 2:
            names.add(line.rsplit("|", 1)[1].strip())
    return names


def test_unchanged_rerun_reads_no_map_and_imports_no_pandas(config: Path) -> None:
    """An unchanged re-run, as a real process: it neither reads the map nor prints its
    groups again (the batch left the map as it was), so neither pandas nor pyarrow is
    imported; the ledger still accounts for every file."""
    assert invoke("batch", str(config)).exit_code == 1  # the bad file fails
    the_map = config.parent / "out" / "friction_map.parquet"
    before = the_map.stat()
    env = {**os.environ, "PYTHONIOENCODING": "utf-8"}
    again = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "tribopipe", "batch", str(config)],
        capture_output=True, text=True, env=env, timeout=300)
    assert again.returncode == 1, again.stderr[-2000:]
    assert "0 reduced, 3 skipped (unchanged), 0 failed" in again.stdout
    assert f"failed: {BAD}: " in again.stderr and "Traceback" not in again.stderr
    assert ": unchanged" in again.stdout
    modules = _imported(again.stderr)
    assert "tribopipe.campaign.batch" in modules  # the probe sees the batch's imports
    heavy = sorted(m for m in modules if m.split(".")[0] in ("pandas", "pyarrow"))
    assert heavy == []
    from tribopipe.export.tables import paper_text

    assert paper_text(pd.read_parquet(the_map)) not in again.stdout
    after = the_map.stat()
    assert (after.st_size, after.st_mtime_ns) == (before.st_size, before.st_mtime_ns)


def test_plots_only_for_runs_reduced_now(config: Path) -> None:
    plots = config.parent / "out" / "plots" / "traces"
    assert invoke("batch", str(config), "--no-plots").exit_code == 1
    assert not plots.exists()

    target = config.parent / "raw" / "DS30_steel_5N_20C_r2.csv"
    run = SyntheticRun(mu_s=0.5, mu_k=0.4, normal_force_N=5.0, temperature_C=20.0,
                       duration_s=150.0, noise=0.004, seed=42)
    write_rheocompass_export(target, run, project="cli", test="t", sample="DS30")
    result = invoke("batch", str(config), "--plots")
    assert "1 reduced, 2 skipped" in result.stdout
    pngs = sorted(plots.glob("*.png"))
    # only the re-measured run is drawn; unchanged runs keep (here: lack) their plot
    assert [p.name.rsplit("_", 1)[0] for p in pngs] == ["DS30_steel_5N_20C_r2"]
    assert pngs[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "plots/traces/" in result.stdout


def test_quick_batch_of_a_folder_by_file_names(exports: Path, tmp_path: Path) -> None:
    folder = tmp_path / "runs"
    shutil.copytree(exports, folder)
    for p in folder.glob("*.csv"):
        p.rename(p.with_suffix(".txt"))
    result = invoke("batch", str(folder), "--pattern", PATTERN, "--glob", "*_r1.txt",
                    "--output", str(tmp_path / "proc"), "--no-plots", "--jobs", "1")
    # the r2 run is outside the glob; the bad r1 file fails
    assert "3 file(s) found (2 read, 1 failed)" in result.stdout, result.output
    assert "2 run(s) in the files read: 2 reduced" in result.stdout, result.output
    runs = pd.read_parquet(tmp_path / "proc" / "friction_map.parquet")
    # no [names] table for a folder: the vocabulary knows the vendor code
    assert set(runs["pin"]) == {"Dragonskin 30"} and set(runs["pin_as_given"]) == {"DS30"}
    assert sorted(runs["normal_force_N"]) == [1.0, 5.0]


def test_map_option_overrides_the_config(config: Path, tmp_path: Path) -> None:
    elsewhere = tmp_path / "shared" / "lab_map.parquet"
    result = invoke("campaign", "run", str(config), "--map", str(elsewhere), "--no-plots")
    assert result.exit_code == 1
    assert len(pd.read_parquet(elsewhere)) == len(GOOD)
    assert not (config.parent / "out" / "friction_map.parquet").exists()


def test_an_export_given_as_campaign_gets_a_hint(exports: Path) -> None:
    result = invoke("batch", str(exports / "DS30_steel_5N_20C_r1.csv"))
    assert result.exit_code == 1
    assert "DS30_steel_5N_20C_r1.csv" in result.output
    assert "not a campaign config" in result.output and "tribopipe reduce" in result.output
    assert "Traceback" not in result.output


def test_a_glob_that_matches_nothing_says_so(config: Path) -> None:
    text = config.read_text(encoding="utf-8").replace('raw_dir = "raw"',
                                                      'raw_dir = "raw"\nglob = "*.txt"')
    config.write_text(text, encoding="utf-8")
    result = invoke("batch", str(config))
    assert result.exit_code == 0
    assert "0 run(s)" in result.stdout
    assert "no file matches '*.txt'" in result.stderr


def test_batch_names_a_hostile_map_and_output_folder_on_one_line(config: Path) -> None:
    """The map's path and the output folder come from the config: the closing lines write
    them as terminal text, so a newline or a bidi override neither splits nor reorders
    them."""
    text = config.read_text(encoding="utf-8").replace(
        'output_dir = "out"', 'output_dir = "out\\u202eput"\nmap = "m\\nap.parquet"')
    config.write_text(text, encoding="utf-8")
    result = invoke("batch", str(config))
    assert "Traceback" not in result.output
    lines = result.stdout.splitlines()
    assert any(line.startswith("map ") and line.endswith(
        "m\\nap.parquet: 3 added, 0 unchanged, 0 replaced, 0 kept conflicting")
        for line in lines), result.stdout
    assert "out\\u202eput/: runs.csv" in result.stdout and "\u202e" not in result.stdout

"""An unchanged re-run reports the ledger its last batch kept, and nothing else does.

A batch that found nothing to do keeps its report in the state; the next batch that finds
the campaign exactly as it was (the same files by name, size, mtime, ctime and inode, the
same config, vocabulary, manifest and map, every trace and table still there) reports it
again without reading a file or a state row (``report.kept``). Each test here changes one
thing and asserts what the batch then does: the full batch, and the work it implies.
Real synthetic exports, real maps and states, the real CLI as a subprocess.
"""

from __future__ import annotations

import json
import os
import shutil
import sqlite3
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pandas as pd
import pytest

from generators.synthetic import SyntheticRun, write_rheocompass_export
from helpers import write_campaign_config
from tribopipe.campaign import load_campaign, run_campaign
from tribopipe.campaign.ledger import BatchReport
from tribopipe.campaign.spec import Campaign
from tribopipe.campaign.state import KEPT_KEY
from tribopipe.frictionmap import parts as fm_parts
from tribopipe.review import HEADER as REVIEW_HEADER

PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
GOOD = {
    "DS30_steel_1N_20C_r1": (0.80, 0.62, 1.0),
    "DS30_steel_5N_20C_r1": (0.47, 0.36, 5.0),
    "LS1_steel_5N_20C_r1": (0.55, 0.42, 5.0),
}
LAB_MATERIALS = '[materials]\n"{name}" = {{ class = "silicone elastomer", aliases = ["LS1"] }}\n'


def _write(path: Path, mu_s: float, mu_k: float, force_N: float, seed: int) -> None:
    run = SyntheticRun(mu_s=mu_s, mu_k=mu_k, normal_force_N=force_N, temperature_C=20.0,
                       duration_s=150.0, noise=0.004, seed=seed)
    write_rheocompass_export(path, run, project="rerun test", test="friction", sample="pin")


@pytest.fixture(scope="module")
def exports(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Three good exports (one of a lab's own material), a truncated one (a failure the
    ledger lists every time) and a note (not an export: skipped, said every time)."""
    folder = tmp_path_factory.mktemp("exports")
    for seed, (stem, (mu_s, mu_k, force)) in enumerate(GOOD.items()):
        _write(folder / f"{stem}.csv", mu_s, mu_k, force, seed)
    whole = (folder / "DS30_steel_1N_20C_r1.csv").read_bytes()
    (folder / "DS30_steel_9N_20C_r1.csv").write_bytes(whole[: len(whole) // 4 * 2])
    (folder / "notes.txt").write_text("pins cut on Monday, discs cleaned with IPA\n")
    return folder


def _config(root: Path, extra_lines: tuple[str, ...] = ()) -> Path:
    return write_campaign_config(
        root, ['name = "rerun"', 'raw_dir = "raw"', 'output_dir = "out"',
               f'filename_pattern = "{PATTERN}"', "plots = true", *extra_lines])


@pytest.fixture()
def root(exports: Path, tmp_path: Path) -> Path:
    shutil.copytree(exports, tmp_path / "raw")
    (tmp_path / "materials.toml").write_text(LAB_MATERIALS.format(name="Lab silicone A"))
    _config(tmp_path)
    return tmp_path


def _batch(root: Path) -> BatchReport:
    return run_campaign(load_campaign(root / "campaign.toml"), jobs=1)


def _settled(root: Path) -> tuple[Campaign, BatchReport]:
    """The campaign reduced, then batched again with nothing changed (that batch keeps
    its ledger), then once more: that one reports the kept ledger."""
    first = _batch(root)
    assert len(first.reduced) == len(GOOD) and not first.kept
    quiet = _batch(root)
    assert quiet.reduced == [] and not quiet.kept
    kept = _batch(root)
    assert kept.kept, "an unchanged campaign reports the ledger its last batch kept"
    assert kept.ledger() == quiet.ledger() and kept.failures == quiet.failures
    assert kept.notes == quiet.notes and kept.skipped == quiet.skipped
    return load_campaign(root / "campaign.toml"), quiet


def _stamps(campaign: Campaign) -> dict[str, int]:
    paths = [campaign.runs_csv, campaign.failures_csv, campaign.state_path,
             campaign.map_path / fm_parts.MANIFEST]
    return {p.name: p.stat().st_mtime_ns for p in paths}


def test_the_kept_ledger_is_the_one_an_unchanged_batch_printed(root: Path) -> None:
    campaign, quiet = _settled(root)
    assert "notes.txt" in " ".join(quiet.notes)  # said again, not read again
    assert dict(quiet.failures).keys() == {"DS30_steel_9N_20C_r1.csv"}
    before = _stamps(campaign)
    again = _batch(root)
    assert again.kept and not again.ok  # the failure still sets the exit code
    assert again.map_summary == "unchanged" and not again.map_landed
    assert again.map_path == campaign.map_path and again.output_dir == campaign.output_dir
    assert _stamps(campaign) == before, "a kept ledger writes nothing"


def test_a_touched_file_is_hashed_again_and_skipped(root: Path) -> None:
    campaign, _ = _settled(root)
    path = campaign.raw_dir / "DS30_steel_5N_20C_r1.csv"
    st = path.stat()
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))
    touched = _batch(root)
    assert not touched.kept and touched.reduced == []  # same bytes: its runs are skipped
    assert len(touched.skipped) == len(GOOD)
    assert _batch(root).kept


def test_a_changed_file_is_reduced_again(root: Path) -> None:
    campaign, _ = _settled(root)
    path = campaign.raw_dir / "DS30_steel_5N_20C_r1.csv"
    _write(path, 0.50, 0.40, 5.0, seed=99)
    changed = _batch(root)
    assert not changed.kept and changed.reduced == ["DS30_steel_5N_20C_r1.csv"]
    rows = pd.read_parquet(campaign.map_path)
    mu_k = rows.loc[rows["source_file"].str.endswith("DS30_steel_5N_20C_r1.csv"), "mu_k"]
    assert mu_k.iloc[0] == pytest.approx(0.40, abs=0.02)


def test_a_changed_config_reduces_every_file_again(root: Path) -> None:
    _settled(root)
    _config(root, ("force_tolerance_rel = 0.2",))
    changed = _batch(root)
    assert not changed.kept and sorted(changed.reduced) == sorted(f"{s}.csv" for s in GOOD)


def test_a_deleted_trace_is_reduced_again(root: Path) -> None:
    campaign, _ = _settled(root)
    traces = sorted(campaign.layout.traces_dir.glob("*.parquet"))
    assert len(traces) == len(GOOD)
    traces[0].unlink()
    again = _batch(root)
    assert not again.kept and len(again.reduced) == 1
    assert traces[0].is_file()


def test_a_deleted_plot_is_what_the_full_batch_does_with_it(root: Path) -> None:
    """The table checks the traces, not the plots (a batch draws a run's plot when it
    reduces it): the kept ledger and the full batch agree that a plot removed by hand
    is left removed."""
    campaign, quiet = _settled(root)
    plots = sorted(campaign.plots_dir.glob("*.png"))
    assert len(plots) == len(GOOD)
    plots[0].unlink()
    kept = _batch(root)
    with sqlite3.connect(campaign.state_path) as con:  # the full batch, for comparison
        con.execute("DELETE FROM meta WHERE key = ?", (KEPT_KEY,))
    full = _batch(root)
    assert kept.kept and not full.kept
    assert kept.ledger() == full.ledger() == quiet.ledger() and full.reduced == []
    assert not plots[0].exists()


def test_a_deleted_table_is_written_again(root: Path) -> None:
    campaign, _ = _settled(root)
    text = campaign.runs_csv.read_text(encoding="utf-8")
    campaign.runs_csv.unlink()
    campaign.failures_csv.unlink()
    again = _batch(root)
    assert not again.kept and again.reduced == []
    assert campaign.runs_csv.read_text(encoding="utf-8") == text
    assert campaign.failures_csv.is_file()


def test_a_map_written_by_another_is_read_and_a_missing_map_refilled(root: Path) -> None:
    campaign, _ = _settled(root)
    manifest = campaign.map_path / fm_parts.MANIFEST
    st = manifest.stat()
    os.utime(manifest, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))  # another writer
    read = _batch(root)
    assert not read.kept and read.reduced == []  # its ids read: every run is there
    assert _batch(root).kept
    shutil.rmtree(campaign.map_path)
    refilled = _batch(root)
    assert not refilled.kept and len(refilled.reduced) == len(GOOD)
    assert len(pd.read_parquet(campaign.map_path)) == len(GOOD)


def test_an_added_file_is_reduced(root: Path) -> None:
    campaign, _ = _settled(root)
    _write(campaign.raw_dir / "DS30_steel_1N_20C_r2.csv", 0.81, 0.63, 1.0, seed=7)
    added = _batch(root)
    assert not added.kept and added.reduced == ["DS30_steel_1N_20C_r2.csv"]
    assert added.files == len(GOOD) + 2


def test_a_removed_file_leaves_the_state_and_keeps_its_map_rows(root: Path) -> None:
    campaign, _ = _settled(root)
    (campaign.raw_dir / "DS30_steel_5N_20C_r1.csv").unlink()
    removed = _batch(root)
    assert not removed.kept and removed.reduced == []
    assert any("DS30_steel_5N_20C_r1.csv: no longer in" in n for n in removed.notes)
    assert len(pd.read_parquet(campaign.map_path)) == len(GOOD)
    assert removed.files == len(GOOD)
    # that note is said once: the next batch finds nothing to do, and keeps that
    assert not _batch(root).kept and _batch(root).kept


def test_a_moved_material_alias_relabels_its_runs(root: Path) -> None:
    campaign, _ = _settled(root)
    (root / "materials.toml").write_text(LAB_MATERIALS.format(name="Lab silicone B"))
    moved = _batch(root)
    assert not moved.kept and moved.reduced == ["LS1_steel_5N_20C_r1.csv"]
    pins = set(pd.read_parquet(campaign.map_path)["pin"])
    assert "Lab silicone B" in pins and "Lab silicone A" not in pins


def test_a_changed_manifest_is_read(root: Path) -> None:
    manifest = root / "raw" / "manifest.csv"
    manifest.write_text("file,pin,disc,normal_force_N,temperature_C,repeat\n"
                        "DS30_steel_5N_20C_r1.csv,DS30,steel,5,20,1\n", encoding="utf-8")
    _config(root, ('manifest = "raw/manifest.csv"',))
    _settled(root)
    manifest.write_text("file,pin,disc,normal_force_N,temperature_C,repeat\n"
                        "DS30_steel_5N_20C_r1.csv,DS30,steel,5,20,1\n"
                        "DS30_steel_5N_20C_r2.csv,DS30,steel,5,20,2\n", encoding="utf-8")
    read = _batch(root)
    assert not read.kept and read.reduced == []
    assert [u for u in read.unmatched if "DS30_steel_5N_20C_r2.csv" in u]


def test_a_review_is_applied_on_every_batch(root: Path) -> None:
    _settled(root)
    campaign = load_campaign(root / "campaign.toml")
    review = root / "review.csv"
    review.write_text(",".join(REVIEW_HEADER) + "\n", encoding="utf-8")
    with_review = replace(campaign, review=review)
    assert not run_campaign(with_review, jobs=1).kept
    assert not run_campaign(with_review, jobs=1).kept


def test_a_state_without_a_kept_ledger_or_from_json_still_works(root: Path) -> None:
    """A state an older version wrote (SQLite without the kept ledger, or the JSON file
    of older still) is read: the batch after it is the full one, the one after kept."""
    campaign, _ = _settled(root)
    with sqlite3.connect(campaign.state_path) as con:
        con.execute("DELETE FROM meta WHERE key = ?", (KEPT_KEY,))
    assert not _batch(root).kept and _batch(root).kept
    # the JSON state: from the SQLite one's rows, as version 2 wrote it
    with sqlite3.connect(campaign.state_path) as con:
        entries = {json.loads(n): json.loads(t)
                   for n, t in con.execute("SELECT name, state FROM files")}
    campaign.state_path.unlink()
    campaign.legacy_state_path.write_text(json.dumps(
        {"version": 2, "campaign": campaign.name, "entries": entries}), encoding="utf-8")
    upgraded = _batch(root)
    assert not upgraded.kept and upgraded.reduced == []
    assert len(upgraded.skipped) == len(GOOD)
    assert campaign.state_path.is_file() and _batch(root).kept


def test_a_kept_ledger_prints_what_the_batch_printed(root: Path) -> None:
    """The real command, as a subprocess: the unchanged batch and the kept ledger say the
    same, with the same exit code, and the kept one loads neither pandas nor pyarrow."""
    config = str(root / "campaign.toml")
    probe = ("import runpy, sys; sys.argv = ['tribopipe', 'batch', %r];\n"
             "try:\n    runpy.run_module('tribopipe', run_name='__main__')\n"
             "finally:\n    print('LOADED', *sorted(m for m in ('numpy', 'pandas', "
             "'pyarrow', 'tribopipe.reduction.reduce') if m in sys.modules), file=sys.stderr)")

    def batch() -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-c", probe % config], cwd=root,
                              capture_output=True, text=True, timeout=300,
                              env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})

    first = batch()
    quiet = batch()
    kept = batch()
    assert first.returncode == quiet.returncode == kept.returncode == 1, kept.stderr
    assert kept.stdout == quiet.stdout and "0 reduced" in kept.stdout
    said, loaded = kept.stderr.rsplit("LOADED", 1)
    assert said == quiet.stderr.rsplit("LOADED", 1)[0]
    # the probe sees imports: the full batch loads the reduction (its workers' code)
    assert "tribopipe.reduction.reduce" in quiet.stderr.rsplit("LOADED", 1)[1]
    assert not {"pandas", "pyarrow"} & set(loaded.split()), loaded


def test_a_new_reduction_method_reduces_every_file_again(root: Path,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """The method's version is in the config hash, not in the campaign's fields: a newer
    method (the same config) is the full batch, which reduces every run again."""
    import tribopipe.config

    _settled(root)
    monkeypatch.setattr(tribopipe.config, "REDUCTION_METHOD",
                        tribopipe.config.REDUCTION_METHOD + "-next")
    redone = _batch(root)
    assert not redone.kept and sorted(redone.reduced) == sorted(f"{s}.csv" for s in GOOD)

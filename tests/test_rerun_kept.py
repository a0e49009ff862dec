"""An unchanged re-run reports the ledger its last batch kept, and nothing else does.

A batch that found nothing to do keeps its report in the state; a batch that did its work
cleanly keeps the ledger of its next unchanged re-run, rehearsed (pending: with the
tables that re-run writes). The next batch that finds the campaign exactly as it was (the
same files by name, size, mtime, ctime and inode, the same config, vocabulary, manifest
and map, every trace and table still there) reports it again without reading a file or a
state row (``report.kept``), writing a pending ledger's tables first. Each test here
changes one thing and asserts what the batch then does, after either ledger: the full
batch, and the work it implies; and after working batches of several shapes, the first
re-run prints, exits and writes byte for byte what the full batch does on a copy of the
campaign. Real synthetic exports, real maps and states, the real CLI as a subprocess.
"""

from __future__ import annotations

import hashlib
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
from tribopipe.campaign.stamp import inputs_stamp
from tribopipe.campaign.state import KEPT_KEY, PENDING_KEY, load_kept
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


def _ledger(campaign: Campaign) -> str | None:
    """Which ledger the state keeps: ``"kept"``, ``"pending"`` or ``None``."""
    with sqlite3.connect(campaign.state_path) as con:
        keys = {k for (k,) in con.execute("SELECT key FROM meta WHERE key IN (?, ?)",
                                          (KEPT_KEY, PENDING_KEY))}
    assert len(keys) <= 1, keys
    return {KEPT_KEY: "kept", PENDING_KEY: "pending", None: None}[next(iter(keys), None)]


@pytest.fixture(params=["kept", "pending"])
def after(request: pytest.FixtureRequest) -> str:
    """Which ledger a change meets: the kept one, or the pending one a working batch
    left."""
    return str(request.param)


def _settled(root: Path, after: str = "kept") -> tuple[Campaign, BatchReport | None]:
    """The campaign reduced (that batch keeps its next re-run's ledger as pending);
    ``after="pending"`` stops there (no report: ``None``). Else it is batched again with
    nothing changed (that batch writes the pending tables and keeps its ledger), then once
    more: that one reports the kept ledger."""
    first = _batch(root)
    assert len(first.reduced) == len(GOOD) and not first.kept
    campaign = load_campaign(root / "campaign.toml")
    assert _ledger(campaign) == "pending"
    if after == "pending":
        return campaign, None
    quiet = _batch(root)
    assert quiet.reduced == [] and quiet.kept and _ledger(campaign) == "kept"
    kept = _batch(root)
    assert kept.kept, "an unchanged campaign reports the ledger its last batch kept"
    assert kept.ledger() == quiet.ledger() and kept.failures == quiet.failures
    assert kept.notes == quiet.notes and kept.skipped == quiet.skipped
    return campaign, quiet


def _stamps(campaign: Campaign) -> dict[str, int]:
    paths = [campaign.runs_csv, campaign.failures_csv, campaign.state_path,
             campaign.map_path / fm_parts.MANIFEST]
    return {p.name: p.stat().st_mtime_ns for p in paths}


def test_the_kept_ledger_is_the_one_an_unchanged_batch_printed(root: Path) -> None:
    campaign, quiet = _settled(root)
    assert quiet is not None
    assert "notes.txt" in " ".join(quiet.notes)  # said again, not read again
    assert dict(quiet.failures).keys() == {"DS30_steel_9N_20C_r1.csv"}
    before = _stamps(campaign)
    again = _batch(root)
    assert again.kept and not again.ok  # the failure still sets the exit code
    assert again.map_summary == "unchanged" and not again.map_landed
    assert again.map_path == campaign.map_path and again.output_dir == campaign.output_dir
    assert _stamps(campaign) == before, "a kept ledger writes nothing"


def test_a_touched_file_is_hashed_again_and_skipped(root: Path, after: str) -> None:
    campaign, _ = _settled(root, after)
    path = campaign.raw_dir / "DS30_steel_5N_20C_r1.csv"
    st = path.stat()
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))
    touched = _batch(root)
    assert not touched.kept and touched.reduced == []  # same bytes: its runs are skipped
    assert len(touched.skipped) == len(GOOD)
    assert _batch(root).kept


def test_a_changed_file_is_reduced_again(root: Path, after: str) -> None:
    campaign, _ = _settled(root, after)
    path = campaign.raw_dir / "DS30_steel_5N_20C_r1.csv"
    _write(path, 0.50, 0.40, 5.0, seed=99)
    changed = _batch(root)
    assert not changed.kept and changed.reduced == ["DS30_steel_5N_20C_r1.csv"]
    rows = pd.read_parquet(campaign.map_path)
    mu_k = rows.loc[rows["source_file"].str.endswith("DS30_steel_5N_20C_r1.csv"), "mu_k"]
    assert mu_k.iloc[0] == pytest.approx(0.40, abs=0.02)


def test_a_changed_config_reduces_every_file_again(root: Path, after: str) -> None:
    _settled(root, after)
    _config(root, ("force_tolerance_rel = 0.2",))
    changed = _batch(root)
    assert not changed.kept and sorted(changed.reduced) == sorted(f"{s}.csv" for s in GOOD)


def test_a_deleted_trace_is_reduced_again(root: Path, after: str) -> None:
    campaign, _ = _settled(root, after)
    traces = sorted(campaign.layout.traces_dir.glob("*.parquet"))
    assert len(traces) == len(GOOD)
    traces[0].unlink()
    again = _batch(root)
    assert not again.kept and len(again.reduced) == 1
    assert traces[0].is_file()


def test_a_deleted_plot_is_what_the_full_batch_does_with_it(root: Path, after: str) -> None:
    """The table checks the traces, not the plots (a batch draws a run's plot when it
    reduces it): the kept (or pending) ledger and the full batch agree that a plot
    removed by hand is left removed."""
    campaign, quiet = _settled(root, after)
    plots = sorted(campaign.plots_dir.glob("*.png"))
    assert len(plots) == len(GOOD)
    plots[0].unlink()
    kept = _batch(root)
    with sqlite3.connect(campaign.state_path) as con:  # the full batch, for comparison
        con.execute("DELETE FROM meta WHERE key = ?", (KEPT_KEY,))
    full = _batch(root)
    assert kept.kept and not full.kept
    assert kept.ledger() == full.ledger() and full.reduced == []
    assert quiet is None or quiet.ledger() == full.ledger()
    assert not plots[0].exists()


def test_a_deleted_table_is_written_again(root: Path, after: str) -> None:
    campaign, _ = _settled(root, after)
    # the table an unchanged re-run writes: the pending ledger's, else the one there
    pending = load_kept(campaign)
    assert pending is not None and (pending.tables is None) == (after == "kept")
    text = pending.tables[0] if pending.tables else campaign.runs_csv.read_text("utf-8")
    campaign.runs_csv.unlink()
    campaign.failures_csv.unlink()
    again = _batch(root)
    assert not again.kept and again.reduced == []
    assert campaign.runs_csv.read_text(encoding="utf-8") == text
    assert campaign.failures_csv.is_file()


def test_a_map_written_by_another_is_read_and_a_missing_map_refilled(root: Path,
                                                                     after: str) -> None:
    campaign, _ = _settled(root, after)
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


def test_an_added_file_is_reduced(root: Path, after: str) -> None:
    campaign, _ = _settled(root, after)
    _write(campaign.raw_dir / "DS30_steel_1N_20C_r2.csv", 0.81, 0.63, 1.0, seed=7)
    added = _batch(root)
    assert not added.kept and added.reduced == ["DS30_steel_1N_20C_r2.csv"]
    assert added.files == len(GOOD) + 2


def test_a_removed_file_leaves_the_state_and_keeps_its_map_rows(root: Path, after: str) -> None:
    campaign, _ = _settled(root, after)
    (campaign.raw_dir / "DS30_steel_5N_20C_r1.csv").unlink()
    removed = _batch(root)
    assert not removed.kept and removed.reduced == []
    assert any("DS30_steel_5N_20C_r1.csv: no longer in" in n for n in removed.notes)
    assert len(pd.read_parquet(campaign.map_path)) == len(GOOD)
    assert removed.files == len(GOOD)
    # that note is said once: the next batch finds nothing to do (it was rehearsed: the
    # batch that noted it keeps its ledger as pending)
    assert _ledger(campaign) == "pending"
    again = _batch(root)
    assert again.kept and not [n for n in again.notes if "no longer in" in n]
    assert _ledger(campaign) == "kept" and _batch(root).kept


def test_a_moved_material_alias_relabels_its_runs(root: Path, after: str) -> None:
    campaign, _ = _settled(root, after)
    (root / "materials.toml").write_text(LAB_MATERIALS.format(name="Lab silicone B"))
    moved = _batch(root)
    assert not moved.kept and moved.reduced == ["LS1_steel_5N_20C_r1.csv"]
    pins = set(pd.read_parquet(campaign.map_path)["pin"])
    assert "Lab silicone B" in pins and "Lab silicone A" not in pins


def test_a_changed_manifest_is_read(root: Path, after: str) -> None:
    manifest = root / "raw" / "manifest.csv"
    manifest.write_text("file,pin,disc,normal_force_N,temperature_C,repeat\n"
                        "DS30_steel_5N_20C_r1.csv,DS30,steel,5,20,1\n", encoding="utf-8")
    _config(root, ('manifest = "raw/manifest.csv"',))
    _settled(root, after)
    manifest.write_text("file,pin,disc,normal_force_N,temperature_C,repeat\n"
                        "DS30_steel_5N_20C_r1.csv,DS30,steel,5,20,1\n"
                        "DS30_steel_5N_20C_r2.csv,DS30,steel,5,20,2\n", encoding="utf-8")
    read = _batch(root)
    assert not read.kept and read.reduced == []
    assert [u for u in read.unmatched if "DS30_steel_5N_20C_r2.csv" in u]


def test_a_review_is_applied_on_every_batch(root: Path, after: str) -> None:
    _settled(root, after)
    campaign = load_campaign(root / "campaign.toml")
    review = root / "review.csv"
    review.write_text(",".join(REVIEW_HEADER) + "\n", encoding="utf-8")
    with_review = replace(campaign, review=review)
    assert not run_campaign(with_review, jobs=1).kept
    assert not run_campaign(with_review, jobs=1).kept


def test_a_state_without_a_kept_ledger_or_from_json_still_works(root: Path) -> None:
    """A state an older version wrote (SQLite without the kept ledger, or the JSON file
    of older still) is read: the batch after it is the full one, the one after kept.
    So is a state whose pending ledger is gone."""
    campaign, _ = _settled(root, "pending")
    with sqlite3.connect(campaign.state_path) as con:
        con.execute("DELETE FROM meta WHERE key = ?", (PENDING_KEY,))
    assert not _batch(root).kept and _batch(root).kept and _ledger(campaign) == "kept"
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
    """The real command, as a subprocess: the unchanged batch and the kept ledger (the
    pending one, then the kept one) say the same, with the same exit code, and the kept
    ones load neither pandas nor pyarrow."""
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
    pending = batch()
    kept = batch()
    with sqlite3.connect(load_campaign(root / "campaign.toml").state_path) as con:
        con.execute("DELETE FROM meta WHERE key = ?", (KEPT_KEY,))
    quiet = batch()  # the full batch, nothing changed
    assert first.returncode == pending.returncode == kept.returncode == quiet.returncode \
        == 1, kept.stderr
    assert kept.stdout == pending.stdout == quiet.stdout and "0 reduced" in kept.stdout
    said = quiet.stderr.rsplit("LOADED", 1)[0]
    # the probe sees imports: the full batch loads the reduction (its workers' code)
    assert "tribopipe.reduction.reduce" in quiet.stderr.rsplit("LOADED", 1)[1]
    for ledger in (pending, kept):
        assert ledger.stderr.rsplit("LOADED", 1)[0] == said
        loaded = ledger.stderr.rsplit("LOADED", 1)[1]
        assert not {"pandas", "pyarrow"} & set(loaded.split()), loaded


def test_a_new_reduction_method_reduces_every_file_again(root: Path, after: str,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """The method's version is in the config hash, not in the campaign's fields: a newer
    method (the same config) is the full batch, which reduces every run again."""
    import tribopipe.config

    _settled(root, after)
    monkeypatch.setattr(tribopipe.config, "REDUCTION_METHOD",
                        tribopipe.config.REDUCTION_METHOD + "-next")
    redone = _batch(root)
    assert not redone.kept and sorted(redone.reduced) == sorted(f"{s}.csv" for s in GOOD)


# ------------------------------------------------ the first re-run after a batch that did work


#: the batch as a subprocess, counting its reads of the state's rows (the full batch's
#: first step; the kept and pending ledgers read one row of its meta table instead)
PROBE = """import runpy, sys
import tribopipe.campaign.batch as batch
reads, load_state = [], batch.load_state
batch.load_state = lambda campaign: reads.append(1) or load_state(campaign)
sys.argv = ['tribopipe', 'batch', 'campaign.toml']
try:
    runpy.run_module('tribopipe', run_name='__main__')
finally:
    print('LOADED', *sorted(m for m in ('pandas', 'pyarrow') if m in sys.modules),
          f'state-reads={len(reads)}', file=sys.stderr)
"""


def _cli(root: Path) -> tuple[int, str, str, set[str]]:
    """``tribopipe batch campaign.toml`` run in ``root`` as a subprocess: its exit code,
    what it printed on stdout and stderr, which of pandas and pyarrow it loaded, and how
    often it read the state's rows (``state-reads=N``)."""
    done = subprocess.run([sys.executable, "-c", PROBE], cwd=root, capture_output=True,
                          text=True, timeout=300,
                          env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    said, loaded = done.stderr.rsplit("LOADED", 1)
    return done.returncode, done.stdout, said, set(loaded.split())


def _state(campaign: Campaign) -> tuple[dict[str, str], dict[str, str], dict[str, object]]:
    """The state's file rows and meta rows (the ledger's row apart, as its JSON without
    the inputs' stamp, which names the campaign's folder)."""
    with sqlite3.connect(campaign.state_path) as con:
        rows = dict(con.execute("SELECT name, state FROM files").fetchall())
        meta = dict(con.execute("SELECT key, value FROM meta").fetchall())
    ledger = json.loads(meta.pop(KEPT_KEY))
    assert PENDING_KEY not in meta
    ledger.pop("inputs")
    return rows, meta, ledger


def _map_bytes(campaign: Campaign) -> dict[str, str]:
    """Every file of the map folder by its name in it: the SHA-256 of its bytes."""
    folder = campaign.map_path
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _first_rerun_is_the_full_one(a: Path) -> Campaign:
    """After a batch that did work in ``a``: the next batch in ``a`` takes the pending
    ledger, the full batch on a copy of the campaign (``a`` copied to ``b``, its pending
    ledger removed) does it all over; both print, exit and write the same, byte for byte
    (paths aside: ``b`` is named as long as ``a``)."""
    campaign = load_campaign(a / "campaign.toml")
    assert _ledger(campaign) == "pending"
    b = a.with_name("b")
    shutil.copytree(a, b, symlinks=True)  # mtimes kept: the state's hashes still trusted
    copy = load_campaign(b / "campaign.toml")
    with sqlite3.connect(copy.state_path) as con:
        con.execute("DELETE FROM meta WHERE key = ?", (PENDING_KEY,))
    map_before = _map_bytes(campaign)
    mine, full = _cli(a), _cli(b)
    # the full batch reads the state's rows; the pending ledger reads none, nor loads a
    # table library
    assert "state-reads=1" in full[3] and mine[3] == {"state-reads=0"}, mine[3]
    assert mine[:3] == (full[0], full[1].replace(str(b), str(a)),
                        full[2].replace(str(b), str(a)))
    for table in (campaign.runs_csv, campaign.failures_csv):
        assert table.read_bytes() == (b / table.relative_to(a)).read_bytes(), table.name
    assert _state(campaign) == _state(copy)
    kept = load_kept(campaign)
    assert kept is not None and kept.tables is None and kept.inputs == inputs_stamp(campaign)
    assert _map_bytes(campaign) == _map_bytes(copy) == map_before
    # and the batch after it reports the kept ledger, as it would after the full one
    assert _cli(a)[:3] == mine[:3] and _ledger(campaign) == "kept"
    return campaign


@pytest.fixture()
def lab(exports: Path, tmp_path: Path) -> Path:
    """The campaign of :func:`root` in ``tmp_path/a`` (its copy goes to ``b``), with a
    file whose name says nothing (failed before it is read) and a manifest."""
    a = tmp_path / "a"
    shutil.copytree(exports, a / "raw")
    shutil.copy(a / "raw" / "DS30_steel_5N_20C_r1.csv", a / "raw" / "unnamed.csv")
    (a / "materials.toml").write_text(LAB_MATERIALS.format(name="Lab silicone A"))
    _config(a)
    return a


def test_after_a_first_batch_the_first_rerun_is_the_full_ones(lab: Path) -> None:
    """Every file new: three reduced, one truncated and one unnamed failed, a note set
    aside; the re-run lists them again."""
    first = _batch(lab)
    assert len(first.reduced) == len(GOOD) and len(first.failures) == 2
    _first_rerun_is_the_full_one(lab)


def test_after_duplicates_a_manifest_and_a_conflict(lab: Path) -> None:
    """The manifest names a copy of an export with that export's labels (a duplicate)
    and a file that is not there; a copy under another repeat number is a conflict."""
    raw = lab / "raw"
    (raw / "unnamed.csv").unlink()
    shutil.copy(raw / "DS30_steel_1N_20C_r1.csv", raw / "copy of r1.csv")
    shutil.copy(raw / "DS30_steel_1N_20C_r1.csv", raw / "DS30_steel_1N_20C_r7.csv")
    (raw / "manifest.csv").write_text(
        "file,pin,disc,normal_force_N,temperature_C,repeat\n"
        "copy of r1.csv,DS30,steel,1,20,1\n"
        "DS30_steel_3N_20C_r1.csv,DS30,steel,3,20,1\n", encoding="utf-8")
    _config(lab, ('manifest = "raw/manifest.csv"',))
    first = _batch(lab)
    assert [f for f, _ in first.duplicates] == ["copy of r1.csv"]
    assert [f for f, _ in first.conflicts] == ["DS30_steel_1N_20C_r7.csv"]
    assert first.unmatched
    _first_rerun_is_the_full_one(lab)


def test_after_a_batch_that_found_files_changed_and_gone(lab: Path) -> None:
    """A batch on a reduced campaign: one file changed (reduced again), one gone (noted
    once, its map rows kept), one added, the unnamed one removed."""
    raw = lab / "raw"
    _batch(lab)
    _batch(lab)
    _write(raw / "DS30_steel_5N_20C_r1.csv", 0.50, 0.40, 5.0, seed=99)
    (raw / "LS1_steel_5N_20C_r1.csv").unlink()
    (raw / "unnamed.csv").unlink()
    _write(raw / "DS30_steel_1N_20C_r2.csv", 0.81, 0.63, 1.0, seed=7)
    work = _batch(lab)
    assert sorted(work.reduced) == ["DS30_steel_1N_20C_r2.csv", "DS30_steel_5N_20C_r1.csv"]
    assert [n for n in work.notes if "LS1_steel_5N_20C_r1.csv: no longer in" in n]
    campaign = _first_rerun_is_the_full_one(lab)
    assert "no longer in" not in campaign.runs_csv.read_text(encoding="utf-8")


def test_a_batch_with_a_decisions_file_keeps_no_ledger(lab: Path) -> None:
    """A review is applied on every batch: a batch with one rehearses nothing, and the
    next is the full one."""
    campaign = replace(load_campaign(lab / "campaign.toml"), review=lab / "review.csv")
    (lab / "review.csv").write_text(",".join(REVIEW_HEADER) + "\n", encoding="utf-8")
    assert len(run_campaign(campaign, jobs=1).reduced) == len(GOOD)
    assert _ledger(campaign) is None
    assert not run_campaign(campaign, jobs=1).kept and _ledger(campaign) is None


def test_a_batch_whose_outputs_fail_keeps_no_ledger(lab: Path) -> None:
    """A batch that cannot write one of its tables ends with an output error: nothing is
    rehearsed, the next batch is the full one (and writes it)."""
    campaign = load_campaign(lab / "campaign.toml")
    campaign.failures_csv.mkdir(parents=True)  # a folder where the table goes
    work = _batch(lab)
    assert work.output_errors and _ledger(campaign) is None
    campaign.failures_csv.rmdir()
    again = _batch(lab)
    assert not again.kept and not again.output_errors and campaign.failures_csv.is_file()

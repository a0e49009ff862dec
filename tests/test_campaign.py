"""Batch a campaign like a lab would: good runs land, bad files are listed, re-runs only do
what changed. Real synthetic RheoCompass exports, real Parquet maps, no mocks."""

from __future__ import annotations

import csv
import json
import os
import shutil
from pathlib import Path

import pandas as pd
import pytest

from generators.synthetic import SyntheticRun, write_rheocompass_export
from helpers import write_campaign_config
from map_files import map_bytes
from tribopipe.campaign import campaign_listing, campaign_table, load_campaign, run_campaign
from tribopipe.campaign.table import CHANGED, FAILED, NEW, REDUCED
from tribopipe.frictionmap import parts as fm_parts

PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
DURATION_S = 150.0

#: file stem -> (true mu_s, true mu_k, applied total normal force [N])
GOOD = {
    "DS30_steel_1N_20C_r1": (0.80, 0.62, 1.0),
    "DS30_steel_1N_20C_r2": (0.82, 0.64, 1.0),
    "DS30_steel_5N_20C_r1": (0.47, 0.36, 5.0),
    "EF50_steel_5N_20C_r1": (0.55, 0.42, 5.75),  # 15 % above nominal: QC flag
}


def write_run(path: Path, mu_s: float, mu_k: float, force_N: float, seed: int,
              test: str = "friction") -> Path:
    run = SyntheticRun(mu_s=mu_s, mu_k=mu_k, normal_force_N=force_N, temperature_C=20.0,
                       duration_s=DURATION_S, noise=0.004, seed=seed)
    return write_rheocompass_export(path, run, project="campaign test", test=test,
                                    sample="pin")


def write_config(root: Path, extra: str = "", instrument: str | None = None) -> Path:
    lines = ['name = "lab check"', 'raw_dir = "raw"', 'output_dir = "out"',
             f'filename_pattern = "{PATTERN}"', "plots = false"]
    if instrument:
        lines.append(f'instrument = "{instrument}"')
    return write_campaign_config(root, lines, extra,
                                 {"DS30": "Dragonskin 30", "EF50": "Ecoflex 00-50"})


@pytest.fixture(scope="module")
def exports(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Four good exports and two truncated ones (a note is no export: skipped, tested in
    tests/test_content_first.py)."""
    folder = tmp_path_factory.mktemp("exports")
    for seed, (stem, (mu_s, mu_k, force)) in enumerate(GOOD.items()):
        write_run(folder / f"{stem}.csv", mu_s, mu_k, force, seed=seed)
    # truncated mid-file, as when a USB stick is pulled during the copy
    whole = (folder / "DS30_steel_1N_20C_r1.csv").read_bytes()
    cut = len(whole) // 2 // 2 * 2  # whole UTF-16 code units
    (folder / "DS30_steel_9N_20C_r1.csv").write_bytes(whole[:cut])
    (folder / "DS30_steel_3N_20C_r1.csv").write_bytes(whole[: len(whole) // 3 // 2 * 2])
    return folder


@pytest.fixture()
def campaign_dir(exports: Path, tmp_path: Path) -> Path:
    shutil.copytree(exports, tmp_path / "raw")
    write_config(tmp_path)
    return tmp_path


def read_runs_csv(path: Path) -> dict[str, dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as fh:
        return {row["file"]: row for row in csv.DictReader(fh)}


def test_bad_files_are_listed_and_the_good_runs_land(campaign_dir: Path) -> None:
    campaign = load_campaign(campaign_dir / "campaign.toml")
    seen: list[tuple[int, int]] = []
    report = run_campaign(campaign, jobs=1, progress=lambda d, t: seen.append((d, t)))

    assert sorted(report.reduced) == sorted(f"{s}.csv" for s in GOOD)
    assert report.skipped == []
    failed = dict(report.failures)
    assert set(failed) == {"DS30_steel_9N_20C_r1.csv", "DS30_steel_3N_20C_r1.csv"}
    for file, reason in failed.items():
        assert reason.startswith(f"{file}") and "\n" not in reason
    assert "truncated" in failed["DS30_steel_9N_20C_r1.csv"]
    assert not report.ok
    # 3 condition groups: DS30 1 N, DS30 5 N, EF50 5 N
    assert report.groups_updated == 3

    runs = pd.read_parquet(campaign.map_path)
    assert len(runs) == len(GOOD)
    for _, row in runs.iterrows():
        stem = Path(row["source_file"]).stem
        mu_s, mu_k, _ = GOOD[stem]
        assert row["mu_k"] == pytest.approx(mu_k, abs=0.02)
        assert row["mu_s"] == pytest.approx(mu_s, abs=0.04)
    by_stem = {Path(r.source_file).stem: r for r in runs.itertuples()}
    assert by_stem["DS30_steel_1N_20C_r2"].pin == "Dragonskin 30"
    assert by_stem["DS30_steel_1N_20C_r2"].repeat == 2
    # nominal 1 N on three pins of r = 3 mm: 11.79 kPa per pin
    assert by_stem["DS30_steel_1N_20C_r2"].pressure_kPa == pytest.approx(11.79, abs=0.01)
    assert "normal_force_off_nominal" in by_stem["EF50_steel_5N_20C_r1"].flags.split(";")
    assert "normal_force_off_nominal" not in by_stem["DS30_steel_5N_20C_r1"].flags.split(";")

    table = read_runs_csv(campaign.runs_csv)
    assert len(table) == 6
    assert table["DS30_steel_3N_20C_r1.csv"]["status"] == "failed"
    assert table["DS30_steel_3N_20C_r1.csv"]["reason"]
    good = table["DS30_steel_5N_20C_r1.csv"]
    assert good["status"] == "reduced"
    assert float(good["mu_k"]) == pytest.approx(0.36, abs=0.02)
    assert (campaign.output_dir / good["trace"]).is_file()
    trace = pd.read_parquet(campaign.output_dir / good["trace"])
    assert {"sliding_distance_mm", "mu", "pressure_kPa"} <= set(trace.columns)
    failures = read_runs_csv_like(campaign.failures_csv)
    assert [f["file"] for f in failures] == sorted(failed)
    assert seen[-1] == (6, 6)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)


def read_runs_csv_like(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as fh:
        return list(csv.DictReader(fh))


def test_rerun_skips_everything_and_leaves_the_map_alone(campaign_dir: Path) -> None:
    campaign = load_campaign(campaign_dir / "campaign.toml")
    run_campaign(campaign, jobs=1)
    before = map_bytes(campaign.map_path)
    manifest = campaign.map_path / fm_parts.MANIFEST
    mtime = manifest.stat().st_mtime_ns

    again = run_campaign(campaign, jobs=1)
    assert again.reduced == []
    assert sorted(again.skipped) == sorted(f"{s}.csv" for s in GOOD)
    # unchanged failures stay listed (and keep the exit code non-zero) without a retry
    assert {f for f, _ in again.failures} == {"DS30_steel_9N_20C_r1.csv",
                                              "DS30_steel_3N_20C_r1.csv"}
    assert again.groups_updated == 0
    assert map_bytes(campaign.map_path) == before
    assert manifest.stat().st_mtime_ns == mtime
    statuses = {r.file: r.status for r in campaign_table(campaign)}
    assert statuses["DS30_steel_1N_20C_r1.csv"] == REDUCED
    assert statuses["DS30_steel_3N_20C_r1.csv"] == FAILED
    assert {r["status"] for r in read_runs_csv(campaign.runs_csv).values()} == {"skipped",
                                                                              "failed"}


def test_changed_content_reduces_only_that_file_and_replaces_its_row(campaign_dir: Path) -> None:
    campaign = load_campaign(campaign_dir / "campaign.toml")
    run_campaign(campaign, jobs=1)
    old = pd.read_parquet(campaign.map_path)
    target = campaign_dir / "raw" / "DS30_steel_1N_20C_r2.csv"
    old_id = old.loc[old["source_file"] == target.name, "measurement_id"].item()

    # the lab re-measured this run: new content, same name
    write_run(target, 0.90, 0.70, 1.0, seed=99)
    # and merely touched another one (copied back, same bytes, new mtime)
    other = campaign_dir / "raw" / "DS30_steel_5N_20C_r1.csv"
    os.utime(other, ns=(other.stat().st_atime_ns, other.stat().st_mtime_ns + 10**9))
    assert {r.file: r.status for r in campaign_table(campaign)}[target.name] == CHANGED

    report = run_campaign(campaign, jobs=1)
    assert report.reduced == [target.name]
    assert other.name in report.skipped
    assert report.removed == 1
    new = pd.read_parquet(campaign.map_path)
    assert len(new) == len(old)
    assert old_id not in set(new["measurement_id"])
    row = new.loc[new["source_file"] == target.name].iloc[0]
    assert row["mu_k"] == pytest.approx(0.70, abs=0.02)
    # the others are untouched
    keep = old.loc[old["source_file"] != target.name].set_index("measurement_id")
    assert set(keep.index) <= set(new["measurement_id"])


def test_a_fixed_bad_file_is_retried(campaign_dir: Path) -> None:
    campaign = load_campaign(campaign_dir / "campaign.toml")
    first = run_campaign(campaign, jobs=1)
    assert "DS30_steel_9N_20C_r1.csv" in dict(first.failures)
    write_run(campaign_dir / "raw" / "DS30_steel_9N_20C_r1.csv", 0.40, 0.30, 9.0, seed=5)
    report = run_campaign(campaign, jobs=1)
    assert report.reduced == ["DS30_steel_9N_20C_r1.csv"]
    assert dict(report.failures).keys() == {"DS30_steel_3N_20C_r1.csv"}
    assert len(pd.read_parquet(campaign.map_path)) == len(GOOD) + 1


def test_config_change_re_reduces_every_run_in_place(campaign_dir: Path) -> None:
    campaign = load_campaign(campaign_dir / "campaign.toml")
    run_campaign(campaign, jobs=1)
    before = pd.read_parquet(campaign.map_path)
    (campaign_dir / "wide.toml").write_text("[instrument]\ncontact_threshold_N = 0.3\n",
                                            encoding="utf-8")
    write_config(campaign_dir, instrument="wide.toml")
    changed = load_campaign(campaign_dir / "campaign.toml")
    assert changed.settings.config_hash != campaign.settings.config_hash
    assert {r.status for r in campaign_table(changed) if r.file.startswith(("DS30_steel_1",
                                                                             "EF50"))} \
        == {CHANGED}
    report = run_campaign(changed, jobs=1)
    assert sorted(report.reduced) == sorted(f"{s}.csv" for s in GOOD)
    after = pd.read_parquet(campaign.map_path)
    # same raw files, same ids: rows replaced, not duplicated
    assert sorted(after["measurement_id"]) == sorted(before["measurement_id"])
    assert set(after["config_hash"]) == {changed.settings.config_hash}


def test_tolerance_decides_the_qc_flag(campaign_dir: Path) -> None:
    write_config(campaign_dir, extra="force_tolerance_rel = 0.2")
    campaign = load_campaign(campaign_dir / "campaign.toml")
    run_campaign(campaign, jobs=1)
    runs = pd.read_parquet(campaign.map_path)
    flags = runs.loc[runs["source_file"] == "EF50_steel_5N_20C_r1.csv", "flags"].item()
    # 0.75 N off at 5 N is within 20 %: the campaign's tolerance overrules the default
    assert "normal_force_off_nominal" not in flags.split(";")


def test_lost_map_makes_the_runs_land_again(campaign_dir: Path) -> None:
    campaign = load_campaign(campaign_dir / "campaign.toml")
    run_campaign(campaign, jobs=1)
    shutil.rmtree(campaign.map_path)
    report = run_campaign(campaign, jobs=1)
    assert len(report.reduced) == len(GOOD)
    assert len(pd.read_parquet(campaign.map_path)) == len(GOOD)


def test_parallel_batch_matches_sequential(exports: Path, tmp_path: Path) -> None:
    results = {}
    for jobs in (1, 2):
        root = tmp_path / f"j{jobs}"
        shutil.copytree(exports, root / "raw")
        campaign = load_campaign(write_config(root))
        report = run_campaign(campaign, jobs=jobs)
        assert len(report.reduced) == len(GOOD) and len(report.failures) == 2
        runs = pd.read_parquet(campaign.map_path).sort_values("measurement_id")
        results[jobs] = runs[["measurement_id", "mu_s", "mu_k", "flags"]].reset_index(drop=True)
    pd.testing.assert_frame_equal(results[1], results[2])


def test_listing_before_and_after(campaign_dir: Path) -> None:
    campaign = load_campaign(campaign_dir / "campaign.toml")
    rows = {r["file"]: r for r in campaign_listing(campaign)}
    assert len(rows) == 6
    assert rows["DS30_steel_5N_20C_r1.csv"]["status"] == NEW
    assert rows["DS30_steel_5N_20C_r1.csv"]["pin"] == "Dragonskin 30"
    assert rows["DS30_steel_5N_20C_r1.csv"]["normal_force_N"] == 5.0
    assert rows["DS30_steel_5N_20C_r1.csv"]["mu_k"] is None
    run_campaign(campaign, jobs=1)
    rows = {r["file"]: r for r in campaign_listing(campaign)}
    assert rows["DS30_steel_5N_20C_r1.csv"]["status"] == REDUCED
    assert rows["DS30_steel_5N_20C_r1.csv"]["mu_k"] == pytest.approx(0.36, abs=0.02)
    assert rows["DS30_steel_3N_20C_r1.csv"]["status"] == FAILED
    assert rows["DS30_steel_3N_20C_r1.csv"]["reason"]


def test_export_test_names_as_a_metadata_source(tmp_path: Path) -> None:
    raw = tmp_path / "raw"
    raw.mkdir()
    write_run(raw / "run01.csv", 0.8, 0.6, 3.0, seed=1, test="DS30_steel_3N_20C_r1")
    write_run(raw / "run02.csv", 0.8, 0.6, 3.0, seed=2, test="DS30_steel_3N_20C_r2")
    # the manifest says 5 N where the export's own Test name says 3 N
    (raw / "manifest.csv").write_text(
        "file,pin,disc,normal_force_N,temperature_C,repeat\nrun02.csv,,,5,,\n",
        encoding="utf-8",
    )
    cfg = tmp_path / "c.toml"
    cfg.write_text(
        '[campaign]\nraw_dir = "raw"\noutput_dir = "out"\nplots = false\n'
        'manifest = "raw/manifest.csv"\nuse_export_names = true\n'
        f'export_pattern = "{PATTERN}"\n[names]\nDS30 = "Dragonskin 30"\n',
        encoding="utf-8",
    )
    campaign = load_campaign(cfg)
    report = run_campaign(campaign, jobs=1)
    assert report.reduced == ["run01.csv"]
    (file, reason), = report.failures
    assert file == "run02.csv"
    assert "contradictory normal_force_N" in reason and "export Test name" in reason
    runs = pd.read_parquet(campaign.map_path)
    assert runs["pin"].tolist() == ["Dragonskin 30"]
    assert runs["normal_force_N"].tolist() == [3.0]
    assert runs["repeat"].tolist() == [1]


def test_a_row_removed_from_the_map_lands_again_alone(campaign_dir: Path) -> None:
    from tribopipe.frictionmap import read_map, write_map

    campaign = load_campaign(campaign_dir / "campaign.toml")
    run_campaign(campaign, jobs=1)
    runs = read_map(campaign.map_path)
    gone = runs["source_file"] == "DS30_steel_5N_20C_r1.csv"
    write_map(campaign.map_path, runs.loc[~gone])  # e.g. another tool dropped it
    report = run_campaign(campaign, jobs=1)
    assert report.reduced == ["DS30_steel_5N_20C_r1.csv"]
    assert len(report.skipped) == len(GOOD) - 1
    assert len(pd.read_parquet(campaign.map_path)) == len(GOOD)


def test_a_foreign_file_at_the_map_path_stops_the_batch_before_any_work(
    campaign_dir: Path,
) -> None:
    from tribopipe.errors import MapError

    campaign = load_campaign(campaign_dir / "campaign.toml")
    campaign.map_path.parent.mkdir(parents=True)
    pd.DataFrame({"a": [1]}).to_parquet(campaign.map_path)
    foreign = campaign.map_path.read_bytes()
    with pytest.raises(MapError, match="friction_map.parquet"):
        run_campaign(campaign, jobs=1)
    assert campaign.map_path.read_bytes() == foreign
    assert not (campaign.output_dir / "traces").exists()


def test_two_batches_of_one_campaign_do_not_interleave(campaign_dir: Path) -> None:
    from filelock import FileLock

    from tribopipe.errors import CampaignError
    from tribopipe.layout import BATCH_LOCK

    campaign = load_campaign(campaign_dir / "campaign.toml")
    campaign.output_dir.mkdir(parents=True)
    with FileLock(str(campaign.output_dir / BATCH_LOCK)):
        with pytest.raises(CampaignError, match="another batch"):
            run_campaign(campaign, jobs=1)
    assert not campaign.map_path.exists()
    assert len(run_campaign(campaign, jobs=1).reduced) == len(GOOD)


def test_campaigns_sharing_an_output_folder_keep_their_own_state(
    campaign_dir: Path, tmp_path_factory: pytest.TempPathFactory
) -> None:
    first = load_campaign(campaign_dir / "campaign.toml")
    other_raw = campaign_dir / "raw2"
    other_raw.mkdir()
    write_run(other_raw / "EF50_steel_1N_20C_r1.csv", 1.2, 0.9, 1.0, seed=11)
    cfg = campaign_dir / "second.toml"
    cfg.write_text(
        f'[campaign]\nname = "second lab"\nraw_dir = "raw2"\noutput_dir = "out"\n'
        f'filename_pattern = "{PATTERN}"\nplots = false\n', encoding="utf-8")
    second = load_campaign(cfg)
    assert second.state_path != first.state_path
    assert second.state_path.name == ".tribopipe-state.second-lab.sqlite"

    run_campaign(first, jobs=1)
    assert run_campaign(second, jobs=1).reduced == ["EF50_steel_1N_20C_r1.csv"]
    again = run_campaign(first, jobs=1)
    assert again.reduced == [] and len(again.skipped) == len(GOOD)
    # one shared map with both campaigns' runs
    assert len(pd.read_parquet(first.map_path)) == len(GOOD) + 1


def test_lost_state_costs_a_re_run_but_changes_no_group(campaign_dir: Path) -> None:
    campaign = load_campaign(campaign_dir / "campaign.toml")
    run_campaign(campaign, jobs=1)
    before = pd.read_parquet(campaign.map_path)
    campaign.state_path.unlink()
    report = run_campaign(campaign, jobs=1)
    assert len(report.reduced) == len(GOOD)
    # the same files give the same rows: nothing in the map changed
    assert report.groups_updated == 0
    assert "0 added" in report.map_summary and f"{len(GOOD)} unchanged" in report.map_summary
    after = pd.read_parquet(campaign.map_path)
    assert sorted(after["measurement_id"]) == sorted(before["measurement_id"])


def test_workers_return_typed_picklable_results(campaign_dir: Path) -> None:
    """What crosses the process boundary is the route's frozen outcome per file (the one
    ``reduce`` gets too): its hash, its tests and a reduced run (record, summary, trace)
    or a failure per run; or the file's failure with its one-line reason."""
    import pickle

    from tribopipe.campaign.worker import Job, WorkerContext, reduce_chunk
    from tribopipe.pipeline import FailedRun, FileOutcome, ReducedRun

    campaign = load_campaign(campaign_dir / "campaign.toml")
    jobs = [Job(file=row.file, path=str(row.path), sources=row.sources, hints=row.hints)
            for row in campaign_table(campaign)
            if row.file in ("DS30_steel_5N_20C_r1.csv", "DS30_steel_9N_20C_r1.csv")]
    done, failed = pickle.loads(pickle.dumps(reduce_chunk(jobs, WorkerContext(campaign, False))))
    assert isinstance(done, FileOutcome) and done.error is None
    assert done.tests == ("friction",)
    (good,) = done.runs
    bad = failed.error
    assert isinstance(good, ReducedRun) and isinstance(bad, FailedRun) and not failed.runs
    assert good.name == "DS30_steel_5N_20C_r1.csv" and good.place.test == "friction"
    assert good.measurement_id == good.record.measurement_id
    assert good.labels.pin == "Dragonskin 30"
    assert good.summary["mu_k"] == pytest.approx(0.36, abs=0.01)
    assert good.trace is not None and good.trace.is_file()
    assert good.trace.is_relative_to(campaign.output_dir)
    assert bad.reason.startswith("DS30_steel_9N_20C_r1.csv") and not bad.transient


def test_the_state_is_sqlite_updated_row_by_row_and_an_old_json_state_converts(
        campaign_dir: Path) -> None:
    import sqlite3

    from tribopipe.campaign.state import CampaignState, load_state

    campaign = load_campaign(campaign_dir / "campaign.toml")
    run_campaign(campaign, jobs=1)
    state = load_state(campaign)
    with sqlite3.connect(campaign.state_path) as con:
        rows = con.execute("SELECT count(*) FROM files").fetchone()[0]
    assert rows == len(state.entries) >= len(GOOD) and state.map is not None
    # a state written as JSON by an older version is read, converted, and still counts
    legacy = CampaignState(campaign=state.campaign, entries=state.entries, map=state.map)
    campaign.state_path.unlink()
    campaign.legacy_state_path.write_text(json.dumps(legacy.to_json()), encoding="utf-8")
    assert load_state(campaign) == legacy
    assert campaign.state_path.is_file()                 # converted
    again = run_campaign(campaign, jobs=1)
    assert again.reduced == [] and len(again.skipped) == len(GOOD)


def test_the_state_read_back_shares_what_its_entries_repeat(campaign_dir: Path) -> None:
    """The entries read back from the state are equal to those the batch wrote (the same
    rows when saved again) while the labels' keys and repeated values are one object."""
    import sqlite3

    from tribopipe.campaign.state import load_state, save_state

    campaign = load_campaign(campaign_dir / "campaign.toml")
    run_campaign(campaign, jobs=1)
    with sqlite3.connect(campaign.state_path) as con:
        before = con.execute("SELECT name, state FROM files ORDER BY name").fetchall()
    state = load_state(campaign)
    labels = [r.entry.labels for e in state.entries.values() for r in e.runs
              if r.entry is not None]
    assert len(labels) >= 2 and all(isinstance(lab, dict) for lab in labels)
    first, second = labels[0], labels[1]
    assert [id(k) for k in first] == [id(k) for k in second]  # one copy of each key
    assert first["report"] is second["report"]                  # equal nested values: one
    assert not hasattr(next(iter(state.entries.values())), "__dict__")  # slotted
    campaign.state_path.unlink()
    save_state(campaign, state)                                 # written again, in full
    with sqlite3.connect(campaign.state_path) as con:
        assert con.execute("SELECT name, state FROM files ORDER BY name").fetchall() == before


def test_the_groups_updated_are_the_statistics_groups(tmp_path: Path) -> None:
    """The batch counts condition groups as the statistics group runs: two runs of one
    pair, force and temperature at two nominal speeds are two groups, and a replaced run
    counts its group."""
    from tribopipe.frictionmap import read_map
    from tribopipe.stats import group_statistics

    raw = tmp_path / "raw"
    raw.mkdir()
    for repeat, rpm in ((1, 0.005), (2, 0.005), (3, 0.05)):
        run = SyntheticRun(mu_s=0.8, mu_k=0.6, normal_force_N=1.0, temperature_C=20.0,
                           duration_s=DURATION_S, noise=0.004, seed=repeat, speed_rpm=rpm)
        write_rheocompass_export(raw / f"DS30_steel_1N_20C_r{repeat}.csv", run,
                                 project="speeds", test="friction", sample="pin")
    campaign = load_campaign(write_config(tmp_path))
    report = run_campaign(campaign, jobs=1)
    assert sorted(report.reduced) == [f"DS30_steel_1N_20C_r{r}.csv" for r in (1, 2, 3)]
    groups = group_statistics(read_map(campaign.map_path))
    assert len(groups) == 2  # one pair, force and temperature; two nominal speeds
    assert report.groups_updated == len(groups)
    # the fast run reduced again from a changed file: its one group, nothing else
    run = SyntheticRun(mu_s=0.8, mu_k=0.5, normal_force_N=1.0, temperature_C=20.0,
                       duration_s=DURATION_S, noise=0.004, seed=9, speed_rpm=0.05)
    write_rheocompass_export(raw / "DS30_steel_1N_20C_r3.csv", run, project="speeds",
                             test="friction", sample="pin")
    again = run_campaign(campaign, jobs=1)
    assert again.reduced == ["DS30_steel_1N_20C_r3.csv"]
    assert again.groups_updated == 1

"""What a working batch's rehearsal starts from, and what the table finds once per batch.

A batch that did its work cleanly rehearses its next unchanged re-run
(:func:`tribopipe.campaign.batch._rehearse`). It starts from the state the batch holds
(:meth:`~tribopipe.campaign.state.BatchEntries.as_read_back`) when that is provably the
state read back from its file; the tests here run working batches of several shapes
(every file new with failures and a note, files added, removed, changed, a file that
fails now, a changed config, duplicates and a conflict with a manifest) and compare, on
the same campaign after the batch, the pending ledger it kept with the one the
rehearsal from the state read back gives (stamps, report, tables, traces), and the
state it started from with :func:`~tribopipe.campaign.state.load_state`'s, entry by
entry and in order. Where it is not provable (a state written under the batch, entries
not decoded from rows) it reads the state back. Its campaign table takes the batch's
rows of the files whose entry the batch left as it was (reduced, same stat, traces
still there, the same campaign and manifest): it is the table built from nothing, row by
row, and finds the metadata of every other file.

The campaign table finds a file's metadata (its name matched, its labels merged) when a
row is asked for it: the plan and ``runs.csv`` of reduced files find none; the materials
check reads the names the table kept as it was built. Their rows, names and refusals
are those found from each row's own metadata. ``runs.csv`` is written from the state's
entries without copying each run into a dict first: every table written or rehearsed in
this module's batches is compared, byte for byte, with the code it replaced (kept here,
as it was).
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import shutil
import sqlite3
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from generators.synthetic import SyntheticRun, write_rheocompass_export
from helpers import write_campaign_config
from tribopipe.campaign import batch as batch_module
from tribopipe.campaign import folder_campaign, load_campaign, run_campaign
from tribopipe.campaign import outputs as outputs_module
from tribopipe.campaign import table as table_module
from tribopipe.campaign.ledger import BatchReport
from tribopipe.campaign.metadata import material_problems, read_manifest
from tribopipe.campaign.spec import Campaign
from tribopipe.campaign.stamp import needed_traces, outputs_stamp
from tribopipe.campaign.state import (
    BatchEntries,
    CampaignState,
    KeptLedger,
    load_kept,
    load_state,
)
from tribopipe.campaign.table import (
    campaign_table,
    check_materials,
    discover_files,
    discover_paths,
    named_materials,
)
from tribopipe.errors import CampaignError

PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
GOOD = {
    "DS30_steel_1N_20C_r1": (0.80, 0.62, 1.0),
    "DS30_steel_5N_20C_r1": (0.47, 0.36, 5.0),
    "LS1_steel_5N_20C_r1": (0.55, 0.42, 5.0),
    "DS30_glass_5N_20C_r1": (0.61, 0.44, 5.0),
}
LAB_MATERIALS = '[materials]\n"{name}" = {{ class = "silicone elastomer", aliases = ["LS1"] }}\n'


def _write(path: Path, mu_s: float, mu_k: float, force_N: float, seed: int) -> None:
    run = SyntheticRun(mu_s=mu_s, mu_k=mu_k, normal_force_N=force_N, temperature_C=20.0,
                       duration_s=120.0, noise=0.004, seed=seed)
    write_rheocompass_export(path, run, project="rehearse test", test="friction",
                             sample="pin")


@pytest.fixture(scope="module")
def exports(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Four good exports (one of a lab's own material), a truncated one, an unnamed one
    and a note (not an export)."""
    folder = tmp_path_factory.mktemp("exports")
    for seed, (stem, (mu_s, mu_k, force)) in enumerate(GOOD.items()):
        _write(folder / f"{stem}.csv", mu_s, mu_k, force, seed)
    whole = (folder / "DS30_steel_1N_20C_r1.csv").read_bytes()
    (folder / "DS30_steel_9N_20C_r1.csv").write_bytes(whole[: len(whole) // 4 * 2])
    shutil.copy(folder / "DS30_steel_5N_20C_r1.csv", folder / "unnamed.csv")
    (folder / "notes.txt").write_text("pins cut on Monday\n")
    return folder


def _config(root: Path, extra_lines: tuple[str, ...] = ()) -> Path:
    return write_campaign_config(
        root, ['name = "rehearse"', 'raw_dir = "raw"', 'output_dir = "out"',
               f'filename_pattern = "{PATTERN}"', "plots = false", *extra_lines])


@pytest.fixture()
def root(exports: Path, tmp_path: Path) -> Path:
    shutil.copytree(exports, tmp_path / "raw")
    (tmp_path / "materials.toml").write_text(LAB_MATERIALS.format(name="Lab silicone A"))
    _config(tmp_path)
    return tmp_path


# --------------------------------------------------------------------------- as it was
def _old_cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return "" if not math.isfinite(value) else repr(round(value, 6))
    if isinstance(value, int):
        return str(value)
    return outputs_module.csv_cell(str(value))


def _old_values(file: str, run: Mapping[str, Any], status: str, labels: Mapping[str, Any],
                reason: str | None, *, measured: bool = False) -> list[Any]:
    keys = tuple(k for k in outputs_module.ENTRY_KEYS if k not in ("labels", "name"))
    values: dict[str, Any] = {
        "file": file, "status": status, **labels, **_old_report_cells(labels),
        "test": run.get("test"), "result": run.get("result"), "interval": run.get("interval"),
        **({k: run.get(k) for k in keys if k not in ("test", "result", "interval")}
           if measured else {}),
        "reason": reason,
    }
    return [values.get(c) for c in outputs_module.RUNS_COLUMNS]


def _old_report_cells(labels: Mapping[str, Any]) -> dict[str, Any]:
    report = labels.get("report")
    if not isinstance(report, Mapping):
        return {}
    try:
        values = {str(k): v for k, v in report.get("values") or []}
        extra = {str(k): str(v) for k, v in report.get("extra") or []}
        return outputs_module.RunReport.of(values, extra).columns()
    except (TypeError, ValueError):
        return {}


def _old_write_runs(writer: Any, rows: Sequence[Any], entries: Mapping[str, Any],
                    this_batch: Mapping[str, str], failures: Mapping[str, str]) -> None:
    writer.writerow(outputs_module.RUNS_COLUMNS)
    for row in rows:
        entry = entries.get(row.file)
        file_labels = {k: row.merged.get(k) for k in outputs_module.LABEL_FIELDS}
        runs = [] if entry is None else [r.flat() for r in entry.runs]
        if entry is None or row.file in failures or not runs:
            status = this_batch.get(row.file, "failed")
            writer.writerow([_old_cell(v) for v in _old_values(
                row.file, {}, status, file_labels, failures.get(row.file))])
            continue
        for run in runs:
            name = run.get("name") or row.file
            kept = run.get("status")
            status = "duplicate" if kept == "duplicate" else this_batch.get(name, "failed")
            ok = kept == "reduced" and status != "failed"
            labels = (run.get("labels") if ok or kept == "duplicate" else None) or file_labels
            reason = failures.get(name) or (entry.reason if kept == "duplicate" else None)
            writer.writerow([_old_cell(v) for v in _old_values(
                row.file, run, status, labels, reason, measured=ok or kept == "duplicate")])
# ---------------------------------------------------------------------------


@pytest.fixture(autouse=True)
def runs_csv_as_before(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Every ``runs.csv`` written or rehearsed here is also made by the code it replaced,
    on the same rows and entries, and must be the same text (returned: each one)."""
    made: list[str] = []
    new = outputs_module._write_runs

    def both(writer: Any, rows: Sequence[Any], entries: Mapping[str, Any],
             this_batch: Mapping[str, str], failures: Mapping[str, str]) -> None:
        mine, old = io.StringIO(), io.StringIO()
        new(csv.writer(mine, lineterminator="\n"), rows, entries, this_batch, failures)
        _old_write_runs(csv.writer(old, lineterminator="\n"), rows, entries, this_batch,
                        failures)
        assert mine.getvalue() == old.getvalue()
        made.append(mine.getvalue())
        new(writer, rows, entries, this_batch, failures)

    monkeypatch.setattr(outputs_module, "_write_runs", both)
    return made


class Spy:
    """A working batch watched: the states read back (``load_state``), and each
    rehearsal's arguments and outcome."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.reads = 0
        self.rehearsals: list[tuple[CampaignState | None, Any, Any, Campaign]] = []
        load, rehearse = batch_module.load_state, batch_module._rehearse

        def counted_load(campaign: Campaign) -> CampaignState:
            self.reads += 1
            return load(campaign)

        def watched(campaign: Campaign, state: CampaignState | None = None,
                    known: Any = None) -> Any:
            out = rehearse(campaign, state, known)
            self.rehearsals.append((state, out, known, campaign))
            return out

        monkeypatch.setattr(batch_module, "load_state", counted_load)
        monkeypatch.setattr(batch_module, "_rehearse", watched)
        self._rehearse = rehearse

    def batch(self, root: Path) -> BatchReport:
        """One batch of the campaign in ``root`` (one worker)."""
        self.reads, self.rehearsals = 0, []
        return run_campaign(load_campaign(root / "campaign.toml"), jobs=1)


def _ledger_of(campaign: Campaign, rerun: Any) -> KeptLedger:
    """The pending ledger a rehearsal's outcome gives, as the batch keeps it (its report
    as JSON: lists, not tuples)."""
    inputs, ended = rerun
    return KeptLedger(inputs=inputs, outputs=outputs_stamp(campaign),
                      traces=needed_traces(ended.entries),
                      report=json.loads(json.dumps(ended.report.to_json())),
                      tables=ended.tables)


def _same_as_read_back(spy: Spy, root: Path) -> tuple[KeptLedger, int]:
    """After a working batch (watched by ``spy``): the rehearsal started from the state
    the batch held (the state file was read once, by the batch), that state is the one
    read back now (entry by entry, in order), and the pending ledger it kept is the one
    the rehearsal from the state read back gives, on the same campaign, now; its table
    is the one built from nothing (:func:`_same_table`). Returns that ledger and how
    many rows the rehearsal's table took from the batch's."""
    campaign = load_campaign(root / "campaign.toml")
    ((held, mine, known, batched),) = spy.rehearsals
    assert spy.reads == 1, "the rehearsal read the state back"
    assert held is not None and mine is not None and known is not None
    taken = _same_table(batched, held, known)
    # a table of the campaign loaded again (another object) takes no row
    assert _same_table(campaign, held, known) == 0
    back = load_state(campaign)
    assert list(held.entries.items()) == list(back.entries.items())
    assert (held.campaign, held.map) == (back.campaign, back.map)
    kept = load_kept(campaign)
    assert kept is not None and kept.tables is not None
    assert kept == _ledger_of(campaign, mine)
    read_back = spy._rehearse(campaign)  # from the state file, as before
    assert read_back is not None
    assert kept == _ledger_of(campaign, read_back)
    assert read_back[1].quiet and read_back[1].report.to_json() == mine[1].report.to_json()
    return kept, taken


def _rows_of(table: Any) -> list[tuple[Any, ...]]:
    return [(r.file, r.where, r.size, r.mtime_ns, r.status, r.problem, r.reason, r.sha256,
             r.previous, r.sources, r.merged, r.hints, r.test_rows) for r in table]


def _same_table(campaign: Campaign, state: CampaignState, known: Any) -> int:
    """The rehearsal's table, with the rows it took from the batch's (``known``), is the
    table built from nothing: row by row, metadata, names and files set aside; it found
    the metadata of every file but those it took, which are the reduced files (or
    duplicates) whose state entry the batch left as it was. Returns how many it took."""
    manifest = read_manifest(campaign.manifest) if campaign.manifest else None
    found: list[str] = []
    real = table_module._file_metadata

    def counted(*args: Any) -> Any:
        found.append(args[2])
        return real(*args)

    table_module._file_metadata = counted
    try:
        taken = campaign_table(campaign, state=state, manifest=manifest, known=known)
    finally:
        table_module._file_metadata = real
    built = campaign_table(campaign, state=state, manifest=manifest)
    assert _rows_of(taken) == _rows_of(built)
    assert taken.names_given() == built.names_given()
    assert taken.not_exports == built.not_exports
    kept = {r.file for r in built if r.status in ("reduced", "duplicate")
            and r.previous is not None and known._entries.get(r.file) is r.previous}
    every = {r.file for r in built} | {f for f, _ in built.not_exports}
    if not known.built_for(campaign, manifest):
        kept = set()
    assert sorted(found) == sorted(every - kept)
    return len(kept)


def test_every_file_new_with_failures_and_a_note(root: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    spy = Spy(monkeypatch)
    first = spy.batch(root)
    assert len(first.reduced) == len(GOOD) and len(first.failures) == 2
    kept, taken = _same_as_read_back(spy, root)
    assert taken == 0  # every entry new
    assert "unnamed.csv" in kept.tables[1] and "notes.txt" in " ".join(kept.report["notes"])


def test_files_added_removed_and_changed(root: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    spy = Spy(monkeypatch)
    spy.batch(root)
    spy.batch(root)  # takes the pending ledger
    raw = root / "raw"
    _write(raw / "DS30_steel_5N_20C_r1.csv", 0.50, 0.40, 5.0, seed=99)
    (raw / "LS1_steel_5N_20C_r1.csv").unlink()
    (raw / "unnamed.csv").unlink()
    _write(raw / "DS30_steel_1N_20C_r2.csv", 0.81, 0.63, 1.0, seed=7)
    work = spy.batch(root)
    assert sorted(work.reduced) == ["DS30_steel_1N_20C_r2.csv", "DS30_steel_5N_20C_r1.csv"]
    assert [n for n in work.notes if "LS1_steel_5N_20C_r1.csv: no longer in" in n]
    _, taken = _same_as_read_back(spy, root)
    assert taken == 2  # DS30_glass, DS30_steel_1N_20C_r1


def test_a_file_that_fails_now(root: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    spy = Spy(monkeypatch)
    spy.batch(root)
    path = root / "raw" / "DS30_glass_5N_20C_r1.csv"
    whole = path.read_bytes()
    path.write_bytes(whole[: len(whole) // 3])
    work = spy.batch(root)
    assert "DS30_glass_5N_20C_r1.csv" in dict(work.failures) and work.reduced == []
    kept, taken = _same_as_read_back(spy, root)
    assert taken == len(GOOD) - 1
    assert "DS30_glass_5N_20C_r1.csv" in kept.tables[1]


def test_a_changed_config_and_material(root: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    spy = Spy(monkeypatch)
    spy.batch(root)
    _config(root, ("force_tolerance_rel = 0.2",))
    (root / "materials.toml").write_text(LAB_MATERIALS.format(name="Lab silicone B"))
    work = spy.batch(root)
    assert sorted(work.reduced) == sorted(f"{s}.csv" for s in GOOD)
    _, taken = _same_as_read_back(spy, root)
    assert taken == 0


def test_duplicates_a_manifest_and_a_conflict(root: Path, monkeypatch: pytest.MonkeyPatch,
                                              runs_csv_as_before: list[str]) -> None:
    raw = root / "raw"
    (raw / "unnamed.csv").unlink()
    shutil.copy(raw / "DS30_steel_1N_20C_r1.csv", raw / "copy of r1.csv")
    shutil.copy(raw / "DS30_steel_1N_20C_r1.csv", raw / "DS30_steel_1N_20C_r7.csv")
    (raw / "manifest.csv").write_text(
        "file,pin,disc,normal_force_N,temperature_C,repeat,humidity_pct,operator,lab_note\n"
        "copy of r1.csv,DS30,steel,1,20,1,,,\n"
        "DS30_steel_5N_20C_r1.csv,DS30,steel,5,20,1,45,Ann,=cut on Monday\n"
        "DS30_steel_3N_20C_r1.csv,DS30,steel,3,20,1,,,\n", encoding="utf-8")
    _config(root, ('manifest = "raw/manifest.csv"',))
    spy = Spy(monkeypatch)
    first = spy.batch(root)
    assert [f for f, _ in first.duplicates] == ["copy of r1.csv"]
    assert [f for f, _ in first.conflicts] == ["DS30_steel_1N_20C_r7.csv"]
    kept, taken = _same_as_read_back(spy, root)
    assert taken == 0
    assert kept.report["unmatched"]
    # the reporting items and the extra metadata of the manifest, in the run's row
    (row,) = [r for r in csv.DictReader(io.StringIO(kept.tables[0]))
              if r["file"] == "DS30_steel_5N_20C_r1.csv"]
    assert (row["humidity_pct"], row["operator"], row["status"]) == ("45.0", "Ann", "skipped")
    assert "lab_note" in row["extra_metadata"] and len(runs_csv_as_before) == 3
    # a file changed under the manifest (read again: an equal one): the others are taken
    assert spy.batch(root).kept
    _write(raw / "DS30_glass_5N_20C_r1.csv", 0.60, 0.45, 5.0, seed=11)
    assert spy.batch(root).reduced == ["DS30_glass_5N_20C_r1.csv"]
    _, taken = _same_as_read_back(spy, root)
    assert taken == 4  # the three reduced others and the duplicate


def _entries(campaign: Campaign) -> BatchEntries:
    return BatchEntries(campaign, load_state(campaign), fresh=False)


def test_a_state_written_under_the_batch_is_read_back(root: Path) -> None:
    """What the batch holds stands for the state file only while no one else wrote it,
    every change is saved, and its entries were decoded from the file's rows."""
    assert run_campaign(load_campaign(root / "campaign.toml"), jobs=1).reduced
    campaign = load_campaign(root / "campaign.toml")
    entries = _entries(campaign)
    held = entries.as_read_back()
    assert held is not None
    assert list(held.entries.items()) == list(load_state(campaign).entries.items())
    name = "DS30_steel_1N_20C_r1.csv"
    one = entries[name]
    entries[name] = one  # set, not saved
    assert entries.as_read_back() is None
    entries.save()  # saved: read back from its row
    again = entries.as_read_back()
    assert again is not None and again.entries[name] == one
    assert list(again.entries) == list(load_state(campaign).entries)
    # another writer: a row the batch does not know of
    with sqlite3.connect(campaign.state_path) as con:
        con.execute("INSERT INTO files (name, state) VALUES (?, ?)",
                    (json.dumps("other.csv"), json.dumps(one.to_json())))
    assert entries.as_read_back() is None


def test_a_row_changed_under_the_batch_before_its_save_is_read_back(root: Path) -> None:
    """Another writer changes a row the batch holds (its name stays: only the file shows
    it), then the batch saves another entry: what the batch holds no longer stands for
    the file, then or after, and the rehearsal reads the state back."""
    assert run_campaign(load_campaign(root / "campaign.toml"), jobs=1).reduced
    campaign = load_campaign(root / "campaign.toml")
    entries = _entries(campaign)
    x, y = list(entries)[:2]
    with sqlite3.connect(campaign.state_path) as con:
        ((text,),) = con.execute("SELECT state FROM files WHERE name = ?",
                                 (json.dumps(x),)).fetchall()
        changed = {**json.loads(text), "sha256": "0" * 64}
        con.execute("UPDATE files SET state = ? WHERE name = ?",
                    (json.dumps(changed), json.dumps(x)))
    assert entries.as_read_back() is None
    entries[y] = entries[y]
    entries.save()
    assert load_state(campaign).entries[x].sha256 == "0" * 64
    assert entries.as_read_back() is None
    entries[y] = entries[y]
    entries.save()  # a later save of the batch's own does not make it provable again
    assert entries.as_read_back() is None


def test_a_state_file_in_wal_mode_is_read_back(root: Path) -> None:
    """A state file someone switched to WAL mode writes beside itself, where the batch's
    stamp of it cannot look: what the batch holds never stands for it."""
    assert run_campaign(load_campaign(root / "campaign.toml"), jobs=1).reduced
    campaign = load_campaign(root / "campaign.toml")
    with sqlite3.connect(campaign.state_path) as con:
        assert con.execute("PRAGMA journal_mode=WAL").fetchone() == ("wal",)
    entries = _entries(campaign)
    assert entries.as_read_back() is None
    again = run_campaign(load_campaign(root / "campaign.toml"), jobs=1)  # still runs
    assert again.skipped and not again.reduced and not again.output_errors


def test_entries_not_decoded_from_rows_are_read_back(root: Path) -> None:
    """A state converted from an older version's JSON: its entries as the batch holds
    them were decoded from the JSON, not from the rows; they stand for the state only
    once written and read back."""
    assert run_campaign(load_campaign(root / "campaign.toml"), jobs=1).reduced
    campaign = load_campaign(root / "campaign.toml")
    with sqlite3.connect(campaign.state_path) as con:
        data = {json.loads(n): json.loads(t)
                for n, t in con.execute("SELECT name, state FROM files")}
    campaign.state_path.unlink()
    campaign.legacy_state_path.write_text(json.dumps(
        {"version": 2, "campaign": campaign.name, "entries": data}), encoding="utf-8")
    converted = load_state(campaign)
    assert converted.entries and converted.rows_of is None
    entries = BatchEntries(campaign, converted, fresh=False)
    assert entries.as_read_back() is None
    # a batch on it: the full one, then its rehearsal reads the state back
    again = run_campaign(campaign, jobs=1)
    assert again.reduced == [] and run_campaign(campaign, jobs=1).kept


@pytest.fixture()
def labelled(root: Path) -> Campaign:
    """The campaign with a manifest: whole-file rows, a test row, a row for no file, and
    names outside the vocabulary (one given twice, one by the manifest)."""
    raw = root / "raw"
    shutil.copy(raw / "DS30_steel_1N_20C_r1.csv", raw / "XX9_steel_1N_20C_r1.csv")
    shutil.copy(raw / "DS30_steel_1N_20C_r1.csv", raw / "XX9_steel_1N_20C_r2.csv")
    (raw / "manifest.csv").write_text(
        "file,test,pin,disc,normal_force_N,temperature_C,repeat\n"
        "unnamed.csv,,DS30,steel,5,20,2\n"
        "DS30_glass_5N_20C_r1.csv,friction,,,,,\n"
        "DS30_steel_5N_20C_r1.csv,,DS30,stele,5,20,1\n"
        "gone.csv,,DS30,steel,3,20,1\n", encoding="utf-8")
    _config(root, ('manifest = "raw/manifest.csv"',))
    return load_campaign(root / "campaign.toml")


def test_rows_find_their_metadata_when_asked(labelled: Campaign,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    campaign = labelled
    assert campaign.manifest is not None
    manifest = read_manifest(campaign.manifest)
    rows = campaign_table(campaign, manifest=manifest)
    found = 0
    real = table_module._file_metadata

    def counted(*args: Any) -> Any:
        nonlocal found
        found += 1
        return real(*args)

    monkeypatch.setattr(table_module, "_file_metadata", counted)
    plan = batch_module._plan(rows, set())
    assert found == 0 and len(plan.todo) == len(rows) - len(plan.failures)
    lazy = [row.test_rows for row in rows]  # from the manifest alone
    assert found == 0
    for row, test_rows in zip(rows, lazy, strict=True):
        meta = real(campaign, manifest, row.file, row.path)
        assert (row.sources, row.merged, row.hints, row.test_rows) == (
            tuple(meta.sources), meta.merged, tuple(meta.hints), meta.test_rows)
        assert test_rows == meta.test_rows
    assert found == len(rows)
    assert any(row.test_rows for row in rows) and any(row.hints for row in rows)


def test_the_names_kept_are_those_each_row_gives(labelled: Campaign) -> None:
    """The materials check reads the names the table kept as it was built: each name as
    many times as the rows' metadata gives it, first where it is first given, so the
    same refusal, word for word."""
    rows = campaign_table(labelled)
    each = named_materials(rows)  # from each row's own metadata
    kept = rows.names_given()
    assert Counter((w, n) for w, n, _ in kept) == Counter((w, n) for w, n, _ in each)
    first = {(w, n): f for w, n, f in reversed(each)}
    assert all(first[(w, n)] == f for w, n, f in kept)
    assert [n for _, n, _ in each].count("XX9") == 2 and ("disc", "stele", "DS30_steel_5N_"
                                                         "20C_r1.csv") in each
    problems = material_problems(labelled, kept)
    assert problems == material_problems(labelled, each) and len(problems) == 2
    assert "and 1 more" in " ".join(problems)
    with pytest.raises(CampaignError) as refused:
        check_materials(labelled, rows)
    with pytest.raises(CampaignError) as each_refused:
        check_materials(labelled, list(rows))
    assert str(refused.value) == str(each_refused.value)


def test_the_paths_listed_as_text_are_the_files_listed(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The inputs' stamp lists the raw folder as text: the same paths, in the same order,
    as :func:`discover_files` finds, among names that are hidden, not exports, the
    tool's own tables (and a table of the same name that is not), the manifest, a
    folder, a symlink loop, spaces, accents and bytes that are not UTF-8; listed by
    :func:`discover_files` itself where a glob, a relative folder or an output folder
    inside it could make them differ."""
    raw = tmp_path / "raw"
    raw.mkdir()
    for name in ("a.csv", "B.CSV", "c.txt", "d.TSV", "e.xlsx", "f.xls", ".hidden.csv",
                 "g.lock", "h.toml", "notes.md", "with space é.csv", "manifest.csv",
                 "x.", "y.csv.lock", "z.lock.csv"):
        (raw / name).write_text("x\n", encoding="utf-8")
    (raw / "runs.csv").write_text("file,test\n", encoding="utf-8")  # the tool's
    (raw / "failures.csv").write_text("name,why\n", encoding="utf-8")  # a user's
    (raw / "sub.csv").mkdir()
    (raw / "loop.csv").symlink_to(raw / "loop.csv")
    with open(os.path.join(os.fsencode(raw), b"bad\xff.csv"), "wb") as fh:
        fh.write(b"x\n")
    campaign = folder_campaign(raw, manifest=raw / "manifest.csv", output_dir=tmp_path / "out")

    def listed(c: Campaign) -> list[str]:
        return [str(p) for p in discover_files(c)]

    as_text = discover_paths(campaign)
    assert as_text == listed(campaign) and len(as_text) == 12
    assert str(raw / "manifest.csv") not in as_text and str(raw / "runs.csv") not in as_text
    with monkeypatch.context() as m:  # listed as text, not by discover_files
        m.setattr(table_module, "discover_files", lambda c: pytest.fail("not as text"))
        assert discover_paths(campaign) == as_text
    for other in (replace(campaign, glob="*.csv"),
                  replace(campaign, output_dir=raw / "out"),
                  replace(campaign, output_dir=raw)):
        assert discover_paths(other) == listed(other)
    monkeypatch.chdir(tmp_path)
    relative = replace(campaign, raw_dir=Path("raw"))
    assert discover_paths(relative) == listed(relative)

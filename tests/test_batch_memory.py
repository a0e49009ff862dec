"""A batch's memory stays flat in the number of files: what its parent keeps per file is
measured by ``tracemalloc`` (bytes, never time) over N and 3N files, and its growth per
file must stay under a bound that a batch holding each file's decoded state entry,
campaign-table row and job (about 5 kB per file) breaks.

- the campaign table of new exports (planning): the table keeps each file's name, stat
  and status, and builds a row when asked for;
- the state's entries of the files a batch landed: let go once saved, read again from
  their SQLite rows;
- a real batch from scratch (``run_campaign``, one worker: in this process), measured
  when it writes ``runs.csv``, when everything it keeps is alive: what grows is its
  compact records and the report's own lists (the names of the runs reduced, the map's
  ids added), under 1 kB per file.
"""

from __future__ import annotations

import gc
import json
import os
import tracemalloc
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe.campaign import batch as batch_module
from tribopipe.campaign import folder_campaign, run_campaign
from tribopipe.campaign.spec import Campaign
from tribopipe.campaign.state import CampaignState, FileState, load_state
from tribopipe.campaign.table import campaign_table

PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"


def _exports(folder: Path, n: int, *, first: int = 0) -> Path:
    """``n`` short distinct exports named for their labels (one run each)."""
    folder.mkdir(parents=True, exist_ok=True)
    for i in range(first, first + n):
        force = (1, 3, 5)[i % 3]
        write_rheocompass_export(
            folder / f"DS30_steel_{force}N_20C_r{i // 3 + 1}.csv",
            SyntheticRun(mu_s=0.8, mu_k=0.5 + 0.0001 * i, normal_force_N=float(force),
                         seed=100 + i, duration_s=40.0, setup_s=10.0),
            project="flat", test="t", sample="DS30")
    return folder


@pytest.fixture(scope="module")
def many(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Exports enough for N and 3N files (hard-linked into each size's folder)."""
    return _exports(tmp_path_factory.mktemp("many"), 3 * 120)


def _first(many: Path, n: int, folder: Path) -> Path:
    """A raw folder holding the first ``n`` files of ``many`` (hard links)."""
    folder.mkdir(parents=True)
    for path in sorted(many.iterdir(), key=lambda p: p.name)[:n]:
        os.link(path, folder / path.name)
    return folder


def _campaign(raw: Path, tmp: Path) -> Campaign:
    return folder_campaign(raw, filename_pattern=PATTERN, map_path=tmp / "map",
                           output_dir=tmp / "out")


def _kept(make: Callable[[], Any]) -> tuple[int, Any]:
    """The bytes ``make()`` allocated and still holds in what it returns (traced)."""
    gc.collect()
    tracemalloc.start()
    try:
        made = make()
        gc.collect()
        return tracemalloc.get_traced_memory()[0], made
    finally:
        tracemalloc.stop()


def _growth(sizes: dict[int, int]) -> float:
    """The growth per file [B] between the smallest and largest size."""
    small, large = min(sizes), max(sizes)
    return (sizes[large] - sizes[small]) / (large - small)


def test_the_campaign_table_keeps_a_few_bytes_per_file(many: Path, tmp_path: Path) -> None:
    """Planning a batch of new files: the table grows by its arrays, not by rows of
    dicts (a row of sources, merged labels and hints kept per file: ~1.2 kB)."""
    kept: dict[int, int] = {}
    for n in (120, 360):
        campaign = _campaign(_first(many, n, tmp_path / f"raw{n}"), tmp_path / f"c{n}")
        size, rows = _kept(lambda c=campaign: campaign_table(c, state=CampaignState()))
        assert len(rows) == n and {r.status for r in rows} == {"new"}
        kept[n] = size
        del rows
    # the name (shared with the listing), its stat and status: under 200 B a file
    print(f"kept {kept} B: {_growth(kept):.0f} B per file")
    assert _growth(kept) < 200, kept


def _entry(i: int, template: dict[str, Any]) -> FileState:
    """A state entry like a real one (``template``: a landed file's), made distinct."""
    data = json.loads(json.dumps(template))
    data["size"] += i
    data["sha256"] = f"{i:064x}"
    for run in data["runs"]:
        run["measurement_id"] = f"{run['measurement_id'][:8]}{i:08x}"
        run["name"] = f"file_{i}.csv"
        run["trace"] = f"traces/file_{i}.parquet"
    return FileState.from_json(data)


@pytest.fixture(scope="module")
def landed(many: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """A state entry of a real landed file (its JSON)."""
    tmp = tmp_path_factory.mktemp("one")
    campaign = _campaign(_first(many, 1, tmp / "raw"), tmp)
    assert run_campaign(campaign, jobs=1, plots=False).ok
    (entry,) = load_state(campaign).entries.values()
    return entry.to_json()


def test_the_entries_a_batch_landed_are_let_go_once_saved(
        many: Path, landed: dict[str, Any], tmp_path: Path) -> None:
    """The entries landed in chunks and saved: what stays is each file's name in the
    index (a decoded entry held per file: ~1.7 kB); each is read again from its row,
    equal to what was landed."""
    from tribopipe.campaign.state import BatchEntries

    kept: dict[int, int] = {}
    for n in (300, 900):
        campaign = _campaign(_first(many, 1, tmp_path / f"raw{n}"), tmp_path / f"c{n}")
        names = [f"file_{i}.csv" for i in range(n)]  # made before: the campaign's own

        def land(c: Campaign = campaign, names: list[str] = names) -> Any:
            entries = BatchEntries(c, CampaignState(), fresh=True)
            for i, name in enumerate(names):
                entries[name] = _entry(i, landed)
                if i % 256 == 255:
                    entries.save()
            entries.save()
            return entries

        kept[n], entries = _kept(land)
        assert len(entries) == n
        assert entries[names[7]] == _entry(7, landed)  # read again from its row
        assert load_state(campaign).entries[names[n - 1]] == _entry(n - 1, landed)
        entries.close()
    print(f"kept {kept} B: {_growth(kept):.0f} B per file")
    assert _growth(kept) < 150, kept


def test_the_ids_the_state_holds_are_known_without_reading_every_entry(
        many: Path, landed: dict[str, Any], tmp_path: Path) -> None:
    """Which of a redone file's old run ids some entry still holds (its runs are dropped
    from the map otherwise) is counted as entries are set, replaced, removed and let go,
    equal to a scan of every entry, each landing, which would read them all back."""
    from tribopipe.campaign.state import BatchEntries

    campaign = _campaign(_first(many, 1, tmp_path / "raw"), tmp_path / "c")
    entries = BatchEntries(campaign, CampaignState(), fresh=True)

    def scan(ids: set[str]) -> set[str]:
        return ids & set().union(*(entries[n].run_ids() for n in entries))

    ids = {mid for i in range(40) for mid in _entry(i, landed).run_ids()}
    for i in range(30):
        entries[f"f{i}"] = _entry(i, landed)
    entries["twin"] = _entry(3, landed)  # a second file of the same runs
    entries.save()  # let go: read back from their rows when asked
    entries["f3"] = _entry(35, landed)  # redone: its old runs live on in its twin
    entries["f4"] = _entry(36, landed)  # redone: its old runs are gone
    del entries["f5"]
    held = entries.held_ids(ids)
    assert held == scan(ids)
    assert _entry(3, landed).run_ids() <= held and not _entry(4, landed).run_ids() & held
    assert not _entry(5, landed).run_ids() & held and _entry(36, landed).run_ids() <= held
    entries.close()


@pytest.mark.slow  # real batches of hundreds of exports, reduced in this process
def test_a_batch_from_scratch_keeps_a_few_hundred_bytes_per_file(
        many: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A real batch of N and 3N new exports, measured when it writes ``runs.csv``: its
    growth per file stays under 2 kB (about 0.9 kB: the report's lists, the compact
    records; the batch that held every file's entry, row and job kept about 4.7 kB)."""
    at_write: list[int] = []
    write = batch_module.write_runs_csv

    def measured(*args: Any, **kwargs: Any) -> None:
        gc.collect()
        at_write.append(tracemalloc.get_traced_memory()[0])
        write(*args, **kwargs)

    monkeypatch.setattr(batch_module, "write_runs_csv", measured)
    warm = _campaign(_first(many, 6, tmp_path / "warm"), tmp_path / "cwarm")
    assert run_campaign(warm, jobs=1, plots=False).ok  # what a first batch loads, once
    kept: dict[int, int] = {}
    for n in (120, 360):
        campaign = _campaign(_first(many, n, tmp_path / f"raw{n}"), tmp_path / f"c{n}")
        gc.collect()
        tracemalloc.start()
        try:
            report = run_campaign(campaign, jobs=1, plots=False)
        finally:
            tracemalloc.stop()
        assert report.ok and len(report.reduced) == n, report.ledger()
        kept[n] = at_write[-1]
        assert len(load_state(campaign).entries) == n
    print(f"kept {kept} B: {_growth(kept):.0f} B per file")
    assert _growth(kept) < 2000, kept

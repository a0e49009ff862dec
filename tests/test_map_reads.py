"""How many times `reduce` and `batch` read the map's rows: once, under the map's lock.

Every read of a map's rows passes once through the store's row conversion
(``frictionmap.store._from_arrow``: a single-file map, or a map folder's parts together),
and every merge of parts through ``frictionmap.store._merged_bytes`` (which copies the
merged parts' rows a batch at a time); the tests count their calls, and whether the map's
lock was held at each, while the real
commands run (``click.testing``). Before any work both commands refuse a foreign or
damaged map without reading its rows (``pipeline.landing.check_map_before_work``); the
rows are read by the one landing (``pipeline.landing.land_runs``) inside the locked
read-modify-write. `bench/bench_map_reads.py` counts every command the same way.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner
from filelock import FileLock, Timeout

from helpers import reduce_cli
from tribopipe.cli import main
from tribopipe.frictionmap import store

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "raw" / "example"
FIRST, SECOND = (EXAMPLE / f"DS30_steel_1N_10C_r{k}.csv" for k in (1, 2))
OTHER = EXAMPLE / "DS30_steel_5N_10C_r1.csv"
PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
pytestmark = pytest.mark.skipif(not FIRST.exists(), reason="the example campaign is not here")


def _locked(map_path: Path) -> bool:
    try:
        FileLock(str(map_path) + ".lock", timeout=0).acquire()
    except Timeout:
        return True
    return False


def _watch(monkeypatch: pytest.MonkeyPatch, map_path: Path) -> list[bool]:
    """For each read of the map's rows while the test runs (and each merge of parts,
    which copies the rows of the parts it merges, a batch at a time): was the map's lock
    held?"""
    held: list[bool] = []
    for name in ("_from_arrow", "_merged_bytes"):
        real = getattr(store, name)

        def watched(*a: Any, real: Any = real, **k: Any) -> Any:
            held.append(_locked(map_path))
            return real(*a, **k)

        monkeypatch.setattr(store, name, watched)
    return held


def _labels(repeat: int, force: str = "1") -> list[str]:
    return ["--pin", "DS30", "--disc", "steel", "--force", force, "--temperature", "10",
            "--repeat", str(repeat)]


def test_reduce_reads_the_map_once_under_its_lock(tmp_path: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    mapfile, out = tmp_path / "map.parquet", tmp_path / "out"
    first = reduce_cli(FIRST, *_labels(1), "--map", mapfile, "--output", out)
    assert first.exit_code == 0, first.output
    held = _watch(monkeypatch, mapfile)
    second = reduce_cli(SECOND, *_labels(2), "--map", mapfile, "--output", out)
    assert second.exit_code == 0, second.output
    # the landing's read under the lock: the columns its checks use of every part, then
    # the one small part the new run merges into, read whole to be rewritten with it
    assert held == [True, True]
    assert "1 added" in second.stderr


def test_reduce_still_refuses_a_foreign_or_damaged_map_before_any_work(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "out"
    foreign = tmp_path / "foreign.parquet"
    foreign.write_bytes(b"PAR1 not a map")
    held = _watch(monkeypatch, foreign)
    done = reduce_cli(FIRST, *_labels(1), "--map", foreign, "--output", out)
    assert done.exit_code == 1 and "foreign.parquet" in done.output, done.output
    assert foreign.read_bytes() == b"PAR1 not a map"
    # a map folder whose manifest is damaged, likewise
    folder = tmp_path / "map.parquet"
    assert reduce_cli(FIRST, *_labels(1), "--map", folder, "--output", out).exit_code == 0
    manifest = folder / "_manifest.json"
    data = json.loads(manifest.read_text(encoding="utf-8"))
    data["n_runs"] = 7
    manifest.write_text(json.dumps(data), encoding="utf-8")
    shutil.rmtree(out)
    done = reduce_cli(SECOND, *_labels(2), "--map", folder, "--output", out)
    assert done.exit_code == 1 and "_manifest.json" in done.output, done.output
    assert not (out / "traces").exists()  # refused before any work
    assert held == []  # neither refusal read a row


def _batch(raw: Path, mapfile: Path, out: Path) -> Any:
    return CliRunner().invoke(main, ["batch", str(raw), "--pattern", PATTERN, "--map",
                                     str(mapfile), "--output", str(out), "--jobs", "1",
                                     "--no-plots"])


def test_batch_reads_the_map_once_under_its_lock(tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    raw, mapfile, out = tmp_path / "raw", tmp_path / "map.parquet", tmp_path / "out"
    raw.mkdir()
    shutil.copyfile(FIRST, raw / FIRST.name)
    assert _batch(raw, mapfile, out).exit_code == 0
    # one new export, the map as the last batch left it: its rows read once, to land
    shutil.copyfile(SECOND, raw / SECOND.name)
    held = _watch(monkeypatch, mapfile)
    done = _batch(raw, mapfile, out)
    assert done.exit_code == 0, done.output
    assert held == [True, True]  # the landing's read and the small part merged, as reduce
    assert "1 reduced" in done.output


def test_batch_after_another_writer_reads_the_ids_then_lands(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The map changed since the last batch (here by `reduce`): which of the state's runs
    it still holds is read first (the ids, to plan the work), then the rows under the
    lock: the one read besides the landing's."""
    raw, mapfile, out = tmp_path / "raw", tmp_path / "map.parquet", tmp_path / "out"
    raw.mkdir()
    shutil.copyfile(FIRST, raw / FIRST.name)
    assert _batch(raw, mapfile, out).exit_code == 0
    assert reduce_cli(OTHER, *_labels(1, "5"), "--map", mapfile,
                      "--output", tmp_path / "r").exit_code == 0
    shutil.copyfile(SECOND, raw / SECOND.name)
    held = _watch(monkeypatch, mapfile)
    done = _batch(raw, mapfile, out)
    assert done.exit_code == 0, done.output
    assert held == [False, True, True]


def test_batch_keeps_no_map_rows_and_prints_the_stored_groups(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The batch's landings keep none of the map's rows (neither the landing's result nor
    the batch's report holds a table); the groups it prints after are the map folder's
    stored ones, read without reading a part, and are those of the map opened whole."""
    import pandas as pd

    from tribopipe.campaign import folder_campaign, run_campaign
    from tribopipe.export.tables import map_paper_text
    from tribopipe.frictionmap.snapshot import open_groups, open_map
    from tribopipe.pipeline import landing

    raw, mapfile, out = tmp_path / "raw", tmp_path / "map.parquet", tmp_path / "out"
    raw.mkdir()
    for source in (FIRST, SECOND):
        shutil.copyfile(source, raw / source.name)
    landed: list[Any] = []
    real = landing.land_runs

    def recording(*a: Any, **k: Any) -> Any:
        landed.append(real(*a, **k))
        return landed[-1]

    monkeypatch.setattr(landing, "land_runs", recording)
    monkeypatch.setattr("tribopipe.campaign.batch.land_runs", recording)
    report = run_campaign(folder_campaign(raw, filename_pattern=PATTERN, output_dir=out,
                                          map_path=mapfile), jobs=1, plots=False)
    assert len(report.reduced) == 2 and report.map_landed and landed
    for value in [*vars(report).values(), *(v for x in landed for v in vars(x).values())]:
        assert not isinstance(value, pd.DataFrame)
    held = _watch(monkeypatch, mapfile)
    text = map_paper_text(open_groups(mapfile))
    assert held == []  # the stored groups, no part read
    assert text == map_paper_text(open_map(mapfile)) and "Dragonskin 30" in text
    done = _batch(raw, mapfile, out)  # unchanged: the map is not touched, nor printed
    assert done.exit_code == 0 and "Dragonskin 30" not in done.output, done.output

"""One duplicate and conflict check for `reduce` and `batch`, made under the map's lock.

The same content under two names is a duplicate (same labels: stored once) or a conflict
(other labels: refused). Both commands decide it from the map as read while they hold
the map's lock, so no other writer can slip a row in between the check and the write.
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from click.testing import CliRunner
from filelock import FileLock, Timeout

import tribopipe.pipeline.landing as landing
from helpers import reduce_cli
from tribopipe.cli import main
from tribopipe.frictionmap.store import update_map_with

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "raw" / "example" / "DS30_steel_1N_10C_r1.csv"
PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
pytestmark = pytest.mark.skipif(not EXAMPLE.exists(), reason="the example campaign is not here")


def _lock_is_held(map_path: Path) -> bool:
    try:
        FileLock(str(map_path) + ".lock", timeout=0).acquire()
    except Timeout:
        return True
    return False


def _watching(module: Any, monkeypatch: pytest.MonkeyPatch, map_path: Path) -> list[bool]:
    """Record, each time ``module`` asks which files the map holds, whether the map's
    lock was held then."""
    held: list[bool] = []
    real = module.map_files_by_hash

    def watched(runs: Any) -> Any:
        held.append(_lock_is_held(map_path))
        return real(runs)

    monkeypatch.setattr(module, "map_files_by_hash", watched)
    return held


def test_update_map_with_decides_under_the_lock(tmp_path: Path) -> None:
    target = tmp_path / "map.parquet"
    seen: list[bool] = []

    def decide(current: pd.DataFrame) -> tuple[list[dict[str, Any]], tuple[str, ...]]:
        seen.append(_lock_is_held(target))
        return [], ()

    report = update_map_with(target, decide)
    assert seen == [True] and not report.changed and not target.exists()


def _reduce(path: Path, mapfile: Path, out: Path, disc: str = "steel") -> Any:
    return reduce_cli(path, "--pin", "DS30", "--disc", disc, "--force", "1",
                      "--temperature", "10", "--repeat", "1", "--map", mapfile, "--output", out)


def test_reduce_checks_the_same_content_under_the_map_lock(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    mapfile, out = tmp_path / "map.parquet", tmp_path / "out"
    first = _reduce(EXAMPLE, mapfile, out)
    assert first.exit_code == 0, first.output
    copy = tmp_path / "copy_of_r1.csv"
    shutil.copyfile(EXAMPLE, copy)
    held = _watching(landing, monkeypatch, mapfile)
    again = _reduce(copy, mapfile, out)
    assert again.exit_code == 0, again.output
    assert held == [True]
    assert "duplicate:" in again.stderr and EXAMPLE.name in again.stderr
    assert len(pd.read_parquet(mapfile)) == 1  # stored once, under the first name
    assert list(pd.read_parquet(mapfile)["source_file"]) == [EXAMPLE.name]


def test_batch_checks_the_same_content_under_the_map_lock(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    raw = tmp_path / "raw"
    (raw / "a").mkdir(parents=True)
    (raw / "b").mkdir()
    shutil.copyfile(EXAMPLE, raw / "a" / EXAMPLE.name)
    shutil.copyfile(EXAMPLE, raw / "b" / "DS30_steel_1N_10C_r2.csv")  # other repeat: a conflict
    mapfile = tmp_path / "map.parquet"
    held = _watching(landing, monkeypatch, mapfile)
    done = CliRunner().invoke(main, ["batch", str(raw), "--pattern", PATTERN, "--glob",
                                     "*/*.csv", "--output", str(tmp_path / "out"), "--map",
                                     str(mapfile), "--jobs", "1", "--no-plots"])
    assert held == [True]
    assert done.exit_code == 1, done.output
    assert "conflict: b/DS30_steel_1N_10C_r2.csv: same content as a/" in done.output
    assert "repeat 1 vs 2" in done.output
    assert len(pd.read_parquet(mapfile)) == 1

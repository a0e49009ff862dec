"""The map under real concurrency: two writer processes at once lose nothing, and a writer
killed in the middle of a write (SIGKILL) leaves the previous map byte-identical."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from test_frictionmap import run_record
from tribopipe import frictionmap as fm

pytestmark = pytest.mark.slow

WRITER = """
import json, sys
from tribopipe.frictionmap import append_records
map_path, records_path = sys.argv[1], sys.argv[2]
records = json.loads(open(records_path).read())
for record in records:  # one append (one lock, one atomic write) per run
    append_records(map_path, [record])
print("done", len(records))
"""


def _start_writer(tmp_path: Path, name: str, map_path: Path, records: list[dict],
                  env: dict[str, str] | None = None) -> subprocess.Popen:
    script = tmp_path / "writer.py"
    script.write_text(WRITER)
    records_path = tmp_path / f"{name}.json"
    records_path.write_text(json.dumps(records))
    return subprocess.Popen(
        [sys.executable, str(script), str(map_path), str(records_path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, **(env or {})},
    )


def test_two_processes_appending_at_once_lose_no_run(tmp_path):
    map_path = tmp_path / "processed" / "friction_map.parquet"
    a = [run_record(i, repeat=i) for i in range(12)]
    b = [run_record(100 + i, repeat=i, disc="acrylic glass") for i in range(12)]
    writers = [_start_writer(tmp_path, "a", map_path, a), _start_writer(tmp_path, "b", map_path, b)]
    for w in writers:
        out, err = w.communicate(timeout=300)
        assert w.returncode == 0, err
        assert out.strip() == "done 12"
    runs = fm.read_map(map_path)
    expected = {r["measurement_id"] for r in a + b}
    assert set(runs["measurement_id"]) == expected and len(runs) == 24
    # every writer's runs are there in its own order
    order = list(runs["measurement_id"])
    for batch in (a, b):
        positions = [order.index(r["measurement_id"]) for r in batch]
        assert positions == sorted(positions)
    assert not list(map_path.parent.glob(".*.tmp"))


def test_a_writer_killed_before_the_rename_leaves_the_previous_map_intact(tmp_path):
    map_path = tmp_path / "friction_map.parquet"
    fm.append_records(map_path, [run_record(1), run_record(2)])
    before = map_path.read_bytes()
    marker = tmp_path / "paused"
    writer = _start_writer(tmp_path, "new", map_path, [run_record(3)],
                           env={fm.PAUSE_ENV: str(marker)})
    deadline = time.monotonic() + 120
    while not marker.exists():
        assert writer.poll() is None, writer.communicate()[1]
        assert time.monotonic() < deadline, "writer never reached the pause"
        time.sleep(0.05)
    temps = list(tmp_path.glob(f".{map_path.name}.*.tmp"))
    assert len(temps) == 1 and temps[0].stat().st_size > 0  # the new map was fully written
    writer.send_signal(signal.SIGKILL)
    writer.communicate(timeout=60)
    assert writer.returncode == -signal.SIGKILL

    assert map_path.read_bytes() == before
    runs = fm.read_map(map_path)
    assert len(runs) == 2
    # the lock died with the writer; the next append works and clears the stale temp file
    report = fm.append_records(map_path, [run_record(3)])
    assert report.added == 1 and len(fm.read_map(map_path)) == 3
    assert not list(tmp_path.glob(f".{map_path.name}.*.tmp"))

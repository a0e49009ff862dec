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

from map_files import map_bytes
from test_frictionmap import run_record
from tribopipe import frictionmap as fm
from tribopipe.frictionmap.schema import MapRow

pytestmark = pytest.mark.slow

WRITER = """
import json, sys
from tribopipe.frictionmap import append_records
from tribopipe.frictionmap.schema import MapRow
map_path, records_path = sys.argv[1], sys.argv[2]
records = json.loads(open(records_path).read())
for record in records:  # one append (one lock, one atomic write) per run
    append_records(map_path, [MapRow.from_mapping(record)])
print("done", len(records))
"""

#: the writer, stopped once its new part and its new manifest are fully written, before it
#: renames the manifest over the committed one: it writes MARKER and sleeps there until
#: the test kills it
PAUSED_WRITER = """
import os, pathlib, time
map_path, marker = os.environ["MAP"], os.environ["MARKER"]
replace = os.replace
def replace_after_a_pause(src, dst, *args, **kwargs):
    if os.fspath(dst) == os.path.join(map_path, "_manifest.json"):
        pathlib.Path(marker).write_text(str(os.getpid()))
        time.sleep(600)
    return replace(src, dst, *args, **kwargs)
os.replace = replace_after_a_pause
""" + WRITER


def _start_writer(tmp_path: Path, name: str, map_path: Path, records: list[MapRow],
                  env: dict[str, str] | None = None, code: str = WRITER) -> subprocess.Popen:
    script = tmp_path / f"writer_{name}.py"
    script.write_text(code)
    records_path = tmp_path / f"{name}.json"
    records_path.write_text(json.dumps([r.as_dict() for r in records]))
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
    expected = {r.measurement_id for r in a + b}
    assert set(runs["measurement_id"]) == expected and len(runs) == 24
    # every writer's runs are there in its own order
    order = list(runs["measurement_id"])
    for batch in (a, b):
        positions = [order.index(r.measurement_id) for r in batch]
        assert positions == sorted(positions)
    assert not list(map_path.parent.glob(".*.tmp"))


def test_a_writer_killed_before_the_rename_leaves_the_previous_map_intact(tmp_path):
    map_path = tmp_path / "friction_map.parquet"
    fm.append_records(map_path, [run_record(1), run_record(2)])
    before = map_bytes(map_path)
    marker = tmp_path / "paused"
    writer = _start_writer(tmp_path, "new", map_path, [run_record(3)],
                           env={"MAP": str(map_path), "MARKER": str(marker)},
                           code=PAUSED_WRITER)
    deadline = time.monotonic() + 120
    while not marker.exists():
        assert writer.poll() is None, writer.communicate()[1]
        assert time.monotonic() < deadline, "writer never reached the pause"
        time.sleep(0.05)
    temps = list(map_path.glob(".*.tmp"))
    assert len(temps) == 1 and temps[0].stat().st_size > 0  # the new manifest was written
    writer.send_signal(signal.SIGKILL)
    writer.communicate(timeout=60)
    assert writer.returncode == -signal.SIGKILL

    after = map_bytes(map_path)
    # the committed manifest and its parts are byte-identical; the killed writer's part
    # (named by no manifest), its temporary manifest and the backup of the committed
    # manifest (written before the new one replaces it) are all it left
    assert {k: v for k, v in after.items() if k in before} == before
    left = set(after) - set(before) - {fm.parts.MANIFEST_BACKUP}
    assert len(left) == 2 and {n.endswith(".tmp") for n in left} == {True, False}, left
    backup = json.loads(after[fm.parts.MANIFEST_BACKUP])["parts"]
    assert [p.sha256 for p in fm.parts.read_manifest(map_path).parts] == [
        p["sha256"] for p in backup]
    runs = fm.read_map(map_path)
    assert len(runs) == 2
    # the lock died with the writer; the next append works and clears what it left
    report = fm.append_records(map_path, [run_record(3)])
    assert report.added == 1 and len(fm.read_map(map_path)) == 3
    assert not list(map_path.glob(".*.tmp"))
    assert not list(fm.parts.leftovers(map_path))


def test_a_backup_that_is_already_the_map_leaves_no_temporary_file(tmp_path):
    """A writer killed after linking the map as <map>.bak and before its rename leaves
    <map>.bak a link of the map itself; the next write keeps it and leaves nothing else
    (a single-file map: the format before map folders, rewritten whole)."""
    map_path = tmp_path / "friction_map.parquet"
    fm.store.write_map_copy(map_path, fm.records_frame([run_record(1)]))
    backup = fm.store.backup_path(map_path)
    backup.unlink(missing_ok=True)
    os.link(map_path, backup)
    fm.append_records(map_path, [run_record(2)])
    assert len(fm.read_map(map_path)) == 2 and len(fm.read_map(backup)) == 1
    assert not list(tmp_path.glob(".*.tmp"))


HOLDER = """
import sys, time
from filelock import FileLock
lock = FileLock(sys.argv[1])
lock.acquire()
print("holding", flush=True)
time.sleep(600)
"""


def _hold_lock(tmp_path: Path, lock_path: Path) -> subprocess.Popen:
    """Another process holding the map's lock, as a tribopipe command does while it
    writes; returns once it holds it."""
    script = tmp_path / "holder.py"
    script.write_text(HOLDER)
    holder = subprocess.Popen([sys.executable, str(script), str(lock_path)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "holding", holder.stderr.read()
    return holder


def test_a_live_lock_refuses_in_one_line_and_a_killed_holder_s_lock_blocks_nothing(
    tmp_path, monkeypatch
):
    from click.testing import CliRunner

    from tribopipe.cli import main
    from tribopipe.errors import MapError
    from tribopipe.frictionmap import store

    map_path = tmp_path / "friction_map.parquet"
    fm.append_records(map_path, [run_record(1)])
    before = map_bytes(map_path)
    lock_path = Path(str(map_path) + ".lock")
    holder = _hold_lock(tmp_path, lock_path)
    try:
        monkeypatch.setattr(store, "LOCK_TIMEOUT_S", 0.5)  # the default waits a minute
        with pytest.raises(MapError) as refused:
            fm.append_records(map_path, [run_record(2)])
        line = str(refused.value)
        assert "\n" not in line and str(map_path) in line
        assert "locked by another process for more than 0.5 s" in line
        assert "a killed process releases it" in line
        # the command line says the same in one line, exit code 1
        result = CliRunner().invoke(main, ["map", "exclude", "--map", str(map_path),
                                           run_record(1).measurement_id, "--reason", "x"])
        assert result.exit_code == 1 and "Traceback" not in result.output
        assert "locked by another process" in result.output
        assert map_bytes(map_path) == before
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.communicate(timeout=60)
    # the holder died with its lock: the file is left behind and blocks nothing
    # (the lock timeout is still 0.5 s: a lock still held would raise MapError here)
    assert lock_path.exists()
    report = fm.append_records(map_path, [run_record(2)])
    assert report.added == 1

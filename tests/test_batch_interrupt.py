"""A batch lands as it goes, and work is kept on interrupt: a real `tribopipe batch`
process stopped by a real SIGINT (Ctrl-C) or SIGTERM keeps every run it landed, releases
its locks, says how many runs landed and exits 130 or 143; killed by SIGKILL, it leaves a
readable map whose locks block nothing. The next batch reduces only the rest."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe import frictionmap as fm
from tribopipe.campaign import folder_campaign, run_campaign
from tribopipe.campaign.state import load_kept

pytestmark = pytest.mark.slow  # real processes reducing dozens of exports

N_FILES = 60
PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"


@pytest.fixture(scope="module")
def exports(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Distinct synthetic exports named for their labels (one run each)."""
    folder = tmp_path_factory.mktemp("exports")
    for i in range(N_FILES):
        force = (1, 3, 5)[i % 3]
        write_rheocompass_export(
            folder / f"DS30_steel_{force}N_20C_r{i // 3 + 1}.csv",
            SyntheticRun(mu_s=0.8, mu_k=0.5 + 0.002 * i, normal_force_N=float(force),
                         seed=100 + i, duration_s=6000.0),  # long: a batch of many seconds
            project="interrupt", test="t", sample="DS30")
    return folder


def _start(raw: Path, map_path: Path, out: Path, jobs: int,
           plots: bool = False) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "tribopipe", "batch", str(raw), "--pattern", PATTERN,
         "--map", str(map_path), "--out", str(out), "--plots" if plots else "--no-plots",
         "-j", str(jobs)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})


def _wait_for_a_landing(proc: subprocess.Popen[str], map_path: Path) -> None:
    deadline = time.monotonic() + 600
    while not (map_path / fm.parts.MANIFEST).exists():
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "the batch never landed anything"
        time.sleep(0.05)


def _copy(exports: Path, tmp_path: Path) -> Path:
    raw = tmp_path / "raw"
    raw.mkdir()
    for f in exports.iterdir():
        (raw / f.name).write_bytes(f.read_bytes())
    return raw


# the pool of two workers also draws each run's plot: a longer batch, so that the signal
# comes while runs are still being reduced
@pytest.mark.parametrize(("sig", "code", "jobs"), [
    (signal.SIGINT, 130, 1), (signal.SIGTERM, 143, 2)])
def test_a_stopped_batch_keeps_what_landed_and_the_next_reduces_the_rest(
        exports: Path, tmp_path: Path, sig: signal.Signals, code: int, jobs: int) -> None:
    raw = _copy(exports, tmp_path)
    map_path, out = tmp_path / "friction_map.parquet", tmp_path / "out"
    proc = _start(raw, map_path, out, jobs, plots=jobs > 1)
    _wait_for_a_landing(proc, map_path)
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=600)
    if proc.returncode == 0:  # pragma: no cover - the machine finished first
        pytest.skip("the batch finished before the signal reached it")
    assert proc.returncode == code, stderr
    assert "Traceback" not in stderr, stderr
    line = [ln for ln in stderr.splitlines() if ln.startswith("interrupted by ")]
    assert len(line) == 1, stderr
    landed = int(line[0].split(": ", 1)[1].split(" ")[0])
    kept = fm.read_map(map_path)
    if landed == N_FILES == len(kept):  # pragma: no cover - every run landed first
        pytest.skip("every run had landed before the signal reached the batch")
    assert 0 < landed == len(kept) < N_FILES, (landed, len(kept))
    assert f"interrupted by {sig.name}" in line[0]
    # its locks are gone or block nothing: the next batch runs and reduces only the rest
    campaign = folder_campaign(raw, filename_pattern=PATTERN, map_path=map_path,
                               output_dir=out)
    # a stopped batch rehearses no re-run: it keeps no ledger, kept or pending
    assert load_kept(campaign) is None
    report = run_campaign(campaign, jobs=1, plots=False)
    assert len(report.skipped) == landed and len(report.reduced) == N_FILES - landed
    assert report.ok and report.interrupted is None
    assert len(fm.read_map(map_path)) == N_FILES
    # that one did its work cleanly: the next is its rehearsed re-run, which reads nothing
    pending = load_kept(campaign)
    assert pending is not None and pending.tables is not None
    again = run_campaign(campaign, jobs=1, plots=False)
    assert again.kept and len(again.skipped) == N_FILES and again.reduced == []


def test_a_killed_batch_leaves_a_readable_map_and_no_lock_that_blocks(
        exports: Path, tmp_path: Path) -> None:
    raw = _copy(exports, tmp_path)
    map_path, out = tmp_path / "friction_map.parquet", tmp_path / "out"
    proc = _start(raw, map_path, out, 1)
    _wait_for_a_landing(proc, map_path)
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=600)
    assert proc.returncode == -signal.SIGKILL
    landed = len(fm.read_map(map_path))
    assert landed > 0
    campaign = folder_campaign(raw, filename_pattern=PATTERN, map_path=map_path,
                               output_dir=out)
    report = run_campaign(campaign, jobs=1, plots=False)
    assert report.ok, report.failures
    assert len(fm.read_map(map_path)) == N_FILES
    assert len(report.reduced) + len(report.skipped) == N_FILES

"""A worker process that dies in the middle of a batch (killed for its memory, a crash in a
native library) costs the files it held, and those the pool can no longer take, a
transient failure each, tried again by the next batch: never the batch itself."""

from __future__ import annotations

import os
from collections.abc import Sequence

from tribopipe.campaign import batch, folder_campaign
from tribopipe.campaign.worker import Job, WorkerContext, crashed
from tribopipe.pipeline.runs import FileOutcome


def _dies_on_the_first_file(chunk: Sequence[Job], ctx: WorkerContext) -> list[FileOutcome]:
    """A worker's chunk: the process exits at once (as the kernel's OOM killer ends it)
    when it holds the first file; any other chunk comes back as a failure it names."""
    if any(job.file == "f000.csv" for job in chunk):
        os._exit(1)
    return crashed(chunk, ValueError("reduced elsewhere"))


def test_a_worker_that_dies_leaves_every_file_accounted_for(monkeypatch, tmp_path):
    monkeypatch.setattr(batch, "reduce_chunk", _dies_on_the_first_file)
    files = [f"f{i:03d}.csv" for i in range(200)]  # far more chunks than are sent at once
    ctx = WorkerContext(campaign=folder_campaign(
        tmp_path, filename_pattern="{pin}_{disc}_{normal_force_N}N_{temperature_C}C_r{repeat}"),
        plots=False)

    def job_of(file: str) -> Job:
        return Job(file=file, path=str(tmp_path / file), sources=(), hints=())

    parts = list(batch._execute(files, job_of, ctx, 2, batch.StopFlag()))
    outcomes = [o for part in parts for o in part]
    assert sorted(o.name for o in outcomes) == files  # each once, none lost
    first = next(o for o in outcomes if o.name == "f000.csv")
    assert first.error is not None and "worker process failed" in first.error.reason
    assert "run again" in first.error.reason

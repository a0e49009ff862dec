"""A batch worker's part: one export of a campaign → its runs, each labelled and reduced.

A worker (a process of the batch's pool, or the batch itself for one job) sends a file
down the one route from an export to its runs (:func:`tribopipe.pipeline.reduce_export`,
the route ``tribopipe reduce`` takes too), labelling each run from the metadata sources
of its test (:mod:`tribopipe.campaign.metadata`), and returns the small picklable
:class:`~tribopipe.pipeline.FileOutcome` (never a trace). A test or run that fails is a
:class:`~tribopipe.pipeline.FailedRun` beside the others; nothing a file holds stops the
batch.
"""

from __future__ import annotations

import contextlib
import gc
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from ..errors import CampaignError, Failure, TribopipeError
from ..figures import trace_figure
from ..labels import FLAG_SYNTHETIC, RunLabels, Undescribed
from ..pipeline.route import failure_of, reduce_export
from ..pipeline.run_outputs import RunOutputs
from ..pipeline.runs import ExportRuns, FailedRun, FileOutcome, RunPlace
from .metadata import ManifestRow, labels_from, merge_metadata, run_report, run_rows
from .patterns import match_pattern
from .spec import Campaign


@dataclass(frozen=True)
class Job:
    """One file to reduce: its campaign-relative name, its path, the file-level metadata
    sources and hints (:class:`~tribopipe.campaign.table.CampaignRow`), the manifest rows
    of its tests and its SHA-256 when already known."""

    file: str
    path: str
    sources: tuple[tuple[str, dict[str, Any]], ...]
    hints: tuple[str, ...]
    test_rows: tuple[ManifestRow, ...] = ()
    sha256: str | None = None


@dataclass(frozen=True)
class WorkerContext:
    campaign: Campaign
    plots: bool


def run_labels(job: Job, place: RunPlace, name: str, campaign: Campaign,
               tests_with_runs: int, header: Mapping[str, str] | None = None) -> RunLabels:
    """The labels of one run, from the metadata sources of its test, in order: the
    manifest rows of its interval and of its test (:func:`run_rows`), the file-level
    sources (manifest row of the file, file name), the test-name pattern on its Test name.
    Raises :class:`CampaignError` naming the run when they contradict each other or a
    required field is missing, and when a file of several tests with runs describes this
    one only at file level (the file's sources cannot tell its tests apart)."""
    sources: list[tuple[str, dict[str, Any]]] = []
    hints = list(job.hints)
    per_test = False
    for row in run_rows(job.test_rows, place.test, place.interval):
        if row.problem is not None:
            raise CampaignError(row.problem, path=name)
        sources.append((f"manifest line {row.line}", dict(row.fields)))
        # an interval row without a test names that interval of every test: it tells
        # the intervals of a test apart, not the tests of a file
        per_test = per_test or row.test is not None
    if job.test_rows and not sources:
        hints.append(f"no manifest row for test {place.test!r}"
                     + ("" if place.interval is None else f" or its interval {place.interval}"))
    sources.extend(job.sources)
    pattern = campaign.test_pattern
    if pattern is not None:
        found = match_pattern(pattern, place.test) if place.test else None
        if found is None:
            hints.append(f"Test name {place.test!r} does not match pattern {pattern!r}")
        else:
            sources.append((f"export Test name {place.test!r}", found))
            per_test = True
    if not sources:
        raise Undescribed(f"metadata missing: no metadata source describes test "
                           f"{place.test!r}", path=name,
                           hint="; ".join(hints) or "add it to the manifest")
    if tests_with_runs > 1 and not per_test:
        described = ", ".join(source for source, _ in sources)
        raise Undescribed(
            f"the file holds {tests_with_runs} tests with runs and only file-level metadata "
            f"({described}) describes them: it cannot tell them apart",
            path=name,
            hint="give the manifest a 'test' column (one row per test) or set a test-name "
                 "pattern (test_pattern, --test-pattern)" + (f"; {'; '.join(hints)}"
                                                             if hints else ""),
        )
    merged = merge_metadata(name, sources, campaign)
    return labels_from(name, merged, hints=hints,
                       report=run_report(merged, campaign.report, header))


def _reduce_one(job: Job, ctx: WorkerContext) -> FileOutcome:
    """Reduce one file in a worker through the one route (:func:`reduce_export`), each run
    labelled from the metadata sources of its test (:func:`run_labels`)."""
    campaign = ctx.campaign

    def labels_for(export: ExportRuns, place: RunPlace, name: str) -> RunLabels:
        tests_with_runs = len({p.test for p, _ in export.runs})
        header = next((dict(m.meta.extra) for p, m in export.runs if p == place), None)
        return run_labels(job, place, name, campaign, tests_with_runs, header)

    return reduce_export(job.path, campaign.settings, labels_for, campaign.read_options,
                         tolerances=campaign.tolerances,
                         extra_flags=(FLAG_SYNTHETIC,) if campaign.synthetic else (),
                         file_hash=job.sha256,
                         outputs=RunOutputs(campaign.layout, plot=ctx.plots), name=job.file,
                         check=campaign.label_check)


#: Cyclic-GC thresholds while reducing. Parsing an export allocates ~10⁵ short-lived
#: containers (cells, rows), which with the default gen-0 threshold (700) triggers hundreds
#: of collections per file that find nothing; measured: −20 % CPU per run.
#:
#: Workers also run one BLAS thread: the batch is already one process per CPU, and
#: OpenBLAS hands a dot product of ~10⁴ samples to its threads, whose start and spin cost
#: more than the product (measured: a reduction 4.7 ms with one thread, 16-31 ms with the
#: default on the 2-CPU benchmark machine while both workers run).
GC_THRESHOLDS = (100_000, 50, 100)


def prepare_workers(ctx: WorkerContext) -> None:
    """Before the workers fork, load in this process what each of them would load for
    itself, so that they inherit it: pandas and pyarrow with the image plugins (~350
    modules, which every worker imports to read and store a run: ~0.5 s of CPU each, and
    on a fresh install each compiled them again; this process needs them anyway to land
    the runs), and when the batch draws plots the trace figure (matplotlib imported,
    fonts loaded, palette and first background drawn: another ~0.5 s each, and memory
    they now share). Only where workers are forked; elsewhere each loads its own."""
    import multiprocessing

    if multiprocessing.get_start_method() != "fork":
        return
    import pandas  # noqa: F401 - loaded to be inherited
    import pyarrow.parquet  # noqa: F401
    from PIL import PngImagePlugin  # noqa: F401

    if ctx.plots:
        trace_figure()


def worker_init() -> None:
    """Start a worker process (ours for its whole life): fewer garbage-collector passes
    and one BLAS thread (see :data:`GC_THRESHOLDS`)."""
    import signal

    from threadpoolctl import threadpool_limits

    gc.set_threshold(*GC_THRESHOLDS)
    threadpool_limits(limits=1, user_api="blas")
    # Ctrl-C reaches the whole process group: the batch (the parent) decides what stops,
    # and ends its workers itself
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def fewer_gc_passes() -> Iterator[None]:
    """:func:`worker_init`'s tuning for an in-process batch, restored afterwards."""
    from threadpoolctl import threadpool_limits

    before = gc.get_threshold()
    gc.set_threshold(*GC_THRESHOLDS)
    try:
        with threadpool_limits(limits=1, user_api="blas"):
            yield
    finally:
        gc.set_threshold(*before)


def _failed_file(job: Job, failure: Failure, *, transient: bool = False) -> FileOutcome:
    """A file that failed as a whole, outside the route (its labels, a crash)."""
    return FileOutcome(path=job.path, name=job.file, file_hash=job.sha256,
                       error=FailedRun(name=job.file, failure=failure, transient=transient))


def reduce_chunk(jobs: Sequence[Job], ctx: WorkerContext) -> list[FileOutcome]:
    """Reduce a chunk of files; each failure is caught and returned with its reason."""
    out: list[FileOutcome] = []
    for job in jobs:
        try:
            out.append(_reduce_one(job, ctx))
        except TribopipeError as exc:
            out.append(_failed_file(job, failure_of(exc, job.path, job.file)))
        except Exception as exc:  # noqa: BLE001 - one broken file must not stop a campaign
            out.append(_failed_file(job, Failure(
                f"internal error {type(exc).__name__}: {exc} (please report with the file)",
                path=job.file), transient=True))
    return out


def crashed(jobs: Sequence[Job], exc: BaseException) -> list[FileOutcome]:
    """The results of a chunk whose worker process died (e.g. killed for memory): each
    file a transient failure, tried again next time."""
    return [_failed_file(job, Failure(f"worker process failed ({type(exc).__name__}: {exc}); "
                                      "run again", path=job.file), transient=True)
            for job in jobs]

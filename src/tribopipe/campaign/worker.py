"""A batch worker's part: one export of a campaign → its runs, each labelled and reduced.

A worker (a process of the batch's pool, or the batch itself for one job) reads a file once
(:func:`tribopipe.pipeline.read_runs`), resolves each run's labels from the metadata
sources of its test (:mod:`tribopipe.campaign.metadata`), reduces it, writes its trace
and trace plot at the layout's paths and returns a small picklable :class:`FileDone`
(never a trace). A test or run that fails is a :class:`FailedRun` beside the others;
nothing a file holds stops the batch.
"""

from __future__ import annotations

import contextlib
import gc
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass
from typing import Any

from ..errors import CampaignError, TribopipeError
from ..escape import display_path, printable
from ..figures import trace_figure
from ..files import os_reason
from ..frictionmap.records import RunLabels
from ..numeric import finite_or_none
from ..pipeline import (
    ExportRuns,
    RunOutcome,
    RunPlace,
    plot_run,
    read_runs,
    reduce_run,
    run_name,
    write_trace,
)
from .metadata import ManifestRow, labels_from, merge_metadata, run_rows
from .patterns import match_pattern
from .spec import Campaign
from .table import RunEntry


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


@dataclass(frozen=True)
class ReducedRun:
    """A run a worker reduced: its file, its name (the file, with the run's place when the
    export holds several), the map record, what the state keeps of it, and a note when
    its trace plot could not be drawn."""

    file: str
    record: dict[str, Any]
    entry: RunEntry
    plot_note: str | None = None

    @property
    def name(self) -> str:
        """The run's name: ``file`` or ``file [test / result / interval i]``."""
        return self.entry.name or self.file


@dataclass(frozen=True)
class FailedRun:
    """A run (or a test without a friction interval, or a whole file: then ``name`` is the
    file and ``test`` ``None``) a worker could not reduce, with its one-line reason;
    ``transient`` when it was not the file's fault (a crashed worker, an internal error),
    so the state is left alone and the file tried again next time; ``undescribed`` when no
    metadata source described its test."""

    file: str
    reason: str
    transient: bool = False
    name: str = ""
    test: str | None = None
    result: str | None = None
    interval: int | None = None
    undescribed: bool = False

    def as_state(self) -> dict[str, Any]:
        """The run's state entry (``status`` failed)."""
        out = {"status": "failed", "name": self.name or self.file, "test": self.test,
               "result": self.result, "interval": self.interval, "reason": self.reason}
        if self.undescribed:
            out["undescribed"] = True
        return out


@dataclass(frozen=True)
class FileDone:
    """What a worker returns per file: its SHA-256, its Test names (in file order) and a
    :class:`ReducedRun` or :class:`FailedRun` per run; or ``error``, the file as a whole
    (unreadable, not an export, a crashed worker)."""

    file: str
    sha256: str | None = None
    tests: tuple[str | None, ...] = ()
    runs: tuple[ReducedRun | FailedRun, ...] = ()
    error: FailedRun | None = None

    @property
    def transient(self) -> bool:
        """True when the file or a run failed for a reason that is not the file's."""
        return (self.error is not None and self.error.transient) or any(
            isinstance(r, FailedRun) and r.transient for r in self.runs)

    @property
    def reduced(self) -> list[ReducedRun]:
        """The runs reduced, in file order."""
        return [r for r in self.runs if isinstance(r, ReducedRun)]


#: what a worker returns per file (small and picklable: never the trace)
RunResult = FileDone


class _Undescribed(CampaignError):
    """No metadata source describes a test (as a test): named in the batch's ledger."""


def _reason(exc: TribopipeError, job: Job, name: str | None = None) -> str:
    """The one-line reason of a failure, starting with the file's campaign-relative name
    (readers name the absolute path, which is long and machine-specific)."""
    text = str(exc)
    if exc.path is None:
        return f"{display_path(name or job.file)}: {text}"
    shown = display_path(exc.path)
    if exc.path == job.path and text.startswith(shown):
        return display_path(job.file) + text[len(shown):]
    return text


def run_labels(job: Job, place: RunPlace, name: str, campaign: Campaign,
               tests_with_runs: int) -> RunLabels:
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
        raise _Undescribed(f"metadata missing: no metadata source describes test "
                           f"{place.test!r}", path=name,
                           hint="; ".join(hints) or "add it to the manifest")
    if tests_with_runs > 1 and not per_test:
        described = ", ".join(source for source, _ in sources)
        raise _Undescribed(
            f"the file holds {tests_with_runs} tests with runs and only file-level metadata "
            f"({described}) describes them: it cannot tell them apart",
            path=name,
            hint="give the manifest a 'test' column (one row per test) or set a test-name "
                 "pattern (test_pattern, --test-pattern)" + (f"; {'; '.join(hints)}"
                                                             if hints else ""),
        )
    return labels_from(name, merge_metadata(name, sources, campaign), hints=hints)


def _reduce_run(job: Job, ctx: WorkerContext, export: ExportRuns, place: RunPlace,
                measurement: Any, name: str, tests_with_runs: int) -> ReducedRun:
    """Label, reduce and write one run."""
    campaign = ctx.campaign
    labels = run_labels(job, place, name, campaign, tests_with_runs)
    outcome = reduce_run(export, place, measurement, campaign.settings, labels,
                         tolerances=campaign.tolerances)
    result = outcome.result
    record = outcome.record
    assert record is not None  # labels_from always names pin and disc
    trace = write_trace(campaign.layout, outcome)
    plot_note = _plot(campaign, outcome, name) if ctx.plots else None
    entry = RunEntry(
        labels=asdict(outcome.labels),
        measurement_id=record["measurement_id"],
        trace=trace.relative_to(campaign.output_dir).as_posix(),
        mu_s=finite_or_none(result.mu_s),
        mu_k=finite_or_none(result.mu_k),
        pressure_kPa=finite_or_none(record.get("pressure_kPa")),
        pressure_measured_kPa=finite_or_none(result.pressure_kPa),
        normal_force_measured_N=finite_or_none(result.normal_force_mean_N),
        temperature_measured_C=finite_or_none(result.temperature_C),
        flags=record["flags"],
        name=name,
        test=place.test,
        result=place.result,
        interval=place.interval,
        occurrence=place.occurrence,
    )
    return ReducedRun(file=job.file, record=record, entry=entry, plot_note=plot_note)


def _reduce_one(job: Job, ctx: WorkerContext) -> FileDone:
    """Read one file in a worker and reduce each of its runs; every run stands alone."""
    export = read_runs(job.path, ctx.campaign.read_options, file_hash=job.sha256)
    tests_with_runs = len({p.test for p, _ in export.runs})
    problems = dict(export.problems)
    measurements = dict(export.runs)
    runs: list[ReducedRun | FailedRun] = []
    for place in export.order:
        name = run_name(job.file, place, export.several)
        where = {"file": job.file, "name": name, "test": place.test, "result": place.result,
                 "interval": place.interval}
        if place in problems:
            runs.append(FailedRun(reason=_reason(problems[place], job, name), **where))
            continue
        try:
            runs.append(_reduce_run(job, ctx, export, place, measurements[place], name,
                                    tests_with_runs))
        except _Undescribed as exc:
            runs.append(FailedRun(reason=_reason(exc, job, name), undescribed=True, **where))
        except TribopipeError as exc:
            runs.append(FailedRun(reason=_reason(exc, job, name), **where))
        except OSError as exc:
            runs.append(FailedRun(reason=f"{display_path(name)}: cannot write: "
                                         f"{os_reason(exc)}", **where))
    return FileDone(file=job.file, sha256=export.file_hash, tests=export.tests,
                    runs=tuple(runs))


def _plot(campaign: Campaign, outcome: RunOutcome, name: str) -> str | None:
    """Draw a run's trace plot beside its trace; returns a note when it could not."""
    try:
        plot_run(campaign.layout, outcome)
    except Exception as exc:  # noqa: BLE001 - a picture must not cost the run its map row
        return printable(f"{name}: trace plot failed ({type(exc).__name__}: {exc})")
    return None


#: Cyclic-GC thresholds while reducing. Parsing an export allocates ~10⁵ short-lived
#: containers (cells, rows), which with the default gen-0 threshold (700) triggers hundreds
#: of collections per file that find nothing; measured: −20 % CPU per run.
#:
#: Workers also run one BLAS thread: the batch is already one process per CPU, and
#: OpenBLAS hands a dot product of ~10⁴ samples to its threads, whose start and spin cost
#: more than the product (measured: a reduction 4.7 ms with one thread, 16-31 ms with the
#: default on the 2-CPU benchmark machine while both workers run).
GC_THRESHOLDS = (100_000, 50, 100)


def prepare_plots(ctx: WorkerContext) -> None:
    """When the batch draws plots, build this process's trace figure before the workers
    fork, so that they inherit it (matplotlib imported, fonts loaded, palette and first
    background drawn: ~0.5 s of CPU each would spend, and memory they now share) instead
    of building their own. Only where workers are forked; elsewhere each builds its figure
    on its first plot."""
    import multiprocessing

    if ctx.plots and multiprocessing.get_start_method() == "fork":
        trace_figure()


def worker_init() -> None:
    """Start a worker process (ours for its whole life): fewer garbage-collector passes
    and one BLAS thread (see :data:`GC_THRESHOLDS`)."""
    from threadpoolctl import threadpool_limits

    gc.set_threshold(*GC_THRESHOLDS)
    threadpool_limits(limits=1, user_api="blas")


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


def reduce_chunk(jobs: Sequence[Job], ctx: WorkerContext) -> list[FileDone]:
    """Reduce a chunk of files; each failure is caught and returned with its reason."""
    out: list[FileDone] = []
    for job in jobs:
        try:
            out.append(_reduce_one(job, ctx))
        except TribopipeError as exc:
            out.append(FileDone(file=job.file, error=FailedRun(file=job.file, name=job.file,
                                                               reason=_reason(exc, job))))
        except OSError as exc:
            out.append(FileDone(file=job.file, error=FailedRun(
                file=job.file, name=job.file,
                reason=f"{display_path(job.file)}: cannot read or write: {os_reason(exc)}")))
        except Exception as exc:  # noqa: BLE001 - one broken file must not stop a campaign
            out.append(FileDone(file=job.file, error=FailedRun(
                file=job.file, name=job.file, transient=True,
                reason=printable(f"{display_path(job.file)}: internal error "
                                 f"{type(exc).__name__}: {exc} (please report with the "
                                 "file)"))))
    return out


def crashed(jobs: Sequence[Job], exc: BaseException) -> list[FileDone]:
    """The results of a chunk whose worker process died (e.g. killed for memory): each
    file a transient failure, tried again next time."""
    return [FileDone(file=job.file, error=FailedRun(
        file=job.file, name=job.file, transient=True,
        reason=f"{job.file}: worker process failed ({type(exc).__name__}: {exc}); run again"))
        for job in jobs]

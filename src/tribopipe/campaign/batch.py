"""The batch: every new or changed file of a campaign reduced in parallel, landed as it goes.

Workers (one process per CPU, :mod:`tribopipe.campaign.worker`) read each file once and
reduce each of its runs (one per friction interval of every test), write each trace and
trace plot at the layout's paths and return small picklable results; the parent lands
what finished in chunks, each through the one landing of ``reduce`` and the batch
(:func:`tribopipe.pipeline.landing.land_runs`: one locked atomic write of the map, the
review applied in it), each file's content checked there against the files seen before
it (in this batch, in the state, in the map: a duplicate is stored once, a conflict
refused); then it writes the state, ``runs.csv`` and ``failures.csv``, and accounts for
everything in a :class:`~tribopipe.campaign.ledger.BatchReport` whose ledger names what
was found and what was left out (:mod:`tribopipe.campaign.ledger`). A failing file, test
or run is reported and skipped, never fatal.
"""

from __future__ import annotations

import math
import os
import time
from bisect import bisect_left
from collections.abc import Callable, Container, Iterator, Mapping, MutableMapping, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from ..errors import CampaignError, OutputError, TribopipeError
from ..files import file_sha256, os_reason
from ..frictionmap.duplicates import ContentOwners, FilesByHash, labels_of
from ..frictionmap.records import stored_file_name
from ..frictionmap.schema import MapRow
from ..frictionmap.snapshot import open_map
from ..labels import flags_text, quality_flags
from ..pipeline.landing import Arrivals, arriving_ids, check_map_before_work, land_runs
from ..pipeline.runs import FileOutcome, ReducedRun
from ..review import Review, read_review
from .ledger import CONFLICT, READ, Account, BatchReport, manifest_ledger, tally
from .metadata import read_manifest
from .outputs import failures_csv_text, runs_csv_text, write_failures_csv, write_runs_csv
from .spec import Campaign
from .stamp import inputs_stamp, keep_report, kept_report
from .state import (
    DUPLICATE,
    FAILED,
    REDUCED,
    SKIPPED,
    BatchEntries,
    CampaignState,
    FileState,
    MapStamp,
    RunEntry,
    RunState,
    Shared,
    load_state,
)
from .table import (
    CampaignRow,
    CampaignTable,
    campaign_table,
    check_materials,
    describe_glob,
    recipe_hash,
)
from .worker import (
    Job,
    WorkerContext,
    crashed,
    fewer_gc_passes,
    prepare_workers,
    reduce_chunk,
    worker_init,
)

ProgressCallback = Callable[[int, int], None]

#: a batch lands what finished every this many files, or every :data:`LAND_EVERY_S`
#: seconds (at least ten times what the last landing took: landing stays a tenth of the
#: work), whichever comes first: each landing is one locked atomic write of the map and
#: of the state, and lets the results go, so memory stays flat and a stopped batch keeps
#: what it finished
LAND_EVERY_FILES = 256
LAND_EVERY_S = 2.0

class SortedNames(Container[str]):
    """Whether a name is one of ``names`` (sorted), by bisection: a campaign's files
    asked about without a set of them beside the list."""

    def __init__(self, names: Sequence[str]) -> None:
        self.names = names

    def __contains__(self, name: object) -> bool:
        at = bisect_left(self.names, name) if isinstance(name, str) else len(self.names)
        return at < len(self.names) and self.names[at] == name


def chunk_size(items: int, workers: int) -> int:
    """The items of a chunk when ``items`` are cut into a few chunks per worker: small
    enough to balance, large enough to amortise pickling."""
    return max(1, min(16, math.ceil(items / (workers * 4))))


def chunk_jobs(items: Sequence[Any], workers: int) -> list[list[Any]]:
    """``items`` cut into chunks of :func:`chunk_size` (the benchmark's parse-only pool
    uses the same cut)."""
    size = chunk_size(len(items), workers)
    return [list(items[i : i + size]) for i in range(0, len(items), size)]


def default_jobs() -> int:
    """Worker processes to use: the CPUs this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def run_campaign(
    campaign: Campaign,
    *,
    jobs: int | None = None,
    plots: bool | None = None,
    progress: ProgressCallback | None = None,
) -> BatchReport:
    """Reduce every run of every new or changed file of a campaign, in parallel, and
    update its map once.

    Writes to ``campaign.output_dir``: ``traces/*.parquet``, ``plots/traces/*.png`` (when
    plots are on; only for runs reduced now), ``runs.csv`` (one row per run),
    ``failures.csv`` (``file,reason``: the file, or the run's name) and the state file;
    appends the new records to ``campaign.map_path`` in one atomic update (replacing the
    rows of changed runs). ``progress(done, total)`` is called as files finish. Failures
    of single files, tests or runs never raise: they are in the report, and so are the
    batch's own outputs that could not be written (``output_errors``). Raises
    :class:`CampaignError` when another batch of the same campaign is running,
    :class:`MapError` when the map path holds a foreign file.
    """
    from filelock import FileLock, Timeout

    lock = FileLock(str(campaign.layout.batch_lock), timeout=0)
    try:
        campaign.output_dir.mkdir(parents=True, exist_ok=True)
        lock.acquire()
    except Timeout:
        raise CampaignError(
            "another batch of this campaign is running (its output folder is locked)",
            path=campaign.output_dir, hint="wait for it to finish",
        ) from None
    except OSError as exc:  # read-only, a file in the way, no space
        raise OutputError(f"cannot use the output folder: {os_reason(exc)}",
                          path=campaign.output_dir) from None
    try:
        return _run_locked(campaign, jobs=jobs, plots=plots, progress=progress)
    finally:
        lock.release()


def _run_locked(campaign: Campaign, *, jobs: int | None, plots: bool | None,
                progress: ProgressCallback | None) -> BatchReport:
    """:func:`run_campaign` while holding the output folder's batch lock."""
    # taken before anything is looked at: a file changed while the batch runs is then
    # never called unchanged by the next one
    inputs = inputs_stamp(campaign)
    kept = kept_report(campaign, inputs)
    if kept is not None:  # nothing changed since a batch that found nothing to do
        if progress:
            progress(kept.files, kept.files)
        return kept
    jobs = default_jobs() if jobs is None else max(1, int(jobs))
    plots = campaign.plots if plots is None else plots
    ended = _batch(campaign, load_state(campaign), jobs=jobs, plots=plots, progress=progress)
    assert ended is not None  # only a rehearsal ends without a report
    report, quiet, clean = ended.report, ended.quiet, ended.clean
    entries = ended.entries if quiet else {}
    # the state the rehearsal starts from: the one the batch holds, when it is provably
    # what reading the state file back would give (else it is read back)
    saved = ended.entries.as_read_back() if clean and not quiet else None
    # and the batch's table, whose rows the rehearsal's takes where they are provably its
    known = ended.rows if saved is not None else None
    del ended  # what the batch holds of the entries is let go first
    # a batch that found nothing to do is kept, for the next one to report again if it
    # finds the campaign as this one did; a batch that did its work cleanly keeps the
    # ledger of its next unchanged re-run, rehearsed, as pending; any other forgets it
    try:
        rerun = _rehearse(campaign, saved, known) if clean and not quiet else None
        del known
        if quiet:
            keep_report(campaign, report, inputs, entries)
        elif rerun is not None:
            keep_report(campaign, rerun[1].report, rerun[0], rerun[1].entries,
                        rerun[1].tables)
        else:
            keep_report(campaign, None, None, {})
    except OutputError as exc:
        report.output_errors.append(str(exc))
    return report


@dataclass(frozen=True)
class _Ended:
    """How a batch ended: its ``report``; whether it found nothing to do (``quiet``: its
    report is kept for the next batch) or did its work cleanly (``clean``: its next
    re-run is rehearsed); its state's ``entries`` as it left them and its campaign table
    (``rows``); for a rehearsal, the text of the ``runs.csv`` and ``failures.csv`` it
    would write (``tables``)."""

    report: BatchReport
    quiet: bool
    clean: bool
    entries: BatchEntries
    rows: CampaignTable
    tables: tuple[str, str] | None = None


def _rehearse(campaign: Campaign, state: CampaignState | None = None,
              known: CampaignTable | None = None) -> tuple[str, _Ended] | None:
    """The next batch, rehearsed at the end of one that did its work cleanly (under its
    lock, after its outputs are written): the campaign's inputs stamped as the next batch
    will stamp them, then :func:`_batch` on the state as it reads it (``state``: as the
    batch holds it, :meth:`~tribopipe.campaign.state.BatchEntries.as_read_back`; else
    read back; ``known``: the batch's table, whose rows its table takes where they are
    provably its own, :func:`~tribopipe.campaign.table.campaign_table`), writing
    nothing.
    Returns the stamp and how it ends when it finds nothing to do (its report and tables
    are then what the next unchanged batch prints and writes), else ``None``; ``None`` too
    when anything fails or a signal comes (what the batch did is not at stake)."""
    stop = StopFlag()
    ended: _Ended | None = None
    with _stop_on_signals(stop):
        inputs = inputs_stamp(campaign)
        # whatever fails here, the batch's own work is done and reported: no ledger
        with suppress(Exception):
            ended = None if inputs is None else _batch(
                campaign, load_state(campaign) if state is None else state, jobs=1,
                plots=False, progress=None, rehearse=True, known=known)
    if inputs is None or ended is None or not ended.quiet or stop.raised:
        return None
    return inputs, ended


def _batch(campaign: Campaign, state: CampaignState, *, jobs: int, plots: bool,
           progress: ProgressCallback | None, rehearse: bool = False,
           known: CampaignTable | None = None) -> _Ended | None:
    """The batch itself, from the campaign's ``state``. ``rehearse``: the next batch
    rehearsed (:func:`_rehearse`): nothing is written, and it ends (``None``) as soon as
    it finds work to do, a decisions file, a file gone, or a state it would write;
    else its tables are kept as text. ``known``: a table built before, its rows taken
    where they are provably this batch's (:func:`campaign_table`)."""
    # a decisions file is checked before any work (its runs only under the map's lock)
    review = read_review(campaign.review) if campaign.review is not None and (
        campaign.review.exists() or campaign.review.is_symlink()) else None
    # the entries of the files landed now are let go once saved (read again from the
    # state file when asked for): the batch's memory stays flat in what it lands
    entries = BatchEntries(campaign, state, fresh=not campaign.state_path.is_file())
    missing_ids, map_checked = _ids_missing_from_map(campaign, state)
    manifest = read_manifest(campaign.manifest) if campaign.manifest is not None else None
    rows = campaign_table(campaign, state=state, manifest=manifest, known=known)
    check_materials(campaign, rows)  # an unknown name refuses the campaign before any work
    plan = _plan(rows, missing_ids)
    files = len(rows)
    done = files - len(plan.todo)
    if progress:
        progress(done, files)

    if rehearse and (plan.todo or review is not None):
        return None  # not a re-run that finds nothing to do
    if plan.todo and not map_checked:
        # refuse a foreign or corrupt map before any work, reading none of its rows (they
        # are read once, under the map's lock, by each landing)
        check_map_before_work(campaign.map_path)

    notes: list[str] = rows.not_export_notes()  # content before labels: never a failure
    if not rows and not rows.not_exports:
        notes.append(f"no file matches {describe_glob(campaign)} in {campaign.raw_dir}")
    vanished = {f: e for f, e in entries.items() if not rows.has(f)}
    if rehearse and vanished:
        return None
    failures = plan.failures
    # reduced and landed in the order of their names (the order results are checked in
    # against each other), whichever worker ends first
    order = sorted(plan.todo)
    redone = SortedNames(order)
    account = Account()
    map_read = False  # a landing read the map under its lock (its rows are not kept)
    stop = StopFlag()
    shared = Shared()  # one copy of what the entries landed now repeat

    def land(results: list[FileOutcome]) -> None:
        """Fold ``results`` into the map (one locked atomic write) and the state; what
        is kept of them afterwards is their names and counts, not their rows."""
        nonlocal account, map_read
        part, read = _land(
            campaign, results, lambda in_map: _apply(
                campaign, results, rows, entries, failures, notes, vanished, in_map,
                redone, shared), entries, review)
        account = account.plus(part)
        map_read = map_read or read
        if rehearse:
            return  # its state is compared, never saved (see the end)
        with suppress(OutputError):  # said by the batch's last save, which meets it again
            entries.save()

    pending: dict[str, FileOutcome] = {}
    ready: list[FileOutcome] = []
    landed_files, at, last, cost = 0, 0, time.monotonic(), 0.0
    with _stop_on_signals(stop):
        for part in _execute(order, _job_of(rows), WorkerContext(campaign=campaign, plots=plots),
                             jobs, stop):
            pending.update((r.name, r) for r in part)
            while at < len(order) and order[at] in pending:
                ready.append(pending.pop(order[at]))
                at += 1
            if len(ready) >= LAND_EVERY_FILES or (
                    ready and time.monotonic() - last >= max(LAND_EVERY_S, 10 * cost)):
                started = time.monotonic()
                land(ready)
                landed_files += len(ready)
                ready, last = [], time.monotonic()
                cost = last - started
                if progress:
                    progress(done + landed_files, files)
        # what finished lands, in order; after a signal, what finished out of order too
        ready += [pending.pop(name) for name in sorted(pending)]
        if ready or not landed_files:
            land(ready)
            landed_files += len(ready)
            if progress:
                progress(done + landed_files, files)
        part = []  # the results landed are let go: what is kept is their names and counts
        ready = []
    if account.review is not None:
        notes.append(account.review.line(campaign.review))
    _forget_vanished(campaign, entries, rows, notes)
    appended = account.appended
    map_summary = "unchanged" if appended is None else appended.summary()

    duplicates = {**plan.duplicates, **account.duplicates}
    outcomes = {**plan.outcomes, **account.outcomes}
    this_batch = {n: REDUCED for n in account.reduced} | {n: SKIPPED for n in plan.skipped} | {
        n: FAILED for n in failures
    }
    # each output is tried even when one fails (a full disk may free up); those that
    # fail are in the report, beside every run's outcome
    problems: list[str] = []
    tables: tuple[str, str] | None = None
    if rehearse:
        # the tables it would write, as text; a re-run that would write the state is not
        # rehearsed (a clean batch leaves none to write)
        if entries.would_write():
            return None
        tables = (runs_csv_text(rows, entries, this_batch, failures),
                  failures_csv_text(failures))
    else:
        for write in (entries.save,
                      lambda: write_runs_csv(campaign, rows, entries, this_batch, failures),
                      lambda: write_failures_csv(campaign, failures)):
            try:
                write()
            except OutputError as exc:
                problems.append(str(exc))
    tests_in, unmatched, undescribed = manifest_ledger(rows, entries, manifest)
    runs_failed = plan.runs_failed + account.runs_failed
    test_tally = tally(outcomes, tests_in)
    report = BatchReport(
        interrupted=stop.name,
        map_landed=map_read,
        campaign=campaign.name,
        total=len(account.reduced) + len(plan.skipped) + runs_failed,
        reduced=account.reduced,
        skipped=plan.skipped,
        failures=sorted(failures.items()),
        groups_updated=len(account.groups),
        removed=0 if appended is None else len(appended.dropped_ids),
        map_path=campaign.map_path,
        map_summary=map_summary,
        output_dir=campaign.output_dir,
        notes=notes,
        flagged=account.flagged,
        duplicates=sorted(duplicates.items()),
        files=files,
        tests=test_tally.found,
        unmatched=unmatched,
        undescribed=undescribed,
        file_tally=tally(outcomes),
        test_tally=test_tally,
        runs_failed=runs_failed,
        conflicts=sorted((f, failures[f]) for f, o in outcomes.items() if o == CONFLICT),
        repeats=account.repeats,
        output_errors=problems,
    )
    # found nothing to do: its report is the one the next unchanged batch prints
    quiet = not plan.todo and not vanished and not problems and stop.name is None \
        and appended is None and not account.repeats and review is None
    # did its work and wrote every output: the next unchanged batch can be rehearsed
    clean = not problems and stop.name is None and campaign.review is None
    entries.close()  # opened again if read again
    return _Ended(report=report, quiet=quiet, clean=clean, entries=entries, rows=rows,
                  tables=tables)


@dataclass(frozen=True)
class _Plan:
    """What a batch does with each file: reduce it (``todo``: its name), skip its runs (unchanged
    since they were reduced: ``skipped`` run names), list it or its runs as failed without
    reading it (``failures``: name → reason), or as a duplicate (file → reason); the
    outcome of each file not reduced now (file → one of :data:`FILE_OUTCOMES`) and the
    runs of unchanged files that failed before (``runs_failed``)."""

    todo: list[str]
    skipped: list[str]
    failures: dict[str, str]
    duplicates: dict[str, str]
    outcomes: dict[str, str]
    runs_failed: int


def _run_ids(entry: FileState | None, statuses: tuple[str, ...] = (REDUCED,)) -> set[str]:
    """The measurement ids of a state entry's runs with one of ``statuses``."""
    return set() if entry is None else entry.run_ids(statuses)


def _plan(rows: Sequence[CampaignRow], missing_ids: set[str]) -> _Plan:
    """Sort the campaign's files into work, skips and known failures; a file with a run
    whose map row went missing (``missing_ids``) is reduced again."""
    todo: list[str] = []
    skipped: list[str] = []
    failures: dict[str, str] = {}
    duplicates: dict[str, str] = {}
    outcomes: dict[str, str] = {}
    runs_failed = 0
    for row in rows:
        previous = row.previous
        stored = _run_ids(previous, (REDUCED, DUPLICATE))
        if row.problem is not None:
            failures[row.file] = row.problem
            outcomes[row.file] = FAILED
        elif row.status == REDUCED and not stored & missing_ids:
            outcomes[row.file] = READ
            for run in row.runs:
                name = run.name or row.file
                if run.status == REDUCED:
                    skipped.append(name)
                else:  # unchanged and failed before: not retried, still listed
                    failures[name] = run.reason or "failed in an earlier batch"
                    runs_failed += 1
        elif row.status == DUPLICATE and not stored & missing_ids:
            duplicates[row.file] = (previous and previous.reason) or "a duplicate"
            outcomes[row.file] = DUPLICATE
        elif row.status == FAILED:
            # unchanged and failed before: do not retry, keep it listed
            failures[row.file] = row.reason or "failed in an earlier batch"
            outcomes[row.file] = CONFLICT if previous and previous.duplicate_of else FAILED
        else:
            todo.append(row.file)
    return _Plan(todo=todo, skipped=skipped, failures=failures, duplicates=duplicates,
                 outcomes=outcomes, runs_failed=runs_failed)


def _job_of(rows: CampaignTable) -> Callable[[str], Job]:
    """The job of a file of ``rows``, made when it is sent to a worker."""
    def job(file: str) -> Job:
        row = rows.row(file)
        return Job(file=row.file, path=row.where, sources=row.sources, hints=row.hints,
                   test_rows=row.test_rows, sha256=row.sha256)
    return job


#: chunks of jobs a batch's pool holds per worker at a time: enough to keep each busy,
#: few enough that the jobs waiting are not the campaign's
IN_FLIGHT_PER_WORKER = 4


def _execute(todo: Sequence[str], job_of: Callable[[str], Job], ctx: WorkerContext,
             jobs: int, stop: StopFlag) -> Iterator[list[FileOutcome]]:
    """Reduce the files ``todo`` (each sent as ``job_of(file)``), yielding the results
    as they finish: in this process, file by file, for one worker, else in a pool of
    ``jobs`` processes, chunk by chunk, a few chunks per worker sent at a time (their
    jobs made as they are sent). A crashed worker's files come back as transient
    failures. Once ``stop`` is raised (a signal), nothing new starts: the pool's workers
    are ended and the jobs not finished are not yielded (the next batch reduces them)."""
    if not todo:
        return
    workers = min(jobs, len(todo))
    if workers == 1:
        with fewer_gc_passes():
            for file in todo:
                if stop.raised:
                    return
                yield reduce_chunk([job_of(file)], ctx)
        return
    from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    size = chunk_size(len(todo), workers)
    starts = iter(range(0, len(todo), size))
    prepare_workers(ctx)
    pool = ProcessPoolExecutor(max_workers=workers, initializer=worker_init)
    futures: dict[Future[list[FileOutcome]], list[Job]] = {}
    unsent: list[list[FileOutcome]] = []  # chunks a broken pool refused

    def send() -> None:
        for start in starts:
            chunk = [job_of(file) for file in todo[start : start + size]]
            try:
                futures[pool.submit(reduce_chunk, chunk, ctx)] = chunk
            except (BrokenProcessPool, RuntimeError) as exc:
                # a worker died (e.g. killed for memory) and the pool takes no more: this
                # chunk and every one after it come back as transient failures
                unsent.append(crashed(chunk, exc))
                continue
            if len(futures) >= workers * IN_FLIGHT_PER_WORKER:
                return

    try:
        send()
        while (futures or unsent) and not stop.raised:
            while unsent:
                yield unsent.pop(0)
            if not futures:
                break
            finished, _ = wait(futures, timeout=0.5, return_when=FIRST_COMPLETED)
            for future in finished:
                chunk = futures.pop(future)
                try:
                    part = future.result()
                except Exception as exc:  # noqa: BLE001 - e.g. a worker killed (OOM)
                    part = crashed(chunk, exc)
                yield part
            if not stop.raised:
                send()
    finally:
        if futures:  # stopped: what did not finish is left for the next batch
            for process in list(getattr(pool, "_processes", {}).values()):
                with suppress(OSError):
                    process.terminate()
        pool.shutdown(wait=True, cancel_futures=True)


def _owners(rows: CampaignTable, redone: Container[str],
            vanished: Mapping[str, FileState], in_map: FilesByHash) -> ContentOwners:
    """The one duplicate check (:class:`ContentOwners`) for a batch: the contents the
    files of the state brought (those not redone now), then the map's own rows; a file
    that left the folder with a content the map holds is the one renamed."""
    known: dict[str, tuple[str, dict[str, dict[str, Any]]]] = {}
    for file, sha256, entry in rows.states():
        if file in redone or entry is None or entry.status != REDUCED or not sha256:
            continue
        runs = {r.entry.measurement_id: labels_of(r.entry.labels)
                for r in entry.runs if r.status == REDUCED and r.entry is not None}
        if runs:
            known.setdefault(sha256, (file, runs))
    renamed = {stored_file_name(f): (f, e.sha256) for f, e in vanished.items()
               if e.status == REDUCED}
    return ContentOwners(in_map, known, renamed)


def _apply(campaign: Campaign, results: Sequence[FileOutcome], rows: CampaignTable,
           entries: MutableMapping[str, FileState], failures: dict[str, str], notes: list[str],
           vanished: Mapping[str, FileState], in_map: FilesByHash,
           redone: Container[str] | None = None, shared: Shared | None = None
           ) -> tuple[Arrivals, Account]:
    """Fold the workers' results into the state ``entries`` and ``failures`` (in file
    order, both updated in place; plot and rename notes added to ``notes``), each file
    checked against the files before it and the map (``in_map``, read under its lock).
    ``redone``: every file the batch reduces again (default: those of ``results``); the
    state's account of them no longer holds; ``shared``: what the entries share
    (:class:`~tribopipe.campaign.state.Shared`)."""
    records: list[MapRow] = []
    old_ids: set[str] = set()
    reduced: list[str] = []
    flagged: list[tuple[str, str]] = []
    duplicates: dict[str, str] = {}
    outcomes: dict[str, str] = {}
    runs_failed = 0
    config_hash = campaign.settings.config_hash  # hashes the settings: once, not per run
    # the contents the campaign's files own, only when there are results to check (a
    # landing of none, as a re-run's, looks at no file's runs)
    owners = _owners(rows, redone if redone is not None else {r.name for r in results},
                     vanished, in_map) if results else ContentOwners({})
    for done in sorted(results, key=lambda r: r.name):
        row = rows.row(done.name)
        old = entries.get(row.file)
        if done.transient:
            # not the file's fault: listed now, retried next time (the state is left as is)
            outcomes[row.file] = FAILED
            for failed in done.failed:
                failures[failed.name] = failed.reason
            continue
        old_ids |= _run_ids(old)
        base = FileState(
            size=row.size, mtime_ns=row.mtime_ns, config_hash=config_hash,
            recipe=recipe_hash(campaign, row.merged, row.test_rows),
            sha256=done.file_hash or row.sha256 or _sha256_or_none(row.path),
            tests=tuple(Shared.text(t) for t in done.tests), status=REDUCED,
        )
        if done.error is not None:
            outcomes[row.file] = FAILED
            failures[row.file] = done.error.reason
            entries[row.file] = replace(base, status=FAILED, reason=done.error.reason)
            continue
        entry = {r.measurement_id: RunEntry.of(r, campaign.output_dir, shared)
                 for r in done.reduced}
        mine = {r.measurement_id: labels_of(r.record) for r in done.reduced}
        same, note = owners.check(done.name, done.file_hash, mine) if mine else (None, None)
        if note:
            notes.append(note)
        if same is not None:
            _drop_outputs(campaign, done, entries)
            runs = tuple(RunState.kept(DUPLICATE, replace(entry[r.measurement_id], trace=""))
                         for r in done.reduced)
            if same.conflict:
                outcomes[row.file] = CONFLICT
                failures[row.file] = same.message()
                entries[row.file] = replace(base, status=FAILED, reason=same.message(),
                                            duplicate_of=same.other)
            else:
                outcomes[row.file] = DUPLICATE
                duplicates[row.file] = same.message()
                entries[row.file] = replace(base, status=DUPLICATE, reason=same.message(),
                                            duplicate_of=same.other, runs=runs)
            continue
        owners.landed(done.name, done.file_hash, mine)
        outcomes[row.file] = READ
        runs_state: list[RunState] = []
        for run in done.runs:
            if isinstance(run, ReducedRun):
                assert run.record is not None  # labels_from always names pin and disc
                reduced.append(run.name)
                records.append(run.record)
                qc = flags_text(quality_flags(run.flags))  # synthetic: said once, not per run
                if qc:
                    flagged.append((run.name, qc))
                notes += [n for n in run.notes if n not in notes]
                runs_state.append(RunState.kept(REDUCED, entry[run.measurement_id]))
            else:
                failures[run.name] = run.reason
                runs_failed += 1
                runs_state.append(RunState.failed(run))
        entries[row.file] = replace(base, runs=tuple(runs_state))
    # the runs of files redone now that no file of the state still holds (none to look
    # for when nothing was redone: an unchanged re-run)
    alive = (entries.held_ids(old_ids) if isinstance(entries, BatchEntries)
             else set().union(*(_run_ids(e) for e in entries.values()))) if old_ids else set()
    return Arrivals(records, old_ids - alive), Account(
        reduced=reduced, flagged=flagged, duplicates=duplicates, outcomes=outcomes,
        runs_failed=runs_failed)


def _drop_outputs(campaign: Campaign, done: FileOutcome,
                  entries: Mapping[str, FileState]) -> None:
    """Remove the traces and plots a worker wrote for runs that do not land (their file
    is a duplicate or a conflict), unless a landed run has the same file (a file of the
    same name and content in another subfolder)."""
    layout = campaign.layout
    kept = {r.entry.trace for e in entries.values() for r in e.runs
            if r.status == REDUCED and r.entry is not None}
    for run in done.reduced:
        mid = run.measurement_id
        if run.trace is not None and run.trace.relative_to(
                campaign.output_dir).as_posix() in kept:
            continue
        for path in (layout.trace_path(done.name, mid), layout.trace_plot_path(done.name, mid)):
            try:
                path.unlink(missing_ok=True)
            except OSError:
                pass  # a stray picture is not worth failing the batch for


def _sha256_or_none(path: Path) -> str | None:
    """The file's SHA-256, or ``None`` when it cannot be read now (it is tried again)."""
    try:
        return file_sha256(path)
    except TribopipeError:
        return None


def _forget_vanished(campaign: Campaign, entries: MutableMapping[str, FileState],
                     rows: CampaignTable, notes: list[str]) -> None:
    """Files that vanished from the folder (no row of ``rows``) leave the state (their map
    rows stay)."""
    for gone in sorted(f for f in entries if not rows.has(f)):
        if entries[gone].status == REDUCED and _run_ids(entries[gone]):
            notes.append(f"{gone}: no longer in {campaign.raw_dir}; its map row(s) are kept")
        del entries[gone]


def _ids_missing_from_map(campaign: Campaign, state: CampaignState) -> tuple[set[str], bool]:
    """The measurement ids of runs the state calls reduced (or duplicates of) that are not
    in the map (so they must land again), and whether the map was read (and so validated)
    to tell.

    A map whose size and ``mtime_ns`` are those the last batch left is trusted without
    reading it; a missing map misses every run.
    """
    ids: set[str] = set()
    for e in state.entries.values():
        ids |= _run_ids(e, (REDUCED, DUPLICATE))
    if not ids:
        return set(), False
    if not campaign.map_path.exists():
        return ids, False
    if state.map is not None and state.map == MapStamp.of(campaign.map_path):
        return set(), False
    present = open_map(campaign.map_path, ["measurement_id"]).ids  # the ids only
    return ids - present, True


def _land(campaign: Campaign, results: Sequence[FileOutcome],
          apply: Callable[[FilesByHash], tuple[Arrivals, Account]],
          entries: Mapping[str, FileState], review: Review | None = None
          ) -> tuple[Account, bool]:
    """One landing of the batch: the results checked against the map and folded in by
    :func:`tribopipe.pipeline.landing.land_runs` (under the map's lock, in one atomic
    write: new records added or replaced, rows of runs whose raw file changed dropped,
    the review applied in the same write), the map locked and read only when a result
    brings or replaces runs or a review is given. Returns what this landing adds to the
    batch's account and whether it read (and so checked) the map under its lock; the
    map's rows are not kept."""
    touches = review is not None or any(r.reduced for r in results) or any(
        _run_ids(entries.get(r.name)) for r in results)
    if not touches:
        return apply({})[1], False
    brought: list[tuple[Arrivals, Account]] = []

    def choose(in_map: FilesByHash) -> Arrivals:
        brought.append(apply(in_map))
        return brought[0][0]

    # the map read once more, under its lock: inside land_runs (update_map_with)
    landed = land_runs(campaign.map_path, choose, review=review,
                       traces_dir=campaign.layout.traces_dir, replace=True,
                       arriving=arriving_ids(results))
    arrivals, account = brought[0]
    account = replace(account, repeats=list(landed.repeats), review=landed.review)
    if not (arrivals.records or arrivals.stale_ids or landed.appended.changed):
        return account, True
    return replace(account, groups=landed.groups, appended=landed.appended), True


class StopFlag:
    """Raised by SIGINT or SIGTERM during a batch: nothing new starts, what finished
    lands. ``name``: the signal's name once raised, else ``None``."""

    def __init__(self) -> None:
        self.name: str | None = None

    @property
    def raised(self) -> bool:
        """True once a signal asked the batch to stop."""
        return self.name is not None


@contextmanager
def _stop_on_signals(stop: StopFlag) -> Iterator[None]:
    """Let SIGINT (Ctrl-C) and SIGTERM raise ``stop`` instead of killing the batch while
    the body runs (in the main thread only: elsewhere signals cannot be caught)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, _frame: Any) -> None:
        stop.name = signal.Signals(signum).name

    old = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)


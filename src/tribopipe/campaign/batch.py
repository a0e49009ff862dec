"""The batch: every new or changed run of a campaign reduced in parallel, the map updated once.

Workers (one process per CPU) reduce chunks of files with :func:`tribopipe.pipeline.reduce_file`,
write each trace and trace plot at the layout's paths and return small picklable results;
the parent folds the records into the map in one atomic update, then writes the state,
``runs.csv`` and ``failures.csv``. A failing file is reported and skipped, never fatal.
"""

from __future__ import annotations

import contextlib
import gc
import math
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from ..errors import CampaignError, TribopipeError
from ..files import file_sha256
from ..frictionmap.records import RunLabels, make_record
from ..frictionmap.store import read_map, update_map
from ..numeric import finite_or_none
from ..pipeline import RunOutcome, plot_run, reduce_file, write_trace
from .metadata import labels_from, merge_metadata
from .outputs import _write_failures_csv, _write_runs_csv
from .patterns import LABEL_FIELDS, match_pattern
from .spec import Campaign
from .table import (
    FAILED,
    REDUCED,
    SKIPPED,
    STATE_VERSION,
    CampaignRow,
    RunEntry,
    campaign_table,
    load_state,
    recipe_hash,
    save_state,
)

ProgressCallback = Callable[[int, int], None]


@dataclass(frozen=True)
class _Job:
    file: str
    path: str
    sources: tuple[tuple[str, dict[str, Any]], ...]
    hints: tuple[str, ...]


@dataclass(frozen=True)
class _Context:
    campaign: Campaign
    plots: bool


@dataclass(frozen=True)
class ReducedRun:
    """A worker's result for a file it reduced: the map record, the file's SHA-256, what
    the state keeps of the run, and a note when its trace plot could not be drawn."""

    file: str
    record: dict[str, Any]
    sha256: str
    entry: RunEntry
    plot_note: str | None = None


@dataclass(frozen=True)
class FailedRun:
    """A worker's result for a file it could not reduce: the one-line reason; ``transient``
    when it was not the file's fault (a crashed worker, an internal error), so the state is
    left alone and the file is tried again next time."""

    file: str
    reason: str
    transient: bool = False


#: what a worker returns per file (small and picklable: never the trace)
RunResult = ReducedRun | FailedRun


def _reduce_one(job: _Job, ctx: _Context) -> ReducedRun:
    """Reduce one file in a worker; returns a small picklable result (never the trace)."""
    campaign = ctx.campaign
    merged = merge_metadata(job.file, job.sources, campaign)
    if campaign.use_export_names:
        outcome = _reduce_with_export_names(job, campaign, merged)
    else:
        labels = labels_from(job.file, merged, hints=job.hints)
        outcome = reduce_file(job.path, campaign.settings, labels, campaign.read_options,
                              tolerances=campaign.tolerances)
    result = outcome.result
    record = outcome.record
    trace = write_trace(campaign.layout, outcome)
    plot_note = _plot(campaign, outcome) if ctx.plots else None
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
    )
    return ReducedRun(file=job.file, record=record, sha256=outcome.file_hash, entry=entry,
                      plot_note=plot_note)


def _reduce_with_export_names(job: _Job, campaign: Campaign, merged: Mapping[str, Any]
                              ) -> RunOutcome:
    """:func:`tribopipe.pipeline.reduce_file` with the export's Test name as a third
    metadata source: the labels are only complete once the file has been read."""
    partial = RunLabels(**{k: merged.get(k) for k in LABEL_FIELDS})
    outcome = reduce_file(job.path, campaign.settings, partial, campaign.read_options)
    meta = outcome.measurement.meta
    sources = list(job.sources)
    hints = list(job.hints)
    found = match_pattern(campaign.export_pattern or "", meta.test) if meta.test else None
    if found is None:
        hints.append(f"export Test name {meta.test!r} does not match pattern "
                     f"{campaign.export_pattern!r}")
    else:
        sources.append((f"export Test name {meta.test!r}", found))
    labels = labels_from(job.file, merge_metadata(job.file, sources, campaign), hints=hints)
    record = make_record(result=outcome.result, labels=labels, meta=meta,
                         file_hash=outcome.file_hash, settings=campaign.settings,
                         tolerances=campaign.tolerances)
    return replace(outcome, labels=labels, record=record)


def _plot(campaign: Campaign, outcome: RunOutcome) -> str | None:
    """Draw a run's trace plot beside its trace; returns a note when it could not."""
    try:
        plot_run(campaign.layout, outcome)
    except Exception as exc:  # noqa: BLE001 - a picture must not cost the run its map row
        return f"{Path(outcome.path).name}: trace plot failed ({type(exc).__name__}: {exc})"
    return None


#: Cyclic-GC thresholds while reducing. Parsing an export allocates ~10⁵ short-lived
#: containers (cells, rows), which with the default gen-0 threshold (700) triggers hundreds
#: of collections per file that find nothing; measured: −20 % CPU per run.
GC_THRESHOLDS = (100_000, 50, 100)


def _worker_init() -> None:
    """Start a worker process (ours for its whole life): fewer garbage-collector passes."""
    gc.set_threshold(*GC_THRESHOLDS)


@contextlib.contextmanager
def _fewer_gc_passes() -> Iterator[None]:
    """:func:`_worker_init`'s tuning for an in-process batch, restored afterwards."""
    before = gc.get_threshold()
    gc.set_threshold(*GC_THRESHOLDS)
    try:
        yield
    finally:
        gc.set_threshold(*before)


def _reason(exc: TribopipeError, job: _Job) -> str:
    """The one-line reason of a failed run, starting with the file's campaign-relative
    name (readers name the absolute path, which is long and machine-specific)."""
    text = str(exc)
    if exc.path is None:
        return f"{job.file}: {text}"
    if exc.path == job.path and text.startswith(exc.path):
        return job.file + text[len(exc.path):]
    return text


def _reduce_chunk(jobs: Sequence[_Job], ctx: _Context) -> list[RunResult]:
    """Reduce a chunk of files; each failure is caught and returned with its reason."""
    out: list[RunResult] = []
    for job in jobs:
        try:
            out.append(_reduce_one(job, ctx))
        except TribopipeError as exc:
            out.append(FailedRun(file=job.file, reason=_reason(exc, job)))
        except OSError as exc:
            out.append(FailedRun(file=job.file,
                                 reason=f"{job.file}: cannot read: {exc.strerror or exc}"))
        except Exception as exc:  # noqa: BLE001 - one broken file must not stop a campaign
            out.append(FailedRun(file=job.file, transient=True,
                                 reason=f"{job.file}: internal error {type(exc).__name__}: "
                                        f"{exc} (please report with the file)"))
    return out


@dataclass(frozen=True)
class BatchReport:
    """What a batch did.

    ``reduced``/``skipped``: files reduced now / unchanged since the last batch;
    ``failures``: ``(file, reason)`` of every run that failed now or earlier and is
    unchanged; ``groups_updated``: condition groups (pin, disc, force, temperature) with a
    map row added, replaced or removed; ``removed``: map rows dropped because their raw
    file changed; ``map_summary``: the map's own account; ``notes``: things worth saying
    that are not failures (plots skipped, files gone from the folder); ``flagged``:
    ``(file, flags)`` of the runs reduced now that carry QC flags (";"-joined).
    """

    campaign: str
    total: int
    reduced: list[str]
    skipped: list[str]
    failures: list[tuple[str, str]]
    groups_updated: int
    removed: int
    map_path: Path
    map_summary: str
    output_dir: Path
    notes: list[str]
    flagged: list[tuple[str, str]] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when no file failed."""
        return not self.failures

    def summary(self) -> str:
        """One line: runs reduced, skipped, failed, groups updated."""
        text = (f"{self.campaign}: {self.total} run(s): {len(self.reduced)} reduced, "
                f"{len(self.skipped)} skipped (unchanged), {len(self.failures)} failed; "
                f"{self.groups_updated} condition group(s) updated")
        if self.removed:
            text += f"; {self.removed} stale map row(s) removed"
        return text


def _chunks(items: Sequence[Any], workers: int) -> list[list[Any]]:
    """``items`` cut into a few chunks per worker: small enough to balance, large enough to
    amortise pickling (the benchmark's parse-only pool uses the same cut)."""
    size = max(1, min(16, math.ceil(len(items) / (workers * 4))))
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
    """Reduce every new or changed run of a campaign, in parallel, and update its map once.

    Writes to ``campaign.output_dir``: ``traces/*.parquet``, ``plots/traces/*.png`` (when
    plots are on and available; only for runs reduced now), ``runs.csv`` (one row per
    file), ``failures.csv`` (``file,reason``) and the state file; appends the new records
    to ``campaign.map_path`` in one atomic update (replacing the rows of changed runs).
    ``progress(done, total)`` is called as runs finish. Failures of single runs never
    raise: they are in the report. Raises :class:`CampaignError` when another batch of
    the same campaign is running, :class:`MapError` when the map path holds a foreign file.
    """
    from filelock import FileLock, Timeout

    campaign.output_dir.mkdir(parents=True, exist_ok=True)
    lock = FileLock(str(campaign.layout.batch_lock), timeout=0)
    try:
        with lock:
            return _run_locked(campaign, jobs=jobs, plots=plots, progress=progress)
    except Timeout:
        raise CampaignError(
            "another batch of this campaign is running (its output folder is locked)",
            path=campaign.output_dir, hint="wait for it to finish",
        ) from None


def _run_locked(campaign: Campaign, *, jobs: int | None, plots: bool | None,
                progress: ProgressCallback | None) -> BatchReport:
    """:func:`run_campaign` while holding the output folder's batch lock."""
    jobs = default_jobs() if jobs is None else max(1, int(jobs))
    plots = campaign.plots if plots is None else plots
    state = load_state(campaign)
    entries: dict[str, Any] = dict(state.get("entries", {}))
    missing_ids, map_checked = _ids_missing_from_map(campaign, state)
    rows = campaign_table(campaign, state=state)
    plan = _plan(rows, missing_ids)
    total = len(rows)
    done = total - len(plan.todo)
    if progress:
        progress(done, total)

    if plan.todo and not map_checked and campaign.map_path.exists():
        read_map(campaign.map_path)  # refuse a foreign or corrupt map before any work
    results = _execute(plan.todo, _Context(campaign=campaign, plots=plots), jobs,
                       progress, done, total)

    notes: list[str] = []
    if not rows:
        notes.append(f"no file matches {campaign.glob!r} in {campaign.raw_dir}")
    by_file = {row.file: row for row in rows}
    failures = plan.failures
    landing = _apply(campaign, results, by_file, entries, failures, notes)
    _forget_vanished(campaign, entries, set(by_file), notes)

    map_summary = "unchanged"
    removed: set[str] = set()
    landed: set[str] = set()
    if landing.records or landing.stale_ids:
        map_summary, landed, removed = _update_map(campaign, landing.records, landing.stale_ids)
    groups = _groups_updated(state, landing.records, landed, removed)
    _save_state_with_map(campaign, entries)

    this_batch = {f: REDUCED for f in landing.reduced} | {f: SKIPPED for f in plan.skipped} | {
        f: FAILED for f in failures
    }
    _write_runs_csv(campaign, rows, entries, this_batch, failures)
    _write_failures_csv(campaign, failures)
    return BatchReport(
        campaign=campaign.name,
        total=total,
        reduced=landing.reduced,
        skipped=plan.skipped,
        failures=sorted(failures.items()),
        groups_updated=len(groups),
        removed=len(removed),
        map_path=campaign.map_path,
        map_summary=map_summary,
        output_dir=campaign.output_dir,
        notes=notes,
        flagged=landing.flagged,
    )


@dataclass(frozen=True)
class _Plan:
    """What a batch does with each row: reduce it (``todo``), skip it (unchanged since it
    was reduced), or list it as failed without reading it (``failures``: file → reason)."""

    todo: list[_Job]
    skipped: list[str]
    failures: dict[str, str]


def _plan(rows: Sequence[CampaignRow], missing_ids: set[str]) -> _Plan:
    """Sort the campaign's rows into work, skips and known failures; a reduced run whose
    map row went missing (``missing_ids``) is reduced again."""
    todo: list[_Job] = []
    skipped: list[str] = []
    failures: dict[str, str] = {}
    for row in rows:
        if row.problem is not None:
            failures[row.file] = row.problem
        elif row.status == REDUCED and (row.previous or {}).get("measurement_id") \
                not in missing_ids:
            skipped.append(row.file)
        elif row.status == FAILED:
            # unchanged and failed before: do not retry, keep it listed
            failures[row.file] = row.reason or "failed in an earlier batch"
        else:
            todo.append(_Job(file=row.file, path=str(row.path), sources=row.sources,
                             hints=row.hints))
    return _Plan(todo=todo, skipped=skipped, failures=failures)


def _execute(todo: list[_Job], ctx: _Context, jobs: int, progress: ProgressCallback | None,
             done: int, total: int) -> list[RunResult]:
    """Reduce the jobs: in this process for one worker, else in a pool of ``jobs``
    processes; ``progress(done, total)`` after every chunk. A crashed worker's files come
    back as transient failures."""
    results: list[RunResult] = []
    if not todo:
        return results
    workers = min(jobs, len(todo))
    chunks = _chunks(todo, workers)
    if workers == 1:
        with _fewer_gc_passes():
            for chunk in chunks:
                results.extend(_reduce_chunk(chunk, ctx))
                done += len(chunk)
                if progress:
                    progress(done, total)
        return results
    from concurrent.futures import ProcessPoolExecutor, as_completed

    with ProcessPoolExecutor(max_workers=workers, initializer=_worker_init) as pool:
        futures = {pool.submit(_reduce_chunk, chunk, ctx): chunk for chunk in chunks}
        for future in as_completed(futures):
            try:
                part = future.result()
            except Exception as exc:  # noqa: BLE001 - e.g. a worker killed (OOM)
                part = [FailedRun(file=job.file, transient=True,
                                  reason=f"{job.file}: worker process failed "
                                         f"({type(exc).__name__}: {exc}); run again")
                        for job in futures[future]]
            results.extend(part)
            done += len(part)
            if progress:
                progress(done, total)
    return results


@dataclass(frozen=True)
class _Landing:
    """What the workers' results bring to the map: the new records, the ids of rows to
    drop (their raw file changed or now fails), the files reduced and the flagged ones."""

    records: list[dict[str, Any]]
    stale_ids: set[str]
    reduced: list[str]
    flagged: list[tuple[str, str]]


def _apply(campaign: Campaign, results: Sequence[RunResult], by_file: Mapping[str, CampaignRow],
           entries: dict[str, Any], failures: dict[str, str], notes: list[str]) -> _Landing:
    """Fold the workers' results into the state ``entries`` and ``failures`` (in file
    order, both updated in place; plot notes added to ``notes``)."""
    records: list[dict[str, Any]] = []
    stale_ids: set[str] = set()
    reduced: list[str] = []
    flagged: list[tuple[str, str]] = []
    config_hash = campaign.settings.config_hash  # hashes the settings: once, not per run
    for res in sorted(results, key=lambda r: r.file):
        row = by_file[res.file]
        old = entries.get(row.file) or {}
        old_id = old.get("measurement_id") if old.get("status") == REDUCED else None
        base = {
            "size": row.size, "mtime_ns": row.mtime_ns, "config_hash": config_hash,
            "recipe": recipe_hash(campaign, row.merged),
        }
        if isinstance(res, ReducedRun):
            reduced.append(row.file)
            records.append(res.record)
            if res.record.get("flags"):
                flagged.append((row.file, res.record["flags"]))
            if old_id and old_id != res.entry.measurement_id:
                stale_ids.add(old_id)
            if res.plot_note and res.plot_note not in notes:
                notes.append(res.plot_note)
            entries[row.file] = {
                **base, "sha256": res.sha256, "status": REDUCED, **res.entry.as_dict(),
            }
        elif res.transient:
            # not the file's fault: listed now, retried next time (the state is left as is)
            failures[row.file] = res.reason
        else:
            failures[row.file] = res.reason
            if old_id:
                stale_ids.add(old_id)
            entries[row.file] = {
                **base, "sha256": row.sha256 or file_sha256(row.path), "status": FAILED,
                "reason": res.reason,
            }
    return _Landing(records=records, stale_ids=stale_ids, reduced=reduced, flagged=flagged)


def _forget_vanished(campaign: Campaign, entries: dict[str, Any], present: set[str],
                     notes: list[str]) -> None:
    """Files that vanished from the folder leave the state (their map rows stay)."""
    for gone in sorted(set(entries) - present):
        if entries[gone].get("status") == REDUCED:
            notes.append(f"{gone}: no longer in {campaign.raw_dir}; its map row is kept")
        del entries[gone]


def _groups_updated(state: Mapping[str, Any], records: Sequence[Mapping[str, Any]],
                    landed: set[str], removed: set[str]) -> set[tuple[Any, ...]]:
    """The condition groups with a map row added, replaced or removed by this batch."""
    old_groups = {
        _group_key(e.get("labels") or {}) for e in state.get("entries", {}).values()
        if e.get("measurement_id") in removed
    }
    return {
        _group_key(r) for r in records if r.get("measurement_id") in landed
    } | old_groups


def _save_state_with_map(campaign: Campaign, entries: Mapping[str, Any]) -> None:
    """Save the state with the map's size and ``mtime_ns`` as this batch leaves it (so the
    next batch trusts an untouched map without reading it)."""
    new_state: dict[str, Any] = {"version": STATE_VERSION, "campaign": campaign.name,
                                 "entries": dict(entries)}
    if campaign.map_path.exists():
        st = campaign.map_path.stat()
        new_state["map"] = {"size": st.st_size, "mtime_ns": st.st_mtime_ns}
    save_state(campaign, new_state)


def _ids_missing_from_map(campaign: Campaign, state: Mapping[str, Any]) -> tuple[set[str], bool]:
    """The measurement ids of runs the state calls reduced that are not in the map (so
    they must land again), and whether the map was read (and so validated) to tell.

    A map whose size and ``mtime_ns`` are those the last batch left is trusted without
    reading it; a missing map misses every run.
    """
    entries = state.get("entries", {})
    ids = {e.get("measurement_id") for e in entries.values() if e.get("status") == REDUCED}
    ids.discard(None)
    if not ids:
        return set(), False
    if not campaign.map_path.exists():
        return ids, False
    st = campaign.map_path.stat()
    seen = state.get("map") or {}
    if seen.get("size") == st.st_size and seen.get("mtime_ns") == st.st_mtime_ns:
        return set(), False
    present = set(read_map(campaign.map_path)["measurement_id"].astype(str))
    return ids - present, True


def _update_map(campaign: Campaign, records: list[dict[str, Any]],
                stale_ids: set[str]) -> tuple[str, set[str], set[str]]:
    """Fold the new records into the map and drop the rows of runs whose raw file changed
    (their measurement id changed with the content), under the map's lock, in one atomic
    write. Returns the map's summary line, the ids added or replaced, and the ids removed.
    """
    report = update_map(campaign.map_path, records, replace=True, drop_ids=sorted(stale_ids))
    return (report.summary(), set(report.added_ids) | set(report.replaced_ids),
            set(report.dropped_ids))


def _group_key(row: Mapping[str, Any]) -> tuple[Any, ...]:
    """The condition group of a record or label dict: pin, disc, nominal F [N], T [°C]."""
    return (row.get("pin"), row.get("disc"), row.get("normal_force_N"), row.get("temperature_C"))

"""One export from raw file to friction-map records: read → its runs → reduce → record.

An export holds one run per friction interval of every test and result
(:func:`tribopipe.reduction.intervals.friction_intervals`): a single test with a set-up and a
friction interval gives one run, a session export one run per test, a test with force or
speed steps one run per step. This is the orchestration used by ``tribopipe reduce`` and
by campaigns; readers and writers stay at the edges, :mod:`tribopipe.reduction.reduce` does the
physics.

:func:`read_runs` reads an export and cuts it into its runs (:class:`ExportRuns`: each
run's :class:`RunPlace` and friction interval, and each test/result that holds no
friction interval with the reason); :func:`reduce_run` reduces one of them to a
:class:`RunOutcome` with its map record; :func:`reduce_export` does both for a whole
file, a failing test or run standing alone. Per run, ``tribopipe reduce`` and the batch
workers then write what the output folder holds for it at the paths of
:mod:`tribopipe.layout`: :func:`write_trace`, :func:`write_summary` (``tribopipe reduce``
only) and :func:`plot_run`. :func:`reduce_files` is the whole ``tribopipe reduce`` over
several files: each file alone, a failing file or run reported in one line and skipped,
a file whose content an earlier one already had reported as its duplicate;
:func:`same_content` tells the batch and :func:`store_runs` the map about such files.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .errors import ReductionError, TribopipeError
from .escape import display_path
from .figures import TraceConditions, plot_trace
from .files import file_sha256, os_reason, write_text_atomic
from .frictionmap.duplicates import (
    SameContent,
    compare_labels,
    labels_of,
    map_files_by_hash,
)
from .frictionmap.records import RunLabels, Tolerances, make_record, measurement_id
from .frictionmap.store import AppendReport, append_records, read_map
from .layout import OutputLayout
from .measurement import interval_label
from .numeric import finite_json, finite_or_none
from .readers import read_export
from .reduction.intervals import friction_intervals
from .reduction.reduce import reduce_measurement

if TYPE_CHECKING:
    from .config import Settings
    from .measurement import Measurement
    from .reduction.reduce import ReductionResult


@dataclass(frozen=True)
class ReadOptions:
    """Forced reader settings; ``None`` means detect."""

    encoding: str | None = None
    delimiter: str | None = None
    decimal: str | None = None


@dataclass(frozen=True)
class RunPlace:
    """Where a run sits in its export: test, result and interval as the export names them
    (``None`` where it names none; ``interval`` is ``None`` for a test/result that holds
    no friction interval). ``occurrence`` counts runs of one export with the same three
    (two tests of one name): 1 for the first, which keeps the id it always had."""

    test: str | None = None
    result: str | None = None
    interval: int | None = None
    occurrence: int = 1

    @property
    def label(self) -> str:
        """``test / result / interval i`` (``#n`` added for a repeated place)."""
        text = interval_label(self.test, self.result, self.interval)
        return f"{text} #{self.occurrence}" if self.occurrence > 1 else text


def run_name(file: str, place: RunPlace, several: bool) -> str:
    """How a run is named in messages and tables: the file alone for an export with one
    run, ``file [test / result / interval i]`` for one with several."""
    label = place.label
    return f"{file} [{label}]" if several and label else file


@dataclass(frozen=True)
class ExportRuns:
    """An export read and cut into its runs, before any reduction.

    ``runs``: each friction interval (carrying its set-up's torque offset) with its place,
    in file order; ``problems``: each test/result that holds no friction interval, with the
    reason (its place has no interval); ``tests``: the Test names of the export in file
    order, one per test (``None`` for an export that names none).
    """

    path: str
    file_hash: str
    runs: tuple[tuple[RunPlace, Measurement], ...]
    problems: tuple[tuple[RunPlace, TribopipeError], ...] = ()
    tests: tuple[str | None, ...] = ()
    #: every place (runs and problems) in file order
    order: tuple[RunPlace, ...] = ()

    @property
    def several(self) -> bool:
        """True when the export holds more than one run or test (names must say which)."""
        return len(self.runs) + len(self.problems) > 1

    def name(self, place: RunPlace, file: str | None = None) -> str:
        """:func:`run_name` of a run of this export (``file`` defaults to the path)."""
        return run_name(self.path if file is None else file, place, self.several)


@dataclass(frozen=True)
class RunOutcome:
    """A reduced run with everything needed to store and explain it."""

    path: str
    measurement: Measurement
    result: ReductionResult
    labels: RunLabels
    file_hash: str
    config_hash: str
    measurement_id: str
    #: the friction-map row; ``None`` when pin or disc is unknown (the run cannot be stored)
    record: dict[str, Any] | None = field(repr=False)
    #: where the run sits in its export
    place: RunPlace = RunPlace()
    #: whether its export holds several runs or tests (then its name says which it is)
    several: bool = False

    @property
    def name(self) -> str:
        """:func:`run_name`: the file, with the run's place when its export holds several."""
        return run_name(self.path, self.place, self.several)


def read_runs(
    path: str | Path,
    read_options: ReadOptions | None = None,
    *,
    file_hash: str | None = None,
) -> ExportRuns:
    """Read an export and cut it into its runs: one per friction interval of every test
    and result (:func:`tribopipe.reduction.intervals.friction_intervals`).

    ``file_hash`` (SHA-256 of the file's bytes) is computed when not given. Raises
    :class:`tribopipe.errors.ReadError` when the file cannot be read as an export; a test
    without a friction interval is not an error here but one of ``problems``.
    """
    opts = read_options or ReadOptions()
    measurements = read_export(
        path, encoding=opts.encoding, delimiter=opts.delimiter, decimal=opts.decimal
    )
    found = friction_intervals(measurements)
    seen: dict[tuple[str | None, str | None, int | None], int] = {}

    def place_of(test: str | None, result: str | None, interval: int | None) -> RunPlace:
        key = (test, result, interval)
        seen[key] = seen.get(key, 0) + 1
        return RunPlace(test, result, interval, seen[key])

    runs: list[tuple[RunPlace, Measurement]] = []
    problems: list[tuple[RunPlace, TribopipeError]] = []
    tests: list[str | None] = []
    order: list[RunPlace] = []
    for group in found:
        if not tests or group.test != tests[-1]:
            tests.append(group.test)
        if group.problem is not None:
            problems.append((place_of(group.test, group.result, None), group.problem))
            order.append(problems[-1][0])
        for m in group.friction:
            runs.append((place_of(m.meta.test, m.meta.result, m.meta.interval), m))
            order.append(runs[-1][0])
    return ExportRuns(
        path=str(path),
        file_hash=file_hash or file_sha256(path),
        runs=tuple(runs),
        problems=tuple(problems),
        tests=tuple(tests),
        order=tuple(order),
    )


def reduce_run(
    export: ExportRuns,
    place: RunPlace,
    measurement: Measurement,
    settings: Settings,
    labels: RunLabels | None = None,
    *,
    tolerances: Tolerances | None = None,
) -> RunOutcome:
    """Reduce one run of an export (``place`` and ``measurement`` from ``export.runs``)
    and build its map record.

    The map record is built only when ``labels`` name pin and disc; ``tolerances``
    (default: the map's 10 %, 2 K) decide its off-nominal QC flags. Raises
    :class:`tribopipe.errors.TribopipeError` subclasses for every bad input.
    """
    labels = labels or RunLabels()
    result = reduce_measurement(measurement, settings.instrument, settings.reduction)
    record = None
    if labels.complete:
        record = make_record(
            result=result,
            labels=labels,
            meta=measurement.meta,
            file_hash=export.file_hash,
            settings=settings,
            tolerances=tolerances,
            occurrence=place.occurrence,
        )
    return RunOutcome(
        path=export.path,
        measurement=measurement,
        result=result,
        labels=labels,
        file_hash=export.file_hash,
        config_hash=settings.config_hash,
        measurement_id=measurement_id(export.file_hash, measurement.meta, place.occurrence),
        record=record,
        place=place,
        several=export.several,
    )


def reduce_file(
    path: str | Path,
    settings: Settings,
    labels: RunLabels | None = None,
    read_options: ReadOptions | None = None,
    *,
    tolerances: Tolerances | None = None,
) -> RunOutcome:
    """Read an export that holds one run, reduce it and build its map record
    (:func:`read_runs` + :func:`reduce_run`).

    Raises :class:`tribopipe.errors.TribopipeError` subclasses for every bad input: the
    reason of a test without a friction interval, and a :class:`ReductionError` for an
    export with several runs (use :func:`reduce_export`, which reduces them all).
    """
    export = read_runs(path, read_options)
    if export.several:
        raise ReductionError(
            f"holds {len(export.runs)} run(s) in {len(export.tests)} test(s), not one",
            path=str(path),
            hint="tribopipe.pipeline.reduce_export reduces every run of an export",
        )
    if export.problems:
        raise export.problems[0][1]
    place, measurement = export.runs[0]
    return reduce_run(export, place, measurement, settings, labels, tolerances=tolerances)


def trace_path(out_dir: str | Path | OutputLayout, outcome: RunOutcome) -> Path:
    """Where a run's reduced trace is written: ``<out_dir>/traces/<stem>_<id8>.parquet``
    (:meth:`tribopipe.layout.OutputLayout.trace_path`)."""
    return OutputLayout.of(out_dir).trace_path(outcome.path, outcome.measurement_id)


def write_trace(out_dir: str | Path | OutputLayout, outcome: RunOutcome) -> Path:
    """Write the reduced trace (Parquet, unit-suffixed columns) and return its path.

    The columns go to Arrow as plain arrays (no pandas metadata round trip), without
    Parquet's dictionary encoding (measured samples hardly repeat: trying it cost two
    thirds of the write, 4.4 ms of 10,000 rows against 1.6, for a file 6 % smaller): a
    campaign writes one trace per run, so this is on the hot path of a batch.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    target = trace_path(out_dir, outcome)
    target.parent.mkdir(parents=True, exist_ok=True)
    trace = outcome.result.trace
    table = pa.table({str(c): trace[c].to_numpy() for c in trace.columns})
    tmp = target.with_suffix(".parquet.tmp")
    try:
        pq.write_table(table, tmp, use_dictionary=False)
        tmp.replace(target)
    except OSError:
        tmp.unlink(missing_ok=True)  # a full disk leaves no half trace behind
        raise
    return target


def run_summary(outcome: RunOutcome) -> dict[str, Any]:
    """A JSON-ready summary of a reduced run: the numbers and the evidence behind them.

    Keys: ``file, run`` (the file, with the run's place when the export holds several),
    ``measurement_id, mu_s, mu_k``, their standard uncertainties ``u_mu_s, u_mu_k`` (GUM,
    k = 1; the budget is ``parameters["uncertainty"]``) and expanded uncertainties
    ``U95_mu_s, U95_mu_k`` (k = 2), ``pressure_kPa`` (measured mean, per pin),
    ``normal_force_N`` (measured mean, total), ``temperature_C`` (measured mean or
    ``None``), ``flags`` (list), the μ_S position (``mu_s_distance_mm``, ``mu_s_time_s``),
    the μ_K window (``mu_k_window_mm``, ``mu_k_window_s``), plateau std and drift, sliding
    speed, labels, where the run sits (``test, result, interval, occurrence``), method,
    parameters, file and config hashes. Strict JSON: a value that is not finite is
    ``None``; ``file`` is the path as printable text.
    """
    r = outcome.result
    meta = outcome.measurement.meta
    return finite_json({
        "file": display_path(outcome.path),
        "run": outcome.name,
        "measurement_id": outcome.measurement_id,
        "mu_s": float(r.mu_s),
        "mu_k": float(r.mu_k),
        "u_mu_s": finite_or_none(r.u_mu_s),
        "u_mu_k": finite_or_none(r.u_mu_k),
        "U95_mu_s": finite_or_none(2.0 * r.u_mu_s),
        "U95_mu_k": finite_or_none(2.0 * r.u_mu_k),
        "pressure_kPa": float(r.pressure_kPa),
        "normal_force_N": float(r.normal_force_mean_N),
        "temperature_C": finite_or_none(r.temperature_C),
        "flags": list(r.flags),
        "mu_s_distance_mm": float(r.mu_s_distance_mm),
        "mu_s_time_s": float(r.mu_s_time_s),
        "mu_k_window_mm": [float(v) for v in r.mu_k_window_mm],
        "mu_k_window_s": [float(v) for v in r.mu_k_window_s],
        "plateau_std": float(r.plateau_std),
        "plateau_drift_per_mm": float(r.plateau_drift_per_mm),
        "sliding_speed_mm_s": float(r.sliding_speed_mm_s),
        "sliding_distance_mm": float(r.sliding_distance_mm),
        "pin": outcome.labels.pin,
        "disc": outcome.labels.disc,
        "nominal_normal_force_N": outcome.labels.normal_force_N,
        "nominal_temperature_C": outcome.labels.temperature_C,
        "repeat": outcome.labels.repeat,
        "test": meta.test,
        "result": meta.result,
        "interval": meta.interval,
        "occurrence": outcome.place.occurrence,
        "method": r.method,
        "parameters": dict(r.parameters),
        "file_hash": outcome.file_hash,
        "config_hash": outcome.config_hash,
    })


def write_summary(out_dir: str | Path | OutputLayout, outcome: RunOutcome) -> Path:
    """Write :func:`run_summary` as JSON: ``<out_dir>/summaries/<stem>_<id8>.json``."""
    target = OutputLayout.of(out_dir).summary_path(outcome.path, outcome.measurement_id)
    text = json.dumps(run_summary(outcome), indent=2, default=str, allow_nan=False)
    return write_text_atomic(target, text)


def plot_run(out_dir: str | Path | OutputLayout, outcome: RunOutcome) -> Path:
    """Draw a run's trace plot (μ and normal force over sliding distance with the μ_S peak
    and the μ_K window, conditions and flags in the title;
    :func:`tribopipe.figures.plot_trace`) to ``<out_dir>/plots/traces/<stem>_<id8>.png``
    and return its path."""
    target = OutputLayout.of(out_dir).trace_plot_path(outcome.path, outcome.measurement_id)
    plot_trace(outcome.result, target, conditions=run_conditions(outcome))
    return target


def run_conditions(outcome: RunOutcome) -> TraceConditions:
    """What a run's trace plot names: its file (with the run's test and place when the
    export holds several, :func:`run_name`) and its nominal conditions (the labels; the
    nominal pressure from its map record when it has one)."""
    labels = outcome.labels
    record = outcome.record or {}
    return TraceConditions(
        source=run_name(Path(outcome.path).name, outcome.place, outcome.several),
        pin=labels.pin, disc=labels.disc,
        normal_force_N=finite_or_none(labels.normal_force_N),
        pressure_kPa=finite_or_none(record.get("pressure_kPa")),
        temperature_C=finite_or_none(labels.temperature_C), repeat=labels.repeat,
    )


@dataclass(frozen=True)
class RunResult:
    """What became of one run of an export (or of a test that holds none): the reduced
    run and the files written for it, or ``error``, one line naming the file and which
    run it is."""

    path: str
    name: str
    place: RunPlace
    outcome: RunOutcome | None = None
    error: str | None = None
    trace: Path | None = None
    summary: Path | None = None
    plot: Path | None = None

    @property
    def ok(self) -> bool:
        """True when the run was reduced (and its outputs written)."""
        return self.error is None


@dataclass(frozen=True)
class FileResult:
    """What :func:`reduce_export` or :func:`reduce_files` made of one file: a
    :class:`RunResult` per run (and per test without a friction interval), or ``error``
    for the file as a whole (unreadable, not an export). ``duplicate_of`` names an
    earlier file of the same call with the same content: this one was not reduced again.
    """

    path: str
    runs: tuple[RunResult, ...] = ()
    error: str | None = None
    file_hash: str | None = None
    tests: tuple[str | None, ...] = ()
    duplicate_of: str | None = None

    @property
    def ok(self) -> bool:
        """True when the file was read and every one of its runs reduced."""
        return self.error is None and all(r.ok for r in self.runs)

    @property
    def outcomes(self) -> list[RunOutcome]:
        """The reduced runs, in file order."""
        return [r.outcome for r in self.runs if r.outcome is not None]

    @property
    def errors(self) -> list[str]:
        """Every one-line error: the file's, or its failed runs'."""
        if self.error is not None:
            return [self.error]
        return [r.error for r in self.runs if r.error is not None]


def _message(exc: BaseException, path: str | Path) -> str:
    """One line naming the file once: the error's text, prefixed with the path when the
    error does not name it."""
    shown = display_path(path)
    if isinstance(exc, OSError):
        return f"{shown}: {os_reason(exc)}"
    message = str(exc)
    return message if shown in message else f"{shown}: {message}"


def reduce_export(
    path: str | Path,
    settings: Settings,
    labels: RunLabels | None = None,
    read_options: ReadOptions | None = None,
    *,
    tolerances: Tolerances | None = None,
    file_hash: str | None = None,
    each_run: Callable[[RunOutcome], Mapping[str, Path | None]] | None = None,
) -> FileResult:
    """Reduce every run of an export (:func:`read_runs`, :func:`reduce_run` per run),
    each labelled ``labels``.

    A test without a friction interval and a run that cannot be reduced each give a
    :class:`RunResult` with its one-line error and the other runs still go through; a
    file that cannot be read gives a :class:`FileResult` with ``error``. Nothing raises
    for a bad file. ``each_run(outcome)`` writes a reduced run's outputs and returns
    their paths (``trace``, ``summary``, ``plot``); when it fails, the run fails.
    """
    try:
        export = read_runs(path, read_options, file_hash=file_hash)
    except (TribopipeError, OSError) as exc:
        return FileResult(path=str(path), error=_message(exc, path), file_hash=file_hash)
    results: list[tuple[int, RunResult]] = []
    for place, problem in export.problems:
        name = export.name(place)
        error = _message(problem, path)
        results.append((0, RunResult(path=str(path), name=name, place=place, error=error)))
    for k, (place, measurement) in enumerate(export.runs, start=1):
        name = export.name(place)
        try:
            outcome = reduce_run(export, place, measurement, settings, labels,
                                 tolerances=tolerances)
            written = dict(each_run(outcome)) if each_run is not None else {}
        except (TribopipeError, OSError) as exc:
            results.append((k, RunResult(path=str(path), name=name, place=place,
                                         error=_message(exc, path))))
            continue
        results.append((k, RunResult(path=str(path), name=name, place=place, outcome=outcome,
                                     **written)))
    position = {place: i for i, place in enumerate(export.order)}
    ordered = tuple(sorted((r for _, r in results), key=lambda r: position[r.place]))
    return FileResult(path=str(path), runs=ordered, file_hash=export.file_hash,
                      tests=export.tests)


def reduce_files(
    paths: Sequence[str | Path],
    settings: Settings,
    labels: RunLabels | None = None,
    read_options: ReadOptions | None = None,
    *,
    out_dir: str | Path | OutputLayout,
    summaries: bool = True,
    plots: bool = False,
    on_file: Callable[[FileResult], None] | None = None,
) -> list[FileResult]:
    """Reduce every run of each file alone (:func:`reduce_export`) and write each run's
    trace, its summary (``summaries``) and its trace plot (``plots``) below ``out_dir``.

    A file that cannot be read, a test without a friction interval and a run that cannot
    be reduced or written each give their one-line error (naming the file once) and the
    others still go through; nothing raises for a bad file. A file whose content (SHA-256)
    an earlier file of ``paths`` already had is not reduced again: its result names that
    file in ``duplicate_of``. ``on_file`` is called with each result as it is done (in
    the order of ``paths``), e.g. to print progress.
    """
    layout = OutputLayout.of(out_dir)

    def write(outcome: RunOutcome) -> dict[str, Path | None]:
        return {
            "trace": write_trace(layout, outcome),
            "summary": write_summary(layout, outcome) if summaries else None,
            "plot": plot_run(layout, outcome) if plots else None,
        }

    results: list[FileResult] = []
    first_with: dict[str, str] = {}
    for path in paths:
        try:
            sha: str | None = file_sha256(path)  # stat first: a FIFO is never opened
        except (OSError, TribopipeError):
            sha = None  # the reader says what is wrong with it, in its words
        if sha is not None and sha in first_with:
            result = FileResult(path=str(path), file_hash=sha, duplicate_of=first_with[sha])
        else:
            if sha is not None:
                first_with[sha] = str(path)
            result = reduce_export(path, settings, labels, read_options, file_hash=sha,
                                   each_run=write)
        if on_file is not None:
            on_file(result)
        results.append(result)
    return results


# ------------------------------------------------------------------ the same content twice


@dataclass(frozen=True)
class StoreReport:
    """What :func:`store_runs` did: the map's :class:`AppendReport` and the runs of files
    the map already held under another name (duplicates left out, conflicts refused)."""

    appended: AppendReport
    same: tuple[SameContent, ...] = ()

    @property
    def conflicts(self) -> tuple[SameContent, ...]:
        """The refused files (labels differ from the map's)."""
        return tuple(s for s in self.same if s.conflict)


def store_runs(map_path: str | Path, outcomes: Sequence[RunOutcome], *,
               replace: bool = False) -> StoreReport:
    """Append the records of reduced runs to the map (:func:`append_records`), after
    checking each file against the map: a file whose runs the map already holds under
    another file name is a duplicate (its records are left out, the map keeps the first
    name) or, where the labels differ, a conflict (refused, unless ``replace``)."""
    records = [o for o in outcomes if o.record is not None]
    by_hash = map_files_by_hash(read_map(map_path)) if Path(map_path).exists() else {}
    same: list[SameContent] = []
    keep: list[dict[str, Any]] = []
    checked: dict[str, SameContent | None] = {}
    for o in records:
        name = Path(o.path).name
        if o.path not in checked:
            others = {src: ids for src, ids in by_hash.get(o.file_hash, {}).items()
                      if src != name}
            found = None
            if others:
                other, old = sorted(others.items())[0]
                new = {r.measurement_id: labels_of(r.record)
                       for r in records if r.path == o.path}
                found = compare_labels(o.path, other, new, old)
                same.append(found)
            checked[o.path] = found
        found = checked[o.path]
        if found is None or (found.conflict and replace):
            keep.append(o.record)
    return StoreReport(appended=append_records(map_path, keep, replace=replace),
                       same=tuple(same))

"""One export from raw file to friction-map records: read → its runs → reduce → record.

An export holds one run per friction interval of every test and result
(:func:`tribopipe.reduction.intervals.friction_intervals`): a single test with a set-up and a
friction interval gives one run, a session export one run per test, a test with force or
speed steps one run per step. This is the orchestration used by ``tribopipe reduce`` and
by campaigns; readers and writers stay at the edges, :mod:`tribopipe.reduction.reduce` does the
physics.

:func:`reduce_export` is the one route from an export to its runs, for ``tribopipe
reduce`` (:func:`reduce_files`) and the batch workers alike: it reads the export once
(:func:`read_runs`: each run's :class:`RunPlace` and friction interval, and each
test/result that holds none with the reason), labels each run, reduces it
(:func:`reduce_run`: the in-memory :class:`RunOutcome`, its QC flags decided once by
:func:`tribopipe.labels.decide_run`), writes its outputs at the paths of
:mod:`tribopipe.layout` (:func:`write_trace`, :func:`write_summary`, :func:`plot_run`) and
returns one :class:`FileOutcome`: a :class:`ReducedRun` or :class:`FailedRun` per run,
each failure with its one-line reason, or the file's error. :func:`store_runs` checks
the reduced files against the map and appends them, under the map's lock.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .errors import (
    Failure,
    NotFrictionTestError,
    OutputError,
    ReductionError,
    TribopipeError,
)
from .escape import display_path, printable
from .figures import TraceConditions, plot_trace
from .files import file_sha256, os_reason, write_text_atomic
from .frictionmap.duplicates import (
    CHECK_COLUMNS,
    GROUP_COLUMNS,
    LABEL_COLUMNS,
    ContentOwners,
    SameContent,
    labels_of,
    map_files_by_hash,
    repeat_clashes,
)
from .frictionmap.records import make_record, measurement_id
from .frictionmap.schema import MapRow
from .frictionmap.store import AppendReport, update_map_with
from .labels import (
    LabelCheck,
    RunLabels,
    RunVerdict,
    Tolerances,
    Undescribed,
    decide_run,
)
from .layout import OutputLayout
from .measurement import interval_label, run_name
from .numeric import finite_json, finite_or_nan, finite_or_none
from .readers import read_export
from .reduction.intervals import friction_intervals
from .reduction.manual import TRACE_META_KEY
from .reduction.reduce import reduce_measurement
from .review import landing_records

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
        return interval_label(self.test, self.result, self.interval, self.occurrence)

    def run_name(self, file: str, several: bool) -> str:
        """The run's name (:func:`tribopipe.measurement.run_name`): the file alone for an
        export with one run, ``file [test / result / interval i]`` for one with several."""
        if not several:
            return file
        return run_name(file, self.test, self.result, self.interval, self.occurrence)


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
        """The name of a run of this export (``file`` defaults to the path)."""
        return place.run_name(self.path if file is None else file, self.several)


@dataclass(frozen=True)
class RunOutcome:
    """A reduced run with everything needed to store and explain it."""

    path: str
    measurement: Measurement
    result: ReductionResult
    file_hash: str
    config_hash: str
    measurement_id: str
    #: its nominal force and flags, decided once (:func:`tribopipe.labels.decide_run`):
    #: what every output of the run shows
    verdict: RunVerdict
    #: the friction-map row; ``None`` when pin or disc is unknown (the run cannot be stored)
    record: MapRow | None = field(repr=False)
    #: where the run sits in its export
    place: RunPlace = RunPlace()
    #: whether its export holds several runs or tests (then its name says which it is)
    several: bool = False

    @property
    def labels(self) -> RunLabels:
        """The labels the run was reduced with."""
        return self.verdict.labels

    @property
    def name(self) -> str:
        """The run's name: the file, with its place when its export holds several."""
        return self.place.run_name(self.path, self.several)


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
    if not runs and problems and all(isinstance(e, NotFrictionTestError) for _, e in problems):
        # said once for the file
        raise _not_friction(path, [e for _, e in problems if isinstance(e, NotFrictionTestError)])
    return ExportRuns(
        path=str(path),
        file_hash=file_hash or file_sha256(path),
        runs=tuple(runs),
        problems=tuple(problems),
        tests=tuple(tests),
        order=tuple(order),
    )


def _not_friction(path: str | Path,
                  problems: Sequence[NotFrictionTestError]) -> NotFrictionTestError:
    """One refusal for an export none of whose tests is pin-on-disc sliding, naming what
    its tests look like (an oscillation, a flow curve ...)."""
    kinds = list(dict.fromkeys(p.looks_like or p.problem for p in problems))
    tests = (f"its {len(problems)} tests (or results) look like" if len(problems) > 1
             else "it looks like")
    return NotFrictionTestError(f"not a pin-on-disc friction test: {tests} "
                                + "; ".join(kinds), looks_like="; ".join(kinds), path=path,
                                hint=problems[0].hint)


def reduce_run(
    export: ExportRuns,
    place: RunPlace,
    measurement: Measurement,
    settings: Settings,
    labels: RunLabels | None = None,
    *,
    tolerances: Tolerances | None = None,
    extra_flags: tuple[str, ...] = (),
    check: LabelCheck | None = None,
) -> RunOutcome:
    """Reduce one run of an export (``place`` and ``measurement`` from ``export.runs``)
    and build its map record.

    The map record is built only when ``labels`` name pin and disc; ``tolerances``
    (default: the map's 10 %, 2 K) decide its off-nominal QC flags; ``extra_flags``
    (e.g. ``synthetic``) join them (:func:`tribopipe.labels.decide_run`). The labels
    are checked against the export first (``check``, default :class:`LabelCheck`: the
    measured force within 25 % of the label, no other material in the Test name or
    sample field), a :class:`~tribopipe.labels.LabelMismatch` otherwise. Raises
    :class:`tribopipe.errors.TribopipeError` subclasses for every bad input.
    """
    labels = labels or RunLabels()
    result = reduce_measurement(measurement, settings.instrument, settings.reduction)
    (check or LabelCheck()).check(labels, finite_or_none(result.normal_force_mean_N),
                                  (("Test name", measurement.meta.test),
                                   ("sample", measurement.meta.sample)))
    verdict = decide_run(labels, result.flags, finite_or_nan(result.normal_force_mean_N),
                         finite_or_nan(result.temperature_C), tolerances, extra_flags,
                         speed_set_point_rpm=result.speed_set_point_rpm,
                         sliding_speed_measured_mm_s=result.sliding_speed_mm_s,
                         instrument=settings.instrument)
    record = None
    if labels.complete:
        record = make_record(
            result=result,
            verdict=verdict,
            meta=measurement.meta,
            file_hash=export.file_hash,
            settings=settings,
            occurrence=place.occurrence,
        )
    return RunOutcome(
        path=export.path,
        measurement=measurement,
        result=result,
        file_hash=export.file_hash,
        config_hash=settings.config_hash,
        measurement_id=measurement_id(export.file_hash, measurement.meta, place.occurrence),
        record=record,
        place=place,
        several=export.several,
        verdict=verdict,
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
    # what a reviewer's window is read with (tribopipe.reduction.manual); a run read over
    # cycles (reciprocating) has no window terms, so a review refuses a window over it
    terms = outcome.result.parameters.trace_terms()
    if terms is not None:
        table = table.replace_schema_metadata({TRACE_META_KEY: terms.to_json()})
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
    speed (measured; the nominal ``nominal_speed_mm_s`` and the interval's
    ``speed_set_point_rpm``), labels, where the run sits (``test, result, interval,
    occurrence``), method, parameters, file and config hashes. Strict JSON: a value that
    is not finite is ``None``; ``file`` is the path as printable text.
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
        "flags": list(outcome.verdict.flags),
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
        "nominal_speed_mm_s": outcome.verdict.nominal_speed_mm_s,
        "speed_set_point_rpm": finite_or_none(r.speed_set_point_rpm),
        "repeat": outcome.labels.repeat,
        "test": meta.test,
        "result": meta.result,
        "interval": meta.interval,
        "occurrence": outcome.place.occurrence,
        "method": r.method,
        "parameters": r.parameters.to_json(),
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
    plot_trace(outcome.result, target, conditions=run_conditions(outcome),
               flags=outcome.verdict.flags)
    return target


def run_conditions(outcome: RunOutcome) -> TraceConditions:
    """What a run's trace plot names: its file (with the run's test and place when the
    export holds several, :meth:`RunPlace.run_name`) and its nominal conditions (the labels; the
    nominal pressure from its map record when it has one)."""
    labels = outcome.labels
    return TraceConditions(
        source=outcome.place.run_name(Path(outcome.path).name, outcome.several),
        pin=labels.pin, disc=labels.disc,
        normal_force_N=finite_or_none(labels.normal_force_N),
        pressure_kPa=None if outcome.record is None else outcome.record.pressure_kPa,
        temperature_C=finite_or_none(labels.temperature_C), repeat=labels.repeat,
    )


# ------------------------------------------------------------------ one route, one outcome


#: the labels of each run of an export: ``labels_for(export, place, name)`` (``name`` is
#: the run's name in messages); raises :class:`~tribopipe.errors.TribopipeError` when the
#: run cannot be labelled (:class:`~tribopipe.labels.Undescribed` when nothing describes it)
LabelsFor = Callable[[ExportRuns, RunPlace, str], RunLabels]


@dataclass(frozen=True)
class RunOutputs:
    """What :func:`reduce_export` writes for each reduced run below ``layout``: always its
    trace (Parquet), its JSON summary when ``summary``, its trace plot when ``plot``."""

    layout: OutputLayout
    summary: bool = False
    plot: bool = False


@dataclass(frozen=True)
class ReducedRun:
    """A run reduced (small and picklable: never its trace).

    ``name``: the run's name in messages (the file as the caller names it, with the run's
    place when the export holds several); ``verdict``: its labels, nominal force and flags
    (:func:`tribopipe.labels.decide_run`); ``summary``: :func:`run_summary`; ``record``:
    its friction-map row (``None`` when pin or disc is unknown); the paths of the outputs
    written; ``notes``: each output that could not be written (the trace plot), naming it
    and why: the run is still reduced and stored.
    """

    name: str
    place: RunPlace
    verdict: RunVerdict
    measurement_id: str
    summary: dict[str, Any] = field(repr=False)
    record: MapRow | None = field(repr=False)
    trace: Path | None = None
    summary_file: Path | None = None
    plot: Path | None = None
    notes: tuple[str, ...] = ()

    @property
    def labels(self) -> RunLabels:
        """The labels the run was reduced with."""
        return self.verdict.labels

    @property
    def flags(self) -> tuple[str, ...]:
        """The run's QC flags, as every output shows them."""
        return self.verdict.flags


@dataclass(frozen=True)
class FailedRun:
    """A run (or a test without a friction interval; ``place`` ``None``: the whole file)
    that could not be reduced, labelled or written: its ``failure`` as fields (the file
    named as the caller names it, or the output, the problem, the hint), its one-line
    :attr:`reason` formatted from them. ``transient`` when it was not the file's fault (a
    crashed worker, an internal error: tried again next time); ``undescribed`` when no
    metadata source described it (:class:`~tribopipe.labels.Undescribed`)."""

    name: str
    failure: Failure
    place: RunPlace | None = None
    transient: bool = False
    undescribed: bool = False

    @property
    def reason(self) -> str:
        """The failure in one line (:meth:`~tribopipe.errors.Failure.text`)."""
        return self.failure.text()


@dataclass(frozen=True)
class FileOutcome:
    """What :func:`reduce_export` made of one file: a :class:`ReducedRun` or
    :class:`FailedRun` per run (and per test without a friction interval), in file order;
    or ``error``, the file as a whole (unreadable, not an export). ``name`` is the file as
    the caller names it in messages; ``duplicate_of`` names an earlier file of the same
    call with the same content: this one's runs were skipped (reduced once)."""

    path: str
    name: str
    file_hash: str | None = None
    tests: tuple[str | None, ...] = ()
    several: bool = False
    runs: tuple[ReducedRun | FailedRun, ...] = ()
    error: FailedRun | None = None
    duplicate_of: str | None = None

    @property
    def reduced(self) -> list[ReducedRun]:
        """The runs reduced, in file order."""
        return [r for r in self.runs if isinstance(r, ReducedRun)]

    @property
    def failed(self) -> list[FailedRun]:
        """The file's failure, or its runs that failed, in file order."""
        if self.error is not None:
            return [self.error]
        return [r for r in self.runs if isinstance(r, FailedRun)]

    @property
    def ok(self) -> bool:
        """True when the file was read and every one of its runs reduced."""
        return not self.failed

    @property
    def transient(self) -> bool:
        """True when the file or a run failed for a reason that is not the file's."""
        return any(r.transient for r in self.failed)


def failure_of(exc: BaseException, path: str | Path, name: str,
               run: str | None = None) -> Failure:
    """The :class:`~tribopipe.errors.Failure` of an error met reading or reducing the
    export at ``path``, naming the file as the caller names it (``name``; a reader names
    the path it was given, which may be long and machine-specific): an error naming the
    export names ``name`` instead, one naming no file names the run (``run``, default
    ``name``), one naming another file (a manifest, an output) keeps it."""
    if isinstance(exc, OSError):
        return Failure(os_reason(exc), path=run or name)
    if not isinstance(exc, TribopipeError):
        return Failure(str(exc), path=run or name)
    failure = exc.failure
    if failure.path is None:
        return replace(failure, path=run or name)
    if failure.path == os.fsdecode(path):
        return replace(failure, path=name)
    return failure


def _written(what: str, target: Path, write: Callable[[], Path]) -> Path:
    """Run ``write`` (which writes ``target``); an OS error becomes an
    :class:`OutputError` naming the output (not the export it came from)."""
    try:
        return write()
    except OSError as exc:
        raise OutputError(f"cannot write its {what} {display_path(target)}: "
                          f"{os_reason(exc)}") from None


def _reduced(outcome: RunOutcome, name: str, outputs: RunOutputs | None) -> ReducedRun:
    """A reduced run with its outputs written: the trace and summary must be (else
    :class:`OutputError`), a trace plot that cannot be drawn is a note."""
    paths: dict[str, Path | None] = {}
    notes: list[str] = []
    summary = run_summary(outcome)
    if outputs is not None:
        layout, mid = outputs.layout, outcome.measurement_id
        paths["trace"] = _written("trace", layout.trace_path(outcome.path, mid),
                                  lambda: write_trace(layout, outcome))
        if outputs.summary:
            paths["summary_file"] = _written(
                "summary", layout.summary_path(outcome.path, mid),
                lambda: write_summary(layout, outcome))
        if outputs.plot:
            target = layout.trace_plot_path(outcome.path, mid)
            try:
                paths["plot"] = plot_run(layout, outcome)
            except Exception as exc:  # noqa: BLE001 - a picture must not cost the run its map row
                notes.append(printable(f"{name}: trace plot {display_path(target)} not drawn "
                                       f"({type(exc).__name__}: {exc})"))
    return ReducedRun(name=name, place=outcome.place, verdict=outcome.verdict,
                      measurement_id=outcome.measurement_id, summary=summary,
                      record=outcome.record, notes=tuple(notes), **paths)


def reduce_export(
    path: str | Path,
    settings: Settings,
    labels: RunLabels | LabelsFor | None = None,
    read_options: ReadOptions | None = None,
    *,
    tolerances: Tolerances | None = None,
    extra_flags: tuple[str, ...] = (),
    file_hash: str | None = None,
    outputs: RunOutputs | None = None,
    name: str | None = None,
    check: LabelCheck | None = None,
) -> FileOutcome:
    """The one route from an export to its runs, for ``tribopipe reduce`` and the batch:
    read it once (:func:`read_runs`), label each run (``labels``, the same for every run,
    or a :data:`LabelsFor`), reduce it (:func:`reduce_run`: its flags decided once) and
    write its outputs (``outputs``), and return one :class:`FileOutcome`.

    ``name`` is the file as messages name it (default: ``path``). A test without a
    friction interval, a run that cannot be labelled, reduced or written each give a
    :class:`FailedRun` with its one-line reason and the other runs still go through; a
    file that cannot be read gives ``error``. Nothing raises for a bad file.
    """
    shown = str(path) if name is None else name
    try:
        export = read_runs(path, read_options, file_hash=file_hash)
    except (TribopipeError, OSError) as exc:
        return FileOutcome(path=str(path), name=shown, file_hash=file_hash,
                           error=FailedRun(name=shown, failure=failure_of(exc, path, shown)))
    problems = dict(export.problems)
    measurements = dict(export.runs)
    runs: list[ReducedRun | FailedRun] = []
    for place in export.order:
        run = place.run_name(shown, export.several)
        if place in problems:
            runs.append(FailedRun(name=run, place=place,
                                  failure=failure_of(problems[place], path, shown, run)))
            continue
        try:
            given = labels(export, place, run) if callable(labels) else labels
            outcome = reduce_run(export, place, measurements[place], settings, given,
                                 tolerances=tolerances, extra_flags=extra_flags, check=check)
            runs.append(_reduced(outcome, run, outputs))
        except (TribopipeError, OSError) as exc:
            # an output that could not be written is not the export's fault: tried again
            runs.append(FailedRun(name=run, place=place,
                                  failure=failure_of(exc, path, shown, run),
                                  transient=isinstance(exc, OutputError),
                                  undescribed=isinstance(exc, Undescribed)))
    return FileOutcome(path=str(path), name=shown, file_hash=export.file_hash,
                       tests=export.tests, several=export.several, runs=tuple(runs))


def reduce_files(
    paths: Sequence[str | Path],
    settings: Settings,
    labels: RunLabels | None = None,
    read_options: ReadOptions | None = None,
    *,
    out_dir: str | Path | OutputLayout | None,
    summaries: bool = True,
    plots: bool = False,
    on_file: Callable[[FileOutcome], None] | None = None,
    check: LabelCheck | None = None,
) -> list[FileOutcome]:
    """``tribopipe reduce`` over several files: each file alone through
    :func:`reduce_export`, writing each run's trace, its summary (``summaries``) and its
    trace plot (``plots``) below ``out_dir`` (nothing when it is ``None``).

    A file whose content (SHA-256) an earlier file of ``paths`` already had is not
    reduced again: its outcome names that file in ``duplicate_of``. ``on_file`` is
    called with each outcome as it is done (in the order of ``paths``), e.g. to print
    progress. Nothing raises for a bad file.
    """
    outputs = (None if out_dir is None else
               RunOutputs(OutputLayout.of(out_dir), summary=summaries, plot=plots))
    results: list[FileOutcome] = []
    first_with: dict[str, str] = {}
    for path in paths:
        try:
            sha: str | None = file_sha256(path)  # stat first: a FIFO is never opened
        except (OSError, TribopipeError):
            sha = None  # the reader says what is wrong with it, in its words
        if sha is not None and sha in first_with:
            result = FileOutcome(path=str(path), name=str(path), file_hash=sha,
                                 duplicate_of=first_with[sha])
        else:
            if sha is not None:
                first_with[sha] = str(path)
            result = reduce_export(path, settings, labels, read_options, file_hash=sha,
                                   outputs=outputs, check=check)
        if on_file is not None:
            on_file(result)
        results.append(result)
    return results


# ------------------------------------------------------------------ the same content twice


@dataclass(frozen=True)
class StoreReport:
    """What :func:`store_runs` did: the map's :class:`AppendReport`, the runs of files
    the map already held under another name (duplicates left out, conflicts refused) and
    the repeat numbers now used twice in one condition (:func:`repeat_clashes`)."""

    appended: AppendReport
    same: tuple[SameContent, ...] = ()
    repeats: tuple[str, ...] = ()

    @property
    def relabelled(self) -> tuple[str, ...]:
        """The runs the map kept with other labels than this reduction's (a relabel
        refused without ``replace``): their measurement ids."""
        appended = self.appended
        return tuple(i for i in appended.conflicting_ids
                     if set(appended.differences.get(i, ())) & set(LABEL_COLUMNS))


def store_runs(map_path: str | Path, files: Sequence[FileOutcome], *,
               replace: bool = False) -> StoreReport:
    """Append the records of the runs reduced in ``files`` to the map, after checking each
    file against the map under its lock (:class:`ContentOwners`, the batch's check too):
    a file whose runs the map already holds under another file name is a duplicate (its
    records are left out, the map keeps the first name) or, where the labels differ, a
    conflict (refused, unless ``replace``). A run the map holds reviewed takes its review
    again (:func:`tribopipe.review.landing_records`, from its trace): never silently
    re-automated."""
    same: list[SameContent] = []
    repeats: list[str] = []
    traces = [r.trace for f in files for r in f.reduced if r.trace is not None]
    traces_dir = traces[0].parent if traces else None

    def decide(current: Any) -> tuple[list[MapRow], tuple[str, ...]]:
        owners = ContentOwners(map_files_by_hash(current))
        keep: list[MapRow] = []
        for f in files:
            records = [r.record for r in f.reduced if r.record is not None]
            if not records:
                continue
            runs = {r.measurement_id: labels_of(r) for r in records}
            found, _ = owners.check(f.path, f.file_hash, runs)
            if found is not None:
                same.append(found)
            if found is None or (found.conflict and replace):
                keep += records
                owners.landed(f.path, f.file_hash, runs)
        repeats.extend(repeat_clashes(current, keep))
        kept, _ = landing_records(current, keep, (), None, traces_dir)
        return kept, ()

    fresh = {r.measurement_id for f in files for r in f.reduced if r.record is not None}

    def reviewed_again(current: Any) -> bool:  # landing_records then reads whole rows
        reviewed = current.loc[current["review"].notna(), "measurement_id"]
        return bool(fresh.intersection(reviewed.astype(str)))

    appended = update_map_with(map_path, decide, replace=replace,
                               columns=(*CHECK_COLUMNS, *GROUP_COLUMNS),
                               needs_all=reviewed_again)
    return StoreReport(appended=appended, same=tuple(same), repeats=tuple(repeats))

"""The one route from an export to its runs: read → its runs → label → reduce → outputs.

:func:`reduce_export` is the route, for ``tribopipe reduce`` (:func:`reduce_files`) and the
batch workers alike: it reads the export once (:func:`read_runs`: each run's
:class:`~tribopipe.pipeline.runs.RunPlace` and friction interval, and each test/result
that holds none with the reason), labels each run, reduces it (:func:`reduce_run`: the
in-memory :class:`~tribopipe.pipeline.runs.RunOutcome`, its QC flags decided once by
:func:`tribopipe.labels.decide_run`), writes its outputs
(:func:`tribopipe.pipeline.run_outputs.reduced_run`) and returns one
:class:`~tribopipe.pipeline.runs.FileOutcome`: a reduced or failed run per run, each
failure with its one-line reason, or the file's error. Landing the runs in the map is
:mod:`~tribopipe.pipeline.landing`.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import (
    Failure,
    NotFrictionTestError,
    OutputError,
    ReductionError,
    TribopipeError,
)
from ..files import file_sha256, os_reason
from ..frictionmap.records import make_record, measurement_id
from ..labels import LabelCheck, RunLabels, Tolerances, Undescribed, decide_run
from ..layout import OutputLayout
from ..numeric import finite_or_nan, finite_or_none
from ..readers import read_export
from ..reduction.intervals import friction_intervals
from ..reduction.reduce import reduce_measurement
from .run_outputs import RunOutputs, reduced_run
from .runs import (
    ExportRuns,
    FailedRun,
    FileOutcome,
    ReadOptions,
    ReducedRun,
    RunOutcome,
    RunPlace,
)

if TYPE_CHECKING:
    from ..config import Settings
    from ..measurement import Measurement


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

#: the labels of each run of an export: ``labels_for(export, place, name)`` (``name`` is
#: the run's name in messages); raises :class:`~tribopipe.errors.TribopipeError` when the
#: run cannot be labelled (:class:`~tribopipe.labels.Undescribed` when nothing describes it)
LabelsFor = Callable[[ExportRuns, RunPlace, str], RunLabels]


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
            runs.append(reduced_run(outcome, run, outputs))
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

"""One run from raw file to friction-map record: read → select interval → reduce → record.

This is the orchestration of a single file used by ``tribopipe reduce`` and by campaigns.
Readers and writers stay at the edges; :mod:`tribopipe.reduce` does the physics.

Per run, both ``tribopipe reduce`` and the batch workers call :func:`reduce_file`, then
write what the output folder holds for it at the paths of :mod:`tribopipe.layout`:
:func:`write_trace`, :func:`write_summary` (``tribopipe reduce`` only) and
:func:`plot_run`. :func:`reduce_files` is the whole ``tribopipe reduce`` over several
files: each file alone, a failing one reported in one line and skipped.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .errors import TribopipeError
from .figures import plot_trace
from .files import file_sha256, write_text_atomic
from .frictionmap.records import RunLabels, Tolerances, make_record, measurement_id
from .intervals import select_friction_interval
from .layout import OutputLayout
from .numeric import finite_or_none
from .readers import read_export
from .reduce import reduce_measurement

if TYPE_CHECKING:
    from .config import Settings
    from .measurement import Measurement
    from .reduce import ReductionResult


@dataclass(frozen=True)
class ReadOptions:
    """Forced reader settings; ``None`` means detect."""

    encoding: str | None = None
    delimiter: str | None = None
    decimal: str | None = None


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


def reduce_file(
    path: str | Path,
    settings: Settings,
    labels: RunLabels | None = None,
    read_options: ReadOptions | None = None,
    *,
    tolerances: Tolerances | None = None,
) -> RunOutcome:
    """Read an export, pick its friction interval, reduce it and build its map record.

    The map record is built only when ``labels`` name pin and disc; ``tolerances``
    (default: the map's 10 %, 2 K) decide its off-nominal QC flags. Raises
    :class:`tribopipe.errors.TribopipeError` subclasses for every bad input.
    """
    labels = labels or RunLabels()
    opts = read_options or ReadOptions()
    measurements = read_export(
        path, encoding=opts.encoding, delimiter=opts.delimiter, decimal=opts.decimal
    )
    measurement = select_friction_interval(measurements)
    result = reduce_measurement(measurement, settings.instrument, settings.reduction)
    file_hash = file_sha256(path)
    record = None
    if labels.complete:
        record = make_record(
            result=result,
            labels=labels,
            meta=measurement.meta,
            file_hash=file_hash,
            settings=settings,
            tolerances=tolerances,
        )
    return RunOutcome(
        path=str(path),
        measurement=measurement,
        result=result,
        labels=labels,
        file_hash=file_hash,
        config_hash=settings.config_hash,
        measurement_id=measurement_id(file_hash, measurement.meta),
        record=record,
    )


def trace_path(out_dir: str | Path | OutputLayout, outcome: RunOutcome) -> Path:
    """Where a run's reduced trace is written: ``<out_dir>/traces/<stem>_<id8>.parquet``
    (:meth:`tribopipe.layout.OutputLayout.trace_path`)."""
    return OutputLayout.of(out_dir).trace_path(outcome.path, outcome.measurement_id)


def write_trace(out_dir: str | Path | OutputLayout, outcome: RunOutcome) -> Path:
    """Write the reduced trace (Parquet, unit-suffixed columns) and return its path.

    The columns go to Arrow as plain arrays (no pandas metadata round trip): a campaign
    writes one trace per run, so this is on the hot path of a batch.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    target = trace_path(out_dir, outcome)
    target.parent.mkdir(parents=True, exist_ok=True)
    trace = outcome.result.trace
    table = pa.table({str(c): trace[c].to_numpy() for c in trace.columns})
    tmp = target.with_suffix(".parquet.tmp")
    pq.write_table(table, tmp)
    tmp.replace(target)
    return target


def run_summary(outcome: RunOutcome) -> dict[str, Any]:
    """A JSON-ready summary of a reduced run: the numbers and the evidence behind them.

    Keys: ``file, measurement_id, mu_s, mu_k, pressure_kPa`` (measured mean, per pin),
    ``normal_force_N`` (measured mean, total), ``temperature_C`` (measured mean or
    ``None``), ``flags`` (list), the μ_S position (``mu_s_distance_mm``, ``mu_s_time_s``),
    the μ_K window (``mu_k_window_mm``, ``mu_k_window_s``), plateau std and drift, sliding
    speed, labels, interval, method, parameters, file and config hashes.
    """
    r = outcome.result
    meta = outcome.measurement.meta
    return {
        "file": outcome.path,
        "measurement_id": outcome.measurement_id,
        "mu_s": float(r.mu_s),
        "mu_k": float(r.mu_k),
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
        "method": r.method,
        "parameters": dict(r.parameters),
        "file_hash": outcome.file_hash,
        "config_hash": outcome.config_hash,
    }


def write_summary(out_dir: str | Path | OutputLayout, outcome: RunOutcome) -> Path:
    """Write :func:`run_summary` as JSON: ``<out_dir>/summaries/<stem>_<id8>.json``."""
    target = OutputLayout.of(out_dir).summary_path(outcome.path, outcome.measurement_id)
    return write_text_atomic(target, json.dumps(run_summary(outcome), indent=2, default=str))


def plot_run(out_dir: str | Path | OutputLayout, outcome: RunOutcome) -> Path:
    """Draw a run's trace plot (μ over sliding distance with the μ_S peak and the μ_K
    window, :func:`tribopipe.figures.plot_trace`) to
    ``<out_dir>/plots/traces/<stem>_<id8>.png`` and return its path."""
    target = OutputLayout.of(out_dir).trace_plot_path(outcome.path, outcome.measurement_id)
    plot_trace(outcome.result, target, title=Path(outcome.path).name)
    return target


@dataclass(frozen=True)
class FileResult:
    """What :func:`reduce_files` made of one file: the reduced run and the files written
    for it, or ``error``, one line naming the file and the problem."""

    path: str
    outcome: RunOutcome | None = None
    error: str | None = None
    trace: Path | None = None
    summary: Path | None = None
    plot: Path | None = None

    @property
    def ok(self) -> bool:
        """True when the file was reduced and its outputs written."""
        return self.error is None


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
    """Reduce each file alone (:func:`reduce_file`) and write its trace, its summary
    (``summaries``) and its trace plot (``plots``) below ``out_dir``.

    A file that cannot be read, reduced or written gives a :class:`FileResult` with its
    one-line ``error`` (naming the file once) and the others still go through; nothing
    raises for a bad file. ``on_file`` is called with each result as it is done (in the
    order of ``paths``), e.g. to print progress.
    """
    layout = OutputLayout.of(out_dir)
    results: list[FileResult] = []
    for path in paths:
        try:
            outcome = reduce_file(path, settings, labels, read_options)
            trace = write_trace(layout, outcome)
            summary = write_summary(layout, outcome) if summaries else None
            plot = plot_run(layout, outcome) if plots else None
        except TribopipeError as exc:
            message = str(exc)
            if str(path) not in message:  # every line names its file, once
                message = f"{path}: {message}"
            result = FileResult(path=str(path), error=message)
        except OSError as exc:
            result = FileResult(path=str(path), error=f"{path}: {exc.strerror or exc}")
        else:
            result = FileResult(path=str(path), outcome=outcome, trace=trace, summary=summary,
                                plot=plot)
        if on_file is not None:
            on_file(result)
        results.append(result)
    return results

"""A reduced run's files, at the paths of :mod:`tribopipe.layout`: its trace (Parquet,
with the terms a reviewer's window is read with), its JSON summary, its trace plot; and
:func:`reduced_run`, the small picklable :class:`~tribopipe.pipeline.runs.ReducedRun`
with its outputs written (a plot that cannot be drawn is a note, never the run's
failure).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import OutputError
from ..escape import display_path, printable
from ..figures import TraceConditions, plot_trace
from ..files import os_reason, write_text_atomic
from ..layout import TRACE_ID_KEY, OutputLayout
from ..numeric import finite_json, finite_or_none
from ..reduction.manual import TRACE_META_KEY
from .runs import ReducedRun, RunOutcome


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
    # the run's whole id, which tells its trace from another run's of the same 8 digits
    meta = {TRACE_ID_KEY: outcome.measurement_id.encode()}
    if terms is not None:
        meta[TRACE_META_KEY] = terms.to_json()
    table = table.replace_schema_metadata(meta)
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


@dataclass(frozen=True)
class RunOutputs:
    """What :func:`reduce_export` writes for each reduced run below ``layout``: always its
    trace (Parquet), its JSON summary when ``summary``, its trace plot when ``plot``."""

    layout: OutputLayout
    summary: bool = False
    plot: bool = False


def _written(what: str, target: Path, write: Callable[[], Path]) -> Path:
    """Run ``write`` (which writes ``target``); an OS error becomes an
    :class:`OutputError` naming the output (not the export it came from)."""
    try:
        return write()
    except OSError as exc:
        raise OutputError(f"cannot write its {what} {display_path(target)}: "
                          f"{os_reason(exc)}") from None


def reduced_run(outcome: RunOutcome, name: str, outputs: RunOutputs | None) -> ReducedRun:
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

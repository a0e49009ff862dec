"""What a batch leaves in its output folder besides traces and plots: ``runs.csv`` (one row
per run of the campaign: per friction interval of every test of every file, and per file
or test that gave none) and ``failures.csv`` (``file,reason``, the file or the run's name,
written by :func:`tribopipe.layout.write_failures`, read back by the report)."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping, Sequence
from operator import attrgetter
from typing import Any

from ..escape import csv_cell
from ..files import atomic_text, write_text_atomic
from ..layout import failures_text, write_failures
from ..reporting import EXTRA_COLUMN, RunReport
from ..reporting import NAMES as REPORTING_NAMES
from .patterns import LABEL_FIELDS
from .spec import Campaign
from .state import DUPLICATE, ENTRY_KEYS, FAILED, REDUCED, FileState, RunEntry
from .table import CampaignRow

RUNS_COLUMNS: tuple[str, ...] = (
    "file", "test", "result", "interval", "status", "pin", "disc", "normal_force_N",
    "temperature_C", "repeat", "mu_s", "mu_k", "pressure_kPa", "normal_force_measured_N",
    "pressure_measured_kPa", "temperature_measured_C", "flags", "measurement_id", "trace",
    "reason", "pin_as_given", "disc_as_given", *REPORTING_NAMES, EXTRA_COLUMN,
)
#: the values a run row takes from its state entry (where it sits, what it measured)
_RUN_KEYS: tuple[str, ...] = tuple(k for k in ENTRY_KEYS if k not in ("labels", "name"))


def _cell(value: Any) -> str:
    """A ``runs.csv`` cell: numbers as written, text as one printable line that no
    spreadsheet reads as a formula (:func:`~tribopipe.escape.csv_cell`)."""
    kind = type(value)  # the plain types first, by their type: a table has 10⁵ cells
    if kind is float:
        return repr(round(value, 6)) if math.isfinite(value) else ""
    if kind is str:
        return csv_cell(value)
    if kind is int:
        return str(value)
    if value is None:
        return ""
    if isinstance(value, float):
        return "" if not math.isfinite(value) else repr(round(value, 6))
    if isinstance(value, int):
        return str(value)
    return csv_cell(str(value))


def write_runs_csv(campaign: Campaign, rows: Sequence[CampaignRow],
                    entries: Mapping[str, FileState], this_batch: Mapping[str, str],
                    failures: Mapping[str, str]) -> None:
    """``runs.csv``: per file of the campaign, a row per run the state knows of it (its
    status in this batch: reduced, skipped, failed or duplicate), else one row for the
    file (failed, with its reason)."""
    with atomic_text(campaign.runs_csv, keep_same=True) as fh:
        # an unchanged re-run leaves the table it would write again as it is
        _write_runs(csv.writer(fh, lineterminator="\n"), rows, entries, this_batch, failures)


def runs_csv_text(rows: Sequence[CampaignRow], entries: Mapping[str, FileState],
                  this_batch: Mapping[str, str], failures: Mapping[str, str]) -> str:
    """The text :func:`write_runs_csv` writes, as one string (a re-run rehearsed:
    :mod:`tribopipe.campaign.stamp`)."""
    buf = io.StringIO()
    _write_runs(csv.writer(buf, lineterminator="\n"), rows, entries, this_batch, failures)
    return buf.getvalue()


def write_tables_text(campaign: Campaign, runs: str, failures: str) -> None:
    """Write ``runs.csv`` and ``failures.csv`` from their text (:func:`runs_csv_text`,
    :func:`failures_csv_text`) as :func:`write_runs_csv` and :func:`write_failures_csv`
    write them: atomically, ``runs.csv`` left as it is when its bytes are those. Raises
    :class:`~tribopipe.errors.OutputError` naming the table that cannot be written."""
    with atomic_text(campaign.runs_csv, keep_same=True) as fh:
        fh.write(runs)
    write_text_atomic(campaign.failures_csv, failures)


def _write_runs(writer: Any, rows: Sequence[CampaignRow], entries: Mapping[str, FileState],
                this_batch: Mapping[str, str], failures: Mapping[str, str]) -> None:
    """The rows of ``runs.csv`` written one by one to ``writer`` (a :func:`csv.writer`)."""
    writer.writerow(RUNS_COLUMNS)
    report_cells = _ReportCells()
    for row in rows:
        entry = entries.get(row.file)
        if entry is None or row.file in failures or not entry.runs:
            status = this_batch.get(row.file, FAILED)
            writer.writerow(_cells(_values(row.file, {}, status, _file_labels(row),
                                           failures.get(row.file))))
            continue
        for run in entry.runs:
            measured_run = run.entry
            name = (run.name if measured_run is None else measured_run.name) or row.file
            kept = run.status
            status = DUPLICATE if kept == DUPLICATE else this_batch.get(name, FAILED)
            ok = kept == REDUCED and status != FAILED
            measured = ok or kept == DUPLICATE
            reason = failures.get(name) or (entry.reason if kept == DUPLICATE else None)
            if measured and measured_run is not None:
                # what it measured, read from its entry (not copied into a dict first)
                labels = measured_run.labels or _file_labels(row)
                writer.writerow(_cells(_measured_values(row.file, measured_run, status,
                                                        labels, reason, report_cells)))
                continue
            # the file's own labels only where the run has none (its metadata is then
            # found: a reduced run's row needs none)
            flat = run.flat()
            labels = (flat.get("labels") if measured else None) or _file_labels(row)
            writer.writerow(_cells(_values(row.file, flat, status, labels, reason,
                                           measured=measured)))


def _cells(values: Sequence[Any]) -> list[str]:
    """A row's values as ``runs.csv`` cells (:func:`_cell`; a missing value is empty)."""
    return ["" if v is None else _cell(v) for v in values]


#: the values a measured run's row takes from its entry besides where it sits
_MEASURED_KEYS: tuple[str, ...] = tuple(k for k in _RUN_KEYS
                                        if k not in ("test", "result", "interval"))
_measured_of = attrgetter(*_MEASURED_KEYS)


class _ReportCells:
    """:func:`_report_cells` of each labels' ``report`` once per ``runs.csv`` (the
    entries read in one go share one object per report that repeats; known by identity,
    each kept alive beside its cells)."""

    def __init__(self) -> None:
        self._cells: dict[int, tuple[Any, dict[str, Any]]] = {}

    def __call__(self, labels: Mapping[str, Any]) -> dict[str, Any]:
        report = labels.get("report")
        if not isinstance(report, Mapping):
            return {}
        kept = self._cells.get(id(report))
        if kept is None or kept[0] is not report:
            kept = (report, _report_cells(labels))
            self._cells[id(report)] = kept
        return kept[1]


def _measured_values(file: str, run: RunEntry, status: str, labels: Mapping[str, Any],
                     reason: str | None, report_cells: _ReportCells) -> list[Any]:
    """:func:`_values` of a measured run (``measured=True``) from its state entry."""
    return _row_values(file, status, labels, report_cells(labels),
                       (run.test, run.result, run.interval),
                       dict(zip(_MEASURED_KEYS, _measured_of(run), strict=True)), reason)


def _file_labels(row: CampaignRow) -> dict[str, Any]:
    """The label fields of a file as its metadata gives them before it is read."""
    merged = row.merged
    return {k: merged.get(k) for k in LABEL_FIELDS}


def _values(file: str, run: Mapping[str, Any], status: str, labels: Mapping[str, Any],
            reason: str | None, *, measured: bool = False) -> list[Any]:
    """One ``runs.csv`` row, in :data:`RUNS_COLUMNS` order."""
    return _row_values(file, status, labels, _report_cells(labels),
                       (run.get("test"), run.get("result"), run.get("interval")),
                       {k: run.get(k) for k in _MEASURED_KEYS} if measured else {}, reason)


def _row_values(file: str, status: str, labels: Mapping[str, Any],
                report: Mapping[str, Any], where: tuple[Any, Any, Any],
                measured: Mapping[str, Any], reason: str | None) -> list[Any]:
    """One ``runs.csv`` row, in :data:`RUNS_COLUMNS` order, from its parts: the file's
    or run's ``labels`` and their ``report`` cells, where the run sits (its test, result
    and interval), what it measured (by :data:`_MEASURED_KEYS`; empty where that is not
    shown) and the ``reason`` it failed."""
    values: dict[str, Any] = {
        "file": file, "status": status, **labels, **report,
        "test": where[0], "result": where[1], "interval": where[2],
        **measured, "reason": reason,
    }
    return list(map(values.get, RUNS_COLUMNS))


def _report_cells(labels: Mapping[str, Any]) -> dict[str, Any]:
    """The reporting-item cells of a run's labels as the state keeps them (``report``:
    ``values`` and ``extra`` as lists of pairs), empty when it holds none."""
    report = labels.get("report")
    if not isinstance(report, Mapping):
        return {}
    try:
        values = {str(k): v for k, v in report.get("values") or []}
        extra = {str(k): str(v) for k, v in report.get("extra") or []}
        return RunReport.of(values, extra).columns()
    except (TypeError, ValueError):  # a hand-edited state: the cells stay empty
        return {}


def write_failures_csv(campaign: Campaign, failures: Mapping[str, str]) -> None:
    """``failures.csv`` (:func:`~tribopipe.layout.write_failures`)."""
    write_failures(campaign.failures_csv, failures)


def failures_csv_text(failures: Mapping[str, str]) -> str:
    """The text :func:`write_failures_csv` writes."""
    return failures_text(failures)

"""What a batch leaves in its output folder besides traces and plots: ``runs.csv`` (one row
per file of the campaign) and ``failures.csv`` (``file,reason``, written by
:func:`tribopipe.layout.write_failures`, read back by the report)."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping, Sequence
from typing import Any

from ..files import write_text_atomic
from ..layout import write_failures
from .patterns import LABEL_FIELDS
from .spec import Campaign
from .table import _SUMMARY_KEYS, FAILED, REDUCED, CampaignRow

RUNS_COLUMNS: tuple[str, ...] = (
    "file", "status", "pin", "disc", "normal_force_N", "temperature_C", "repeat", "mu_s",
    "mu_k", "pressure_kPa", "normal_force_measured_N", "pressure_measured_kPa",
    "temperature_measured_C", "flags", "measurement_id", "trace", "reason",
)


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return "" if not math.isfinite(value) else repr(round(value, 6))
    return str(value)


def _write_runs_csv(campaign: Campaign, rows: Sequence[CampaignRow],
                    entries: Mapping[str, Any], this_batch: Mapping[str, str],
                    failures: Mapping[str, str]) -> None:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(RUNS_COLUMNS)
    for row in rows:
        entry = entries.get(row.file) or {}
        status = this_batch.get(row.file, FAILED)
        ok = entry.get("status") == REDUCED and status != FAILED
        labels = entry.get("labels") if ok else None
        labels = labels or {k: row.merged.get(k) for k in LABEL_FIELDS}
        values = {
            "file": row.file, "status": status, **labels,
            **({k: entry.get(k) for k in _SUMMARY_KEYS if k != "labels"} if ok else {}),
            "reason": failures.get(row.file),
        }
        writer.writerow([_cell(values.get(c)) for c in RUNS_COLUMNS])
    write_text_atomic(campaign.runs_csv, buf.getvalue())


def _write_failures_csv(campaign: Campaign, failures: Mapping[str, str]) -> None:
    write_failures(campaign.failures_csv, failures)

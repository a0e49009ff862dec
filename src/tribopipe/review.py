"""A lab's review of its runs: the decisions file ``review.csv``, read and checked, and
applied to the map's rows.

``review.csv`` has one row per decision and the columns :data:`HEADER`:

``run``              the run's measurement id, or the file name of a one-run export
``action``           ``accept``: the run's QC flags do not count against its group (they
                     stay visible, marked reviewed); ``exclude``: the run leaves the
                     statistics, with ``reason``; ``window``: μ_K (and its u) is re-read
                     over ``kinetic_from_mm``–``kinetic_to_mm``, and μ_S at
                     ``static_peak_mm`` when that is given
                     (:mod:`tribopipe.reduction.manual`: the same estimator and budget
                     as the automatic window)
``kinetic_from_mm``, ``kinetic_to_mm``, ``static_peak_mm``   distances along the sliding
                     path [mm] (``window`` only)
``reason``, ``who``, ``date``   why, who and when (``reason`` required for ``exclude``)

A reviewed row keeps the reduction's own values beside the reviewed ones (the ``auto_``
columns of :data:`tribopipe.frictionmap.schema.REVIEW_COLUMNS`) with the decision
itself (``review``, ``review_by``, ``review_date``, ``review_reason`` and the reviewer's
distances), so that a run re-reduced later takes its review again
(:func:`review_records`) and is never silently re-automated. Every problem of a
decision — a run that is not in the map, a window outside the trace, or shorter than
the estimator needs — is one :class:`ReviewError` line naming the file and line, and
nothing is applied.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .errors import ReductionError, TribopipeError
from .escape import csv_cell, csv_uncell, display_path
from .files import read_regular
from .frictionmap.schema import MapRow, checked_row, frame_rows
from .layout import find_trace
from .reduction.manual import (
    TRACE_META_KEY,
    SlidingSamples,
    TraceTerms,
    kinetic_over,
    static_at,
)
from .validate import text_problem

if TYPE_CHECKING:
    import pandas as pd

#: the columns of ``review.csv``, in order
HEADER: tuple[str, ...] = ("run", "action", "kinetic_from_mm", "kinetic_to_mm",
                           "static_peak_mm", "reason", "who", "date")
ACTIONS: tuple[str, ...] = ("accept", "exclude", "window")
#: the file name a campaign's review has by default (beside the campaign file)
REVIEW_FILE = "review.csv"
#: the most decisions one file may hold
MAX_DECISIONS = 1_000_000
#: the largest decisions file read [bytes]
MAX_REVIEW_BYTES = 256 * 1024 * 1024
#: the reduction's own values a review keeps beside the reviewed ones: auto column ← column
AUTO_OF: dict[str, str] = {
    "auto_mu_s": "mu_s", "auto_mu_k": "mu_k", "auto_u_mu_s": "u_mu_s",
    "auto_u_mu_k": "u_mu_k", "auto_mu_s_distance_mm": "mu_s_distance_mm",
    "auto_mu_k_window_start_mm": "mu_k_window_start_mm",
    "auto_mu_k_window_end_mm": "mu_k_window_end_mm",
}
#: the columns a ``window`` decision re-reads (restored from the trace when withdrawn
#: only where an ``auto_`` column keeps them; the others are re-read over the
#: automatic window)
_REREAD = ("mu_k_window_start_s", "mu_k_window_end_s", "plateau_std", "plateau_drift_per_mm",
           "mu_s_time_s")
#: the review's own columns (the decision), cleared when a review is withdrawn
DECISION_COLUMNS: tuple[str, ...] = (
    "review", "review_by", "review_date", "review_reason", "review_kinetic_from_mm",
    "review_kinetic_to_mm", "review_static_peak_mm")


class ReviewError(TribopipeError):
    """A decisions file or one of its decisions that cannot be applied (one line naming
    the file and line)."""


@dataclass(frozen=True)
class Decision:
    """One row of ``review.csv`` (:data:`HEADER`); ``line`` is its line in the file (the
    header is line 1). Distances in mm, ``None`` when the cell is empty; texts raw."""

    line: int
    run: str
    action: str
    kinetic_from_mm: float | None = None
    kinetic_to_mm: float | None = None
    static_peak_mm: float | None = None
    reason: str = ""
    who: str = ""
    date: str = ""

    def cells(self) -> list[str]:
        """The row's cells as :func:`review_csv` writes them."""
        def number(v: float | None) -> str:
            return "" if v is None else repr(float(v))
        return [self.run, self.action, number(self.kinetic_from_mm), number(self.kinetic_to_mm),
                number(self.static_peak_mm), self.reason, self.who, self.date]


@dataclass(frozen=True)
class Review:
    """The decisions of one ``review.csv`` (``path``), one per run, in file order."""

    path: Path
    decisions: tuple[Decision, ...]

    def where(self, d: Decision) -> str:
        """``<file> line N (run R)``: how a message names a decision."""
        return f"{display_path(self.path)} line {d.line} (run {d.run})"


def _number(cell: str, column: str, where: str) -> float | None:
    if cell.strip() == "":
        return None
    try:
        value = float(cell)
    except ValueError:
        raise ReviewError(f"{where}: {column} {cell!r} is not a number (mm)") from None
    if not math.isfinite(value) or value < 0:
        raise ReviewError(f"{where}: {column} {cell!r} must be a finite distance ≥ 0 mm")
    return value


def _decision(cells: Mapping[str, str], line: int, where: str) -> Decision:
    """One checked row of ``review.csv``."""
    for column in ("run", "reason", "who", "date"):
        problem = text_problem(cells[column])
        if problem:
            raise ReviewError(f"{where}: {column} {problem}")
    run, action = cells["run"].strip(), cells["action"].strip()
    if not run:
        raise ReviewError(f"{where}: run is empty (a measurement id or a one-run file's name)")
    if action not in ACTIONS:
        raise ReviewError(f"{where}: action {action!r} is not one of {', '.join(ACTIONS)}")
    lo = _number(cells["kinetic_from_mm"], "kinetic_from_mm", where)
    hi = _number(cells["kinetic_to_mm"], "kinetic_to_mm", where)
    peak = _number(cells["static_peak_mm"], "static_peak_mm", where)
    if action == "window":
        if lo is None or hi is None:
            raise ReviewError(f"{where}: a window decision needs kinetic_from_mm and "
                              "kinetic_to_mm")
        if hi <= lo:
            raise ReviewError(f"{where}: the window {lo:g}–{hi:g} mm must end after it starts")
    elif lo is not None or hi is not None or peak is not None:
        raise ReviewError(f"{where}: distances belong to a window decision, not {action!r}")
    if action == "exclude" and not cells["reason"].strip():
        raise ReviewError(f"{where}: an exclusion needs a reason")
    return Decision(line=line, run=run, action=action, kinetic_from_mm=lo, kinetic_to_mm=hi,
                    static_peak_mm=peak, reason=cells["reason"].strip(),
                    who=cells["who"].strip(), date=cells["date"].strip())


def parse_review(text: str, path: str | Path) -> Review:
    """The decisions in the text of a ``review.csv`` (``path`` names it in messages).
    :class:`ReviewError` for a missing or unknown column, a bad cell, or a run decided
    twice."""
    p = Path(path)
    name = display_path(p)
    reader = csv.reader(io.StringIO(text.lstrip("\ufeff"), newline=""))
    try:
        header = next(reader, None)
        if header is None:
            raise ReviewError(f"{name}: empty; expected the header {','.join(HEADER)}")
        header = [h.strip() for h in header]
        missing = [h for h in HEADER if h not in header]
        unknown = [h for h in header if h not in HEADER]
        if missing or unknown or len(set(header)) != len(header):
            raise ReviewError(
                f"{name} line 1: expected the columns {','.join(HEADER)}"
                + (f"; missing {', '.join(missing)}" if missing else "")
                + (f"; unknown {', '.join(map(repr, unknown))}" if unknown else ""))
        decisions: list[Decision] = []
        seen: dict[str, int] = {}
        for row in reader:
            line = reader.line_num
            if not any(c.strip() for c in row):
                continue
            where = f"{name} line {line}"
            if len(row) != len(header):
                raise ReviewError(f"{where}: {len(row)} cells, expected {len(header)}")
            if len(decisions) >= MAX_DECISIONS:
                raise ReviewError(f"{where}: more than {MAX_DECISIONS} decisions")
            cells = {h: csv_uncell(c) for h, c in zip(header, row, strict=True)}
            d = _decision(cells, line, where)
            if d.run in seen:
                raise ReviewError(f"{where}: run {d.run} is decided twice (also on line "
                                  f"{seen[d.run]}); keep one decision per run")
            seen[d.run] = line
            decisions.append(d)
    except csv.Error as exc:
        raise ReviewError(f"{name} line {reader.line_num}: not CSV ({exc})") from None
    return Review(path=p, decisions=tuple(decisions))


def read_review(path: str | Path) -> Review:
    """Read and check ``review.csv`` (:func:`parse_review`); a missing or unreadable
    file is a :class:`ReviewError`."""
    p = Path(path)
    try:
        raw = read_regular(p, max_bytes=MAX_REVIEW_BYTES)
    except TribopipeError as exc:
        raise ReviewError(str(exc)) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ReviewError(f"{display_path(p)}: not UTF-8 text") from None
    return parse_review(text, p)


def review_csv(decisions: Iterable[Decision]) -> str:
    """``review.csv`` text: the header, then one row per decision (numbers by their
    shortest round-trip text, texts through :func:`tribopipe.escape.csv_cell`)."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(HEADER)
    for d in decisions:
        writer.writerow([csv_cell(c) for c in d.cells()])
    return out.getvalue()


def decision_of_row(row: MapRow, line: int = 0) -> Decision | None:
    """The decision a reviewed map row holds (``None`` for a row not reviewed)."""
    if row.review is None:
        return None
    return Decision(line=line, run=row.measurement_id, action=row.review,
                    kinetic_from_mm=row.review_kinetic_from_mm,
                    kinetic_to_mm=row.review_kinetic_to_mm,
                    static_peak_mm=row.review_static_peak_mm, reason=row.review_reason or "",
                    who=row.review_by or "", date=row.review_date or "")


def _cleared(row: MapRow) -> MapRow:
    """``row`` without a review: no decision and no ``auto_`` copy."""
    none: dict[str, Any] = dict.fromkeys((*AUTO_OF, *DECISION_COLUMNS))
    return replace(row, **none)


def automatic(row: MapRow, samples: Callable[[], tuple[SlidingSamples,
              TraceTerms]] | None = None) -> MapRow:
    """The row as the reduction made it: a reviewed row with its ``auto_`` values back,
    its decision cleared and, after an exclusion by review, included again. The columns
    a window re-reads without an ``auto_`` copy (its times, the plateau's scatter and
    drift, μ_S's time) are re-read over the automatic window from ``samples()`` when a
    window was applied."""
    if row.review is None:
        return row
    out = _cleared(replace(row, **{col: getattr(row, auto) for auto, col in AUTO_OF.items()}))
    if row.review == "exclude":
        out = replace(out, excluded=False, exclusion_reason=None)
    start, end = out.mu_k_window_start_mm, out.mu_k_window_end_mm
    if row.review == "window" and samples is not None and start is not None and end is not None:
        smp, terms = samples()
        k = kinetic_over(smp, start, end, terms)
        out = replace(out, mu_k_window_start_s=k.start_s, mu_k_window_end_s=k.end_s,
                      plateau_std=k.std, plateau_drift_per_mm=k.drift_per_mm)
        s_peak = out.mu_s_distance_mm
        if s_peak is not None and smp.s_mm.size:
            out = replace(out, mu_s_time_s=float(
                smp.t_s[int(np.argmin(np.abs(smp.s_mm - s_peak)))]))
    return out


def reviewed(auto: MapRow, d: Decision, where: str,
             samples: Callable[[], tuple[SlidingSamples, TraceTerms]]) -> MapRow:
    """The row ``auto`` (as the reduction made it) with decision ``d`` applied; the
    automatic values kept in the ``auto_`` columns. :class:`ReviewError` naming
    ``where`` when the decision cannot be applied."""
    out = replace(auto, **{col_auto: getattr(auto, col) for col_auto, col in AUTO_OF.items()})
    out = replace(out, review=d.action, review_by=d.who or None, review_date=d.date or None,
                  review_reason=d.reason or None, review_kinetic_from_mm=d.kinetic_from_mm,
                  review_kinetic_to_mm=d.kinetic_to_mm, review_static_peak_mm=d.static_peak_mm)
    if d.action == "exclude":
        out = replace(out, excluded=True, exclusion_reason=d.reason)
    elif d.action == "window":
        assert d.kinetic_from_mm is not None and d.kinetic_to_mm is not None
        smp, terms = samples()
        try:
            k = kinetic_over(smp, d.kinetic_from_mm, d.kinetic_to_mm, terms, where=where)
            out = replace(out, mu_k=k.mu_k, u_mu_k=k.u_mu_k, mu_k_window_start_mm=k.start_mm,
                          mu_k_window_end_mm=k.end_mm, mu_k_window_start_s=k.start_s,
                          mu_k_window_end_s=k.end_s, plateau_std=k.std,
                          plateau_drift_per_mm=k.drift_per_mm)
            if d.static_peak_mm is not None:
                st = static_at(smp, d.static_peak_mm, terms, where=where)
                out = replace(out, mu_s=st.mu_s, u_mu_s=st.u_mu_s,
                              mu_s_distance_mm=st.distance_mm, mu_s_time_s=st.time_s)
        except ReductionError as exc:
            raise ReviewError(str(exc)) from None
    try:
        return checked_row(out, where=where)
    except TribopipeError as exc:
        raise ReviewError(f"{where}: the reviewed row breaks a rule: {exc}") from None


def trace_samples(traces_dir: Path | None, measurement_id: str,
                  where: str) -> tuple[SlidingSamples, TraceTerms]:
    """A run's sliding samples and terms from its trace Parquet under ``traces_dir``;
    :class:`ReviewError` naming ``where`` when there is none or it predates the terms."""
    samples, terms, _ = trace_table(traces_dir, measurement_id, where)
    return samples, terms


def trace_table(traces_dir: Path | None, measurement_id: str,
                where: str) -> tuple[SlidingSamples, TraceTerms, pd.DataFrame]:
    """:func:`trace_samples` and the whole trace (read once)."""
    import pyarrow.parquet as pq

    path = None if traces_dir is None else find_trace(traces_dir, measurement_id)
    if path is None:
        raise ReviewError(f"{where}: no trace of the run under "
                          f"{display_path(traces_dir) if traces_dir else 'the output folder'}; "
                          "a window is read from the run's trace")
    try:
        table = pq.read_table(path)
    except (OSError, ValueError) as exc:
        raise ReviewError(f"{where}: cannot read the trace {display_path(path)}: {exc}") from None
    terms = TraceTerms.from_json((table.schema.metadata or {}).get(TRACE_META_KEY, b""))
    if terms is None:
        raise ReviewError(f"{where}: the trace {display_path(path)} was written before traces "
                          "kept their uncertainty terms; reduce the run again",
                          hint="remove the campaign's .tribopipe-state.*.sqlite from its output "
                               "folder and run batch: every run is reduced again")
    frame = table.to_pandas()
    return SlidingSamples.of_trace(frame), terms, frame


def _resolve(review: Review, rows: Mapping[str, MapRow]) -> dict[str, Decision]:
    """Run id → decision: each decision's run found by id or by its one-run file's name;
    :class:`ReviewError` for a run not in the map or named twice."""
    by_file: dict[str, list[str]] = {}
    for mid, row in rows.items():
        if row.source_file is not None:
            by_file.setdefault(row.source_file, []).append(mid)
    out: dict[str, Decision] = {}
    for d in review.decisions:
        where = review.where(d)
        if d.run in rows:
            mid = d.run
        elif d.run in by_file and len(by_file[d.run]) == 1:
            mid = by_file[d.run][0]
        elif d.run in by_file:
            raise ReviewError(f"{where}: the file holds {len(by_file[d.run])} runs; name one "
                              "by its measurement id")
        else:
            raise ReviewError(f"{where}: no such run in the map (a measurement id, or the "
                              "file name of a one-run export)")
        if mid in out:
            raise ReviewError(f"{where}: run {mid} is also decided on line {out[mid].line}")
        out[mid] = d
    return out


@dataclass(frozen=True)
class ReviewOutcome:
    """What a review did to a map: the records that change (to fold in, replacing their
    rows), and the counts of decisions applied by action and of reviews withdrawn (runs
    reviewed in the map, no longer in the file: back to the reduction's values)."""

    records: list[MapRow]
    applied: dict[str, int]
    withdrawn: list[str]

    def line(self, path: Path | None) -> str:
        """One line for a batch's notes."""
        parts = ", ".join(f"{n} {a}" for a, n in self.applied.items() if n) or "no decision"
        text = f"review {display_path(path) if path else '(kept in the map)'}: {parts}"
        if self.withdrawn:
            text += f"; {len(self.withdrawn)} withdrawn (back to the automatic values)"
        return text


def review_records(rows: Sequence[MapRow], review: Review | None,
                   traces_dir: Path | None, *, fresh: Iterable[str] = ()) -> ReviewOutcome:
    """Apply a review to map rows (``rows``: every row as the map will hold it, the
    records of runs reduced now included).

    With ``review``, each decision is applied to its run and each reviewed row without a
    decision goes back to the reduction's values (withdrawn). Without one, the rows keep
    their own reviews: those of the runs in ``fresh`` (ids reduced now, whose records
    carry no review) take the review their old row held (the caller passes those rows
    with the old row's decision columns). Returns the records to fold in: only rows
    whose content changes are needed, but every reviewed row is returned (folding an
    unchanged row changes nothing). Nothing is applied when any decision fails: the
    first failure is a :class:`ReviewError` naming its line."""
    by_id = {r.measurement_id: r for r in rows}
    fresh_ids = set(fresh)
    if review is not None:
        decided = _resolve(review, by_id)
        where_of = {mid: review.where(d) for mid, d in decided.items()}
    else:
        decided = {}
        for mid, row in by_id.items():
            d = decision_of_row(row)
            if d is not None:
                decided[mid] = d
        where_of = {mid: f"the review of run {mid} kept in the map" for mid in decided}
    records: list[MapRow] = []
    applied = dict.fromkeys(ACTIONS, 0)
    withdrawn: list[str] = []
    for mid, row in by_id.items():
        d = decided.get(mid)
        was_reviewed = row.review is not None
        if d is None and not was_reviewed:
            continue
        where = where_of.get(mid, f"run {mid}")

        def load(mid: str = mid, where: str = where) -> tuple[SlidingSamples, TraceTerms]:
            return trace_samples(traces_dir, mid, where)

        # a fresh record is already automatic; an old row is made so (its auto_ values)
        base = _cleared(row) if mid in fresh_ids else automatic(row, load)
        if d is None:
            withdrawn.append(mid)
            records.append(checked_row(base, where=where))
            continue
        records.append(reviewed(base, d, where, load))
        applied[d.action] += 1
    return ReviewOutcome(records=records, applied=applied, withdrawn=withdrawn)


def review_counts(runs: pd.DataFrame) -> dict[str, int]:
    """How many rows of ``runs`` carry each review action (zero where none)."""
    counts = dict.fromkeys(ACTIONS, 0)
    if "review" in runs.columns:
        for action, n in runs["review"].dropna().astype(str).value_counts().items():
            if action in counts:
                counts[str(action)] = int(n)
    return counts


def landing_records(current: pd.DataFrame, records: Sequence[MapRow],
                    stale_ids: Iterable[str], review: Review | None, traces_dir: Path | None
                    ) -> tuple[list[MapRow], ReviewOutcome | None]:
    """The records a batch folds into its map (``current``, read under the map's lock)
    with the review applied: ``records`` (the runs reduced now), each reviewed run's
    record taking its review — from ``review`` when given, else the one its old row
    held, so a re-reduced run is never silently re-automated — and the rows the review
    changes. Without ``review`` and with no reviewed row re-reduced, ``records`` as
    they are and ``None``. A review withdraws (:func:`review_records`) only reviewed
    rows whose trace lies under ``traces_dir`` (this campaign's runs)."""
    stale = set(stale_ids)
    fresh = {r.measurement_id: r for r in records}
    reviewed_now = set()
    if "review" in current.columns:
        reviewed_now = set(current.loc[current["review"].notna(), "measurement_id"].astype(str))
    if review is None and not (reviewed_now & set(fresh)):
        return list(records), None
    rows: list[MapRow] = []
    old_rows = {r.measurement_id: r for r in frame_rows(current)}
    for mid, old in old_rows.items():
        if mid in stale:
            continue
        if mid in fresh:
            # the decision the old row held (used without a file)
            row = replace(fresh[mid], **{col: getattr(old, col) for col in DECISION_COLUMNS})
            if old.review != "exclude":  # a `map exclude` stays
                row = replace(row, excluded=old.excluded, exclusion_reason=old.exclusion_reason)
            rows.append(row)
        else:
            if (review is not None and mid in reviewed_now and traces_dir is not None
                    and find_trace(traces_dir, mid) is None
                    and not any(d.run in (mid, old.source_file) for d in review.decisions)):
                continue  # another campaign's reviewed run: not this file's to withdraw
            rows.append(old)
    rows += [r for mid, r in fresh.items() if mid not in old_rows]
    outcome = review_records(rows, review, traces_dir, fresh=set(fresh) & set(old_rows))
    changed = {r.measurement_id: r for r in outcome.records}
    out: list[MapRow] = [changed.pop(mid, rec) for mid, rec in fresh.items()]
    return out + list(changed.values()), outcome

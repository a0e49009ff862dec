"""A campaign's stamp, and the ledger kept for a batch that finds nothing changed.

An unchanged re-run of a large campaign should cost a listing of its folder and a
``stat`` per file, not the building of its table. So a batch that found nothing to do
(no file read, no landing, no file gone, every output written) keeps its report in the
state (:class:`~tribopipe.campaign.state.KeptLedger`) with two stamps:

* :func:`inputs_stamp`, taken before the batch looked at anything: every field of the
  campaign as loaded (its config, instrument settings, names, materials vocabulary,
  patterns, tolerances, paths), its config hash (which carries the reduction method's
  version), the columns of ``runs.csv``, the manifest's bytes, each file of the folder by its
  name, size, ``mtime_ns``, ``ctime_ns`` and inode (stricter than the size and
  ``mtime_ns`` the table trusts a file's hash on), the map's stamp
  (:class:`~tribopipe.campaign.state.MapStamp`: a map folder's manifest) and the
  tribopipe version;
* :func:`outputs_stamp`, taken after it wrote its outputs: the bytes of ``runs.csv`` and
  ``failures.csv``.

The next batch whose two stamps are those kept, whose reduced runs' traces are all still
on disk and which has no decisions file to apply (a review is applied on every batch)
reports the kept ledger again (:func:`kept_report`) and writes nothing. Anything else
(a file touched, added, removed; the config, the vocabulary, the manifest or the map
changed; a trace or an output gone) is the full batch.

A batch that did work keeps no ledger of its own (the next one says its runs were
skipped, and writes ``runs.csv`` with those statuses), but when it ends cleanly it
rehearses its next unchanged re-run, by the batch's own code on the state it saved
(:func:`tribopipe.campaign.batch.run_campaign`), and keeps that re-run's ledger as
*pending*: its report, the ``runs.csv`` and ``failures.csv`` it would write
(:attr:`~tribopipe.campaign.state.KeptLedger.tables`), stamped with the inputs as the next
batch will find them and the tables as this batch wrote them. The next batch that finds
both stamps so writes those tables, reports that ledger and keeps it as the kept one.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable, Mapping
from pathlib import Path

from .. import __version__
from ..errors import OutputError
from .ledger import BatchReport
from .outputs import RUNS_COLUMNS, write_tables_text
from .spec import Campaign
from .state import DUPLICATE, REDUCED, FileState, KeptLedger, MapStamp, load_kept, save_kept
from .table import TraceListing, discover_paths

#: bumped when what a stamp covers changes (an old stamp then never matches)
STAMP_VERSION = 1


def _stat_text(path: str | Path) -> str:
    """A file's size, ``mtime_ns``, ``ctime_ns`` and inode (symlinks followed), or why it
    cannot be stat'ed."""
    try:
        st = os.stat(path)
    except OSError as exc:
        return f"! {exc.errno}"
    return f"{st.st_size} {st.st_mtime_ns} {st.st_ctime_ns} {st.st_ino} {st.st_mode}"


def inputs_stamp(campaign: Campaign) -> str | None:
    """The SHA-256 of everything a batch's outcome depends on besides its own outputs
    (see the module docstring); ``None`` when the raw folder cannot be listed."""
    h = hashlib.sha256()
    # the config hash carries the reduction method's version, which the campaign's repr
    # does not; the tables' columns, which a newer version may add to
    h.update(f"{STAMP_VERSION}\0{__version__}\0{campaign.settings.config_hash}\0"
             f"{RUNS_COLUMNS}\0{campaign!r}\0".encode("utf-8", "replace"))
    if campaign.manifest is not None:
        try:
            h.update(hashlib.sha256(campaign.manifest.read_bytes()).digest())
        except OSError as exc:
            h.update(f"! manifest {exc.errno}".encode())
    stamp = MapStamp.of(campaign.map_path)
    h.update(f"\0map {stamp}\0".encode())
    try:
        files = discover_paths(campaign)
    except OSError:
        return None
    root = str(campaign.raw_dir)
    for path in files:
        h.update(f"{path}\0{_stat_text(path)}\n".removeprefix(root).encode("utf-8", "replace"))
    return h.hexdigest()


def outputs_stamp(campaign: Campaign) -> str:
    """The stamp of a batch's tables, ``runs.csv`` and ``failures.csv``, as they are now:
    the SHA-256 of their bytes (a batch of an older version writes the same tables
    again)."""
    h = hashlib.sha256()
    for path in (campaign.runs_csv, campaign.failures_csv):
        try:
            h.update(hashlib.sha256(path.read_bytes()).digest())
        except OSError as exc:
            h.update(f"! {exc.errno}".encode())
    return h.hexdigest()


def needed_traces(entries: Mapping[str, FileState]) -> tuple[str, ...]:
    """The traces (relative to the output folder) of every reduced run of the files a
    batch keeps as reduced or duplicate: those the table checks are on disk."""
    return tuple(r.entry.trace for e in entries.values() if e.status in (REDUCED, DUPLICATE)
                 for r in e.runs if r.status == REDUCED and r.entry is not None)


def _all_present(campaign: Campaign, traces: Iterable[str]) -> bool:
    listing = TraceListing(campaign)
    return all(t and listing.present(t) for t in traces)


def kept_report(campaign: Campaign, inputs: str | None) -> BatchReport | None:
    """The ledger the last batch kept (:attr:`BatchReport.kept` true), when the campaign
    is as that batch found it: ``inputs`` (:func:`inputs_stamp`, taken now) and the
    outputs' stamp are those kept, its traces are all on disk and no decisions file is to
    be applied; else ``None`` (the full batch). A pending ledger's tables are written
    first (as the full batch writes them) and the ledger then kept as the kept one; when
    they or the state cannot be written, ``None``: the full batch, which says so."""
    if inputs is None or campaign.review is not None:
        return None
    kept = load_kept(campaign)
    if kept is None or kept.inputs != inputs or kept.outputs != outputs_stamp(campaign) \
            or not _all_present(campaign, kept.traces):
        return None
    try:
        report = BatchReport.from_json(kept.report, campaign.map_path, campaign.output_dir)
    except (KeyError, TypeError, ValueError, AttributeError):
        return None
    if kept.tables is not None:
        try:
            write_tables_text(campaign, *kept.tables)
            save_kept(campaign, KeptLedger(inputs=inputs, outputs=outputs_stamp(campaign),
                                           traces=kept.traces, report=kept.report))
        except OutputError:
            return None
    return report


def keep_report(campaign: Campaign, report: BatchReport | None, inputs: str | None,
                entries: Mapping[str, FileState],
                tables: tuple[str, str] | None = None) -> None:
    """Keep ``report`` (of a batch that found nothing to do, the campaign's inputs
    stamped ``inputs`` before it began; its state's ``entries``) for the next batch, with
    ``tables`` (the text of ``runs.csv`` and ``failures.csv``) as a pending ledger: the
    report of a re-run rehearsed, whose tables are not written yet (the outputs' stamp
    is then of the tables the batch that did work wrote); ``None`` forgets the one kept.
    Raises :class:`~tribopipe.errors.OutputError` when the state cannot be written."""
    if report is None or inputs is None:
        save_kept(campaign, None)
        return
    save_kept(campaign, KeptLedger(inputs=inputs, outputs=outputs_stamp(campaign),
                                   traces=needed_traces(entries), report=report.to_json(),
                                   tables=tables))

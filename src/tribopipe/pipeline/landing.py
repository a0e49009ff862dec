"""Reduced runs landed in the friction map: the one landing of ``tribopipe reduce`` and of
the batch.

:func:`land_runs` is that landing. Under the map's lock it reads the map once more
(:func:`tribopipe.frictionmap.store.update_map_with`, the locked read-modify-write), lets
the caller decide from the files the map holds what lands (the one duplicate and conflict
check, :class:`~tribopipe.frictionmap.duplicates.ContentOwners`), finds the repeat numbers
used twice, applies the review (:func:`tribopipe.review.landing_records`: a review file,
else the one each reviewed row holds), notes the condition groups touched and writes the
map in one atomic change. ``tribopipe reduce`` lands all its files at once
(:func:`store_runs`); the batch lands in chunks as its workers finish, each chunk one call.

:func:`check_map_before_work` refuses a foreign or damaged map before any work without
reading its rows: the rows are read and checked once, by the landing, under the lock.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..frictionmap.duplicates import (
    CHECK_COLUMNS,
    GROUP_COLUMNS,
    LABEL_COLUMNS,
    ContentOwners,
    FilesByHash,
    SameContent,
    labels_of,
    map_files_by_hash,
    repeat_clashes,
)
from ..frictionmap.parts import read_manifest
from ..frictionmap.schema import MapRow, unvalidated_frame
from ..frictionmap.store import AppendReport, map_metadata, update_map_with
from ..review import Review, ReviewOutcome, landing_records
from ..stats import condition_keys
from .runs import FileOutcome

if TYPE_CHECKING:
    import pandas as pd


#: the map columns a landing reads of every row when the runs it brings are known
#: (:func:`land_runs`' ``arriving``): the duplicate check's, and those of the repeat
#: numbers' condition groups
LANDING_COLUMNS: tuple[str, ...] = (*CHECK_COLUMNS, *GROUP_COLUMNS)


@dataclass(frozen=True)
class Arrivals:
    """What a caller brings to the map, decided from the map as read under its lock: the
    ``records`` to add (or replace) and the ids of rows to drop (``stale_ids``: their raw
    file changed, or the run now fails)."""

    records: Sequence[MapRow] = ()
    stale_ids: Collection[str] = ()


@dataclass(frozen=True)
class Landed:
    """What one landing did: the map's :class:`AppendReport`, the repeat numbers now
    used twice in one condition, what the review did (``None`` when none applied) and
    the condition groups (:func:`tribopipe.stats.condition_keys`) with a row added,
    replaced or removed. Not the map's rows: a landing keeps none of them (a command
    that shows the map afterwards reads its stored groups)."""

    appended: AppendReport
    repeats: tuple[str, ...] = ()
    review: ReviewOutcome | None = None
    groups: frozenset[tuple[Any, ...]] = frozenset()


def land_runs(
    map_path: str | Path,
    choose: Callable[[FilesByHash], Arrivals],
    *,
    review: Review | None = None,
    traces_dir: Path | None = None,
    replace: bool = False,
    arriving: Collection[str] | None = None,
) -> Landed:
    """Land reduced runs in the map at ``map_path``: the one landing of ``reduce`` and the
    batch, one locked atomic read-modify-write.

    **The map is read once more here, under its lock**: inside
    :func:`~tribopipe.frictionmap.store.update_map_with`, which reads the map while it
    holds ``<map>.lock``, so that the duplicate check, the review and the write see one
    map that no other writer can change in between. That is the one read a command makes
    besides its own (``reduce`` makes none before: :func:`check_map_before_work` reads no
    rows). ``choose(in_map)`` decides from the files the map holds by content
    (:func:`~tribopipe.frictionmap.duplicates.map_files_by_hash`) which records land and
    which rows go; it runs once. Then the repeat numbers the records would use twice are
    found, the review (``review``, else the one each reviewed row holds; ``traces_dir``:
    where this caller's traces are, for a re-read window) is applied in the same write
    (a decision that fails raises before anything is written), and the map is written
    only when something changed. ``replace``: records whose content differs from the
    map's row replace it.

    ``arriving``: the ids of every run the caller may bring, when it knows them before
    the map is read. Then a map folder is read as an append needs it
    (:data:`LANDING_COLUMNS` of every row, every column only of the parts the change
    touches), unless a review is given or one of those runs is reviewed in the map
    (the review reads whole rows); without ``arriving`` every column is read."""
    found: list[tuple[Arrivals, list[str], ReviewOutcome | None, dict[str, Any]]] = []

    def decide(current: pd.DataFrame) -> tuple[list[MapRow], Collection[str]]:
        arrivals = choose(map_files_by_hash(current))
        stale = set(arrivals.stale_ids)
        repeats = repeat_clashes(current, arrivals.records, stale)
        folded, outcome = landing_records(current, arrivals.records, stale, review,
                                          traces_dir)
        ids = stale | {r.measurement_id for r in folded}
        # each row's group as the map held it, for the groups a replacement leaves
        before = condition_keys(current.loc[current["measurement_id"].isin(ids)])
        found.append((Arrivals(folded, stale), repeats, outcome, before))
        return folded, stale

    def reviewed_again(current: pd.DataFrame) -> bool:  # then the review reads whole rows
        reviewed = current.loc[current["review"].notna(), "measurement_id"].astype(str)
        return bool(set(arriving or ()).intersection(reviewed))

    projected = arriving is not None and review is None
    appended = update_map_with(map_path, decide, replace=replace,
                               columns=LANDING_COLUMNS if projected else None,
                               needs_all=reviewed_again if projected else None)
    (arrivals, repeats, outcome, before) = found[0]
    landed = set(appended.added_ids) | set(appended.replaced_ids)
    touched = [r for r in arrivals.records if r.measurement_id in landed]
    groups = set(condition_keys(unvalidated_frame(touched)).values()) if touched else set()
    groups |= {k for mid, k in before.items() if mid in landed | set(appended.dropped_ids)}
    return Landed(appended=appended, repeats=tuple(repeats), review=outcome,
                  groups=frozenset(groups))


def check_map_before_work(map_path: str | Path) -> None:
    """Refuse a map that cannot take runs before any work, reading none of its rows: a
    map folder's manifest (its digest, every part named:
    :func:`~tribopipe.frictionmap.parts.read_manifest`), a single file's Parquet schema
    and metadata (:func:`~tribopipe.frictionmap.store.map_metadata`). No map yet is
    fine. A part damaged on disk is refused by the landing's read, before the map is
    written (the runs' traces are already written then). Raises
    :class:`~tribopipe.errors.MapError` in one line."""
    p = Path(map_path)
    if not (p.exists() or p.is_symlink()):
        return
    if p.is_dir():
        read_manifest(p)
    else:
        map_metadata(p)


@dataclass(frozen=True)
class StoreReport:
    """What :func:`store_runs` did: the map's :class:`AppendReport`, the runs of files
    the map already held under another name (duplicates left out, conflicts refused) and
    the repeat numbers now used twice in one condition
    (:func:`~tribopipe.frictionmap.duplicates.repeat_clashes`)."""

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


def arriving_ids(files: Sequence[FileOutcome]) -> set[str]:
    """The measurement ids of every run reduced in ``files`` (what a landing brings)."""
    return {r.record.measurement_id for f in files for r in f.reduced if r.record is not None}


def store_runs(map_path: str | Path, files: Sequence[FileOutcome], *,
               replace: bool = False) -> StoreReport:
    """``tribopipe reduce``'s landing (:func:`land_runs`): the records of the runs reduced
    in ``files`` appended to the map, each file checked against the map under its lock
    (:class:`ContentOwners`, the batch's check too): a file whose runs the map already
    holds under another file name is a duplicate (its records are left out, the map keeps
    the first name) or, where the labels differ, a conflict (refused, unless ``replace``).
    A run the map holds reviewed takes its review again (from its trace): never silently
    re-automated."""
    same: list[SameContent] = []
    traces = [r.trace for f in files for r in f.reduced if r.trace is not None]

    def choose(in_map: FilesByHash) -> Arrivals:
        owners = ContentOwners(in_map)
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
        return Arrivals(keep)

    landed = land_runs(map_path, choose, traces_dir=traces[0].parent if traces else None,
                       replace=replace, arriving=arriving_ids(files))
    return StoreReport(appended=landed.appended, same=tuple(same), repeats=landed.repeats)

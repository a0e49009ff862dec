"""The friction map on disk: its one reader, locked atomic writes, and every change.

Reading: :func:`read_map` is the one reader of a map file. It refuses in one
:class:`~tribopipe.errors.MapError` line, naming the path and where to restore the map
from (:func:`backup_path`, the previous version every rewrite keeps), a path that is not
a regular file (never opened), a file that is not Parquet or whose buffers or text are
damaged, a Parquet file without our metadata (a foreign file), a newer schema, a missing
column, a column stored with another Arrow type, a row that breaks
:func:`~tribopipe.frictionmap.schema.check_runs`, and a map whose rows fail the checksum
stored in its metadata (:func:`~tribopipe.frictionmap.schema.content_sha256`); the
writer puts that metadata in with :func:`map_info`.

Writing: every change to a map — append, update, merge, exclusion — is one
read-modify-write under a :mod:`filelock` lock on ``<map>.lock``, written to a temporary
file in the same folder (with the map's file mode), fsynced and renamed over the map
(:func:`_write_atomic`), the replaced map kept as ``<map>.bak``, so a killed writer leaves
the previous map intact. :func:`fold_records` is the pure core of an append. A file at
the map path that is not one of our maps is refused, never overwritten.
"""

from __future__ import annotations

import glob
import json
import math
import os
import shutil
import stat
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import __version__
from ..config import DEFAULT_TEST_METHOD
from ..errors import MapError, ReadError
from ..escape import display_path
from ..files import file_kind, fsync_dir, os_reason, regular_file
from ..memory import return_free_memory
from ..stats import GROUP_INPUT_COLUMNS, group_rows
from ..validate import text_problem
from .parts import (
    MANIFEST,
    GroupsFile,
    Manifest,
    Part,
    collect_garbage,
    commit,
    file_mode,
    manifest_path,
    read_groups_bytes,
    read_manifest,
    read_part_bytes,
    restore_hint,
    settle,
    write_groups,
    write_part,
)
from .schema import (
    ADDED_IN_VERSION,
    ADDED_LATER_CONTENT,
    COLUMNS,
    CONTENT_COLUMNS,
    KIND,
    META_KEY,
    RUN_COLUMNS,
    SCHEMA_NAME,
    SCHEMA_VERSION,
    MapRow,
    check_runs,
    columns_sha256,
    content_sha256,
    empty_map,
    frame_records,
    is_missing,
    records_frame,
    unvalidated_frame,
    utc_now,
)
from .stored_groups import (
    Key,
    groups_bytes,
    groups_differ,
    keys_of,
    of_keys,
    rows_from_bytes,
    updated,
)

if TYPE_CHECKING:
    import pandas as pd

#: Seconds to wait for another process's lock on the map before giving up.
LOCK_TIMEOUT_S = 60.0
#: whether Arrow decodes a map's Parquet parts and converts their rows with its thread
#: pool: no (measured at 10⁵ rows on a loaded 2-core machine, `bench/README.md`: the
#: pool's threads cost up to 0.15 s of kernel CPU per read, single-threaded decoding
#: 0.03 s)
PARQUET_THREADS = False


# --------------------------------------------------------------------------- writing


@contextmanager
def _locked(path: Path) -> Iterator[None]:
    """Hold ``<map>.lock`` while the body runs. The lock is the kernel's (``flock``), so it
    dies with the process that holds it: a lock file left by a killed command blocks
    nothing. A live holder makes this wait up to :data:`LOCK_TIMEOUT_S`, then refuse."""
    from filelock import FileLock, Timeout

    lock_path = Path(str(path) + ".lock")
    lock = FileLock(str(lock_path), timeout=LOCK_TIMEOUT_S)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        lock.acquire()
    except Timeout:
        raise MapError(
            f"friction map is locked by another process for more than {LOCK_TIMEOUT_S:g} s",
            path=path,
            hint=f"another tribopipe command is writing it; wait for it to finish (a killed "
                 f"process releases it: never delete {lock_path.name} by hand)",
        ) from None
    except NotImplementedError:  # an old filelock on a file system without flock
        raise MapError("cannot lock the friction map: its file system has no file locks",
                       path=path, hint="keep the map on a local disk") from None
    except OSError as exc:
        raise MapError(f"cannot lock the friction map ({exc.strerror or exc})", path=path,
                       hint="is the directory writable?") from None
    try:
        yield
    finally:
        lock.release()


def _clean_stale_temps(path: Path) -> None:
    # Under the lock, any temporary map beside ours belongs to a writer that died.
    for stale in path.parent.glob(f".{glob.escape(path.name)}.*.tmp"):
        with suppress(OSError):
            stale.unlink()


def _new_temp(path: Path) -> tuple[int, Path]:
    """A new temporary file beside ``path`` (its name matches :func:`_clean_stale_temps`)
    with the map's mode: the mode the map has, or for a new map ``0o666`` less the umask
    (``mkstemp`` would give ``0o600`` and take colleagues' read access away)."""
    import secrets

    try:
        mode = stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        mode = None
    for _ in range(100):
        tmp = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
        if mode is not None:
            with suppress(OSError):
                os.fchmod(fd, mode)
        return fd, tmp
    raise FileExistsError(f"no free temporary name beside {path}")  # pragma: no cover


def _keep_previous(path: Path) -> None:
    """Keep the map about to be replaced as ``<map>.bak`` (a hard link: no copy). The
    caller has just read and validated it; where links are impossible, no backup."""
    if not path.exists():
        return
    backup = backup_path(path)
    link = backup.with_name(f".{path.name}.{os.getpid()}.bak.tmp")
    try:
        with suppress(FileNotFoundError):
            link.unlink()
        os.link(path, link)
        os.replace(link, backup)
        # renaming a link over another link of the same file does nothing (POSIX): when
        # <map>.bak is already the map (a writer killed after linking it), drop ours
        with suppress(FileNotFoundError):
            link.unlink()
    except OSError:
        with suppress(OSError):
            link.unlink()


def _write_atomic(path: Path, runs: pd.DataFrame) -> None:
    """Write ``runs`` to ``path`` via a fsynced temporary file and an atomic rename, with
    the checksum of its content in the metadata, the previous map kept as ``<map>.bak``
    and the map's file mode kept.

    The caller holds the lock.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(runs.loc[:, list(RUN_COLUMNS)], preserve_index=False)
    meta = dict(table.schema.metadata or {})
    meta[META_KEY] = map_info(runs)
    table = table.replace_schema_metadata(meta)
    _clean_stale_temps(path)
    try:
        fd, tmp = _new_temp(path)
    except OSError as exc:
        raise MapError(f"cannot write the friction map ({os_reason(exc)})",
                       path=path) from None
    try:
        with os.fdopen(fd, "wb") as fh:
            pq.write_table(table, fh)
            fh.flush()
            os.fsync(fh.fileno())
        _keep_previous(path)
        os.replace(tmp, path)
    except BaseException as exc:
        with suppress(OSError):
            tmp.unlink()
        if isinstance(exc, OSError):  # disk full, permissions: the old map is untouched
            raise MapError(f"cannot write the friction map ({os_reason(exc)})",
                           path=path) from None
        raise
    fsync_dir(path.parent)


def write_map(path: str | os.PathLike[str], runs: pd.DataFrame) -> None:
    """Replace the map at ``path`` with ``runs`` (validated), atomically and under the lock.

    Refuses (``MapError``) to overwrite a file that is not a friction map.
    """
    p = Path(path)
    frame = records_frame(frame_records(runs), where="row")
    with _locked(p):
        if _writes_parts(p):
            _, _, manifest = _read_parts_map(p, ["measurement_id"])  # refuse a foreign one
            _commit_parts(p, manifest, [frame])
            return
        read_map(p)  # refuse foreign or corrupt files before replacing them
        _write_atomic(p, frame)


def write_map_copy(path: str | os.PathLike[str], runs: pd.DataFrame) -> Path:
    """Write ``runs`` (validated) as a new friction-map file at ``path`` without the map's
    lock: for a file in a folder no other process uses (a data package being written).
    Refuses (``MapError``) to replace an existing file."""
    p = Path(path)
    if p.exists():
        raise MapError("exists already; a map copy is written only to a new path", path=p)
    _write_atomic(p, check_runs(_schema_frame(runs), "row"))
    return p


class MapCopyWriter:
    """A new friction-map file at ``path`` written a batch of rows at a time, without the
    map's lock (a file in a folder no other process uses: a data package being written),
    so that a large map is never one DataFrame: each batch (:meth:`write`) is checked
    (:func:`~tribopipe.frictionmap.schema.check_runs`) and written as a row group of a
    temporary file; :meth:`finish` checks that ``n_runs`` rows came, fsyncs and renames
    it into place. The metadata (:func:`rows_info`: the rows' count, sources and
    checksum) is the caller's, computed column by column
    (:func:`~tribopipe.frictionmap.schema.columns_sha256`); a reader checks it against
    the rows as for any map. Used as a context manager: a writer left without
    :meth:`finish` (an error) removes its temporary file. Refuses (``MapError``) to
    replace an existing file."""

    def __init__(self, path: str | os.PathLike[str], n_runs: int, sources: Iterable[str],
                 digest: str) -> None:
        self.path = Path(path)
        if self.path.exists():
            raise MapError("exists already; a map copy is written only to a new path",
                           path=self.path)
        self._n_runs = n_runs
        self._info = rows_info(n_runs, sources, digest)
        self._written = 0
        self._writer: Any = None
        self._schema: Any = None
        self._fh: Any = None
        self._tmp: Path | None = None

    def __enter__(self) -> MapCopyWriter:
        fd, self._tmp = _new_temp(self.path)
        self._fh = os.fdopen(fd, "wb")
        return self

    def write(self, runs: pd.DataFrame) -> None:
        """Check the map rows ``runs`` and write them as the next row group."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        frame = check_runs(_schema_frame(runs), "row")
        table = pa.Table.from_pandas(frame.loc[:, list(RUN_COLUMNS)], preserve_index=False)
        table = table.replace_schema_metadata(None)
        if self._writer is None:
            self._schema = table.schema.with_metadata({META_KEY: self._info})
            self._writer = pq.ParquetWriter(self._fh, self._schema)
        self._writer.write_table(table.cast(self._schema))
        self._written += len(frame)

    def finish(self) -> Path:
        """Close the file, fsync it and rename it to :attr:`path`."""
        if self._writer is None:  # no rows: an empty map
            self.write(empty_map())
        if self._written != self._n_runs:
            raise MapError(f"{self._written} rows written, {self._n_runs} announced",
                           path=self.path)
        assert self._tmp is not None
        self._writer.close()
        self._fh.flush()
        os.fsync(self._fh.fileno())
        self._fh.close()
        os.replace(self._tmp, self.path)
        self._tmp = None
        fsync_dir(self.path.parent)
        return self.path

    def __exit__(self, *exc: object) -> None:
        if self._tmp is not None:  # not finished: nothing is left behind
            if self._writer is not None:
                with suppress(Exception):
                    self._writer.close()
            with suppress(OSError):
                self._fh.close()
            with suppress(OSError):
                self._tmp.unlink()
            self._tmp = None


def _schema_frame(runs: pd.DataFrame) -> pd.DataFrame:
    """``runs`` with the schema's columns, in order, each in its kind's dtype, converted
    column by column (what :func:`records_frame` makes of the same rows one by one,
    without a copy of every row); a value of another kind is a :class:`MapError` naming
    the column."""
    import pandas as pd

    out: dict[str, Any] = {}
    typed = {"float": "float64", "int": "Int64", "bool": "bool", "str": "str"}
    for name in RUN_COLUMNS:
        kind, col = KIND[name], runs[name]
        if str(col.dtype) == typed[kind]:  # already the schema's dtype: kept, not copied
            out[name] = col.array
            continue
        loose = col.dtype == object  # a column of a typed dtype holds its kind already
        try:
            if kind == "float":
                if loose and col.map(lambda v: isinstance(v, bool | str)).any():
                    raise TypeError("text or true/false is not a number")
                out[name] = pd.to_numeric(col, errors="raise").astype("float64").to_numpy()
            elif kind == "int":
                out[name] = pd.array(col.to_numpy(dtype=object), dtype="Int64")
            elif kind == "bool":
                if col.dtype != bool and not col.map(lambda v: isinstance(v, bool)).all():
                    raise TypeError("expected true or false")
                out[name] = col.astype(bool).to_numpy()
            else:
                if loose and not col.map(lambda v: is_missing(v) or isinstance(v, str)).all():
                    raise TypeError("expected text")
                texts = col.astype(object).where(col.notna(), None).to_numpy()
                out[name] = pd.array(texts, dtype="str")
        except (TypeError, ValueError, OverflowError) as exc:
            raise MapError(f"expected {kind} values ({exc})", column=name) from None
    return pd.DataFrame(out, columns=list(RUN_COLUMNS), index=pd.RangeIndex(len(runs)))


# --------------------------------------------------------------------------- appending


@dataclass(frozen=True)
class AppendReport:
    """What an append or merge did, by measurement id.

    ``added``: new runs; ``unchanged``: already in the map with the same content;
    ``replaced``: content differed and ``replace=True``; ``kept_conflicting``: content
    differed and the map's row was kept. ``differences`` maps each conflicting or replaced
    id to the names of the columns that differ, ``values`` to ``(column, map's value, new
    value)`` for each of them. ``dropped_ids``: rows removed by :func:`update_map`.
    """

    added_ids: tuple[str, ...] = ()
    unchanged_ids: tuple[str, ...] = ()
    replaced_ids: tuple[str, ...] = ()
    conflicting_ids: tuple[str, ...] = ()
    differences: dict[str, tuple[str, ...]] = field(default_factory=dict)
    dropped_ids: tuple[str, ...] = ()
    values: dict[str, tuple[tuple[str, Any, Any], ...]] = field(default_factory=dict)

    @property
    def added(self) -> int:
        """Number of runs added."""
        return len(self.added_ids)

    @property
    def unchanged(self) -> int:
        """Number of runs already present with identical content."""
        return len(self.unchanged_ids)

    @property
    def replaced(self) -> int:
        """Number of rows replaced (``replace=True``)."""
        return len(self.replaced_ids)

    @property
    def kept_conflicting(self) -> int:
        """Number of runs whose content differs from the map's row, which was kept."""
        return len(self.conflicting_ids)

    @property
    def changed(self) -> bool:
        """True when the map file was rewritten."""
        return bool(self.added_ids or self.replaced_ids or self.dropped_ids)

    def summary(self) -> str:
        """One line: ``3 added, 1 unchanged, 0 replaced, 1 kept (conflicting: ...)``."""
        text = (
            f"{self.added} added, {self.unchanged} unchanged, {self.replaced} replaced, "
            f"{self.kept_conflicting} kept conflicting"
        )
        if self.dropped_ids:
            text += f", {len(self.dropped_ids)} dropped"
        if self.conflicting_ids:
            details = "; ".join(
                f"{i} differs in {', '.join(self.differences.get(i, ()))}"
                for i in self.conflicting_ids[:5]
            )
            more = " …" if len(self.conflicting_ids) > 5 else ""
            text += f" ({details}{more}; pass --replace to overwrite)"
        return text

    def conflict_lines(self, theirs: str = "the new rows",
                       ids: Iterable[str] | None = None) -> list[str]:
        """One line per conflicting run (those of ``ids`` only, when given): its id and,
        per differing column, the map's value and the value in ``theirs``."""
        lines = []
        wanted = None if ids is None else set(ids)
        for mid in self.conflicting_ids:
            if wanted is not None and mid not in wanted:
                continue
            cells = "; ".join(
                f"{column} {_show(ours)} in the map, {_show(new)} in {theirs}"
                for column, ours, new in self.values.get(mid, ())
            )
            lines.append(f"conflict: run {mid}: {cells}; kept the map's row")
        return lines


def _show(value: Any) -> str:
    """A cell for a message: missing as 'missing', floats by repr, text quoted."""
    if is_missing(value):
        return "missing"
    return repr(value) if isinstance(value, str) else str(value)


def same_value(a: Any, b: Any) -> bool:
    if is_missing(a) and is_missing(b):
        return True
    if is_missing(a) or is_missing(b):
        return False
    if isinstance(a, float) or isinstance(b, float):
        # Platform noise in a re-reduction is not a different result.
        return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=1e-12)
    return a == b


#: content columns whose missing value in an older row means one value: a row written
#: before schema version 6 was measured on the founding rheometer cell
_MISSING_MEANS: dict[str, str] = {"test_method": DEFAULT_TEST_METHOD}


def _differences(old: Mapping[str, Any], new: Mapping[str, Any]) -> tuple[str, ...]:
    """The content columns where ``new`` differs from ``old`` (a column
    :data:`~tribopipe.frictionmap.schema.ADDED_LATER_CONTENT` missing in ``old`` is none,
    but a missing :data:`_MISSING_MEANS` column is that value)."""
    def value(row: Mapping[str, Any], c: str) -> Any:
        return _MISSING_MEANS[c] if c in _MISSING_MEANS and is_missing(row[c]) else row[c]

    return tuple(c for c in CONTENT_COLUMNS if not same_value(value(old, c), value(new, c))
                 and not (c in ADDED_LATER_CONTENT and c not in _MISSING_MEANS
                          and is_missing(old[c])))


def fold_records(
    runs: pd.DataFrame, records: Sequence[MapRow], *, replace: bool = False
) -> tuple[pd.DataFrame, AppendReport]:
    """Pure core of :func:`append_records`: the map with ``records`` folded in, and the report.

    Existing rows keep their position; new runs are added at the end in the given order.
    A replaced row keeps the map's exclusion state (a human decision about the run),
    unless the record or the row holds a review (:mod:`tribopipe.review`), which decides
    the exclusion itself.
    Neither input is modified. Every row of the result keeps the rules of
    :func:`~tribopipe.frictionmap.schema.check_runs` (``runs`` may come from anywhere).
    """
    base = check_runs(runs.loc[:, list(RUN_COLUMNS)].reset_index(drop=True), "row")
    return _fold(base, records_frame(records), replace=replace)


def _fold(
    runs: pd.DataFrame, new_frame: pd.DataFrame, *, replace: bool
) -> tuple[pd.DataFrame, AppendReport]:
    """:func:`fold_records` of records already validated into ``new_frame``; the rows
    of ``runs`` are not checked again (:func:`update_map` has them from :func:`read_map`,
    which checked every one), nor are the rows of ``new_frame``."""
    import numpy as np
    import pandas as pd

    base = runs.loc[:, list(RUN_COLUMNS)].reset_index(drop=True)
    position = {m: i for i, m in enumerate(base["measurement_id"])}
    # a new row whose id is neither in the map nor repeated among the new rows is added
    # as it is, column-wise; only the others are compared record by record
    new_ids = new_frame["measurement_id"]
    plain = np.asarray(~new_ids.isin(list(position)) & ~new_ids.duplicated(keep=False),
                       dtype=bool)
    new_frame = new_frame.reset_index(drop=True)
    others = new_frame.loc[~plain]
    # map rows looked at (then replaced), by position: converted in one pass, not per record
    hits = sorted({position[m] for m in others["measurement_id"] if m in position})
    touched = dict(zip(hits, frame_records(base.iloc[hits]), strict=True))
    fresh: dict[str, dict[str, Any]] = {}  # runs new to the map, in order (= the added ids)
    # ids in first-seen order (dicts as ordered sets: a repeated id keeps its place)
    unchanged: dict[str, None] = {}
    replaced: dict[str, None] = {}
    conflicting: dict[str, None] = {}
    differences: dict[str, tuple[str, ...]] = {}
    values: dict[str, tuple[tuple[str, Any, Any], ...]] = {}
    first_at: dict[str, int] = {}  # where each fresh run of the others first came
    for at, rec in zip(others.index, frame_records(others), strict=True):
        mid = rec["measurement_id"]
        first_at.setdefault(mid, int(at))
        if mid in fresh:
            old = fresh[mid]
        elif mid in position:
            old = touched[position[mid]]
        else:
            fresh[mid] = rec
            continue
        diff = _differences(old, rec)
        if not diff:
            if mid not in fresh:
                unchanged[mid] = None
            continue
        differences[mid] = diff
        values[mid] = tuple((c, old[c], rec[c]) for c in diff)
        if replace:
            if is_missing(rec.get("review")) and is_missing(old.get("review")):
                rec = {**rec, "excluded": old["excluded"],
                       "exclusion_reason": old["exclusion_reason"]}
            if mid in fresh:
                fresh[mid] = rec
            else:
                touched[position[mid]] = rec
                replaced[mid] = None
        else:
            conflicting[mid] = None
    # the added runs in the order they came: the plain rows and the first of the others
    order = sorted([(int(i), None) for i in np.flatnonzero(plain)]
                   + [(first_at[m], m) for m in fresh], key=lambda x: x[0])
    added = [str(new_ids.iat[i]) if m is None else m for i, m in order]
    report = AppendReport(
        added_ids=tuple(added),
        unchanged_ids=tuple(unchanged),
        replaced_ids=tuple(replaced),
        conflicting_ids=tuple(conflicting),
        differences=differences,
        values=values,
    )
    merged = base
    if replaced:
        where = [position[mid] for mid in replaced]
        swapped = unvalidated_frame([touched[i] for i in where], where="row")
        swapped.index = pd.Index(where)
        merged = pd.concat([merged.drop(index=where), swapped]).sort_index()
    if order:
        extra = new_frame.loc[plain, list(RUN_COLUMNS)]
        if fresh:
            others_fresh = unvalidated_frame(list(fresh.values()), where="record")
            others_fresh.index = pd.Index([first_at[m] for m in fresh])
            extra = pd.concat([extra, others_fresh]).sort_index()
        merged = pd.concat([merged, extra], ignore_index=True) if len(merged) else extra
    return merged.reset_index(drop=True), report


def append_records(
    path: str | os.PathLike[str],
    records: Sequence[MapRow],
    *,
    replace: bool = False,
) -> AppendReport:
    """Append run records to the map at ``path`` (created if absent).

    Idempotent: a run already present with the same content is left alone; a run whose
    content differs replaces its row only when ``replace`` is true. The records are
    validated before the lock is taken, and the file is rewritten (atomically) only when
    something was added or replaced, so a failing append leaves the map byte-identical.
    """
    return update_map(path, records, replace=replace)


def append_frame(path: str | os.PathLike[str], runs: pd.DataFrame, *,
                 replace: bool = False) -> AppendReport:
    """:func:`append_records` of rows already in a map DataFrame (another map's or a
    package's runs), converted and checked column by column: no row object per run, so a
    merge of 10⁵ rows does not hold them twice over."""
    p = Path(path)
    new_frame = check_runs(_schema_frame(runs), "row")  # validate before touching anything
    with _locked(p):
        if _writes_parts(p):
            return _update_parts(p, lambda _: (new_frame, ()), replace)[0]
        return _fold_and_write(p, read_map(p), new_frame, replace, ())[0]


def update_map(
    path: str | os.PathLike[str],
    records: Sequence[MapRow],
    *,
    replace: bool = False,
    drop_ids: Iterable[str] = (),
) -> AppendReport:
    """:func:`append_records` that also removes the rows ``drop_ids`` (e.g. runs whose raw
    file changed), in the same locked read-modify-write and one atomic write.

    Ids in ``drop_ids`` that are also among ``records`` are not dropped; unknown ids are
    ignored. Validation happens before anything is touched.
    """
    p = Path(path)
    new_frame = records_frame(records)  # validate before touching anything
    with _locked(p):
        if _writes_parts(p):
            # the fold reads the ids of every row, every column only of the parts
            # holding a run it compares, replaces or drops
            return _update_parts(p, lambda _: (new_frame, drop_ids), replace, ())[0]
        # the locked read-modify-write: the map read again under the lock
        return _fold_and_write(p, read_map(p), new_frame, replace, drop_ids)[0]


#: what to fold into a map, decided from the map as it is: the records and the ids to drop
MapChange = tuple[Sequence[MapRow], Iterable[str]]
#: a :data:`MapChange` with the records checked into a frame
FrameChange = tuple["pd.DataFrame", Iterable[str]]


def update_map_with(
    path: str | os.PathLike[str],
    decide: Callable[[pd.DataFrame], MapChange],
    *,
    replace: bool = False,
    columns: Sequence[str] | None = None,
    needs_all: Callable[[pd.DataFrame], bool] | None = None,
) -> AppendReport:
    """:func:`update_map` with the records and the ids to drop decided by
    ``decide(current)`` from the map as read under its lock, so that a check against the
    map (the same content under another name) cannot race another writer. ``decide``
    runs once; the map is rewritten only when something changed. ``columns``: the map
    columns ``decide`` reads (``measurement_id`` always; all when ``None``), and
    ``needs_all(rows)``: whether, given those columns of the map's rows, ``decide``
    needs every column after all (:func:`change_map_with`). The map's rows after the
    change are not made: the landing of ``reduce`` and the batch
    (:func:`~tribopipe.pipeline.landing.land_runs`) shows none."""
    return _change_map_with(path, decide, replace, columns, needs_all, after=False)[0]


def change_map_with(
    path: str | os.PathLike[str],
    decide: Callable[[pd.DataFrame], MapChange],
    *,
    replace: bool = False,
    columns: Sequence[str] | None = None,
    needs_all: Callable[[pd.DataFrame], bool] | None = None,
) -> tuple[AppendReport, pd.DataFrame]:
    """:func:`update_map_with`, returning also the rows of the map as this change left it
    (in the map's order; the columns ``decide`` was given), so that a command that shows
    the map after its write need not read it again.

    In a map folder, an append costs what it adds: under the lock it reads ``columns`` of
    every row (Parquet's column projection), and every column only of the parts holding a
    run the change compares, replaces or drops; it writes the new rows as a new part and
    rewrites only the parts where a row changed. A single-file map (the format before
    parts) is read and rewritten whole."""
    report, rows = _change_map_with(path, decide, replace, columns, needs_all, after=True)
    assert rows is not None
    return report, rows


def _change_map_with(path: str | os.PathLike[str], decide: Callable[[pd.DataFrame], MapChange],
                     replace: bool, columns: Sequence[str] | None,
                     needs_all: Callable[[pd.DataFrame], bool] | None, *, after: bool
                     ) -> tuple[AppendReport, pd.DataFrame | None]:
    """:func:`change_map_with`; the rows after the change only when ``after``. What the
    change read and wrote is handed back to the system once it is done
    (:func:`~tribopipe.memory.return_free_memory`): a batch lands again and again, and
    each landing's Arrow buffers and C heap would otherwise stay with the process beside
    the next one's."""
    p = Path(path)

    def checked(current: pd.DataFrame) -> FrameChange:
        records, drop_ids = decide(current)
        return records_frame(records), drop_ids

    try:
        with _locked(p):
            # A command that appends reads the map once more here, under the lock: the
            # check against the map and the write see one map, which no other writer can
            # change in between.
            if _writes_parts(p):
                return _update_parts(p, checked, replace, columns, needs_all, after)
            new_frame, drop_ids = checked(current := read_map(p))
            report, rows = _fold_and_write(p, current, new_frame, replace, drop_ids)
            return report, rows if columns is None else _select(
                rows, ["measurement_id", *columns])
    finally:
        return_free_memory(collect=False)


def _writes_parts(p: Path) -> bool:
    """True when a change of the map at ``p`` is committed as parts: a map folder, or no
    map yet (a new map is a folder); a single-file map is rewritten whole until it is
    converted (:func:`upgrade_map`)."""
    return p.is_dir() or not (p.exists() or p.is_symlink())


def _fold_and_write(p: Path, current: pd.DataFrame, new_frame: pd.DataFrame, replace: bool,
                    drop_ids: Iterable[str]) -> tuple[AppendReport, pd.DataFrame]:
    """Fold validated records into the map read under the lock, drop ``drop_ids`` and
    write it atomically when something changed. The caller holds the lock."""
    import dataclasses

    drop = set(drop_ids) - set(new_frame["measurement_id"])
    gone = current["measurement_id"].isin(sorted(drop)).to_numpy()
    merged, report = _fold(current.loc[~gone], new_frame, replace=replace)
    report = dataclasses.replace(
        report, dropped_ids=tuple(current.loc[gone, "measurement_id"].astype(str))
    )
    if report.changed:
        _write_atomic(p, merged)
        return report, merged
    return report, current


# --------------------------------------------------------------------------- exclusions


def _resolve_ids(runs: pd.DataFrame, ids: Iterable[str], path: Path) -> list[int]:
    known = list(runs["measurement_id"])
    positions = []
    for given in ids:
        hits = [i for i, m in enumerate(known) if m == given]
        if not hits and len(given) >= 6:
            hits = [i for i, m in enumerate(known) if m.startswith(given)]
        if not hits:
            raise MapError(
                f"no run with measurement id {given!r}",
                path=path,
                hint="`tribopipe map show` lists the ids",
            )
        if len(hits) > 1:
            raise MapError(f"id prefix {given!r} matches {len(hits)} runs", path=path,
                           hint="give more digits")
        positions.append(hits[0])
    return positions


def set_excluded(
    path: str | os.PathLike[str], ids: Sequence[str], *, reason: str | None
) -> list[str]:
    """Exclude runs from the statistics (``reason`` given) or include them again
    (``reason=None``). Ids may be given as unique prefixes of at least 6 digits.

    The runs stay in the map with the reason recorded; returns the full ids changed.
    Raises :class:`MapError` for an unknown id or an empty reason.
    """
    p = Path(path)
    if reason is not None and not reason.strip():
        raise MapError("an exclusion needs a reason", path=p, hint="pass --reason TEXT")
    problem = None if reason is None else text_problem(reason.strip(), 1000)
    if problem is not None:
        raise MapError(f"the reason: {problem}", path=p, hint="pass --reason TEXT")
    if not p.exists():
        raise MapError("friction map not found", path=p, hint="pass --map PATH")
    with _locked(p):
        # the locked read-modify-write: the map read under the lock (a map folder: the
        # columns the decision reads, then every column of the parts it changes only)
        parts_map = p.is_dir()
        if parts_map:
            runs, _, manifest = _read_parts_map(p, (*EXCLUSION_COLUMNS,
                                                    *GROUP_INPUT_COLUMNS))
        else:
            runs = read_map(p)
        positions = _resolve_ids(runs, ids, p)
        new_state = (reason is not None, None if reason is None else reason.strip())
        changed_at = [i for i in dict.fromkeys(positions)
                      if (bool(runs["excluded"].iat[i]),
                          _or_none(runs["exclusion_reason"].iat[i])) != new_state]
        changed = [str(runs["measurement_id"].iat[i]) for i in changed_at]
        if changed and parts_map:
            assert manifest is not None
            owner = _owner(manifest)
            rewritten = {}
            touched: set[Key] = set()
            for k in sorted({int(owner[i]) for i in changed_at}):
                rows = _read_parts(p, [manifest.parts[k]])
                where = rows["measurement_id"].isin(changed).to_numpy()
                touched |= keys_of(rows.loc[where])
                _set_state(rows, where, new_state)
                rewritten[k] = rows

            def frame_of(k: int) -> pd.DataFrame:
                assert manifest is not None
                return rewritten[k] if k in rewritten else _read_parts(p, [manifest.parts[k]])

            _change_parts(p, manifest, rewritten, None, frame_of, touched,
                          _by_part(runs, manifest, owner))
        elif changed:
            new = runs.copy()
            _set_state(new, new["measurement_id"].isin(changed).to_numpy(), new_state)
            # rows read (and checked) with a checked reason: not checked a second time
            _write_atomic(p, unvalidated_frame(frame_records(new), where="row"))
    return changed


#: the columns an exclusion or inclusion decides from
EXCLUSION_COLUMNS: tuple[str, ...] = ("measurement_id", "excluded", "exclusion_reason")


def _set_state(rows: pd.DataFrame, where: Any, state: tuple[bool, str | None]) -> None:
    """Set the exclusion ``state`` (excluded, reason) of the rows ``where`` (a mask), in
    place."""
    rows.loc[where, "excluded"] = state[0]
    rows.loc[where, "exclusion_reason"] = state[1]


def _or_none(value: Any) -> Any:
    return None if is_missing(value) else value


def exclude_runs(path: str | os.PathLike[str], ids: Sequence[str], reason: str) -> list[str]:
    """Leave runs out of the statistics, recording why; returns the ids changed."""
    if reason is None:
        raise MapError("an exclusion needs a reason", path=path, hint="pass --reason TEXT")
    return set_excluded(path, ids, reason=reason)


def include_runs(path: str | os.PathLike[str], ids: Sequence[str]) -> list[str]:
    """Take excluded runs back into the statistics; returns the ids changed."""
    return set_excluded(path, ids, reason=None)


# --------------------------------------------------------------------------- reading


def backup_path(path: str | os.PathLike[str]) -> Path:
    """Where the previous version of the map at ``path`` is kept: ``<map>.bak`` (a hard
    link made by every rewrite, so it costs no copy)."""
    p = Path(path)
    return p.with_name(p.name + ".bak")


def _restore_hint(path: Path) -> str:
    if path.is_dir():
        return restore_hint(path)
    backup = backup_path(path)
    try:
        kept = backup.is_file()
    except OSError:
        kept = False
    if kept:
        return f"restore it from {display_path(backup)} (its previous version) or a backup"
    return "restore it from a backup"


def _damaged(path: Path, problem: str) -> MapError:
    """A map that cannot be read as ours: one line, with where to restore it from."""
    return MapError(problem, path=path, hint=_restore_hint(path) +
                    "; the file is never overwritten, or pass another --map")


def read_map(path: str | os.PathLike[str]) -> pd.DataFrame:
    """Read and validate a friction map; an absent file is an empty map.

    A map of an older schema version reads with the columns added since
    (:data:`~tribopipe.frictionmap.schema.ADDED_IN_VERSION`) missing; the next write stores
    it in the current version. Raises :class:`MapError` (one line naming the path) when
    the path is not a regular file (a folder, a FIFO, a device: never opened), the file is
    not Parquet, is a Parquet file without tribopipe's schema metadata (a foreign file),
    was written by a newer schema, lacks columns, stores a column with another type, holds
    a row that breaks the rules of :func:`~tribopipe.frictionmap.schema.check_runs`, or
    fails its checksum (the SHA-256 of its content stored in its metadata when it was
    written: a map changed outside tribopipe, or damaged on disk, is refused rather than
    read with other values). A map written before the checksum existed is read, and
    gains one on its next write.

    A map folder of parts (:mod:`~tribopipe.frictionmap.parts`) is read through its
    manifest, each part checked against its SHA-256 there. A command opens a map once, as
    a :class:`~tribopipe.frictionmap.snapshot.MapSnapshot`; this is the snapshot's rows.
    """
    return load_map(path)[0]


def load_map(path: str | os.PathLike[str], columns: Sequence[str] | None = None
             ) -> tuple[pd.DataFrame, dict[str, Any]]:
    """The one reader of a friction map: its rows (the map's ``columns`` only, all when
    ``None``) and its metadata (as :func:`map_metadata` gives it). A map folder of parts
    reads only those columns of each part, after checking the part's bytes against the
    manifest's SHA-256 (its rows were checked as they came in: ``map validate`` checks
    them all again); a single-file map (the format before parts) is read and checked
    whole, as :func:`read_map` describes. Raises :class:`MapError` in one line."""
    p = Path(path)
    try:
        st = os.stat(p)
    except FileNotFoundError:
        _refuse_interrupted_upgrade(p)
        return _select(empty_map(), columns), _empty_info()
    except OSError as exc:
        raise MapError(f"cannot read the friction map: {os_reason(exc)}", path=p) from None
    if stat.S_ISDIR(st.st_mode):
        runs, info, _ = _read_parts_map(p, columns)
        return runs, info
    if not stat.S_ISREG(st.st_mode):
        raise MapError(f"is {file_kind(st.st_mode)}, expected a friction-map Parquet file; "
                       "not opened", path=p, hint="pass another --map")
    runs, info = _read_file_map(p)
    return _select(runs, columns), info


def _select(runs: pd.DataFrame, columns: Sequence[str] | None) -> pd.DataFrame:
    if columns is None:
        return runs
    return runs.loc[:, _wanted(columns)]


def _wanted(columns: Sequence[str]) -> list[str]:
    """``columns`` in the map's order; an unknown name is refused."""
    unknown = sorted(set(columns) - set(RUN_COLUMNS))
    if unknown:
        raise MapError(f"no map column named {', '.join(unknown)}")
    return [c for c in RUN_COLUMNS if c in set(columns)]


def _empty_info() -> dict[str, Any]:
    return {"schema": SCHEMA_NAME, "schema_version": SCHEMA_VERSION, "n_runs": 0,
            "sources": [], "format": "none"}


def _read_file_map(p: Path) -> tuple[pd.DataFrame, dict[str, Any]]:
    """A single-file map (the format before parts), read and checked whole."""
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(p)
        # every buffer checked, text for valid UTF-8 too (Parquet readers do not)
        table.validate(full=True)
        table.column_names  # noqa: B018 - names that are not UTF-8 raise here
    except Exception as exc:  # noqa: BLE001 - pyarrow raises many types for a damaged file
        raise _damaged(p, f"not a readable Parquet file ({_first_line(exc)})") from None
    info = _check_metadata(table.schema.metadata or {}, p)
    table = _with_added_columns(table, info["schema_version"])
    absent = [c for c in RUN_COLUMNS if c not in table.column_names]
    if absent:
        raise MapError(f"friction map lacks column(s) {', '.join(absent)}", path=p,
                       column=absent[0], hint=_restore_hint(p))
    try:
        runs = _from_arrow(table.select(list(RUN_COLUMNS)))
    except MapError as exc:
        raise MapError(exc.problem, path=p, column=exc.column,
                       hint=_restore_hint(p)) from None
    stored = info.get("content_sha256")
    if stored is not None and stored != content_sha256(runs, info["schema_version"]):
        raise MapError(
            f"the map at {display_path(p)} fails its checksum: its rows are not those "
            "tribopipe wrote (damaged on disk, or changed by another program); refusing to "
            f"read or overwrite it; {_restore_hint(p)}"
        )
    _refuse_duplicates(p, runs["measurement_id"])
    return runs, info


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    first = text.splitlines()[0][:160] if text else ""
    return f"{type(exc).__name__}: {first}" if first else type(exc).__name__


def map_metadata(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The schema and provenance a map carries in its Parquet metadata: ``schema``,
    ``schema_version``, ``columns`` (name, kind, unit, meaning), ``tribopipe_version`` and
    ``written_at`` of the last write, ``n_runs``, ``sources``, ``content_sha256``.
    Validated like :func:`read_map` (the rows are not read). A map folder of parts
    gives its manifest's account instead of ``content_sha256``: ``format`` ``"parts"``,
    ``generation`` and ``parts`` (each part's checksum is in the manifest)."""
    import pyarrow.parquet as pq

    p = Path(path)
    if p.is_dir():
        return load_map(p, ["measurement_id"])[1]
    try:
        regular_file(p, what="a friction-map Parquet file")
        schema = pq.read_schema(p)
    except ReadError as exc:
        raise MapError(exc.problem, path=p) from None
    except Exception as exc:  # noqa: BLE001 - pyarrow raises many types for a damaged file
        raise _damaged(p, f"not a readable Parquet file ({_first_line(exc)})") from None
    return _check_metadata(schema.metadata or {}, p)


def _with_added_columns(table: Any, version: int,
                        columns: Sequence[str] = RUN_COLUMNS) -> Any:
    """``table`` with the columns (of ``columns``) a map of schema ``version`` could not
    have had (those of :data:`ADDED_IN_VERSION` added later) appended as all missing."""
    import pyarrow as pa

    types = {"str": pa.string(), "float": pa.float64(), "int": pa.int64()}
    for name in columns:
        if name not in table.column_names and ADDED_IN_VERSION.get(name, 1) > version:
            table = table.append_column(name, pa.nulls(table.num_rows, types[KIND[name]]))
    return table


def _arrow_type_ok(kind: str, arrow_type: Any) -> bool:
    """True when a column of ``kind`` may be stored as ``arrow_type``."""
    import pyarrow as pa

    if pa.types.is_null(arrow_type):
        return True
    if kind == "float":
        return pa.types.is_floating(arrow_type) or pa.types.is_integer(arrow_type)
    if kind == "int":
        return pa.types.is_integer(arrow_type)
    if kind == "bool":
        return pa.types.is_boolean(arrow_type)
    return pa.types.is_string(arrow_type) or pa.types.is_large_string(arrow_type)


def _from_arrow(table: Any, columns: Sequence[str] = RUN_COLUMNS, *,
                check: bool = True) -> pd.DataFrame:
    """The map DataFrame of an Arrow table of the run columns, coerced column by column
    (vectorised: the read path of every command) and validated. Each column must be
    stored with an Arrow type of its kind (``excluded`` stored as the text ``"false"`` is
    refused, not read as true). ``columns``: those to read (in the map's order);
    ``check``: apply :func:`~tribopipe.frictionmap.schema.check_runs` (a full set of
    columns only; parts whose checksum the manifest vouches for were checked as they came
    in)."""
    import pandas as pd

    for name in columns:
        arrow_type = table.schema.field(name).type
        if not _arrow_type_ok(KIND[name], arrow_type):
            kind = KIND[name]
            raise MapError(f"expected {kind} values, stored as {arrow_type}, not "
                           f"{'text' if kind == 'str' else kind}", column=name)
    try:
        # our own columns only, without the pandas metadata (a damaged copy of it must
        # not decide how the rows are read)
        frame = table.replace_schema_metadata(None).to_pandas(ignore_metadata=True,
                                                              use_threads=PARQUET_THREADS)
    except Exception as exc:  # noqa: BLE001 - a damaged column
        raise MapError(f"cannot read the rows ({_first_line(exc)})") from None
    out = {name: _typed_cells(name, frame[name]) for name in columns}
    runs = pd.DataFrame(out, columns=list(columns), index=pd.RangeIndex(len(frame)))
    return check_runs(runs, "row") if check else runs


def _typed_cells(name: str, col: Any) -> Any:
    """The cells of the map column ``name`` as pandas read them from Arrow (``col``), in
    the dtype of its kind (:func:`_from_arrow`, a column at a time)."""
    import pandas as pd

    kind = KIND[name]
    try:
        if kind == "float":
            return pd.to_numeric(col, errors="raise").astype("float64").to_numpy()
        if kind == "int":
            return pd.array(col, dtype="Int64")
        if kind == "bool":
            if col.isna().any():
                raise ValueError("missing true/false")
            return col.astype(bool).to_numpy()
        if col.dtype == "str":  # Arrow text as pandas reads it: no copy
            return col.array
        return pd.array(col.astype(object).where(col.notna(), None), dtype="str")
    except (TypeError, ValueError, OverflowError) as exc:
        raise MapError(f"expected {kind} values ({exc})", column=name) from None


def _check_metadata(metadata: Mapping[bytes, bytes], path: Path) -> dict[str, Any]:
    raw = metadata.get(META_KEY)
    if raw is None:
        raise MapError(
            "a Parquet file, but not a tribopipe friction map (no 'tribopipe.frictionmap' "
            "schema metadata); refusing to read or overwrite it",
            path=path,
            hint="pass another --map",
        )
    try:
        info = json.loads(raw)
    except (ValueError, UnicodeDecodeError, RecursionError):
        raise _damaged(path, "friction-map metadata is not valid JSON") from None
    if not isinstance(info, dict) or info.get("schema") != SCHEMA_NAME:
        raise _damaged(path, "friction-map metadata names another schema")
    version = info.get("schema_version")
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise _damaged(path, f"friction-map schema version {version!r} is not a version")
    if version > SCHEMA_VERSION:
        raise MapError(
            f"friction-map schema version {version!r}; this tribopipe reads up to "
            f"{SCHEMA_VERSION}",
            path=path,
            hint="upgrade tribopipe",
        )
    digest = info.get("content_sha256")
    if digest is not None and not (isinstance(digest, str) and len(digest) == 64):
        raise _damaged(path, "friction-map metadata holds a damaged checksum")
    return info



def map_info(runs: pd.DataFrame) -> bytes:
    """The JSON our Parquet metadata key holds for ``runs``: the schema (every column's
    kind, unit and meaning), the writing version and time, the sources and the checksum
    of the rows."""
    return rows_info(len(runs), runs["source"].dropna(), content_sha256(runs))


def rows_info(n_runs: int, sources: Iterable[str], digest: str) -> bytes:
    """:func:`map_info` of ``n_runs`` rows naming ``sources`` whose
    :func:`~tribopipe.frictionmap.schema.content_sha256` is ``digest``."""
    info = {
        "schema": SCHEMA_NAME,
        "schema_version": SCHEMA_VERSION,
        "columns": [
            {"name": c.name, "kind": c.kind, "unit": c.unit, "meaning": c.meaning}
            for c in COLUMNS
        ],
        "tribopipe_version": __version__,
        "written_at": utc_now(),
        "n_runs": n_runs,
        "sources": sorted(set(sources)),
        "content_sha256": digest,
    }
    return json.dumps(info, ensure_ascii=False).encode()


# --------------------------------------------------------------------------- parts


def _folder_manifest(p: Path) -> Manifest | None:
    """The committed manifest of the map folder ``p``; ``None`` for a folder holding
    nothing of a map yet (empty, or only a killed writer's temporary files): an empty
    map. A folder with anything else but no manifest is refused."""
    if manifest_path(p).exists() or manifest_path(p).is_symlink():
        return read_manifest(p)
    try:
        others = [e.name for e in p.iterdir()
                  if not (e.name.startswith(".") and e.name.endswith(".tmp"))]
    except OSError as exc:
        raise MapError(f"cannot read the map folder ({os_reason(exc)})", path=p) from None
    if others:
        raise MapError(f"a folder that is not a friction map (no {MANIFEST}); refusing to "
                       "read or write into it", path=p, hint="pass another --map")
    return None


def _read_parts_map(p: Path, columns: Sequence[str] | None = None, *, full: bool = False
                    ) -> tuple[pd.DataFrame, dict[str, Any], Manifest | None]:
    """The rows (``columns`` only) and metadata of the map folder ``p``, and its manifest.
    Each part's bytes are checked against the manifest before they are parsed; ``full``
    checks more, as ``map validate`` does: every buffer, each part's rows against the
    checksum of its content in its own metadata, and every row against the row rules."""
    if not p.exists():
        _refuse_interrupted_upgrade(p)
    manifest = _folder_manifest(p) if p.exists() else None
    if manifest is None:
        return _select(empty_map(), columns), {**_empty_info(), "format": "parts"}, None
    runs = _read_parts(p, manifest.parts, columns, full=full)
    return runs, _parts_info(manifest), manifest


def _parts_info(manifest: Manifest) -> dict[str, Any]:
    """The metadata of a map folder committed as ``manifest`` (as :func:`load_map` gives
    it)."""
    versions = [part.schema_version for part in manifest.parts]
    info = {
        "schema": SCHEMA_NAME,
        "schema_version": max(versions) if versions else SCHEMA_VERSION,
        "columns": _columns_info(),
        "tribopipe_version": manifest.tribopipe_version,
        "written_at": manifest.written_at,
        "n_runs": manifest.n_runs,
        "sources": list(manifest.sources),
        "format": "parts",
        "generation": manifest.generation,
        "parts": len(manifest.parts),
        # the commit's parts, so that rows of this read can be read whole later
        # (:func:`rows_by_id`) from the same parts, whatever was committed since
        "part_list": manifest.parts,
    }
    if manifest.groups is not None:
        info["groups"] = manifest.groups.as_json()
    return info


def _read_parts(p: Path, parts: Iterable[Part], columns: Sequence[str] | None = None, *,
                full: bool = False) -> pd.DataFrame:
    """The rows (``columns`` only, all when ``None``) of ``parts`` (in that order) of the
    map folder ``p``, each part's bytes checked against the manifest's checksum first
    (``full``: as :func:`_read_parts_map`). Only the columns asked for are parsed
    (Parquet's column projection)."""
    wanted = list(RUN_COLUMNS) if columns is None else _wanted(columns)
    table = _read_parts_table(p, parts, wanted, full=full)
    try:
        runs = _from_arrow(table, wanted, check=full)
    except MapError as exc:
        raise MapError(exc.problem, path=p, column=exc.column) from None
    if "measurement_id" in wanted:
        _refuse_duplicates(p, runs["measurement_id"])
    return runs


def _refuse_duplicates(p: Path, ids: pd.Series) -> None:
    """Raise :class:`MapError` naming the first measurement id seen twice in ``ids``."""
    if ids.duplicated().any():
        dup = ids.loc[ids.duplicated()].iloc[0]
        raise MapError(f"duplicate measurement_id {dup}", path=p, column="measurement_id")


def _read_parts_table(p: Path, parts: Iterable[Part], wanted: Sequence[str], *,
                      full: bool = False) -> Any:
    """The columns ``wanted`` (in the map's order) of ``parts`` of the map folder ``p`` as
    one Arrow table, each part checked as :func:`_read_parts` says (the rows themselves
    are checked by the caller)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    wanted = list(wanted)
    tables = []
    for part in parts:
        data = read_part_bytes(p, part)
        try:
            file = pq.ParquetFile(pa.BufferReader(data))  # its footer parsed once
            # one thread: a part is a few MB, and on a loaded machine Arrow's thread pool
            # costs more CPU in the kernel than it saves (PARQUET_THREADS)
            table = file.read(columns=_stored(file.schema_arrow, wanted),
                              use_threads=PARQUET_THREADS)
            meta = table.schema.metadata or {}
        except Exception as exc:  # noqa: BLE001 - pyarrow raises many types
            raise MapError(f"part {part.file}: not a readable Parquet file "
                           f"({_first_line(exc)})", path=p) from None
        info = _check_metadata(meta, p)
        if table.num_rows != part.n_runs or info["schema_version"] != part.schema_version:
            raise MapError(f"part {part.file} is not the part its manifest names", path=p)
        if full:
            _verify_part(p, part.file, table, info)
        table = _with_added_columns(table, part.schema_version, wanted)
        absent = [c for c in wanted if c not in table.column_names]
        if absent:
            raise MapError(f"part {part.file} lacks column(s) {', '.join(absent)}", path=p,
                           column=absent[0])
        tables.append(table.select(wanted).replace_schema_metadata(None))
    if tables:
        return pa.concat_tables(tables, promote_options="permissive")
    return pa.Table.from_pandas(empty_map().loc[:, wanted], preserve_index=False)


def load_map_table(path: str | os.PathLike[str]) -> tuple[Any, dict[str, Any]]:
    """The map at ``path`` as one Arrow table of every run column (as stored; the columns
    added since a part's schema version all missing) and its metadata, checked as
    :func:`load_map` checks it: a map folder's parts against the manifest, each id once;
    a single-file map whole. For a command that goes through the rows a batch or a
    column at a time (:func:`frame_of_table`) instead of holding them all as a
    DataFrame (``map publish``). Raises :class:`MapError` in one line."""
    import pyarrow as pa

    p = Path(path)
    if p.is_dir():
        manifest = _folder_manifest(p)
        if manifest is None:
            return (pa.Table.from_pandas(empty_map(), preserve_index=False),
                    {**_empty_info(), "format": "parts"})
        table = _read_parts_table(p, manifest.parts, RUN_COLUMNS)
        _refuse_duplicates(p, frame_of_table(table, ["measurement_id"])["measurement_id"])
        return table, _parts_info(manifest)
    runs, info = load_map(p)  # a single file (or none): read and checked whole
    return pa.Table.from_pandas(runs, preserve_index=False), info


def frame_of_table(table: Any, columns: Sequence[str] | None = None) -> pd.DataFrame:
    """The map DataFrame (the schema's dtypes) of ``columns`` (all when ``None``) of an
    Arrow table of checked map rows (:func:`load_map_table`, or a slice of it)."""
    wanted = list(RUN_COLUMNS) if columns is None else _wanted(columns)
    return _from_arrow(table.select(wanted), wanted, check=False)


def rows_by_id(path: str | os.PathLike[str], info: Mapping[str, Any],
               ids: Iterable[str]) -> pd.DataFrame:
    """Every column of the runs ``ids`` (measurement ids) of the map folder at ``path``,
    as the read that gave ``info`` (its :func:`load_map` metadata) found them, in the
    map's order: only the parts that hold one of them are parsed whole (each part's bytes
    checked against the manifest's SHA-256, as every read does); the others' ids column
    only. For a command that opened the map with a few columns and shows some rows whole
    (``map show``'s excluded and reviewed runs). A map that is not a folder of parts (a
    single file) is read whole again. Raises :class:`MapError` when an id is not in the
    map, or a part is gone (the map was written twice since ``info`` was read)."""
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.parquet as pq

    p = Path(path)
    wanted = set(ids)
    parts = info.get("part_list")
    if info.get("format") != "parts" or parts is None:
        runs = load_map(p)[0]
        found = runs[runs["measurement_id"].isin(wanted)]
    else:
        tables = []
        for part in parts:
            data = read_part_bytes(p, part)
            try:
                file = pq.ParquetFile(pa.BufferReader(data))
                in_part = file.read(columns=["measurement_id"], use_threads=PARQUET_THREADS)
                mask = pc.is_in(in_part["measurement_id"],
                                value_set=pa.array(sorted(wanted), pa.string()))
                if not pc.any(mask).as_py():
                    continue
                table = file.read(use_threads=PARQUET_THREADS)
            except Exception as exc:  # noqa: BLE001 - pyarrow raises many types
                raise MapError(f"part {part.file}: not a readable Parquet file "
                               f"({_first_line(exc)})", path=p) from None
            table = _with_added_columns(table.filter(mask), part.schema_version)
            tables.append(table.select(list(RUN_COLUMNS)).replace_schema_metadata(None))
        if not tables:
            found = empty_map()
        else:
            try:
                found = _from_arrow(pa.concat_tables(tables, promote_options="permissive"),
                                    check=False)
            except MapError as exc:
                raise MapError(exc.problem, path=p, column=exc.column) from None
    if len(found) != len(wanted):
        raise MapError("the map changed while it was read (a run is gone); run the "
                       "command again", path=p)
    return found.reset_index(drop=True)


def _verify_part(p: Path, name: str, table: Any, info: Mapping[str, Any]) -> None:
    """Check a part read whole as ``map validate`` does: every buffer (text as UTF-8) and
    its rows against the checksum of its content in its own metadata."""
    try:
        table.validate(full=True)
    except Exception as exc:  # noqa: BLE001 - pyarrow raises many types
        raise MapError(f"part {name}: damaged ({_first_line(exc)})", path=p) from None
    stored = info.get("content_sha256")
    whole = _with_added_columns(table, info["schema_version"])
    try:
        rows = _from_arrow(whole.select(list(RUN_COLUMNS)), check=False)
    except MapError as exc:
        raise MapError(f"part {name}: {exc.problem}", path=p, column=exc.column) from None
    if stored is None or stored != content_sha256(rows, info["schema_version"]):
        raise MapError(f"part {name} fails the checksum of its rows", path=p)


def verify_map(path: str | os.PathLike[str]) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Read the map at ``path`` with every check there is (``map validate``): for a map
    folder, each part's bytes against the manifest, every buffer, each part's rows against
    the checksum in its metadata, every row against the row rules, and the stored
    groups against the groups of its rows (:func:`~tribopipe.stats.group_statistics`);
    a single-file map as :func:`read_map` reads it (which checks all of that)."""
    p = Path(path)
    if p.is_dir():
        runs, info, manifest = _read_parts_map(p, full=True)
        stored = _stored_rows(p, manifest)
        if stored is not None:
            problem = groups_differ(stored, runs)
            if problem is not None:
                raise MapError(f"the stored condition groups differ from the groups of its "
                               f"rows ({problem})", path=p,
                               hint="`tribopipe map compact` computes them again")
        return runs, info
    return load_map(p)


def _stored(schema: Any, wanted: Sequence[str]) -> list[str]:
    names = set(schema.names)
    return [c for c in wanted if c in names]


def _columns_info() -> list[dict[str, str]]:
    return [{"name": c.name, "kind": c.kind, "unit": c.unit, "meaning": c.meaning}
            for c in COLUMNS]


@dataclass(frozen=True)
class _Merged:
    """Pieces merged into one new part (:func:`_merged_tail`), in order: kept parts, read
    from their checked bytes a batch of rows at a time as the new part is written, and
    checked frames (new or rewritten rows). Its rows are never held as one frame."""

    pieces: tuple[Part | pd.DataFrame, ...]

    @property
    def n_runs(self) -> int:
        """The rows of the merged part."""
        return sum(q.n_runs if isinstance(q, Part) else len(q) for q in self.pieces)


#: a merge of parts copies a kept part's rows this many at a time (each a row group of
#: the new part): what a merge holds of them, whatever the map's size (some 15 MB of
#: Arrow). Smaller row groups read slower: at 1,024 rows a 10⁵-row part was 1.6 × the
#: bytes and read in about 3 × the CPU of one row group; at 16,384 as one row group
MERGE_BATCH_ROWS = 16384


def _merged_bytes(p: Path, merged: _Merged) -> memoryview:
    """The part ``merged`` makes, as one friction-map Parquet file in memory: the same
    rows, columns, Arrow types and row checksum as :func:`_part_bytes` of their
    concatenation, written without holding them: the content checksum is taken a column
    at a time (:func:`~tribopipe.frictionmap.schema.columns_sha256`), then the rows are
    copied a batch at a time (:data:`MERGE_BATCH_ROWS`), each kept part from its bytes
    checked against the manifest. Kept parts are of :data:`SCHEMA_VERSION` (an older one
    comes as a frame, read with its added columns)."""
    import pandas as pd
    import pyarrow as pa
    import pyarrow.parquet as pq

    # each kept part's bytes checked against the manifest, its footer parsed once
    files = {q.file: pq.ParquetFile(pa.BufferReader(read_part_bytes(p, q)))
             for q in merged.pieces if isinstance(q, Part)}

    def file(part: Part) -> Any:
        return files[part.file]

    def cells(part: Part, name: str) -> pd.Series:  # as a read of the part gives them
        table = file(part).read(columns=[name], use_threads=PARQUET_THREADS)
        stored = table.replace_schema_metadata(None).to_pandas(
            ignore_metadata=True, use_threads=PARQUET_THREADS)[name]
        return pd.Series(_typed_cells(name, stored), name=name)

    def column_of(name: str) -> pd.Series:
        column = [cells(q, name) if isinstance(q, Part) else q[name]
                  for q in merged.pieces]
        return pd.concat(column, ignore_index=True) if len(column) > 1 else column[0]

    n_runs = merged.n_runs
    digest = columns_sha256(n_runs, column_of)
    sources = column_of("source").dropna()
    frames = [q for q in merged.pieces if not isinstance(q, Part)]
    # the Arrow schema a frame of the schema's dtypes is written with (:func:`_part_bytes`)
    schema = pa.Table.from_pandas(frames[0].iloc[:0].loc[:, list(RUN_COLUMNS)],
                                  preserve_index=False).schema
    meta = dict(schema.metadata or {})
    meta[META_KEY] = rows_info(n_runs, sources, digest)
    schema = schema.with_metadata(meta)
    del sources
    sink = pa.BufferOutputStream()
    with pq.ParquetWriter(sink, schema) as writer:
        for q in merged.pieces:
            if isinstance(q, Part):
                for batch in file(q).iter_batches(batch_size=MERGE_BATCH_ROWS,
                                                  columns=list(RUN_COLUMNS),
                                                  use_threads=PARQUET_THREADS):
                    writer.write_table(pa.Table.from_batches([batch]).cast(schema))
            else:
                for start in range(0, len(q), MERGE_BATCH_ROWS):
                    rows = q.iloc[start:start + MERGE_BATCH_ROWS].loc[:, list(RUN_COLUMNS)]
                    writer.write_table(pa.Table.from_pandas(rows, preserve_index=False)
                                       .cast(schema))
    return memoryview(sink.getvalue())


def _part_bytes(runs: pd.DataFrame) -> bytes:
    """``runs`` (checked rows) as one friction-map Parquet file, in memory."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(runs.loc[:, list(RUN_COLUMNS)], preserve_index=False)
    meta = dict(table.schema.metadata or {})
    meta[META_KEY] = map_info(runs)
    sink = pa.BufferOutputStream()
    pq.write_table(table.replace_schema_metadata(meta), sink)
    return bytes(sink.getvalue())


#: a new part is merged with the part before it when that one holds at most this many
#: times its rows: parts stay few (about log N) and a row is rewritten about log N times
MERGE_FACTOR = 4


def _flat(pieces: Iterable[Part | pd.DataFrame | _Merged]) -> list[Part | pd.DataFrame]:
    """``pieces`` with each merged one replaced by its own pieces (the same rows, in
    order)."""
    return [q for piece in pieces
            for q in (piece.pieces if isinstance(piece, _Merged) else (piece,))]


def _frames(pieces: Iterable[Part | pd.DataFrame | _Merged]) -> list[pd.DataFrame]:
    """The frames (new or rewritten rows) among ``pieces``, merged ones' included."""
    return [q for q in _flat(pieces) if not isinstance(q, Part)]


def _commit_parts(p: Path, manifest: Manifest | None,
                  pieces: Sequence[Part | pd.DataFrame | _Merged],
                  touched: set[Key] | None = None,
                  read: Mapping[str, pd.DataFrame] | None = None) -> None:
    """Commit the map folder ``p`` as ``pieces`` in order: parts kept as they are, and
    frames (checked rows) written as new parts, with the stored condition groups brought
    up to date in the same commit: those of the conditions ``touched`` computed again
    (all of them when ``None``, or when the map had none stored; ``read``: the rows of
    kept parts the caller has read already, by part file, with the statistics' columns).
    The caller holds the lock and has read the map (the manifest ``manifest``, ``None``
    for a new map)."""
    generation = 1 if manifest is None else manifest.generation + 1
    mode = file_mode(manifest_path(p))
    written: list[Part] = []
    groups = _groups_after(p, manifest, pieces, touched, read or {})
    try:
        p.mkdir(exist_ok=True)
        for piece in pieces:
            if isinstance(piece, Part):
                written.append(piece)
            elif isinstance(piece, _Merged):
                written.append(write_part(p, generation, _merged_bytes(p, piece),
                                          piece.n_runs, SCHEMA_VERSION, mode))
            elif len(piece):
                written.append(write_part(p, generation, _part_bytes(piece), len(piece),
                                          SCHEMA_VERSION, mode))
        stored = write_groups(p, generation, groups_bytes(groups), len(groups), mode)
        sources: set[str] = set(manifest.sources if manifest is not None else ())
        for frame in _frames(pieces):
            sources |= set(frame["source"].dropna().astype(str))
        commit(p, Manifest(generation=generation, parts=settle(p, tuple(written)),
                           written_at=utc_now(), tribopipe_version=__version__,
                           sources=tuple(sorted(sources)), groups=stored), manifest, mode)
    except OSError as exc:  # disk full, permissions: the committed map is untouched
        raise MapError(f"cannot write the friction map ({os_reason(exc)})", path=p) from None
    collect_garbage(p)


def _groups_after(p: Path, manifest: Manifest | None,
                  pieces: Sequence[Part | pd.DataFrame | _Merged],
                  touched: set[Key] | None, known: Mapping[str, pd.DataFrame]
                  ) -> pd.DataFrame:
    """The stored group rows of the map ``pieces`` will make: the stored ones with the
    conditions ``touched`` computed again from their runs (those columns of every piece
    read, :data:`~tribopipe.stats.GROUP_INPUT_COLUMNS`), or all computed when ``touched``
    is ``None`` or the map has none stored yet. The rows of a kept part are taken from
    ``known`` (by part file) where the caller read them, else read."""
    import pandas as pd

    old = _stored_rows(p, manifest)
    if old is None:
        touched = None
    pieces = _flat(pieces)
    kept = [piece for piece in pieces if isinstance(piece, Part) and piece.file not in known]
    read = dict(zip([q.file for q in kept],
                    _split(_read_parts(p, kept, GROUP_INPUT_COLUMNS), kept), strict=True)
                ) if kept else {}
    frames = []
    for piece in pieces:
        # the touched conditions' rows picked before their columns are copied
        if (isinstance(piece, Part) and touched is not None and piece.file in known
                and isinstance(known, _PartRows)):
            rows = known.of_keys(piece.file, touched)
        else:
            rows = ((known[piece.file] if piece.file in known else read[piece.file])
                    if isinstance(piece, Part) else piece)
            rows = rows if touched is None else of_keys(rows, touched)
        frames.append(rows.loc[:, list(GROUP_INPUT_COLUMNS)])
    runs = (pd.concat(frames, ignore_index=True) if frames
            else unvalidated_frame([], where="row").loc[:, list(GROUP_INPUT_COLUMNS)])
    if touched is None or old is None:
        return group_rows(runs) if len(runs) else pd.DataFrame()
    return updated(old, touched, runs)


def _split(rows: pd.DataFrame, parts: Sequence[Part]) -> list[pd.DataFrame]:
    """``rows`` (those of ``parts``, in order) cut into each part's."""
    out, start = [], 0
    for part in parts:
        out.append(rows.iloc[start:start + part.n_runs])
        start += part.n_runs
    return out


def _stored_rows(p: Path, manifest: Manifest | None) -> pd.DataFrame | None:
    """The stored group rows of the committed ``manifest``; ``None`` when it has none (a
    map written before they were stored) or they are of another version."""
    if manifest is None or manifest.groups is None:
        return None
    return rows_from_bytes(read_groups_bytes(p, manifest.groups), str(p))


def committed_groups_info(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The metadata a snapshot of rows a write just left needs to read the map folder's
    stored groups (``format`` ``"parts"`` and the committed manifest's ``groups``), read
    from the manifest alone (no row is read); ``{"format": "rows"}`` for a map without
    them (a single file, no map, a folder without stored groups)."""
    p = Path(path)
    if not p.is_dir():
        return {"format": "rows"}
    manifest = read_manifest(p)
    if manifest.groups is None:
        return {"format": "rows"}
    return {"format": "parts", "n_runs": manifest.n_runs,
            "generation": manifest.generation, "groups": manifest.groups.as_json()}


def stored_groups(path: str | os.PathLike[str], info: Mapping[str, Any]
                  ) -> pd.DataFrame | None:
    """The stored group rows (:func:`~tribopipe.stats.group_rows` of every condition) of
    the map folder at ``path`` as ``info`` (its :func:`load_map` metadata) found it,
    checked against their SHA-256; ``None`` for a map without them (a single file, an
    older folder, another version of the statistics). Raises :class:`MapError` when the
    file is changed, or gone (the map was written twice since ``info`` was read)."""
    entry = info.get("groups")
    if info.get("format") != "parts" or not isinstance(entry, Mapping):
        return None
    p = Path(path)
    groups = GroupsFile(str(entry["file"]), str(entry["sha256"]), int(entry["bytes"]),
                        int(entry["n_groups"]))
    return rows_from_bytes(read_groups_bytes(p, groups), str(p))


def _merged_tail(pieces: list[Part | pd.DataFrame], frames: Callable[[int], pd.DataFrame],
                 origin: list[int | None]) -> list[Part | pd.DataFrame | _Merged]:
    """``pieces`` with trailing pieces merged while the one before the last holds at most
    :data:`MERGE_FACTOR` times the last one's rows, into a :class:`_Merged` (its rows are
    copied as the new part is written, not held); a kept part of an older schema version
    comes as its rows, ``frames(k)`` (``k`` its place in the manifest: ``origin``)."""
    out: list[Part | pd.DataFrame | _Merged] = list(pieces)
    where = list(origin)

    def rows(i: int) -> int:
        piece = out[i]
        return piece.n_runs if isinstance(piece, Part | _Merged) else len(piece)

    def merged(i: int) -> tuple[Part | pd.DataFrame, ...]:
        piece = out[i]
        if isinstance(piece, _Merged):
            return piece.pieces
        if isinstance(piece, Part) and piece.schema_version != SCHEMA_VERSION:
            k = where[i]
            assert k is not None
            return (frames(k),)
        return (piece,)

    while len(out) >= 2 and not isinstance(out[-1], Part) and rows(-2) <= MERGE_FACTOR * rows(-1):
        out[-2:] = [_Merged((*merged(-2), *merged(-1)))]
        where[-2:] = [None]
    return out


def _change_parts(p: Path, manifest: Manifest | None,
                  rewritten: Mapping[int, pd.DataFrame], fresh: pd.DataFrame | None,
                  frame_of: Callable[[int], pd.DataFrame], touched: set[Key],
                  read: Mapping[str, pd.DataFrame] | None = None) -> None:
    """Commit a change of the map folder ``p``: the parts ``rewritten`` (places in
    ``manifest``) replaced by their new rows (checked rows, in order; none: the part
    goes), ``fresh`` rows added as a new part. Untouched parts are kept as they are; a
    kept part is read (``frame_of(k)``, all columns) only when the new part is merged
    into it. The stored groups of the conditions ``touched`` (those of every row added,
    changed or removed, before and after) are computed again. The caller holds the
    lock."""
    pieces: list[Part | pd.DataFrame] = []
    origin: list[int | None] = []
    parts_ = manifest.parts if manifest is not None else ()
    for k, part in enumerate(parts_):
        if k in rewritten:
            pieces.append(rewritten[k].reset_index(drop=True))
            origin.append(None)
        else:
            pieces.append(part)
            origin.append(k)
    if fresh is not None and len(fresh):
        pieces.append(fresh.reset_index(drop=True))
        origin.append(None)
    keep = [i for i, piece in enumerate(pieces) if isinstance(piece, Part) or len(piece)]
    pieces, origin = [pieces[i] for i in keep], [origin[i] for i in keep]
    _commit_parts(p, manifest, _merged_tail(pieces, frame_of, origin), touched, read)


def _owner(manifest: Manifest | None) -> Any:
    """The place in ``manifest`` of the part each row comes from."""
    import numpy as np

    if manifest is None:
        return np.zeros(0, dtype=int)
    return np.repeat(np.arange(len(manifest.parts)), [q.n_runs for q in manifest.parts])


def _update_parts(p: Path, decide: Callable[[pd.DataFrame], FrameChange], replace: bool,
                  columns: Sequence[str] | None = None,
                  needs_all: Callable[[pd.DataFrame], bool] | None = None,
                  after: bool = True) -> tuple[AppendReport, pd.DataFrame | None]:
    """The locked read-modify-write of a map folder, reading what the change needs: the
    ``columns`` ``decide`` reads (with ``measurement_id``; all when ``None``, or when
    ``needs_all`` says so of those rows) of every row, under the lock (the second read
    of a command that appends, so that no other writer slips in between the duplicate
    check and the write), ``decide`` asked once, then every column only of the parts
    that hold a run the change replaces, compares or drops. The change is committed as
    a new part, those parts rewritten when a row of theirs changed, every other part
    kept as it is. Returns the report and the map's rows after the change (the columns
    read; ``None`` unless ``after``). The caller holds the lock."""
    import dataclasses

    import numpy as np
    import pandas as pd

    # with the statistics' columns: the stored groups of the touched conditions are
    # computed again from the rows read here, not read a second time
    need = None if columns is None else ["measurement_id", *columns, *GROUP_INPUT_COLUMNS]
    current, _, manifest = _read_parts_map(p, need)
    if (need is not None and needs_all is not None and manifest is not None
            and needs_all(current)):
        current, need = _read_parts(p, manifest.parts), None
    new_frame, drop_ids = decide(current)
    new_ids = set(new_frame["measurement_id"])
    drop = set(drop_ids) - new_ids
    ids = current["measurement_id"]
    gone = ids.isin(sorted(drop)).to_numpy()
    owner = _owner(manifest)
    touched = sorted({int(k) for k in owner[gone | ids.isin(sorted(new_ids)).to_numpy()]})
    # every column of the parts the change looks into: the rows it compares, replaces or
    # drops live there (a run new to the map needs nothing of the map but its id)
    rows_of = {k: (current.loc[owner == k].reset_index(drop=True) if need is None
                   else _read_parts(p, [manifest.parts[k]])) for k in touched} \
        if manifest is not None else {}
    base = (pd.concat([rows_of[k] for k in touched], ignore_index=True) if touched
            else unvalidated_frame([], where="row"))
    base_owner = np.repeat(np.asarray(touched, dtype=int),
                           [len(rows_of[k]) for k in touched])
    base_gone = base["measurement_id"].isin(sorted(drop)).to_numpy()
    kept = base.loc[~base_gone].reset_index(drop=True)
    merged, report = _fold(kept, new_frame, replace=replace)
    report = dataclasses.replace(
        report, dropped_ids=tuple(current.loc[gone, "measurement_id"].astype(str)))
    if not report.changed:
        return report, current
    kept_owner = base_owner[~base_gone]
    by_id = dict(zip(kept["measurement_id"], kept_owner, strict=True))
    dirty = {int(by_id[m]) for m in report.replaced_ids} | {int(k) for k in owner[gone]}
    old_rows = merged.iloc[:len(kept)]
    rewritten = {k: old_rows.loc[kept_owner == k] for k in dirty}

    def frame_of(k: int) -> pd.DataFrame:  # a kept part's rows, to merge the new ones in
        assert manifest is not None
        if k in rows_of:
            return rows_of[k]
        if need is None:  # every column read already
            return current.loc[owner == k].reset_index(drop=True)
        return _read_parts(p, [manifest.parts[k]])

    touched_keys = keys_of(new_frame) | keys_of(
        base.loc[base["measurement_id"].isin(sorted(new_ids | drop))])
    _change_parts(p, manifest, rewritten, merged.iloc[len(kept):], frame_of, touched_keys,
                  _by_part(current, manifest, owner))
    if not after:  # a second copy of the rows read, for a caller that shows none
        return report, None
    return report, _after(current.loc[~gone].reset_index(drop=True), old_rows,
                          merged.iloc[len(kept):], set(report.replaced_ids))


def _by_part(rows: pd.DataFrame, manifest: Manifest | None, owner: Any
             ) -> Mapping[str, pd.DataFrame]:
    """``rows`` (every row of ``manifest``'s parts, in order; ``owner``: each row's part)
    by part file, each part's rows cut out when asked for (not a second copy of every
    row held beside ``rows``)."""
    return _PartRows(rows, manifest, owner)


class _PartRows(Mapping[str, "pd.DataFrame"]):
    """:func:`_by_part`'s mapping."""

    def __init__(self, rows: pd.DataFrame, manifest: Manifest | None, owner: Any) -> None:
        self._rows, self._owner = rows, owner
        self._near: pd.DataFrame | None = None
        self._keys: set[Key] = set()
        self._near_owner: Any = None
        self._at = {} if manifest is None else {
            part.file: k for k, part in enumerate(manifest.parts)}

    def __getitem__(self, file: str) -> pd.DataFrame:
        return self._rows.loc[self._owner == self._at[file]]

    def of_keys(self, file: str, keys: set[Key]) -> pd.DataFrame:
        """The rows of the part ``file`` whose condition is one of ``keys``
        (:func:`~tribopipe.frictionmap.stored_groups.of_keys`, picked from every row
        once for all parts)."""
        if self._near is None or self._keys != keys:
            self._near, self._keys = of_keys(self._rows, keys), set(keys)
            self._near_owner = self._owner[self._rows.index.get_indexer(self._near.index)]
        return self._near.loc[self._near_owner == self._at[file]]

    def __contains__(self, file: object) -> bool:
        return file in self._at

    def __iter__(self) -> Iterator[str]:
        return iter(self._at)

    def __len__(self) -> int:
        return len(self._at)


def _after(kept: pd.DataFrame, changed: pd.DataFrame, fresh: pd.DataFrame,
           replaced: set[str]) -> pd.DataFrame:
    """The map's rows after a change (the columns of ``kept``): ``kept`` (the rows left,
    in order) with the ``replaced`` ids' rows taken from ``changed``, then ``fresh``."""
    import numpy as np
    import pandas as pd

    cols = list(kept.columns)
    out = kept
    if replaced:
        pos = np.flatnonzero(kept["measurement_id"].isin(sorted(replaced)).to_numpy())
        new = changed.loc[changed["measurement_id"].isin(sorted(replaced)), cols]
        new = new.set_index(new["measurement_id"].astype(str), drop=False)
        swapped = new.loc[list(kept["measurement_id"].iloc[pos].astype(str))]
        swapped.index = pd.Index(pos)
        out = pd.concat([kept.drop(index=list(pos)), swapped]).sort_index()
    if len(fresh):
        out = pd.concat([out, fresh.loc[:, cols]], ignore_index=True) if len(out) else \
            fresh.loc[:, cols]
    return out.reset_index(drop=True)


def upgrade_map(path: str | os.PathLike[str]) -> tuple[int, Path | None]:
    """Convert the single-file map at ``path`` (the format before parts) into a map folder
    of one part at the same path, under the map's lock: every row read and checked, the
    folder built beside it and fsynced, the file kept as ``<map>.bak``, then the folder
    renamed into its place. Returns the number of runs and where the old file is kept
    (``None`` when the map was a folder already: nothing to do). A conversion killed
    between its two renames is finished by running it again (reads refuse the map until
    then, in one line that says so)."""
    p = Path(path)
    staged = _upgrade_folder(p)
    with _locked(p):
        if not p.exists() and staged.is_dir():  # a conversion killed between its renames
            read_manifest(staged)
            os.replace(staged, p)
            fsync_dir(p.parent)
            return load_map(p, ["measurement_id"])[1]["n_runs"], backup_path(p)
        if not p.exists():
            raise MapError("friction map not found", path=p, hint="pass --map PATH")
        if p.is_dir():
            return load_map(p, ["measurement_id"])[1]["n_runs"], None
        runs, _ = _read_file_map(p)  # every row checked once more, as map validate does
        if staged.exists():
            shutil.rmtree(staged)
        staged.mkdir()
        try:
            _commit_parts(staged, None, [runs])
            os.replace(p, backup_path(p))
            os.replace(staged, p)
        except OSError as exc:
            raise MapError(f"cannot convert the friction map ({os_reason(exc)})",
                           path=p) from None
        fsync_dir(p.parent)
        return len(runs), backup_path(p)


def _upgrade_folder(p: Path) -> Path:
    return p.with_name(f".{p.name}.upgrade")


def _refuse_interrupted_upgrade(p: Path) -> None:
    if _upgrade_folder(p).is_dir():
        raise MapError("the map's conversion to a folder of parts was interrupted",
                       path=p, hint="run `tribopipe map upgrade` again to finish it")


def compact_map(path: str | os.PathLike[str]) -> tuple[int, int]:
    """Rewrite the map folder at ``path`` as one part, under the map's lock, with the
    safety of every write (new part fsynced, the manifest swapped atomically, the previous
    commit kept as ``_manifest.json.bak`` with its parts until the next write), with the
    stored condition groups computed again from every row (also for a map of one part
    whose stored groups are missing or differ from its rows). Returns the number of
    parts before and after. A single-file map is refused: convert it first
    (:func:`upgrade_map`)."""
    p = Path(path)
    if not p.exists():
        raise MapError("friction map not found", path=p, hint="pass --map PATH")
    if not p.is_dir():
        raise MapError("a single-file map has nothing to compact", path=p,
                       hint="convert it first: tribopipe map upgrade")
    with _locked(p):
        runs, _, manifest = _read_parts_map(p)
        before = 0 if manifest is None else len(manifest.parts)
        stored = _stored_rows(p, manifest)
        if before <= 1 and (manifest is None or stored is not None
                            and groups_differ(stored, runs) is None):
            return before, before
        # one part, and the stored groups all computed again from its rows
        _commit_parts(p, manifest, [runs])
        return before, 1

"""A campaign's incremental state: typed, and read and written in this one place.

``<output_dir>/.tribopipe-state.<name>.sqlite`` (SQLite, updated row by row: one row per
file, the JSON of its :class:`FileState`) remembers, per file (:class:`FileState`):
size, ``mtime_ns``, SHA-256, the config hash, a recipe hash (config + the labels known
before reading + QC tolerances), the file's status, its tests and, per run
(:class:`RunState`), its status and what :class:`RunEntry` holds of a reduced run; and
the map's size and ``mtime_ns`` as the last batch left it (:class:`MapStamp`). One state
per campaign name, so campaigns may share an output folder and a map.
:meth:`FileState.to_json` and :meth:`FileState.from_json` are the only translation
between these types and a row; :func:`load_state` and :func:`save_state` read and write
a whole state, and a batch's :class:`BatchEntries` reads an entry back from its row and
writes what its landings changed, row by row. The JSON state file older versions wrote
(``.tribopipe-state.<name>.json``, :meth:`CampaignState.from_json`) is read once and
converted.
"""

from __future__ import annotations

import json
import os
import sqlite3
import stat
import sys
from collections.abc import Iterator, MutableMapping
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import OutputError
from ..frictionmap.parts import MANIFEST
from ..labels import flags_text
from ..numeric import finite_json

if TYPE_CHECKING:
    from ..pipeline.runs import FailedRun, ReducedRun
    from .spec import Campaign

STATE_VERSION = 2

#: the statuses of a campaign file or run before a batch (``campaign list``)
NEW, REDUCED, CHANGED, FAILED = "new", "reduced", "changed", "failed"
#: a file whose content another file of the campaign (or the map) holds: stored once
DUPLICATE = "duplicate"
#: what a batch did with a run (``runs.csv``)
SKIPPED = "skipped"


@dataclass(frozen=True, slots=True)
class RunEntry:
    """What the state keeps of a reduced run (and ``runs.csv`` shows), as its worker
    found it: the labels, the id, the trace (relative to the output folder), μ_S and μ_K,
    the nominal pressure [kPa], the measured pressure [kPa], normal force [N] and
    temperature [°C] (``None`` when not finite), the ``;``-joined flags, and where the run
    sits in its export (its name, test, result, interval and occurrence)."""

    labels: dict[str, Any]
    measurement_id: str
    trace: str
    mu_s: float | None
    mu_k: float | None
    pressure_kPa: float | None
    pressure_measured_kPa: float | None
    normal_force_measured_N: float | None
    temperature_measured_C: float | None
    flags: str
    name: str = ""
    test: str | None = None
    result: str | None = None
    interval: int | None = None
    occurrence: int = 1

    def as_dict(self) -> dict[str, Any]:
        """The entry's fields as the state's JSON keys (the labels a copy of their own:
        its nested values are plain JSON values, read and never changed)."""
        out = {k: getattr(self, k) for k in ENTRY_KEYS}
        out["labels"] = dict(self.labels)
        return out

    @classmethod
    def of(cls, run: ReducedRun, output_dir: Path, shared: Shared | None = None) -> RunEntry:
        """What the state keeps of a run reduced now (its trace relative to
        ``output_dir``; ``shared`` keeps one copy of what many runs repeat, see
        :class:`Shared`)."""
        record, summary, place = run.record, run.summary, run.place
        share = Shared() if shared is None else shared
        return cls(
            labels=share.labels(asdict(run.labels)),
            measurement_id=run.measurement_id,
            trace="" if run.trace is None else run.trace.relative_to(output_dir).as_posix(),
            mu_s=summary["mu_s"],
            mu_k=summary["mu_k"],
            pressure_kPa=None if record is None else record.pressure_kPa,
            pressure_measured_kPa=summary["pressure_kPa"],
            normal_force_measured_N=summary["normal_force_N"],
            temperature_measured_C=summary["temperature_C"],
            flags=share.text(flags_text(run.flags)),
            name=run.name,
            test=share.text(place.test),
            result=share.text(place.result),
            interval=place.interval,
            occurrence=place.occurrence,
        )


#: the keys of a state run entry that come from a :class:`RunEntry`
ENTRY_KEYS: tuple[str, ...] = tuple(f.name for f in fields(RunEntry))


@dataclass(frozen=True, slots=True)
class RunState:
    """One run of a file as the state keeps it: ``status`` reduced or duplicate (then
    ``entry`` holds what was measured) or failed (then ``reason`` says why and
    ``undescribed`` whether no metadata source described its test); its name and where
    it sits in its export."""

    status: str
    name: str = ""
    test: str | None = None
    result: str | None = None
    interval: int | None = None
    reason: str | None = None
    undescribed: bool = False
    entry: RunEntry | None = None

    @classmethod
    def kept(cls, status: str, entry: RunEntry) -> RunState:
        """A reduced (or duplicate) run with what was measured."""
        return cls(status=status, name=entry.name, test=entry.test, result=entry.result,
                   interval=entry.interval, entry=entry)

    @classmethod
    def failed(cls, run: FailedRun) -> RunState:
        """A run that failed, with its reason."""
        place = run.place
        return cls(status=FAILED, name=run.name, test=place.test if place else None,
                   result=place.result if place else None,
                   interval=place.interval if place else None, reason=run.reason,
                   undescribed=run.undescribed)

    @property
    def measurement_id(self) -> str | None:
        """The run's id, when it was reduced."""
        return None if self.entry is None else self.entry.measurement_id

    @property
    def labels(self) -> dict[str, Any] | None:
        """The labels it was reduced with, when it was."""
        return None if self.entry is None else self.entry.labels

    def flat(self) -> dict[str, Any]:
        """The run as one flat dict: its JSON form (``status`` and the entry's keys, or
        where it sits and why it failed)."""
        if self.entry is not None:
            return {"status": self.status, **self.entry.as_dict()}
        out: dict[str, Any] = {"status": self.status, "name": self.name, "test": self.test,
                               "result": self.result, "interval": self.interval,
                               "reason": self.reason}
        if self.undescribed:
            out["undescribed"] = True
        return out

    @classmethod
    def from_json(cls, data: dict[str, Any], shared: Shared | None = None) -> RunState:
        """The run from its JSON form (:meth:`flat`); ``shared`` keeps one copy of the
        labels and short strings that many runs repeat (see :class:`Shared`)."""
        share = Shared() if shared is None else shared
        status = sys.intern(str(data["status"]))
        if status in (REDUCED, DUPLICATE):
            values = {k: data[k] for k in ENTRY_KEYS if k in data}
            if isinstance(values.get("labels"), dict):
                values["labels"] = share.labels(values["labels"])
            for key in _REPEATED:
                if isinstance(values.get(key), str):
                    values[key] = sys.intern(values[key])
            return cls.kept(status, RunEntry(**values))
        return cls(status=status, name=str(data.get("name") or ""),
                   test=share.text(data.get("test")), result=share.text(data.get("result")),
                   interval=data.get("interval"), reason=data.get("reason"),
                   undescribed=bool(data.get("undescribed")))


#: the entry's string fields that repeat from run to run (interned: one copy each)
_REPEATED = ("flags", "test", "result")


class Shared:
    """One copy of what many state entries repeat, for the entries of one read or one
    batch: the labels' keys and short repeated strings interned, equal nested values of
    the labels (a report's lists) one object (the entries' labels are read and never
    changed; :meth:`RunEntry.as_dict` copies them). A batch holds every file's entry, and
    a decoded entry's own copy of these was half of what it cost in memory."""

    __slots__ = ("_values",)

    def __init__(self) -> None:
        self._values: dict[str, Any] = {}

    def labels(self, labels: dict[str, Any]) -> dict[str, Any]:
        """``labels`` as a new dict, its keys and string values interned and its nested
        dicts and lists shared with their equals."""
        return {sys.intern(k): self.value(v) for k, v in labels.items()}

    def value(self, value: Any) -> Any:
        """A label's value: a string interned, a dict or list shared with its equals."""
        if isinstance(value, str):
            return sys.intern(value)
        if isinstance(value, (dict, list)):
            return self._values.setdefault(json.dumps(value, sort_keys=True, default=str),
                                           value)
        return value

    @staticmethod
    def text(value: Any) -> Any:
        """``value`` interned when it is a string, else as it is."""
        return sys.intern(value) if isinstance(value, str) else value


@dataclass(frozen=True, slots=True)
class FileState:
    """What the state keeps of a file: its size, ``mtime_ns`` and SHA-256, the config and
    recipe hashes it was reduced with, its status (reduced, duplicate, failed), its Test
    names (``None``: not known), its runs, and why it failed or which file it duplicates.
    """

    size: int
    mtime_ns: int
    config_hash: str | None
    recipe: str | None
    sha256: str | None
    status: str
    tests: tuple[str | None, ...] | None = ()
    runs: tuple[RunState, ...] = ()
    reason: str | None = None
    duplicate_of: str | None = None

    def run_ids(self, statuses: tuple[str, ...] = (REDUCED,)) -> set[str]:
        """The measurement ids of its runs with one of ``statuses``."""
        return {r.entry.measurement_id for r in self.runs
                if r.status in statuses and r.entry is not None and r.entry.measurement_id}

    def to_json(self) -> dict[str, Any]:
        """Its JSON form."""
        out: dict[str, Any] = {
            "size": self.size, "mtime_ns": self.mtime_ns, "config_hash": self.config_hash,
            "recipe": self.recipe, "sha256": self.sha256, "status": self.status,
            "tests": None if self.tests is None else list(self.tests),
            "runs": [r.flat() for r in self.runs]}
        if self.reason is not None:
            out["reason"] = self.reason
        if self.duplicate_of is not None:
            out["duplicate_of"] = self.duplicate_of
        return out

    @classmethod
    def from_json(cls, data: dict[str, Any], shared: Shared | None = None) -> FileState:
        """The file from its JSON form; ``shared`` keeps one copy of what many files
        repeat (see :class:`Shared`)."""
        share = Shared() if shared is None else shared
        tests = data.get("tests")
        return cls(size=int(data["size"]), mtime_ns=int(data["mtime_ns"]),
                   config_hash=share.text(data.get("config_hash")),
                   recipe=share.text(data.get("recipe")),
                   sha256=data.get("sha256"), status=sys.intern(str(data["status"])),
                   tests=None if tests is None else tuple(share.text(t) for t in tests),
                   runs=tuple(RunState.from_json(r, share) for r in data.get("runs") or []),
                   reason=data.get("reason"), duplicate_of=data.get("duplicate_of"))


@dataclass(frozen=True)
class MapStamp:
    """The map file's size and ``mtime_ns`` as a batch left it: an untouched map is
    trusted without reading it."""

    size: int
    mtime_ns: int

    @classmethod
    def of(cls, path: Path) -> MapStamp | None:
        """The stamp of the map at ``path`` (``None`` when there is none): of its
        manifest for a map folder (every commit replaces it), else of the file."""
        if not path.exists():
            return None
        try:
            st = (path / MANIFEST).stat() if path.is_dir() else path.stat()
        except OSError:
            return None
        return cls(size=st.st_size, mtime_ns=st.st_mtime_ns)


#: a state file's inode, size, ``mtime_ns``, ``ctime_ns`` and SQLite's file change
#: counter (the 4 bytes at offset 24 of its header, which every write transaction of a
#: rollback-journal database, as this one is, increments): every write changes it
FileStamp = tuple[int, int, int, int, bytes]


def _file_stamp(path: Path) -> FileStamp | None:
    """The :data:`FileStamp` of ``path``, ``None`` when it cannot be read (or is not a
    regular file: never opened then), or is a database in WAL mode (its header's write
    version, byte 18, is not 1): its writes go to another file, unseen here."""
    try:
        if not stat.S_ISREG(path.stat().st_mode):
            return None
        with path.open("rb") as fh:
            st = os.fstat(fh.fileno())
            header = fh.read(28)
    except OSError:
        return None
    if len(header) < 28 or header[18] != 1:
        return None
    return (st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns, header[24:28])


@dataclass(frozen=True)
class CampaignState:
    """A campaign's incremental state: its name, each file's :class:`FileState` (by
    campaign-relative name) and the map's :class:`MapStamp`. ``rows_of``: the state
    file's :data:`FileStamp` as it was when its entries were decoded from its rows
    (``None``: they were not, e.g. an empty state or the JSON of an older version)."""

    campaign: str | None = None
    entries: dict[str, FileState] = field(default_factory=dict)
    map: MapStamp | None = None
    rows_of: FileStamp | None = field(default=None, compare=False, repr=False)

    def to_json(self) -> dict[str, Any]:
        """The state file's JSON."""
        out: dict[str, Any] = {"version": STATE_VERSION, "campaign": self.campaign,
                               "entries": {f: e.to_json() for f, e in self.entries.items()}}
        if self.map is not None:
            out["map"] = asdict(self.map)
        return out

    @classmethod
    def from_json(cls, data: Any) -> CampaignState:
        """The state from its JSON; an empty state when it is not one this version wrote
        (a lost state only costs a full re-run)."""
        if not isinstance(data, dict) or data.get("version") != STATE_VERSION or \
                not isinstance(data.get("entries"), dict):
            return cls()
        try:
            stamp = data.get("map")
            shared = Shared()
            return cls(campaign=data.get("campaign"),
                       entries={str(f): FileState.from_json(e, shared)
                                for f, e in data["entries"].items()},
                       map=None if not stamp else MapStamp(int(stamp["size"]),
                                                           int(stamp["mtime_ns"])))
        except (KeyError, TypeError, ValueError, AttributeError):
            return cls()


@dataclass(frozen=True)
class KeptLedger:
    """What the state keeps of a batch that found nothing to do, so that the next one
    that finds the campaign as it was reports it again without reading any file or row:
    the stamp of the campaign's inputs (``inputs``) and of the batch's own outputs
    (``outputs``) as that batch left them
    (:mod:`tribopipe.campaign.stamp`), the traces its reduced runs need (relative to the
    output folder), and its report (:meth:`~tribopipe.campaign.ledger.BatchReport.to_json`).
    """

    inputs: str
    outputs: str
    traces: tuple[str, ...]
    report: dict[str, Any]
    #: a pending ledger's tables: the text of ``runs.csv`` and ``failures.csv`` the next
    #: unchanged batch writes before it reports (rehearsed by a batch that did work, whose
    #: own tables ``outputs`` stamps); ``None`` for a ledger kept by a batch that found
    #: nothing to do
    tables: tuple[str, str] | None = None


#: the state's row (in its ``meta`` table) that keeps a :class:`KeptLedger`
KEPT_KEY = "kept_ledger"
#: the row that keeps a pending one (with its tables): a version that does not know it
#: never reads it
PENDING_KEY = "pending_ledger"


def load_kept(campaign: Campaign) -> KeptLedger | None:
    """The :class:`KeptLedger` of the campaign's state (one row of it read), ``None`` when
    there is none, the state is not one this version wrote, or it cannot be read."""
    path = campaign.state_path
    if not path.is_file():
        return None
    try:
        con = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=60)
        try:
            meta = dict(con.execute("SELECT key, value FROM meta WHERE key IN (?, ?, ?)",
                                    ("version", KEPT_KEY, PENDING_KEY)).fetchall())
        finally:
            con.close()
        text = meta.get(KEPT_KEY, meta.get(PENDING_KEY))
        if meta.get("version") != str(STATE_VERSION) or not isinstance(text, str):
            return None
        data = json.loads(text)
        tables = None if KEPT_KEY in meta else (str(data["runs_csv"]),
                                                 str(data["failures_csv"]))
        return KeptLedger(inputs=str(data["inputs"]), outputs=str(data["outputs"]),
                          traces=tuple(str(t) for t in data["traces"]),
                          report=dict(data["report"]), tables=tables)
    except (sqlite3.Error, ValueError, TypeError, KeyError):
        return None


def save_kept(campaign: Campaign, kept: KeptLedger | None) -> None:
    """Keep ``kept`` in the campaign's state, as the kept ledger or, with its tables, the
    pending one, in place of any other (``None``: forget the one kept, when there is a
    state). Raises :class:`~tribopipe.errors.OutputError` naming the file when it cannot
    be written."""
    path = campaign.state_path
    if kept is None and not path.is_file():
        return
    try:
        con = _connect(path)
        try:
            con.execute("BEGIN IMMEDIATE")
            con.execute("DELETE FROM meta WHERE key IN (?, ?)", (KEPT_KEY, PENDING_KEY))
            if kept is not None:
                data: dict[str, Any] = {"inputs": kept.inputs, "outputs": kept.outputs,
                                        "traces": list(kept.traces), "report": kept.report}
                if kept.tables is not None:
                    data["runs_csv"], data["failures_csv"] = kept.tables
                con.execute("INSERT INTO meta (key, value) VALUES (?, ?)",
                            (KEPT_KEY if kept.tables is None else PENDING_KEY,
                             json.dumps(data, separators=(",", ":"))))
            con.execute("COMMIT")
        finally:
            con.close()
    except (OSError, sqlite3.Error) as exc:
        raise OutputError(f"cannot write the campaign state ({exc})", path=path) from None


def load_state(campaign: Campaign) -> CampaignState:
    """The incremental state of a campaign (empty when there is none or it is unreadable:
    a lost state only costs a full re-run). Where only the JSON state of an older version
    exists, it is read and converted: written into the SQLite state, which is read from
    then on."""
    path = campaign.state_path
    if path.is_file():
        try:
            return _read_sqlite(path)
        except (sqlite3.Error, ValueError, TypeError, KeyError):
            return CampaignState()
    try:
        data = json.loads(campaign.legacy_state_path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return CampaignState()
    state = CampaignState.from_json(data)
    if state.entries or state.campaign is not None:
        try:
            save_state(campaign, state)
        except OutputError:
            pass  # read again next time: the batch says so when it saves
    return state


def _connect(path: Path) -> sqlite3.Connection:
    con = sqlite3.connect(path, timeout=60, isolation_level=None)
    con.execute("PRAGMA synchronous=FULL")
    con.execute("CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
    con.execute("CREATE TABLE IF NOT EXISTS files (name TEXT PRIMARY KEY, state TEXT NOT NULL)")
    return con


def _read_sqlite(path: Path) -> CampaignState:
    # stamped before it is read: a write after this is seen by any later comparison
    stamp = _file_stamp(path)
    con = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=60)
    try:
        meta = dict(con.execute("SELECT key, value FROM meta").fetchall())
        if meta.get("version") != str(STATE_VERSION):
            return CampaignState()
        loads, shared = json.loads, Shared()
        entries = {loads(name): FileState.from_json(loads(text), shared)
                   for name, text in con.execute("SELECT name, state FROM files")}
    finally:
        con.close()
    kept = json.loads(meta.get("map", "null"))
    return CampaignState(campaign=json.loads(meta.get("campaign", "null")), entries=entries,
                         map=None if not kept else MapStamp(int(kept["size"]),
                                                            int(kept["mtime_ns"])),
                         rows_of=stamp)


def save_state(campaign: Campaign, state: CampaignState,
               saved: CampaignState | None = None) -> None:
    """Write the incremental state into its SQLite file, in one transaction: the files
    whose entry differs from ``saved`` (what the file holds already; ``None``: every
    file) row by row, the files gone from it removed, and the campaign's name and the
    map's stamp (a batch saves through :class:`BatchEntries`, row by row, instead). Raises
    :class:`~tribopipe.errors.OutputError` naming the file when it cannot be written."""
    path = campaign.state_path
    before = {} if saved is None else saved.entries
    # a name is kept as its JSON (ASCII): a file name that is not valid UTF-8 (its bytes
    # kept as surrogates) stays exactly that name
    changed = [(json.dumps(name), _entry_text(entry)) for name, entry in state.entries.items()
               if before.get(name) is not entry and before.get(name) != entry]
    gone = [(json.dumps(name),) for name in before if name not in state.entries]
    _write_rows(path, changed, gone, _meta_rows(state.campaign, state.map),
                clear=saved is None)


def _meta_rows(campaign: str | None, stamp: MapStamp | None) -> list[tuple[str, str]]:
    """The state file's ``meta`` rows (key, value): its version, the campaign's name and
    the map's :class:`MapStamp`."""
    return [("version", str(STATE_VERSION)), ("campaign", json.dumps(campaign)),
            ("map", json.dumps(None if stamp is None else asdict(stamp)))]


def _write_rows(path: Path, changed: list[tuple[str, str]], gone: list[tuple[str]],
                meta: list[tuple[str, str]], *, clear: bool) -> None:
    """One transaction on the state file: its file rows cleared first (``clear``), the
    ``changed`` rows (name, state) written, the ``gone`` rows removed, the ``meta``
    keys set. Raises :class:`~tribopipe.errors.OutputError` naming the file when it
    cannot be written."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        con = _connect(path)
        try:
            con.execute("BEGIN IMMEDIATE")
            if clear:
                con.execute("DELETE FROM files")
            con.executemany("INSERT OR REPLACE INTO files (name, state) VALUES (?, ?)", changed)
            con.executemany("DELETE FROM files WHERE name = ?", gone)
            con.executemany("INSERT OR REPLACE INTO meta (key, value) VALUES (?, ?)", meta)
            con.execute("COMMIT")
        finally:
            con.close()
    except (OSError, sqlite3.Error) as exc:
        raise OutputError(f"cannot write the campaign state ({exc})", path=path) from None


def _entry_text(entry: FileState) -> str:
    """A file's entry as the state stores it: compact, strict JSON (a value that is not
    finite is ``null``; the entries hold none, so the slow walk is the rare fallback)."""
    data = entry.to_json()
    try:
        return json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=False)
    except ValueError:
        return json.dumps(finite_json(data), sort_keys=True, separators=(",", ":"),
                          allow_nan=False)


class BatchEntries(MutableMapping[str, FileState]):
    """A campaign's file entries while a batch runs, in the order a dict of them would
    keep (the state's, then the files landed): the entries as loaded, and those set since
    the last :meth:`save`, are held; an entry :meth:`save` wrote is let go and read again
    from its SQLite row (decoded then) when asked for. So what the batch holds of the
    files it landed is their names, not their entries: its memory stays flat in the
    number of files it lands.

    ``loaded``: the state as :func:`load_state` read it; ``fresh``: the state file held
    nothing of it (none, or the JSON of an older version just converted is not counted:
    see :func:`load_state`), so the first save writes every entry after clearing its
    rows."""

    def __init__(self, campaign: Campaign, loaded: CampaignState, *, fresh: bool) -> None:
        self._path = campaign.state_path
        self._name = campaign.name
        self._map_path = campaign.map_path
        #: file → its entry when held, else ``None`` (in the state file only)
        self._index: dict[str, FileState | None] = dict(loaded.entries)
        self._dirty: set[str] = set()
        self._gone: set[str] = set()
        self._fresh = fresh
        self._written: tuple[str | None, MapStamp | None] | None = \
            None if fresh else (loaded.campaign, loaded.map)
        self._reader: sqlite3.Connection | None = None
        #: the state file's stamp when what it holds was last known (its rows decoded by
        #: load_state, or this batch's last save); ``None``: not known
        self._known: FileStamp | None = None if fresh else loaded.rows_of
        #: every entry held is one decoded from its row (as load_state reads it back)
        self._decoded = loaded.rows_of is not None or not loaded.entries
        #: how many entries hold each reduced run's id: which ids the state still holds
        #: is asked on every landing of files redone (a changed config redoes them all),
        #: and reading every entry back each time would grow as n²
        self._holders: dict[str, int] = {}
        for entry in loaded.entries.values():
            self._count(entry, 1)

    def _count(self, entry: FileState | None, step: int) -> None:
        """Count ``entry``'s reduced runs' ids once more (``step`` 1) or once less (-1)."""
        for mid in entry.run_ids() if entry is not None else ():
            n = self._holders.get(mid, 0) + step
            if n > 0:
                self._holders[mid] = n
            else:
                self._holders.pop(mid, None)

    def _hold(self, name: str, entry: FileState | None) -> None:
        """Count ``entry``'s ids as held by ``name`` (``None``: none) in place of those
        of the entry it held (read back from its row when it was let go)."""
        if name in self._index:
            self._count(self._held(name), -1)
        self._count(entry, 1)

    def held_ids(self, ids: set[str]) -> set[str]:
        """Those of ``ids`` some entry holds as a reduced run's id (read from no row)."""
        return {mid for mid in ids if mid in self._holders}

    def __len__(self) -> int:
        return len(self._index)

    def __iter__(self) -> Iterator[str]:
        return iter(self._index)

    def __contains__(self, name: object) -> bool:
        return name in self._index

    def __getitem__(self, name: str) -> FileState:
        entry = self._index[name]
        return entry if entry is not None else self._read(name)

    def __setitem__(self, name: str, entry: FileState) -> None:
        self._hold(name, entry)
        self._index[name] = entry
        self._dirty.add(name)
        self._gone.discard(name)

    def __delitem__(self, name: str) -> None:
        self._hold(name, None)
        del self._index[name]
        self._dirty.discard(name)
        self._gone.add(name)

    def _read(self, name: str) -> FileState:
        """The entry of ``name`` from its row of the state file."""
        if self._reader is None:
            self._reader = sqlite3.connect(f"file:{self._path}?mode=ro", uri=True,
                                           timeout=60, isolation_level=None)
        # every row fetched: no statement left open to hold the file against a write
        rows = self._reader.execute("SELECT state FROM files WHERE name = ?",
                                    (json.dumps(name),)).fetchall()
        if not rows:  # the state file was changed under the batch
            raise KeyError(name)
        return FileState.from_json(json.loads(rows[0][0]))

    def _held(self, name: str) -> FileState | None:
        """The entry of ``name``, ``None`` when the state file no longer holds it."""
        try:
            return self[name]
        except (KeyError, sqlite3.Error, ValueError, TypeError):
            return None

    def close(self) -> None:
        """Close the state file, when it was read."""
        if self._reader is not None:
            self._reader.close()
            self._reader = None

    def _writes(self, stamp: MapStamp | None) -> bool:
        """Whether :meth:`save` writes, the map's stamp being ``stamp``."""
        return bool(self._dirty or self._gone) or not self._path.exists() or \
            self._written != (self._name, stamp)

    def would_write(self) -> bool:
        """Whether :meth:`save` would write anything now: an entry set or removed since
        the last save, no state file, or a campaign name or map stamp it does not hold."""
        return self._writes(MapStamp.of(self._map_path))

    def save(self) -> None:
        """Write what changed since the last save into the state file, in one
        transaction: the entries set (row by row), the files removed, the campaign's
        name and the map's size and ``mtime_ns`` as the batch leaves it (so the next
        batch trusts an untouched map without reading it); nothing when none of these
        changed. The entries written are let go. Raises
        :class:`~tribopipe.errors.OutputError` naming the file when it cannot be
        written (then they are kept, for the next save)."""
        stamp = MapStamp.of(self._map_path)
        if not self._writes(stamp):
            return
        # a state file removed under the batch is written again in full (from what it
        # still holds: entries it let go are lost with it, and reduced again next time)
        fresh = self._fresh or not self._path.is_file()
        names = list(self._index) if fresh else [n for n in self._index if n in self._dirty]
        held = {n: self._held(n) for n in names} if fresh else {n: self[n] for n in names}
        changed = [(json.dumps(n), _entry_text(e)) for n, e in held.items() if e is not None]
        gone = [(json.dumps(n),) for n in self._gone]
        meta = _meta_rows(self._name, stamp)
        # the file as the batch last knew it, just before this write: else another writer
        # changed it since, and what the batch holds is no longer provably what it holds
        untouched = _file_stamp(self._path) == self._known
        _write_rows(self._path, changed, gone, meta, clear=fresh)
        for name, entry in held.items():
            if entry is None:
                del self._index[name]
            else:
                self._index[name] = None
        self._dirty.clear()
        self._gone.clear()
        if fresh:  # every entry was written and let go: each is read back when asked for
            self._decoded = True
        self._fresh = False
        self._written = (self._name, stamp)
        self._known = _file_stamp(self._path) if untouched or fresh else None

    def as_read_back(self) -> CampaignState | None:
        """The state :func:`load_state` would read from the state file now, from what
        the batch holds, when that is provably it; else ``None`` (read it).

        Provably: everything set or removed is saved; the file is as the batch last knew
        it (its :data:`FileStamp` that of its last save, or of load_state's read: no one
        wrote it since); its rows are those of the entries held (by name, in the file's
        order, which is load_state's); each entry held was decoded from its row and
        never set since (a row the batch wrote, it let go: that entry is read back from
        its row, as load_state would). Costs a listing of the rows' names and a row read
        per entry let go, not the decoding of the whole state."""
        if self._dirty or self._gone or not self._decoded or self._known is None \
                or self._written is None:
            return None
        try:
            if _file_stamp(self._path) != self._known:
                return None
            con = sqlite3.connect(f"file:{self._path}?mode=ro", uri=True, timeout=60)
            try:
                meta = dict(con.execute("SELECT key, value FROM meta WHERE key IN (?, ?, ?)",
                                        ("version", "campaign", "map")).fetchall())
                # a table scan's order: that of load_state's read
                names = [json.loads(n) for (n,) in
                         con.execute("SELECT name FROM files ORDER BY rowid")]
            finally:
                con.close()
            name, stamp = self._written
            if meta != dict(_meta_rows(name, stamp)) \
                    or len(names) != len(self._index) \
                    or not all(n in self._index for n in names):
                return None
            entries = {n: self[n] for n in names}
            if _file_stamp(self._path) != self._known:  # written while it was read
                return None
        except (KeyError, sqlite3.Error, ValueError, TypeError):
            return None
        finally:
            self.close()
        return CampaignState(campaign=name, entries=entries, map=stamp, rows_of=self._known)

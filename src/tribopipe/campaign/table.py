"""A campaign as a table, before anything runs: one row per file, its metadata and status.

Which files
-----------
:func:`discover_files`: by default every export the readers know in the raw folder (the
suffixes of :data:`tribopipe.readers.EXPORT_SUFFIXES`, in any case: ``.csv``, ``.txt``,
``.tsv``, ``.xlsx`` and ``.xls``, which is refused with its reason), else the campaign's
``glob``. Never taken: hidden files, the manifest, the review file, campaign configs
(``.toml``), and the tool's own outputs (the map, anything the output folder holds,
``runs.csv`` and ``failures.csv`` tables, state and ``.lock`` files).

Content before labels
---------------------
A file about to be read (new, changed or failed before) and a file no label source
describes is first looked at (:func:`tribopipe.readers.export_kind`): one that is surely
not an instrument export (a note, a PDF, an image) is set aside as ``not an export:
skipped`` (:attr:`CampaignTable.not_exports`), never a failure. A file that is an export
but that no label source describes is read before its labels are judged: when none of
its tests is a friction test, it is named for what it is ("it looks like a stress
relaxation test"), as it would be with every label given; an export that cannot be read
fails with the reader's reason.

Incremental state
-----------------
The last batch's :class:`~tribopipe.campaign.state.CampaignState` says, per file, what it
found. Like git's index, the cached hash is trusted while size and ``mtime_ns`` are
unchanged, so an unchanged campaign is checked with one ``stat`` per file and every run
of an unchanged file is skipped.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
from array import array
from bisect import bisect_left
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from ..errors import CampaignError, ReadError
from ..escape import csv_cell, display_path
from ..files import file_sha256, regular_file
from ..labels import LABEL_FORCE_REL, RunLabels
from ..layout import FAILURES_CSV, RUNS_CSV
from ..materials import ADD_HINT, joined_problems
from ..pipeline.route import read_runs
from ..readers import EXPORT_SUFFIXES, export_kind
from .metadata import (
    MANIFEST_COLUMNS,
    Manifest,
    ManifestRow,
    labels_from,
    material_problems,
    merge_metadata,
    read_manifest,
)
from .patterns import LABEL_FIELDS, match_pattern, pattern_break
from .spec import Campaign
from .state import (
    CHANGED,
    DUPLICATE,
    FAILED,
    NEW,
    REDUCED,
    CampaignState,
    FileState,
    RunState,
    load_state,
)


@dataclass(frozen=True)
class CampaignRow:
    """One file of a campaign: its metadata (as known before reading it) and status.

    ``sources`` are the file-level metadata sources (name, fields) in priority order
    (the manifest's whole-file row, the file name); ``test_rows`` the manifest rows of its
    tests (their Test names are only checked once the file is read); ``problem`` is a
    metadata error known before reading; ``status`` is one of ``new, reduced, changed,
    failed, duplicate``; ``reason`` why the file failed (last batch or now); ``previous``
    what the state keeps of the file; ``hints`` why a source said nothing. ``where``
    is the file's path as text (:attr:`path` the :class:`~pathlib.Path`): a campaign
    holds a row per file, and a path object costs several times its text.

    The metadata (``sources``, ``merged``, ``hints``, ``test_rows``) is found from the
    file's name and the manifest when first asked for (``metadata``, when given, is
    it): a pass over the table that reads only names, stats and statuses (the plan,
    ``runs.csv`` of reduced files) matches and merges no labels. Once found it is kept
    on the (frozen) row; two rows are equal by their fields, not by what they found.
    """

    file: str
    where: str
    size: int
    mtime_ns: int
    problem: str | None
    status: str
    reason: str | None = None
    sha256: str | None = None
    previous: FileState | None = None
    metadata: _Metadata | None = field(default=None, repr=False, compare=False)
    #: the campaign and manifest the metadata is found from when first asked for
    origin: tuple[Campaign, Manifest | None] | None = field(default=None, repr=False,
                                                            compare=False)

    def _meta(self) -> _Metadata:
        """The file's metadata, found once (:func:`_file_metadata`)."""
        meta = self.metadata
        if meta is None:
            if self.origin is None:  # not read: a file that is not a regular one
                meta = _Metadata([], [], (), {}, None, False)
            else:
                meta = _file_metadata(*self.origin, self.file, self.path)
            object.__setattr__(self, "metadata", meta)
        return meta

    @property
    def sources(self) -> tuple[tuple[str, dict[str, Any]], ...]:
        """The file-level metadata sources (name, fields), in priority order."""
        return tuple(self._meta().sources)

    @property
    def merged(self) -> dict[str, Any]:
        """The labels merged from :attr:`sources` (empty when they could not be)."""
        return self._meta().merged

    @property
    def hints(self) -> tuple[str, ...]:
        """Why a metadata source said nothing of the file."""
        return tuple(self._meta().hints)

    @property
    def test_rows(self) -> tuple[ManifestRow, ...]:
        """The manifest rows of its tests (read from the manifest alone: no labels are
        merged to find them)."""
        if self.metadata is None and self.origin is not None:
            manifest = self.origin[1]
            return () if manifest is None else manifest.for_file(self.file,
                                                                 self.path.name)[1]
        return self._meta().test_rows

    @property
    def path(self) -> Path:
        """The file's path."""
        return Path(self.where)

    @property
    def labels(self) -> RunLabels:
        """The nominal labels known before reading (missing fields are ``None``)."""
        m = self.merged
        return RunLabels(
            pin=m.get("pin"), disc=m.get("disc"), normal_force_N=m.get("normal_force_N"),
            temperature_C=m.get("temperature_C"), repeat=m.get("repeat"),
            pin_as_given=m.get("pin_as_given"), disc_as_given=m.get("disc_as_given"),
        )

    @property
    def runs(self) -> tuple[RunState, ...]:
        """The runs the state knows of this file (its last batch), in file order."""
        return () if self.previous is None else self.previous.runs


def _is_tool_table(path: Path) -> bool:
    """A ``runs.csv`` or ``failures.csv`` this tool wrote (first cell ``file``)."""
    if path.name not in (RUNS_CSV, FAILURES_CSV):
        return False
    try:
        regular_file(path)  # never open a FIFO
        with path.open("rb") as fh:
            return fh.read(5) == b"file,"
    except (OSError, ReadError):
        return False


def discover_files(campaign: Campaign) -> list[Path]:
    """The campaign's raw exports, sorted by relative path: every file of ``raw_dir``
    with a suffix the readers know (any case), or the campaign's ``glob``; never hidden
    files, the manifest, campaign configs, or the tool's own outputs (see the module
    docstring). What matches but is not a regular file (a folder, a FIFO, a symlink
    loop) is kept: :func:`campaign_table` lists it as failed, with its reason."""
    root = campaign.raw_dir
    if campaign.glob is None:
        # one scandir: the directory entries carry their type, no stat per file
        with os.scandir(root) as it:
            candidates = [Path(e.path) for e in it
                          if os.path.splitext(e.name)[1].lower() in EXPORT_SUFFIXES
                          and not e.name.startswith(".")]
    else:
        candidates = [p for p in root.glob(campaign.glob) if not p.name.startswith(".")]
    not_runs = {p for p in (campaign.manifest, campaign.source, campaign.map_path,
                            campaign.review) if p}
    layout = campaign.layout
    inside = campaign.output_dir != root and campaign.output_dir.is_relative_to(root)
    # the output folder's own files can only be met where it is, or holds, the raw folder
    outputs_here = inside or root.is_relative_to(campaign.output_dir)
    files = [
        p for p in candidates
        if p.suffix.lower() != ".toml" and not p.name.endswith(".lock")
        and p not in not_runs
        and not (inside and p.is_relative_to(campaign.output_dir))
        and not (outputs_here and layout.written_here(p)) and not _is_tool_table(p)
    ]
    return sorted(files, key=lambda p: _relative(p, root))


def discover_paths(campaign: Campaign) -> list[str]:
    """:func:`discover_files` as text (``str`` of each path, in its order), listed as
    text where that is the same: a raw folder given as an absolute path on POSIX, no
    glob, and no output folder in or around it (the usual campaign: thousands of files,
    a path object costs several times its text); else from :func:`discover_files`.

    There, an entry's path is the folder's text joined with its name (as
    :func:`os.scandir` makes it and a path object writes it), two paths are the same
    file name when their texts are, and the order by relative path is the order of the
    names."""
    root = campaign.raw_dir
    if campaign.glob is not None or os.name != "posix" or not root.is_absolute() \
            or root.is_relative_to(campaign.output_dir) \
            or campaign.output_dir.is_relative_to(root):
        return [str(p) for p in discover_files(campaign)]
    not_runs = {str(p) for p in (campaign.manifest, campaign.source, campaign.map_path,
                                 campaign.review) if p}
    base = str(root)
    with os.scandir(base) as it:
        names = [e.name for e in it
                 if os.path.splitext(e.name)[1].lower() in EXPORT_SUFFIXES
                 and not e.name.startswith(".")]
    paths = []
    for name in sorted(names):
        path = os.path.join(base, name)
        if name.lower().endswith(".toml") or name.endswith(".lock") or path in not_runs:
            continue
        if name in (RUNS_CSV, FAILURES_CSV) and _is_tool_table(Path(path)):
            continue
        paths.append(path)
    return paths


def describe_glob(campaign: Campaign) -> str:
    """The files a campaign takes, in words: its glob, or the export suffixes."""
    if campaign.glob is not None:
        return repr(campaign.glob)
    return "exports (" + ", ".join(f"*{s}" for s in EXPORT_SUFFIXES) + ", any case)"


def recipe_hash(campaign: Campaign, merged: Mapping[str, Any],
                test_rows: Sequence[ManifestRow] = ()) -> str:
    """Hash of everything besides the raw bytes that a file's records depend on: the
    settings' config hash, the labels known before reading (the file-level ones and the
    manifest rows of its tests), the QC tolerances and the test-name rules (16 hex
    digits)."""
    payload: dict[str, Any] = {"campaign": _campaign_key(campaign),
                               "labels": {k: merged.get(k) for k in LABEL_FIELDS}}
    # the reporting items and extra metadata, only when given (older hashes stay valid)
    report = {k: v for k, v in merged.items()
              if k not in LABEL_FIELDS and not k.endswith("_as_given")}
    if report or campaign.report.values or campaign.report.extra:
        payload["report"] = [sorted(report.items(), key=str), campaign.report.columns()]
    if test_rows:
        payload["tests"] = sorted(
            # a row without an interval hashes as before the interval column existed
            [r.test or "", r.line, sorted(r.fields.items()), r.problem]
            + ([r.interval] if r.interval is not None else []) for r in test_rows)
    text = _RECIPE_JSON.encode(payload)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


#: the JSON of :func:`recipe_hash` (``json.dumps(payload, sort_keys=True, default=str)``),
#: its encoder made once rather than per file
_RECIPE_JSON = json.JSONEncoder(sort_keys=True, default=str)


#: _campaign_key's figures, by the campaign's id → (that campaign, its key)
_KEYS: dict[int, tuple[Campaign, str]] = {}


def _campaign_key(campaign: Campaign) -> str:
    """The part of recipe_hash shared by every run of a campaign, computed once per
    campaign (known by identity: hashing a campaign walks its whole vocabulary)."""
    kept = _KEYS.get(id(campaign))
    if kept is not None and kept[0] is campaign:
        return kept[1]
    key = _compute_campaign_key(campaign)
    if len(_KEYS) >= 8:
        _KEYS.clear()
    _KEYS[id(campaign)] = (campaign, key)
    return key


def _compute_campaign_key(campaign: Campaign) -> str:
    payload = {
        "config": campaign.settings.config_hash,
        "tolerances": asdict(campaign.tolerances),
        # only when set, so the hashes of every other campaign stay what they were
        **({"synthetic": True} if campaign.synthetic else {}),
        # the label check, only when not the default (older hashes stay valid)
        **({"label_check": [campaign.label_check.keep_labels, campaign.label_check.force_rel]}
           if (campaign.label_check.keep_labels
               or campaign.label_check.force_rel != LABEL_FORCE_REL) else {}),
        # the labels in recipe_hash already carry the [names] aliases, except those read
        # from Test names, so the aliases only matter with a test-name pattern
        "export_names": [campaign.test_pattern, list(campaign.names)]
        if campaign.test_pattern is not None else None,
        "read": asdict(campaign.read_options),
    }
    return hashlib.sha256(json.dumps(payload, sort_keys=True, default=str).encode()).hexdigest()


def _relative(path: Path, root: Path) -> str:
    """``path`` relative to ``root`` (below it), as a POSIX path; by its text when it
    starts with the root's (as every discovered file's does: a campaign has thousands)."""
    text, prefix = str(path), str(root) + os.sep
    if text.startswith(prefix) and root.is_absolute():
        rel = text[len(prefix):]
        return rel if os.sep == "/" else rel.replace(os.sep, "/")
    return path.relative_to(root).as_posix()


class TraceListing:
    """Whether a trace (relative to the output folder) is a file on disk: those directly
    in ``traces/`` from one listing of it (a campaign has thousands), any other by a
    ``stat``."""

    def __init__(self, campaign: Campaign) -> None:
        self.output_dir = campaign.output_dir
        self.folder = campaign.layout.traces_dir.relative_to(campaign.output_dir).as_posix()
        self._listed: set[str] | None = None

    def present(self, trace: str) -> bool:
        """True when ``trace`` is a file (symlinks followed)."""
        folder, _, name = trace.rpartition("/")
        if folder != self.folder or not name:
            return (self.output_dir / trace).is_file()
        if self._listed is None:
            try:
                with os.scandir(self.output_dir / self.folder) as it:
                    self._listed = {e.name for e in it if e.is_file()}
            except OSError:
                self._listed = set()
        return name in self._listed


def _traces_present(traces: TraceListing, entry: FileState) -> bool:
    """True when every reduced run of a state entry still has its trace on disk."""
    for run in entry.runs:
        if run.status == REDUCED:
            trace = run.entry.trace if run.entry is not None else ""
            if not trace or not traces.present(trace):
                return False
    return True


#: what a :class:`CampaignTable` keeps of a file besides its name, stat and status, when
#: it has any: (path as text when it is not the raw folder's join with the name, problem,
#: reason, SHA-256, whether its metadata was read)
_Extra = tuple[str | None, str | None, str | None, str | None, bool]
#: the range of the table's stat array (signed 64-bit)
_INT64 = (-(2**63), 2**63 - 1)
#: the statuses a table row may have, by their code in :attr:`CampaignTable._status`
_STATUSES = (NEW, REDUCED, CHANGED, FAILED, DUPLICATE)


class CampaignTable(Sequence[CampaignRow]):
    """The rows of :func:`campaign_table`, in the order of the files' names, and the files
    set aside as not an export: ``not_exports`` holds ``(file, what it is)``, e.g.
    ``("notes.txt", "a text with no table …")``.

    A campaign holds a row per file, so the table keeps of each only what its row cannot
    find again, in arrays (its name, size, ``mtime_ns`` and status; its problem, reason
    and SHA-256 for the files that have them) and builds the row when it is asked for:
    its metadata from the file's name and the manifest when that row is asked for it,
    what the state keeps of it from the state's entries (as loaded). The pin and disc
    names the metadata gives are kept as the table is built (:meth:`names_given`), once
    per name: the materials check finds no row's metadata again."""

    def __init__(self, campaign: Campaign, manifest: Manifest | None,
                 entries: Mapping[str, FileState],
                 not_exports: Sequence[tuple[str, str]] = ()) -> None:
        self._campaign = campaign
        self._manifest = manifest
        #: a file's path as text is kept only when it is not this and its name (as it is
        #: for every file listed in the raw folder): joined as text, not as a path
        self._root = str(campaign.raw_dir) + os.sep
        self._entries = entries
        self._names: list[str] = []
        self._stats = array("q")  # size, mtime_ns of each file in turn
        self._status = bytearray()  # its index in _STATUSES
        self._extra: dict[int, _Extra] = {}
        self._huge: dict[int, tuple[int, int]] = {}  # a stat an int64 cannot hold
        #: the pin and disc names each file's metadata gives, ``(what, name)`` in order:
        #: one tuple per distinct list of them (a campaign repeats a few), by its index
        self._given: dict[tuple[tuple[str, str], ...], int] = {(): 0}
        self._given_list: list[tuple[tuple[str, str], ...]] = [()]  # by index
        self._given_of = array("I")  # each file's index
        self.not_exports: list[tuple[str, str]] = list(not_exports)

    def _add(self, row: CampaignRow, *, read: bool = True) -> None:
        """Keep ``row`` (its metadata read from its name and the manifest: ``read``)."""
        self._append(row.file, row.where, (row.size, row.mtime_ns), row.status, row.problem,
                     row.reason, row.sha256, read,
                     tuple(_row_materials(row)) if read else ())

    def _append(self, file: str, where: str, stat: tuple[int, int], status: str,
                problem: str | None, reason: str | None, sha: str | None, read: bool,
                given: tuple[tuple[str, str], ...]) -> None:
        """Keep a file: its name, path, size and ``mtime_ns``, status, problem, reason,
        SHA-256, whether its metadata was read and the material names it gives."""
        extra = (None if where == self._root + file else where, problem, reason, sha, read)
        if extra != (None, None, None, None, True):
            self._extra[len(self._names)] = extra
        if not all(_INT64[0] <= v <= _INT64[1] for v in stat):  # a clock far off: kept aside
            self._huge[len(self._names)] = stat
            stat = (0, 0)
        self._names.append(file)
        self._stats.extend(stat)
        self._status.append(_STATUSES.index(status))
        index = self._given.get(given)
        if index is None:
            index = self._given[given] = len(self._given_list)
            self._given_list.append(given)
        self._given_of.append(index)

    def names_given(self) -> list[tuple[str, str, str]]:
        """The pin and disc names of :func:`named_materials`, from those kept as the
        table was built: each ``(what, name, where first given)`` as many times as it is
        given, each name's in a row, the names in the order first met. What
        :func:`~tribopipe.campaign.metadata.material_problems` says of it is what it says
        of :func:`named_materials` (it names the first place of a name and how many
        more)."""
        seen: dict[tuple[str, str], list[Any]] = {}
        for at, index in enumerate(self._given_of):
            for pair in self._given_list[index]:
                first = seen.get(pair)
                if first is None:
                    seen[pair] = [display_path(self._names[at]), 1]
                else:
                    first[1] += 1
        return [(what, name, first[0]) for (what, name), first in seen.items()
                for _ in range(first[1])]

    def built_for(self, campaign: Campaign, manifest: Manifest | None) -> bool:
        """Whether this table was built for ``campaign`` (the same object) and the same
        ``manifest`` (that object, or one read from the same file with the same rows,
        values of the same types: their ``repr``): its files' metadata and recipes are
        those found now."""
        mine = self._manifest
        return campaign is self._campaign and (manifest is mine or (
            manifest is not None and mine is not None and manifest.path == mine.path
            and repr(manifest.rows) == repr(mine.rows)))

    def unchanged(self, file: str, stat: tuple[int, int],
                  previous: FileState | None) -> int | None:
        """Where ``file`` is in this table (:meth:`built_for` the campaign and manifest
        of a table built now) when its row here is the row that table would give it,
        but for the check that its traces are still on disk: reduced or a duplicate,
        with this size and ``mtime_ns`` and, from the state, this very ``previous``
        entry (so the same hash and status). Else ``None``."""
        if previous is None or self._entries.get(file) is not previous:
            return None
        at = self._find(file)
        if at is None or _STATUSES[self._status[at]] not in (REDUCED, DUPLICATE):
            return None
        kept = self._huge.get(at) or (self._stats[2 * at], self._stats[2 * at + 1])
        return at if kept == stat else None

    def _append_from(self, known: CampaignTable, at: int, where: str) -> None:
        """Keep the row ``at`` of ``known`` as it is there (:meth:`unchanged`), at
        ``where``."""
        _, problem, reason, sha, read = known._extra.get(at, (None, None, None, None, True))
        self._append(known._names[at], where,
                     known._huge.get(at) or (known._stats[2 * at], known._stats[2 * at + 1]),
                     _STATUSES[known._status[at]], problem, reason, sha, read,
                     known._given_list[known._given_of[at]])

    def __len__(self) -> int:
        return len(self._names)

    def __getitem__(self, index: Any) -> Any:
        if isinstance(index, slice):
            return [self._row(i) for i in range(len(self._names))[index]]
        return self._row(range(len(self._names))[index])

    def __iter__(self) -> Iterator[CampaignRow]:
        return (self._row(i) for i in range(len(self._names)))

    def _find(self, file: str) -> int | None:
        """The index of ``file`` (the files are sorted by name), else ``None``."""
        at = bisect_left(self._names, file)
        return at if at < len(self._names) and self._names[at] == file else None

    def files(self) -> list[str]:
        """The files' names, in the order of the rows (without building them)."""
        return list(self._names)

    def has(self, file: str) -> bool:
        """True when ``file`` is a row of the table."""
        return self._find(file) is not None

    def row(self, file: str) -> CampaignRow:
        """The row of ``file``. Raises ``KeyError`` when it has none."""
        at = self._find(file)
        if at is None:
            raise KeyError(file)
        return self._row(at)

    def states(self) -> Iterator[tuple[str, str | None, FileState | None]]:
        """Each file's name, SHA-256 (when known) and what the state keeps of it, without
        building its row."""
        for at, file in enumerate(self._names):
            extra = self._extra.get(at)
            yield file, None if extra is None else extra[3], self._entries.get(file)

    def _row(self, at: int) -> CampaignRow:
        file = self._names[at]
        where, problem, reason, sha, read = self._extra.get(at, (None, None, None, None, True))
        size, mtime_ns = self._huge.get(at) or (self._stats[2 * at], self._stats[2 * at + 1])
        # its metadata is found when asked for (not read: a file that is not a regular one)
        return CampaignRow(
            file=file, where=self._root + file if where is None else where,
            size=size, mtime_ns=mtime_ns, problem=problem,
            status=_STATUSES[self._status[at]], reason=reason, sha256=sha,
            previous=self._entries.get(file),
            origin=(self._campaign, self._manifest) if read else None)

    def not_export_notes(self) -> list[str]:
        """One line per file set aside: ``not an export: skipped: notes.txt (a text …)``."""
        return [f"not an export: skipped: {display_path(f)} ({what})"
                for f, what in self.not_exports]


@dataclass
class _Metadata:
    """What a file's name and the manifest say of it before it is read: the file-level
    sources (name, fields) in priority order, why a source said nothing (``hints``), the
    manifest rows of its tests, the merged labels (empty when they could not be merged)
    and the problem known so far; ``check_labels``: its labels can be judged before it
    is read (no per-test source may complete them)."""

    sources: list[tuple[str, dict[str, Any]]]
    hints: list[str]
    test_rows: tuple[ManifestRow, ...]
    merged: dict[str, Any]
    problem: str | None
    check_labels: bool


def _file_metadata(campaign: Campaign, manifest: Manifest | None, rel: str,
                   path: Path) -> _Metadata:
    """What the manifest and the file's name (``rel``, at ``path``) say of a file."""
    sources: list[tuple[str, dict[str, Any]]] = []
    hints: list[str] = []
    problem: str | None = None
    test_rows: tuple[ManifestRow, ...] = ()
    if manifest is not None:
        whole, test_rows = manifest.for_file(rel, path.name)
        if whole is not None:
            sources.append((f"manifest line {whole.line}", dict(whole.fields)))
            problem = whole.problem
        elif not test_rows:
            near = manifest.near_miss(path.name)
            hints.append(f"no row for it in manifest {manifest.name}" + (
                f" (did you mean its row {near!r}? name the file as it is, "
                f"{path.name!r})" if near else ""))
    if campaign.filename_pattern is not None:
        found = match_pattern(campaign.filename_pattern, path.stem)
        if found is None:
            hints.append(f"name does not match pattern {campaign.filename_pattern!r}: "
                         + pattern_break(campaign.filename_pattern, path.stem))
        else:
            sources.append(("file name", found))
    merged: dict[str, Any] = {}
    check_labels = False
    if problem is None:
        try:
            merged = merge_metadata(rel, sources, campaign)
            check_labels = not test_rows and campaign.test_pattern is None
        except CampaignError as exc:
            problem = str(exc)
    return _Metadata(sources, hints, test_rows, merged, problem, check_labels)


def _content_problem(campaign: Campaign, path: Path, rel: str) -> str | None:
    """Why an export no label source describes cannot be reduced whatever its labels: it
    holds no friction test (named for what it is) or cannot be read; ``None`` when it
    reads as a friction export (then its labels are what is missing)."""
    try:
        read_runs(path, campaign.read_options, file_hash="-")
    except ReadError as exc:
        return f"{display_path(rel)}: {exc.problem}" + (f"; hint: {exc.hint}" if exc.hint
                                                        else "")
    except (OSError, ValueError):
        return None
    return None


def campaign_table(campaign: Campaign, *, state: CampaignState | None = None,
                   manifest: Manifest | None = None,
                   known: CampaignTable | None = None) -> CampaignTable:
    """The campaign as a table, before anything runs: one row per file with its metadata
    and status (``new, reduced, changed, failed, duplicate``).

    A file counts as ``reduced`` (or ``duplicate``) when its content (SHA-256, trusted
    from the state while size and ``mtime_ns`` are unchanged) and its recipe hash match
    the last batch and the traces of its reduced runs still exist; ``failed`` when the
    same holds for a file that failed or its metadata is already known to be wrong.
    ``state`` defaults to the campaign's state file, ``manifest`` to its manifest.
    ``known``: a table built before (a batch's, for its rehearsal), whose rows are taken
    where they are provably those this one would find (:meth:`CampaignTable.unchanged`)
    and the file's traces are still on disk: its labels are not matched and merged again.
    """
    entries = (state if state is not None else load_state(campaign)).entries
    if manifest is None and campaign.manifest is not None:
        manifest = read_manifest(campaign.manifest)
    traces = TraceListing(campaign)
    rows = CampaignTable(campaign, manifest, entries)
    if known is not None and not known.built_for(campaign, manifest):
        known = None
    for path in discover_files(campaign):
        rel = _relative(path, campaign.raw_dir)
        try:
            st = regular_file(path, what="an export file")
        except ReadError as exc:
            unreadable = f"{display_path(rel)}: {exc.problem}"
            rows._add(CampaignRow(file=rel, where=str(path), size=-1, mtime_ns=-1,
                                  problem=unreadable, status=FAILED, reason=unreadable),
                      read=False)
            continue
        previous = entries.get(rel)
        at = None if known is None else known.unchanged(
            rel, (st.st_size, st.st_mtime_ns), previous)
        if known is not None and at is not None and previous is not None \
                and _traces_present(traces, previous):
            rows._append_from(known, at, str(path))
            continue
        meta = _file_metadata(campaign, manifest, rel, path)
        hints, test_rows, merged = meta.hints, meta.test_rows, meta.merged
        problem, check_labels = meta.problem, meta.check_labels
        sha = None
        status = NEW
        reason = None
        if previous is not None:
            same_stat = previous.size == st.st_size and previous.mtime_ns == st.st_mtime_ns
            try:
                sha = previous.sha256 if same_stat else file_sha256(path)
            except ReadError as exc:
                problem = problem or f"{display_path(rel)}: {exc.problem}"
            same = sha is not None and sha == previous.sha256 and \
                previous.recipe == recipe_hash(campaign, merged, test_rows)
            if same and previous.status in (REDUCED, DUPLICATE):
                status = previous.status if _traces_present(traces, previous) else CHANGED
            elif same and previous.status == FAILED:
                status, reason = FAILED, previous.reason
            else:
                status = CHANGED
        if check_labels and status not in (REDUCED, DUPLICATE):
            # the labels of a file unchanged since it landed (the same labels: its recipe
            # hash holds them) were checked when it landed
            try:
                labels_from(rel, merged, hints=hints)
            except CampaignError as exc:
                problem = str(exc)
        # content before labels: what is not an export is set aside, and an export no
        # label source describes is named for what it holds before its labels are judged
        if status in (NEW, CHANGED, FAILED) or problem is not None:
            kind = export_kind(path)
            if kind is not None:
                rows.not_exports.append((rel, kind))
                continue
            if problem is not None and not test_rows:
                problem = _content_problem(campaign, path, rel) or problem
        if problem is not None:
            status, reason = FAILED, problem
        rows._add(CampaignRow(
            file=rel, where=str(path), size=st.st_size, mtime_ns=st.st_mtime_ns,
            problem=problem, status=status, reason=reason, sha256=sha, previous=previous,
            metadata=meta,
        ))
    return rows


def _row_materials(row: CampaignRow) -> Iterator[tuple[str, str]]:
    """Each pin and disc name a row's metadata gives (its sources, then the manifest
    rows of its tests), as ``(what, name)``."""
    fields = [f for _, f in row.sources] + [r.fields for r in row.test_rows]
    for given in fields:
        for what in ("pin", "disc"):
            value = given.get(what)
            if isinstance(value, str):
                yield what, value


def named_materials(rows: Sequence[CampaignRow]) -> list[tuple[str, str, str]]:
    """Every pin and disc name the campaign's metadata gives before any export is read
    (the manifest's rows, the file names), as ``(what, name, file)``, row by row."""
    return [(what, name, display_path(row.file)) for row in rows
            for what, name in _row_materials(row)]


def check_materials(campaign: Campaign, rows: Sequence[CampaignRow]) -> None:
    """Refuse the whole campaign, before any work, when a pin or disc name its metadata
    gives is not in its materials vocabulary: one :class:`CampaignError` naming each such
    name, with a did-you-mean and a file that uses it
    (:func:`~tribopipe.campaign.metadata.material_problems`). Names read from Test names
    are checked as each export is read (that run fails alone)."""
    named = rows.names_given() if isinstance(rows, CampaignTable) else named_materials(rows)
    problems = material_problems(campaign, named)
    if problems:
        raise CampaignError(
            f"{len(problems)} material name(s) not in the vocabulary, nothing reduced: "
            + joined_problems(problems),
            path=campaign.source or campaign.raw_dir, hint=ADD_HINT)


def campaign_listing(campaign: Campaign) -> list[dict[str, Any]]:
    """The campaign table as JSON-ready dicts, for ``tribopipe campaign list``: one per run.

    Keys: ``file, test, result, interval, run, status, pin, disc, normal_force_N,
    temperature_C, repeat, mu_s, mu_k, flags, measurement_id, sources, reason``. A file
    that is not an export is listed last with the status :data:`NOT_AN_EXPORT`. A file
    the last batch read gives a row per run it found (and per test without a friction
    interval), with the labels it used (so they include fields read from Test names) and
    μ values for reduced runs; a file not read yet gives a row per test its manifest rows
    name, else one row (its tests are known once it is read).
    """
    out: list[dict[str, Any]] = []
    table = campaign_table(campaign)
    for row in table:
        base = {k: row.merged.get(k) for k in LABEL_FIELDS}
        sources = [name for name, _ in row.sources]
        if row.status in (REDUCED, DUPLICATE) and row.runs:
            for run in row.runs:
                flat = run.flat()
                out.append(_listed(row.file, flat, run.status or row.status,
                                   run.labels or base, sources, run.reason,
                                   values=flat if run.entry is not None else {}))
        elif row.status in (NEW, CHANGED) and row.test_rows:
            for test_row in row.test_rows:
                labels = {**base, **{k: v for k, v in test_row.fields.items()
                                     if base.get(k) is None}}
                out.append(_listed(row.file, {"test": test_row.test,
                                              "interval": test_row.interval}, row.status, labels,
                                   [*sources, f"manifest line {test_row.line}"], row.reason))
        else:
            out.append(_listed(row.file, {}, row.status, base, sources, row.reason))
    for file, what in table.not_exports:  # content before labels: set aside, not failed
        out.append(_listed(file, {}, NOT_AN_EXPORT, {}, [], f"not an export: {what}"))
    return out


#: the status ``campaign list`` gives a file set aside as not an export (never a failure)
NOT_AN_EXPORT = "skipped (not an export)"


def _listed(file: str, run: Mapping[str, Any], status: str, labels: Mapping[str, Any],
            sources: list[str], reason: str | None, *,
            values: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """One row of :func:`campaign_listing`."""
    values = values or {}
    return {
        "file": file,
        "test": run.get("test"),
        "result": run.get("result"),
        "interval": run.get("interval"),
        "run": run.get("name") or file,
        "status": status,
        **{k: labels.get(k) for k in LABEL_FIELDS},
        "mu_s": values.get("mu_s"),
        "mu_k": values.get("mu_k"),
        "flags": values.get("flags"),
        "measurement_id": values.get("measurement_id"),
        "sources": sources,
        "reason": reason,
    }


def manifest_template(campaign: Campaign) -> tuple[str, list[tuple[str, str]]]:
    """A manifest to fill in for a campaign's folder (``tribopipe campaign manifest``):
    ``(CSV text, files set aside as not an export)``. One row per export found
    (:func:`discover_files`; what :func:`tribopipe.readers.export_kind` calls no export
    is left out and returned), columns :data:`MANIFEST_COLUMNS`; the labels the
    campaign's file-name pattern finds are filled in, the rest left empty. The text
    starts with a UTF-8 BOM, so a spreadsheet opens it as UTF-8, and every cell is safe
    for a spreadsheet (:func:`~tribopipe.escape.csv_cell`; the manifest reader undoes
    it)."""
    buffer = io.StringIO()
    out = csv.writer(buffer, lineterminator="\n")
    out.writerow(MANIFEST_COLUMNS)
    skipped: list[tuple[str, str]] = []
    for path in discover_files(campaign):
        rel = _relative(path, campaign.raw_dir)
        kind = export_kind(path)
        if kind is not None:
            skipped.append((rel, kind))
            continue
        found = (match_pattern(campaign.filename_pattern, path.stem)
                 if campaign.filename_pattern is not None else None) or {}
        cells = [rel] + [_template_cell(found.get(k)) for k in LABEL_FIELDS]
        out.writerow([csv_cell(c) for c in cells])
    return "\ufeff" + buffer.getvalue(), skipped


def _template_cell(value: Any) -> str:
    """A label as a manifest cell: numbers without a needless ``.0``, missing as empty."""
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)

"""The friction map as a folder of immutable Parquet parts and one small manifest.

A map at ``processed/friction_map.parquet`` is a folder (a Parquet *dataset*)::

    friction_map.parquet/
        _manifest.json          the committed map: its parts, in order, with checksums
        _manifest.json.bak      the previous commit (its parts are kept until the next one)
        part-000007-3fa9c1d2.parquet
        part-000012-b04e6a7f.parquet
        ...

Each part is a complete friction-map Parquet file (our schema metadata and the checksum
of its rows inside), written once to a temporary name, fsynced and renamed, and never
changed again. The manifest names the parts in row order with each file's SHA-256, size,
row count and schema version; a commit writes a new manifest the same way and renames it
over the old one, which it keeps as ``_manifest.json.bak``. So the map is always one
committed manifest and the parts it names: a writer killed at any moment leaves the last
commit, and a part changed on disk fails its checksum and is refused.

Parts named by no kept manifest (a killed writer's, or those a compaction replaced two
commits ago) and temporary files are removed by the next commit, under the map's lock.
Other tools read the folder as one table (``pandas.read_parquet``, DuckDB's
``read_parquet('friction_map.parquet/*.parquet')``) once such leftovers are gone; tribopipe
itself reads only the parts the manifest names.

This module knows files, names and checksums; what a row is and the lock are the store's
(:mod:`tribopipe.frictionmap.store`).
"""

from __future__ import annotations

import hashlib
import json
import os
import secrets
from collections.abc import Iterator, Mapping
from contextlib import suppress
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, BinaryIO

from ..errors import MapError
from ..files import fsync_dir, os_reason

#: the manifest's file name inside the map folder (a leading ``_``: Parquet readers of the
#: folder skip it)
MANIFEST = "_manifest.json"
#: the previous commit's manifest
MANIFEST_BACKUP = MANIFEST + ".bak"
#: what the manifest says it is, and the version of its layout
FORMAT = "tribopipe.frictionmap.parts"
FORMAT_VERSION = 1
#: a manifest larger than this is not read (a million parts is far beyond any map)
MAX_MANIFEST_BYTES = 256 * 1024 * 1024


@dataclass(frozen=True)
class Part:
    """One immutable part of a map: its file name in the folder, its rows, the SHA-256
    and size in bytes of the file, and the schema version its rows were written in."""

    file: str
    n_runs: int
    sha256: str
    bytes: int
    schema_version: int

    def as_json(self) -> dict[str, Any]:
        """The part as the manifest stores it (its fields, in their order)."""
        return asdict(self)


@dataclass(frozen=True)
class GroupsFile:
    """The stored condition groups of a commit (:mod:`~tribopipe.frictionmap.stored_groups`):
    the file's name in the folder (under :data:`GROUPS_DIR`), its SHA-256 and size in
    bytes, and how many group rows it holds."""

    file: str
    sha256: str
    bytes: int
    n_groups: int

    def as_json(self) -> dict[str, Any]:
        """The groups file as the manifest stores it (its fields, in their order)."""
        return asdict(self)


@dataclass(frozen=True)
class Manifest:
    """A committed map: its parts in row order, the commit's number (``generation``,
    counting up from 1), when and by which tribopipe it was written, and the labs'
    sources the rows name (``sources``)."""

    generation: int
    parts: tuple[Part, ...]
    written_at: str
    tribopipe_version: str
    sources: tuple[str, ...] = ()
    groups: GroupsFile | None = None

    @property
    def n_runs(self) -> int:
        """The number of rows of the map."""
        return sum(p.n_runs for p in self.parts)

    def as_json(self) -> dict[str, Any]:
        """The manifest's JSON object, with ``manifest_sha256``: the digest of the rest."""
        body = {"format": FORMAT, "format_version": FORMAT_VERSION,
                "generation": self.generation, "written_at": self.written_at,
                "tribopipe_version": self.tribopipe_version, "n_runs": self.n_runs,
                "sources": list(self.sources), "parts": [p.as_json() for p in self.parts]}
        if self.groups is not None:  # a manifest without it reads as before
            body["groups"] = self.groups.as_json()
        return {**body, "manifest_sha256": _digest(body)}


def _digest(body: Mapping[str, Any]) -> str:
    return hashlib.sha256(json.dumps(body, sort_keys=True, ensure_ascii=False)
                          .encode("utf-8", "surrogatepass")).hexdigest()


def is_parts_map(path: Path) -> bool:
    """True when ``path`` is a folder (a map of parts, or something to refuse as one)."""
    return path.is_dir()


def manifest_path(folder: Path) -> Path:
    """The committed manifest of the map folder ``folder``."""
    return folder / MANIFEST


def backup_manifest_path(folder: Path) -> Path:
    """The previous commit's manifest of the map folder ``folder``."""
    return folder / MANIFEST_BACKUP


def restore_hint(folder: Path) -> str:
    """How to go back to the previous commit of a damaged map folder."""
    backup = backup_manifest_path(folder)
    if backup.is_file():
        return (f"restore its previous version by renaming {backup.name} to {MANIFEST} in "
                "the map folder, or restore it from a backup")
    return "restore it from a backup"


def _refuse(folder: Path, problem: str) -> MapError:
    return MapError(problem, path=folder, hint=restore_hint(folder) +
                    "; nothing in the folder is ever overwritten, or pass another --map")


def _read_at_most(fh: BinaryIO, limit: int) -> bytes:
    """The first ``limit`` bytes of ``fh`` (all of it when shorter), read a MiB at a time:
    a buffer of ``limit`` bytes is never made for a file of a few kB."""
    chunks: list[bytes] = []
    size = 0
    while size < limit:
        chunk = fh.read(min(1 << 20, limit - size))
        if not chunk:
            break
        chunks.append(chunk)
        size += len(chunk)
    return b"".join(chunks)


def read_manifest(folder: Path) -> Manifest:
    """The committed manifest of ``folder``, checked: its JSON, its own digest, every part
    named as a plain file name of this folder with a checksum, a size and a row count.
    Raises :class:`MapError` in one line naming the folder."""
    path = manifest_path(folder)
    try:
        with open(path, "rb") as fh:
            raw = _read_at_most(fh, MAX_MANIFEST_BYTES + 1)
    except FileNotFoundError:
        raise _refuse(folder, f"a folder without {MANIFEST}: not a tribopipe friction map "
                              "of parts (or its manifest is lost)") from None
    except OSError as exc:
        raise MapError(f"cannot read the map's manifest ({os_reason(exc)})",
                       path=folder) from None
    if len(raw) > MAX_MANIFEST_BYTES:
        raise _refuse(folder, f"{MANIFEST} is larger than {MAX_MANIFEST_BYTES} bytes")
    try:
        data = json.loads(raw.decode("utf-8"))
    except (ValueError, UnicodeDecodeError, RecursionError):
        raise _refuse(folder, f"{MANIFEST} is not valid JSON (damaged)") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise _refuse(folder, f"{MANIFEST} is not a tribopipe friction-map manifest")
    version = data.get("format_version")
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise _refuse(folder, f"{MANIFEST} names no format version")
    if version > FORMAT_VERSION:
        raise MapError(f"map folder format version {version}; this tribopipe reads up to "
                       f"{FORMAT_VERSION}", path=folder, hint="upgrade tribopipe")
    stored = data.pop("manifest_sha256", None)
    if stored != _digest(data):
        raise _refuse(folder, f"{MANIFEST} fails its checksum (damaged, or changed by "
                              "another program)")
    try:
        parts = tuple(_part(p) for p in data["parts"])
        manifest = Manifest(generation=_count(data["generation"]), parts=parts,
                            written_at=str(data["written_at"]),
                            tribopipe_version=str(data["tribopipe_version"]),
                            sources=tuple(str(s) for s in data.get("sources", ())),
                            groups=_groups(data.get("groups")))
    except (KeyError, TypeError, ValueError) as exc:
        raise _refuse(folder, f"{MANIFEST} is malformed ({exc})") from None
    if manifest.n_runs != data.get("n_runs"):
        raise _refuse(folder, f"{MANIFEST} counts {data.get('n_runs')!r} runs, its parts "
                              f"{manifest.n_runs}")
    if len({p.file for p in parts}) != len(parts):
        raise _refuse(folder, f"{MANIFEST} names one part twice")
    return manifest


def _count(value: Any) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or value < 0:
        raise ValueError(f"{value!r} is not a count")
    return value


def _part(entry: Any) -> Part:
    if not isinstance(entry, dict):
        raise TypeError("a part is not an object")
    name = entry["file"]
    base = name.removeprefix(PREVIOUS + "/") if isinstance(name, str) else name
    if (not isinstance(base, str) or not base.startswith("part-")
            or not base.endswith(".parquet") or "/" in base or "\\" in base
            or base != os.path.basename(base) or "\x00" in base):
        raise ValueError(f"part name {name!r} is not a part of this folder")
    sha = entry["sha256"]
    if not isinstance(sha, str) or len(sha) != 64:
        raise ValueError(f"part {name!r} has no checksum")
    return Part(file=name, n_runs=_count(entry["n_runs"]), sha256=sha,
                bytes=_count(entry["bytes"]),
                schema_version=max(1, _count(entry["schema_version"])))


#: the subfolder of the stored groups files (a leading ``_``: readers of the map folder
#: as a Parquet dataset skip it)
GROUPS_DIR = "_groups"


def _groups(entry: Any) -> GroupsFile | None:
    if entry is None:
        return None
    if not isinstance(entry, dict):
        raise TypeError("the groups entry is not an object")
    name = entry["file"]
    base = name.removeprefix(GROUPS_DIR + "/") if isinstance(name, str) else name
    if (not isinstance(name, str) or not name.startswith(GROUPS_DIR + "/")
            or not base.startswith("groups-") or not base.endswith(".parquet")
            or base != os.path.basename(base) or "\\" in base or "\x00" in base):
        raise ValueError(f"groups file name {name!r} is not one of this folder")
    sha = entry["sha256"]
    if not isinstance(sha, str) or len(sha) != 64:
        raise ValueError(f"groups file {name!r} has no checksum")
    return GroupsFile(file=name, sha256=sha, bytes=_count(entry["bytes"]),
                      n_groups=_count(entry["n_groups"]))


def read_groups_bytes(folder: Path, groups: GroupsFile) -> bytes:
    """The bytes of the stored groups file ``groups``, checked against its size and
    SHA-256 in the manifest (a changed file is refused, as a changed part is)."""
    path = folder / groups.file
    try:
        if path.is_symlink() or not path.is_file():
            raise _refuse(folder, f"{groups.file} named by {MANIFEST} is missing or not a "
                                  "regular file")
        data = path.read_bytes()
    except OSError as exc:
        raise MapError(f"cannot read {groups.file} ({os_reason(exc)})", path=folder) from None
    if len(data) != groups.bytes or hashlib.sha256(data).hexdigest() != groups.sha256:
        raise _refuse(folder, f"{groups.file} fails its checksum: its bytes are not those "
                              "tribopipe wrote (damaged on disk, or changed by another "
                              "program); refusing to read or overwrite the map")
    return data


def write_groups(folder: Path, generation: int, data: bytes, n_groups: int,
                 mode: int | None = None) -> GroupsFile:
    """Write a new stored groups file holding ``data`` into ``folder``'s
    :data:`GROUPS_DIR`, fsynced (with the folder), under a fresh name of commit
    ``generation``; the map's only once a manifest naming it is committed."""
    sub = folder / GROUPS_DIR
    sub.mkdir(exist_ok=True)
    for _ in range(100):
        name = f"groups-{generation:06d}-{secrets.token_hex(4)}.parquet"
        if not (sub / name).exists():
            break
    _write_new(sub, name, data, mode)
    fsync_dir(sub)
    return GroupsFile(file=f"{GROUPS_DIR}/{name}", sha256=hashlib.sha256(data).hexdigest(),
                      bytes=len(data), n_groups=n_groups)


def read_part_bytes(folder: Path, part: Part) -> bytes:
    """The bytes of ``part``, checked against its size and SHA-256 in the manifest: a part
    changed after it was written (by another program, or damage) is refused."""
    path = folder / part.file
    try:
        if path.is_symlink() or not path.is_file():
            raise _refuse(folder, f"part {part.file} named by {MANIFEST} is missing or not "
                                  "a regular file")
        data = path.read_bytes()
    except OSError as exc:
        raise MapError(f"cannot read part {part.file} ({os_reason(exc)})",
                       path=folder) from None
    if len(data) != part.bytes or hashlib.sha256(data).hexdigest() != part.sha256:
        raise _refuse(folder, f"part {part.file} fails its checksum: its bytes are not "
                              "those tribopipe wrote (damaged on disk, or changed by another "
                              "program); refusing to read or overwrite the map")
    return data


def _write_new(folder: Path, final: str, data: bytes | memoryview, mode: int | None) -> None:
    """Write ``data`` to ``folder/final`` through a fsynced temporary file and a rename
    (a part's ``final`` does not exist yet: parts are never overwritten; a manifest's
    rename replaces the one before it)."""
    tmp = folder / f".{final}.{os.getpid()}.{secrets.token_hex(4)}.tmp"
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        if mode is not None:
            with suppress(OSError):
                os.fchmod(fd, mode)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, folder / final)
    except BaseException:
        with suppress(OSError):
            tmp.unlink()
        raise


def write_part(folder: Path, generation: int, data: bytes | memoryview, n_runs: int,
               schema_version: int, mode: int | None = None) -> Part:
    """Write a new part holding ``data`` (a friction-map Parquet file of ``n_runs`` rows)
    into ``folder``, fsynced, under a fresh name of commit ``generation``; it is part of
    the map only once a manifest naming it is committed (:func:`commit`)."""
    for _ in range(100):
        name = f"part-{generation:06d}-{secrets.token_hex(4)}.parquet"
        if not (folder / name).exists():
            break
    _write_new(folder, name, data, mode)
    return Part(file=name, n_runs=n_runs, sha256=hashlib.sha256(data).hexdigest(),
                bytes=len(data), schema_version=schema_version)


#: the subfolder where the parts only the previous commit names are kept (a leading
#: ``_``: readers of the map folder skip it, so they see the committed rows only)
PREVIOUS = "_previous"


def _write_json(folder: Path, final: str, manifest: Manifest, mode: int | None) -> None:
    data = (json.dumps(manifest.as_json(), ensure_ascii=False, indent=1) + "\n").encode(
        "utf-8", "surrogatepass")
    _write_new(folder, final, data, mode)


def _link(src: Path, dst: Path) -> None:
    if dst.exists():
        return
    tmp = dst.with_name(f".{dst.name}.{os.getpid()}.tmp")
    with suppress(FileNotFoundError):
        tmp.unlink()
    os.link(src, tmp)
    os.replace(tmp, dst)


def settle(folder: Path, parts: tuple[Part, ...]) -> tuple[Part, ...]:
    """``parts`` to keep in a new commit, each in the map folder itself: a part kept in
    :data:`PREVIOUS` (a restored commit's) is linked back beside the others."""
    out = []
    for part in parts:
        if part.file.startswith(PREVIOUS + "/"):
            name = part.file.split("/", 1)[1]
            _link(folder / part.file, folder / name)
            part = Part(name, part.n_runs, part.sha256, part.bytes, part.schema_version)
        out.append(part)
    return tuple(out)


def commit(folder: Path, manifest: Manifest, previous: Manifest | None,
           mode: int | None = None) -> None:
    """Make ``manifest`` the map's, ``previous`` (the committed one) kept as
    ``_manifest.json.bak``: the parts only ``previous`` names are linked into
    :data:`PREVIOUS` (where readers of the folder do not see them) and the backup names
    them there; the new manifest is written to a fsynced temporary file and renamed over
    the committed one; the folder is fsynced. Every part ``manifest`` names must be in
    the folder itself, written and fsynced already. The caller holds the map's lock."""
    if previous is not None:
        current = {p.file for p in manifest.parts}
        gone = [p for p in previous.parts if p.file not in current]
        if gone:
            (folder / PREVIOUS).mkdir(exist_ok=True)
        moved = []
        for part in previous.parts:
            if part.file in current or part.file.startswith(PREVIOUS + "/"):
                moved.append(part)
                continue
            _link(folder / part.file, folder / PREVIOUS / part.file)
            moved.append(Part(f"{PREVIOUS}/{part.file}", part.n_runs, part.sha256,
                              part.bytes, part.schema_version))
        _write_json(folder, MANIFEST_BACKUP,
                    Manifest(previous.generation, tuple(moved), previous.written_at,
                             previous.tribopipe_version, previous.sources,
                             previous.groups), mode)
    fsync_dir(folder)  # new parts and the backup are durable before the manifest names them
    _write_json(folder, MANIFEST, manifest, mode)
    fsync_dir(folder)


def kept_parts(folder: Path) -> set[str]:
    """The part files (relative to ``folder``) named by the committed manifest or the
    previous one (those a restore of the previous commit needs)."""
    kept: set[str] = set()
    for path in (manifest_path(folder), backup_manifest_path(folder)):
        try:
            data = json.loads(path.read_bytes())
            kept |= {str(p["file"]) for p in data["parts"]}
            if isinstance(data.get("groups"), dict):
                kept.add(str(data["groups"]["file"]))
        except (OSError, ValueError, KeyError, TypeError, UnicodeDecodeError):
            continue
    return kept


def leftovers(folder: Path) -> Iterator[Path]:
    """Files of ``folder`` that belong to no kept commit: temporary files of a killed
    writer and parts no kept manifest names."""
    kept = kept_parts(folder)
    for sub, prefix in ((folder, ""), (folder / PREVIOUS, PREVIOUS + "/"),
                        (folder / GROUPS_DIR, GROUPS_DIR + "/")):
        try:
            entries = list(sub.iterdir())
        except OSError:
            continue
        for entry in entries:
            name = entry.name
            if name.startswith(".") and name.endswith(".tmp"):
                yield entry
            elif (name.startswith(("part-", "groups-")) and name.endswith(".parquet")
                  and prefix + name not in kept):
                yield entry


def collect_garbage(folder: Path) -> int:
    """Remove :func:`leftovers` (under the map's lock); returns how many were removed."""
    removed = 0
    for entry in list(leftovers(folder)):
        with suppress(OSError):
            entry.unlink()
            removed += 1
    return removed


def file_mode(path: Path) -> int | None:
    """The permission bits of ``path``, or ``None`` when it does not exist."""
    import stat

    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        return None

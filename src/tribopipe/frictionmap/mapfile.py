"""The friction-map file: what a map's Parquet file must be to be read, and its metadata.

:func:`read_map` is the one reader of a map file. It refuses in one
:class:`~tribopipe.errors.MapError` line, naming the path and where to restore the map
from (:func:`backup_path`, the previous version every rewrite keeps), a path that is not
a regular file (never opened), a file that is not Parquet or whose buffers or text are
damaged, a Parquet file without our metadata (a foreign file), a newer schema, a missing
column, a column stored with another Arrow type, a row that breaks
:func:`~tribopipe.frictionmap.schema.check_runs`, and a map whose rows fail the checksum
stored in its metadata (:func:`~tribopipe.frictionmap.schema.content_sha256`). The writer
(:mod:`tribopipe.frictionmap.store`) puts that metadata in with :func:`map_info`.
"""

from __future__ import annotations

import json
import os
import stat
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import __version__
from ..errors import MapError, ReadError
from ..escape import display_path
from ..files import file_kind, os_reason, regular_file
from .schema import (
    ADDED_IN_VERSION,
    COLUMNS,
    KIND,
    META_KEY,
    RUN_COLUMNS,
    SCHEMA_NAME,
    SCHEMA_VERSION,
    check_runs,
    content_sha256,
    empty_map,
    utc_now,
)

if TYPE_CHECKING:
    import pandas as pd


def backup_path(path: str | os.PathLike[str]) -> Path:
    """Where the previous version of the map at ``path`` is kept: ``<map>.bak`` (a hard
    link made by every rewrite, so it costs no copy)."""
    p = Path(path)
    return p.with_name(p.name + ".bak")


def _restore_hint(path: Path) -> str:
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
    """
    import pyarrow.parquet as pq

    p = Path(path)
    try:
        st = os.stat(p)
    except FileNotFoundError:
        return empty_map()
    except OSError as exc:
        raise MapError(f"cannot read the friction map: {os_reason(exc)}", path=p) from None
    if not stat.S_ISREG(st.st_mode):
        raise MapError(f"is {file_kind(st.st_mode)}, expected a friction-map Parquet file; "
                       "not opened", path=p, hint="pass another --map")
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
    if runs["measurement_id"].duplicated().any():
        dup = runs.loc[runs["measurement_id"].duplicated(), "measurement_id"].iloc[0]
        raise MapError(f"duplicate measurement_id {dup}", path=p, column="measurement_id")
    return runs


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    first = text.splitlines()[0][:160] if text else ""
    return f"{type(exc).__name__}: {first}" if first else type(exc).__name__


def map_metadata(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The schema and provenance a map carries in its Parquet metadata: ``schema``,
    ``schema_version``, ``columns`` (name, kind, unit, meaning), ``tribopipe_version`` and
    ``written_at`` of the last write, ``n_runs``, ``sources``, ``content_sha256``.
    Validated like :func:`read_map` (the rows are not read)."""
    import pyarrow.parquet as pq

    p = Path(path)
    try:
        regular_file(p, what="a friction-map Parquet file")
        schema = pq.read_schema(p)
    except ReadError as exc:
        raise MapError(exc.problem, path=p) from None
    except Exception as exc:  # noqa: BLE001 - pyarrow raises many types for a damaged file
        raise _damaged(p, f"not a readable Parquet file ({_first_line(exc)})") from None
    return _check_metadata(schema.metadata or {}, p)


def _with_added_columns(table: Any, version: int) -> Any:
    """``table`` with the columns a map of schema ``version`` could not have had (those of
    :data:`ADDED_IN_VERSION` added later) appended as all missing."""
    import pyarrow as pa

    types = {"str": pa.string(), "float": pa.float64(), "int": pa.int64()}
    for name in RUN_COLUMNS:
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


def _from_arrow(table: Any) -> pd.DataFrame:
    """The map DataFrame of an Arrow table of the run columns, coerced column by column
    (vectorised: the read path of every command) and validated. Each column must be
    stored with an Arrow type of its kind (``excluded`` stored as the text ``"false"`` is
    refused, not read as true)."""
    import pandas as pd

    for name in RUN_COLUMNS:
        arrow_type = table.schema.field(name).type
        if not _arrow_type_ok(KIND[name], arrow_type):
            kind = KIND[name]
            raise MapError(f"expected {kind} values, stored as {arrow_type}, not "
                           f"{'text' if kind == 'str' else kind}", column=name)
    try:
        # our own columns only, without the pandas metadata (a damaged copy of it must
        # not decide how the rows are read)
        frame = table.replace_schema_metadata(None).to_pandas(ignore_metadata=True)
    except Exception as exc:  # noqa: BLE001 - a damaged column
        raise MapError(f"cannot read the rows ({_first_line(exc)})") from None
    columns: dict[str, Any] = {}
    for name in RUN_COLUMNS:
        kind = KIND[name]
        col = frame[name]
        try:
            if kind == "float":
                columns[name] = pd.to_numeric(col, errors="raise").astype("float64").to_numpy()
            elif kind == "int":
                columns[name] = pd.array(col, dtype="Int64")
            elif kind == "bool":
                if col.isna().any():
                    raise ValueError("missing true/false")
                columns[name] = col.astype(bool).to_numpy()
            else:
                columns[name] = pd.array(col.astype(object).where(col.notna(), None), dtype="str")
        except (TypeError, ValueError, OverflowError) as exc:
            raise MapError(f"expected {kind} values ({exc})", column=name) from None
    runs = pd.DataFrame(columns, columns=list(RUN_COLUMNS), index=pd.RangeIndex(len(frame)))
    return check_runs(runs, "row")


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
    info = {
        "schema": SCHEMA_NAME,
        "schema_version": SCHEMA_VERSION,
        "columns": [
            {"name": c.name, "kind": c.kind, "unit": c.unit, "meaning": c.meaning}
            for c in COLUMNS
        ],
        "tribopipe_version": __version__,
        "written_at": utc_now(),
        "n_runs": len(runs),
        "sources": sorted(set(runs["source"].dropna())),
        "content_sha256": content_sha256(runs),
    }
    return json.dumps(info, ensure_ascii=False).encode()

"""The friction map as a Frictionless Data Package: the standard's JSON, and reading a package
someone sent without trusting it.

A package is a folder with a ``datapackage.json`` descriptor (Data Package and Table Schema
v1, profile ``data-package``) that lists its resources with their paths, sizes
(``bytes``), SHA-256 checksums (``hash``), licences, sources and, for tables, a Table Schema
whose fields carry a ``unit`` (a tribopipe property beside the standard ones). tribopipe
writes the descriptor itself rather than through the ``frictionless`` library (that
decision, with its measured cost, is in ``docs/DESIGN.md``); the tests check the packages
it writes with ``frictionless``.

Everything here treats a package as hostile:

* the descriptor is read only up to :attr:`PackageLimits.descriptor_bytes`, its nesting is
  counted before it is parsed (:attr:`PackageLimits.json_depth`), duplicate keys, ``NaN``
  and numbers too long to convert are refused;
* a resource's path must be a relative POSIX path inside the package folder: URLs, absolute
  paths, drive letters, backslashes, ``..`` and empty segments are refused, and so is a
  symbolic link that leads outside; only regular files are opened (never a FIFO or device),
  and only up to :attr:`PackageLimits.resource_bytes`;
* CSV cells are parsed by their field's type with strict lexical rules (no ``nan``, no
  ``1_000``, bounded lengths), one :class:`Problem` per cell.
"""

from __future__ import annotations

import codecs
import csv
import hashlib
import io
import json
import os
import re
import stat
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any

from ..errors import MapError
from ..validate import MU
from .schema import ADDED_IN_VERSION, ALWAYS, COLUMNS, IN_PACKAGES

#: the descriptor's file name in a package folder
DESCRIPTOR = "datapackage.json"
#: the descriptor's profile (Data Package v1; its tables are "tabular-data-resource"s, the
#: other files plain resources, so the package as a whole is a "data-package")
PROFILE = "data-package"
#: key of tribopipe's own block in the descriptor (schema, version, lab, ...)
TRIBOPIPE_KEY = "tribopipe"
#: Table Schema type of each map column kind
TABLE_TYPES = {"str": "string", "float": "number", "int": "integer", "bool": "boolean"}
#: the first bytes of a Parquet file (a friction map given where a package was expected)
PARQUET_MAGIC = b"PAR1"
#: how booleans are written in the package's CSV
TRUE, FALSE = "true", "false"

_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_INTEGER = re.compile(r"[-+]?\d{1,18}")
_SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.\-]*:")
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


@dataclass(frozen=True)
class PackageLimits:
    """Bounds on what reading a package may cost: descriptor size [bytes] and nesting
    depth, number of resources and of fields per schema, size of each resource file
    [bytes], characters per CSV cell, and how many problems are listed before the rest are
    counted."""

    descriptor_bytes: int = 1 << 20
    json_depth: int = 32
    resources: int = 64
    fields: int = 256
    resource_bytes: int = 512 << 20
    cell_chars: int = 10_000
    problems: int = 200


@dataclass(frozen=True)
class Problem:
    """One problem of a package: ``where`` names the file (and row, field) it is in."""

    where: str
    problem: str

    def __str__(self) -> str:
        return f"{self.where}: {self.problem}"


#: the limits a package is read with unless told otherwise
DEFAULT_LIMITS = PackageLimits()


class PackageRefused(MapError):
    """A package that cannot be read further (no descriptor, a bomb, ...): one line."""


# --------------------------------------------------------------------------- the standard's JSON


def field(name: str, kind: str, unit: str, meaning: str, **constraints: Any) -> dict[str, Any]:
    """One Table Schema field: ``name``, ``type`` (from a map column kind of
    :data:`TABLE_TYPES`), ``description``, the ``unit`` when there is one and any
    ``constraints``."""
    out: dict[str, Any] = {"name": name, "type": TABLE_TYPES[kind], "description": meaning}
    if unit:
        out["unit"] = unit
    if constraints:
        out["constraints"] = constraints
    return out


def run_columns(version: int) -> tuple[str, ...]:
    """The run columns of map schema ``version`` (those added later left out)."""
    return tuple(c.name for c in COLUMNS if ADDED_IN_VERSION.get(c.name, 1) <= version)


def runs_fields(version: int | None = None) -> list[dict[str, Any]]:
    """The Table Schema fields of the runs table (one per map column of schema ``version``,
    default: the current one), derived from the table of row rules
    (:data:`tribopipe.frictionmap.schema.COLUMNS`): units, ``required`` (the columns
    required in every row and those required in a package), ``unique`` for the id, and the
    physical bounds as ``minimum``/``maximum`` (Table Schema v1 has no strict bound: a
    strict one is written as ``minimum`` and checked strictly by
    :func:`~tribopipe.frictionmap.checks.validate_runs`)."""
    columns = set(run_columns(version)) if version is not None else None
    fields = []
    for column in COLUMNS:
        if columns is not None and column.name not in columns:
            continue
        constraints: dict[str, Any] = {}
        if column.required in (ALWAYS, IN_PACKAGES):
            constraints["required"] = True
        if column.name == "measurement_id":
            constraints["unique"] = True
        if column.bounds is not None:
            constraints["minimum"] = column.bounds.low
            constraints["maximum"] = column.bounds.high
        if column.choices:
            constraints["enum"] = list(column.choices)
        f = field(column.name, column.kind, column.unit, column.meaning, **constraints)
        if column.name == "reduced_at":
            f["type"] = "datetime"
        fields.append(f)
    return fields


def table_schema(fields: Sequence[Mapping[str, Any]], *,
                 primary_key: str | None = None,
                 foreign_keys: Mapping[str, tuple[str, str]] | None = None) -> dict[str, Any]:
    """A Table Schema of ``fields``: missing values are empty cells, booleans
    ``true``/``false``; ``foreign_keys`` maps a field to the (resource, field) it refers
    to."""
    schema: dict[str, Any] = {"fields": [dict(f) for f in fields], "missingValues": [""]}
    for f in schema["fields"]:
        if f["type"] == "boolean":
            f["trueValues"], f["falseValues"] = [TRUE], [FALSE]
    if primary_key:
        schema["primaryKey"] = primary_key
    if foreign_keys:
        schema["foreignKeys"] = [
            {"fields": name, "reference": {"resource": resource, "fields": target}}
            for name, (resource, target) in foreign_keys.items()]
    return schema


def _group_field(name: str, kind: str) -> dict[str, Any]:
    """The field of a group-statistics column, by its name (units from the suffix)."""
    known = {
        "pin": ("", "pin material"), "disc": ("", "disc material"),
        "normal_force_N": ("N", "nominal total normal force"),
        "pressure_kPa": ("kPa", "nominal contact pressure per pin"),
        "temperature_C": ("°C", "nominal temperature"),
        "nominal_speed_mm_s": ("mm/s", "nominal sliding speed of the group"),
        "sliding_speed_mm_s": ("mm/s", "measured sliding speed of the group"),
        "range_exceeds_r": ("", "the group's range exceeds the repeatability limit r"),
        "qc_flagged": ("", "the group holds a run with QC flags"),
        "run_ids": ("", "measurement ids of the group's runs, ';'-joined"),
    }
    if name == GROUP_ID:
        return field(name, kind, "", "the group's number (1, 2, …): data/group_runs.csv "
                     "lists its runs", required=True, unique=True, minimum=1)
    if name in known:
        unit, meaning = known[name]
        return field(name, kind, unit, meaning)
    quantity, suffix = (name[:4], name[5:]) if name[:5] in ("mu_k_", "mu_s_") else ("", name)
    symbol = {"mu_k": "μ_K", "mu_s": "μ_S"}.get(quantity, "")
    meanings = {
        "n": "number of repeats with a value", "mean": "mean of the repeats",
        "std": "sample standard deviation (n−1)", "sem": "standard error of the mean",
        "ci95_low": "lower end of the Student-t 95 % confidence interval",
        "ci95_high": "upper end of the Student-t 95 % confidence interval",
        "cv": "coefficient of variation (SD / mean)", "min": "smallest repeat",
        "max": "largest repeat", "values": "the repeats' values, ';'-joined",
    }
    meaning = meanings.get(suffix, suffix.replace("_", " "))
    return field(name, kind, "", f"{symbol}: {meaning}" if symbol else meaning)


def groups_fields(columns: Sequence[tuple[str, str]]) -> list[dict[str, Any]]:
    """The Table Schema fields of a group-statistics table given as ``(column, kind)``."""
    return [_group_field(name, kind) for name, kind in columns]


#: the group table's column that numbers its groups (package profile version 3 on)
GROUP_ID = "group"
#: the group-statistics columns whose cells grow with the runs of a group: a package of
#: profile version 3 leaves them out and lists each group's runs in ``group_runs.csv``
JOINED_COLUMNS: tuple[str, ...] = ("mu_k_values", "mu_s_values", "run_ids")
#: the table linking each condition group to its runs: one row per (group, run)
GROUP_RUNS_FIELDS: tuple[dict[str, Any], ...] = (
    field(GROUP_ID, "int", "", "the group's number in data/groups.csv", required=True,
          minimum=1),
    field("measurement_id", "str", "", "measurement id of one of the group's runs "
          "(data/runs.csv); each included run is in one group", required=True, unique=True),
)

#: the 7-column FrictionMap table of the founding paper's MATLAB app
FRICTIONMAP_FIELDS: tuple[dict[str, Any], ...] = (
    field("pin", "str", "", "pin material"),
    field("disc", "str", "", "disc material"),
    field("contactForce", "float", "N", "total normal force on the three pins"),
    field("contactPressure", "float", "kPa", "contact pressure per pin"),
    field("temperature", "float", "°C", "temperature"),
    field("measurementNo", "float", "", "repeat number within the condition"),
    field("cof", "float", "", "kinetic coefficient of friction μ_K", minimum=MU.low,
          maximum=MU.high),
)


def sha256_hash(data: bytes) -> str:
    """The descriptor's ``hash`` of ``data``: ``sha256:<64 hex digits>``."""
    return "sha256:" + hashlib.sha256(data).hexdigest()


# --------------------------------------------------------------------------- reading safely


def descriptor_path(path: str | os.PathLike[str]) -> Path:
    """The descriptor of a package given as its folder or as the ``datapackage.json``."""
    p = Path(path)
    return p / DESCRIPTOR if p.is_dir() else p


def _json_depth(raw: bytes) -> int:
    """The deepest nesting of arrays and objects in JSON text (strings skipped)."""
    depth = deepest = 0
    in_string = escaped = False
    for byte in raw:
        if in_string:
            if escaped:
                escaped = False
            elif byte == 0x5C:  # backslash
                escaped = True
            elif byte == 0x22:
                in_string = False
        elif byte == 0x22:
            in_string = True
        elif byte in (0x5B, 0x7B):
            depth += 1
            deepest = max(deepest, depth)
        elif byte in (0x5D, 0x7D):
            depth -= 1
    return deepest


def _no_duplicate_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"duplicate key {key!r}")
        out[key] = value
    return out


def _refuse_constant(name: str) -> Any:
    raise ValueError(f"{name} is not JSON")


def load_descriptor(path: str | os.PathLike[str],
                    limits: PackageLimits = DEFAULT_LIMITS) -> tuple[dict[str, Any], Path]:
    """The descriptor of the package at ``path`` (folder or ``datapackage.json``) and the
    package folder. Raises :class:`PackageRefused` (one line) when it is absent, not a
    regular file, larger than the limit, a Parquet file (a map, not a package), nested
    deeper than the limit, or not a JSON object."""
    desc = descriptor_path(path)
    raw = read_bounded(desc, limits.descriptor_bytes, what="descriptor")
    if raw.startswith(PARQUET_MAGIC):
        raise PackageRefused(
            "is a Parquet file (a friction map?), not a data package; `map validate` checks "
            "a package folder or its datapackage.json, and a map is checked whole on every "
            "read: run `tribopipe map show --map` on it", path=desc)
    depth = _json_depth(raw)
    if depth > limits.json_depth:
        raise PackageRefused(f"JSON nested {depth} deep, more than {limits.json_depth}",
                             path=desc)
    try:
        data = json.loads(raw.decode("utf-8-sig"), object_pairs_hook=_no_duplicate_keys,
                          parse_constant=_refuse_constant)
    except (ValueError, RecursionError) as exc:
        raise PackageRefused(f"not valid JSON ({str(exc).splitlines()[0]})",
                             path=desc) from None
    if not isinstance(data, dict):
        raise PackageRefused("expected a JSON object (a Data Package descriptor)", path=desc)
    return data, desc.parent


#: bytes read at a time by the streaming readers (hash, CSV)
BLOCK_BYTES = 1 << 20


def _open_regular(path: Path, limit: int, what: str) -> tuple[Any, int]:
    """An open binary handle on the regular file ``path`` and its size, refused like
    :func:`read_bounded`."""
    try:
        info = os.stat(path)
    except OSError as exc:
        raise PackageRefused(f"{what} not found ({exc.strerror or exc})", path=path) from None
    if not stat.S_ISREG(info.st_mode):
        raise PackageRefused(f"{what} is not a regular file", path=path)
    if info.st_size > limit:
        raise PackageRefused(f"{what} is {info.st_size} bytes, more than the limit of "
                             f"{limit}", path=path)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise PackageRefused(f"cannot read {what} ({exc.strerror or exc})", path=path) from None
    return os.fdopen(fd, "rb"), info.st_size


def file_digest(path: Path, limit: int, *, what: str = "file") -> tuple[int, str]:
    """The size [bytes] and the descriptor's ``hash`` (``sha256:…``) of the regular file
    ``path``, read in blocks (never whole in memory); refused (:class:`PackageRefused`) as
    :func:`read_bounded` refuses."""
    fh, _ = _open_regular(path, limit, what)
    digest = hashlib.sha256()
    size = 0
    try:
        with fh:
            while block := fh.read(BLOCK_BYTES):
                size += len(block)
                if size > limit:
                    raise PackageRefused(f"{what} grew beyond the limit of {limit} bytes",
                                         path=path)
                digest.update(block)
    except OSError as exc:
        raise PackageRefused(f"cannot read {what} ({exc.strerror or exc})", path=path) from None
    return size, "sha256:" + digest.hexdigest()


class NotUtf8(ValueError):
    """Text that is not UTF-8: ``byte`` is the offset of the first bad byte."""

    def __init__(self, byte: int) -> None:
        super().__init__(f"not UTF-8 (byte {byte})")
        self.byte = byte


def text_lines(path: Path, limit: int, *, what: str = "file") -> Iterator[str]:
    """The lines of the UTF-8 text file ``path`` (a leading BOM dropped), each with its
    line end, split where ``io.StringIO(text, newline="")`` splits (``\n``, ``\r``,
    ``\r\n``), read in blocks so that the file is never whole in memory. Raises
    :class:`NotUtf8` at the first byte that is not UTF-8, :class:`PackageRefused` as
    :func:`read_bounded` does."""
    fh, _ = _open_regular(path, limit, what)
    decoder = codecs.getincrementaldecoder("utf-8")()
    pending = ""
    consumed = 0
    first = True
    with fh:
        while True:
            block = fh.read(BLOCK_BYTES)
            final = not block
            buffered = len(decoder.getstate()[0])
            try:
                text = decoder.decode(block, final)
            except UnicodeDecodeError as exc:
                raise NotUtf8(consumed - buffered + exc.start) from None
            consumed += len(block)
            if first and text:
                text = text.removeprefix("\ufeff")
                first = False
            lines = io.StringIO(pending + text, newline="").readlines()
            # a line without its end yet (or a CR whose LF may follow) waits for the next
            # block
            pending = lines.pop() if lines and not final and not lines[-1].endswith(
                "\n") else ""
            yield from lines
            if final:
                return


def read_bounded(path: Path, limit: int, *, what: str = "file") -> bytes:
    """The bytes of the regular file ``path``, refused (:class:`PackageRefused`) when it is
    absent, not a regular file (a FIFO, device or folder is never opened) or larger than
    ``limit`` bytes."""
    fh, _ = _open_regular(path, limit, what)
    try:
        with fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise PackageRefused(f"cannot read {what} ({exc.strerror or exc})", path=path) from None
    if len(data) > limit:
        raise PackageRefused(f"{what} grew beyond the limit of {limit} bytes", path=path)
    return data


def resource_file(base: Path, value: Any) -> Path:
    """The file a resource's ``path`` names inside the package folder ``base``.

    Raises :class:`PackageRefused` for anything but a relative POSIX path to a place inside
    ``base``: a list of chunks, a URL or drive (``scheme:``), an absolute path, a
    backslash, a control character, an empty, ``.`` or ``..`` segment, or a symbolic link
    that leads out of the folder.
    """
    if not isinstance(value, str):
        raise PackageRefused("path must be one relative path (text); chunked or missing "
                             "paths are not accepted")
    shown = json.dumps(value)[:120]
    if not value or len(value) > 1024 or _CONTROL.search(value):
        raise PackageRefused(f"path {shown} is empty, too long or holds a control character")
    if _SCHEME.match(value) or "://" in value:
        raise PackageRefused(f"path {shown} is a URL or drive; only files inside the "
                             "package are read")
    if value.startswith("/") or "\\" in value:
        raise PackageRefused(f"path {shown} is absolute or uses backslashes; expected a "
                             "relative POSIX path inside the package")
    if any(part in ("", ".", "..") for part in value.split("/")):
        raise PackageRefused(f"path {shown} has an empty, '.' or '..' segment; expected a "
                             "path inside the package")
    root = base.resolve()
    target = (base / value).resolve()
    if not target.is_relative_to(root):
        raise PackageRefused(f"path {shown} leads outside the package (a symbolic link)")
    return target


# --------------------------------------------------------------------------- typed CSV cells


def parse_cell(text: str, ftype: str) -> Any:
    """The value of one CSV cell of Table Schema type ``ftype`` (``''`` is missing:
    ``None``). Raises ``ValueError`` saying what was expected."""
    if text == "":
        return None
    if ftype == "number":
        if len(text) > 64 or not _NUMBER.fullmatch(text):
            raise ValueError(f"{text[:40]!r} is not a number")
        return float(text)
    if ftype == "integer":
        if not _INTEGER.fullmatch(text):
            raise ValueError(f"{text[:40]!r} is not a whole number")
        return int(text)
    if ftype == "boolean":
        if text not in (TRUE, FALSE):
            raise ValueError(f"{text[:40]!r} is not {TRUE} or {FALSE}")
        return text == TRUE
    if ftype == "datetime":
        try:
            datetime.fromisoformat(text.replace("Z", "+00:00"))
        except ValueError:
            raise ValueError(f"{text[:40]!r} is not an ISO 8601 time") from None
        return text
    return text


def csv_rows(data: bytes, where: str,
             limits: PackageLimits) -> tuple[list[list[str]], Problem | None]:
    """The rows of UTF-8 CSV ``data`` (header first) and, where the text cannot be decoded
    or split (a cell longer than ``limits.cell_chars`` included), the :class:`Problem` that
    stopped the reading (the rows before it are returned)."""
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        return [], Problem(where, f"not UTF-8 (byte {exc.start})")
    rows: list[list[str]] = []
    old = csv.field_size_limit()
    csv.field_size_limit(limits.cell_chars)  # process-wide: restored before returning
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    try:
        for row in reader:
            rows.append(row)
    except csv.Error as exc:
        return rows, Problem(f"{where}: line {reader.line_num}", f"not CSV ({exc})")
    finally:
        csv.field_size_limit(old)
    return rows, None


# --------------------------------------------------------------------------- typed CSV columns

#: rows parsed at a time by :func:`read_csv_columns` (their cells are Python strings only
#: while the batch is typed)
BATCH_ROWS = 4096
_NUMBER_RE2 = "^" + _NUMBER.pattern + "$"
_INTEGER_RE2 = "^" + _INTEGER.pattern + "$"


def read_csv_columns(path: Path, fields: Sequence[Mapping[str, Any]], where: str,
                     limits: PackageLimits, add: Any) -> dict[str, Any] | None:
    """The rows of the UTF-8 CSV file ``path`` as typed columns, read in batches of
    :data:`BATCH_ROWS` rows so that no row is held as text beyond its batch.

    ``fields`` are the Table Schema fields the header must list, in order. Each cell is
    parsed by its field's type exactly as :func:`parse_cell` parses it (the common cells
    checked column-wise, any other by :func:`parse_cell` itself); every problem is handed
    to ``add(where, problem)`` in row order, then field order: a cell that does not parse
    (``row N, field F: …``), a required cell that is missing, a row of another number of
    cells (left out), and what stops the reading (not UTF-8, not CSV, a cell longer than
    ``limits.cell_chars``, a wrong header), after which ``None`` is returned.

    Returns, per field name, ``number`` as float64 (NaN missing), ``integer`` as pandas
    ``Int64``, ``boolean`` as pandas ``boolean``, other types as pandas ``str`` (missing
    NaN); a cell that does not parse is missing."""
    import numpy as np
    import pandas as pd
    import pyarrow as pa

    names = [str(f["name"]) for f in fields]
    types = [str(f["type"]) for f in fields]
    required = [bool((f.get("constraints") or {}).get("required")) for f in fields]
    chunks: list[list[Any]] = [[] for _ in names]
    n = 0
    old = csv.field_size_limit()
    csv.field_size_limit(limits.cell_chars)  # process-wide: restored before returning
    try:
        reader = csv.reader(text_lines(path, limits.resource_bytes), strict=True)
        try:
            header = next(reader, None)
            if header != names:
                add(where, "line 1: header does not list the schema's fields in order "
                    f"(expected {', '.join(names)[:200]})")
                return None
            batch: list[list[str]] = []
            numbers: list[int] = []
            short: list[tuple[int, int, str]] = []  # rows of another length, left out
            for cells in reader:
                n += 1
                if len(cells) != len(names):
                    short.append((n, -1, f"row {n}: {len(cells)} cells, expected "
                                  f"{len(names)}"))
                    continue
                batch.append(cells)
                numbers.append(n)
                if len(batch) == BATCH_ROWS:
                    _typed_batch(batch, numbers, short, names, types, required, chunks,
                                 where, add)
                    batch, numbers, short = [], [], []
            _typed_batch(batch, numbers, short, names, types, required, chunks, where, add)
        except csv.Error as exc:
            add(f"{where}: line {reader.line_num}", f"not CSV ({exc})")
            return None
        except NotUtf8 as exc:
            add(where, str(exc))
            return None
    finally:
        csv.field_size_limit(old)
    out: dict[str, Any] = {}
    for name, ftype, parts in zip(names, types, chunks, strict=True):
        if ftype == "number":
            out[name] = np.concatenate(parts) if parts else np.zeros(0)
        elif ftype == "integer":
            out[name] = pd.array(np.concatenate(parts) if parts else [], dtype="Int64")
        elif ftype == "boolean":
            out[name] = pd.array(np.concatenate(parts) if parts else [], dtype="boolean")
        else:
            out[name] = pd.array(pa.chunked_array(parts, type=pa.string()), dtype="str")
    return out


def _typed_batch(batch: list[list[str]], numbers: list[int],
                 short: list[tuple[int, int, str]], names: list[str], types: list[str],
                 required: list[bool], chunks: list[list[Any]], where: str,
                 add: Any) -> None:
    """Type one batch of rows (each of ``len(names)`` cells, ``numbers``: their row
    numbers among every data row) into ``chunks``; its problems, with those of the rows of
    another length read meanwhile (``short``), to ``add`` in row, then field order."""
    import numpy as np
    import pyarrow as pa
    import pyarrow.compute as pc

    problems: list[tuple[int, int, str]] = list(short)
    for j, (name, ftype, need) in enumerate(zip(names, types, required, strict=True)):
        texts = [cells[j] for cells in batch]
        arr = pa.array(texts, type=pa.string())
        empty = np.asarray(pc.equal(arr, ""), dtype=bool)
        if ftype in ("number", "integer"):
            pattern = _NUMBER_RE2 if ftype == "number" else _INTEGER_RE2
            fast = pc.match_substring_regex(arr, pattern)
            if ftype == "number":
                fast = pc.and_(fast, pc.less_equal(pc.utf8_length(arr), 64))
            ok = np.asarray(fast, dtype=bool)
            values: Any
            if ftype == "number":  # Arrow reads these texts as float() does
                values = np.asarray(pc.cast(pc.if_else(fast, arr, pa.scalar(None, pa.string())),
                                            pa.float64()).to_numpy(zero_copy_only=False),
                                    dtype=float).copy()
            else:
                values = np.asarray([int(t) if good else None for t, good in
                                     zip(texts, ok, strict=True)], dtype=object)
        elif ftype == "boolean":
            true = np.asarray(pc.equal(arr, TRUE), dtype=bool)
            ok = true | np.asarray(pc.equal(arr, FALSE), dtype=bool)
            values = np.asarray([bool(t) if good else None for t, good in
                                 zip(true, ok, strict=True)], dtype=object)
        elif ftype == "datetime":
            seen: dict[str, bool] = {}
            ok = np.fromiter((seen.setdefault(t, _is_iso(t)) if t else True for t in texts),
                             dtype=bool, count=len(texts))
            values = None
        else:
            ok = np.ones(len(texts), dtype=bool)
            values = None
        # the rare cells the column-wise rules do not vouch for: parse_cell decides
        for i in np.flatnonzero(~ok & ~empty):
            try:
                value = parse_cell(texts[i], ftype)
            except ValueError as exc:
                problems.append((int(numbers[i]), j, f"row {numbers[i]}, field {name}: {exc}, "
                                 f"expected {_article(ftype)} {ftype}"))
                value = None
            if values is None:  # text: kept where it parses
                empty[i] = value is None
            else:
                values[i] = np.nan if ftype == "number" and value is None else value
        if values is None:  # text stays Arrow text: no Python string outlives its batch
            values = pc.if_else(pa.array(empty), pa.scalar(None, pa.string()), arr)
        if need:
            for i in np.flatnonzero(empty):
                problems.append((int(numbers[i]), j,
                                 f"row {numbers[i]}, field {name}: missing, expected a value"))
        chunks[j].append(values)
    for _, _, problem in sorted(problems, key=lambda p: (p[0], p[1])):
        add(where, problem)


def _is_iso(text: str) -> bool:
    try:
        datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        return False
    return True


def _article(word: str) -> str:
    """The indefinite article before ``word`` ("an integer", "a number")."""
    return "an" if word[:1].lower() in "aeiou" else "a"

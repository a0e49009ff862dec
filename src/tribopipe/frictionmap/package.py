"""Checking a friction-map data package someone sent, and its runs for a merge.

:func:`check_package` reads a package (:mod:`tribopipe.frictionmap.datapackage` for the
standard's JSON and the hostile-input rules) and lists every problem, one line each,
naming the file, the row and the field: the descriptor (profile, tribopipe's schema version,
the lab, licences, resource names), each resource's path, size and SHA-256, the runs table's
schema (every field's name, type and unit against the map's schema of that version), every
cell of ``data/runs.csv`` (type, required, the row checks of
:func:`tribopipe.frictionmap.checks.validate_runs`: physical ranges, duplicate ids,
provenance), the Parquet copy of the runs against the CSV, the group table against the
statistics of the runs, the 7-column FrictionMap table against the included runs, and the
founding paper's citation where its rows are republished. :func:`package_runs` is the same
check for a merge: the runs, or :class:`PackageInvalid` when anything is wrong.

A checksum shows that a file is the one the descriptor describes (nothing lost or changed on
the way); it is not a signature: whoever can edit the files can edit the descriptor too.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeGuard, cast

from ..errors import MapError
from ..escape import printable
from ..memory import return_free_memory
from ..stats import GROUP_MU_K_INPUT, group_mu_k, run_ids_of
from .checks import validate_runs
from .datapackage import (
    DEFAULT_LIMITS,
    DESCRIPTOR,
    FALSE,
    FRICTIONMAP_FIELDS,
    GROUP_ID,
    GROUP_RUNS_FIELDS,
    PROFILE,
    TABLE_TYPES,
    TRIBOPIPE_KEY,
    TRUE,
    PackageLimits,
    PackageRefused,
    Problem,
    descriptor_path,
    file_digest,
    load_descriptor,
    read_csv_columns,
    resource_file,
    run_columns,
    runs_fields,
)
from .profile import (
    LINKED_GROUPS_VERSION,
    PROFILE_NAME,
    PROFILE_VERSION,
    descriptor_profile_version,
    upgrade_note,
)
from .published import FOUNDING_PAPER
from .schema import (
    ADDED_IN_VERSION,
    KIND,
    RUN_COLUMNS,
    SCHEMA_NAME,
    SCHEMA_VERSION,
    SOURCE_PUBLISHED,
    columns_sha256,
    is_missing,
)
from .store import map_metadata, same_value

if TYPE_CHECKING:
    from collections.abc import Iterator

    import pandas as pd

#: names of the resources tribopipe publishes (``runs`` is the one a package must have)
RUNS, RUNS_PARQUET = "runs", "runs-parquet"
GROUPS, GROUPS_PARQUET = "groups", "groups-parquet"
#: the table of each group's runs (package profile version 3 on)
GROUP_RUNS = "group-runs"
FRICTIONMAP_APP = "frictionmap-app"
#: the first schema version a package can declare (version 1 maps had no ``lab``)
FIRST_PACKAGE_VERSION = 2


class PackageInvalid(MapError):
    """A package with problems; ``problems`` holds every line."""

    def __init__(self, problems: list[str], path: Path) -> None:
        more = f" (and {len(problems) - 1} more problem(s))" if len(problems) > 1 else ""
        super().__init__(
            f"not a valid friction-map package: {problems[0]}{more}",
            path=path,
            hint="`tribopipe map validate` lists every problem",
        )
        self.problems = problems


@dataclass
class PackageCheck:
    """What :func:`check_package` found: the descriptor's path, the problems (the first
    ``limits.problems`` of them, ``more`` counts the rest), the lab and the runs (map
    DataFrame, ``None`` when the runs table could not be read)."""

    path: Path
    problems: list[Problem] = field(default_factory=list)
    more: int = 0
    lab: str | None = None
    runs: pd.DataFrame | None = None
    #: the package profile version it declares (:mod:`tribopipe.frictionmap.profile`)
    profile_version: int = PROFILE_VERSION
    #: what reading it had to say that is not a problem (an older version upgraded)
    notes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when the package has no problem."""
        return not self.problems and not self.more

    def verdict(self) -> str:
        """The line for a package without problems: who published it and how many of its
        runs each lab measured (a package may carry other labs' runs, e.g. the published
        map's), most runs first."""
        n = 0 if self.runs is None else len(self.runs)
        text = f"{self.path}: valid friction-map package from {self.lab}, {n} runs"
        if self.runs is None or not n:
            return text
        counts = self.runs["lab"].astype(str).value_counts(sort=False)
        by_lab = sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))
        if len(by_lab) == 1 and by_lab[0][0] == self.lab:
            return text
        return text + ": " + ", ".join(f"{k} measured by {lab}" for lab, k in by_lab)

    def lines(self) -> list[str]:
        """One line per problem (and one counting those beyond the limit)."""
        out = [str(p) for p in self.problems]
        if self.more:
            out.append(f"{self.path}: … and {self.more} more problem(s) not listed")
        return out


class _Checker:
    """Collects problems up to a limit; each check appends to it."""

    def __init__(self, path: Path, limits: PackageLimits) -> None:
        self.result = PackageCheck(path)
        self.limits = limits

    def add(self, where: str, problem: str) -> None:
        if len(self.result.problems) < self.limits.problems:
            self.result.problems.append(Problem(where, problem))
        else:
            self.result.more += 1


def check_package(path: str | os.PathLike[str],
                  limits: PackageLimits = DEFAULT_LIMITS, *,
                  keep_runs: bool = True) -> PackageCheck:
    """Check the package at ``path`` (its folder or its ``datapackage.json``); see the
    module docstring for what is checked. Never raises for a bad package: every problem is
    in the result. With ``keep_runs`` false the result's runs hold the ``lab`` column only
    (what :meth:`PackageCheck.verdict` reads): each step after the Parquet copy's keeps
    only the columns it compares, and the others are let go early (a caller that wants
    the verdict, not the runs: 10⁵ runs of every column are some 100 MB)."""
    desc = descriptor_path(path)
    check = _Checker(desc, limits)
    try:
        descriptor, base = load_descriptor(desc, limits)
    except PackageRefused as exc:
        check.add(printable(desc.name), exc.problem)  # the file given, whatever its name
        return check.result
    version = _check_descriptor(check, descriptor)
    resources = _resources(check, descriptor)
    if version is None or RUNS not in resources:
        if version is not None:
            check.add(DESCRIPTOR, f"no resource named {RUNS!r} (the runs table)")
        return check.result
    files = {name: _check_file(check, res, base) for name, res in resources.items()}
    before = len(check.result.problems) + check.result.more
    runs = _check_runs(check, resources[RUNS], files[RUNS], version)
    check.result.runs = runs
    if runs is None or len(check.result.problems) + check.result.more > before:
        # the other tables are compared with clean runs only: against faulty ones they
        # would repeat the runs' problems, not add any
        return check.result
    return_free_memory()  # what parsing and checking the rows freed, before the copies
    if (parquet := files.get(RUNS_PARQUET)) is not None:
        _check_parquet_copy(check, resources[RUNS_PARQUET], parquet, runs)
    if not keep_runs:  # the columns the later steps read
        check.result.runs = runs.loc[:, ["lab"]]
        runs = runs.loc[:, list(dict.fromkeys((*GROUP_MU_K_INPUT, "mu_k", "source")))]
        return_free_memory()
    if (groups := files.get(GROUPS)) is not None:
        before_groups = len(check.result.problems) + check.result.more
        table = _group_columns(check, resources[GROUPS], groups)
        members = None if table is None else _check_groups(check, resources[GROUPS], table,
                                                           runs)
        clean = len(check.result.problems) + check.result.more == before_groups
        return_free_memory()
        if table is not None and clean and (
                groups_copy := files.get(GROUPS_PARQUET)) is not None:
            _check_groups_copy(check, resources[GROUPS_PARQUET], groups_copy, table)
        del table
        return_free_memory()
        linked = check.result.profile_version >= LINKED_GROUPS_VERSION
        if members is not None and (links := files.get(GROUP_RUNS)) is not None:
            _check_group_runs(check, resources[GROUP_RUNS], links, members,
                              str(resources[GROUPS].get("path")))
        elif linked and GROUP_RUNS not in resources:
            check.add(DESCRIPTOR, f"resource {GROUPS!r} without {GROUP_RUNS!r} (the runs of "
                      f"each group), which package profile version "
                      f"{check.result.profile_version} requires beside it")
    if (app_table := files.get(FRICTIONMAP_APP)) is not None:
        _check_frictionmap_table(check, resources[FRICTIONMAP_APP], app_table, runs)
    if (runs["source"] == SOURCE_PUBLISHED).any() and not _cites_founding_paper(descriptor):
        check.add(DESCRIPTOR, "holds the founding paper's published rows but does not cite "
                  f"it in 'sources' (expected {FOUNDING_PAPER['title']!r})")
    return check.result


def package_runs(path: str | os.PathLike[str],
                 limits: PackageLimits = DEFAULT_LIMITS) -> tuple[pd.DataFrame, str]:
    """The runs (map DataFrame) and the lab of a package that passes
    :func:`check_package`; :class:`PackageInvalid` (every problem line) otherwise."""
    result = check_package(path, limits)
    if not result.ok or result.runs is None:
        raise PackageInvalid(result.lines() or ["the runs table could not be read"],
                             result.path)
    return result.runs, str(result.lab)


# --------------------------------------------------------------------------- descriptor


def _text(value: Any) -> TypeGuard[str]:
    return isinstance(value, str) and bool(value.strip())


def _check_descriptor(check: _Checker, d: dict[str, Any]) -> int | None:
    """Profile, tribopipe block, lab, licences; the declared schema version (``None``
    when it cannot be read further)."""
    where = DESCRIPTOR
    if d.get("profile") != PROFILE:
        check.add(where, f"profile {d.get('profile')!r}, expected {PROFILE!r}")
    if not _licences_ok(d.get("licenses")):
        check.add(where, "no licence: expected 'licenses' with a name or path")
    info = d.get(TRIBOPIPE_KEY)
    if not isinstance(info, dict) or info.get("schema") != SCHEMA_NAME:
        check.add(where, f"no {TRIBOPIPE_KEY!r} block naming the schema {SCHEMA_NAME!r}; "
                  "not a friction-map package")
        return None
    profile = descriptor_profile_version(d)
    if profile is None:
        check.add(where, f"package profile {info.get('profile')!r} version "
                  f"{info.get('profile_version')!r}; expected {PROFILE_NAME!r} with a version "
                  "number")
        return None
    if profile > PROFILE_VERSION:
        check.add(where, f"package profile version {profile}; this tribopipe reads versions "
                  f"1 to {PROFILE_VERSION} (upgrade tribopipe for a newer one)")
        return None
    check.result.profile_version = profile
    note = upgrade_note(profile)
    if note is not None:
        check.result.notes.append(note)
    version = info.get("schema_version")
    if isinstance(version, bool) or not isinstance(version, int) or not (
            FIRST_PACKAGE_VERSION <= version <= SCHEMA_VERSION):
        check.add(where, f"schema version {version!r}; this tribopipe reads packages of "
                  f"versions {FIRST_PACKAGE_VERSION} to {SCHEMA_VERSION} (upgrade tribopipe "
                  "for a newer one)")
        return None
    if not _text(info.get("lab")):
        check.add(where, "provenance: no lab named in the tribopipe block")
    else:
        check.result.lab = str(info["lab"]).strip()
    return version


def _licences_ok(value: Any) -> bool:
    return isinstance(value, list) and bool(value) and all(
        isinstance(x, dict) and (_text(x.get("name")) or _text(x.get("path"))) for x in value)


def _resources(check: _Checker, d: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The resources by name (unique, bounded in number)."""
    items = d.get("resources")
    if not isinstance(items, list) or not items:
        check.add(DESCRIPTOR, "no 'resources' list")
        return {}
    if len(items) > check.limits.resources:
        check.add(DESCRIPTOR, f"{len(items)} resources, more than the limit of "
                  f"{check.limits.resources}")
        return {}
    out: dict[str, dict[str, Any]] = {}
    for i, res in enumerate(items, 1):
        name = res.get("name") if isinstance(res, dict) else None
        if not _text(name):
            check.add(DESCRIPTOR, f"resource {i} has no name")
        elif name in out:
            check.add(DESCRIPTOR, f"resource name {name!r} appears twice")
        else:
            out[name] = res
    return out


def _check_file(check: _Checker, res: dict[str, Any], base: Path) -> Path | None:
    """The file of a resource after its path, size and checksum checks (``None`` when
    refused); it is read in blocks for its checksum, never whole."""
    where = f"{DESCRIPTOR}: resource {res['name']!r}"
    if "data" in res:
        check.add(where, "inline 'data' is not accepted; expected a file")
        return None
    try:
        target = resource_file(base, res.get("path"))
    except PackageRefused as exc:
        check.add(where, exc.problem)
        return None
    try:
        length, digest = file_digest(target, check.limits.resource_bytes, what="file")
    except PackageRefused as exc:
        check.add(where, f"path {json.dumps(res['path'])}: {exc.problem}")
        return None
    shown = str(res["path"])
    if not _licences_ok(res.get("licenses")):
        check.add(shown, "no licence: expected 'licenses' with a name or path")
    # a file that is not the one described is reported once; its content is not read
    expected = res.get("hash")
    if not isinstance(expected, str) or not expected.startswith("sha256:"):
        check.add(shown, "checksum: expected 'hash' as 'sha256:<64 hex digits>'")
        return None
    if digest != expected.lower():
        check.add(shown, f"checksum: SHA-256 is {digest[7:19]}…, the descriptor "
                  f"says {expected[7:19]}… (the file was changed or damaged)")
        return None
    size = res.get("bytes")
    if isinstance(size, bool) or not isinstance(size, int):
        check.add(shown, "checksum: expected 'bytes', the file's size")
        return None
    if size != length:
        check.add(shown, f"checksum: {length} bytes, the descriptor says {size}")
        return None
    return target


# --------------------------------------------------------------------------- runs


def _check_fields(check: _Checker, schema: Any, expected: list[dict[str, Any]],
                  where: str) -> list[dict[str, Any]] | None:
    """The descriptor's fields after comparing each with ``expected`` (name, type, unit);
    ``None`` when they cannot be used."""
    fields = schema.get("fields") if isinstance(schema, dict) else None
    if not isinstance(fields, list) or not fields or len(fields) > check.limits.fields:
        check.add(where, "schema: expected 'fields', a list of at most "
                  f"{check.limits.fields} fields")
        return None
    by_name = {f["name"]: f for f in expected}
    seen: set[str] = set()
    usable = True
    for f in fields:
        name = f.get("name") if isinstance(f, dict) else None
        if not isinstance(name, str) or name in seen:
            check.add(where, f"schema: field {name!r} is unnamed or appears twice")
            usable = False
            continue
        seen.add(name)
        want = by_name.get(name)
        if want is None:
            check.add(where, f"schema: field {name!r} is not a column of this schema version")
            usable = False
            continue
        if f.get("type") != want["type"]:
            check.add(where, f"schema: field {name!r} has type {f.get('type')!r}, expected "
                      f"{want['type']!r}")
            usable = False
        if (f.get("unit") or "") != want.get("unit", ""):
            check.add(where, f"schema: field {name!r} has unit {f.get('unit')!r}, expected "
                      f"{want.get('unit', '')!r}")
            usable = False
    for name in by_name:
        if name not in seen:
            check.add(where, f"schema: field {name!r} is missing")
            usable = False
    return fields if usable else None


def _table(check: _Checker, path: Path, fields: list[dict[str, Any]],
           shown: str) -> dict[str, Any] | None:
    """The rows of a CSV resource as typed columns
    (:func:`~tribopipe.frictionmap.datapackage.read_csv_columns`), every cell problem
    reported (a bad cell is missing); ``None`` when the header is wrong or the text
    unreadable."""
    return read_csv_columns(path, fields, shown, check.limits, check.add)


def _check_runs(check: _Checker, res: dict[str, Any], path: Path | None,
                version: int) -> pd.DataFrame | None:
    """The runs table: schema against the map's, every cell, then the row checks."""
    if path is None:
        return None
    shown = str(res.get("path"))
    fields = _check_fields(check, res.get("schema"), runs_fields(version), shown)
    if fields is None:
        return None
    columns = _table(check, path, fields, shown)
    if columns is None:
        return None
    if not set(run_columns(version)) <= set(columns):
        return None
    runs = _map_frame(check, columns, shown)
    if runs is None:
        return None
    # CSV cannot tell an empty text from a missing one: flags are never missing in a map
    # ("" is a run without flags), every other text is missing rather than empty
    runs["flags"] = runs["flags"].fillna("")
    for problem in validate_runs(runs, require_lab=True):
        check.add(shown, f"row {problem.row}, field {problem.field}: {problem.problem}")
    return runs


def _map_frame(check: _Checker, columns: dict[str, Any], shown: str) -> pd.DataFrame | None:
    """Typed CSV columns as a map DataFrame (the schema's columns and dtypes; a column of
    an older schema version missing in every row); ``None`` where a true/false column
    misses a value (said)."""
    import numpy as np
    import pandas as pd

    n = len(next(iter(columns.values()))) if columns else 0
    out: dict[str, Any] = {}
    for name in RUN_COLUMNS:
        kind = KIND[name]
        values = columns.get(name)
        if kind == "float":
            out[name] = (np.full(n, np.nan) if values is None
                         else np.asarray(values, dtype=float))
        elif kind == "int":
            out[name] = pd.array([None] * n if values is None else values, dtype="Int64")
        elif kind == "bool":
            missing = np.ones(n, dtype=bool) if values is None else np.asarray(
                pd.isna(values), dtype=bool)
            if missing.any():
                row = int(np.flatnonzero(missing)[0]) + 1
                check.add(shown, f"row {row}, field {name}: missing, expected {TRUE} or "
                          f"{FALSE}")
                return None
            out[name] = np.asarray(values, dtype=bool)
        else:
            out[name] = pd.array([None] * n if values is None else values, dtype="str")
    return pd.DataFrame(out, columns=list(RUN_COLUMNS), index=pd.RangeIndex(n))


def _check_parquet_copy(check: _Checker, res: dict[str, Any], path: Path,
                        runs: pd.DataFrame) -> None:
    """The Parquet copy of the runs is a friction map (our metadata, the checksum of its
    own rows) and holds the same rows as the CSV. Read one column at a time, never whole:
    each column is compared with the CSV's (the first differing cells listed in row
    order, the rest counted) and fed to the checksum of the copy's rows."""
    import numpy as np
    import pyarrow as pa

    shown = str(res.get("path"))
    parquet = _open_parquet(check, path, shown)
    if parquet is None:
        return
    meta = parquet.metadata
    try:
        info = map_metadata(path)
    except MapError as exc:
        check.add(shown, exc.problem)
        return
    if meta.num_rows != len(runs):
        check.add(shown, f"{meta.num_rows} rows, the CSV has {len(runs)}")
        return
    version = int(info["schema_version"])
    copy = _ParquetColumns(parquet, len(runs), version)
    names = list(RUN_COLUMNS)
    differs = np.zeros((len(runs), len(names)), dtype=bool)
    compared: set[str] = set()

    def compared_column(name: str) -> pd.Series:
        """The copy's column ``name``, compared with the CSV's as it is read."""
        column = copy[name]
        differs[:, names.index(name)] = ~_same_values(runs[name], column)
        compared.add(name)
        return column

    try:
        stored = info.get("content_sha256")
        # each column read once: compared with the CSV's and fed to the checksum
        intact = stored is None or stored == columns_sha256(len(runs), compared_column,
                                                            version)
        for name in names:
            if name not in compared:
                compared_column(name)
    except (pa.ArrowException, OSError, ValueError, TypeError, KeyError) as exc:
        check.add(shown, f"not a readable friction map ({str(exc)[:120]})")
        return
    if not intact:
        check.add(shown, "fails its checksum: its rows are not those tribopipe wrote "
                  "(damaged, or changed by another program)")
        return
    _name_differences(check, shown, differs, names, runs, copy)


def _open_parquet(check: _Checker, path: Path, shown: str) -> Any:
    """The Parquet file at ``path`` opened (its footer read), or ``None`` with the problem
    said: not readable as Parquet, or unpacking to more than the resource limit."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        parquet = pq.ParquetFile(path)
        meta = parquet.metadata
        unpacked = sum(meta.row_group(i).total_byte_size for i in range(meta.num_row_groups))
    except (pa.ArrowException, OSError, ValueError) as exc:
        check.add(shown, f"not a readable Parquet file ({str(exc)[:120]})")
        return None
    if unpacked > check.limits.resource_bytes:
        check.add(shown, f"unpacks to {unpacked} bytes, more than the limit of "
                  f"{check.limits.resource_bytes}")
        return None
    return parquet


def _name_differences(check: _Checker, shown: str, differs: Any, names: list[str],
                      csv: Any, copy: Any) -> None:
    """Each cell where ``differs`` (rows × ``names``) is true, in row order, said with the
    copy's value and the CSV's (``csv[name]`` and ``copy[name]`` are columns): the first
    up to the problem limit, the rest counted."""
    import numpy as np

    for row, j in np.argwhere(differs)[:check.limits.problems]:
        name = names[j]
        ours, theirs = _plain(csv[name].iloc[row]), _plain(copy[name].iloc[row])
        check.add(shown, f"row {row + 1}, field {name}: {theirs!r} differs from the CSV's "
                  f"{ours!r}")
    check.result.more += max(0, int(differs.sum()) - check.limits.problems)


def _check_groups_copy(check: _Checker, res: dict[str, Any], path: Path,
                       columns: dict[str, Any]) -> None:
    """The Parquet copy of the group table holds the CSV's columns and rows (``columns``,
    as :func:`_group_columns` parsed them; numbers within a relative 1e-9): the first
    differing cells listed in row order, the rest counted. Called on a group CSV that
    passed its own check."""
    import numpy as np
    import pandas as pd
    import pyarrow as pa

    shown = str(res.get("path"))
    parquet = _open_parquet(check, path, shown)
    if parquet is None:
        return
    try:
        copy = parquet.read().to_pandas()
    except (pa.ArrowException, OSError, ValueError) as exc:
        check.add(shown, f"not a readable Parquet file ({str(exc)[:120]})")
        return
    names = list(columns)
    if list(copy.columns) != names:
        check.add(shown, f"columns {list(map(str, copy.columns))} differ from the CSV's "
                  f"{names}")
        return
    n = len(next(iter(columns.values()))) if columns else 0
    if len(copy) != n:
        check.add(shown, f"{len(copy)} rows, the CSV has {n}")
        return
    # a column at a time, as a Series of its own (no frame of the CSV's columns beside
    # the copy); a CSV cannot tell an empty text from a missing one: neither can the
    # comparison
    csv_frame = {name: _empty_as_missing(pd.Series(columns[name])) for name in names}
    for name in names:
        if _is_text(copy[name]):
            copy[name] = _empty_as_missing(copy[name])
    differs = np.zeros((n, len(names)), dtype=bool)
    try:
        for j, name in enumerate(names):
            differs[:, j] = ~_same_values(csv_frame[name], copy[name])
    except (TypeError, ValueError) as exc:
        check.add(shown, f"not comparable with the CSV ({str(exc)[:120]})")
        return
    _name_differences(check, shown, differs, names, csv_frame, copy)


def _is_text(column: pd.Series) -> bool:
    """Whether ``column`` holds text (object, NumPy string or pandas string dtype)."""
    return column.dtype.kind in "OUT" or str(column.dtype) == "str"


def _empty_as_missing(column: pd.Series) -> pd.Series:
    """A text column with its empty texts missing (other columns as they are)."""
    return column.mask(column.astype(object) == "") if _is_text(column) else column


class _ParquetColumns:
    """The columns of a friction map's Parquet file read one at a time as a map
    DataFrame holds them (a column of a later schema version than the file's missing in
    every row): what :func:`~tribopipe.frictionmap.schema.content_sha256` needs of a
    frame, without the frame."""

    def __init__(self, parquet: Any, n: int, version: int) -> None:
        self.parquet, self.n, self.version = parquet, n, version
        self.names = set(parquet.schema_arrow.names)

    def __len__(self) -> int:
        return self.n

    def __getitem__(self, name: str) -> pd.Series:
        import numpy as np
        import pandas as pd
        import pyarrow as pa

        kind = KIND[name]
        if name not in self.names:
            if ADDED_IN_VERSION.get(name, 1) <= self.version:
                raise KeyError(f"no column {name}")
            column = pa.nulls(self.n, pa.string() if kind == "str" else pa.float64())
        else:
            column = self.parquet.read(columns=[name]).column(0)
        if kind == "float":
            return pd.Series(np.asarray(column.to_numpy(zero_copy_only=False), dtype=float))
        if kind == "int":
            return pd.Series(pd.array(column.to_pylist(), dtype="Int64"))
        if kind == "bool":
            values = column.to_pylist()
            if not all(isinstance(v, bool) for v in values):
                raise TypeError(f"{name}: expected true or false in every row")
            return pd.Series(np.asarray(values, dtype=bool))
        if not (pa.types.is_string(column.type) or pa.types.is_large_string(column.type)
                or pa.types.is_null(column.type)):
            raise TypeError(f"{name}: expected text, stored as {column.type}")
        return pd.Series(pd.array(column.cast(pa.string()), dtype="str"))


def _plain(value: Any) -> Any:
    """A cell as a plain Python value (missing as ``None``)."""
    if is_missing(value):
        return None
    return value.item() if hasattr(value, "item") else value


def _same_values(a: pd.Series, b: pd.Series) -> Any:
    """Per row, :func:`~tribopipe.frictionmap.store.same_value` of two columns of one
    kind, column-wise: both missing, or equal (numbers within a relative 1e-9)."""
    import numpy as np

    missing_a = np.asarray(a.isna(), dtype=bool)
    missing_b = np.asarray(b.isna(), dtype=bool)
    both = missing_a & missing_b
    present = ~missing_a & ~missing_b
    if a.dtype.kind == "f" or b.dtype.kind == "f":
        x = np.asarray(a, dtype=float)
        y = np.asarray(b, dtype=float)
        with np.errstate(invalid="ignore"):
            equal = np.isclose(x, y, rtol=1e-9, atol=1e-12) | (x == y)
    elif str(a.dtype) == "str" and str(b.dtype) == "str":  # texts compared as texts
        equal = np.asarray(a.reset_index(drop=True).eq(b.reset_index(drop=True))
                           .fillna(False), dtype=bool)
    else:
        equal = np.asarray((a.astype(object) == b.astype(object)).fillna(False), dtype=bool)
    return both | (present & equal)


def _group_fields(res: dict[str, Any]) -> list[dict[str, Any]] | None:
    """The group table's declared fields, each with a name and a Table Schema type;
    ``None`` when the schema does not declare them so."""
    schema = res.get("schema")
    fields = schema.get("fields") if isinstance(schema, dict) else None
    if not isinstance(fields, list) or not all(
            isinstance(f, dict) and isinstance(f.get("name"), str)
            and f.get("type") in TABLE_TYPES.values() for f in fields):
        return None
    return fields


def _group_columns(check: _Checker, res: dict[str, Any], path: Path
                   ) -> dict[str, Any] | None:
    """The group table parsed by its own schema (typed columns), read once for every
    check of it; ``None``, with the problem said, when it cannot be."""
    fields = _group_fields(res)
    if fields is None:
        check.add(str(res.get("path")),
                  "schema: expected 'fields' with a name and a Table Schema type each")
        return None
    return _table(check, path, fields, str(res.get("path")))


def _check_groups(check: _Checker, res: dict[str, Any], columns: dict[str, Any],
                  runs: pd.DataFrame) -> dict[int, str] | None:
    """The group table (``columns``, as :func:`_group_columns` parsed it): its μ_K n and
    mean follow from the runs. From package profile version 3 the groups are numbered
    (``group``, unique): returns, per group number, the ids of the runs its conditions
    make in the runs table (what ``group_runs.csv`` must list), as the group's
    ``run_ids`` cell (:func:`~tribopipe.stats.run_ids_of` reads it; one text per group,
    not a set of 10⁵ texts); ``None`` before version 3."""
    shown = str(res.get("path"))
    fields = cast("list[dict[str, Any]]", _group_fields(res))
    keys: tuple[str, ...] = ("pin", "disc", "normal_force_N", "temperature_C")
    names = {f["name"] for f in fields}
    if not {*keys, "mu_k_n", "mu_k_mean"} <= names:
        check.add(shown, "schema: expected the fields pin, disc, normal_force_N, "
                  "temperature_C, mu_k_n and mu_k_mean")
        return None
    linked = check.result.profile_version >= LINKED_GROUPS_VERSION
    if linked and not any(f["name"] == GROUP_ID and f.get("type") == "integer"
                          for f in fields):
        check.add(shown, f"schema: expected the field {GROUP_ID!r} (integer), the group's "
                  f"number, which package profile version {check.result.profile_version} "
                  "requires")
        return None
    if "nominal_speed_mm_s" in names:
        keys += ("nominal_speed_mm_s",)  # a map of several speeds: groups split by speed
    # the columns compared only, a row at a time as plain values (a group table of 10⁵
    # groups has some 70 more); the runs' groups as columns, each found by its key
    used = [name for name in columns if name in (*keys, "mu_k_n", "mu_k_mean", GROUP_ID)]
    groups = group_mu_k(runs)  # group_statistics(runs, show_speed=True)'s columns
    computed = {_key_of(key): j for j, key in enumerate(
        zip(*(groups[k].tolist() for k in keys), strict=True))}
    figures = {name: groups[name].tolist() for name in ("mu_k_n", "mu_k_mean", "run_ids")}
    del groups
    n_rows = len(columns[used[0]])
    if n_rows != len(computed):
        check.add(shown, f"{n_rows} groups, the runs make {len(computed)}")
    members: dict[int, str] = {}
    first: dict[int, int] = {}
    at = {name: i for i, name in enumerate(used)}
    for n, values in enumerate(_plain_rows([columns[name] for name in used]), 1):
        number = values[at[GROUP_ID]] if linked else None
        if isinstance(number, int) and number < 1:
            check.add(shown, f"row {n}, field {GROUP_ID}: {number} is not a group number "
                      "(expected 1 or more)")
            number = None
        if isinstance(number, int):
            if number in first:
                check.add(shown, f"row {n}, field {GROUP_ID}: group {number} appears twice "
                          f"(first in row {first[number]})")
                number = None
            else:
                first[number] = n
        j = computed.get(_key_of(tuple(values[at[k]] for k in keys)))
        if j is None:
            check.add(shown, f"row {n}: no runs of this group in the runs table")
            continue
        for name in ("mu_k_n", "mu_k_mean"):
            theirs, ours = values[at[name]], figures[name][j]
            if not same_value(theirs, ours):
                check.add(shown, f"row {n}, field {name}: {theirs!r} does not follow "
                          f"from the runs ({ours!r})")
        if isinstance(number, int):
            members[number] = figures["run_ids"][j]
    return members if linked else None


#: rows of a table made plain at a time by :func:`_plain_rows`
PLAIN_ROWS = 8192


def _plain_rows(columns: list[Any]) -> Iterator[tuple[Any, ...]]:
    """The rows of equally long typed columns (NumPy or pandas arrays) as tuples of plain
    Python values, missing as ``None``, made :data:`PLAIN_ROWS` rows at a time (never a
    list of every cell)."""
    import numpy as np
    import pandas as pd

    n = len(columns[0]) if columns else 0
    for start in range(0, n, PLAIN_ROWS):
        parts = []
        for column in columns:
            part = column[start:start + PLAIN_ROWS]
            values = part.tolist()
            for i in np.flatnonzero(np.asarray(pd.isna(part), dtype=bool)).tolist():
                values[i] = None
            parts.append(values)
        yield from zip(*parts, strict=True)


def _check_group_runs(check: _Checker, res: dict[str, Any], path: Path,
                      members: dict[int, str], groups_shown: str) -> None:
    """The linking table lists each numbered group's runs, each included run once, and
    the runs of a group are those its conditions make in the runs table (``members``: by
    group number, the ids :func:`~tribopipe.stats.run_ids_of` reads in the group's
    ``run_ids`` cell)."""
    shown = str(res.get("path"))
    fields = _check_fields(check, (res.get("schema") or {}), list(GROUP_RUNS_FIELDS), shown)
    if fields is None:
        return
    columns = _table(check, path, fields, shown)
    if columns is None:
        return
    owner = {mid: number for number, ids in members.items() for mid in run_ids_of(ids)}
    seen: dict[str, int] = {}
    listed: dict[int, set[str]] = {number: set() for number in members}
    for n, (number, mid) in enumerate(_plain_rows([columns[GROUP_ID],
                                                   columns["measurement_id"]]), 1):
        if number is None or mid is None:
            continue  # said by the cell check
        if mid in seen:
            check.add(shown, f"row {n}, field measurement_id: run {mid[:40]!r} is listed "
                      f"twice (first in row {seen[mid]})")
            continue
        seen[mid] = n
        if number not in members:
            check.add(shown, f"row {n}, field {GROUP_ID}: {number} is not a group of "
                      f"{groups_shown}")
        elif mid not in owner:
            check.add(shown, f"row {n}, field measurement_id: {mid[:40]!r} is not an "
                      "included run of the runs table")
        else:
            listed[number].add(mid)
    for number in sorted(members):
        got, expected = listed[number], frozenset(run_ids_of(members[number]))
        if got != expected:
            check.add(shown, f"group {number}: lists {len(got)} run(s), the group's "
                      f"conditions in the runs table make {len(expected)} "
                      f"({len(expected - got)} of them not listed, {len(got - expected)} "
                      "listed that belong to another group)")


def _key_of(values: tuple[Any, ...]) -> tuple[Any, ...]:
    """A group's key (its values of the key fields, in order) as the group table and the
    runs' groups are matched on: missing as ``None``, numbers rounded to 1e-9."""
    out = []
    for v in values:
        if isinstance(v, float) and math.isnan(v):
            v = None
        out.append(round(float(v), 9) if isinstance(v, int | float) and v is not None else v)
    return tuple(out)


def _check_frictionmap_table(check: _Checker, res: dict[str, Any], path: Path,
                             runs: pd.DataFrame) -> None:
    """The 7-column table holds the included runs' μ_K in map order."""
    import numpy as np
    import pandas as pd

    shown = str(res.get("path"))
    columns = _table(check, path, list(FRICTIONMAP_FIELDS), shown)
    if columns is None:
        return
    included = runs.loc[~runs["excluded"].astype(bool), "mu_k"].reset_index(drop=True)
    cof = pd.Series(columns["cof"])
    if len(cof) != len(included):
        check.add(shown, f"{len(cof)} rows, the runs table has {len(included)} included runs")
        return
    for i in np.flatnonzero(~_same_values(cof, included)):
        check.add(shown, f"row {i + 1}, field cof: {_plain(cof.iloc[i])!r} differs from the "
                  f"run's mu_k {_plain(included.iloc[i])!r}")


def _cites_founding_paper(d: dict[str, Any]) -> bool:
    sources = d.get("sources")
    return isinstance(sources, list) and any(
        isinstance(s, dict) and FOUNDING_PAPER["title"] in str(s.get("title", ""))
        for s in sources)
